"""The scan matching's blocks: motion sums against the simulator's truth,
the benchmark logs' relations against CSM's, and their run-to-run spread;
CSM's recorded runs."""
import json
import os
import re
import statistics
import subprocess
import sys

from .common import ROOT, Skip, spread, write_atomically

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

CSM_FILE = os.path.join(ROOT, "tools", "figures_csm.json")

CSM_SOURCE = (
    "CSM (Censi's PL-ICP, github.com/AndreaCensi/csm at dff2557, CMake Release, "
    "-O3 -D_GNU_SOURCE, default sm_icp parameters, scan to scan from the odometry, "
    "the scans' true beam angles; the laser pose -laser_x 0.04 on FR079), "
    "epsilon_xy = epsilon_theta = F x 1e-4 for each factor F; each run's trajectory "
    "scored with `odocal eval --relations --json` (docs/performance.md)"
)


def default_convergence():
    """The default `[icp] convergence` (m), read from src/icp/params.rs."""
    with open(os.path.join(ROOT, "src", "icp", "params.rs")) as f:
        m = re.search(r"^\s*convergence: ([0-9.eE+-]+),$", f.read(), re.M)
    if not m:
        raise SystemExit("src/icp/params.rs: no default `convergence: X,` found")
    return float(m.group(1))


def bound_config(runner, log, factor):
    """`--config` arguments setting the convergence bound to `factor` times
    its default (a file of the log's own: the runs go in parallel); none for
    the default itself."""
    if factor == "1.0":
        return []
    bound = float(factor) * default_convergence()
    return ["--config", runner.scratch_file(f"conv-{log}-{factor}.toml", f"[icp]\nconvergence = {bound!r}\n")]


def relations(runner, log, factor):
    """`odocal eval --relations --json` of a benchmark log matched with the
    convergence bound at `factor` times its default, with the matcher's mean
    iterations per pair (a future, run once)."""
    bag = runner.data_file(f"slam-benchmark/{log}.mcap")

    def work():
        tum = runner.path(f"{log}-{factor}.tum")
        icp = runner.run(["icp", "--input", bag, "--out", tum, "--json"] + bound_config(runner, log, factor))
        rel = os.path.join(runner.data, "slam-benchmark", f"{log}.relations")
        out = runner.run(["eval", "--estimate", tum, "--relations", rel, "--json"])
        return dict(json.loads(out)["relations"], iterations_per_pair=json.loads(icp)["mean_iterations"])

    return runner.once(("relations", log, factor), work)


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
    futures = {log: relations(runner, log, "1.0") for log in LOGS}
    for log in LOGS:
        ours = relations_cells(futures[log].result())
        theirs = relations_cells(csm_run(csm, log, "1.0"))
        rows.append(f"| {LOG_LABEL[log]} | {' | '.join(ours + theirs)} |")
    return rows


def ensemble_cells(runs):
    """(local, all) cells over the five bounds: median (range)."""
    t, t_range = spread([r["local"]["trans_mean"] for r in runs], 4)
    a, a_range = spread([r["local"]["rot_mean_deg"] for r in runs], 3)
    if t_range is None and a_range is None:
        local = f"{t} m, {a}° (every run)"
    else:
        local = f"{t} m{f' ({t_range})' if t_range else ''}, {a}°"
        local += f" ({a_range}°)" if a_range else ""
    m, m_range = spread([r["trans_mean"] for r in runs], 3)
    return local, f"{m} m ({m_range})" if m_range else f"{m} m (every run)"


def block_run_to_run(runner, csm):
    rows = [
        "| log | odocal local | odocal all | CSM local | CSM all |",
        "|---|---|---|---|---|",
    ]
    futures = {(log, f): relations(runner, log, f) for log in LOGS for f in FACTORS}
    for log in LOGS:
        ours = ensemble_cells([futures[(log, f)].result() for f in FACTORS])
        theirs = ensemble_cells([csm_run(csm, log, f) for f in FACTORS])
        rows.append(f"| {log} | {' | '.join(ours + theirs)} |")
    return rows


# The convergence bounds of the speed table (m, as multiples of the default
# 10 µm), each judged over its own five-bound ensemble.
SWEEP = [("1 m (one step)", 100000), ("1 cm", 1000), ("1 mm", 100), ("0.1 mm", 10), ("10 µm (default)", 1)]


def sweep_factor(multiple, factor):
    """The factor of the default bound for `factor` times `multiple` of it."""
    return "1.0" if multiple == 1 and factor == "1.0" else repr(multiple * float(factor))


def sweep_cell(runs, at_bound):
    """Iterations per pair at the bound itself; the ensemble's median local
    translation and rotation and all-relations errors."""
    med = statistics.median
    return (f"{at_bound['iterations_per_pair']:.1f} it; "
            f"{med([r['local']['trans_mean'] for r in runs]):.4f} m, "
            f"{med([r['local']['rot_mean_deg'] for r in runs]):.3f}°, "
            f"{med([r['trans_mean'] for r in runs]):.3f} m")


