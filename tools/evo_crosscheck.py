#!/usr/bin/env python3
"""Runs evo (github.com/MichaelGrupp/evo, 1.38) on a pair of TUM files for the
cases odocal's eval module must reproduce, and prints one JSON object.

Usage:
  evo_crosscheck.py --ref REF.tum --est EST.tum [--t-max-diff S] [--t-offset S]
  evo_crosscheck.py --generate DIR [--seed N]      # write a seeded 3D pair, then run

Cases (evo CLI equivalents):
  none       evo_ape tum REF EST               / evo_rpe ... --delta 1 --delta_unit f
  se3        ... -a
  sim3       ... -as
  origin     ... --align_origin
  rpe_m      evo_rpe ... --delta 1 --delta_unit m   (no alignment)
  se3_rpe_m  evo_rpe ... -a --delta 1 --delta_unit m
  interp     ... --sync_method interpolation        (no alignment)
  points_se3 evo_ape ... -a -r trans_part / evo_rpe ... -a -r point_distance
             (position-only references: only `ape` and `rpe` are reported)
Each case reports `matched`, `ape` (-r trans_part), `ape_rot_deg` (-r angle_deg),
`rpe` and `rpe_rot_deg` with rmse/mean/median/std/min/max. With --cli, the
`se3` case is also run through the evo_ape/evo_rpe command lines (--save_results
zip) and reported as `se3_cli`, to show the API and the CLI agree.
"""
import argparse
import copy
import json
import math
import os
import subprocess
import sys
import tempfile
import zipfile

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402
from evo.core import metrics, sync  # noqa: E402
from evo.core.sync_method import SyncMethod  # noqa: E402
from evo.main_ape import ape  # noqa: E402
from evo.main_rpe import rpe  # noqa: E402
from evo.tools import file_interface  # noqa: E402

KEYS = ["rmse", "mean", "median", "std", "min", "max"]
PR = metrics.PoseRelation


def stats(result):
    return {k: float(result.stats[k]) for k in KEYS}


