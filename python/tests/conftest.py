"""Shared fixtures: the odocal binary (to compare the package with the
command line on the same files) and a short simulated recording."""

import importlib
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def odocal_bin() -> str:
    """``$ODOCAL_BIN``, else the release build of this checkout, else PATH."""
    if os.environ.get("ODOCAL_BIN"):
        return os.environ["ODOCAL_BIN"]
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    built = target / "release" / "odocal"
    if built.exists():
        return str(built)
    found = shutil.which("odocal")
    if not found:
        pytest.fail("no odocal binary: build it (cargo build --release) or set ODOCAL_BIN")
    return found


def need(module: str):
    """The imported ``module``. Without it the test skips, but under CI
    (``CI`` set, as ``.ci/run`` does) it fails: CI installs every module the
    tests use, so a missing one is a broken setup, not a reason to pass."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        if os.environ.get("CI"):
            pytest.fail(f"module {module} missing under CI ({e}); .ci/run installs it")
        pytest.skip(f"module {module} not installed ({e})")


def cli(*args, ok=True):
    """Runs the command line; with ``ok``, asserts exit 0 and returns the
    parsed ``--json`` stdout, else returns the completed process."""
    p = subprocess.run([odocal_bin(), *map(str, args)], capture_output=True, text=True)
    if not ok:
        return p
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """A 40 s simulated hall run with a known radius change, written by the
    command line, and its truth."""
    d = tmp_path_factory.mktemp("sim")
    bag, truth = d / "hall.mcap", d / "hall.json"
    cli("simulate", "--scenario", "hall", "--seed", "3", "--duration", "40",
        "--effect", "radius_scale:right=0.01,left=-0.005",
        "--out", bag, "--truth", truth, "--json")
    return bag, truth
