#!/usr/bin/env python3
"""The mutation-testing table of docs/reliability.md from cargo-mutants'
outcome files: per source file, the mutants caught, missed, timed out and
unviable, and the share of viable mutants caught.

Each OUT is a `mutants.out` folder (or its parent) of one `cargo mutants`
run; a later folder's outcome of a mutant replaces an earlier one's (a run
with `--iterate` after new tests re-tests only what the first missed). A
mutant a run's `--iterate` skipped as caught stays caught.

A mutant the tests hang on (a timeout) counts as noticed, as cargo-mutants
reports it apart from the missed ones.

Usage: mutants_table.py OUT [OUT ...] [--total FILE=N ...] [--listed LIST]
       (--total: the mutants `cargo mutants --list` finds in FILE, so that
       a file tested only in part says how much of it was tested;
       --listed: the output of `cargo mutants --list` on the current source:
       for a file it names, outcomes of mutants it does not list (run on an
       earlier version of the file, whose lines have since moved) are left
       out, and the file's total defaults to its listed count)
"""

import argparse
import json
import sys
from collections import Counter, defaultdict
from pathlib import Path

KINDS = {
    "CaughtMutant": "caught",
    "MissedMutant": "missed",
    "Timeout": "timeout",
    "Unviable": "unviable",
}


def outcomes(folder):
    """(mutant name, file, kind) of every mutant a run tested."""
    p = Path(folder)
    if (p / "mutants.out").is_dir():
        p = p / "mutants.out"
    data = json.loads((p / "outcomes.json").read_text())
    for o in data["outcomes"]:
        m = o["scenario"].get("Mutant") if isinstance(o["scenario"], dict) else None
        if m is None or o["summary"] not in KINDS:
            continue
        yield m["name"], m["file"], KINDS[o["summary"]]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="+")
    ap.add_argument("--total", action="append", default=[])
    ap.add_argument("--listed")
    a = ap.parse_args()
    listed = None
    if a.listed:
        listed = {ln.strip() for ln in Path(a.listed).read_text().splitlines() if ln.strip()}
    listed_files = Counter(n.split(":", 1)[0] for n in listed or ())
    latest = {}
    stale = Counter()
    for folder in a.out:
        for name, file, kind in outcomes(folder):
            if file in listed_files and name not in listed:
                stale[file] += 1
                continue
            latest[name] = (file, kind)
    per_file = defaultdict(Counter)
    for file, kind in latest.values():
        per_file[file][kind] += 1
    totals = {f: str(n) for f, n in listed_files.items()}
    totals.update(t.split("=", 1) for t in a.total)
    print("| module | caught | timeout | missed | unviable | tested of | caught of viable |")
    print("|---|---|---|---|---|---|---|")
    for file in sorted(per_file):
        c = per_file[file]
        viable = c["caught"] + c["missed"] + c["timeout"]
        tested = sum(c.values())
        # A mutant the tests hang on (timeout) is one they noticed.
        share = f"{100.0 * (c['caught'] + c['timeout']) / viable:.0f} %" if viable else "–"
        of = totals.get(file, str(tested))
        print(f"| `{file}` | {c['caught']} | {c['timeout']} | {c['missed']} | "
              f"{c['unviable']} | {tested} of {of} | {share} |")
    if stale:
        print("\nLeft out (mutants of an earlier version of the file, not in the current"
              " source): " + ", ".join(f"`{f}` {n}" for f, n in sorted(stale.items())) + ".")
    missed = sorted(n for n, (_, k) in latest.items() if k == "missed")
    if missed:
        print("\nSurvivors:\n")
        for n in missed:
            print(f"- `{n}`")
    return 0


if __name__ == "__main__":
    sys.exit(main())
