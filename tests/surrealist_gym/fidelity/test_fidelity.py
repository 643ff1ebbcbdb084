"""The fidelity harness on the real labelled sets: labels, a few real flights, the report, the CLI and bad input."""
import csv
import json
import math
import shutil

import numpy as np
import pytest

from surrealist_gym.cli import main
from surrealist_gym.fidelity.measure import (
    InvalidLabels,
    airborne_time,
    build_report,
    load_labelled_set,
    measure_fidelity,
    region_stats,
)
from surrealist_gym.outcomes import RunRecord
from tests.conftest import SHARED_DATA

COMPETITION = SHARED_DATA / "competition"
RILAST = COMPETITION / "rilast-mission1" / "tests.csv"
CAMBA = COMPETITION / "camba-collection"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def rilast(shared_data):
    return load_labelled_set(RILAST)


@pytest.fixture
def small_folder(tmp_path, shared_data):
    """Two CAMBA YAMLs (missions 1 and 3) with case_studies/ beside them, and labels with airborne times."""
    folder = tmp_path / "set"
    folder.mkdir()
    shutil.copytree(COMPETITION / "case_studies", tmp_path / "case_studies")
    names = ["12-11-12-44-14-5O9PN", "02-12-16-24-05-5O9PN"]
    for name in names:
        shutil.copy(CAMBA / f"{name}.yaml", folder)
    _write(folder / "labels.csv", ["test", "mission", "px4_min_distance_2d", "airborne_s"],
           [[names[0], "case_studies/mission1.plan", "0.53", "120"], [names[1], "mission3", "1.32", "150.5"]])
    return folder


def _write(path, header, rows):
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)
    return path


# --- labels ------------------------------------------------------------------------------------------------------
def test_rilast_csv_labels(rilast):
    assert len(rilast) == 1350
    results = [label.result for label in rilast.labels]
    assert results.count("timeout") == 174 and results.count("flown") == 1176
    assert all(math.isnan(label.distance) for label in rilast.labels if label.result == "timeout")
    flown = [label.distance for label in rilast.labels if label.result == "flown"]
    assert sum(d < 1.5 for d in flown) == 144 and min(flown) == 0.6489  # 144 soft failures, as the README says
    first = rilast.labels[0]
    assert (first.test_id, first.distance, first.row) == ("random_run0_0", 4.2331, 2)
    test = rilast.tests[0]
    assert test.mission_file.endswith("mission1.plan") and len(test.obstacles) == 3
    assert test.obstacles[0].to_list() == [9.0, 3.0, 24.0, -7.0, 13.0, 0.0, 6.0]
    assert test.params["COM_OBS_AVOID"] == 1
    sub = rilast.subset(limit=5, every=100)
    assert [label.test_id for label in sub.labels] == [rilast.labels[i].test_id for i in range(0, 500, 100)]


def test_camba_folder_labels(shared_data):
    lset = load_labelled_set(CAMBA)
    assert len(lset) == 21 and lset.labels_file.endswith("labels.csv")
    assert all(label.result == "flown" and 0.2 <= label.distance <= 1.44 for label in lset.labels)
    by_id = dict(zip((label.test_id for label in lset.labels), lset.tests))
    assert by_id["02-12-16-24-05-5O9PN"].mission_file.endswith("mission3.plan")
    assert len(by_id["17-11-08-02-29-5O9PN"].obstacles) == 2


def test_airborne_time():
    t = np.arange(6.0)
    assert airborne_time(t, [[0, 0, z] for z in (0.1, 0.5, 2, 2, 0.2, 0.1)]) == 2.0
    assert airborne_time(t, [[0, 0, z] for z in (0.1, 0.5, 2, 2, 2, 2)]) == 4.0  # never landed: to the end
    assert airborne_time(t, [[0, 0, 0.1]] * 6) == 0.0


