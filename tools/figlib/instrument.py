"""The scan matcher as an instrument: scan-to-scan ICP's own error per pair,
measured on null runs of the simulator (no effect, so the wheels read the
true motion), and the null diagnoses at three lengths.

The truth of each pair is the wheel encoders' (nominal radius 0.32 m, wheel
base 0.65 m): in a null run the simulated chair carries no effect, so they
read its true wheel motion, quantised to 8800 ticks and sampled at 100 Hz
(the 10 Hz /ground_truth poses are too coarse for 20 ms pairs). Reading the bags uses Python `mcap` and `rosbags`; the arithmetic is
numpy's, nothing of odocal's diagnosis."""
import csv
import math
import os

import numpy as np

from .common import num

# The wheelchair's nominal wheels.
RADIUS, WHEEL_BASE = 0.32, 0.65
SCENARIOS = ["figure-eight", "random-walk", "hall", "square", "corridor-loop"]
# (laser rate Hz, seeds): the `simulate` default and the blind suite's.
RUNS = [(50, (401, 402, 403)), (25, (401, 402))]
DURATION = 150
# Inner bin bounds, as `diagnose::instrument::Instrument` holds them.
ANISOTROPY = [2.0, 2.5, 3.0]
STEP = [0.012, 0.02]
ROTATION = [0.002, 0.005, 0.01, 0.02]
# A pair whose forward step is under this (m) turns in place: the laser,
# off the axle, swings on an arc with nothing of a forward motion.
IN_PLACE_STEP = 0.002
# Rows a run needs in a cell to count in its run-to-run spread.
MIN_ROWS = 50


def _topic(bag, topic):
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with open(bag, "rb") as f:
        for schema, _, msg in make_reader(f).iter_messages(topics=[topic]):
            yield ts.deserialize_cdr(msg.data, schema.name)


def _stamp(m):
    return m.header.stamp.sec + m.header.stamp.nanosec * 1e-9


def pairs(bag, motions):
    """Per valid pair: true forward speed and turn rate (wheels), ICP's
    (the motion's own, as the diagnosis reads it), the anisotropy σx/σy and
    the weights 1/σ² of both."""
    jt, jl, jr = [], [], []
    for m in _topic(bag, "/joint_states"):
        pos = dict(zip(m.name, m.position))
        jt.append(_stamp(m)), jl.append(pos["left_wheel"]), jr.append(pos["right_wheel"])
    jt, jl, jr = map(np.array, (jt, jl, jr))
    with open(motions) as f:
        rows = [r for r in csv.DictReader(f) if r["valid"] == "1"]
    col = lambda k: np.array([float(r[k]) for r in rows])
    t0, t1 = col("t0"), col("t1")
    dt = t1 - t0
    keep = dt > 0
    dl = np.interp(t1, jt, jl) - np.interp(t0, jt, jl)
    dr = np.interp(t1, jt, jr) - np.interp(t0, jt, jr)
    v = RADIUS * (dl + dr) / 2 / dt
    w = RADIUS * (dr - dl) / WHEEL_BASE / dt
    out = dict(dt=dt, v=v, w=w, icp_v=col("dx") / dt, icp_w=col("dtheta") / dt,
               anisotropy=np.sqrt(col("cov_xx") / col("cov_yy")),
               wv=dt ** 2 / col("cov_xx"), ww=dt ** 2 / col("cov_tt"))
    return {k: a[keep] for k, a in out.items()}


def _bin(edges, x):
    return np.searchsorted(np.array(edges), x, side="right")


