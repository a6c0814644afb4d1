#!/usr/bin/env bash
# Runs every fuzz target in turn, at the lowest priority on one core, for
# SECONDS each (default 480), and prints executions and time per target.
# A target that finds a crash stops early; its input is in
# fuzz/artifacts/<target>/ (copy it to tests/fuzz-regressions/<target>/ once
# fixed). Build the seed corpora first: fuzz/seed-corpora.sh.
# Usage: fuzz/run-all.sh [SECONDS] [TARGET...]
#        (FUZZ_NO_BUILD=1: run the binaries already built, without rebuilding)
set -uo pipefail
cd "$(dirname "$0")/.."
secs="${1:-480}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(mcap_read cdr_msgs carmen tum kitti relations effect_spec robot_toml pipeline_toml ros1_bag rosbag2_db3 rosbag2_dir censi_tuples ros2_control_yaml)
mkdir -p fuzz/logs
printf '%-14s %12s %8s %8s %s\n' target executions seconds exec/s result
for t in "${targets[@]}"; do
  log="fuzz/logs/$t.log"
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  opts=(-max_total_time="$secs" -timeout=20 -rss_limit_mb=2048 -print_final_stats=1)
  if [ -n "${FUZZ_NO_BUILD:-}" ]; then
    # The binaries `cargo fuzz build -O` made, as they are: a campaign that
    # runs while the sources change does not rebuild before each target.
    bin="fuzz/target/x86_64-unknown-linux-gnu/release/$t"
    ASAN_OPTIONS="${ASAN_OPTIONS:-detect_odr_violation=0}" nice -n 19 "$bin" -artifact_prefix="fuzz/artifacts/$t/" "fuzz/corpus/$t" "${opts[@]}" >"$log" 2>&1
  else
    RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz run -O "$t" "fuzz/corpus/$t" -- "${opts[@]}" >"$log" 2>&1
  fi
  rc=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  took=$(grep -o 'Done [0-9]* runs in [0-9]* second' "$log" | grep -o 'in [0-9]*' | grep -o '[0-9]*' | tail -1)
  [ -n "$took" ] || took=$(grep -o '#[0-9]*.*time: *[0-9]*s' "$log" | tail -1 | grep -o '[0-9]*s$' | tr -d s)
  result=ok; [ $rc -eq 0 ] || result="CRASH (see $log)"
  rate=$([ -n "${took:-}" ] && [ "${took:-0}" -gt 0 ] && echo $(( ${runs:-0} / took )) || echo -)
  printf '%-14s %12s %8s %8s %s\n' "$t" "${runs:-?}" "${took:-?}" "$rate" "$result"
done
