#!/usr/bin/env python3
"""An independent ROS 2 peer for `odocal live`, with no ROS installed:
Cyclone DDS (the `cyclonedds` package from PyPI, which bundles it) and the
`mcap` package, nothing of odocal.

`listen` subscribes to a recording's topics (as `odocal play` publishes
them) for `--seconds` and prints what came: counts, the stamps' order, the
first scan's fields and the static transform, to compare with the MCAP.

`publish` reads a ROS 2 MCAP with `mcap`, decodes each message with
Cyclone's own CDR (the message types are declared below from the ROS 2
interface definitions, with ROS 2's DDS type names) and publishes it on
`rt/<topic>` at the log times scaled by `--rate`, with the QoS a robot's
drivers use: scans and the gyro best effort (sensor data), the joint states
reliable, /tf_static reliable and transient-local. It waits until odocal's
readers are matched, and listens meanwhile to `/odocal/odometry` and
`/diagnostics`. `--malformed N` also sends N scans that are not LaserScans
(another layout under LaserScan's type name) and one larger than the
node's limit. It prints one JSON object: what it sent and what it heard.

Both sides are pinned to 127.0.0.1 (CYCLONEDDS_URI, set here unless given).
`discovery` measures how long a participant of this peer and `odocal live`
take to match, in both orders of joining.
"""
import argparse
import json
import os
import sys
import time
from dataclasses import dataclass, field

# ParticipantIndex auto: Cyclone listens on the well-known unicast
# discovery ports, where a participant that joins later (odocal) announces
# itself first; with Cyclone's default (none, an ephemeral port) it would be
# found only at Cyclone's next periodic announcement, seconds later.
os.environ.setdefault(
    "CYCLONEDDS_URI",
    "<CycloneDDS><Domain><General><Interfaces>"
    '<NetworkInterface address="127.0.0.1"/></Interfaces></General>'
    "<Discovery><ParticipantIndex>auto</ParticipantIndex></Discovery>"
    "</Domain></CycloneDDS>",
)

from cyclonedds.core import Qos, Policy  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import float32, float64, int32, uint32, uint8, sequence, array  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from mcap.reader import make_reader  # noqa: E402


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header
    angle_min: float32
    angle_max: float32
    angle_increment: float32
    time_increment: float32
    scan_time: float32
    range_min: float32
    range_max: float32
    ranges: sequence[float32]
    intensities: sequence[float32]


@dataclass
class NotALaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    """Another layout under LaserScan's name: what a misconfigured or
    broken publisher sends."""
    header: Header
    junk: sequence[uint8]


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Imu(IdlStruct, typename="sensor_msgs::msg::dds_::Imu_"):
    header: Header
    orientation: Quaternion
    orientation_covariance: array[float64, 9]
    angular_velocity: Vector3
    angular_velocity_covariance: array[float64, 9]
    linear_acceleration: Vector3
    linear_acceleration_covariance: array[float64, 9]


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Vector3
    orientation: Quaternion


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: array[float64, 36]


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist
    covariance: array[float64, 36]


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key: str
    value: str


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level: uint8
    name: str
    message: str
    hardware_id: str
    values: sequence[KeyValue]


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header: Header
    status: sequence[DiagnosticStatus]


TYPES = {
    "sensor_msgs/msg/LaserScan": LaserScan,
    "sensor_msgs/msg/JointState": JointState,
    "sensor_msgs/msg/Imu": Imu,
    "tf2_msgs/msg/TFMessage": TFMessage,
}

SENSOR = Qos(
    Policy.Reliability.BestEffort,
    Policy.Durability.Volatile,
    Policy.History.KeepLast(5),
)
RELIABLE = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.Volatile,
    Policy.History.KeepLast(10),
)
LATCHED = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.TransientLocal,
    Policy.History.KeepLast(1),
)


def qos_for(topic, type_name):
    if topic == "/tf_static":
        return LATCHED
    if type_name == "sensor_msgs/msg/JointState":
        return RELIABLE
    return SENSOR


# The listener's own readers keep everything between two polls.
HEARD = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.Volatile,
    Policy.History.KeepAll,
)


