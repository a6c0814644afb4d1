"""A small simulated fleet (7 robots × 8 days × 60 s, histories hidden in a
truth file): generated and judged by ``odocal experiment fleet``, then run
through the package locally and on a local Ray started here. Both engines
must give the command line's table and alarms, and the alarms must be
exactly the hidden events."""

import json
import shutil
from pathlib import Path

import pytest

import odocal
from conftest import cli, need


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    d = tmp_path_factory.mktemp("fleet")
    settings = d / "settings.toml"
    settings.write_text("[fleet]\ndays = 8\nduration_s = 60.0\n")
    p = cli("experiment", "fleet", "--runs", "7", "--seed", "4", "--settings", settings,
            "--out", d, ok=False)
    assert p.returncode == 0, p.stderr
    return d


def alarms(summary):
    return [(a["robot"], a["kind"], a["day"]) for a in summary["alarms"]]


def test_the_alarms_are_exactly_the_hidden_events(fleet):
    result = json.loads((fleet / "fleet.json").read_text())
    assert result["correct"] == result["robots"] == 7, json.dumps(result["verdicts"], indent=1)
    truth = json.loads((fleet / "fleet-truth.json").read_text())
    assert {t["history"] for t in truth} == {"wear", "step", "swap", "short", "knocked", "nothing"}
    assert not any(Path(fleet / "fleet-data").rglob("*truth*"))


def test_local_and_ray_engines_give_the_command_lines_table(fleet, tmp_path):
    manifest = fleet / "fleet-data" / "manifest.csv"
    reference = (fleet / "fleet-run" / "fleet.csv").read_text()
    cli_run = json.loads((fleet / "fleet-run" / "fleet.json").read_text())

    local = odocal.fleet.run(manifest, tmp_path / "local", engine="local")
    assert (tmp_path / "local" / "fleet.csv").read_text() == reference
    assert alarms(local) == alarms(cli_run)

    ray = need("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray = odocal.fleet.run(manifest, tmp_path / "ray", engine="ray")
    finally:
        ray.shutdown()
    assert on_ray["processed"] == on_ray["recordings"] == 56
    assert (tmp_path / "ray" / "fleet.csv").read_text() == reference
    assert alarms(on_ray) == alarms(cli_run)
    assert on_ray["robots"] == local["robots"]


def test_a_rerun_takes_every_result_from_the_cache(fleet, tmp_path):
    manifest = fleet / "fleet-data" / "manifest.csv"
    out = tmp_path / "again"
    shutil.copytree(fleet / "fleet-run", out)
    first = json.loads((out / "fleet.json").read_text())
    again = odocal.fleet.run(manifest, out)
    assert (again["processed"], again["cached"]) == (0, 56)
    assert again["table"] == first["table"]
    assert (out / "fleet.csv").read_text() == (fleet / "fleet-run" / "fleet.csv").read_text()


def test_a_bad_manifest_raises_the_command_lines_message(tmp_path):
    bad = tmp_path / "manifest.csv"
    bad.write_text("robot,path,start\nchair-01,nowhere.mcap,2026-01-05\n")
    p = cli("fleet", bad, "--out", tmp_path / "o", ok=False)
    assert p.returncode == 2
    with pytest.raises(odocal.InputError) as e:
        odocal.fleet.run(bad, tmp_path / "p")
    assert str(e.value) in p.stderr and "line 2" in str(e.value)


def test_the_scoring_tool_counts_every_event_and_its_days_to_alarm(fleet, tmp_path):
    """``tools/fleet_scores.py`` on this fleet: every event raised, every
    alarm an event, and the days a daily run takes (a swap and a short
    recording on their day, a knocked laser and a step one day later, wear
    once four calibrations exist); with one alarm taken away, that event is
    counted as missed (a negative control of the scoring itself)."""
    import importlib.util
    import subprocess
    import sys
    from conftest import ROOT, odocal_bin

    tool = ROOT / "tools" / "fleet_scores.py"
    scores = tmp_path / "scores.json"
    p = subprocess.run([sys.executable, str(tool), str(fleet), "--odocal", odocal_bin(),
                        "--json", str(scores)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    figures = json.loads(scores.read_text())
    totals = figures["totals"]
    assert (totals["events"], totals["raised"], totals["alarms"], totals["true"]) == (5, 5, 5, 5)
    delays = {row[0]: sorted(row[6]) for row in figures["rows"]}
    assert delays["fault"] == [0, 1] and delays["insufficient"] == [0], delays
    assert delays["step"] == [1], delays
    assert len(delays["wear"]) == 1 and 3 <= delays["wear"][0] <= 7, delays

    spec = importlib.util.spec_from_file_location("fleet_scores", tool)
    scoring = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scoring)
    truth = json.loads((fleet / "fleet-truth.json").read_text())
    run = json.loads((fleet / "fleet-run" / "fleet.json").read_text())["alarms"]
    knocked = next(t["robot"] for t in truth if t["history"] == "knocked")
    kept = [a for a in run if a["robot"] != knocked]
    _, missed = scoring.score(truth, kept, {0: kept})
    assert (missed["events"], missed["raised"], missed["alarms"], missed["true"]) == (5, 4, 4, 4)
