#!/usr/bin/env python3
"""README's generated tables, recomputed from odocal's own commands.

Each block of README.md between a line `<!-- figures: NAME -->` and the next
`<!-- /figures -->` is what this script computes from the release binary, the
bundled recording, the simulator and the real logs of the shared data folder:

  figures.py --check   exit 1 when a block differs from what the binary gives
                       (the difference shown); the test command runs this
  figures.py --write   rewrite the blocks in README.md (atomically)
  figures.py --print   print the blocks

Blocks (about 40 s on 2 cores; the slow one only with --all or --only):
  icp-truth    motion sums against the simulator's truth (tools/icp_bias.py)
  relations    the four benchmark logs' relation errors, odocal and CSM
  run-to-run   the same over the five convergence bounds 0.8-1.2 x default
  real-calibration  the real recordings' batch and filter calibrations
  what-changed the changes named at each firing on simulated runs (25 runs)
  real-firings the firings of the real recordings and the bundled one, named
  table-ii-scans  seed 000's Table II on simulated scans through ICP, 30 runs
               (slow: ~1.5 min; its time per step is not compared)
  blind-suite  the blind diagnosis suite, 125 simulated runs (slow: ~4 min)

CSM's figures are recorded measurements (tools/figures_csm.json: Censi's
PL-ICP built and run by tools/csm/, as README's Performance section says);
`--csm DIR` scores its trajectories DIR/LOG-F.tum (F = each bound's factor)
with `odocal eval --relations` and records them again. odocal's figures are always
computed afresh. Blocks that need the shared data (ODOCAL_DATA, default
../shared/data) say SKIP when it is missing; under CI (`CI` set) that fails.

Options: --odocal BIN (default $ODOCAL_BIN or $CARGO_TARGET_DIR/release/odocal
or target/release/odocal), --data DIR, --only NAME (repeatable), --jobs N.
Prose that quotes these figures is not generated: --write says which blocks
changed, so that the text around them can be read again.
"""
import argparse
import concurrent.futures
import difflib
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
README = os.path.join(ROOT, "README.md")
CSM_FILE = os.path.join(ROOT, "tools", "figures_csm.json")
LOGS = ["intel", "mit-csail", "fr079", "aces"]
# The names the tables give the logs (the last two were never tuned on).
LOG_LABEL = {
    "intel": "intel",
    "mit-csail": "mit-csail",
    "fr079": "fr079 (not used for tuning)",
    "aces": "aces (not used for tuning)",
}
# Factors of the default convergence bound (tests/support.rs,
# CONVERGENCE_FACTORS); 1.0 is the default run.
FACTORS = ["0.8", "0.9", "1.0", "1.1", "1.2"]
CSM_DEFAULT_EPSILON = 1e-4
BEGIN = re.compile(r"^<!-- figures: ([a-z0-9-]+) -->$")
END = "<!-- /figures -->"


def default_convergence():
    """The default `[icp] convergence` (m), read from src/icp/params.rs."""
    with open(os.path.join(ROOT, "src", "icp", "params.rs")) as f:
        m = re.search(r"^\s*convergence: ([0-9.eE+-]+),$", f.read(), re.M)
    if not m:
        raise SystemExit("src/icp/params.rs: no default `convergence: X,` found")
    return float(m.group(1))


class Skip(Exception):
    """A block that cannot be computed here (missing data), with the reason."""


