#!/usr/bin/env python3
"""Independent decoder for odocal's MCAP cross-checks.

Usage: mcap_dump.py BAG [--all TOPIC]...

Reads BAG with the `mcap` and `mcap_ros2` packages (not odocal's code) and
prints one JSON object on stdout:

  {"profile": ..., "library": ...,
   "topics": {TOPIC: {"schema": NAME, "schema_encoding": ..., "schema_text": ...,
                      "message_encoding": ..., "metadata": {...}, "count": N,
                      "messages": [{"index": i, "log_time": ns, ...decoded fields}]}}}

Messages are indexed in file order, per topic. By default a few messages per
topic are decoded (first, second, quarter, middle, three quarters, last);
`--all TOPIC` decodes every message of TOPIC. Non-finite floats are written as
the strings "nan", "inf", "-inf" so the output is strict JSON.
"""
import json
import math
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def num(x):
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


def header(h):
    return {"sec": int(h.stamp.sec), "nanosec": int(h.stamp.nanosec), "frame_id": h.frame_id}


def pose(p):
    return {
        "x": num(p.position.x), "y": num(p.position.y), "z": num(p.position.z),
        "qx": num(p.orientation.x), "qy": num(p.orientation.y),
        "qz": num(p.orientation.z), "qw": num(p.orientation.w),
    }


def decode_fields(schema, m):
    s = schema.replace("/msg/", "/")
    if s == "sensor_msgs/LaserScan":
        return {
            "header": header(m.header),
            "angle_min": num(m.angle_min), "angle_max": num(m.angle_max),
            "angle_increment": num(m.angle_increment),
            "time_increment": num(m.time_increment), "scan_time": num(m.scan_time),
            "range_min": num(m.range_min), "range_max": num(m.range_max),
            "ranges": [num(r) for r in m.ranges],
            "intensities": len(m.intensities),
        }
    if s == "sensor_msgs/JointState":
        return {
            "header": header(m.header), "name": list(m.name),
            "position": [num(v) for v in m.position],
            "velocity": [num(v) for v in m.velocity],
            "effort": [num(v) for v in m.effort],
        }
    if s == "sensor_msgs/Imu":
        av = m.angular_velocity
        return {"header": header(m.header),
                "angular_velocity": [num(av.x), num(av.y), num(av.z)]}
    if s == "nav_msgs/Odometry":
        return {"header": header(m.header), "child_frame_id": m.child_frame_id,
                "pose": pose(m.pose.pose)}
    if s == "geometry_msgs/PoseStamped":
        return {"header": header(m.header), "pose": pose(m.pose)}
    if s == "geometry_msgs/PointStamped":
        return {"header": header(m.header),
                "point": [num(m.point.x), num(m.point.y), num(m.point.z)]}
    if s == "tf2_msgs/TFMessage":
        out = []
        for t in m.transforms:
            tr, q = t.transform.translation, t.transform.rotation
            out.append({"header": header(t.header), "child_frame_id": t.child_frame_id,
                        "translation": [num(tr.x), num(tr.y), num(tr.z)],
                        "rotation": [num(q.x), num(q.y), num(q.z), num(q.w)]})
        return {"transforms": out}
    return {}


def main():
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    path, rest = args[0], args[1:]
    full = {rest[i + 1] for i in range(len(rest) - 1) if rest[i] == "--all"}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        head = reader.get_header()
        summary = reader.get_summary()
        counts = {}
        for _schema, channel, _msg in reader.iter_messages(log_time_order=False):
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
        topics = {}
        wanted = {}
        for ch in summary.channels.values():
            sc = summary.schemas.get(ch.schema_id)
            n = counts.get(ch.topic, 0)
            topics[ch.topic] = {
                "schema": sc.name if sc else "",
                "schema_encoding": sc.encoding if sc else "",
                "schema_text": sc.data.decode() if sc else "",
                "message_encoding": ch.message_encoding,
                "metadata": dict(ch.metadata),
                "count": n,
                "messages": [],
            }
            if ch.topic in full:
                wanted[ch.topic] = set(range(n))
            else:
                wanted[ch.topic] = {i for i in (0, 1, n // 4, n // 2, 3 * n // 4, n - 1) if 0 <= i < n}
        index = {}
        factory = DecoderFactory()
        decoders = {}
        for sc, ch, msg in reader.iter_messages(log_time_order=False):
            i = index.get(ch.topic, 0)
            index[ch.topic] = i + 1
            if i in wanted.get(ch.topic, ()):
                if ch.id not in decoders:
                    decoders[ch.id] = factory.decoder_for(ch.message_encoding, sc)
                decoded = decoders[ch.id](msg.data)
                rec = {"index": i, "log_time": msg.log_time}
                rec.update(decode_fields(sc.name, decoded))
                topics[ch.topic]["messages"].append(rec)
    json.dump({"profile": head.profile, "library": head.library, "topics": topics},
              sys.stdout, allow_nan=False)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
