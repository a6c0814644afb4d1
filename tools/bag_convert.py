#!/usr/bin/env python3
"""Rewrites a ROS 2 MCAP as the other bags robots produce, with the `rosbags`
package (an implementation independent of odocal's readers):

  OUT/bag.bag   ROS 1 bag, format 2.0 (chunks none, bz2 or lz4)
  OUT/db3/      rosbag2 folder with one SQLite file (metadata.yaml + .db3)
  OUT/mcap/     rosbag2 folder with one MCAP file

The source is read with the `mcap` package in log-time order. ROS 2 outputs
carry the CDR payloads unchanged; the ROS 1 bag gets them converted by
rosbags (`cdr_to_ros1`, which adds Header.seq), /tf_static latched as
`rosbag record` marks it. `--by-topic` writes the ROS 1 bag topic after topic
with small chunks, so that its chunks overlap in time (what a merged or
re-indexed bag looks like): a reader must merge them by time.

Usage: bag_convert.py SRC.mcap OUT [--ros1-compression none|bz2|lz4]
                      [--by-topic] [--only bag,db3,mcap]
"""

import argparse
import sys
from pathlib import Path

from mcap.reader import make_reader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore


def read_source(path):
    """All messages of the MCAP: (topic, type, log time ns, CDR bytes),
    in log-time order, and the schema texts by type."""
    msgs, schemas = [], {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            name = schema.name if schema else ""
            if schema and schema.encoding == "ros2msg":
                schemas[name] = schema.data.decode()
            msgs.append((channel.topic, name, message.log_time, bytes(message.data)))
    return msgs, schemas


def typestore_with(schemas):
    """The ROS 2 Humble types plus any the bag defines itself."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    for name, text in schemas.items():
        if name not in store.fielddefs:
            store.register(get_types_from_msg(text, name))
    return store


def write_ros1(msgs, store, out, compression, by_topic):
    writer = Writer1(out)
    if compression != "none":
        writer.set_compression(getattr(Writer1.CompressionFormat, compression.upper()))
    if by_topic:
        writer.chunk_threshold = 16 * 1024
        msgs = sorted(msgs, key=lambda m: m[0])  # stable: time order within a topic
    conns = {}
    with writer:
        for topic, name, t, data in msgs:
            if topic not in conns:
                latching = 1 if topic == "/tf_static" else None
                conns[topic] = writer.add_connection(topic, name, typestore=store, latching=latching)
            writer.write(conns[topic], t, bytes(store.cdr_to_ros1(data, name)))


def write_ros2(msgs, store, out, plugin):
    conns = {}
    with Writer2(out, version=9, storage_plugin=plugin) as writer:
        for topic, name, t, data in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, name, typestore=store)
            writer.write(conns[topic], t, data)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("out")
    ap.add_argument("--ros1-compression", default="none", choices=["none", "bz2", "lz4"])
    ap.add_argument("--by-topic", action="store_true")
    ap.add_argument("--only", default="bag,db3,mcap")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    msgs, schemas = read_source(a.src)
    store = typestore_with(schemas)
    only = set(a.only.split(","))
    if "bag" in only:
        write_ros1(msgs, store, out / "bag.bag", a.ros1_compression, a.by_topic)
    if "db3" in only:
        write_ros2(msgs, store, out / "db3", StoragePlugin.SQLITE3)
    if "mcap" in only:
        write_ros2(msgs, store, out / "mcap", StoragePlugin.MCAP)
    print(f"{len(msgs)} messages", file=sys.stderr)


if __name__ == "__main__":
    main()
