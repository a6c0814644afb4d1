"""``python -m odocal.fleet SOURCE --out DIR [--engine local|ray] [--address A]``:
what ``odocal fleet --engine ray`` runs. Bad input exits 2 with the message."""

from __future__ import annotations

import argparse
import json
import sys

from .. import InputError, OutputError
from . import run


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m odocal.fleet", description=__doc__)
    ap.add_argument("source", help="fleet folder ROBOT/…/REC or manifest CSV robot,path,start")
    ap.add_argument("--out", required=True)
    ap.add_argument("--engine", choices=["local", "ray"], default="ray")
    ap.add_argument("--address", default=None, help="Ray cluster address (else a local Ray)")
    ap.add_argument("--num-cpus", type=int, default=None, help="CPUs of a local Ray")
    ap.add_argument("--method", default=None)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--robot", default=None)
    ap.add_argument("--config", default=None)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    try:
        s = run(a.source, a.out, engine=a.engine, address=a.address, num_cpus=a.num_cpus,
                method=a.method, seed=a.seed, robot=a.robot, config=a.config)
    except InputError as e:
        print(f"odocal: {e}", file=sys.stderr)
        return 2
    except OutputError as e:
        print(f"odocal: {e}", file=sys.stderr)
        return 1
    if a.json:
        print(json.dumps(s, indent=2))
        return 0
    print(f"{s['robot_count']} robots, {s['recordings']} recordings ({s['processed']} calibrated "
          f"now, {s['cached']} cached), method {s['method']}; day 0 = {s['epoch']}")
    if not s["alarms"]:
        print("no alarm")
    for al in s["alarms"]:
        print(f"{al['robot']:<12} {al['kind']:<12} day {al['day']:<6} {al['evidence']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
