#!/usr/bin/env python3
"""The Mines rover's two sessions measured by Censi's CSM: is exp2's wheel
radius 5 % under exp1's?

Usage: mines_csm_check.py SM_TUM [--data DIR] [--work DIR] [--json]

SM_TUM is the driver built by tools/csm/build.sh (CSM's PL-ICP, sm_icp with
its default parameters). DIR is the shared data (default $ODOCAL_DATA, else
../shared/data beside the checkout).

Nothing of odocal's is used: each session's MCAP is read with the `mcap`
and `mcap_ros2` packages, its scans written as a CSM log whose odometry is
the nominal rover of BreezySLAM's mines.py (radius 77 mm, wheel base 330 mm,
the first guess of each match), CSM matches consecutive scans with the laser
145 mm ahead of the axle (the bag's /tf_static), and the wheel radius is read
as the data README's tick check does: in 2 s windows of straight driving,
the distance CSM moved the robot over the wheels' mean rotation.

A match CSM rejects takes the odometry's increment in sm_tum's trajectory;
such pairs are recognised (the increment equals the odometry's to 1e-9 m)
and every window holding one is left out, so no window carries the nominal
radius.

Printed per session: the radius as the least-squares scale of wheel rotation
onto CSM's distance over the straight windows (the data README's reading;
a window starts at every other scan, so they overlap), the windows' median,
and the least-squares scale of every accepted match's forward motion (turns
included, no window); then the three exp1/exp2 ratios, each with its std
and 95 % interval from a block bootstrap (2 s blocks, seed 1). The data README's
tick check gives 1.054. Scans and wheels are paired by stamp, as the tick
check pairs them (no time offset).
"""
import argparse
import bisect
import json
import math
import os
import random
import statistics
import subprocess
import sys
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

import csm_export  # this folder's: the CSM log records the benchmark runs use

NOMINAL_RADIUS_M = 0.077  # mines.py: WheeledVehicle(77, 165)
NOMINAL_BASE_M = 0.330
LASER_X_M = 0.145  # the bags' /tf_static, mines.py's URG04LX(70, 145)
WINDOW_SCANS = 20  # 2 s at 10 Hz
WINDOW_STEP = 2  # a window starts at every other scan (they overlap)
STRAIGHT_RAD = 0.05  # largest turn in a straight window (rad)
MIN_TRAVEL_M = 0.2  # shortest window travel, by the nominal radius (m)


def stamp(h):
    return h.stamp.sec + h.stamp.nanosec * 1e-9


