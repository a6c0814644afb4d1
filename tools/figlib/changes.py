"""The change-naming blocks: what `calibrate` names at each firing on
simulated runs with a known change, and on the real recordings."""
import json
import os

from .calibration import calibrate
from .common import ROOT, num, span
from .instrument import wilson

# (effect spec, unit, scale to it and decimals of the estimate); seeds 1-5,
# 60 s of the corridor loop, the change at 30 s.
CHANGES = [
    ("radius_step:time=30,right=0.004,left=0", "mm", 1000, 2),
    ("radius_step:time=30,right=0,left=0.004", "mm", 1000, 2),
    ("latency_change:time=30,delay=0.08", "s", 1, 4),
    ("laser_knock:time=30,dx=0,dy=0,dyaw=0.035", "rad", 1, 4),
    (None, "", 1, 0),
]

SEEDS = ["1", "2", "3", "4", "5"]


def changes_of(runner, effect, seed):
    """`changes` of `calibrate --json` on a simulated 60 s run."""
    name = f"chg-{(effect or 'none').replace(':', '_').replace(',', '_')}-{seed}"
    bag = runner.path(f"{name}.mcap")
    sim = ["simulate", "--seed", seed, "--duration", "60", "--out", bag]
    runner.run(sim + (["--effect", effect] if effect else []))
    out = runner.run(["calibrate", "--input", bag, "--out", runner.path(name), "--json"])
    return json.loads(out).get("changes", [])


def firing_cells(runs, total):
    """(fired at, named): the runs' first firings and later ones, their
    detector; what was named in how many of the `total` runs, and the others'
    verdicts (`runs` are those that fired)."""
    first = [r[0]["time_s"] for r in runs]
    later = [t for r in runs for t in [c["time_s"] for c in r[1:]] + r[0]["refired_s"]]
    fired = span(first, 2) + (f", again at {span(later, 2)}" if later else "")
    fired += f" ({'mounting watch' if runs[0][0]['detector'] == 'laser_mount' else runs[0][0]['detector']})"
    named = [r[0] for r in runs if r[0]["effect"] != "undetermined"]
    kinds = sorted({(c["effect"], c["parameter"]) for c in named})
    parts = [f"{e}, {p}, {sum(1 for c in named if (c['effect'], c['parameter']) == (e, p))} of {total}"
             for e, p in kinds]
    if any(c["refired_s"] for c in named):
        parts[-1] += ", reported once with the later firing"
    if named and named[0]["effect"] == "laser_offset":
        off = max(abs(c["parameters"][k]) for c in named for k in ("x", "y")) * 1000
        parts[-1] += f" (x, y within {off:.0f} mm of 0)"
    left = [r[0] for r in runs if r[0]["effect"] == "undetermined"]
    if left:
        standing = sorted({c["standing"] for c in left if c["standing"]})
        parts.append(f"{len(left)} `undetermined`" + (f", {', '.join(standing)} standing" if standing else ""))
    if len(runs) < total:
        parts.append(f"{total - len(runs)} never fired")
    return fired, "; ".join(parts), named


def estimate_cells(named, unit, scale, digits):
    """(estimate ± stderr, onset [interval], ΔBIC) over the named runs."""
    if not named:
        return "–", "–", "–"
    est = span([c["estimate"] * scale for c in named], digits)
    err = span([c["stderr"] * scale for c in named], digits)
    lo = min(c["onset_interval_s"][0] for c in named)
    hi = max(c["onset_interval_s"][1] for c in named)
    onset = f"{span([c['onset_s'] for c in named], 2)} [{num(lo, 2)}–{num(hi, 2)}]"
    return f"{est} {unit} ± {err} {unit}", onset, span([c["delta_bic"] for c in named], 0)


def block_what_changed(runner, csm):
    rows = [
        "| change at 30 s (truth) | fired at (s) | named | estimate ± stderr | onset (s) [95 % interval] | ΔBIC |",
        "|---|---|---|---|---|---|",
    ]
    futures = {(e, s): runner.pool.submit(changes_of, runner, e, s) for e, *_ in CHANGES for s in SEEDS}
    for effect, unit, scale, digits in CHANGES:
        runs = [futures[(effect, s)].result() for s in SEEDS]
        label = f"`{effect}`" if effect else "none"
        if not any(runs):
            rows.append(f"| {label} | never | – | – | – | – |")
            continue
        fired, named_cell, named = firing_cells([r for r in runs if r], len(runs))
        cells = [label, fired, named_cell, *estimate_cells(named, unit, scale, digits)]
        rows.append("| " + " | ".join(cells) + " |")
    return rows


# (label, bag: under the data folder or, starting with scans/, bundled, robot
# file, what was named there before the naming rules: a record, not computed).
FIRING_RECORDINGS = [
    ("Mines exp1", "mines-rover/exp1.mcap", "mines-rover", "turn_slip at 272.9 s (ΔBIC 12.1)"),
    ("Mines exp2", "mines-rover/exp2.mcap", "mines-rover",
     "laser_offset yaw −0.064 rad at 367.8 s, x −81 mm at 386.9 s"),
    ("LEGO robot", "lego-robot/lego-robot.mcap", "lego-robot",
     "laser_offset yaw −0.090 rad at 17.6 s, latency −0.435 s at 46.3 s"),
    ("`scans/wheelchair-corridor.mcap` (step right −5 mm, left +4 mm at 40 s)",
     "scans/wheelchair-corridor.mcap", None, "the same"),
]


