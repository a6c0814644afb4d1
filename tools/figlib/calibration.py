"""The calibration blocks: the real recordings' batch and filter
calibrations, [Farina, Table II] on simulated scans, a simulated fleet."""
import json
import os
import re

from .common import ROOT, num, pm

PARAMETER_LABEL = {"r_right": "R_R", "r_left": "R_L", "wheel_base": "D"}


def calibrate(runner, bag, robot, method, init_batch):
    """A future of one `odocal calibrate --json` (run once): its output, or
    None and the reason when the calibration is refused (exit 2)."""
    args = ["calibrate", "--input", bag, "--robot", robot, "--method", method, "--json"]
    args += ["--init", "batch"] if init_batch else []
    out = runner.path(f"cal-{os.path.basename(bag)}-{method}-{int(init_batch)}")
    return calibrate_once(runner, ("calibrate", bag, robot, method, init_batch), args, out)


def calibrate_once(runner, key, args, out, result=lambda out, d: d):
    """A future of `odocal ARGS --out OUT` run once per `key`: `result(out,
    its JSON)`, or None and the reason when the calibration is refused
    (exit 2)."""

    def work():
        p = runner.call([*args, "--out", out], allowed=(0, 2))
        refused = re.search(r"calibration refused: (.*)", p.stderr)
        if p.returncode == 2 and refused:
            return None, refused.group(1)
        if p.returncode != 0:
            raise RuntimeError(f"odocal {' '.join(args)} failed ({p.returncode}):\n{p.stderr}")
        return result(out, json.loads(p.stdout)), None

    return runner.once(key, work)


def refusal_cell(reason):
    """A refusal in a few words: a parameter at its search range's edge named
    with its value, any other reason as odocal gives it."""
    m = re.match(r"(\w+) came out ([0-9.]+) m, at the edge of its search range", reason)
    if m:
        name = PARAMETER_LABEL.get(m.group(1), m.group(1))
        return f"refused ({name} {num(float(m.group(2)) * 1000, 1)} mm at the edge of its search range)"
    return f"refused ({reason.split(':')[0]})"


# The real-robot table: each online method (and the published Adaptive-PF)
# from the robot file's nominal values, and the batch, on every real
# recording. (label, input under the data folder, robot file name).
REAL_INPUTS = [
    ("LEGO robot", "lego-robot/lego-robot.mcap", "lego-robot"),
    ("Mines exp1", "mines-rover/exp1.mcap", "mines-rover"),
    ("Mines exp2", "mines-rover/exp2.mcap", "mines-rover"),
    ("Censi lstraight", "censi-calibration/lstraight.tuple", "khepera"),
    ("Censi l90", "censi-calibration/l90.tuple", "khepera"),
    ("Censi lmov", "censi-calibration/lmov.tuple", "khepera"),
]
# (row label, method, whether the published preset)
REAL_ROWS = [
    ("adaptive-pf", "adaptive-pf", False),
    ("pf", "pf", False),
    ("dkf", "dkf", False),
    ("akf", "akf", False),
    ("adaptive-pf, published", "adaptive-pf", True),
    ("batch", "batch", False),
]
# The independent references: the LEGO tracker's dead-reckoning fit (data
# README: 20.0 mm wheels, 172.5 mm track; compared as R/D, free of the
# tracker's scale), the Mines tick check (data README: 2050 / 2160 ticks per
# revolution at 77 mm from straight runs), the authors' solver (Censi).
TRACKER_TURN = 0.0200 / 0.1725
TICKS_RADIUS = {"Mines exp1": 0.077 * 2000 / 2050, "Mines exp2": 0.077 * 2000 / 2160}


def published_config(runner):
    return runner.scratch_file("published.toml", '[calib]\npreset = "published"\n')


