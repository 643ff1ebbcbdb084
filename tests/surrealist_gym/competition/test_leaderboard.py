"""``surrealist leaderboard``: the competition's reference generator (third_party, unedited) run through compete on a
case study with wind, scored as the 2026 edition did (with and without the wind), on local workers and on a real Dask
LocalCluster (the same leaderboard.csv), resumed without running a cell again; the 2024 comparison with PX4's Table 1;
one-line errors before any work."""
from __future__ import annotations

import csv
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

from surrealist_gym.cli import main
from surrealist_gym.competition.compete.locate import AERIALIST_ENV
from surrealist_gym.competition.leaderboard import BoardRow, name_tools
from surrealist_gym.competition.published import PUBLISHED, published_name, rerun_share
from surrealist_gym.errors import ALLOW_OUTSIDE_ENV

ROOT = Path(__file__).resolve().parents[3]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
CASE_STUDIES = ROOT.parent / "shared" / "data" / "competition" / "case_studies"
AERIALIST_PATH = os.pathsep.join(str(THIRD_PARTY / p) for p in ("aerialist-master", "aerialist-0.2.1"))

if not THIRD_PARTY.is_dir():
    pytest.skip(f"needs the competition's tools and Aerialist in {THIRD_PARTY}", allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav4"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete]' (Aerialist's imports)")

WIND = {"velocity_mean": 4.0, "velocity_max": 6.0, "direction": [0, 1, 0], "velocity_variance": 0.5,
        "gust_start": 20.0, "gust_duration": 10.0, "gust_velocity_mean": 3.0, "gust_velocity_max": 5.0,
        "gust_direction": [1, 0, 0]}


#: A small competition tool: boxes drawn with Python's random, unseeded (compete seeds it), within the rules and
#: near mission1's path, each flown once by Aerialist master's DockerAgent and written as the snippet writes tests.
TOOL = '''\
import os, random, shutil, sys
from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.docker_agent import DockerAgent
from aerialist.px4.obstacle import Obstacle

out = "generated_tests/boxes"
os.makedirs(out, exist_ok=True)
for i in range(int(sys.argv[3])):
    test = AerialistTest.from_yaml(sys.argv[2])
    size = Obstacle.Size(random.uniform(4, 12), random.uniform(2, 5), 20)
    test.simulation.obstacles = [Obstacle(size, Obstacle.Position(random.uniform(-5, 10), random.uniform(12, 25), 0,
                                                                  random.uniform(0, 90)))]
    results = DockerAgent(test).run()
    test.to_yaml(f"{out}/test_{i}.yaml")
    shutil.copy2(results[0].log_file, f"{out}/test_{i}.ulg")
print(f"output folder: {out}")
'''