class Runner:
    """Runs odocal commands once each, in a scratch folder, `jobs` at a time."""

    def __init__(self, odocal, data, scratch, jobs):
        self.odocal = odocal
        self.data = data
        self.scratch = scratch
        self.pool = concurrent.futures.ThreadPoolExecutor(max_workers=jobs)
        self.futures = {}

    def path(self, name):
        return os.path.join(self.scratch, name)

    def run(self, args, check=True):
        """Runs odocal with `args`; its stdout, or an error naming the command."""
        cmd = [self.odocal] + [str(a) for a in args]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if check and p.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
        return p.stdout

    def once(self, key, fn):
        """`fn()` started once per key in the pool; its future."""
        if key not in self.futures:
            self.futures[key] = self.pool.submit(fn)
        return self.futures[key]

    def benchmark_log(self, log):
        path = os.path.join(self.data, "slam-benchmark", f"{log}.mcap")
        if not os.path.isfile(path):
            raise Skip(f"{path} missing (set ODOCAL_DATA to the shared data folder)")
        return path

    def bound_config(self, factor):
        """`--config` arguments setting the convergence bound to `factor`
        times its default; none for the default itself."""
        if factor == "1.0":
            return []
        cfg = self.path(f"conv-{factor}.toml")
        with open(cfg, "w") as f:
            f.write(f"[icp]\nconvergence = {float(factor) * default_convergence()!r}\n")
        return ["--config", cfg]

    def relations(self, log, factor):
        """`odocal eval --relations --json` of the log matched with the
        convergence bound at `factor` times its default."""
        bag = self.benchmark_log(log)

        def work():
            tum = self.path(f"{log}-{factor}.tum")
            self.run(["icp", "--input", bag, "--out", tum] + self.bound_config(factor))
            rel = os.path.join(self.data, "slam-benchmark", f"{log}.relations")
            out = self.run(["eval", "--estimate", tum, "--relations", rel, "--json"])
            return json.loads(out)["relations"]

        return self.once(("relations", log, factor), work)


# --- number formats ----------------------------------------------------------


def spread(values, fmt):
    """(median, range) as text; the range is None when every value prints
    alike."""
    lo, hi = fmt(min(values)), fmt(max(values))
    return fmt(statistics.median(values)), (None if lo == hi else f"{lo}–{hi}")


# --- blocks ------------------------------------------------------------------


def relations_cells(r):
    """(local, all) cells of one run's relations: translation mean ± std and
    the local rotation mean."""
    loc = r["local"]
    local = f"{loc['trans_mean']:.3f} ± {loc['trans_std']:.3f} m, {loc['rot_mean_deg']:.2f}°"
    return local, f"{r['trans_mean']:.2f} ± {r['trans_std']:.2f} m"


def block_relations(runner, csm):
    rows = [
        "| log | odocal local | odocal all | CSM local | CSM all |",
        "|---|---|---|---|---|",
    ]
    futures = {log: runner.relations(log, "1.0") for log in LOGS}
    for log in LOGS:
        ours = relations_cells(futures[log].result())
        theirs = relations_cells(csm_run(csm, log, "1.0"))
        rows.append(f"| {LOG_LABEL[log]} | {' | '.join(ours + theirs)} |")
    return rows


def ensemble_cells(runs):
    """(local, all) cells over the five bounds: median (range)."""
    f4, f3 = (lambda v: f"{v:.4f}"), (lambda v: f"{v:.3f}")
    t, t_range = spread([r["local"]["trans_mean"] for r in runs], f4)
    a, a_range = spread([r["local"]["rot_mean_deg"] for r in runs], f3)
    if t_range is None and a_range is None:
        local = f"{t} m, {a}° (every run)"
    else:
        local = f"{t} m{f' ({t_range})' if t_range else ''}, {a}°"
        local += f" ({a_range}°)" if a_range else ""
    m, m_range = spread([r["trans_mean"] for r in runs], f3)
    return local, f"{m} m ({m_range})" if m_range else f"{m} m (every run)"


def block_run_to_run(runner, csm):
    rows = [
        "| log | odocal local | odocal all | CSM local | CSM all |",
        "|---|---|---|---|---|",
    ]
    futures = {(log, f): runner.relations(log, f) for log in LOGS for f in FACTORS}
    for log in LOGS:
        ours = ensemble_cells([futures[(log, f)].result() for f in FACTORS])
        theirs = ensemble_cells([csm_run(csm, log, f) for f in FACTORS])
        rows.append(f"| {log} | {' | '.join(ours + theirs)} |")
    return rows


