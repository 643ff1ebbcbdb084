"""``surrealist evaluate``: three CAMBA tests x 2 runs end to end (CSVs, report, figures), the statistics of made-up
runs, and every bad input's one line and exit code 2."""
import csv
import math
import shutil

import numpy as np
import pytest

from surrealist_gym.aerialist import load_test, save_test
from surrealist_gym.cli import main
from surrealist_gym.competition.reevaluation import summarise_test
from surrealist_gym.competition.tool_output import load_tests
from surrealist_gym.outcomes import RunRecord
from surrealist_gym.testcase import Obstacle
from tests.conftest import SHARED_DATA

COMPETITION = SHARED_DATA / "competition"
CAMBA = COMPETITION / "camba-collection"
NAMES = ["12-11-12-44-14-5O9PN", "02-12-16-24-05-5O9PN", "26-11-13-35-31-5O9PN"]  # missions 1, 3 and 3
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def folder(tmp_path, shared_data):
    """Three CAMBA YAMLs with case_studies/ beside them (their mission_file is relative)."""
    shutil.copytree(COMPETITION / "case_studies", tmp_path / "case_studies")
    tests = tmp_path / "tests"
    tests.mkdir()
    for name in NAMES:
        shutil.copy(CAMBA / f"{name}.yaml", tests)
    (tests / "notes.txt").write_text("not a test\n")  # ignored: not a YAML
    return tests


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


# --- end to end ----------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_evaluate_three_camba_tests(folder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["evaluate", str(folder), "--runs", "2", "--workers", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "3 tests x 2 runs, seed 0" in printed and "distinct failures:" in printed
    assert all(name in printed for name in NAMES)

    rows = _rows(out / "evaluation.csv")
    assert [r["file"].rsplit("/", 1)[-1] for r in rows] == sorted(f"{n}.yaml" for n in NAMES)
    assert list(rows[0])[:12] == ["file", "runs", "failures", "errors", "p", "ci_low", "ci_high", "points_mean",
                                  "points_median_run", "min_distance", "median_distance", "statuses"]
    runs = _rows(out / "runs.csv")
    assert len(runs) == 6 and {r["run"] for r in runs} == {"0", "1"}
    for row in rows:
        mine = [r for r in runs if r["file"] == row["file"]]
        failures = sum(int(r["failed"]) for r in mine)
        assert int(row["runs"]) == 2 and int(row["failures"]) == failures
        assert float(row["p"]) == failures / 2
        assert 0 <= float(row["ci_low"]) <= float(row["p"]) <= float(row["ci_high"]) <= 1
        assert float(row["points_mean"]) == pytest.approx(np.mean([int(r["points"]) for r in mine]))
        distances = [float(r["distance"]) for r in mine]
        assert float(row["min_distance"]) == pytest.approx(min(distances), abs=1e-4)
        assert float(row["median_distance"]) == pytest.approx(np.median(distances), abs=1e-4)
        for r in mine:  # a run fails when it collides or comes within 1.5 m
            assert int(r["failed"]) == (r["status"] == "collision" or float(r["distance"]) < 1.5)
        assert sum(int(n) for n in (s.split(":")[1] for s in row["statuses"].split())) == 2
        assert row["uav"] == "px4-v1.12-sitl-iris"  # competition tests fly the SITL Iris
        assert (row["suite"] != "") == (failures > 0)

    report = (out / "report.md").read_text()
    assert report.startswith("# Re-evaluation of 3 tests")
    assert "| test | failures | errors | p [95% CI] |" in report and all(name in report for name in NAMES)
    for png in ("distances.png", "top-views.png", "suite-map.png"):
        assert f"]({png})" in report
        assert (out / png).read_bytes()[:8] == PNG_MAGIC


@pytest.mark.slow
def test_same_seed_same_runs_and_uav_option(folder, tmp_path):
    test = folder / f"{NAMES[2]}.yaml"
    for name in ("a", "b"):
        assert main(["evaluate", str(test), "--runs", "2", "--workers", "1", "--random-seed", "3",
                     "--uav", "px4-v1.12-sitl-iris", "--out", str(tmp_path / name)]) == 0
    a, b = (_rows(tmp_path / name / "runs.csv") for name in ("a", "b"))
    assert [r["distance"] for r in a] == [r["distance"] for r in b]


# --- statistics ----------------------------------------------------------------------------------------------------
def _run(index, distance, status="success"):
    return RunRecord(index, status, distance, 100.0, np.zeros((2, 3)))