@pytest.fixture(scope="module")
def boxes(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("tools") / "boxes"
    folder.mkdir()
    (folder / "cli.py").write_text(TOOL)
    return folder


@pytest.fixture(scope="module", autouse=True)
def _shared_case_studies_allowed():
    """The windy case study names the shared case studies' files by absolute path: every command of this module may
    read them (--allow-outside, as the environment variable its workers inherit)."""
    old = os.environ.get(ALLOW_OUTSIDE_ENV)
    os.environ[ALLOW_OUTSIDE_ENV] = str(CASE_STUDIES)
    yield
    if old is None:
        del os.environ[ALLOW_OUTSIDE_ENV]
    else:
        os.environ[ALLOW_OUTSIDE_ENV] = old


@pytest.fixture(scope="module")
def windy(tmp_path_factory) -> Path:
    """mission1 with a 2026 wind (every key of Aerialist's wind.py that sets speeds, directions and a gust), its files
    named by absolute paths so the tool's folder need not hold them."""
    import yaml

    doc = yaml.safe_load((CASE_STUDIES / "mission1.yaml").read_text())
    for section, key in (("drone", "params_file"), ("drone", "mission_file"), ("test", "commands_file")):
        doc[section][key] = str(CASE_STUDIES / Path(doc[section][key]).name)
    doc["simulation"]["wind"] = WIND
    path = tmp_path_factory.mktemp("case") / "mission1-wind.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.fixture(scope="module")
def aerialist():
    old = os.environ.get(AERIALIST_ENV)
    os.environ[AERIALIST_ENV] = AERIALIST_PATH
    yield
    if old is None:
        del os.environ[AERIALIST_ENV]
    else:
        os.environ[AERIALIST_ENV] = old


def _board(out: Path, tool: Path, windy: Path, *extra: str) -> int:
    return main(["leaderboard", str(tool), "--case-study", str(windy), "--edition", "2026", "--budget", "3",
                 "--repetitions", "1", "--runs", "2", "--random-seed", "5", "--out", str(out), *extra])


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def local_board(tmp_path_factory, boxes, windy, aerialist) -> Path:
    out = tmp_path_factory.mktemp("board") / "local"
    assert _board(out, boxes, windy, "--workers", "2") == 0
    return out


def test_a_board_runs_each_cell_through_compete_and_scores_with_and_without_wind(local_board):
    rows = _rows(local_board / "leaderboard.csv")
    assert '"uav": "px4-v1.12-sitl-iris"' in (local_board / "uav.json").read_text()
    assert [(r["tool"], r["case_study"], r["wind"]) for r in rows] == [
        ("boxes", "mission1-wind", "with"), ("boxes", "mission1-wind", "without")]
    assert list(rows[0])[:10] == ["tool", "case_study", "repetition", "wind", "reported_tests", "evaluated_tests",
                                  "failing_tests", "suite_score", "rank", "simulations"]
    for row in rows:
        assert row["reported_tests"] == row["evaluated_tests"] == "3" and row["simulations"] == "3"
        assert row["rank"] == "1" and float(row["suite_score"]) >= 0
    summary = local_board / "cells" / "boxes" / "mission1-wind-rep0" / "summary.json"
    assert summary.is_file()
    scores = local_board / "scores" / "boxes"
    with_wind = scores / "mission1-wind-rep0-with-wind" / "evaluations.sqlite"
    without = scores / "mission1-wind-rep0-without-wind" / "evaluations.sqlite"
    from surrealist_gym.store import EvaluationStore

    def distances(path):
        db = EvaluationStore(path, readonly=True)
        try:
            return sorted(r["distance"] for row in db for r in row.runs)
        finally:
            db.close()

    blown, calm = distances(with_wind), distances(without)
    assert len(blown) == len(calm) == 6  # 3 tests x 2 runs each
    assert blown != calm  # the wind moved the flights
    report = (local_board / "report.md").read_text()
    assert "with wind" not in report or "without" in report
    assert (local_board / "leaderboard.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_2026_cell_is_its_test_scores_times_the_similarity_penalty_by_hand(local_board):
    """2026: each test's score from the average points of its runs, its boxes and its average time; the sum times
    sim_pen = 1 - similar / evaluated, two tests similar when their runs' averaged flights are under 0.4 m apart along
    DTW's path."""
    from surrealist_gym.aerialist import load_test
    from surrealist_gym.competition.suite import trajectory_distance
    from surrealist_gym.fitness import average_runs
    from surrealist_gym.outcomes import run_points
    from surrealist_gym.store import EvaluationStore

    rows = {r["wind"]: r for r in _rows(local_board / "leaderboard.csv")}
    for wind in ("with", "without"):
        path = local_board / "scores" / "boxes" / f"mission1-wind-rep0-{wind}-wind" / "evaluations.sqlite"
        tests: dict[int, tuple[str, list, list]] = {}  # the runs are stored in chunks: gathered per test
        with EvaluationStore(path, readonly=True) as db:
            for e in db:
                file, runs, flights = tests.setdefault(e.info["test"], (e.test["file"], [], []))
                runs += e.runs
                flights += [np.asarray(t) for t in e.info["trajectories"]]
        assert sorted(tests) == [0, 1, 2] and all(len(runs) == 2 for _, runs, _ in tests.values())  # --runs 2
        total, averages = 0.0, []
        for k in sorted(tests):
            file, runs, flights = tests[k]
            points = [run_points(r["status"], r["distance"]) for r in runs]
            minutes = sum(r["duration"] for r in runs) / len(runs) / 60.0
            boxes = len(load_test(file).obstacles)
            total += (sum(points) / len(points)) * 10.0 / (boxes ** 2 * minutes)
            averages.append(average_runs(flights))
        similar = [None] * len(averages)
        for i in range(len(averages)):
            similar[i] = next((j for j in range(i) if similar[j] is None
                               and trajectory_distance(averages[j], averages[i]) < 0.4), None)
        sim_pen = 1.0 - sum(s is not None for s in similar) / len(similar)
        assert float(rows[wind]["suite_score"]) == pytest.approx(total * sim_pen, rel=1e-5, abs=1e-6)


def test_a_board_resumes_without_running_a_cell_again(local_board, boxes, windy, aerialist):
    log = local_board / "cells" / "boxes" / "mission1-wind-rep0.log"
    before = (log.stat().st_mtime_ns, (local_board / "leaderboard.csv").read_bytes())
    assert _board(local_board, boxes, windy, "--workers", "1") == 0
    assert log.stat().st_mtime_ns == before[0]
    assert (local_board / "leaderboard.csv").read_bytes() == before[1]
    assert not list((local_board / "cells").rglob("*.interrupted-*"))


def test_a_board_killed_mid_cell_resumes_it_to_the_same_board(local_board, boxes, windy, aerialist, tmp_path):
    """kill -9 of the leaderboard while its cell's compete flies: the cell (compete and its tool) ends with it, the
    flights it stored are kept, and the same command resumes the cell and gives the board of an uninterrupted run."""
    from surrealist_gym.results import count_rows
    from tests.conftest import alive, killed_and_resumed, until

    out = tmp_path / "killed"
    cell = out / "cells" / "boxes" / "mission1-wind-rep0"
    argv = ["leaderboard", boxes, "--case-study", windy, "--edition", "2026", "--budget", "3", "--repetitions", "1",
            "--runs", "2", "--random-seed", "5", "--workers", "1", "--out", out]
    killed_and_resumed(argv, out, lambda: count_rows(cell / "flights.sqlite", "flights"))
    assert not (cell / "summary.json").exists()

    def cell_processes() -> list[int]:  # the cell's compete and the processes of its tool
        found = []
        for entry in Path("/proc").iterdir():
            try:
                if entry.name.isdigit() and str(cell).encode() in (entry / "cmdline").read_bytes() + \
                        os.readlink(entry / "cwd").encode():
                    found.append(int(entry.name))
            except OSError:
                continue
        return found

    until(lambda: not any(alive(p) for p in cell_processes()), "the cell to end with the leaderboard")
    assert _board(out, boxes, windy, "--workers", "1") == 0
    assert _rows(out / "leaderboard.csv") == _rows(local_board / "leaderboard.csv")
    assert not list((out / "cells").rglob("*.interrupted-*"))


def test_a_dask_cluster_gives_the_same_board_as_local_workers(local_board, boxes, windy, aerialist, tmp_path):
    distributed = pytest.importorskip("distributed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster:
            assert _board(tmp_path / "dask", boxes, windy, "--dask-scheduler", cluster.scheduler_address) == 0
    assert (tmp_path / "dask" / "leaderboard.csv").read_bytes() == (local_board / "leaderboard.csv").read_bytes()


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize("argv, expected", [
    (["--edition", "2023"], "--edition"),
    (["--edition", "2025", "--case-study", "mission9"], "mission9"),
    (["--edition", "2025", "--repetitions", "0"], "--repetitions: expected a whole number >= 1"),
    (["--edition", "2025", "--budget", "-1"], "--budget: expected a whole number >= 1"),
    (["--edition", "2026", "--tests", "0"], "--tests: expected a whole number >= 1"),
    (["--edition", "2026", "--similar-m", "-0.5"], "--similar-m: expected metres >= 0"),
    (["--edition", "2025", "--similar-m", "0.5"], "--similar-m: the 2025 edition judged tests alike by the ground"),
])
def test_bad_input_is_one_line_before_any_work(argv, expected, capsys, tmp_path, aerialist):
    out = tmp_path / "out"
    args = ["leaderboard", str(SNIPPETS), "--out", str(out), *argv]
    if "--case-study" not in argv:
        args += ["--case-study", "mission1"]
    assert main(args) == 2
    assert expected in _one_line(capsys)
    assert not out.exists()


def test_a_folder_without_cli_py_or_given_twice_is_refused(capsys, tmp_path, aerialist):
    assert main(["leaderboard", str(tmp_path), "--case-study", "mission1", "--edition", "2025", "--out",
                 str(tmp_path / "out")]) == 2
    assert "no cli.py" in _one_line(capsys)
    assert main(["leaderboard", str(SNIPPETS), str(SNIPPETS), "--case-study", "mission1", "--edition", "2025",
                 "--out", str(tmp_path / "out")]) == 2
    assert "given twice" in _one_line(capsys)


def test_a_folder_holding_another_board_is_refused(local_board, boxes, windy, capsys, aerialist):
    assert main(["leaderboard", str(boxes), "--case-study", str(windy), "--edition", "2025", "--budget", "3",
                 "--repetitions", "1", "--out", str(local_board)]) == 2
    assert "other settings (edition: '2026')" in _one_line(capsys)


def test_a_board_grows_into_its_folder_reusing_its_cells(local_board, boxes, windy, aerialist):
    """A second tool joins the board: the first tool's cell is not run again, and both are ranked."""
    log = local_board / "cells" / "boxes" / "mission1-wind-rep0.log"
    before = log.stat().st_mtime_ns
    ambiegen = THIRD_PARTY / "peers" / "ambiegen" / "snippets"
    pytest.importorskip("pymoo", reason="AmbieGen's pymoo: pip install -e '.[compete-tools]'")
    assert main(["leaderboard", str(boxes), str(ambiegen), "--case-study", str(windy), "--edition", "2026",
                 "--budget", "3", "--repetitions", "1", "--runs", "2", "--random-seed", "5", "--workers", "2",
                 "--out", str(local_board)]) == 0
    assert log.stat().st_mtime_ns == before
    rows = _rows(local_board / "leaderboard.csv")
    assert sorted({r["tool"] for r in rows}) == ["ambiegen", "boxes"] and len(rows) == 4
    assert {r["rank"] for r in rows} <= {"1", "2"}


def test_tools_are_named_by_their_folder():
    peers = THIRD_PARTY / "peers"
    names = [t.name for t in name_tools([peers / "camba" / "snippets", peers / "deephyperion-uav" / "DeepHyperion",
                                         SNIPPETS, peers / "palm" / "snippets"])]
    assert names == ["camba", "deephyperion", "uav-testing-competition", "palm"]
    assert [published_name(n) for n in names] == ["CAMBA", "DeepHyperion-UAV", None, "PALM"]
    assert published_name("tgen-uq") == "TGen-UQ" and published_name("ambiegen") == "AmbieGen"


def test_the_published_reruns_are_the_reports():
    # Surrealist 2025: 11 + 3 + 1 of 20 + 9 + 9 re-run tests failed again (the 39% of COMPETITION.md section 5)
    assert rerun_share(PUBLISHED["2025"]["Surrealist"]) == pytest.approx(15 / 38)
    assert sum(c.failing for t in PUBLISHED["2025"].values() for c in t.values()) == 102
    assert sum(c.evaluated for t in PUBLISHED["2025"].values() for c in t.values()) == 244


def test_the_2024_agreement_compares_our_cells_with_table_1():
    from surrealist_gym.competition.reports.leaderboard import Summary, agreement_2024

    def summary(tool, case, score):
        row = BoardRow(tool, case, 0, "", int(score * 3), 20, 5, score, score, float("nan"), 1.0, 1, 200, 0, "")
        return Summary(tool, case, "", [row], "2024")

    ours = [summary("camba", "mission2", 9.0), summary("ambiegen", "mission2", 3.0),
            summary("deephyperion", "mission2", 1.0), summary("camba", "mission3", 2.0),
            summary("ambiegen", "mission3", 5.0), summary("deephyperion", "mission3", 4.0)]
    agree = agreement_2024(ours)
    assert len(agree["cells"]) == 6
    assert agree["studies"]["CS2"] == {"ours": ["CAMBA", "AmbieGen", "DeepHyperion-UAV"],
                                       "report": ["CAMBA", "AmbieGen", "DeepHyperion-UAV"], "same_order": True,
                                       "report_best_first": True}
    assert agree["studies"]["CS3"]["report_best_first"] is False  # CAMBA leads CS3 on PX4, last here
    assert -1 <= agree["spearman"] < 0.6


def test_evaluate_scores_a_compete_folder_as_the_tool_s_output(local_board, tmp_path):
    cell = local_board / "cells" / "boxes" / "mission1-wind-rep0"
    assert main(["evaluate", str(cell), "--competition", "2025", "--runs", "1", "--any-layout", "--workers", "1",
                 "--out", str(tmp_path / "ev")]) == 0
    rows = _rows(tmp_path / "ev" / "leaderboard.csv")
    assert [(r["folder"], r["tests"], r["drawn"]) for r in rows] == [(str(cell), "3", "3")]
    flown = {r["file"] for r in _rows(tmp_path / "ev" / "runs.csv")}
    assert len(flown) == 3 and all("/tool/generated_tests/" in f for f in flown)  # not the flights/ copies


def test_a_compete_folder_is_a_cell_run_before(local_board, tmp_path, aerialist):
    """The local board's compete folder, given as TOOL_DIR, is scored as it is: no tool runs, the same figures."""
    cell = local_board / "cells" / "boxes" / "mission1-wind-rep0"
    assert main(["leaderboard", str(cell), "--edition", "2026", "--budget", "3", "--runs", "2", "--random-seed", "5",
                 "--workers", "1", "--out", str(tmp_path / "again")]) == 0
    assert not (tmp_path / "again" / "cells").exists()
    mine = [{k: v for k, v in r.items() if k != "case_study"} for r in _rows(tmp_path / "again" / "leaderboard.csv")]
    theirs = [{k: v for k, v in r.items() if k != "case_study"} for r in _rows(local_board / "leaderboard.csv")
              if r["tool"] == "boxes"]
    assert mine == [{**r, "rank": "1"} for r in theirs]
    assert main(["leaderboard", str(cell), "--edition", "2026", "--budget", "4", "--out", str(tmp_path / "b")]) == 2


def test_one_writer_per_board(local_board, boxes, windy, capsys, aerialist):
    from surrealist_gym.competition.leaderboard import BOARD_FILE
    from surrealist_gym.results import ResultsFolder

    other = ResultsFolder.claim(local_board, "leaderboard", None, settings_file=BOARD_FILE, stores=())
    try:  # another leaderboard at work in the folder
        assert _board(local_board, boxes, windy, "--workers", "1") == 2
    finally:
        other.release()
    assert f"another process (process {os.getpid()}) is writing to this folder" in _one_line(capsys)


def test_a_case_study_is_the_tool_s_own_from_any_folder(tmp_path, monkeypatch, aerialist):
    """mission1 is the tool's case_studies/mission1.yaml, as compete gives it, wherever the command runs."""
    from surrealist_gym.competition.leaderboard import plan
    from surrealist_gym.competition.rules import CASE_STUDY_ENV

    monkeypatch.delenv(CASE_STUDY_ENV, raising=False)
    monkeypatch.chdir(tmp_path)  # no ../shared/data here: the project's own look-up finds nothing
    board = plan([SNIPPETS], ["mission1"], "2026", out=tmp_path / "board")
    assert board.case_studies == ("mission1",) and board.winds == (None,)
    assert not (tmp_path / "board").exists()