# Rows of the truth table: label, how the recording is made (None: the
# bundled one), and the `[icp]` settings.
TRUTH_ROWS = [
    (
        "bundled `scans/wheelchair-corridor.mcap` (25 Hz, laser on the back, sweeping)",
        None,
        "",
    ),
    (
        "`simulate --scenario square --duration 60 --seed 3`",
        ["--scenario", "square", "--duration", "60", "--seed", "3"],
        "",
    ),
    (
        "`simulate --scenario corridor-loop --seed 5`",
        ["--scenario", "corridor-loop", "--seed", "5"],
        "",
    ),
    (
        "the same scan to scan (`--config C`, `C` = `[icp] local_map = false`, as `diagnose` matches)",
        ["--scenario", "corridor-loop", "--seed", "5"],
        "[icp]\nlocal_map = false\n",
    ),
]


def simulated(runner, sim):
    """(bag, truth) paths of `odocal simulate` with the arguments `sim`."""
    key = "-".join(sim)
    return runner.path(f"{key}.mcap"), runner.path(f"{key}.truth.json")


def simulate(runner, sim):
    bag, truth = simulated(runner, sim)
    runner.run(["simulate", *sim, "--out", bag, "--truth", truth])


def truth_row(runner, k, sim, icp_settings):
    """One row's cells: Σdx and Σdθ ratios, error per pair, flagged pairs."""
    if sim is None:
        bag = os.path.join(ROOT, "scans", "wheelchair-corridor.mcap")
        truth = os.path.join(ROOT, "scans", "wheelchair-corridor.truth.json")
    else:
        bag, truth = simulated(runner, sim)
    cfg = runner.path(f"truth-{k}.toml")
    with open(cfg, "w") as f:
        f.write(icp_settings)
    tum, motions = runner.path(f"truth-{k}.tum"), runner.path(f"truth-{k}.csv")
    runner.run(["icp", "--input", bag, "--out", tum, "--motions", motions, "--config", cfg])
    bias = subprocess.run(
        [sys.executable, os.path.join(ROOT, "tools", "icp_bias.py"), motions, truth],
        capture_output=True, text=True, check=True,
    ).stdout
    v = dict(line.split(None, 1) for line in bias.splitlines() if line.strip())
    flagged = int(v["pairs"]) - int(v["valid"])
    return [
        f"{float(v['dx_ratio']):.4f}",
        f"{float(v['dtheta_ratio']):.4f}",
        f"{float(v['trans_err_mm']):.1f} mm, {float(v['rot_err_deg']):.3f}°",
        str(flagged),
    ]


def block_icp_truth(runner, csm):
    rows = [
        "| recording | Σdx ICP/true | Σdθ ICP/true | error per pair | flagged pairs |",
        "|---|---|---|---|---|",
    ]
    # The simulations first: a row waiting on one from inside the pool could
    # hold every worker.
    sims = {tuple(sim) for _, sim, _ in TRUTH_ROWS if sim is not None}
    for fut in [runner.pool.submit(simulate, runner, list(sim)) for sim in sorted(sims)]:
        fut.result()
    futures = [
        runner.pool.submit(truth_row, runner, k, sim, cfg)
        for k, (_, sim, cfg) in enumerate(TRUTH_ROWS)
    ]
    for (label, _, _), fut in zip(TRUTH_ROWS, futures):
        rows.append(f"| {label} | {' | '.join(fut.result())} |")
    return rows


# --- calibrations of the real recordings ----------------------------------------

# (label, bag under the data folder, robot file name)
REAL_RECORDINGS = [
    ("mines-rover exp1", "mines-rover/exp1.mcap", "mines-rover"),
    ("mines-rover exp2", "mines-rover/exp2.mcap", "mines-rover"),
    ("lego-robot", "lego-robot/lego-robot.mcap", "lego-robot"),
]
FILTERS = ["adaptive-pf", "dkf", "akf"]
PARAMETER_LABEL = {"r_right": "R_R", "r_left": "R_L", "wheel_base": "D"}


def num(x, digits):
    """`x` to `digits` decimals with a typographic minus."""
    return f"{x:.{digits}f}".replace("-", "−")


