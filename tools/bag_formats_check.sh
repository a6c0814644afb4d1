#!/usr/bin/env bash
# Converts each Freiburg benchmark log (MCAP) to a ROS 1 bag (lz4 chunks) and
# a rosbag2 SQLite folder with tools/bag_convert.py (the `rosbags` package),
# runs `odocal icp` on all three, and checks that the TUM outputs are
# byte-identical. Prints one line per log; exits 1 on any difference.
# Usage: tools/bag_formats_check.sh ODOCAL_BINARY [DATA_DIR] [LOG...]
set -euo pipefail
bin=${1:?odocal binary}
data=${2:-${ODOCAL_DATA:-../shared/data}}/slam-benchmark
shift $(( $# >= 2 ? 2 : 1 ))
logs=("$@")
[ ${#logs[@]} -gt 0 ] || logs=(intel aces fr079 mit-csail)
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for log in "${logs[@]}"; do
  python3 "$here/bag_convert.py" "$data/$log.mcap" "$tmp/$log" --ros1-compression lz4 --only bag,db3 2>/dev/null
  for src in "$data/$log.mcap" "$tmp/$log/bag.bag" "$tmp/$log/db3"; do
    "$bin" icp --input "$src" --out "$tmp/$log-$(basename "$src").tum" >/dev/null 2>&1
  done
  a=$(md5sum < "$tmp/$log-$log.mcap.tum" | cut -c1-32)
  b=$(md5sum < "$tmp/$log-bag.bag.tum" | cut -c1-32)
  c=$(md5sum < "$tmp/$log-db3.tum" | cut -c1-32)
  poses=$(wc -l < "$tmp/$log-$log.mcap.tum")
  if [ "$a" = "$b" ] && [ "$a" = "$c" ]; then
    echo "$log: identical TUM from .mcap, .bag, .db3 folder ($poses poses, md5 $a)"
  else
    echo "$log: DIFFERENT mcap $a bag $b db3 $c"; status=1
  fi
done
exit $status