# --- metrics on hand-made outcomes --------------------------------------------------------------------------------
def test_region_stats_by_hand():
    theirs = np.array([0.5, 1.0, 2.0, 4.0, 8.0])
    ours = np.array([1.0, 3.0, 2.0, 5.0, 1.2])
    stats = region_stats(theirs, ours, (ours < 1.5).astype(float))
    assert stats.tests == 5 and stats.their_failures == 2
    # positives score 1.0 and 3.0; negatives 2.0, 5.0, 1.2: pairs with a smaller positive: 3 + 1 of 6
    assert stats.auc == pytest.approx(4 / 6)
    assert stats.precision == 0.5 and stats.recall == 0.5  # ours < 1.5: 1.0 (hit) and 1.2 (false alarm)
    # "ours <= t": t = 1.0 gives precision 1, recall 0.5; recall 1 needs t = 3.0 at precision 2/4 < 0.6
    assert (stats.best_recall, stats.best_threshold_m) == (0.5, 1.0)
    assert stats.spearman == pytest.approx(0.3)  # rank differences 0, 2, 0, 1, 3: 1 - 6 * 14 / 120
    assert stats.their_failure_rate == 0.4 and stats.our_failure_rate == 0.4
    empty = region_stats(np.array([]), np.array([]), np.array([]))
    assert empty.tests == 0 and math.isnan(empty.spearman) and math.isnan(empty.auc)


def test_build_report_counts_and_mapping(rilast):
    lset = rilast.subset(limit=4)
    assert [label.result for label in lset.labels] == ["flown", "flown", "flown", "flown"]
    lset = type(lset)(lset.source, lset.labels_file, lset.labels[:3] + rilast.labels[5:6],
                      lset.tests[:3] + rilast.tests[5:6])  # random_run0_5 has no result
    def run(index, status, distance, airborne, duration):
        return RunRecord(index, status, distance, duration, airborne=airborne)

    runs = [(run(0, "success", 4.0, 50, 55), run(1, "success", 1.0, 50, 55)),
            (run(0, "stuck", 2.0, 30, 35), run(1, "collision", 0.0, 20, 22)),
            (run(0, "timeout", 3.0, 100, 101), run(1, "error", math.nan, 0, 0)),
            (run(0, "timeout", 3.0, 100, 101), run(1, "success", 2.5, 60, 65))]
    report = build_report(lset, runs, runs=2, close=4.3)
    rows = report.rows
    assert rows[0].distance == 2.5 and rows[0].failure_probability == 0.5
    assert rows[1].distance == 1.0 and rows[1].status == "stuck"  # tie: stuck before collision
    assert rows[2].distances == [] and math.isnan(rows[2].distance)  # timeout and error runs give no distance
    assert report.overall.tests == 2  # test 3 did not fly in ours, test 4 did not in theirs
    assert dict(report.confusion["flown"]) == {"success": 2, "timeout": 1, "stuck": 1, "collision": 1, "error": 1}
    assert dict(report.confusion["timeout"])["timeout"] == 1
    assert report.blocked["their_timeouts"] == 1 and report.blocked["our_blocked_runs"] == 3
    assert report.blocked["recall"] == 0.5 and report.blocked["precision"] == pytest.approx(1 / 3)
    assert dict(report.unseen["statuses"]) == {"stuck": 1, "collision": 1, "error": 1}
    assert report.unseen["share"] == 3 / 8
    assert report.durations is None
    summary = json.loads(report.to_json())
    assert summary["our_statuses"]["success"] == 3 and summary["overall"]["tests"] == 2


# --- real flights ------------------------------------------------------------------------------------------------
def test_a_few_rilast_flights_pool_equals_inline(rilast):
    sub = rilast.subset(limit=3, every=300)
    seen = []
    pooled = measure_fidelity(sub, workers=2, progress=lambda done, total: seen.append((done, total)))
    inline = measure_fidelity(sub, workers=1)
    assert seen[-1] == (3, 3) and len(seen) == 3
    assert [r.label.test_id for r in pooled.rows] == [label.test_id for label in sub.labels]
    assert [r.runs for r in pooled.rows] == [r.runs for r in inline.rows]  # the seeds do not depend on the worker
    for row in pooled.rows:
        (run,) = row.runs
        assert run.status in ("success", "timeout", "stuck", "collision", "error")
        assert 0 < run.airborne <= run.duration
        if run.status not in ("timeout", "error"):
            assert row.distance == run.distance >= 0
    flown = sum(r.label.result == "flown" and not math.isnan(r.distance) for r in pooled.rows)
    assert pooled.overall.tests == flown
    assert pooled.close.tests == sum(r.label.distance < 3 for r in pooled.rows if not math.isnan(r.distance)
                                     and r.label.result == "flown")
    assert math.isnan(pooled.overall.spearman) or -1 <= pooled.overall.spearman <= 1
    assert sum(sum(c.values()) for c in pooled.confusion.values()) == 3