def real_run(runner, label, rel, robot, method, published):
    """A future of `odocal calibrate --json` from the nominal values: (its
    output, its calibration.csv rows) or (None, the refusal)."""
    bag = runner.data_file(rel)
    args = ["calibrate", "--input", bag, "--robot", robot, "--method", method, "--json"]
    args += ["--config", published_config(runner)] if published else []
    out = runner.path(f"real-{label.replace(' ', '-')}-{method}-{int(published)}")
    with_history = lambda out, d: (d, history_rows(out))
    return calibrate_once(runner, ("real", rel, robot, method, published), args, out, with_history)


def history_rows(out):
    """(t, R_R, R_L, D) of each row of OUT/calibration.csv (none without it)."""
    rows = []
    csv = os.path.join(out, "calibration.csv")
    if os.path.exists(csv):
        with open(csv) as f:
            head = f.readline().strip().split(",")
            for line in f:
                row = dict(zip(head, line.strip().split(",")))
                rows.append([float(row[k]) for k in ("t", "r_right", "r_left", "wheel_base")])
    return rows


def kinematics(d):
    """(R_R, R_L, D), (their std) of a filter's or the batch's output."""
    if "final" in d:
        f, s = d["final"], d["std"]
        return [f[k] for k in ("r_right", "r_left", "wheel_base")], [s[k] for k in ("r_right", "r_left", "wheel_base")]
    return ([d[k]["value"] for k in ("r_right", "r_left", "wheel_base")],
            [d[k]["std"] for k in ("r_right", "r_left", "wheel_base")])


def settled_s(history):
    """Seconds from the first estimate to the first after which every one
    stays within 1 % of the final radii and 2 % of the final wheel base."""
    if len(history) < 2:
        return None
    last = history[-1]
    near = lambda h: all(abs(h[i] / last[i] - 1) <= 0.01 for i in (1, 2)) and abs(h[3] / last[3] - 1) <= 0.02
    k = len(history) - 1
    while k > 0 and near(history[k - 1]):
        k -= 1
    return history[k][0] - history[0][0]


def reference_cell(label):
    if label == "LEGO robot":
        return f"tracker fit: R/D {TRACKER_TURN:.4f} (20.0 / 172.5 mm)"
    if label in TICKS_RADIUS:
        return f"tick check: R {num(TICKS_RADIUS[label] * 1000, 1)} mm"
    return "authors' solver: " + censi_authors_text(label)


def censi_authors(runner, label):
    path = runner.data_file(f"censi-calibration/{label.split()[-1]}_results.json")
    with open(path) as f:
        a = json.load(f)
    return [a["r_diam"] / 2, a["l_diam"] / 2, a["axle"]]


def censi_authors_text(label):
    return f"`{label.split()[-1]}_results.json`"


def agreement(runner, label, k):
    """How the estimate `k` = (R_R, R_L, D) departs from the column's
    independent reference."""
    if label == "LEGO robot":
        turn = 0.5 * (k[0] + k[1]) / k[2]
        return f"R/D {num(100 * (turn / TRACKER_TURN - 1), 1)} %"
    if label in TICKS_RADIUS:
        r = 0.5 * (k[0] + k[1])
        return f"R {num(100 * (r / TICKS_RADIUS[label] - 1), 1)} %"
    a = censi_authors(runner, label)
    worst = max((abs(k[i] / a[i] - 1), i) for i in range(3))
    return f"worst {('R_R', 'R_L', 'D')[worst[1]]} {num(100 * (k[worst[1]] / a[worst[1]] - 1), 2)} %"


def real_cell(runner, label, result):
    got, refused = result
    if refused:
        return refusal_cell(refused)
    d, history = got
    k, s = kinematics(d)
    cell = (f"R {num(k[0] * 1000, 2 if k[0] < 0.03 else 1)} / {num(k[1] * 1000, 2 if k[1] < 0.03 else 1)} "
            f"± {num(max(s[0], s[1]) * 1000, 2 if k[0] < 0.03 else 1)}, "
            f"D {num(k[2] * 1000, 1)} ± {num(s[2] * 1000, 1)}")
    dt = d.get("time_offset")
    if dt and dt.get("value") is not None and dt.get("source", "estimated") == "estimated" and dt["std"] > 0:
        cell += f"; δ {num(dt['value'], 3)} ± {num(dt['std'], 3)} s"
    t = settled_s(history) if "final" in d else None
    if t is not None:
        cell += f"; settled {num(t, 0)} s"
    return cell + f"; {agreement(runner, label, k)}"


