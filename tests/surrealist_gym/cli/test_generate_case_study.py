"""``surrealist generate --case-study``: a tiny search end to end, the suite's export (both Aerialist key sets in one
file), and the case-study options' bad input (one line, exit 2)."""
import csv
import json

import numpy as np
import pytest
import yaml

from surrealist_gym.aerialist import load_test
from surrealist_gym.cli import main
from surrealist_gym.competition.rules import load_case_study
from surrealist_gym.competition.suite import Member, Suite
from surrealist_gym.competition.suite_export import export_suite
from surrealist_gym.sim.profiles import load_profile
from surrealist_gym.sim.runner import simulate
from surrealist_gym.testcase import Obstacle
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
    """A real failing flight (a box across mission1's track, flown in PyBullet) exported and read back; Aerialist's
    own loaders read the export in tests/surrealist_gym/test_aerialist.py."""
    base = load_case_study(CASE_STUDIES / "mission1.yaml")
    test = base.with_obstacles([Obstacle(10, 3, 20, 4.5, 25, 0, 0)])
    run = simulate(test, runs=1, seed=0, config=load_profile("px4-v1.12-sitl-iris").sim_config())[0]
    member = Member(test, run.competition_distance, run.trajectory.xyz, 1, run.status.value)
    suite, _ = Suite(threshold_m=np.inf).offer(member)  # kept whatever the distance: this tests the export
    paths = export_suite(suite, tmp_path / "suite")
    assert [p.name for p in paths] == ["failure-01.yaml"]
    doc = yaml.safe_load(paths[0].read_text())
    assert {"robot", "drone", "simulation", "mission", "test"} <= set(doc)  # master's keys and 0.2.x's
    assert doc["robot"] == doc["drone"] and doc["mission"] == doc["test"]
    assert doc["robot"]["mission_file"] == "case_studies/mission1.plan"
    assert doc["simulation"]["obstacles"][0]["shape"] == "box" and doc["simulation"]["obstacles"][0]["size"]["r"] == 0
    assert not (tmp_path / "suite" / "legacy").exists()
    again = load_test(paths[0])
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
    assert main(["generate", "--seed", str(seed), "--case-study", str(seed), "--out", str(tmp_path / "x")]) == 2
    assert "--case-study: a case study brings its own mission" in _one_line(capsys)


# --- the export ranked by expected test score ---------------------------------------------------------------------
def _points(distance: float, status: str) -> int:
    if status == "collision" or distance < 0.25:
        return 5
    return 2 if distance < 1.0 else 1 if distance < 1.5 else 0


def _by_hand(runs, boxes: int) -> float:
    """Expected test score: mean points x 10 / (boxes^2 x mean minutes), from (distance, status, duration [s])."""
    points = [_points(d, s) for d, s, _ in runs]
    minutes = sum(t for _, _, t in runs) / len(runs) / 60
    return sum(points) / len(points) * 10 / (boxes ** 2 * minutes)


@pytest.fixture(scope="module")
def flown_suite():
    """CAMBA's three mission3 tests (short flights) as a suite, each with one real flight as the search's run."""
    from tests.conftest import SHARED_DATA

    camba = SHARED_DATA / "competition" / "camba-collection"
    if not camba.is_dir():
        pytest.skip(f"needs the shared data folder {SHARED_DATA}")
    config = load_profile("px4-v1.12-sitl-iris").sim_config()
    members, runs = [], []
    for i, name in enumerate(["02-12-16-24-05-5O9PN", "04-12-14-10-41-5O9PN", "26-11-13-35-31-5O9PN"]):
        test = load_test(camba / f"{name}.yaml")
        run = simulate(test, runs=1, seed=0, config=config)[0]
        members.append(Member(test, run.competition_distance, run.trajectory.xyz, i + 1, run.status.value))
        runs.append(run)
    return Suite(members=tuple(members)), runs