def test_cli_end_to_end_on_rilast(tmp_path, capsys, shared_data):
    out = tmp_path / "out"
    assert main(["fidelity", str(RILAST), "--limit", "3", "--every", "100", "--workers", "1", "--runs", "2",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "3 labelled tests" in text and "2 run(s) each" in text and "2-D competition distance" in text
    assert "Spearman, 2-D competition distance" in text and "tests/s" in text
    with open(out / "fidelity.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["test"] for r in rows] == ["random_run0_0", "random_run0_100", "random_run0_200"]
    assert all(r["runs"] == "2" and float(r["our_failure_probability"]) in (0, 0.5, 1) for r in rows)
    summary = json.loads((out / "fidelity.json").read_text())
    assert summary["tests"] == 3 and summary["runs_per_test"] == 2 and summary["distance"].startswith("2-D")
    assert sum(summary["our_statuses"].values()) == 6
    assert (out / "fidelity.png").read_bytes()[:8] == PNG_MAGIC


def test_cli_folder_with_durations_json(small_folder, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["fidelity", str(small_folder), "--workers", "1", "--json", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["tests"] == 2 and summary["durations"]["tests"] == 2
    assert summary["durations"]["q1_ratio"] <= summary["durations"]["median_ratio"] <= summary["durations"]["q3_ratio"]
    assert summary["overall"]["their_failures"] == summary["overall"]["tests"]
    assert set(summary["files"]) == {"csv", "json", "png"}


# --- bad input ---------------------------------------------------------------------------------------------------
def _bad_csv(tmp_path, header, row):
    (tmp_path / "case_studies").mkdir(exist_ok=True)
    for name in ("mission1.yaml", "mission1.plan", "mission-params.csv", "mission-commands.csv"):
        shutil.copy(COMPETITION / "case_studies" / name, tmp_path / "case_studies")
    (tmp_path / "set").mkdir(exist_ok=True)
    obstacles = json.dumps([{"l": 8, "w": 3, "h": 18, "x": -6, "y": 30, "z": 0, "r": 57}])
    values = {"test_id": "t1", "obstacles": obstacles, "px4_min_distance_2d": "4.4", "px4_result": "flown"}
    values.update(row)
    return _write(tmp_path / "set" / "tests.csv", header, [[values.get(h, "") for h in header], [
        "t0" if h == "test_id" else values.get(h, "") for h in header]])


CSV_HEADER = ["test_id", "obstacles", "px4_min_distance_2d", "px4_result"]


@pytest.mark.parametrize("header, row, message", [
    (CSV_HEADER[:2] + CSV_HEADER[3:], {}, "row 1 (header): missing column 'px4_min_distance_2d'"),
    (CSV_HEADER, {"px4_min_distance_2d": "far"}, "row 2, field 'px4_min_distance_2d': expected a non-negative "
                                                 "number, got 'far'"),
    (CSV_HEADER, {"px4_min_distance_2d": ""}, "row 2, field 'px4_min_distance_2d'"),
    (CSV_HEADER, {"px4_result": "crashed"}, "row 2, field 'px4_result': unknown result 'crashed'"),
    (CSV_HEADER, {"obstacles": "[{\"l\": 8}"}, "row 2, field 'obstacles'"),
    (CSV_HEADER, {"obstacles": "[{\"l\": -8, \"w\": 3, \"h\": 18, \"x\": 0, \"y\": 20}]"}, "row 2, field 'obstacles'"),
    (CSV_HEADER + ["mission"], {"mission": "mission3"}, "row 2, field 'mission': 'mission3' but the base test "
                                                        "flies mission1.plan"),
    (CSV_HEADER + ["n_obstacles"], {"n_obstacles": "2"}, "row 2, field 'n_obstacles': 2 but the test has 1"),
])
def test_bad_tests_csv_exits_2_naming_file_row_field(tmp_path, capsys, shared_data, header, row, message):
    path = _bad_csv(tmp_path, header, row)
    assert main(["fidelity", str(path), "--workers", "1", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}: {message}") and err.count("\n") == 1 and not (tmp_path / "out").exists()


@pytest.mark.parametrize("edit, message", [
    (lambda folder: _write(folder / "labels.csv", ["test", "px4_min_distance_2d"],
                           [["12-11-12-44-14-5O9PN", "0.53"], ["02-12-16-24-05-5O9PN", "1.32"], ["nope", "1"]]),
     "labels.csv: row 4, field 'test': no test YAML nope.yaml in"),
    (lambda folder: _write(folder / "labels.csv", ["test", "px4_min_distance_2d"], [["12-11-12-44-14-5O9PN", "1"]]),
     "02-12-16-24-05-5O9PN.yaml: no label row in"),
    (lambda folder: _write(folder / "labels.csv", ["test", "mission", "px4_min_distance_2d"],
                           [["12-11-12-44-14-5O9PN", "mission1", "0.53"], ["02-12-16-24-05-5O9PN", "mission1", "1"]]),
     "labels.csv: row 3, field 'mission': 'mission1' but 02-12-16-24-05-5O9PN.yaml flies mission3.plan"),
    (lambda folder: _write(folder / "labels.csv", ["test", "px4_min_distance_2d", "airborne_s"],
                           [["12-11-12-44-14-5O9PN", "0.53", "-3"], ["02-12-16-24-05-5O9PN", "1", ""]]),
     "labels.csv: row 2, field 'airborne_s': expected a non-negative number, got '-3'"),
    (lambda folder: _write(folder / "labels.csv", ["name", "px4_min_distance_2d"], [["x", "1"]]),
     "labels.csv: row 1 (header): missing column 'test_id' (or 'test')"),
    (lambda folder: (folder / "labels.csv").unlink(), "labels.csv: labels file not found"),
])
def test_bad_folder_labels_exit_2(small_folder, tmp_path, capsys, edit, message):
    edit(small_folder)
    assert main(["fidelity", str(small_folder), "--workers", "1", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


@pytest.mark.parametrize("args, message", [
    (["--mission", "missing.yaml"], "error: missing.yaml: base test YAML (mission and parameters) of "),
    (["--uav", "no-such-uav"],
     "error: --uav 'no-such-uav': not a preset (px4-v1.12-sitl-iris, px4-vision-case0, px4-vision-sitl)"),
    (["--runs", "0"], "error: --runs: expected a whole number >= 1, got 0"),
    (["--labels", "labels.csv"], "error: "),
])
def test_bad_options_exit_2(tmp_path, capsys, shared_data, args, message):
    assert main(["fidelity", str(RILAST), *args, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1


def test_csv_without_case_studies_names_the_default_mission(tmp_path, capsys, shared_data):
    path = _write(tmp_path / "tests.csv", CSV_HEADER, [["t1", "[]", "1.0", "flown"]])
    with pytest.raises(InvalidLabels, match=r"case_studies/mission1.yaml: base test YAML .* give one with --mission"):
        load_labelled_set(path)
    assert main(["fidelity", str(path), "--mission", str(COMPETITION / "case_studies" / "mission1.yaml"),
                 "--workers", "1", "--out", str(tmp_path / "out")]) == 0  # no obstacles: distance inf, no pairs


def test_cli_killed_mid_run_resumes_to_the_same_report(tmp_path, capsys, shared_data):
    """kill -9 of ``surrealist fidelity`` while it flies: the runs stored are kept, the killed run's lock does not
    stand in the way, and the same command flies the rest and reports as an uninterrupted run."""
    from surrealist_gym.results import ResultsFolder
    from tests.conftest import killed_and_resumed

    def argv(out):
        return ["fidelity", str(RILAST), "--limit", "6", "--every", "50", "--workers", "1", "--runs", "1",
                "--out", str(out)]

    def rows(out):  # fidelity.csv, and the summary's figures but its wall time
        with open(out / "fidelity.csv", newline="") as f:
            table = list(csv.DictReader(f))
        summary = json.loads((out / "fidelity.json").read_text())
        return table, {k: v for k, v in summary.items() if "wall" not in k and "per_s" not in k}

    full = tmp_path / "full"
    assert main(argv(full)) == 0
    out = tmp_path / "killed"
    stored = ResultsFolder(out, "fidelity").stored
    killed_and_resumed(argv(out), out, stored, at_least=2)
    kept = stored()
    assert 2 <= kept < 6 and not (out / "fidelity.json").exists()
    assert main(argv(out)) == 0
    assert stored() == 6 and rows(out) == rows(full)
    capsys.readouterr()
    assert main([*argv(out)[:-2], "--runs", "2", "--out", str(out)]) == 2  # other settings: refused, named
    assert "(runs: 1 there, 2 here)" in capsys.readouterr().err
