#!/bin/sh
# CSM's runs behind the CSM columns of docs/results/: each benchmark log matched with
# epsilon_xy = epsilon_theta = F x 1e-4 (CSM's default) for the five factors
# F of odocal's run-to-run table, default sm_icp parameters otherwise, the
# laser pose -laser_x 0.04 on FR079 (its /tf_static).
#
# Usage: tools/csm/runs.sh SM_TUM BAGS_DIR OUT_DIR
#   SM_TUM    the driver built by build.sh
#   BAGS_DIR  the benchmark bags (../shared/data/slam-benchmark)
#   OUT_DIR   gets LOG.json (tools/csm_export.py), LOG-F.tum and LOG-F.err
# Prints each run's timing line (CPU time of the matching loop alone). Then
# `python3 tools/figures.py --csm OUT_DIR` scores the trajectories and records
# them in tools/figures_csm.json.
set -eu
[ $# -eq 3 ] || { echo "usage: $0 SM_TUM BAGS_DIR OUT_DIR" >&2; exit 2; }
SM=$1; BAGS=$2; OUT=$3
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
for L in intel mit-csail fr079 aces; do
  [ -s "$OUT/$L.json" ] || python3 "$HERE/../csm_export.py" "$BAGS/$L.mcap" "$OUT/$L.json"
done
for F in 0.8 0.9 1.0 1.1 1.2; do
  E=$(python3 -c "print(repr($F * 1e-4))")
  for L in intel mit-csail fr079 aces; do
    X=""; [ "$L" = fr079 ] && X="-laser_x 0.04"
    # shellcheck disable=SC2086
    "$SM" -in "$OUT/$L.json" $X -epsilon_xy "$E" -epsilon_theta "$E" \
      > "$OUT/$L-$F.tum" 2> "$OUT/$L-$F.err"
    echo "$L $F $(grep -o 'sm_tum: pairs.*' "$OUT/$L-$F.err")"
  done
done
