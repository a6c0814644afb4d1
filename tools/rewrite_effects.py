#!/usr/bin/env python3
"""Rewrites a clean ROS 2 MCAP so that it records one effect or fault, by laws
written here and nowhere in odocal.

odocal's simulator and its diagnosis share one law for every effect
(`effects::Departures`), so a diagnosis that names the simulator's effects may
only recognise its own formulas. This tool writes the same physical
departures into a recording after the fact, with the `mcap` and `rosbags`
packages and its own arithmetic, so that the diagnosis meets laws it did not
write. Every message it does not rewrite is copied byte for byte.

Laws (JOINT = right_wheel or left_wheel; angles in rad, times in s):

  radius:JOINT=K        the wheel's rolling radius is (1 + K) times the robot
                        file's: the same ground distance turns it 1/(1 + K) as
                        far, so its positions and velocities are divided by 1 + K
                        (table effect radius_scale, parameter K)
  latency:DELAY         the encoder stream is DELAY late: every JointState's
                        header stamp and log time move DELAY later
                        (table effect latency)
  mounting:DX,DY,DYAW   the laser sits DX, DY, DYAW away from where /tf_static
                        says: the stated base_link -> laser transform is moved
                        by minus that (table effect laser_offset)
  out_of_round:JOINT=A  the encoder reads p - A sin p of the wheel's true angle p
                        (fault wheel_out_of_round)
  gyro_scale:K          the gyro reads (1 + K) times the turn rate (not in the
                        effect table)
  backlash:JOINT=B      a dead band of B rad between wheel and encoder: after a
                        reversal the reading stays until the wheel has turned B
                        back (not in the effect table)
  quantise:TICKS        positions rounded to whole ticks of 2 pi / TICKS (not in
                        the effect table)

Usage: rewrite_effects.py SRC.mcap DST.mcap LAW
"""

import argparse
import math
import sys
from dataclasses import replace

import numpy as np
from rosbags.typesys import Stores, get_typestore

from mcap_rewrite import rewrite

JOINT_STATE = "sensor_msgs/msg/JointState"
IMU = "sensor_msgs/msg/Imu"
TF = "tf2_msgs/msg/TFMessage"


def parse(law):
    """(name, value) of a LAW argument: value a float, a (joint, float) pair
    or a three-float tuple."""
    name, _, arg = law.partition(":")
    if name in ("radius", "out_of_round", "backlash"):
        joint, _, v = arg.partition("=")
        if joint not in ("right_wheel", "left_wheel"):
            raise ValueError(f"{law}: name right_wheel or left_wheel")
        return name, (joint, float(v))
    if name in ("latency", "gyro_scale", "quantise"):
        return name, float(arg)
    if name == "mounting":
        parts = [float(x) for x in arg.split(",")]
        if len(parts) != 3:
            raise ValueError(f"{law}: give DX,DY,DYAW")
        return name, tuple(parts)
    raise ValueError(f"{law}: unknown law (see --help)")


class Joints:
    """Rewrites JointState positions (and velocities) by a per-joint law
    that may keep state from message to message (the backlash)."""

    def __init__(self, name, value):
        self.name, self.value = name, value
        self.reading = {}  # backlash: the encoder's last reading per joint

    def position(self, joint, p):
        if self.name == "radius" and joint == self.value[0]:
            return p / (1.0 + self.value[1])
        if self.name == "out_of_round" and joint == self.value[0]:
            return p - self.value[1] * math.sin(p)
        if self.name == "backlash" and joint == self.value[0]:
            b = self.value[1]
            r = self.reading.get(joint, p)
            # The encoder moves only when the wheel pushes it from one side of
            # the band or the other.
            if p > r + b:
                r = p - b
            elif p < r - b:
                r = p + b
            self.reading[joint] = r
            return r
        if self.name == "quantise":
            tick = 2.0 * math.pi / self.value
            return math.floor(p / tick + 0.5) * tick
        return p

    def velocity(self, joint, p, v):
        if self.name == "radius" and joint == self.value[0]:
            return v / (1.0 + self.value[1])
        if self.name == "out_of_round" and joint == self.value[0]:
            return v * (1.0 - self.value[1] * math.cos(p))
        return v

    def rewrite(self, store, data):
        msg = store.deserialize_cdr(data, JOINT_STATE)
        pos = np.array(msg.position, dtype=np.float64, copy=True)
        vel = np.array(msg.velocity, dtype=np.float64, copy=True)
        for i, joint in enumerate(msg.name):
            p = pos[i] if i < len(pos) else None
            if i < len(vel) and p is not None:
                vel[i] = self.velocity(joint, p, vel[i])
            if p is not None:
                pos[i] = self.position(joint, p)
        msg = replace(msg, position=pos, velocity=vel)
        return bytes(store.serialize_cdr(msg, JOINT_STATE))


def later(store, data, delay):
    """A JointState whose header stamp is `delay` s later."""
    msg = store.deserialize_cdr(data, JOINT_STATE)
    ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec + round(delay * 1e9)
    stamp = replace(msg.header.stamp, sec=ns // 10**9, nanosec=ns % 10**9)
    msg = replace(msg, header=replace(msg.header, stamp=stamp))
    return bytes(store.serialize_cdr(msg, JOINT_STATE))


def gyro(store, data, k):
    """An Imu whose turn rate reads (1 + k) times."""
    msg = store.deserialize_cdr(data, IMU)
    w = replace(msg.angular_velocity, z=msg.angular_velocity.z * (1.0 + k))
    return bytes(store.serialize_cdr(replace(msg, angular_velocity=w), IMU))


def stated_mount(store, data, d):
    """A TFMessage whose base_link -> laser transform is moved by -d: the
    laser is d from where the recording now says it is."""
    msg = store.deserialize_cdr(data, TF)
    out = []
    for t in msg.transforms:
        if t.child_frame_id.lstrip("/") == "laser":
            q = t.transform.rotation
            yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
            yaw -= d[2]
            tr = replace(
                t.transform.translation,
                x=t.transform.translation.x - d[0],
                y=t.transform.translation.y - d[1],
            )
            rot = replace(q, x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
            t = replace(t, transform=replace(t.transform, translation=tr, rotation=rot))
        out.append(t)
    return bytes(store.serialize_cdr(replace(msg, transforms=out), TF))


def main():
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=__doc__.split("\n\n", 2)[2])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("law")
    a = ap.parse_args()
    try:
        name, value = parse(a.law)
    except ValueError as e:
        sys.exit(str(e))
    store = get_typestore(Stores.ROS2_HUMBLE)
    joints = Joints(name, value)

    def change(kind, topic, log_time, data):
        if kind == JOINT_STATE and name in ("radius", "out_of_round", "backlash", "quantise"):
            return log_time, joints.rewrite(store, data)
        if kind == JOINT_STATE and name == "latency":
            return log_time + round(value * 1e9), later(store, data, value)
        if kind == IMU and name == "gyro_scale":
            return log_time, gyro(store, data, value)
        if kind == TF and name == "mounting" and topic == "/tf_static":
            return log_time, stated_mount(store, data, value)
        return None

    changed = rewrite(a.src, a.dst, "rewrite_effects", change)
    if changed == 0:
        sys.exit(f"{a.src}: no message the law {a.law} rewrites")
    print(f"{changed} messages rewritten ({a.law})", file=sys.stderr)


if __name__ == "__main__":
    main()
