"""``surrealist predict`` on real tests (two CAMBA YAMLs flown once each), its bad input (one line, exit 2, nothing
flown or written), ``--fit``'s refusals, and the pre-screen options of generate and export-tool."""
import csv
import json
import shutil

import pytest

from surrealist_gym.cli import main
from tests.conftest import SHARED_DATA, refused

COMPETITION = SHARED_DATA / "competition"
CAMBA = COMPETITION / "camba-collection"
NAMES = ["12-11-12-44-14-5O9PN", "02-12-16-24-05-5O9PN"]


@pytest.fixture
def two_tests(tmp_path, shared_data, monkeypatch):
    """Two CAMBA YAMLs (missions 1 and 3) in a folder, case_studies/ beside them."""
    folder = tmp_path / "tests"
    folder.mkdir()
    shutil.copytree(COMPETITION / "case_studies", tmp_path / "case_studies")
    for name in NAMES:
        shutil.copy(CAMBA / f"{name}.yaml", folder)
    monkeypatch.chdir(tmp_path)
    return folder


def test_predict_writes_probabilities_for_each_test(two_tests, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["predict", str(two_tests), "--runs", "1", "--workers", "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    with open(out / "predictions.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["test"] for r in rows] == sorted(NAMES)
    for row in rows:
        assert 0.0 <= float(row["p_px4_under_1_5m"]) <= 1.0 and 0.0 <= float(row["p_px4_under_1m"]) <= 1.0
        assert float(row["p_px4_under_1m"]) <= float(row["p_px4_under_1_5m"]) + 0.2
        assert row["runs"] == "1" and float(row["our_distance_m"]) >= 0.0
    assert "P(PX4 < 1.5 m)" in printed and (out / "evaluations.sqlite").is_file() and (out / "uav.json").is_file()
    # the same command resumes from the store: nothing flown again, the same table
    before = (out / "predictions.csv").read_text()
    assert main(["predict", str(two_tests), "--runs", "1", "--workers", "1", "--out", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["predictions"][0]["test"] == sorted(NAMES)[0]
    assert (out / "predictions.csv").read_text() == before


@pytest.mark.parametrize("make, words", [
    (lambda d: d / "missing.yaml", ["missing.yaml", "no such file"]),
    (lambda d: (d / "bad.yaml").write_text("drone: [1, 2\n") and d / "bad.yaml", ["bad.yaml"]),
    (lambda d: (d / "notes.txt").write_text("not a test") and d / "notes.txt", ["notes.txt"]),
    (lambda d: (d / "empty").mkdir() or d / "empty", ["empty", "no test YAML"]),
], ids=["missing", "broken YAML", "not YAML", "empty folder"])
def test_bad_input_is_one_line_before_any_flight(two_tests, tmp_path, capsys, make, words):
    bad = make(tmp_path)
    out = tmp_path / "out"
    refused(capsys, ["predict", str(two_tests), str(bad), "--runs", "1", "--workers", "1", "--out", str(out)],
            *words)
    assert not out.exists()


@pytest.mark.parametrize("argv, words", [
    (["predict"], ["give TESTS"]),
    (["predict", "x.yaml", "--labels", "l.csv"], ["--labels: applies only with --fit"]),
    (["predict", "--fit", "tests.csv"], ["--fit: name the model file", "--model FILE.json"]),
    (["predict", "--fit", "tests.csv", "--model", "m.txt"], ["--model m.txt", ".json"]),
    (["predict", "x.yaml", "--runs", "0"], ["--runs: expected a whole number >= 1"]),
    (["predict", "x.yaml", "--seed", "3"], ["--seed: use --random-seed"]),
    (["predict", "x.yaml", "--model", "none.json"], ["none.json", "cannot read the model"]),
    (["generate", "--px4-verdict"], ["--px4-verdict: applies only with --case-study"]),
])
def test_refusals_are_one_line(tmp_path, capsys, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    refused(capsys, [*argv, "--out", str(tmp_path / "out")], *words)
    assert not (tmp_path / "out").exists()


def test_export_tool_passes_the_pre_screen_to_its_search(tmp_path, capsys):
    tool = tmp_path / "tool"
    assert main(["export-tool", str(tool), "--px4-verdict"]) == 0
    assert json.loads((tool / "surrealist-tool.json").read_text())["px4_verdict"] is True
    assert '"--px4-verdict"' in (tool / "cli.py").read_text()
    assert "ranked by the model of PX4's verdict" in capsys.readouterr().out
    plain = tmp_path / "plain"
    assert main(["export-tool", str(plain)]) == 0
    assert json.loads((plain / "surrealist-tool.json").read_text())["px4_verdict"] is False


def test_generate_px4_verdict_ranks_the_suite_by_the_model(tmp_path, shared_data, capsys):
    """The suite's export with ``--px4-verdict``: two CAMBA mission3 tests as a suite, confirmed once each, ranked by
    P(PX4 < 1.5 m) x expected score (px4-verdict.csv), failure-01 the first."""
    from types import SimpleNamespace

    from surrealist_gym.aerialist import load_test
    from surrealist_gym.cli.generate import _write_suite
    from surrealist_gym.competition.suite import Member, Suite
    from surrealist_gym.sim.profiles import load_profile
    from surrealist_gym.sim.runner import simulate

    config = load_profile("px4-v1.12-sitl-iris").sim_config()
    members = []
    for i, name in enumerate(["02-12-16-24-05-5O9PN", "04-12-14-10-41-5O9PN"]):
        test = load_test(CAMBA / f"{name}.yaml")
        run = simulate(test, runs=1, seed=0, config=config)[0]
        members.append(Member(test, run.competition_distance, run.trajectory.xyz, i + 1, run.status.value))
    out = tmp_path / "search"
    _write_suite(out, Suite(members=tuple(members)), SimpleNamespace(
        confirm=1, random_seed=0, uav="px4-v1.12-sitl-iris", workers=1, buffer=0.0, px4_verdict=True))
    assert "ranked by the model of PX4's verdict" in capsys.readouterr().out
    with open(out / "suite" / "px4-verdict.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    keys = [float(r["p_px4_under_1_5m"]) * float(r["expected_score"]) for r in rows]
    assert keys == sorted(keys, reverse=True) and [r["test"] for r in rows] == ["failure-01.yaml", "failure-02.yaml"]
    with open(out / "suite" / "suite.csv", newline="") as f:
        assert [float(r["expected_score"]) for r in csv.DictReader(f)] == \
            pytest.approx([float(r["expected_score"]) for r in rows], abs=1e-3)


def test_fit_on_a_labelled_folder_writes_the_table_and_a_model_that_predicts(two_tests, tmp_path, capsys):
    """``--fit`` on two labelled CAMBA YAMLs flown once each: the training table, the model file, then predict reads
    it (a toy fit: two tests; the shipped model's refit is test_verdict's)."""
    with open(two_tests / "labels.csv", "w", newline="") as f:
        csv.writer(f).writerows([["test", "px4_min_distance_2d"], [NAMES[0], "0.53"], [NAMES[1], "1.80"]])
    model, out = tmp_path / "m.json", tmp_path / "fit"
    assert main(["predict", "--fit", str(two_tests), "--model", str(model), "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    assert "fitted on" in capsys.readouterr().out
    with open(out / "training.csv", newline="") as f:
        assert sorted(r["test"] for r in csv.DictReader(f)) == sorted(NAMES)
    assert json.loads(model.read_text())["trained_on"]["runs"] == 1
    yaml = two_tests / f"{NAMES[0]}.yaml"
    assert main(["predict", str(yaml), "--model", str(model), "--workers", "1", "--out", str(tmp_path / "p")]) == 0
    with open(tmp_path / "p" / "predictions.csv", newline="") as f:
        assert next(csv.DictReader(f))["runs"] == "1"  # the model's runs by default