def block_real_calibration(runner, csm):
    rows = ["| | " + " | ".join(label for label, _, _ in REAL_INPUTS) + " |",
            "|---" * (len(REAL_INPUTS) + 1) + "|",
            "| reference | " + " | ".join(reference_cell(label) for label, _, _ in REAL_INPUTS) + " |"]
    futures = {
        (row, label): real_run(runner, label, rel, robot, method, published)
        for row, method, published in REAL_ROWS
        for label, rel, robot in REAL_INPUTS
    }
    for row, _, _ in REAL_ROWS:
        cells = [real_cell(runner, label, futures[(row, label)].result()) for label, _, _ in REAL_INPUTS]
        rows.append(f"| {row} | {' | '.join(cells)} |")
    return rows


# The LEGO robot's scanner corrections, each row's `[scanner]` keys kept from
# its robot file (scans/robots/lego-robot.toml), then the data README's own
# dead reckoning (a record, not computed).
LEGO_SCANNER = [
    ("as recorded", ()),
    ("range offset 70 mm", ("range_offset",)),
    ("beam spacing ×1.03", ("angle_increment",)),
    ("both (the robot file)", ("angle_increment", "range_offset")),
]
LEGO_DATA_README = ("| data README: 0.349 mm/tick (fitted to the tracker), width and start pose fitted to the "
                    "tracker | 20.0 | 172.5 | – | 0.056 m | – |")


def lego_robot_with(runner, keys):
    """The LEGO robot file with only `keys` of its `[scanner]` table."""
    with open(os.path.join(ROOT, "scans", "robots", "lego-robot.toml")) as f:
        lines, table = f.read().splitlines(), None
    kept = []
    for line in lines:
        if line.startswith("["):
            table = line.split("]")[0].strip("[")
        key = line.split("=")[0].strip()
        if table == "scanner" and "=" in line and key not in keys:
            continue
        kept.append(line)
    name = f"lego-robot-{'-'.join(keys) or 'as-recorded'}.toml"
    return runner.scratch_file(name, "\n".join(kept) + "\n")


def lego_scanner_row(runner, bag, label, keys):
    """The batch with these scanner corrections, then its odometry (`--method
    none`, on the laser clock) against the tracker, SE(2)- and Sim(2)-aligned
    after moving it back by the batch's time offset."""
    name = f"lego-scanner-{len(keys)}-{'-'.join(keys)}"
    out, cfg = runner.path(name), runner.scratch_file(f"{name}.toml", '[topics]\nreference = "/reference"\n')
    args = ["calibrate", "--input", bag, "--robot", lego_robot_with(runner, keys), "--init", "batch",
            "--method", "none", "--out", out, "--json"]
    start = json.loads(runner.run(args))["start"]
    delta = start["time_offset"]["value"]
    ape = {}
    for align in ("se2", "sim2"):
        ape[align] = json.loads(runner.run([
            "eval", "--estimate", os.path.join(out, "trajectory.tum"), "--reference", bag, "--align",
            align, "--t-offset", repr(delta), "--config", cfg, "--json"]))
    rr, rl, wb = start["r_right"], start["r_left"], start["wheel_base"]
    return (f"| {label} | {num(rr['value'] * 1000, 1)} / {num(rl['value'] * 1000, 1)} ± "
            f"{num(max(rr['std'], rl['std']) * 1000, 1)} | {num(wb['value'] * 1000, 0)} ± {num(wb['std'] * 1000, 0)} | "
            f"{num(delta, 3)} | {ape['se2']['ape']['rmse']:.3f} m | {ape['sim2']['ape']['rmse']:.3f} m, "
            f"{ape['sim2']['alignment']['scale']:.3f} |")