def read(bag):
    """Scans and (stamp, left, right) wheel angles (rad), in stamp order."""
    scans, wheels = [], []
    with open(bag, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, ch, _, m in reader.iter_decoded_messages(topics=["/scan", "/joint_states"]):
            if ch.topic == "/scan":
                scans.append((stamp(m.header), m))
            else:
                pos = dict(zip(m.name, m.position))
                wheels.append((stamp(m.header), pos["left_wheel"], pos["right_wheel"]))
    scans.sort(key=lambda s: s[0])
    wheels.sort(key=lambda w: w[0])
    return scans, wheels


def wheels_at(wheels, ts, t):
    """Wheel angles linearly interpolated at t (held beyond the ends); ts
    are the wheels' stamps."""
    i = bisect.bisect_left(ts, t)
    if i == 0:
        return wheels[0][1:]
    if i >= len(wheels):
        return wheels[-1][1:]
    (t0, l0, r0), (t1, l1, r1) = wheels[i - 1], wheels[i]
    s = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
    return (l0 + s * (l1 - l0), r0 + s * (r1 - r0))


def nominal_odometry(angles):
    """Dead reckoning of the nominal rover over consecutive wheel angles."""
    x = y = th = 0.0
    poses = [(x, y, th)]
    for (l0, r0), (l1, r1) in zip(angles, angles[1:]):
        dl, dr = NOMINAL_RADIUS_M * (l1 - l0), NOMINAL_RADIUS_M * (r1 - r0)
        ds, dth = 0.5 * (dl + dr), (dr - dl) / NOMINAL_BASE_M
        x += ds * math.cos(th + 0.5 * dth)
        y += ds * math.sin(th + 0.5 * dth)
        th += dth
        poses.append((x, y, th))
    return poses


def read_tum(path):
    """Poses (x, y, yaw) of a TUM file, in its order."""
    rows = []
    for line in Path(path).read_text().splitlines():
        _, x, y, _, _, _, qz, qw = map(float, line.split())
        rows.append((x, y, 2.0 * math.atan2(qz, qw)))
    return rows


def increment(a, b):
    """b in a's frame (x, y, yaw)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], 2 * math.pi))


def session(bag, sm_tum, work):
    scans, wheels = read(bag)
    if len(scans) < 2 * WINDOW_SCANS or not wheels:
        sys.exit(f"{bag}: too few scans or no /joint_states")
    ts = [w[0] for w in wheels]
    angles = [wheels_at(wheels, ts, t) for t, _ in scans]
    odo = nominal_odometry(angles)
    # The scans in CSM's log format as csm_export.py writes them, each with
    # the nominal odometry at its own stamp.
    ns = [csm_export.stamp(m.header) for _, m in scans]
    odom = [(t, *o) for t, o in zip(ns, odo)]
    log = work / (bag.stem + ".json")
    with open(log, "w") as f:
        for t, (_, m) in zip(ns, scans):
            f.write(json.dumps(csm_export.record(t, m, odom, ns)) + "\n")
    tum = work / (bag.stem + ".tum")
    with open(tum, "w") as out, open(work / (bag.stem + ".err"), "w") as err:
        subprocess.run(
            [sm_tum, "-in", str(log), "-laser_x", str(LASER_X_M)], stdout=out, stderr=err, check=True
        )
    poses = read_tum(tum)
    if len(poses) != len(scans):
        sys.exit(f"{tum}: {len(poses)} poses for {len(scans)} scans")
    failed = [
        max(abs(p - q) for p, q in zip(increment(poses[i], poses[i + 1]), increment(odo[i], odo[i + 1]))) < 1e-9
        for i in range(len(poses) - 1)
    ]
    return windows(poses, angles, failed), matches(poses, angles, failed), sum(failed)


def windows(poses, angles, failed):
    """(distance by CSM (m), mean wheel rotation (rad)) of each straight 2 s
    window with no rejected match, one starting at every other scan."""
    out = []
    for i in range(0, len(poses) - WINDOW_SCANS, WINDOW_STEP):
        j = i + WINDOW_SCANS
        if any(failed[i:j]):
            continue
        dx, dy, dth = increment(poses[i], poses[j])
        rot = 0.5 * ((angles[j][0] - angles[i][0]) + (angles[j][1] - angles[i][1]))
        if abs(dth) > STRAIGHT_RAD or abs(rot) * NOMINAL_RADIUS_M < MIN_TRAVEL_M:
            continue
        out.append((math.hypot(dx, dy), abs(rot)))
    return out


def matches(poses, angles, failed):
    """(forward motion by CSM (m), mean wheel rotation (rad)) of every
    accepted match."""
    out = []
    for i, bad in enumerate(failed):
        if not bad:
            rot = 0.5 * ((angles[i + 1][0] - angles[i][0]) + (angles[i + 1][1] - angles[i][1]))
            out.append((increment(poses[i], poses[i + 1])[0], rot))
    return out


def least_squares(pairs):
    """Radius (m): the scale of wheel rotation onto distance."""
    return sum(d * s for d, s in pairs) / sum(s * s for _, s in pairs)


def block_bootstrap(a, b, block, stat, seed=1, draws=2000):
    """Std and 95 % interval of stat(a) / stat(b), a and b resampled in
    blocks of `block` consecutive items (overlapping windows and
    consecutive matches are not independent)."""
    rng = random.Random(seed)
    blocks = [[x[i : i + block] for i in range(0, len(x), block)] for x in (a, b)]
    ratios = sorted(
        stat([p for _ in bl for p in rng.choice(bl)]) / stat([p for _ in bl2 for p in rng.choice(bl2)])
        for bl, bl2 in [blocks] * draws
    )
    return statistics.pstdev(ratios), ratios[int(0.025 * draws)], ratios[int(0.975 * draws) - 1]


def radii(win, each):
    return {
        "windows": len(win),
        "windows_least_squares": least_squares(win),
        "windows_median": statistics.median(d / s for d, s in win),
        "matches": len(each),
        "matches_least_squares": least_squares(each),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sm_tum")
    default = os.environ.get("ODOCAL_DATA", str(Path(__file__).resolve().parents[1] / "../shared/data"))
    ap.add_argument("--data", default=default)
    ap.add_argument("--work", default="target/mines-csm")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    res, lists = {}, {}
    for e in ["exp1", "exp2"]:
        bag = Path(a.data) / "mines-rover" / f"{e}.mcap"
        if not bag.is_file():
            sys.exit(f"{bag}: not found (set ODOCAL_DATA or --data)")
        win, each, rejected = session(bag, a.sm_tum, work)
        if not win:
            sys.exit(f"{bag}: no straight 2 s window without a rejected match")
        res[e] = radii(win, each) | {"rejected": rejected}
        lists[e] = (win, each)
    keys = ["windows_least_squares", "windows_median", "matches_least_squares"]
    res["ratio"] = {k: res["exp1"][k] / res["exp2"][k] for k in keys}
    spread = {
        "windows_least_squares": (lists["exp1"][0], lists["exp2"][0], WINDOW_SCANS // WINDOW_STEP, least_squares),
        "windows_median": (lists["exp1"][0], lists["exp2"][0], WINDOW_SCANS // WINDOW_STEP,
                           lambda w: statistics.median(d / s for d, s in w)),
        "matches_least_squares": (lists["exp1"][1], lists["exp2"][1], WINDOW_SCANS, least_squares),
    }
    res["ratio_spread"] = {k: dict(zip(["std", "low95", "high95"], block_bootstrap(*v)))
                           for k, v in spread.items()}
    if a.json:
        print(json.dumps(res, indent=1))
        return
    for e in ["exp1", "exp2"]:
        r = res[e]
        print(f"{e}: radius (mm) over {r['windows']} straight 2 s windows: least squares "
              f"{1e3 * r['windows_least_squares']:.1f}, median {1e3 * r['windows_median']:.1f}; "
              f"over {r['matches']} accepted matches ({r['rejected']} rejected): least squares "
              f"{1e3 * r['matches_least_squares']:.1f}")
    for k, q in res["ratio"].items():
        sp = res["ratio_spread"][k]
        print(f"exp1/exp2, {k.replace('_', ' ')}: {q:.3f} ± {sp['std']:.3f} "
              f"(95 % {sp['low95']:.3f}–{sp['high95']:.3f})")
    print("the data README's tick check: 1.054")


if __name__ == "__main__":
    main()
