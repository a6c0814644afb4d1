#!/usr/bin/env python3
"""The generated tables of docs/results/, recomputed from odocal's own commands.

Each page docs/results/NAME.md is generated whole (its title, how the table is
computed, the table between `<!-- figures: NAME -->` and `<!-- /figures -->`)
from the release binary, the bundled recording, the simulator and the real logs
of the shared data folder:

  figures.py --check   exit 1 when a page differs from what the binary gives
                       (the difference shown); the test command runs this
  figures.py --write   rewrite the pages (atomically)
  figures.py --print   print the pages

Blocks (tools/figlib/; about 2 minutes on 2 cores, the slow ones only with --all
or --only):
  icp-truth         motion sums against the simulator's truth (tools/icp_bias.py)
  relations         the four benchmark logs' relation errors, odocal and CSM
  icp-metrics       point-to-line against point-to-point: relations and truth
  run-to-run        the same over the five convergence bounds 0.8-1.2 x default
  bound-sweep       iterations and relations from a 1 m to the default 10 µm bound
  real-calibration  the real recordings' batch and filter calibrations
  lego-scanner      the LEGO robot's batch with and without its scanner corrections
  what-changed      the changes named at each firing on 25 simulated runs
  real-diagnosis    the diagnosis of the real recordings
  real-firings      the firings of the real recordings and the bundled one
  null-firings      changes reported and re-spreads on 60 simulated null runs
  table-ii-scans    [Farina, Table II] on simulated scans through ICP, 30 runs
                    (slow: ~1.5 min; its time per step is not compared)
  blind-suite       the blind diagnosis suite, 125 simulated runs (slow: ~4 min)
  independent-laws  clean bags rewritten by tools/rewrite_effects.py, diagnosed (slow: ~5 min)
  icp-instrument    scan-to-scan ICP's own error on 25 null runs, the diagnosis's
                    instrument table (slow: ~5 min)
  null-lengths      72 null runs, every scenario at 60, 150 and 300 s, diagnosed
                    (slow: ~6 min)
  fleet             a simulated fleet, 12 chairs over 10 days (slow: ~3 min)

CSM's figures are recorded measurements (tools/figures_csm.json: Censi's
PL-ICP built and run by tools/csm/, as docs/performance.md says);
`--csm DIR` scores its trajectories DIR/LOG-F.tum (F = each bound's factor)
with `odocal eval --relations` and records them again. odocal's figures are always
computed afresh. Blocks that need the shared data (ODOCAL_DATA, default
../shared/data) say SKIP when it is missing; under CI (`CI` set) that fails.

Options: --odocal BIN (default $ODOCAL_BIN or $CARGO_TARGET_DIR/release/odocal
or target/release/odocal), --data DIR, --only NAME (repeatable), --jobs N.
The manual's prose refers to these pages rather than quoting their numbers:
--write says which pages changed.
"""
import argparse
import concurrent.futures
import difflib
import json
import os
import sys
import tempfile

from figlib import calibration, changes, diagnosis, instrument, pages, scan_matching
from figlib.common import ROOT, Runner, Skip, write_atomically

RESULTS = os.path.join(ROOT, "docs", "results")

# name: (how it is computed, whether it is slow: computed only with --all).
BLOCKS = {
    "icp-truth": (scan_matching.block_icp_truth, False),
    "relations": (scan_matching.block_relations, False),
    "icp-metrics": (scan_matching.block_icp_metrics, False),
    "run-to-run": (scan_matching.block_run_to_run, False),
    "bound-sweep": (scan_matching.block_bound_sweep, False),
    "real-calibration": (calibration.block_real_calibration, False),
    "lego-scanner": (calibration.block_lego_scanner, False),
    "what-changed": (changes.block_what_changed, False),
    "real-diagnosis": (diagnosis.block_real_diagnosis, False),
    "real-firings": (changes.block_real_firings, False),
    "null-firings": (changes.block_null_firings, False),
    "table-ii-scans": (calibration.block_table_ii_scans, True),
    "blind-suite": (diagnosis.block_blind_suite, True),
    "independent-laws": (diagnosis.block_independent_laws, True),
    "floor-slip": (diagnosis.block_floor_slip, True),
    "icp-instrument": (instrument.block_icp_instrument, True),
    "null-lengths": (instrument.block_null_lengths, True),
    "fleet": (calibration.block_fleet, True),
}