def firings(runner, rel, robot):
    """A future of the Adaptive-PF's `calibrate --json` output (None and the
    reason when refused): the real recordings from the batch, the very run of
    the calibration table; the bundled one with the defaults."""
    if not rel.startswith("scans/"):
        return calibrate(runner, runner.data_file(rel), robot, "adaptive-pf", True)
    out = runner.path(f"firings-{os.path.basename(rel)}")
    args = ["calibrate", "--input", os.path.join(ROOT, rel), "--out", out, "--json"]
    return runner.once(("firings", rel), lambda: (json.loads(runner.run(args)), None))


def named_change(c):
    """A named change: effect, parameter, size ± stderr, onset [interval]."""
    scale, unit, digits = {"radius_step": (1000, "mm", 2), "latency": (1, "s", 3)}.get(
        c["effect"], (1, "", 4))
    lo, hi = c["onset_interval_s"]
    return (f"{c['effect']} {c['parameter']} {num(c['estimate'] * scale, digits)} ± "
            f"{num(c['stderr'] * scale, digits)} {unit}, onset {num(c['onset_s'], 2)} s "
            f"[{num(lo, 2)}–{num(hi, 2)}]").replace("  ", " ")


def block_real_firings(runner, csm):
    rows = [
        "| recording | firings | named | named, before these rules |",
        "|---|---|---|---|",
    ]
    futures = [firings(runner, rel, robot) for _, rel, robot, _ in FIRING_RECORDINGS]
    for (label, rel, _, before), fut in zip(FIRING_RECORDINGS, futures):
        d, refused = fut.result()
        if refused:
            raise RuntimeError(f"{rel}: calibration refused: {refused}")
        changes = d.get("changes", [])
        detectors = sorted({"mounting watch" if c["detector"] == "laser_mount" else c["detector"]
                            for c in changes})
        fired = f"{len(changes)} ({', '.join(detectors)})" if changes else "0"
        named = [named_change(c) for c in changes if c["effect"] != "undetermined"]
        standing = [c["standing"] for c in changes if c["effect"] == "undetermined" and c["standing"]]
        below = sum(1 for c in changes if c["effect"] == "undetermined" and not c["standing"])
        names = ", ".join(dict.fromkeys(standing))
        left = ([f"{len(standing)} standing ({names})"] if standing else []) + (
            [f"{below} below the margin"] if below else [])
        cell = "; ".join(named) if named else "none" + (f": {', '.join(left)}" if left else "")
        rows.append(f"| {label} | {fired} | {cell} | {before} |")
    return rows


# Null runs: nothing changes; every scenario, seeds 1-5, at two lengths.
NULL_SCENARIOS = ["hall", "corridor-loop", "square", "square-ccw", "figure-eight", "random-walk"]
NULL_LENGTHS = ["60", "150"]


def null_changes(runner, scenario, seed, secs):
    """(`changes`, `respreads_s`) of `calibrate --json` (the default
    Adaptive-PF) on a simulated run of `scenario` where nothing changes."""
    name = f"null-firing-{scenario}-{seed}-{secs}"
    bag = runner.path(f"{name}.mcap")
    runner.run(["simulate", "--scenario", scenario, "--seed", seed, "--duration", secs,
                "--out", bag])
    out = json.loads(runner.run(["calibrate", "--input", bag, "--out", runner.path(name),
                                 "--json"]))
    return out.get("changes", []), out.get("respreads_s", [])


def null_cell(runs):
    """Runs with a change reported (their firings' times and what was
    named), and runs whose filter re-spread itself (and when)."""
    fired = [c for r, _ in runs for c in r]
    cell = f"{sum(1 for r, _ in runs if r)} of {len(runs)}"
    if fired:
        named = [c["effect"] for c in fired if c["effect"] != "undetermined"]
        cell += (f", at {', '.join(num(c['time_s'], 1) for c in fired)}; "
                 + (", ".join(named) if named else "none named"))
    spread = [t for _, r in runs for t in r]
    cell += f" · {sum(1 for _, r in runs if r)} of {len(runs)}"
    return cell + (f", at {', '.join(num(t, 1) for t in spread)}" if spread else "")


def block_null_firings(runner, csm):
    """Where nothing changed: per scenario and length, how many runs
    reported a change (and when, and what), and how many re-spread their
    filter (and when)."""
    futures = {(sc, s, n): runner.pool.submit(null_changes, runner, sc, s, n)
               for sc in NULL_SCENARIOS for s in SEEDS for n in NULL_LENGTHS}
    rows = ["| scenario | " + " | ".join(f"{n} s: runs with a change reported · runs re-spread"
                                         for n in NULL_LENGTHS) + " |",
            "|---|" + "---|" * len(NULL_LENGTHS)]
    quiet = {n: 0 for n in NULL_LENGTHS}
    for sc in NULL_SCENARIOS:
        cells = []
        for n in NULL_LENGTHS:
            runs = [futures[(sc, s, n)].result() for s in SEEDS]
            quiet[n] += sum(1 for r, _ in runs if not r)
            cells.append(null_cell(runs))
        rows.append(f"| {sc} | " + " | ".join(cells) + " |")
    total = len(NULL_SCENARIOS) * len(SEEDS)
    cells = []
    for n in NULL_LENGTHS:
        lo, hi = wilson(quiet[n], total)
        cells.append(f"{quiet[n]} of {total} report no change (95 % Wilson "
                     f"{num(100 * lo, 1)}–{num(100 * hi, 1)} %)")
    rows.append("| all | " + " | ".join(cells) + " |")
    return rows