def _write(out, suite, confirm: int, capsys) -> str:
    from types import SimpleNamespace

    from surrealist_gym.cli.generate import _write_suite

    _write_suite(out, suite, SimpleNamespace(confirm=confirm, random_seed=0, uav="px4-v1.12-sitl-iris", workers=1,
                                             buffer=0.0))
    return capsys.readouterr().out


def _suite_rows(out) -> list[dict]:
    with open(out / "suite" / "suite.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_export_is_ranked_by_the_confirmations_expected_score(tmp_path, flown_suite, capsys):
    suite, _ = flown_suite
    out = tmp_path / "search"
    printed = _write(out, suite, 2, capsys)
    folder = out / "suite"
    with open(folder / "confirmation" / "runs.csv", newline="") as f:
        runs = list(csv.DictReader(f))
    names = [f"failure-{k:02d}" for k in (1, 2, 3)]
    scores = []
    for name in names:
        mine = [(float(r["distance"]), r["status"], float(r["duration_s"])) for r in runs
                if r["file"].endswith(f"/{name}.yaml") and r["status"] != "error"]
        scores.append(_by_hand(mine, len(load_test(folder / f"{name}.yaml").obstacles)))
    assert scores == sorted(scores, reverse=True)  # the best first: 2025 evaluates the first 20 written
    assert [float(r["expected_score"]) for r in _suite_rows(out)] == pytest.approx(scores, abs=1e-3)
    assert [r["test"] for r in _suite_rows(out)] == names

    # the confirmation's runs are those of the files named: the same files re-flown with the same seed agree
    again = tmp_path / "again"
    assert main(["evaluate", str(folder), "--runs", "2", "--random-seed", "1", "--workers", "1",
                 "--out", str(again)]) == 0
    with open(again / "runs.csv", newline="") as f:
        assert [(r["file"].rsplit("/", 1)[-1], r["distance"]) for r in csv.DictReader(f)] == \
            [(r["file"].rsplit("/", 1)[-1], r["distance"]) for r in runs]

    closest = min(suite.members, key=lambda m: (m.status != "collision", m.distance))
    assert f"closest failure: {closest.distance:.2f} m ({closest.status}) in {folder}/failure-" in printed
    from surrealist_gym.competition.scoring import area_diversity

    assert (f"expected 2025 scores of the first 3 (from 2 re-runs each): failure {sum(scores):.2f} "
            in printed)  # CAMBA's three layouts differ: no duplicate
    assert f"diversity {area_diversity([m.test.obstacles for m in suite.members]):.2f} (1 - mean area IoU)" in printed


def test_without_confirmation_the_search_runs_rank_the_export(tmp_path, flown_suite, capsys):
    from surrealist_gym.evaluation import RunSummary
    from surrealist_gym.store import EvaluationStore, StoredEvaluation

    suite, flown = flown_suite
    out = tmp_path / "search"
    out.mkdir()
    with EvaluationStore(out / "evaluations.sqlite") as store:  # as the search stores its evaluations
        for member, run in zip(suite.members, flown):
            store.add(StoredEvaluation(member.test.key(), {}, (0,), (RunSummary.of(run).to_dict(),), None))
    printed = _write(out, suite, 0, capsys)
    expected = [_by_hand([(r.competition_distance, r.status.value, r.duration)], len(m.test.obstacles))
                for m, r in zip(suite.members, flown)]
    order = sorted(range(3), key=lambda i: (-expected[i], i))
    rows = _suite_rows(out)
    assert [float(r["expected_score"]) for r in rows] == pytest.approx([expected[i] for i in order], abs=1e-3)
    assert [int(r["evaluation"]) for r in rows] == [suite.members[i].evaluation for i in order]
    for k, i in enumerate(order):
        assert load_test(out / "suite" / f"failure-{k + 1:02d}.yaml").obstacles == suite.members[i].test.obstacles
    assert "(from the search's own runs): failure" in printed and not (out / "suite" / "confirmation").exists()
