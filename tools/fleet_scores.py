#!/usr/bin/env python3
"""Scores a simulated fleet's alarms against its hidden histories, and how
many days each event took to be raised.

`odocal experiment fleet --out OUT` writes the recordings and their manifest
(`OUT/fleet-data/manifest.csv`), the hidden histories
(`OUT/fleet-truth.json`) and the fleet run (`OUT/fleet-run/`). This tool:

1. reads the alarms of the whole run (`OUT/fleet-run/fleet.json`) and the
   events each history should raise (wear: a `wear` alarm; a step on day d:
   `step` on d; swapped wiring from d: `fault` on d; a short recording on
   d: `insufficient` on d; a knocked laser from d: `fault` on d);
2. counts, per kind of event, the events raised (recall) and, per kind of
   alarm, the alarms that are an event (precision): an alarm is an event's
   when it is of its robot and kind and, but for wear, of its day;
3. runs `odocal fleet` again on every prefix of the days (days 0..k of the
   manifest, each into its own folder whose cache is the whole run's, so
   that nothing is calibrated again) and takes, for each raised event, the
   first k whose run raises it: the days from the event to its alarm, as a
   fleet run once a day would have seen it.

Usage: fleet_scores.py OUT [--odocal BIN] [--json FILE]
Prints a markdown table; `--json` also writes the figures.
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

# History -> the alarm kind it should raise.
EXPECTED_KIND = {
    "wear": "wear",
    "step": "step",
    "swap": "fault",
    "short": "insufficient",
    "knocked": "fault",
}


def events(truth):
    """(robot, history, kind, day or None) of every event the histories hold."""
    out = []
    for t in truth:
        h = t["history"]
        if h == "nothing":
            continue
        day = None if h == "wear" else float(t["day"])
        out.append((t["robot"], h, EXPECTED_KIND[h], day))
    return out


def matches(alarm, event):
    robot, _, kind, day = event
    return alarm["robot"] == robot and alarm["kind"] == kind and (
        day is None or round(alarm["day"]) == day)


def prefix_runs(odocal, out, manifest, days, scratch):
    """{k: alarms of `odocal fleet` on the manifest's days 0..k}, each run
    into its own folder sharing the whole run's cache."""
    with open(manifest) as f:
        rows = list(csv.DictReader(f))
    starts = sorted({r["start"] for r in rows})
    base = os.path.dirname(os.path.abspath(manifest))
    runs = {}
    for k in range(days):
        keep = set(starts[: k + 1])
        path = os.path.join(scratch, f"manifest-{k}.csv")
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=["robot", "path", "start"])
            w.writeheader()
            for r in rows:
                if r["start"] in keep:
                    w.writerow(dict(r, path=os.path.join(base, r["path"])))
        dest = os.path.join(scratch, f"run-{k}")
        os.makedirs(dest, exist_ok=True)
        cache = os.path.join(dest, "cache")
        if not os.path.exists(cache):
            os.symlink(os.path.join(out, "fleet-run", "cache"), cache)
        p = subprocess.run([odocal, "fleet", path, "--out", dest, "--json"],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"odocal fleet on days 0..{k}: exit {p.returncode}: {p.stderr.strip()}")
        summary = json.loads(p.stdout)
        if summary.get("processed", 0):
            sys.exit(f"days 0..{k}: {summary['processed']} recordings calibrated again (cache missed)")
        runs[k] = summary["alarms"]
    return runs


def score(truth, alarms, runs):
    evs = events(truth)
    kinds = sorted({e[2] for e in evs} | {a["kind"] for a in alarms})
    rows = []
    totals = {"events": 0, "raised": 0, "alarms": 0, "true": 0, "delays": []}
    for kind in kinds:
        mine = [e for e in evs if e[2] == kind]
        raised = [e for e in mine if any(matches(a, e) for a in alarms)]
        raised_by = [a for a in alarms if a["kind"] == kind]
        true = [a for a in raised_by if any(matches(a, e) for e in evs)]
        delays = []
        for e in raised:
            first = min(k for k, run in runs.items() if any(matches(a, e) for a in run)) \
                if any(any(matches(a, e) for a in run) for run in runs.values()) else None
            if first is not None:
                delays.append(first - (e[3] or 0.0))
        for name, n in (("events", len(mine)), ("raised", len(raised)),
                        ("alarms", len(raised_by)), ("true", len(true))):
            totals[name] += n
        totals["delays"] += delays
        rows.append((kind, sorted({e[1] for e in mine}), len(mine), len(raised),
                     len(raised_by), len(true), delays))
    return rows, totals


def ratio(a, b):
    return f"{a}/{b} ({100.0 * a / b:.0f} %)" if b else "–"


def delay_cell(delays):
    if not delays:
        return "–"
    return (f"median {statistics.median(delays):g}, max {max(delays):g}"
            if len(delays) > 1 else f"{delays[0]:g}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--odocal", default=os.environ.get("ODOCAL_BIN", "odocal"))
    ap.add_argument("--json")
    a = ap.parse_args()
    out = os.path.abspath(a.out)
    with open(os.path.join(out, "fleet-truth.json")) as f:
        truth = json.load(f)
    with open(os.path.join(out, "fleet-run", "fleet.json")) as f:
        alarms = json.load(f)["alarms"]
    with open(os.path.join(out, "fleet.json")) as f:
        days = json.load(f)["days"]
    with tempfile.TemporaryDirectory() as scratch:
        runs = prefix_runs(a.odocal, out, os.path.join(out, "fleet-data", "manifest.csv"), days, scratch)
    rows, totals = score(truth, alarms, runs)
    print("| kind | histories | events raised (recall) | alarms that are events (precision) "
          "| days from event to alarm |")
    print("|---|---|---|---|---|")
    for kind, hist, n_ev, n_raised, n_alarms, n_true, delays in rows:
        print(f"| `{kind}` | {', '.join(hist) or '–'} | {ratio(n_raised, n_ev)} | "
              f"{ratio(n_true, n_alarms)} | {delay_cell(delays)} |")
    print(f"| all | | {ratio(totals['raised'], totals['events'])} | "
          f"{ratio(totals['true'], totals['alarms'])} | {delay_cell(totals['delays'])} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"rows": rows, "totals": totals}, f, indent=1)


if __name__ == "__main__":
    main()
