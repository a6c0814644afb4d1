#!/usr/bin/env bash
# Every test suite: the Rust tests (`cargo test --release`), the generated
# tables of docs/results/ recomputed with the release binary just built and
# compared (tools/figures.py --check), the API documentation built with
# warnings as errors (cargo doc), then the Python package built from python/
# and installed into this Python, and its pytest suite (which compares the
# package with that binary).
# Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${ODOCAL_PYTHON:-python3}"

echo "== Rust: cargo test --release $*"
cargo test --release "$@"

# Under CI the slow blocks too (the blind diagnosis suite, Table II through
# scans, the simulated fleet: about 9 more minutes on 2 cores), so that every
# acceptance rate the manual quotes is recomputed and compared.
echo "== docs/results/ generated tables against this build (tools/figures.py --check${CI:+ --all})"
export ODOCAL_BIN="${CARGO_TARGET_DIR:-target}/release/odocal"
"$PY" tools/figures.py --check ${CI:+--all} --odocal "$ODOCAL_BIN"

echo "== API documentation: cargo doc --no-deps (warnings are errors)"
# The same features as the tests above (a --no-default-features run documents without Rerun).
DOC_FEATURES=()
for a in "$@"; do
  case "$a" in --no-default-features | --all-features | --features=*) DOC_FEATURES+=("$a") ;; esac
done
RUSTDOCFLAGS="${RUSTDOCFLAGS:-} -Dwarnings" cargo doc --no-deps "${DOC_FEATURES[@]}"

echo "== Python package: build and install python/ (maturin)"
"$PY" -m pip --version >/dev/null
"$PY" -c "import maturin" 2>/dev/null || "$PY" -m pip install --quiet "maturin>=1.5,<2"
"$PY" -m pip install --quiet --disable-pip-version-check --no-build-isolation python/

echo "== Python: pytest python/tests"
"$PY" -m pytest python/tests -q -p no:cacheprovider