def calibrate(runner, bag, robot, method, init_batch):
    """(`--json` output or None, the refusal) of one `odocal calibrate`."""
    args = ["calibrate", "--input", bag, "--robot", robot, "--method", method, "--json"]
    args += ["--init", "batch"] if init_batch else []
    out = runner.path(f"cal-{os.path.basename(bag)}-{method}-{int(init_batch)}")
    p = subprocess.run([runner.odocal, *args, "--out", out], capture_output=True, text=True)
    refused = re.search(r"calibration refused: (.*)", p.stderr)
    if p.returncode == 2 and refused:
        return None, refused.group(1)
    if p.returncode != 0:
        raise RuntimeError(f"odocal {' '.join(args)} failed ({p.returncode}):\n{p.stderr}")
    return json.loads(p.stdout), None


def refusal_cell(reason):
    """A refusal in a few words: a parameter at its search range's edge named
    with its value, any other reason as odocal gives it."""
    m = re.match(r"(\w+) came out ([0-9.]+) m, at the edge of its search range", reason)
    if m:
        name = PARAMETER_LABEL.get(m.group(1), m.group(1))
        return f"refused ({name} {num(float(m.group(2)) * 1000, 1)} mm at the edge of its search range)"
    return f"refused ({reason.split(':')[0]})"


def filter_cell(result):
    d, refused = result
    if refused:
        return refusal_cell(refused)
    f, sd = d["final"], d["std"]
    r = [num(f[k] * 1000, 1) for k in ("r_right", "r_left")]
    cell = (f"R {r[0]} / {r[1]} ± {num(max(sd['r_right'], sd['r_left']) * 1000, 1)}, "
            f"D {num(f['wheel_base'] * 1000, 0)} ± {num(sd['wheel_base'] * 1000, 0)}")
    nominal = [num(d["assumptions"][k]["value"] * 1000, 1) for k in ("r_right", "r_left")]
    nominal_d = num(d["assumptions"]["wheel_base"]["value"] * 1000, 0)
    if r == nominal and num(f["wheel_base"] * 1000, 0) == nominal_d:
        cell += " (the nominal values)"
    return cell


def batch_cell(result):
    d, refused = result
    if refused:
        return refusal_cell(refused)
    mm = lambda v, k: num(v * 1000, k)
    rr, rl, wb, las, dt = (d[k] for k in ("r_right", "r_left", "wheel_base", "laser", "time_offset"))
    return (f"R {mm(rr['value'], 1)} / {mm(rl['value'], 1)} ± {mm(max(rr['std'], rl['std']), 1)} mm, "
            f"D {mm(wb['value'], 0)} ± {mm(wb['std'], 0)} mm, "
            f"laser {mm(las['x']['value'], 0)} / {mm(las['y']['value'], 0)} "
            f"± {mm(max(las['x']['std'], las['y']['std']), 0)} mm, "
            f"δ {num(dt['value'], 3)} ± {num(dt['std'], 3)} s")


def block_real_calibration(runner, csm):
    rows = [
        "| recording | batch (radii, wheel base, laser x/y, time offset) | "
        + " | ".join(f"{m} nominal / from batch" for m in FILTERS) + " |",
        "|---|---|---|---|---|",
    ]
    for label, rel, robot in REAL_RECORDINGS:
        bag = os.path.join(runner.data, rel)
        if not os.path.isfile(bag):
            raise Skip(f"{bag} missing (set ODOCAL_DATA to the shared data folder)")
    futures = {
        (rel, m, b): runner.pool.submit(calibrate, runner, os.path.join(runner.data, rel), robot, m, b)
        for _, rel, robot in REAL_RECORDINGS
        for m, b in [("batch", False)] + [(m, b) for m in FILTERS for b in (False, True)]
    }
    for label, rel, _ in REAL_RECORDINGS:
        cells = [batch_cell(futures[(rel, "batch", False)].result())]
        for m in FILTERS:
            pair = [filter_cell(futures[(rel, m, b)].result()) for b in (False, True)]
            cells.append(" / ".join(pair))
        rows.append(f"| {label} | {' | '.join(cells)} |")
    return rows


# --- what changed, named at each firing ------------------------------------------

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


def span(values, digits):
    """`lo–hi` of `values` at `digits` decimals, one value when they print alike."""
    lo, hi = num(min(values), digits), num(max(values), digits)
    return lo if lo == hi else f"{lo}–{hi}"