def volatile(row):
    """Rows of timings: measured on a quiet machine (the page says so), so
    neither compared nor rewritten here."""
    return row.startswith("| time per step")


def merged(old, new):
    """`new` with each volatile row taken from `old` (matched by its first
    cell) where it has one with as many cells (a table that gained a column
    takes the new row whole)."""
    first = lambda row: row.split("|")[1].strip() if row.count("|") > 1 else row
    kept = {first(r): r for r in old if volatile(r)}
    same = lambda r: first(r) in kept and kept[first(r)].count("|") == r.count("|")
    return [kept[first(r)] if volatile(r) and same(r) else r for r in new]


def default_odocal():
    if os.environ.get("ODOCAL_BIN"):
        return os.environ["ODOCAL_BIN"]
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    return os.path.join(target, "release", "odocal")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--check", action="store_true")
    mode.add_argument("--write", action="store_true")
    mode.add_argument("--print", action="store_true")
    mode.add_argument("--csm", metavar="DIR")
    ap.add_argument("--odocal", default=default_odocal())
    ap.add_argument("--data", default=os.environ.get(
        "ODOCAL_DATA", os.path.join(os.path.dirname(ROOT), "shared", "data")))
    ap.add_argument("--only", action="append", choices=sorted(BLOCKS))
    ap.add_argument("--all", action="store_true", help="the slow blocks too")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    if not os.access(a.odocal, os.X_OK):
        raise SystemExit(f"{a.odocal}: no odocal binary (build it, or give --odocal BIN)")
    with tempfile.TemporaryDirectory(prefix="odocal-figures-") as scratch:
        runner = Runner(a.odocal, a.data, scratch, a.jobs)
        if a.csm:
            scan_matching.record_csm(runner, a.csm)
            return 0
        return regenerate(runner, a)


def page_path(name):
    return os.path.join(RESULTS, f"{name}.md")


def read_page(name):
    """The page's text, or "" when it does not exist yet."""
    try:
        with open(page_path(name)) as f:
            return f.read()
    except FileNotFoundError:
        return ""


def regenerate(runner, a):
    names = list(dict.fromkeys(a.only or sorted(n for n, (_, slow) in BLOCKS.items() if a.all or not slow)))
    with open(scan_matching.CSM_FILE) as f:
        csm = json.load(f)
    changed, skipped = [], []
    # Every block started at once (each waits on its own runs in the pool).
    with concurrent.futures.ThreadPoolExecutor(max_workers=len(names)) as blocks:
        results = {n: blocks.submit(BLOCKS[n][0], runner, csm) for n in names}
    for name in names:
        try:
            rows = results[name].result()
        except RuntimeError as e:
            raise SystemExit(f"figures {name}: {e}")
        except Skip as s:
            print(f"SKIP figures {name}: {s}", file=sys.stderr)
            skipped.append(name)
            continue
        old = read_page(name)
        rows = merged(pages.table_of(old, name) or [], rows)
        new = pages.render(name, rows, BLOCKS[name][1])
        if a.print:
            print(new)
        if new != old:
            changed.append(name)
            rel = os.path.relpath(page_path(name), ROOT)
            sys.stderr.writelines(difflib.unified_diff(
                old.splitlines(keepends=True), new.splitlines(keepends=True),
                f"{rel} (as committed)", f"{rel} (odocal)"))
            if a.write:
                os.makedirs(RESULTS, exist_ok=True)
                write_atomically(page_path(name), new)
    verdict = "differ" if a.check else "changed"
    print(f"figures: {len(names) - len(skipped)} blocks computed, {len(skipped)} skipped; "
          f"{verdict}: {', '.join(sorted(changed)) or 'none'}", file=sys.stderr)
    if skipped and os.environ.get("CI"):
        print("figures: under CI every block must be computed", file=sys.stderr)
        return 1
    return 1 if a.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())