def cells(runs):
    """The table: per cell the pooled relative error Σ w e x / Σ w x² over
    every run, the standard deviation of the runs' own estimates (runs with
    at least MIN_ROWS rows there) and the rows. A cell seen in fewer than
    three runs is allowed its whole error again as spread. The turn rate's
    cells are per rotation bin, for pairs moving forward (row 0) and turning
    in place (row 1); an in-place cell no pair fell in takes the moving
    pairs' cell (and says so by its row count, 0)."""
    shape_v = (len(ANISOTROPY) + 1, len(STEP) + 1)
    shape_w = (2, len(ROTATION) + 1)

    def table(shape, key):
        num_, den, n = np.zeros(shape), np.zeros(shape), np.zeros(shape, int)
        per_run = {}
        for d in runs:
            if key == "v":
                idx = (_bin(ANISOTROPY, d["anisotropy"]), _bin(STEP, np.abs(d["v"]) * d["dt"]))
                e, x, wt = d["icp_v"] - d["v"], d["v"], d["wv"]
            else:
                idx = ((np.abs(d["v"]) * d["dt"] < IN_PLACE_STEP).astype(int),
                       _bin(ROTATION, np.abs(d["w"]) * d["dt"]))
                e, x, wt = d["icp_w"] - d["w"], d["w"], d["ww"]
            moving = np.abs(x) > (0.05 if key == "v" else 0.02)
            for cell in np.ndindex(*shape):
                s = moving & np.all([i == c for i, c in zip(idx, cell)], axis=0)
                a, b = (wt[s] * e[s] * x[s]).sum(), (wt[s] * x[s] ** 2).sum()
                num_[cell] += a
                den[cell] += b
                n[cell] += s.sum()
                if s.sum() >= MIN_ROWS:
                    per_run.setdefault(cell, []).append(a / b)
        out = {}
        for cell in np.ndindex(*shape):
            err = num_[cell] / den[cell] if den[cell] > 0 else 0.0
            own = per_run.get(cell, [])
            spread = float(np.std(own)) if len(own) >= 3 else max(abs(err), float(np.std(own or [0])))
            out[cell] = (float(err), spread, int(n[cell]), len(own))
        if key == "w":
            for j in range(shape[1]):
                if out[(1, j)][2] == 0:
                    out[(1, j)] = out[(0, j)][:2] + (0, 0)
        return out

    return table(shape_v, "v"), table(shape_w, "w")


def measure(runner):
    """Simulates and matches every null run (scan to scan) in the pool; the
    per-pair data of each."""
    s2s = runner.scratch_file("instrument-icp.toml", "[icp]\nlocal_map = false\n")

    def one(rate, scenario, seed):
        cfg = runner.scratch_file(f"instrument-sim-{rate}.toml", f"[sim.laser]\nrate_hz = {rate}.0\n")
        bag = runner.path(f"instrument-{rate}-{scenario}-{seed}.mcap")
        csv_ = bag[:-5] + ".csv"
        runner.run(["simulate", "--config", cfg, "--scenario", scenario, "--seed", seed,
                    "--duration", DURATION, "--out", bag])
        runner.run(["icp", "--config", s2s, "--input", bag, "--out", bag[:-5] + ".tum",
                    "--motions", csv_])
        return pairs(bag, csv_)

    futures = [runner.pool.submit(one, rate, sc, seed)
               for rate, seeds in RUNS for sc in SCENARIOS for seed in seeds]
    return [f.result() for f in futures]


def _bounds(edges, unit, scale=1.0):
    lo = [None] + edges
    hi = edges + [None]
    fmt = lambda x: num(x * scale, 3 if scale == 1 else 0)
    return [f"< {fmt(h)} {unit}" if a is None else f"≥ {fmt(a)} {unit}" if h is None
            else f"{fmt(a)}–{fmt(h)} {unit}" for a, h in zip(lo, hi)]


def block_icp_instrument(runner, csm):
    """The instrument table (relative error ± run-to-run spread, rows, runs
    per cell), as `diagnose::instrument::Instrument::default()` holds it."""
    runs = measure(runner)
    fwd, turn = cells(runs)
    steps = _bounds(STEP, "mm", 1000)
    rows = ["| forward speed: σx/σy of the pair | " + " | ".join(f"step {s}" for s in steps) + " |",
            "|---|" + "---|" * len(steps)]
    for i, a in enumerate(_bounds(ANISOTROPY, "")):
        cellv = [fwd[(i, j)] for j in range(len(steps))]
        rows.append(f"| {a.strip()} | " + " | ".join(
            f"{num(100 * e, 2)} ± {num(100 * s, 2)} % ({n} rows, {k} runs)" for e, s, n, k in cellv)
            + " |")
    rows += ["", f"| turn rate: rotation per pair | moving | in place (step < {num(1000 * IN_PLACE_STEP, 0)} mm) |",
             "|---|---|---|"]
    cellw = lambda e, s, n, k: (f"{num(100 * e, 2)} ± {num(100 * s, 2)} % ({n} rows, {k} runs)" if n
                                else f"{num(100 * e, 2)} ± {num(100 * s, 2)} % (no pair: the moving cell)")
    for i, r in enumerate(_bounds(ROTATION, "mrad", 1000)):
        rows.append(f"| {r} | {cellw(*turn[(0, i)])} | {cellw(*turn[(1, i)])} |")
    return rows