def firing_cells(runs):
    """(fired at, named): the runs' first firings and later ones, their
    detector; what was named in how many runs, and the others' verdicts."""
    first = [r[0]["time_s"] for r in runs]
    later = [t for r in runs for t in [c["time_s"] for c in r[1:]] + r[0]["refired_s"]]
    fired = span(first, 2) + (f", again at {span(later, 2)}" if later else "")
    fired += f" ({'mounting watch' if runs[0][0]['detector'] == 'laser_mount' else runs[0][0]['detector']})"
    named = [r[0] for r in runs if r[0]["effect"] != "undetermined"]
    kinds = sorted({(c["effect"], c["parameter"]) for c in named})
    parts = [f"{e}, {p}, {sum(1 for c in named if (c['effect'], c['parameter']) == (e, p))} of {len(runs)}"
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
    return fired, "; ".join(parts), named


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
        if not all(runs):
            raise RuntimeError(f"{label}: fired in only {sum(map(bool, runs))} of {len(runs)} runs")
        fired, named_cell, named = firing_cells(runs)
        est = span([c["estimate"] * scale for c in named], digits)
        err = span([c["stderr"] * scale for c in named], digits)
        onset = span([c["onset_s"] for c in named], 2)
        lo = min(c["onset_interval_s"][0] for c in named)
        hi = max(c["onset_interval_s"][1] for c in named)
        bic = span([c["delta_bic"] for c in named], 0)
        rows.append(f"| {label} | {fired} | {named_cell} | {est} {unit} ± {err} {unit} | "
                    f"{onset} [{num(lo, 2)}–{num(hi, 2)}] | {bic} |")
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


def firings_of(runner, rel, robot):
    """`changes` of `calibrate --json` (the real recordings from the batch)."""
    if rel.startswith("scans/"):
        args = ["--input", os.path.join(ROOT, rel)]
    else:
        args = ["--input", os.path.join(runner.data, rel), "--robot", robot, "--init", "batch"]
    out = runner.path(f"firings-{os.path.basename(rel)}")
    return json.loads(runner.run(["calibrate", *args, "--out", out, "--json"])).get("changes", [])


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
    for _, rel, _, _ in FIRING_RECORDINGS:
        if not rel.startswith("scans/") and not os.path.isfile(os.path.join(runner.data, rel)):
            raise Skip(f"{os.path.join(runner.data, rel)} missing (set ODOCAL_DATA to the shared data folder)")
    futures = [runner.pool.submit(firings_of, runner, rel, robot) for _, rel, robot, _ in FIRING_RECORDINGS]
    for (label, _, _, before), fut in zip(FIRING_RECORDINGS, futures):
        changes = fut.result()
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


# --- seed 000's Table II end to end --------------------------------------------

# The columns (the experiment's configurations) and seed 000's own figures
# (its Table II: a record, not computed).
TABLE_II = [("Adaptive-PF", "adaptive-pf"), ("DKF", "dkf"), ("AKF", "akf"), ("PF (fixed)", "pf")]
PAPER = {
    "final radius error R_R / R_L (mm)": ("1.86 / 1.91", "2.11 / 1.85"),
    "wheel base error (mm)": ("–", "–"),
    "convergence (s), runs converged": ("32.55", "60.73"),
    "RMSE x,y (m), online odometry": ("3.38", "5.44"),
    "RMSE θ (rad), online odometry": ("0.585", "0.941"),
    "RMSE x,y (m), final parameters": ("–", "–"),
    "time per step (ms)": ("0.89", "0.46"),
}


def paired_wins(md):
    """{configuration: {column: wins}} from the experiment's paired table."""
    wins, head = {}, None
    for line in md.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if cells[0] == "against":
            head = cells[1:]
        elif head and len(cells) == len(head) + 1 and "/" in cells[1]:
            wins[cells[0]] = {h: c.split(" / ")[0] for h, c in zip(head, cells[1:])}
    return wins


def table_ii_row(label, rows, wins, cell, column):
    """One metric over the configurations: `cell(row)` and, against the
    Adaptive-PF, its paired wins under `column` (None: no paired figure)."""
    out = []
    for k, (_, key) in enumerate(TABLE_II):
        text = cell(rows[key])
        if k and column:
            text += f" (wins {wins[key][column]}/{rows[key]['runs_n']})"
        out.append(text)
    return f"| {label} | {' | '.join(out + list(PAPER[label]))} |"


def block_table_ii_scans(runner, csm):
    out = runner.path("montecarlo-scans")
    runner.run(["experiment", "montecarlo-scans", "--runs", "30", "--out", out])
    with open(os.path.join(out, "montecarlo-scans.json")) as f:
        d = json.load(f)
    with open(os.path.join(out, "montecarlo-scans.md")) as f:
        wins = paired_wins(f.read())
    rows = {r["label"]: dict(r, runs_n=d["runs"]) for r in d["rows"]}
    med = lambda r, k: r[k]["median"]
    mm = lambda v: num(v * 1000, 2 if v < 0.01 else 1)
    c = lambda r: med(r, "convergence_s_censored")  # a run that never converges counts its length
    conv = lambda r: (f"{num(c(r), 1 if c(r) < 100 else 0)}, "
                      f"{r['converged'] * 100:.0f} %")
    return [
        "| | " + " | ".join(name for name, _ in TABLE_II) + " | paper: Adaptive-PF | paper: DKF |",
        "|---|---|---|---|---|---|---|",
        table_ii_row("final radius error R_R / R_L (mm)", rows, wins,
                     lambda r: f"{num(med(r, 'err_r_right') * 1000, 2)} / {num(med(r, 'err_r_left') * 1000, 2)}",
                     "radius error"),
        table_ii_row("wheel base error (mm)", rows, wins, lambda r: mm(med(r, "err_wheel_base")), None),
        table_ii_row("convergence (s), runs converged", rows, wins, conv, "convergence"),
        table_ii_row("RMSE x,y (m), online odometry", rows, wins,
                     lambda r: num(med(r, "rmse_xy"), 3), "RMSE x,y"),
        table_ii_row("RMSE θ (rad), online odometry", rows, wins,
                     lambda r: num(med(r, "rmse_theta"), 4), "RMSE θ"),
        table_ii_row("RMSE x,y (m), final parameters", rows, wins,
                     lambda r: num(med(r, "rmse_xy_final"), 3 if med(r, "rmse_xy_final") < 1 else 2),
                     "RMSE x,y, final parameters"),
        table_ii_row("time per step (ms)", rows, wins,
                     lambda r: f"{med(r, 'mean_iteration_ms'):.2g}", None),
    ]


def block_blind_suite(runner, csm):
    """The blind diagnosis suite's table, as `odocal experiment diagnose`
    writes it (125 simulated runs through bag, ICP and diagnosis)."""
    out = runner.path("blind-suite")
    runner.run(["experiment", "diagnose", "--runs", "5", "--seed", "200", "--out", out])
    with open(os.path.join(out, "diagnose.md")) as f:
        return [line.rstrip("\n") for line in f if line.startswith("|")]


def volatile(row):
    """Rows of timings: measured on a quiet machine (README says which), so
    neither compared nor rewritten here."""
    return row.startswith("| time per step")


def merged(old, new):
    """`new` with each volatile row taken from `old` (matched by its first
    cell) where it has one."""
    first = lambda row: row.split("|")[1].strip() if row.count("|") > 1 else row
    kept = {first(r): r for r in old if volatile(r)}
    return [kept.get(first(r), r) if volatile(r) else r for r in new]


# name: (how it is computed, whether it is slow: computed only with --all).
BLOCKS = {
    "icp-truth": (block_icp_truth, False),
    "relations": (block_relations, False),
    "run-to-run": (block_run_to_run, False),
    "real-calibration": (block_real_calibration, False),
    "what-changed": (block_what_changed, False),
    "real-firings": (block_real_firings, False),
    "table-ii-scans": (block_table_ii_scans, True),
    "blind-suite": (block_blind_suite, True),
}


# --- CSM's recorded figures ----------------------------------------------------

CSM_SOURCE = (
    "CSM (Censi's PL-ICP, github.com/AndreaCensi/csm at dff2557, CMake Release, "
    "-O3 -D_GNU_SOURCE, default sm_icp parameters, scan to scan from the odometry, "
    "the scans' true beam angles; the laser pose -laser_x 0.04 on FR079), epsilon_xy = epsilon_theta = F x 1e-4 for each "
    "factor F; each run's trajectory scored with `odocal eval --relations --json` "
    "(README, Performance)"
)


def csm_run(csm, log, factor):
    try:
        return csm["runs"][log][factor]
    except KeyError:
        raise Skip(f"no CSM run of {log} at {factor}× in {CSM_FILE} (record it with --csm DIR)")


def record_csm(runner, folder):
    """Scores CSM's trajectories DIR/LOG-F.tum and rewrites figures_csm.json."""
    csm = {"source": CSM_SOURCE}
    for log in LOGS:
        for factor in FACTORS:
            tum = os.path.join(folder, f"{log}-{factor}.tum")
            rel = os.path.join(runner.data, "slam-benchmark", f"{log}.relations")
            out = runner.run(["eval", "--estimate", tum, "--relations", rel, "--json"])
            csm.setdefault("runs", {}).setdefault(log, {})[factor] = json.loads(out)["relations"]
    write_atomically(CSM_FILE, json.dumps(csm, indent=1) + "\n")


# --- README ------------------------------------------------------------------


def blocks_of(text):
    """{name: (first line index inside, end marker's index)} of README's
    generated blocks; an unterminated or repeated block is an error."""
    lines, found, i = text.split("\n"), {}, 0
    while i < len(lines):
        m = BEGIN.match(lines[i])
        if m:
            end = next((j for j in range(i + 1, len(lines)) if lines[j] == END), None)
            if end is None or m.group(1) in found:
                raise SystemExit(f"README.md line {i + 1}: block {m.group(1)} unterminated or repeated")
            found[m.group(1)] = (i + 1, end)
            i = end
        i += 1
    return lines, found


def write_atomically(path, text):
    """`text` into `path` through a renamed temporary file (the file's mode
    kept; 0644 for a new one)."""
    mode = os.stat(path).st_mode & 0o777 if os.path.exists(path) else 0o644
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".figures-")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.chmod(tmp, mode)
    os.replace(tmp, path)


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
            record_csm(runner, a.csm)
            return 0
        return regenerate(runner, a)


