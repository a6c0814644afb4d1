"""The diagnosis blocks: the real recordings diagnosed, and the blind suite
of simulated runs."""
import json
import os
import subprocess
import sys

from .common import num, pm, percent

# (label, input under the data folder, robot: a bundled name or a robot file's
# text, settings, the authors' results file of a Censi set or None).
DIAGNOSED = [
    ('lego-robot (`[topics] reference = "/reference"`), every candidate',
     "lego-robot/lego-robot.mcap", "lego-robot", '[topics]\nreference = "/reference"\n', None),
    ("lego-robot, candidates latency, radius_scale, wheel_base_scale",
     "lego-robot/lego-robot.mcap", "lego-robot",
     '[topics]\nreference = "/reference"\n[diagnose]\n'
     'candidates = ["latency", "radius_scale", "wheel_base_scale"]\n', None),
    ("mines-rover exp1", "mines-rover/exp1.mcap", "mines-rover", "", None),
    ("mines-rover exp2", "mines-rover/exp2.mcap", "mines-rover", "", None),
    ("censi lstraight (tuples; no latency candidate: no common clock)",
     "censi-calibration/lstraight.tuple", "khepera", "", "censi-calibration/lstraight_results.json"),
    ("censi l90", "censi-calibration/l90.tuple", "khepera", "", "censi-calibration/l90_results.json"),
    ("censi lmov", "censi-calibration/lmov.tuple", "khepera", "", "censi-calibration/lmov_results.json"),
    ("intel (odometry against ICP, `[diagnose] min_interval = 1.0`, virtual wheels r 0.1 m, D 0.4 m)",
     "slam-benchmark/intel.mcap",
     'name = "intel-virtual"\nr_right = 0.1\nr_left = 0.1\nwheel_base = 0.4\n',
     "[diagnose]\nmin_interval = 1.0\n", None),
]


def diagnose(runner, k, rel, robot, settings):
    """`odocal diagnose --measured --json` of one row."""
    if "\n" in robot:
        robot = runner.scratch_file(f"robot-{k}.toml", robot)
    cfg = runner.scratch_file(f"diagnose-{k}.toml", settings)
    return json.loads(runner.run(["diagnose", "--measured", os.path.join(runner.data, rel),
                                  "--robot", robot, "--config", cfg, "--json"]))


def cause_cell(c, authors):
    """One named cause with its ΔBIC; a Censi set's laser mount beside the
    authors' (absolute: the robot file states none)."""
    e, p, se = c["effect"], c["parameters"], c["stderr"]
    if e == "latency":
        d = p["delay"]
        text = pm(d, se["delay"], 1, 3, "s") if abs(d) >= 0.01 else pm(d, se["delay"], 1000, 3, "ms")
    elif e == "laser_offset" and authors:
        text = (f"x {pm(p['x'], se['x'], 1000, 1, 'mm')}, y {pm(p['y'], se['y'], 1000, 1, 'mm')}, "
                f"yaw {pm(p['yaw'], se['yaw'], 1, 4, 'rad')} (authors {num(authors['l_x'] * 1000, 1)}, "
                f"{num(authors['l_y'] * 1000, 1)} mm, {num(authors['l_theta'], 4)} rad)")
    elif e == "laser_offset":
        text = ", ".join(f"{k} {pm(p[k], se[k], 100, 1, 'cm')}" for k in ("x", "y"))
        text += f", yaw {pm(p['yaw'], se['yaw'], 1, 3, 'rad')}"
    elif e in ("turn_slip", "encoder_gain"):
        text = pm(p["k"], se["k"], 1, 2 if e == "turn_slip" else 4, "s/rad")
    elif e == "wheel_base_scale":
        text = percent(p["scale"], se["scale"])
    elif e == "radius_scale":
        text = f"L {percent(p['left'], se['left'])}, R {percent(p['right'], se['right'])}"
    elif e == "radius_step":
        text = (f"at {p['time']:.0f} s, L {pm(p['left'], se['left'], 1000, 2, 'mm')}, "
                f"R {pm(p['right'], se['right'], 1000, 2, 'mm')}")
    else:
        text = ", ".join(f"{k} {pm(v, se.get(k, float('nan')), 1, 4, '')}".rstrip() for k, v in p.items())
    return f"{e} {text} ({c['delta_bic']:.0f})"


