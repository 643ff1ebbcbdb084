"""``surrealist generate --case-study``: a tiny search end to end, the suite's export in both key sets, and the
case-study options' bad input (one line, exit 2)."""
import csv
import json

import numpy as np
import pytest
import yaml

from surrealist_gym.cli import main
from surrealist_gym.competition import load_case_study
from surrealist_gym.sim.profiles import load_profile
from surrealist_gym.sim.runner import simulate
from surrealist_gym.suite import Member, Suite
from surrealist_gym.suite_export import export_suite
from surrealist_gym.testcase import Obstacle, load_test
from tests.conftest import CASE_STUDIES


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


def test_tiny_case_study_search_writes_results_and_suite(tmp_path, capsys):
    out = tmp_path / "m1"
    code = main(["generate", "--case-study", str(CASE_STUDIES / "mission1.yaml"), "--budget", "4", "--workers",
                 "1", "--obstacles", "2", "--confirm", "2", "--out", str(out)])
    assert code == 0
    run = json.loads((out / "run.json").read_text())
    assert (run["budget"], run["runs"], run["agent"], run["obstacles"]) == (4, 1, "suite", 2)
    assert run["uav"] == "px4-v1.12-sitl-iris" and run["case_study"].endswith("mission1.yaml")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["distance"] == "competition" and summary["evaluations"] == 4
    assert len(summary["best_obstacles"]) == 2
    with open(out / "suite" / "suite.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    printed = capsys.readouterr().out
    assert f"suite: {len(rows)} distinct failures" in printed
    assert (out / "suite" / "suite.png").is_file()


def test_suite_exports_both_key_sets_ready_for_aerialist(tmp_path):
    """A real failing flight (a box across mission1's track, flown in PyBullet) exported and read back."""
    base = load_case_study(CASE_STUDIES / "mission1.yaml")
    test = base.with_obstacles([Obstacle(10, 3, 20, 4.5, 25, 0, 0)])
    run = simulate(test, runs=1, seed=0, config=load_profile("px4-v1.12-sitl-iris").sim_config())[0]
    member = Member(test, run.competition_distance, run.trajectory.xyz, 1, run.status.value)
    suite, _ = Suite(threshold_m=np.inf).offer(member)  # kept whatever the distance: this tests the export
    paths = export_suite(suite, tmp_path / "suite")
    assert [p.name for p in paths] == ["failure-01.yaml"]
    current = yaml.safe_load(paths[0].read_text())
    legacy = yaml.safe_load((tmp_path / "suite" / "legacy" / "failure-01.yaml").read_text())
    assert {"robot", "simulation", "mission"} <= set(current) and "drone" not in current
    assert {"drone", "simulation", "test"} <= set(legacy) and "robot" not in legacy
    assert current["robot"]["mission_file"] == "case_studies/mission1.plan"
    assert legacy["drone"]["mission_file"] == "case_studies/mission1.plan"
    for path in (paths[0], tmp_path / "suite" / "legacy" / "failure-01.yaml"):
        again = load_test(path)
        assert again.obstacles == test.obstacles and again.mission.items == test.mission.items
        assert again.commands == test.commands
    with open(tmp_path / "suite" / "suite.csv", newline="") as f:
        row = next(csv.DictReader(f))
    assert row["test"] == "failure-01" and float(row["distance_m"]) == pytest.approx(run.competition_distance, abs=1e-3)


@pytest.mark.parametrize("argv, message", [
    (["--case-study", "mission9"], "case study 'mission9': not found in"),
    (["--case-study", "mission1", "--obstacles", "4"], "--obstacles: the competition allows 1 to 3 boxes, got 4"),
    (["--case-study", "mission1", "--confirm", "-1"], "--confirm: expected a whole number >= 0, got -1"),
])
def test_case_study_bad_input_is_one_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.setenv("SURREALIST_CASE_STUDIES", str(CASE_STUDIES))
    out = tmp_path / "never"
    assert main(["generate", *argv, "--out", str(out)]) == 2
    assert message in _one_line(capsys)
    assert not out.exists()


def test_case_study_and_seed_test_exclude_each_other(tmp_path, capsys):
    seed = CASE_STUDIES / "mission1.yaml"
    assert main(["generate", str(seed), "--case-study", str(seed), "--out", str(tmp_path / "x")]) == 2
    assert "--case-study: a case study brings its own mission" in _one_line(capsys)