def regenerate(runner, a):
    with open(README) as f:
        text = f.read()
    lines, found = blocks_of(text)
    names = a.only or sorted(n for n, (_, slow) in BLOCKS.items() if a.all or not slow)
    missing = [n for n in names if n not in found]
    if missing:
        raise SystemExit(f"README.md has no block {', '.join(missing)}")
    with open(CSM_FILE) as f:
        csm = json.load(f)
    changed, skipped = [], []
    # Every block started at once (each waits on its own runs in the pool).
    with concurrent.futures.ThreadPoolExecutor(max_workers=len(names)) as blocks:
        results = {n: blocks.submit(BLOCKS[n][0], runner, csm) for n in names}
    for name in sorted(names, key=lambda n: -found[n][0]):
        start, end = found[name]
        try:
            new = results[name].result()
        except RuntimeError as e:
            raise SystemExit(f"figures {name}: {e}")
        except Skip as s:
            print(f"SKIP figures {name}: {s}", file=sys.stderr)
            skipped.append(name)
            continue
        old = lines[start:end]
        new = merged(old, new)
        if a.print:
            print(f"<!-- figures: {name} -->\n" + "\n".join(new) + f"\n{END}")
        if new != old:
            changed.append(name)
            sys.stderr.writelines(difflib.unified_diff(
                [l + "\n" for l in old], [l + "\n" for l in new],
                f"README.md ({name})", f"odocal ({name})"))
            lines[start:end] = new
    if a.write and changed:
        write_atomically(README, "\n".join(lines))
    verdict = "differ" if a.check else "changed"
    print(f"figures: {len(names) - len(skipped)} blocks computed, {len(skipped)} skipped; "
          f"{verdict}: {', '.join(sorted(changed)) or 'none'}", file=sys.stderr)
    if skipped and os.environ.get("CI"):
        print("figures: under CI every block must be computed", file=sys.stderr)
        return 1
    return 1 if a.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())