def left_cell(r):
    """A structure the final model leaves: stream, kind, size, p."""
    size, unit = r["size"], r["unit"]
    if unit == "rad/s per rad/s":
        text = f"{num(size * 100, 2)} %"
    elif unit.startswith("m/s") and abs(size) < 0.001:
        text = f"{num(size * 1000, 2)} mm{unit[1:]}"
    else:
        text = f"{num(size, 3)} {unit}"
    mantissa, exponent = f"{r['p_value']:.0e}".split("e")
    whose = ", scan matching's" if r.get("source") == "scan_matching" else ""
    return f"{r['stream']}: {r['structure']} {text} ({mantissa}e{int(exponent)}{whose})"


def gain_cell(g):
    before, after = g["heldout_rmse_before"], g["heldout_rmse_after"]
    text = f"{before:.2f} → {after:.2f} ({num(-g['relative'] * 100, 0)} %)"
    t = g.get("trajectory")
    if not t:
        return text + "; no reference"
    return (text + f"; RPE {t['rpe_before']:.3f} → {t['rpe_after']:.3f} m, "
            f"ATE {t['ate_before']:.3f} → {t['ate_after']:.3f} m")


def block_real_diagnosis(runner, csm):
    rows = [
        "| data | verdict | causes (estimate ± stderr, ΔBIC) | left (stream: structure, size, p) "
        "| held-out residual RMSE; reference error |",
        "|---|---|---|---|---|",
    ]
    for _, rel, _, _, _ in DIAGNOSED:
        runner.data_file(rel)
    futures = [runner.pool.submit(diagnose, runner, k, rel, robot, cfg)
               for k, (_, rel, robot, cfg, _) in enumerate(DIAGNOSED)]
    for (label, _, _, _, results), fut in zip(DIAGNOSED, futures):
        d = fut.result()
        authors = None
        if results:
            with open(os.path.join(runner.data, results)) as f:
                authors = json.load(f)
        causes = [cause_cell(c, authors) for c in d["causes"]]
        causes += [f"fault {f['name']} ({f['evidence']})" for f in d["faults"]]
        left = [left_cell(r) for r in d["remaining"]]
        rows.append(f"| {label} | {d['verdict']} | {'; '.join(causes) or '–'} | "
                    f"{'; '.join(left) or '–'} | {gain_cell(d['gain'])} |")
    return rows


def block_blind_suite(runner, csm):
    """The blind diagnosis suite's table, as `odocal experiment diagnose`
    writes it (125 simulated runs through bag, ICP and diagnosis)."""
    out = runner.path("blind-suite")
    runner.run(["experiment", "diagnose", "--runs", "5", "--seed", "200", "--out", out])
    with open(os.path.join(out, "diagnose.md")) as f:
        return [line.rstrip("\n") for line in f if line.startswith("|")]


# The independent laws (tools/rewrite_effects.py): (law, what it is, the check
# of one diagnosis: (right?, what was named)).
LAW_SCENARIOS = [("figure-eight", 301), ("random-walk", 303), ("square", 302),
                 ("corridor-loop", 304)]


def _named(d):
    """Every named cause and fault with its parameters, as a cell."""
    fmt = lambda p: ", ".join(f"{k} {num(v, 4)}" for k, v in sorted(p.items()))
    out = [f"{c['effect']} ({fmt(c['parameters'])})" for c in d["causes"]]
    out += [f"fault {f['name']} ({fmt(f.get('parameters') or {})})" for f in d["faults"]]
    return "; ".join(out) or "–"


def _table_effect(effect, key, truth):
    """Right when `effect` is named with `key` within 20 % of `truth` and no
    other table effect is named."""
    def check(d):
        names = [c["effect"] for c in d["causes"]]
        hit = [c for c in d["causes"] if c["effect"] == effect]
        ok = (names == [effect] and hit and
              abs(hit[0]["parameters"].get(key, float("nan")) - truth) <= 0.2 * abs(truth))
        return bool(ok)
    return check


def _radii(right, left, kappa=None):
    """Right when `radius_scale` is named alone among the table effects with
    both wheels within 20 % of (`right`, `left`), and the only fault named,
    if any, is `tyre_load_transfer` with its `kappa` within 20 % of `kappa`
    (none at all when `kappa` is None: no load moves)."""
    def check(d):
        names = [c["effect"] for c in d["causes"]]
        if names != ["radius_scale"]:
            return False
        p = d["causes"][0]["parameters"]
        radii = all(abs(p.get(k, float("nan")) - t) <= 0.2 * abs(t)
                    for k, t in (("right", right), ("left", left)))
        faults = d["faults"]
        if kappa is None or not faults:
            return radii and not faults
        return (radii and len(faults) == 1 and faults[0]["name"] == "tyre_load_transfer"
                and abs(faults[0]["parameters"]["kappa"] - kappa) <= 0.2 * kappa)
    return check