class Listener:
    """Counts and keeps what odocal publishes."""

    def __init__(self, dp):
        self.odom = DataReader(dp, Topic(dp, "rt/odocal/odometry", Odometry), qos=HEARD)
        self.diag = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray), qos=HEARD)
        self.n_odom = 0
        self.n_diag = 0
        self.last_odom = None
        self.levels = []
        self.last_status = None
        self.odom_stamps_increase = True
        self.first_diag_s = None
        self.t0 = time.monotonic()

    def poll(self):
        for m in self.odom.take(N=100000):
            if not isinstance(m, Odometry):
                continue
            s = m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec
            if self.last_odom is not None and s < self.last_odom["stamp"]:
                self.odom_stamps_increase = False
            self.n_odom += 1
            self.last_odom = {
                "stamp": s,
                "frame_id": m.header.frame_id,
                "child_frame_id": m.child_frame_id,
                "x": m.pose.pose.position.x,
                "y": m.pose.pose.position.y,
            }
        for m in self.diag.take(N=100):
            if not isinstance(m, DiagnosticArray):
                continue
            self.n_diag += 1
            if self.first_diag_s is None:
                self.first_diag_s = time.monotonic() - self.t0
            for st in m.status:
                if st.name == "odocal: calibration":
                    self.levels.append(int(st.level))
                    self.last_status = {
                        "level": int(st.level),
                        "message": st.message,
                        "values": {kv.key: kv.value for kv in st.values},
                    }


