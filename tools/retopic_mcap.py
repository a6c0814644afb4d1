#!/usr/bin/env python3
"""Copies an MCAP with the Python `mcap` library (independent of odocal),
moving or dropping topics: how other robots' bags state (or do not state)
their transforms.

    retopic_mcap.py IN.mcap OUT.mcap [--move FROM=TO]... [--drop TOPIC]...

`--move /tf_static=/tf` puts the static transforms on /tf (as a robot whose
robot_state_publisher publishes every joint there); `--drop /tf_static`
leaves the mounting unstated. Message bytes are copied unchanged.
"""
import argparse

from mcap.reader import make_reader
from mcap.writer import Writer


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--move", action="append", default=[])
    ap.add_argument("--drop", action="append", default=[])
    a = ap.parse_args()
    moves = dict(m.split("=", 1) for m in a.move)
    with open(a.src, "rb") as f, open(a.dst, "wb") as out:
        reader = make_reader(f)
        w = Writer(out)
        w.start(profile="ros2", library="retopic_mcap.py")
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.topic in a.drop:
                continue
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(
                    moves.get(channel.topic, channel.topic),
                    channel.message_encoding,
                    schemas[schema.id],
                    channel.metadata,
                )
            w.add_message(
                channels[channel.id],
                log_time=message.log_time,
                data=message.data,
                publish_time=message.publish_time,
                sequence=message.sequence,
            )
        w.finish()


if __name__ == "__main__":
    main()