# Tyres that follow their load, in the simulator (`tyre_load`, not a law of
# the effect table): 100 kg on the chair's 0.65 m axle, the centre of mass
# 6.5 cm left of the middle and 0.5 m high, 50 kN/m tyres. Standing, the
# right wheel carries 100 g (0.5 − 0.065/0.65) N and the left 100 g (0.5 +
# 0.1) N, so the radii of 0.32 m shrink by 7.85 and 11.77 mm: relative
# −0.0245 and −0.0368 (what radius_scale should read; the turns move a
# further 0.05 % per (m/s)(rad/s) onto the outer wheel).
TYRE = "tyre_load:mass=100,com_y=0.065,height=0.5,stiffness=50000"
# The control: the same tyres with the centre of mass on the ground, so no
# load moves in turns and the standing radii are the whole departure.
TYRE_FLAT = "tyre_load:mass=100,com_y=0.065,height=0,stiffness=50000"
TYRE_RADII = tuple(-100 * 9.80665 * (0.5 + s * 0.065 / 0.65) / 50000 / 0.32 for s in (-1, 1))
# The turn's share: each radius changes by ∓κ v ω of the nominal, κ = m h /
# (D k r) in s²/m (relative radius per m/s² of lateral acceleration).
TYRE_KAPPA = 100 * 0.5 / (0.65 * 50000 * 0.32)


def _out_of_table(fault=None, key=None, truth=None):
    """Right when no table effect is named and, for a fault of the catalogue,
    that fault is named with `key` within 20 % of `truth`; for a departure
    the catalogue does not hold, when no fault is named either."""
    def check(d):
        if d["causes"]:
            return False
        if fault is None:
            return not d["faults"]
        hit = [f for f in d["faults"] if f["name"] == fault]
        return bool(hit) and abs(hit[0]["parameters"].get(key, float("nan")) - truth) <= 0.2 * truth
    return check


LAWS = [
    ("none", "nothing (the clean bag)", lambda d: not d["causes"] and not d["faults"]),
    ("radius:right_wheel=0.012", "table: `radius_scale` right 0.012",
     _table_effect("radius_scale", "right", 0.012)),
    ("latency:0.05", "table: `latency` 0.05 s", _table_effect("latency", "delay", 0.05)),
    ("mounting:0,0,0.02", "table: `laser_offset` yaw 0.02 rad",
     _table_effect("laser_offset", "yaw", 0.02)),
    ("mounting:0.05,0,0", "table: `laser_offset` x 0.05 m (forward, not turned)",
     _table_effect("laser_offset", "x", 0.05)),
    ("mounting:0,0.05,0", "table: `laser_offset` y 0.05 m (sideways, not turned)",
     _table_effect("laser_offset", "y", 0.05)),
    ("out_of_round:right_wheel=0.03", "fault: `wheel_out_of_round` right 0.03",
     _out_of_table("wheel_out_of_round", "right", 0.03)),
    ("gyro_scale:0.02", "fault: `gyro_scale` +0.02 (the gyro against the scan matching)",
     _out_of_table("gyro_scale", "scale", 0.02)),
    ("backlash:right_wheel=0.02", "out of the table: 0.02 rad backlash, right", _out_of_table()),
    ("quantise:512", "out of the table: 512 ticks per revolution", _out_of_table()),
    (f"simulated {TYRE}", "physics in the simulator: tyres deflecting under an off-centre "
     f"load (static radius_scale right {TYRE_RADII[0]:.4f}, left {TYRE_RADII[1]:.4f}; "
     f"in turns `tyre_load_transfer` kappa {TYRE_KAPPA:.4f} s²/m, if named)",
     _radii(*TYRE_RADII, kappa=TYRE_KAPPA)),
    (f"simulated {TYRE_FLAT}", "the same tyres, the centre of mass on the ground: no load moves "
     "in turns (the control of the row above)", _radii(*TYRE_RADII)),
]


def _law_diagnosis(runner, clean, scenario, law):
    """`odocal diagnose --json` of the scenario's clean bag rewritten by `law`."""
    if law == "none":
        bag = clean
    elif law.startswith("simulated "):
        # Not a rewrite: the simulator drives the same scenario and seed
        # with the physics switched on.
        seed = dict(LAW_SCENARIOS)[scenario]
        spec = law.split(" ", 1)[1]
        height = dict(kv.split("=") for kv in spec.split(":", 1)[1].split(","))["height"]
        bag = runner.path(f"law-{scenario}-tyre-h{height}.mcap")
        runner.run(["simulate", "--scenario", scenario, "--seed", seed, "--duration", "150",
                    "--effect", spec, "--out", bag])
    else:
        name = law.replace(":", "_").replace("=", "_").replace(",", "_")
        bag = runner.path(f"law-{scenario}-{name}.mcap")
        tool = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                            "rewrite_effects.py")
        subprocess.run([sys.executable, tool, clean, bag, law], check=True, capture_output=True)
    return json.loads(runner.run(["diagnose", "--measured", bag, "--json"]))


