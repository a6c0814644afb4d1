#!/usr/bin/env python3
"""Rewrites the wheels of a ROS 2 MCAP as other robots report them, with the
Python `mcap` and `rosbags` packages (independent of odocal's readers and
writers). The /joint_states messages (wheel positions, rad) are replaced:

  odometry  nav_msgs/msg/Odometry on --topic (default /odom), as a
            diff_drive_controller configured with --radius R (m) and
            --separation D (m) would publish it: wheel rates by backward
            differences of consecutive positions, V = R (w_r + w_l) / 2,
            W = R (w_r - w_l) / D, the pose integrated from them;
  ticks     std_msgs/msg/Int32MultiArray on --topic (default /wheel_ticks),
            data = [right, left] encoder counters: round(angle * N / 2pi)
            ticks for --ticks-per-rev N, plus --start, as --bits-bit signed
            counters that wrap around;
  rename    the same JointState with the joints renamed --left / --right.

Every other message is copied byte for byte. `--until S` keeps the first S
seconds (log time); `--drop TOPIC` leaves a topic out.

Usage: wheel_sources.py SRC.mcap OUT.mcap MODE [options]
"""

import argparse
import math

import numpy as np
from mcap.reader import make_reader
from mcap.writer import Writer
from rosbags.typesys import Stores, get_typestore

STORE = get_typestore(Stores.ROS2_HUMBLE)
JOINT_STATE = "sensor_msgs/msg/JointState"


def joint_angles(msg):
    names = list(msg.name)
    return {n: float(p) for n, p in zip(names, msg.position)}


class Odometry:
    """The controller: rates from consecutive wheel positions, the twist,
    and the pose integrated from it (midpoint heading)."""

    def __init__(self, radius, separation):
        self.r, self.d = radius, separation
        self.prev = None
        self.x = self.y = self.th = 0.0

    def message(self, js):
        a = joint_angles(js)
        t = js.header.stamp.sec + js.header.stamp.nanosec * 1e-9
        left, right = a["left_wheel"], a["right_wheel"]
        v = w = 0.0
        if self.prev is not None and t > self.prev[0]:
            dt = t - self.prev[0]
            wl, wr = (left - self.prev[1]) / dt, (right - self.prev[2]) / dt
            v = self.r * (wr + wl) / 2.0
            w = self.r * (wr - wl) / self.d
            mid = self.th + 0.5 * w * dt
            self.x += v * dt * math.cos(mid)
            self.y += v * dt * math.sin(mid)
            self.th += w * dt
        self.prev = (t, left, right)
        T = STORE.types
        return T["nav_msgs/msg/Odometry"](
            header=T["std_msgs/msg/Header"](stamp=js.header.stamp, frame_id="odom"),
            child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](
                pose=T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=self.x, y=self.y, z=0.0),
                    orientation=T["geometry_msgs/msg/Quaternion"](
                        x=0.0, y=0.0, z=math.sin(self.th / 2), w=math.cos(self.th / 2)
                    ),
                ),
                covariance=np.zeros(36),
            ),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](
                    linear=T["geometry_msgs/msg/Vector3"](x=v, y=0.0, z=0.0),
                    angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=w),
                ),
                covariance=np.zeros(36),
            ),
        )


class Ticks:
    """Encoder counters of `bits` bits, signed, wrapping around."""

    def __init__(self, ticks_per_rev, bits, start):
        self.n, self.bits, self.start = ticks_per_rev, bits, start

    def wrap(self, count):
        half = 1 << (self.bits - 1)
        return ((count + half) % (1 << self.bits)) - half

    def message(self, js):
        a = joint_angles(js)
        counts = [
            self.wrap(round(a[w] * self.n / (2 * math.pi)) + self.start)
            for w in ("right_wheel", "left_wheel")
        ]
        T = STORE.types
        return T["std_msgs/msg/Int32MultiArray"](
            layout=T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0),
            data=np.array(counts, dtype=np.int32),
        )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("mode", choices=["odometry", "ticks", "rename"])
    ap.add_argument("--topic")
    ap.add_argument("--radius", type=float)
    ap.add_argument("--separation", type=float)
    ap.add_argument("--ticks-per-rev", type=float)
    ap.add_argument("--bits", type=int, default=32)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--left", default="wheel_l_joint")
    ap.add_argument("--right", default="wheel_r_joint")
    ap.add_argument("--until", type=float)
    ap.add_argument("--drop", action="append", default=[])
    a = ap.parse_args()
    if a.mode == "odometry":
        conv, out_type, topic = Odometry(a.radius, a.separation), "nav_msgs/msg/Odometry", a.topic or "/odom"
    elif a.mode == "ticks":
        conv = Ticks(a.ticks_per_rev, a.bits, a.start)
        out_type, topic = "std_msgs/msg/Int32MultiArray", a.topic or "/wheel_ticks"
    else:
        conv, out_type, topic = None, JOINT_STATE, "/joint_states"
    with open(a.src, "rb") as f, open(a.dst, "wb") as out:
        w = Writer(out)
        w.start(profile="ros2", library="wheel_sources.py")
        schemas, channels, first = {}, {}, None
        new_schema = w.register_schema(out_type, "ros2msg", STORE.generate_msgdef(out_type, ros_version=2)[0].encode())
        new_channel = w.register_channel(topic, "cdr", new_schema)
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            first = message.log_time if first is None else first
            if a.until is not None and message.log_time - first > a.until * 1e9:
                break
            if channel.topic in a.drop:
                continue
            if channel.topic == "/joint_states":
                js = STORE.deserialize_cdr(message.data, JOINT_STATE)
                if conv is None:
                    js.name = [a.left, a.right] + list(js.name[2:])
                    msg = js
                else:
                    msg = conv.message(js)
                data = bytes(STORE.serialize_cdr(msg, out_type))
                w.add_message(new_channel, log_time=message.log_time, data=data, publish_time=message.log_time)
                continue
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(
                    channel.topic, channel.message_encoding, schemas[schema.id], channel.metadata
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