def test_statistics_of_made_up_runs():
    runs = [_run(0, 0.1), _run(1, 0.8), _run(2, 1.4), _run(3, 2.0), _run(4, math.inf)]
    stats = summarise_test("t.yaml", None, runs)
    assert (stats.failures, stats.p) == (3, 0.6)
    assert (round(stats.ci_low, 4), round(stats.ci_high, 4)) == (0.1466, 0.9473)  # Clopper-Pearson, 3 of 5
    assert stats.points_mean == pytest.approx((5 + 2 + 1) / 5)
    assert stats.points_median_run == 1  # the third closest run: 1.4 m
    assert (stats.min_distance, stats.median_distance) == (0.1, pytest.approx(1.1))
    assert stats.closest_failure.index == 0
    crash = summarise_test("t.yaml", None, [_run(0, 3.0, "collision"), _run(1, 2.0)])
    assert (crash.failures, crash.points_mean, crash.points_median_run) == (1, 2.5, 0)
    assert crash.closest_failure.status == "collision"


def test_error_runs_are_neither_passes_nor_failures():
    # a run in error (its simulation raised, or the vehicle flipped: a distance may be kept) is counted apart
    runs = [_run(0, 0.1), _run(1, 2.0), _run(2, math.inf, "error"), _run(3, 0.2, "error")]
    stats = summarise_test("t.yaml", None, runs)
    assert (stats.failures, stats.errors, stats.flown, stats.p) == (1, 2, 2, 0.5)
    assert (round(stats.ci_low, 4), round(stats.ci_high, 4)) == (0.0126, 0.9874)  # Clopper-Pearson, 1 of 2
    assert (stats.points_mean, stats.points_median_run, stats.min_distance) == (2.5, 0, 0.1)
    assert stats.to_row()["errors"] == 2 and stats.statuses == "success:2 error:2"
    none = summarise_test("t.yaml", None, [_run(0, math.inf, "error"), _run(1, 0.3, "error")])
    assert (none.failures, none.errors, none.flown, none.points_median_run) == (0, 2, 0, None)
    assert all(math.isnan(v) for v in (none.p, none.ci_low, none.ci_high, none.points_mean, none.min_distance))
    assert none.closest_failure is None
    row = none.to_row()
    assert (row["p"], row["ci_low"], row["ci_high"], row["points_median_run"]) == ("", "", "", "")


def test_rotations_beyond_90_degrees_are_the_same_boxes(shared_data):
    # 20 of the 21 CAMBA tests turn a box by more than 90 degrees: each is a box within the rules, turned less
    assert len(load_tests([CAMBA])) == 21


# --- bad input -----------------------------------------------------------------------------------------------------
def test_no_yaml_in_folder(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["evaluate", str(tmp_path / "empty")]) == 2
    assert _one_line(capsys) == f"error: {tmp_path / 'empty'}: no test YAML (*.yaml, *.yml) in this folder"


def test_missing_path(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path / "nope")]) == 2
    assert _one_line(capsys) == f"error: {tmp_path / 'nope'}: no such file or folder"


def test_file_that_is_not_a_test(tmp_path, capsys):
    bad = tmp_path / "labels.yaml"
    bad.write_text("- test: a\n  distance: 1.2\n")
    assert main(["evaluate", str(bad)]) == 2
    assert _one_line(capsys).startswith(f"error: {bad}: expected a mapping with sections")


def test_test_without_mission(tmp_path, capsys):
    bad = tmp_path / "no-mission.yaml"
    bad.write_text("simulation:\n  obstacles: []\n")
    assert main(["evaluate", str(bad)]) == 2
    assert _one_line(capsys) == f"error: {bad}: mission_file: no mission item with a position to fly to"


def test_rule_breaking_test_names_file_and_field(folder, tmp_path, capsys):
    test = load_test(folder / f"{NAMES[0]}.yaml")
    moved = test.with_obstacles([test.obstacles[0], Obstacle(4, 4, 15, 35.0, 20.0)])  # x beyond 30
    bad = folder / "moved.yaml"
    save_test(moved, bad)
    assert main(["evaluate", str(bad)]) == 2
    assert _one_line(capsys) == (f"error: {bad}: obstacles[1].x: 35 is outside the competition's [-40, 30]; "
                                 f"--any-layout skips the competition's rules")
    assert len(load_tests([bad], any_layout=True)) == 1


@pytest.mark.parametrize("option", [["--runs", "0"], ["--workers", "0"]])
def test_bad_counts(option, tmp_path, capsys):
    assert main(["evaluate", str(tmp_path), *option]) == 2
    assert _one_line(capsys) == f"error: {option[0]}: expected a whole number >= 1, got 0"


def test_unknown_uav(folder, capsys):
    assert main(["evaluate", str(folder), "--uav", "nope"]) == 2
    assert _one_line(capsys).startswith("error: --uav 'nope': not a preset")