def wait_matched(writers, listener, timeout):
    """Until every writer has a matched reader (odocal's), or timeout."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        listener.poll()
        if all(w.get_publication_matched_status().current_count > 0 for w in writers.values()):
            return True
        time.sleep(0.05)
    return False


def publish(args):
    joined = time.monotonic()
    dp = DomainParticipant(args.domain)
    listener = Listener(dp)
    writers, topics, plan = {}, {}, []
    with open(args.mcap, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            cls = TYPES.get(schema.name)
            if cls is None or channel.topic not in args.topics:
                continue
            if channel.topic not in writers:
                t = Topic(dp, "rt" + channel.topic, cls)
                topics[channel.topic] = t
                writers[channel.topic] = DataWriter(dp, t, qos=qos_for(channel.topic, schema.name))
            plan.append((message.log_time, channel.topic, cls.deserialize(message.data)))
    matched = wait_matched(writers, listener, args.match_timeout)
    matched_s = time.monotonic() - joined
    sent = {}
    t0 = plan[0][0] if plan else 0
    w0 = time.monotonic()
    behind = 0.0
    for i, (log_time, topic, msg) in enumerate(plan):
        due = w0 + (log_time - t0) * 1e-9 / args.rate
        now = time.monotonic()
        if due > now:
            time.sleep(due - now)
        else:
            behind = max(behind, now - due)
        writers[topic].write(msg)
        sent[topic] = sent.get(topic, 0) + 1
        if i % 50 == 0:
            listener.poll()
    bad = 0
    if args.malformed:
        bad = send_malformed(args)
    end = time.monotonic() + args.linger
    while time.monotonic() < end:
        listener.poll()
        time.sleep(0.05)
    return {
        "matched": matched,
        "matched_s": matched_s,
        "sent": sent,
        "malformed_sent": bad,
        "max_behind_s": behind,
        "play_wall_s": time.monotonic() - w0,
        "odometry_received": listener.n_odom,
        "odometry_stamps_increase": listener.odom_stamps_increase,
        "last_odometry": listener.last_odom,
        "diagnostics_received": listener.n_diag,
        "first_diagnostics_s": listener.first_diag_s,
        "levels_seen": sorted(set(listener.levels)),
        "last_status": listener.last_status,
    }


def send_malformed(args):
    """Scans that are no LaserScan, and one larger than odocal's limit, from
    a participant of their own (a second, broken publisher)."""
    dp = DomainParticipant(args.domain)
    w = DataWriter(dp, Topic(dp, "rt/scan", NotALaserScan), qos=SENSOR)
    end = time.monotonic() + args.match_timeout
    while w.get_publication_matched_status().current_count == 0 and time.monotonic() < end:
        time.sleep(0.05)
    header = Header(stamp=Time(sec=10**6, nanosec=0), frame_id="laser")
    for k in range(args.malformed):
        w.write(NotALaserScan(header=header, junk=[0xFF] * (13 + k)))
        time.sleep(0.02)
    big = DataWriter(dp, Topic(dp, "rt/scan", LaserScan), qos=SENSOR)
    end = time.monotonic() + args.match_timeout
    while big.get_publication_matched_status().current_count == 0 and time.monotonic() < end:
        time.sleep(0.05)
    big.write(LaserScan(
        header=header, angle_min=-1.0, angle_max=1.0, angle_increment=2.0 / (args.oversized - 1),
        time_increment=0.0, scan_time=0.04, range_min=0.1, range_max=20.0,
        ranges=[1.0] * args.oversized, intensities=[]))
    time.sleep(0.5)
    return args.malformed + 1


def listen(args):
    dp = DomainParticipant(args.domain)
    readers = {}
    for topic, cls in [("/scan", LaserScan), ("/joint_states", JointState), ("/imu", Imu),
                       ("/tf_static", TFMessage)]:
        qos = LATCHED if topic == "/tf_static" else Qos(
            Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepAll)
        readers[topic] = (cls, DataReader(dp, Topic(dp, "rt" + topic, cls), qos=qos))
    counts = {t: 0 for t in readers}
    ordered = {t: True for t in readers}
    last = {}
    first_scan, transform = None, None
    end = time.monotonic() + args.seconds
    while time.monotonic() < end:
        for topic, (cls, r) in readers.items():
            for m in r.take(N=100000):
                # Samples that say a writer went away carry no message.
                if not isinstance(m, cls):
                    continue
                counts[topic] += 1
                if topic == "/tf_static":
                    tr = m.transforms[0]
                    transform = {"child": tr.child_frame_id, "parent": tr.header.frame_id,
                                 "x": tr.transform.translation.x, "y": tr.transform.translation.y}
                    continue
                t = m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec
                if topic in last and t < last[topic]:
                    ordered[topic] = False
                last[topic] = t
                if topic == "/scan" and first_scan is None:
                    first_scan = {"stamp": t, "frame_id": m.header.frame_id,
                                  "beams": len(m.ranges), "angle_min": m.angle_min,
                                  "range_max": m.range_max}
        time.sleep(0.02)
    return {"counts": counts, "ordered": ordered, "last_stamp": last,
            "first_scan": first_scan, "tf_static": transform}


def discovery(args):
    """Seconds to a match: a peer joining where odocal runs, then odocal
    joining where a peer runs (each `--trials` times, fresh domains)."""
    import subprocess
    cfg = os.path.join(os.path.dirname(os.path.abspath(args.odocal)), "live-discovery.toml")
    with open(cfg, "w") as f:
        f.write("[live]\nlocalhost_only = true\n")
    out = {"peer_joins_s": [], "odocal_joins_s": []}
    import tempfile
    scratch = tempfile.mkdtemp(prefix="odocal-discovery-")
    for k in range(args.trials):
        for order in ("peer_joins_s", "odocal_joins_s"):
            d = args.domain + 2 * k + (order == "odocal_joins_s")
            env = dict(os.environ, ROS_DOMAIN_ID=str(d))
            start = lambda: subprocess.Popen(
                [args.odocal, "live", "--out", scratch, "--config", cfg], env=env,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            node = start() if order == "peer_joins_s" else None
            if node:
                time.sleep(2)
            t0 = time.monotonic()
            dp = DomainParticipant(d)
            w = DataWriter(dp, Topic(dp, "rt/scan", LaserScan), qos=SENSOR)
            if node is None:
                time.sleep(1)
                t0 = time.monotonic()
                node = start()
            while w.get_publication_matched_status().current_count == 0:
                if time.monotonic() - t0 > 30:
                    break
                time.sleep(0.005)
            out[order].append(round(time.monotonic() - t0, 3))
            node.kill()
            node.wait()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("command", choices=["publish", "listen", "discovery"])
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--mcap")
    ap.add_argument("--seconds", type=float, default=20.0, help="listen: how long")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--topics", nargs="+", default=["/scan", "/joint_states", "/imu", "/tf_static"])
    ap.add_argument("--match-timeout", type=float, default=30.0)
    ap.add_argument("--linger", type=float, default=3.0, help="seconds to listen after the last message")
    ap.add_argument("--malformed", type=int, default=0)
    ap.add_argument("--oversized", type=int, default=200_000, help="beams of the oversized scan")
    ap.add_argument("--odocal", help="discovery: the odocal binary")
    ap.add_argument("--trials", type=int, default=5)
    args = ap.parse_args()
    out = {"publish": publish, "listen": listen, "discovery": discovery}[args.command](args)
    json.dump(out, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