def block_lego_scanner(runner, csm):
    bag = runner.data_file("lego-robot/lego-robot.mcap")
    rows = ["| scanner | R_R / R_L (mm) | D (mm) | δ (s) | APE SE(2) | APE Sim(2), scale |",
            "|---|---|---|---|---|---|"]
    futures = [runner.pool.submit(lego_scanner_row, runner, bag, label, keys) for label, keys in LEGO_SCANNER]
    return rows + [f.result() for f in futures] + [LEGO_DATA_README]


# The columns (the experiment's configurations) and the figures of [Farina, Table II]
# (its Table II: a record, not computed).
TABLE_II = [("Adaptive-PF", "adaptive-pf"), ("DKF", "dkf"), ("AKF", "akf"), ("PF (fixed)", "pf"),
            ("Adaptive-PF, published", "adaptive-pf-published")]

PAPER = {
    "final radius error R_R / R_L (mm)": ("1.86 / 1.91", "2.11 / 1.85"),
    "wheel base error (mm)": ("–", "–"),
    "convergence (s), runs converged": ("32.55", "60.73"),
    "RMSE x,y (m), online odometry": ("3.38", "5.44"),
    "RMSE θ (rad), online odometry": ("0.585", "0.941"),
    "RMSE x,y (m), final parameters": ("–", "–"),
    "RMSE x,y (m), 10 s windows from the estimate at each start": ("–", "–"),
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
        "|---" * (len(TABLE_II) + 3) + "|",
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
        table_ii_row("RMSE x,y (m), 10 s windows from the estimate at each start", rows, wins,
                     lambda r: num(med(r, "rmse_xy_window"), 3), "RMSE x,y, 10 s windows"),
        table_ii_row("time per step (ms)", rows, wins,
                     lambda r: f"{med(r, 'mean_iteration_ms'):.2g}", None),
    ]


def fleet_alarm_cell(found, alarms):
    """The experiment's verdict on what was found, with the alarm's size (a
    step) or how many recordings it spans (a fault)."""
    for a in alarms:
        values = a.get("values") or {}
        side = next((k for k in ("r_left", "r_right") if f"{k}_step_m" in values), None)
        if a["kind"] == "step" and side:
            name = {"r_left": "R_L", "r_right": "R_R"}[side]
            size = pm(values[f"{side}_step_m"], values[f"{side}_step_std_m"], 1000, 2, "mm")
            return f"{found}: {name} {size}"
        spans = values.get("recordings", 1)
        if a["kind"] == "fault" and spans > 1:
            return found.replace(")", f", {spans:.0f} recordings)")
    return found


def block_fleet(runner, csm):
    """`odocal experiment fleet --runs 12 --seed 7` with ten days: each
    robot's hidden history against what the fleet run found."""
    out, cfg = runner.path("fleet"), runner.scratch_file("fleet.toml", "[fleet]\ndays = 10\n")
    runner.run(["experiment", "fleet", "--runs", "12", "--seed", "7", "--settings", cfg, "--out", out])
    with open(os.path.join(out, "fleet.json")) as f:
        verdicts = json.load(f)["verdicts"]
    with open(os.path.join(out, "fleet-run", "fleet.json")) as f:
        alarms = json.load(f)["alarms"]
    rows = ["| robot | hidden history | alarms | wear rate est./true | right |", "|---|---|---|---|---|"]
    for v in verdicts:
        mine = [a for a in alarms if a["robot"] == v["robot"]]
        ratio = f"{v['rate_ratio']:.3f}" if v["rate_ratio"] is not None else ""
        cells = [v["robot"], v["truth"].replace("-", "−"), fleet_alarm_cell(v["found"], mine), ratio,
                 "yes" if v["correct"] else "no"]
        rows.append("| " + " | ".join(cells).replace("|  |", "| |") + " |")
    return rows