def _clean(runner, scenario, seed):
    """The scenario's clean 150 s bag."""
    bag = runner.path(f"law-{scenario}-clean.mcap")
    runner.run(["simulate", "--scenario", scenario, "--seed", seed, "--duration", "150",
                "--out", bag])
    return bag


def block_independent_laws(runner, csm):
    """The diagnosis against laws it does not share: each clean 150 s bag
    rewritten by tools/rewrite_effects.py, then diagnosed."""
    cleans = {s: runner.pool.submit(_clean, runner, s, n) for s, n in LAW_SCENARIOS}
    cleans = {s: f.result() for s, f in cleans.items()}
    futures = {(law, s): runner.pool.submit(_law_diagnosis, runner, cleans[s], s, law)
               for law, _, _ in LAWS for s, _ in LAW_SCENARIOS}
    head = "| written | what it is | " + " | ".join(s for s, _ in LAW_SCENARIOS) + " | right |"
    rows = [head, "|" + "---|" * (len(LAW_SCENARIOS) + 3)]
    for law, what, check in LAWS:
        cells, right = [], 0
        for s, _ in LAW_SCENARIOS:
            d = futures[(law, s)].result()
            ok = check(d)
            right += ok
            cells.append(f"{'✓' if ok else '✗'} {d['verdict']}: {_named(d)}")
        rows.append(f"| `{law}` | {what} | " + " | ".join(cells) +
                    f" | {right} of {len(LAW_SCENARIOS)} |")
    return rows


# Slip on part of the floor at sizes near its reporting floor: the blind
# suite's band on each scenario (`slippery_half` in src/experiments/blind/cases.rs),
# one seed per scenario, 90 s.
SLIP_SCENARIOS = [("corridor-loop", 300, 15, 30), ("hall", 301, 15, 30), ("square", 302, 5, 10),
                  ("square-ccw", 303, 5, 10), ("figure-eight", 304, 24, 30),
                  ("random-walk", 305, 10, 20)]
SLIP_SIZES = ["0.02", "0.03", "0.05"]


def _slip_diagnosis(runner, scenario, seed, x0, x1, slip):
    """`odocal diagnose --json` of a 90 s run whose wheels over-read by
    `slip` on the band x0 ≤ x < x1."""
    bag = runner.path(f"slip-{scenario}-{seed}-{slip}.mcap")
    runner.run(["simulate", "--scenario", scenario, "--seed", str(seed), "--duration", "90",
                "--effect", f"floor_slip:x_min={x0},x_max={x1},slip={slip}", "--out", bag])
    return json.loads(runner.run(["diagnose", "--measured", bag, "--json"]))


def block_floor_slip(runner, csm):
    """Floor slips of 2, 3 and 5 % on half the area of every scenario:
    whether `floor_slip` is named, its size ± stderr, the verdict and any
    table effect named beside it."""
    futures = {(s, k): runner.pool.submit(_slip_diagnosis, runner, s, n, x0, x1, k)
               for s, n, x0, x1 in SLIP_SCENARIOS for k in SLIP_SIZES}
    rows = ["| scenario (seed) | " + " | ".join(f"slip {float(k) * 100:g} %" for k in SLIP_SIZES)
            + " |", "|---|" + "---|" * len(SLIP_SIZES)]
    named = {k: 0 for k in SLIP_SIZES}
    for s, n, _, _ in SLIP_SCENARIOS:
        cells = []
        for k in SLIP_SIZES:
            d = futures[(s, k)].result()
            f = next((f for f in d["faults"] if f["name"] == "floor_slip"), None)
            others = ", ".join(c["effect"] for c in d["causes"]) or "–"
            if f:
                named[k] += 1
                p = f["parameters"]
                head = f"✓ {percent(p['slip'], p['slip_stderr'])}"
            else:
                head = "✗ not named"
            cells.append(f"{head}; {d['verdict']}; beside it: {others}")
        rows.append(f"| {s} ({n}) | " + " | ".join(cells) + " |")
    rows.append("| named | " + " | ".join(f"{named[k]} of {len(SLIP_SCENARIOS)}"
                                         for k in SLIP_SIZES) + " |")
    return rows
