#!/usr/bin/env python3
"""Writes a ROS 2 bag's laser scans in CSM's JSON log format, for matching
the same scans with Censi's CSM (github.com/AndreaCensi/csm, `sm3` and the
like) beside odocal.

Usage: csm_export.py BAG OUT.json [--scan-topic /scan] [--odom-topic /odom]

Reads BAG with the `mcap` and `mcap_ros2` packages (not odocal's code). One
JSON object per line and scan, in stamp order:

  {"nrays", "min_theta", "max_theta", "theta": [...], "readings": [...],
   "valid": [...], "odometry": [x, y, theta], "timestamp": [sec, usec]}

- `theta` are the scan's true beam angles, angle_min + i * angle_increment
  (the laser frame; CSM's `laser_x/y/theta` parameters place it on the robot);
- a reading is valid when finite and within [range_min, range_max] of its
  message (REP 117; the Freiburg logs' no-return values lie beyond range_max);
  invalid readings are written as -1 with valid = 0;
- `odometry` is the odometry topic's pose linearly interpolated at the scan
  stamp (heading unwrapped), the odometry nearest in time before the first
  and after the last odometry message;
- `timestamp` is the scan's header stamp as [seconds, microseconds].

Scans with duplicate stamps are kept (CSM matches them like any other).
"""
import argparse
import bisect
import json
import math
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def stamp(h):
    return int(h.stamp.sec) * 10**9 + int(h.stamp.nanosec)


def read(bag, scan_topic, odom_topic):
    scans, odom = [], []
    with open(bag, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, m in reader.iter_decoded_messages(topics=[scan_topic, odom_topic]):
            if channel.topic == scan_topic:
                scans.append((stamp(m.header), m))
            else:
                p = m.pose.pose
                odom.append((stamp(m.header), p.position.x, p.position.y, yaw(p.orientation)))
    scans.sort(key=lambda s: s[0])
    odom.sort(key=lambda o: o[0])
    # Unwrap the heading so interpolation never crosses ±π the long way.
    for i in range(1, len(odom)):
        t, x, y, th = odom[i]
        prev = odom[i - 1][3]
        th = prev + math.remainder(th - prev, 2 * math.pi)
        odom[i] = (t, x, y, th)
    return scans, odom


def odometry_at(odom, stamps, t):
    if not odom:
        return [0.0, 0.0, 0.0]
    i = bisect.bisect_left(stamps, t)
    if i == 0:
        return list(odom[0][1:])
    if i >= len(odom):
        return list(odom[-1][1:])
    (t0, *a), (t1, *b) = odom[i - 1], odom[i]
    s = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
    x, y, th = (a[k] + s * (b[k] - a[k]) for k in range(3))
    return [x, y, math.remainder(th, 2 * math.pi)]


def record(t, m, odom, stamps):
    n = len(m.ranges)
    theta = [m.angle_min + i * m.angle_increment for i in range(n)]
    valid = [int(math.isfinite(r) and m.range_min <= r <= m.range_max) for r in m.ranges]
    readings = [float(r) if v else -1.0 for r, v in zip(m.ranges, valid)]
    return {
        "nrays": n,
        "min_theta": theta[0] if n else 0.0,
        "max_theta": theta[-1] if n else 0.0,
        "theta": theta,
        "readings": readings,
        "valid": valid,
        "odometry": odometry_at(odom, stamps, t),
        "timestamp": [t // 10**9, (t % 10**9) // 1000],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("bag")
    ap.add_argument("out")
    ap.add_argument("--scan-topic", default="/scan")
    ap.add_argument("--odom-topic", default="/odom")
    a = ap.parse_args()
    scans, odom = read(a.bag, a.scan_topic, a.odom_topic)
    if not scans:
        sys.exit(f"{a.bag}: no messages on {a.scan_topic}")
    stamps = [o[0] for o in odom]
    with open(a.out, "w") as f:
        for t, m in scans:
            f.write(json.dumps(record(t, m, odom, stamps)) + "\n")
    print(f"{a.out}: {len(scans)} scans, {len(odom)} odometry poses", file=sys.stderr)


if __name__ == "__main__":
    main()