def rust_table(fwd, turn):
    """The table as `Instrument::default()`'s literals (4 decimals)."""
    f = lambda c: f"[{c[0]:.4f}, {c[1]:.4f}]"
    lines = ["forward: vec!["]
    for i in range(len(ANISOTROPY) + 1):
        lines.append("    vec![" + ", ".join(f(fwd[(i, j)]) for j in range(len(STEP) + 1)) + "],")
    for key, row in (("turn", 0), ("turn_in_place", 1)):
        lines += ["],", f"{key}: vec!["] if row == 0 else [f"{key}: vec!["]
        lines += [f"    {f(turn[(row, i)])}," for i in range(len(ROTATION) + 1)]
        lines.append("],")
    return "\n".join(lines)


# The null runs at three lengths: every built-in scenario, seeds 501–504.
NULL_SCENARIOS = ["figure-eight", "random-walk", "hall", "square", "square-ccw", "corridor-loop"]
NULL_LENGTHS = [60, 150, 300]
NULL_SEEDS = [501, 502, 503, 504]


def wilson(k, n, z=1.959963984540054):
    """95 % Wilson score interval of k successes in n trials [Wilson1927]."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (centre - half, centre + half)


def _null(runner, scenario, length, seed):
    """One null run through bag, ICP and diagnosis: its diagnosis."""
    import json
    bag = runner.path(f"null-{scenario}-{length}-{seed}.mcap")
    runner.run(["simulate", "--scenario", scenario, "--seed", seed, "--duration", length,
                "--out", bag])
    return json.loads(runner.run(["diagnose", "--measured", bag, "--json"]))


def block_null_lengths(runner, csm):
    """Null runs of every scenario at 60, 150 and 300 s (the `simulate`
    default: laser at 50 Hz): how many come out `no-discrepancy`, and what
    is left over otherwise or put on the scan matcher."""
    futures = {(s, n, k): runner.pool.submit(_null, runner, s, n, k)
               for s in NULL_SCENARIOS for n in NULL_LENGTHS for k in NULL_SEEDS}
    rows = ["| scenario | " + " | ".join(f"{n} s" for n in NULL_LENGTHS) + " |",
            "|---|" + "---|" * len(NULL_LENGTHS)]
    total = right = 0
    for s in NULL_SCENARIOS:
        cells = []
        for n in NULL_LENGTHS:
            ds = [futures[(s, n, k)].result() for k in NULL_SEEDS]
            ok = sum(d["verdict"] == "no-discrepancy" for d in ds)
            total, right = total + len(ds), right + ok
            wrong = sorted({f"{d['verdict']}: " + (", ".join(
                [c["effect"] for c in d["causes"]] + [f["name"] for f in d["faults"]] +
                [f"{r['stream']} {r['structure']}" for r in d["remaining"] if r["source"] == "robot"])
                or "–") for d in ds if d["verdict"] != "no-discrepancy"})
            instrument_ = sum(any(r["source"] == "scan_matching" for r in d["remaining"]) for d in ds)
            cell = f"{ok} of {len(ds)}"
            if instrument_:
                cell += f"; {instrument_} with a structure put on the scan matcher"
            if wrong:
                cell += "; " + "; ".join(wrong)
            cells.append(cell)
        rows.append(f"| {s} | " + " | ".join(cells) + " |")
    lo, hi = wilson(right, total)
    rows.append(f"| all | {right} of {total} `no-discrepancy` ({num(100 * right / total, 1)} %, "
                f"95 % Wilson interval {num(100 * lo, 1)}–{num(100 * hi, 1)} %) |" +
                " |" * (len(NULL_LENGTHS) - 1))
    return rows
