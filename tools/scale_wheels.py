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

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

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
    changed = 0
    with open(a.src, "rb") as f, open(a.dst, "wb") as out:
        w = Writer(out, compression=CompressionType.ZSTD)
        w.start("ros2", "scale_wheels")
        schemas, channels = {}, {}
        for schema, channel, msg in make_reader(f).iter_messages(log_time_order=True):
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas.get(channel.schema_id, 0),
                    channel.metadata,
                )
            data = msg.data
            if schema is not None and schema.name == JOINT_STATE:
                data = scaled(store, data, a.scale, joints)
                changed += 1
            w.add_message(channels[channel.id], msg.log_time, data, msg.publish_time, msg.sequence)
        w.finish()
    print(f"{changed} JointState messages scaled by 1/{a.scale}", file=sys.stderr)


if __name__ == "__main__":
    main()
