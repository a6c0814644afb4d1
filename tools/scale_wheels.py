#!/usr/bin/env python3
"""Rewrites a ROS 2 MCAP as if the robot's wheels had grown: every
`sensor_msgs/msg/JointState` position and velocity of the named joints is
divided by K, so that the same motion reads as a radius K times larger
(distance = r·φ). Everything else is copied byte for byte, stamps included.

It is written with the `mcap` and `rosbags` packages, independently of
odocal's readers and writers: a real recording with a known radius change
that odocal's own simulator did not make.

Usage: scale_wheels.py SRC.mcap DST.mcap --scale K [--joints a,b]
       (default: every joint of every JointState)
"""

import argparse
import sys
from dataclasses import replace

import numpy as np

from rosbags.typesys import Stores, get_typestore

from mcap_rewrite import rewrite

JOINT_STATE = "sensor_msgs/msg/JointState"


def scaled(store, data, k, joints):
    """The JointState CDR `data` with the named joints' position and
    velocity divided by `k`."""
    msg = store.deserialize_cdr(data, JOINT_STATE)
    pick = [joints is None or n in joints for n in msg.name]
    for field in ("position", "velocity"):
        values = np.array(getattr(msg, field), dtype=np.float64, copy=True)
        n = min(len(values), len(pick))
        values[:n][np.array(pick[:n], dtype=bool)] /= k
        msg = replace(msg, **{field: values})
    return bytes(store.serialize_cdr(msg, JOINT_STATE))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--scale", type=float, required=True)
    ap.add_argument("--joints", default=None)
    a = ap.parse_args()
    if not a.scale > 0:
        sys.exit("--scale must be > 0")
    joints = set(a.joints.split(",")) if a.joints else None
    store = get_typestore(Stores.ROS2_HUMBLE)

    def change(kind, topic, log_time, data):
        if kind != JOINT_STATE:
            return None
        return log_time, scaled(store, data, a.scale, joints)

    changed = rewrite(a.src, a.dst, "scale_wheels", change)
    print(f"{changed} JointState messages scaled by 1/{a.scale}", file=sys.stderr)


if __name__ == "__main__":
    main()
