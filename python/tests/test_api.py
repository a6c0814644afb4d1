"""Each function of the package against the command line on the same file:
the same numbers (timings aside), the same files, the same refusals."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

import odocal
from conftest import cli, need

# Wall-clock figures differ from run to run; everything else must not.
TIMINGS = {"wall_s", "pairs_per_s", "mean_iteration_ms", "match_ms_per_pair", "mean_pair_ms",
           "decode_s", "icp_s"}


def drop_timings(v):
    if isinstance(v, dict):
        return {k: drop_timings(x) for k, x in v.items() if k not in TIMINGS}
    if isinstance(v, list):
        return [drop_timings(x) for x in v]
    return v


def test_simulate_writes_the_same_bag_as_the_command_line(tmp_path, sim):
    bag, _ = sim
    mine = tmp_path / "hall.mcap"
    s = odocal.simulate(mine, scenario="hall", seed=3, duration=40,
                        effects=["radius_scale:right=0.01,left=-0.005"],
                        truth=tmp_path / "hall.json")
    assert mine.read_bytes() == bag.read_bytes()
    assert s["scans"] > 0 and s["effects"] == ["radius_scale:right=0.01,left=-0.005"]


def test_read_gives_every_stream_as_arrays(sim):
    bag, truth = sim
    rec = odocal.read(bag)
    summary = cli("simulate", "--scenario", "hall", "--seed", "3", "--duration", "40",
                  "--effect", "radius_scale:right=0.01,left=-0.005",
                  "--out", bag.parent / "again.mcap", "--json")
    assert rec.scans == summary["scans"]
    assert rec["ranges"].shape[0] == summary["scans"] and rec["ranges"].dtype == np.float32
    assert rec["wheels"].shape == (summary["wheel_samples"], 3)
    assert rec["gyro"].shape == (summary["gyro_samples"], 2)
    assert rec["reference"].shape == (summary["reference_poses"], 4)
    assert np.all(np.diff(rec["scan_stamps"]) > 0)
    # The reference's path length is the simulator's true one (sampled, so
    # slightly shorter).
    ref = rec["reference"]
    length = np.sum(np.hypot(np.diff(ref[:, 1]), np.diff(ref[:, 2])))
    assert abs(length - summary["path_length_m"]) < 0.02 * summary["path_length_m"]
    assert rec["base_from_laser"] is not None


def test_icp_matches_the_command_line(tmp_path, sim):
    bag, _ = sim
    m = odocal.icp(bag, tmp_path / "py")
    c = cli("icp", "--input", bag, "--out", tmp_path / "cli.tum",
            "--motions", tmp_path / "cli.csv", "--json")
    assert drop_timings(dict((k, m[k]) for k in c)) == drop_timings(c)
    assert Path(m["tum"]).read_bytes() == (tmp_path / "cli.tum").read_bytes()
    assert Path(m["motions_csv"]).read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert m.trajectory.shape[1] == 4 and len(m.motions) == c["pairs"]


def test_calibrate_matches_the_command_line(tmp_path, sim):
    bag, _ = sim
    py = odocal.calibrate(bag, tmp_path / "py", method="dkf")
    c = cli("calibrate", "--input", bag, "--method", "dkf", "--out", tmp_path / "cli", "--json")
    assert drop_timings({k: py[k] for k in c}) == drop_timings(c)
    assert (tmp_path / "py" / "calibration.csv").read_bytes() == \
        (tmp_path / "cli" / "calibration.csv").read_bytes()
    h = py.history
    assert len(h) == c["iterations"] and "r_right" in h.dtype.names
    assert h["r_right"][-1] == pytest.approx(c["final"]["r_right"], rel=1e-6)


def test_calibrate_from_motions_matches_the_command_line(tmp_path, sim):
    bag, _ = sim
    m = odocal.icp(bag, tmp_path / "icp")
    rec = odocal.read(bag)
    wheels = tmp_path / "wheels.csv"
    np.savetxt(wheels, rec["wheels"], delimiter=",", header="t,left,right", comments="",
               fmt="%.17g")
    py = odocal.calibrate(m, tmp_path / "py", wheels=wheels, method="dkf")
    c = cli("calibrate", "--motions", m["motions_csv"], "--wheels", wheels, "--method", "dkf",
            "--out", tmp_path / "cli", "--json")
    assert drop_timings({k: py[k] for k in c}) == drop_timings(c)


def test_diagnose_matches_the_command_line(sim):
    bag, _ = sim
    assert drop_timings(odocal.diagnose(bag)) == drop_timings(cli("diagnose", "--measured", bag, "--json"))


def tum_of(rows, path):
    """n × 4 (t, x, y, θ) as a TUM file."""
    with open(path, "w") as f:
        for t, x, y, th in rows.tolist():
            f.write(f"{t!r} {x!r} {y!r} 0 0 0 {math.sin(th / 2)!r} {math.cos(th / 2)!r}\n")


def test_eval_matches_the_command_line_and_evo(tmp_path, sim):
    bag, _ = sim
    m = odocal.icp(bag, tmp_path / "icp")
    ref = tmp_path / "ref.tum"
    tum_of(odocal.read(bag)["reference"], ref)
    for align in ["none", "se3", "origin"]:
        py = odocal.eval(m["tum"], ref, align=align)
        c = cli("eval", "--estimate", m["tum"], "--reference", ref, "--align", align, "--json")
        assert py == c
    need("evo")
    from evo.core import metrics, sync
    from evo.main_ape import ape
    from evo.tools import file_interface
    r = file_interface.read_tum_trajectory_file(str(ref))
    e = file_interface.read_tum_trajectory_file(str(m["tum"]))
    r, e = sync.associate_trajectories(r, e, max_diff=0.01)
    res = ape(r, e, metrics.PoseRelation.translation_part, align=True, correct_scale=False)
    py = odocal.eval(m["tum"], ref, align="se3", t_max_diff=0.01)
    assert py["paired"] == r.num_poses
    for k in ["rmse", "mean", "median", "std", "min", "max"]:
        assert py["ape"][k] == pytest.approx(float(res.stats[k]), rel=1e-9, abs=1e-12)


def stderr_message(p):
    """The command line's message without its ``odocal: `` prefix."""
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("odocal: ")
    return line[len("odocal: "):]