def block_bound_sweep(runner, csm):
    rows = ["| bound | " + " | ".join(LOGS) + " |", "|---|---|---|---|---|"]
    futures = {(log, m, f): relations(runner, log, sweep_factor(m, f))
               for _, m in SWEEP for log in LOGS for f in FACTORS}
    for label, m in SWEEP:
        cells = []
        for log in LOGS:
            runs = [futures[(log, m, f)].result() for f in FACTORS]
            cells.append(sweep_cell(runs, runs[FACTORS.index("1.0")]))
        rows.append(f"| {label} | {' | '.join(cells)} |")
    theirs = [sweep_cell([csm_run(csm, log, f) for f in FACTORS], csm_run(csm, log, "1.0")) for log in LOGS]
    return rows + [f"| CSM (its loop) | {' | '.join(theirs)} |"]


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
    cfg = runner.scratch_file(f"truth-{k}.toml", icp_settings)
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


def csm_run(csm, log, factor):
    try:
        return csm["runs"][log][factor]
    except KeyError:
        raise Skip(f"no CSM run of {log} at {factor}× in {CSM_FILE} (record it with --csm DIR)")


def record_csm(runner, folder):
    """Scores CSM's trajectories DIR/LOG-F.tum, reads its iterations per pair
    from the driver's DIR/LOG-F.err, and rewrites figures_csm.json."""
    csm = {"source": CSM_SOURCE}
    for log in LOGS:
        for factor in FACTORS:
            tum = os.path.join(folder, f"{log}-{factor}.tum")
            rel = os.path.join(runner.data, "slam-benchmark", f"{log}.relations")
            out = runner.run(["eval", "--estimate", tum, "--relations", rel, "--json"])
            run = json.loads(out)["relations"]
            with open(os.path.join(folder, f"{log}-{factor}.err")) as f:
                run["iterations_per_pair"] = float(re.search(r"iters_per_pair ([0-9.]+)", f.read()).group(1))
            csm.setdefault("runs", {}).setdefault(log, {})[factor] = run
    write_atomically(CSM_FILE, json.dumps(csm, indent=1) + "\n")


# The metrics of the side-by-side: `[icp] metric` values and their labels.
METRICS = [("point-to-line", "point-to-line (default)"), ("point-to-point", "point-to-point")]


def metric_relations(runner, log, metric):
    """`relations` of one log matched with `[icp] metric = metric` (the
    default bound), with its iterations per pair; point-to-line is the
    default run itself."""
    if metric == "point-to-line":
        return relations(runner, log, "1.0")
    bag = runner.data_file(f"slam-benchmark/{log}.mcap")

    def work():
        cfg = runner.scratch_file(f"metric-{metric}.toml", f'[icp]\nmetric = "{metric}"\n')
        tum = runner.path(f"{log}-{metric}.tum")
        icp = runner.run(["icp", "--input", bag, "--out", tum, "--json", "--config", cfg])
        rel = os.path.join(runner.data, "slam-benchmark", f"{log}.relations")
        out = runner.run(["eval", "--estimate", tum, "--relations", rel, "--json"])
        return dict(json.loads(out)["relations"], iterations_per_pair=json.loads(icp)["mean_iterations"])

    return runner.once(("metric-relations", log, metric), work)


# Simulated recordings of the metrics' truth rows: label and `simulate` arguments.
METRIC_SIMS = [
    ("corridor loop, scan to scan", ["--scenario", "corridor-loop", "--seed", "5"], True),
    ("corridor loop, local map", ["--scenario", "corridor-loop", "--seed", "5"], False),
    ("square room, scan to scan", ["--scenario", "square", "--duration", "60", "--seed", "3"], True),
]


def block_icp_metrics(runner, csm):
    rows = [
        "| metric | recording | local | all | iterations per pair |",
        "|---|---|---|---|---|",
    ]
    futures = {(log, m): metric_relations(runner, log, m) for log in LOGS for m, _ in METRICS}
    for metric, label in METRICS:
        for log in LOGS:
            r = futures[(log, metric)].result()
            local, whole = relations_cells(r)
            rows.append(f"| {label} | {log} | {local} | {whole} | {r['iterations_per_pair']:.1f} |")
    rows += [
        "",
        "| metric | simulated recording | Σdx ICP/true | Σdθ ICP/true | error per pair | flagged pairs |",
        "|---|---|---|---|---|---|",
    ]
    sims = {tuple(sim) for _, sim, _ in METRIC_SIMS}
    for fut in [runner.pool.submit(simulate, runner, list(sim)) for sim in sorted(sims)]:
        fut.result()
    jobs = []
    for metric, label in METRICS:
        for k, (name, sim, scan_to_scan) in enumerate(METRIC_SIMS):
            cfg = f'[icp]\nmetric = "{metric}"\n' + ("local_map = false\n" if scan_to_scan else "")
            key = f"metric-{metric}-{k}"
            jobs.append((label, name, runner.pool.submit(truth_row, runner, key, sim, cfg)))
    for label, name, fut in jobs:
        rows.append(f"| {label} | {name} | {' | '.join(fut.result())} |")
    return rows
