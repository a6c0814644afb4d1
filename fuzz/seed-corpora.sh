#!/usr/bin/env bash
# Builds the seed corpora of the fuzz targets in fuzz/corpus/<target>/ from the
# real recordings in the shared data folder and odocal's own bundled outputs.
# Corpora are not committed; run this before `cargo fuzz run`.
# Needs python3 with the `mcap` package (pip install mcap).
# Usage: fuzz/seed-corpora.sh [DATA_DIR]   (default: $ODOCAL_DATA or ../shared/data)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/.." && pwd)"
data="${1:-${ODOCAL_DATA:-$repo/../shared/data}}"
[ -d "$data" ] || { echo "no data folder at $data" >&2; exit 2; }
out="$here/corpus"
mkdir -p "$out"/{mcap_read,cdr_msgs,carmen,tum,kitti,relations,effect_spec,robot_toml,pipeline_toml}
mkdir -p "$out"/{ros1_bag,rosbag2_db3,rosbag2_dir,censi_tuples,ros2_control_yaml}

# MCAP: small slices (first messages of every channel) of each real bag and of
# the bundled simulated bag, written chunked+zstd, chunked+lz4 and unchunked;
# every CDR message type once per bag for the decoders.
python3 - "$data" "$repo" "$out" <<'PY'
import sys, pathlib, hashlib
from mcap.reader import make_reader
from mcap.writer import Writer, CompressionType

data, repo, out = map(pathlib.Path, sys.argv[1:])
bags = sorted(data.glob("**/*.mcap")) + sorted((repo / "scans").glob("*.mcap"))
kinds = ["sensor_msgs/msg/LaserScan", "sensor_msgs/msg/JointState", "sensor_msgs/msg/Imu",
         "nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped",
         "geometry_msgs/msg/PointStamped", "tf2_msgs/msg/TFMessage"]
