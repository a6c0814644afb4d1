#!/usr/bin/env python3
"""Measures `odocal live` on this machine (docs/live.md's tables).

`rates`: for each replay rate, `odocal live` on a fresh loopback domain
against a publisher of the bundled recording (the independent Cyclone DDS
peer `tools/live_peer.py`, or `odocal play` with `--player play`), stopped
with SIGINT at the end; one markdown row per rate from the node's
`live.json`, the peer's report and `summary.json` against the offline
`odocal calibrate` of the same recording.

`hour`: `odocal play --loop` feeds an hour of the recording's time (48
rounds of 75 s) at `--rate`; the node's resident memory is sampled every
`--every` seconds (/proc/PID/status VmRSS) and printed as a table.

Usage:
  python3 tools/live_bench.py rates --odocal target/release/odocal --rates 1 3 10
  python3 tools/live_bench.py hour --odocal target/release/odocal --rate 12
"""
import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUNDLED = os.path.join(ROOT, "scans", "wheelchair-corridor.mcap")
CONFIG = "[live]\nlocalhost_only = true\nwait_s = 120.0\n"


def start_node(odocal, out, cfg, domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    err = open(os.path.join(os.path.dirname(out), f"node-{domain}.err"), "w")
    return subprocess.Popen([odocal, "live", "--out", out, "--config", cfg],
                            env=env, stdout=subprocess.DEVNULL, stderr=err)


def stop_node(node, timeout=120):
    node.send_signal(signal.SIGINT)
    node.wait(timeout=timeout)


def offline(odocal, work):
    out = os.path.join(work, "offline")
    subprocess.run([odocal, "calibrate", "--input", BUNDLED, "--out", out, "--json"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.load(open(os.path.join(out, "summary.json")))["final"]


def publish(args, domain, rate, cfg):
    if args.player == "peer":
        p = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "live_peer.py"), "publish",
                            "--domain", str(domain), "--mcap", BUNDLED, "--rate", str(rate)],
                           check=True, capture_output=True, text=True)
        return json.loads(p.stdout)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    p = subprocess.run([args.odocal, "play", BUNDLED, "--rate", str(rate), "--delay", "3",
                        "--config", cfg, "--json"], env=env, check=True,
                       capture_output=True, text=True)
    played = json.loads(p.stdout)
    time.sleep(3)
    return {"max_behind_s": played["max_behind_s"], "play_wall_s": played["wall_s"],
            "odometry_received": None, "sent": {}}


def rates(args):
    work = tempfile.mkdtemp(prefix="odocal-live-bench-")
    cfg = os.path.join(work, "live.toml")
    open(cfg, "w").write(CONFIG)
    ref = offline(args.odocal, work)
    print(f"publisher: {args.player}; offline calibrate: R_R {ref['r_right']:.5f} m, "
          f"R_L {ref['r_left']:.5f} m, D {ref['wheel_base']:.5f} m\n")
    print("| rate | play (s) | publisher behind (s) | start (s) | scan → estimate median / p95 (ms) "
          "| wheel → odometry median / p95 (ms) | CPU (% of a core) | refused / dropped "
          "| ΔR_R, ΔR_L, ΔD vs offline (mm) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for rate in args.rates:
        domain = random.randint(100, 230)
        out = os.path.join(work, f"live-{rate}")
        node = start_node(args.odocal, out, cfg, domain)
        time.sleep(0.5)
        peer = publish(args, domain, rate, cfg)
        stop_node(node)
        rep = json.load(open(os.path.join(out, "live.json")))
        fin = json.load(open(os.path.join(out, "summary.json")))["final"]
        d = [1e3 * (fin[k] - ref[k]) for k in ("r_right", "r_left", "wheel_base")]
        s, w = rep["scan_to_estimate"], rep["wheel_to_odometry"]
        m = rep["messages"]
        print(f"| ×{rate:g} | {peer['play_wall_s']:.1f} | {peer['max_behind_s']:.3f} "
              f"| {rep['start_s']:.1f} | {s['median_ms']:.0f} / {s['p95_ms']:.0f} "
              f"| {w['median_ms']:.2f} / {w['p95_ms']:.2f} | {100 * rep['cpu_share']:.0f} "
              f"| {m[3]} / {m[1]} | {d[0]:+.2f}, {d[1]:+.2f}, {d[2]:+.2f} |", flush=True)


def rss_kb(pid):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def hour(args):
    work = tempfile.mkdtemp(prefix="odocal-live-hour-")
    cfg = os.path.join(work, "live.toml")
    open(cfg, "w").write(CONFIG)
    domain = random.randint(100, 230)
    node = start_node(args.odocal, os.path.join(work, "out"), cfg, domain)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    player = subprocess.Popen([args.odocal, "play", BUNDLED, "--rate", str(args.rate), "--loop",
                               "--delay", "2", "--config", cfg, "--json"], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    wall = 3600.0 / args.rate
    t0 = time.monotonic()
    print(f"| input time (min) | node RSS (MB) |\n|---|---|")
    while time.monotonic() - t0 < wall:
        time.sleep(args.every)
        el = time.monotonic() - t0
        print(f"| {el * args.rate / 60:.0f} | {rss_kb(node.pid) / 1024:.1f} |", flush=True)
    player.send_signal(signal.SIGINT)
    played = json.loads(player.communicate(timeout=60)[0])
    stop_node(node, timeout=600)
    rep = json.load(open(os.path.join(work, "out", "live.json")))
    print(f"\nplayed {played['messages']} messages in {played['rounds']} rounds; node: "
          f"{rep['samples'][0]} scans, {rep['messages'][1]} dropped on a full queue, "
          f"CPU {100 * rep['cpu_share']:.0f} % of a core")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=["rates", "hour"])
    ap.add_argument("--odocal", required=True)
    ap.add_argument("--rates", type=float, nargs="+", default=[1, 3, 10])
    ap.add_argument("--rate", type=float, default=12)
    ap.add_argument("--every", type=float, default=15)
    ap.add_argument("--player", choices=["peer", "play"], default="peer")
    args = ap.parse_args()
    rates(args) if args.what == "rates" else hour(args)


if __name__ == "__main__":
    main()