def quat_from_rpy(r, p, y):
    cr, sr = math.cos(r / 2), math.sin(r / 2)
    cp, sp = math.cos(p / 2), math.sin(p / 2)
    cy, sy = math.cos(y / 2), math.sin(y / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def generate(directory, seed):
    """A 3D helix-like reference at ~50 Hz and a noisy, scaled, rotated estimate
    at ~20 Hz with its own stamps (some farther than 0.01 s from any reference)."""
    rng = np.random.default_rng(seed)
    os.makedirs(directory, exist_ok=True)
    ref_t = np.cumsum(rng.uniform(0.015, 0.025, 1500))
    est_t = np.cumsum(rng.uniform(0.04, 0.06, 600)) + rng.uniform(0, 0.01)

    def truth(t):
        return (
            np.array([4 * math.cos(0.2 * t), 3 * math.sin(0.3 * t), 0.5 * math.sin(0.1 * t)]),
            (0.05 * math.sin(0.5 * t), 0.03 * math.cos(0.4 * t), 0.3 * t),
        )

    ref_path = os.path.join(directory, "reference.tum")
    est_path = os.path.join(directory, "estimate.tum")
    with open(ref_path, "w") as f:
        for t in ref_t:
            p, rpy = truth(t)
            f.write(" ".join(repr(float(v)) for v in (t, *p, *quat_from_rpy(*rpy))) + "\n")
    with open(est_path, "w") as f:
        for t in est_t:
            p, rpy = truth(t)
            p = 1.05 * p + np.array([0.3, -0.2, 0.1]) + rng.normal(0, 0.05, 3)
            rpy = tuple(a + rng.normal(0, 0.02) for a in rpy)
            f.write(" ".join(repr(float(v)) for v in (t, *p, *quat_from_rpy(*rpy))) + "\n")
    return ref_path, est_path


def run_case(ref, est, args, align=False, scale=False, origin=False, unit=metrics.Unit.frames,
             interpolate=False, points=False):
    method = SyncMethod.interpolation if interpolate else SyncMethod.nearest_time
    r, e = sync.associate_trajectories(
        ref, est, sync_method=method, max_diff=args.t_max_diff, offset_2=args.t_offset
    )
    out = {"matched": int(r.num_poses)}
    if points:
        res = ape(copy.deepcopy(r), copy.deepcopy(e), PR.translation_part, align=align,
                  correct_scale=scale)
        out["ape"] = stats(res)
        res = rpe(copy.deepcopy(r), copy.deepcopy(e), PR.point_distance, delta=1, delta_unit=unit,
                  align=align, correct_scale=scale)
        out["rpe"] = stats(res)
        return out
    for key, rel in (("ape", PR.translation_part), ("ape_rot_deg", PR.rotation_angle_deg)):
        res = ape(copy.deepcopy(r), copy.deepcopy(e), rel, align=align, correct_scale=scale,
                  align_origin=origin)
        out[key] = stats(res)
    for key, rel in (("rpe", PR.translation_part), ("rpe_rot_deg", PR.rotation_angle_deg)):
        res = rpe(copy.deepcopy(r), copy.deepcopy(e), rel, delta=1, delta_unit=unit,
                  align=align, correct_scale=scale, align_origin=origin)
        out[key] = stats(res)
    return out


def run_cli(ref_path, est_path, args, flags):
    """The se3 case through evo's command lines, results read from the zips."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        jobs = [
            ("ape", "evo_ape", ["-r", "trans_part"]),
            ("ape_rot_deg", "evo_ape", ["-r", "angle_deg"]),
            ("rpe", "evo_rpe", ["-r", "trans_part", "--delta", "1", "--delta_unit", "f"]),
            ("rpe_rot_deg", "evo_rpe", ["-r", "angle_deg", "--delta", "1", "--delta_unit", "f"]),
        ]
        for key, tool, extra in jobs:
            zpath = os.path.join(tmp, key + ".zip")
            cmd = [tool, "tum", ref_path, est_path, *flags, *extra, "--no_warnings",
                   "--t_max_diff", repr(args.t_max_diff), "--t_offset", repr(args.t_offset),
                   "--save_results", zpath]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            with zipfile.ZipFile(zpath) as z:
                s = json.loads(z.read("stats.json"))
            out[key] = {k: float(s[k]) for k in KEYS}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ref")
    ap.add_argument("--est")
    ap.add_argument("--generate", metavar="DIR")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--t-max-diff", type=float, default=0.01)
    ap.add_argument("--t-offset", type=float, default=0.0)
    ap.add_argument("--cli", action="store_true", help="also run the se3 case via evo_ape/evo_rpe")
    args = ap.parse_args()
    if args.generate:
        args.ref, args.est = generate(args.generate, args.seed)
    if not (args.ref and args.est):
        ap.error("give --ref and --est, or --generate DIR")
    ref = file_interface.read_tum_trajectory_file(args.ref)
    est = file_interface.read_tum_trajectory_file(args.est)
    m = metrics.Unit.meters
    cases = {
        "none": run_case(ref, est, args),
        "se3": run_case(ref, est, args, align=True),
        "sim3": run_case(ref, est, args, align=True, scale=True),
        "origin": run_case(ref, est, args, origin=True),
        "rpe_m": run_case(ref, est, args, unit=m),
        "se3_rpe_m": run_case(ref, est, args, align=True, unit=m),
        "interp": run_case(ref, est, args, interpolate=True),
        "points_se3": run_case(ref, est, args, align=True, points=True),
    }
    if args.cli:
        cases["se3_cli"] = run_cli(args.ref, args.est, args, ["-a"])
    json.dump({"evo": __import__("evo").__version__, "reference": args.ref, "estimate": args.est,
               "cases": cases}, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