for bag in bags:
    per_channel, kept, cdr_seen = {}, [], set()
    with open(bag, "rb") as f:
        r = make_reader(f)
        for schema, channel, msg in r.iter_messages(log_time_order=False):
            n = per_channel.get(channel.id, 0)
            if n >= 4:
                continue
            per_channel[channel.id] = n + 1
            kept.append((schema, channel, msg))
            if schema and schema.name in kinds and schema.name not in cdr_seen:
                cdr_seen.add(schema.name)
                b = bytes([kinds.index(schema.name)]) + msg.data
                (out / "cdr_msgs" / f"{bag.stem}-{schema.name.split('/')[-1]}").write_bytes(b)
    for comp, chunked in [(CompressionType.ZSTD, True), (CompressionType.LZ4, True),
                          (CompressionType.NONE, False)]:
        path = out / "mcap_read" / f"{bag.stem}-{comp.name.lower()}-{'chunked' if chunked else 'flat'}.mcap"
        with open(path, "wb") as f:
            w = Writer(f, compression=comp, use_chunking=chunked)
            w.start("ros2", "odocal-seed")
            sids, cids = {}, {}
            for schema, channel, msg in kept:
                if schema and schema.id not in sids:
                    sids[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
                if channel.id not in cids:
                    cids[channel.id] = w.register_channel(
                        channel.topic, channel.message_encoding,
                        sids.get(channel.schema_id, 0), channel.metadata)
                w.add_message(cids[channel.id], msg.log_time, msg.data, msg.publish_time,
                              msg.sequence)
            w.finish()
# A DiagnosticArray as `odocal live` publishes it (no bag here holds one),
# CDR little-endian by hand; the fuzz target's kind byte 0xF7 picks it.
import struct
def cdr_string(buf, s):
    buf += b"\0" * (-len(buf) % 4)
    b = s.encode() + b"\0"
    return buf + struct.pack("<I", len(b)) + b
body = bytearray(struct.pack("<iI", 12, 500))
body = cdr_string(body, "base_link")
body += b"\0" * (-len(body) % 4) + struct.pack("<I", 1)
body += bytes([1])
for s in ["odocal: calibration", "converged", ""]:
    body = cdr_string(body, s)
body += b"\0" * (-len(body) % 4) + struct.pack("<I", 1)
for s in ["r_right", "0.3201"]:
    body = cdr_string(body, s)
# The encapsulation header's 4 bytes precede the body; CDR aligns from after it.
(out / "cdr_msgs" / "live-DiagnosticArray").write_bytes(bytes([0xF7, 0, 1, 0, 0]) + bytes(body))
print(f"mcap_read: {len(list((out / 'mcap_read').iterdir()))} seeds, "
      f"cdr_msgs: {len(list((out / 'cdr_msgs').iterdir()))} seeds")
PY

# ROS 1 bags and rosbag2 files and folders: the MCAP slices above rewritten by
# the `rosbags` package (tools/bag_convert.py; an implementation independent of
# odocal's readers), the ROS 1 bag in each chunk compression, one written topic
# after topic (chunks overlapping in time). A folder seed is its metadata.yaml,
# a NUL, then the storage file's bytes (the target writes both names).
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
for slice in "$out"/mcap_read/*-zstd-chunked.mcap; do
  stem="$(basename "$slice" -zstd-chunked.mcap)"
  for comp in none bz2 lz4; do
    python3 "$repo/tools/bag_convert.py" "$slice" "$tmp/$stem-$comp" --ros1-compression "$comp" \
      --only bag 2>/dev/null
    cp "$tmp/$stem-$comp/bag.bag" "$out/ros1_bag/$stem-$comp.bag"
  done
  python3 "$repo/tools/bag_convert.py" "$slice" "$tmp/$stem-topic" --by-topic --only bag 2>/dev/null
  cp "$tmp/$stem-topic/bag.bag" "$out/ros1_bag/$stem-by-topic.bag"
  python3 "$repo/tools/bag_convert.py" "$slice" "$tmp/$stem-2" --only db3,mcap 2>/dev/null
  cp "$tmp/$stem-2"/db3/*.db3 "$out/rosbag2_db3/$stem.db3"
  for kind in db3 mcap; do
    dir="$tmp/$stem-2/$kind"
    storage="$(ls "$dir" | grep -v metadata.yaml | head -1)"
    # The target's storage file is bag_0.<kind>: name it so in the metadata.
    { sed "s/$storage/bag_0.$kind/" "$dir/metadata.yaml"; printf '\0'; cat "$dir/$storage"; } \
      > "$out/rosbag2_dir/$stem-$kind"
  done
done

# Censi et al.'s tuples: heads of the three real sets.
for f in "$data"/censi-calibration/*.tuple; do head -n 30 "$f" > "$out/censi_tuples/$(basename "$f")"; done

# CARMEN: the head of the real log (FLASER lines) plus ODOM and ROBOTLASER1 lines.
for n in 3 20; do head -n "$n" "$data/slam-benchmark/mit-csail.clf" > "$out/carmen/mit-csail-$n.clf"; done
cat > "$out/carmen/kinds.clf" <<'CLF'
# comment
PARAM robot_front_laser_max 80
FLASER 3 1.0 2.0 3.0 0 0 0 1.5 2.5 0.1 10.5 host 10.6
ODOM 1.6 2.6 0.2 0 0 0 10.7 host 10.8
ROBOTLASER1 0 -1.0 2.0 0.5 30 0.01 0 5 1 1 1 1 1 0 1.2 2 0 1 2 0 0 0 0 0 0 11.0 host 11.1
CLF

# Relations: heads of every real file (quirks included: header, double spaces, t1 > t2).
for f in "$data"/slam-benchmark/*.relations; do head -n 40 "$f" > "$out/relations/$(basename "$f")"; done

# TUM and KITTI: the odometry of the real CARMEN log as trajectories.
python3 - "$data/slam-benchmark/mit-csail.clf" "$out" <<'PY'
import sys, math, pathlib
clf, out = sys.argv[1], pathlib.Path(sys.argv[2])
poses = []
for line in open(clf):
    f = line.split()
    if f and f[0] == "FLASER":
        n = int(f[1]); x, y, th = map(float, f[n + 5:n + 8]); t = float(f[n + 8])
        poses.append((t, x, y, th))
for k in (3, 30):
    sub = poses[:k]
    tum = "# timestamp tx ty tz qx qy qz qw\n" + "".join(
        f"{t} {x} {y} 0 0 0 {math.sin(th / 2)} {math.cos(th / 2)}\n" for t, x, y, th in sub)
    (out / "tum" / f"mit-csail-{k}.tum").write_text(tum)
    kp = "".join(f"{math.cos(th)} {-math.sin(th)} 0 {x} {math.sin(th)} {math.cos(th)} 0 {y} 0 0 1 0\n"
                 for t, x, y, th in sub)
    kt = "".join(f"{t}\n" for t, *_ in sub)
    (out / "kitti" / f"mit-csail-{k}").write_text(kp + "\0" + kt)
PY

# Effect SPECs: every name, with and without parameters.
i=0
for s in radius_scale radius_scale:right=0.01,left=-0.02 wheel_base_scale:scale=0.03 \
    radius_step:time=55,right=0.004,left=0.002 radius_drift:right=0.001 encoder_gain:k=0.01 \
    latency:delay=0.04 laser_offset:x=0.02,y=-0.01,yaw=0.005 gyro_bias:bias=0.001 turn_slip:k=0.02; do
  printf '%s' "$s" > "$out/effect_spec/$i"; i=$((i + 1))
done

# TOML: the bundled robot files and settings.
cp "$repo"/scans/robots/*.toml "$out/robot_toml/"
cp "$repo"/scans/*.toml "$out/pipeline_toml/"
printf '[topics]\nscan = "/laser"\n[icp]\n' > "$out/pipeline_toml/topics.toml"

for d in "$out"/*/; do echo "$(basename "$d"): $(ls "$d" | wc -l) files, $(du -sh "$d" | cut -f1)"; done
