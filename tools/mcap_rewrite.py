"""Copies a ROS 2 MCAP message by message, letting a function rewrite some:
the loop `scale_wheels.py` and `rewrite_effects.py` share (Python `mcap`)."""

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer


def rewrite(src, dst, library, change):
    """Writes `dst` from `src` with `change(schema_name, topic, log_time,
    data)` -> `(log_time, data)` for a rewritten message or None to copy it
    byte for byte; returns how many were rewritten."""
    changed = 0
    with open(src, "rb") as f, open(dst, "wb") as out:
        w = Writer(out, compression=CompressionType.ZSTD)
        w.start("ros2", library)
        schemas, channels = {}, {}
        for schema, channel, msg in make_reader(f).iter_messages(log_time_order=True):
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(
                    channel.topic, channel.message_encoding,
                    schemas.get(channel.schema_id, 0), channel.metadata)
            log_time, data = msg.log_time, msg.data
            new = change(schema.name if schema is not None else "", channel.topic, log_time, data)
            if new is not None:
                log_time, data = new
                changed += 1
            w.add_message(channels[channel.id], log_time, data, msg.publish_time, msg.sequence)
        w.finish()
    return changed