def test_bad_input_raises_with_the_command_lines_message(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAP0\r\nthis is not an mcap")
    want = stderr_message(cli("calibrate", "--input", junk, "--out", tmp_path / "c", ok=False))
    with pytest.raises(odocal.InputError) as e:
        odocal.calibrate(junk, tmp_path / "p")
    assert str(e.value) == want
    assert isinstance(e.value, ValueError)
    missing = tmp_path / "missing.mcap"
    want = stderr_message(cli("icp", "--input", missing, "--out", tmp_path / "t.tum", ok=False))
    with pytest.raises(odocal.InputError) as e:
        odocal.read(missing)
    assert str(missing) in str(e.value)
    with pytest.raises(odocal.InputError) as e:
        odocal.icp(missing, tmp_path / "i")
    assert str(e.value) == want


def test_a_refused_calibration_raises_the_refusal(tmp_path, sim):
    bag, _ = sim
    robot = tmp_path / "swapped.toml"
    text = (Path(__file__).resolve().parents[2] / "scans/robots/wheelchair.toml").read_text()
    text = text.replace('left_joint = "left_wheel"', 'left_joint = "TMP"') \
               .replace('right_joint = "right_wheel"', 'right_joint = "left_wheel"') \
               .replace('left_joint = "TMP"', 'left_joint = "right_wheel"')
    robot.write_text(text)
    want = stderr_message(cli("calibrate", "--input", bag, "--robot", robot,
                              "--out", tmp_path / "c", ok=False))
    with pytest.raises(odocal.InputError) as e:
        odocal.calibrate(bag, tmp_path / "p", robot=robot)
    assert str(e.value) == want and "Swap left_joint and right_joint" in want
