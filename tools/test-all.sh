#!/usr/bin/env bash
# Every test suite: the Rust tests (`cargo test --release`), README's generated
# tables recomputed with the release binary just built and
# compared (tools/figures.py --check), then the Python package built from
# python/ and installed into this Python, and its pytest suite (which compares
# the package with that binary).
# Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${ODOCAL_PYTHON:-python3}"

echo "== Rust: cargo test --release $*"
cargo test --release "$@"

echo "== README's generated tables against this build (tools/figures.py --check)"
export ODOCAL_BIN="${CARGO_TARGET_DIR:-target}/release/odocal"
"$PY" tools/figures.py --check --odocal "$ODOCAL_BIN"

echo "== Python package: build and install python/ (maturin)"
"$PY" -m pip --version >/dev/null
"$PY" -c "import maturin" 2>/dev/null || "$PY" -m pip install --quiet "maturin>=1.5,<2"
"$PY" -m pip install --quiet --disable-pip-version-check --no-build-isolation python/

echo "== Python: pytest python/tests"
"$PY" -m pytest python/tests -q -p no:cacheprovider
