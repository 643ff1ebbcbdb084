"""``surrealist evaluate --competition``: CAMBA's published suite (21 tests, missions 1 and 3, one folder each) scored
as the 2025 and 2024 editions did, checked against a hand computation from runs.csv and the YAMLs; the draw recorded
so that a resume scores the same tests; the leaderboard's files and figure; one-line errors before anything is
flown. Real flights, few runs."""
import csv
import json
import math
import re
import shutil

import pytest
import shapely
import yaml

from surrealist_gym.cli import main
from surrealist_gym.competition import scoring
from tests.conftest import SHARED_DATA

COMPETITION = SHARED_DATA / "competition"
CAMBA = COMPETITION / "camba-collection"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def camba(tmp_path_factory):
    """CAMBA's suite split by case study: mission1/ (18 tests) and mission3/ (3), case_studies/ beside them."""
    if not CAMBA.is_dir():
        pytest.skip(f"needs the shared data folder {SHARED_DATA}")
    root = tmp_path_factory.mktemp("camba")
    shutil.copytree(COMPETITION / "case_studies", root / "case_studies")  # their mission_file is relative
    for yaml_file in sorted(CAMBA.glob("*.yaml")):
        mission = yaml.safe_load(yaml_file.read_text())["drone"]["mission_file"]  # case_studies/missionN.plan
        folder = root / mission.split("/")[-1].split(".")[0]
        folder.mkdir(exist_ok=True)
        shutil.copy(yaml_file, folder)
    assert (len(list((root / "mission1").glob("*.yaml"))), len(list((root / "mission3").glob("*.yaml")))) == (18, 3)
    return root


# --- by hand -------------------------------------------------------------------------------------------------------
def _points(distance: float, status: str) -> int:
    if status == "collision" or distance < 0.25:
        return 5
    return 2 if distance < 1.0 else 1 if distance < 1.5 else 0


def _boxes(file) -> list[dict]:
    return yaml.safe_load(open(file))["simulation"]["obstacles"]


def _footprint(box: dict):
    """The box's ground, corner by corner: (l, w) turned by r about (x, y)."""
    x, y, r = box["position"]["x"], box["position"]["y"], math.radians(box["position"]["r"])
    half = [(box["size"]["l"] / 2 * a, box["size"]["w"] / 2 * b) for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    return shapely.Polygon([(x + math.cos(r) * u - math.sin(r) * v, y + math.sin(r) * u + math.cos(r) * v)
                            for u, v in half])


def _hand_scores(runs_csv, files) -> dict[str, float]:
    """test_score = mean points x 10 / (boxes^2 x mean minutes), from runs.csv's distances and durations."""
    out = {}
    runs = _rows(runs_csv)
    for f in files:
        mine = [r for r in runs if r["file"] == str(f) and r["status"] != "error"]
        points = [_points(float(r["distance"]), r["status"]) for r in mine]
        minutes = sum(float(r["duration_s"]) for r in mine) / len(mine) / 60
        boxes = len(_boxes(f))
        out[str(f)] = (sum(points) / len(points)) * 10 / (boxes ** 2 * minutes)
    return out


def _hand_diversity(files) -> float:
    grounds = [shapely.unary_union([_footprint(b) for b in _boxes(f)]) for f in files]
    pairs = [(a.intersection(b).area / a.union(b).area) for i, a in enumerate(grounds) for b in grounds[i + 1:]]
    return 1 - sum(pairs) / len(pairs)


# --- CAMBA ---------------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_camba_scored_as_2025_matches_a_hand_computation(camba, tmp_path, capsys):
    out = tmp_path / "out"
    folders = [camba / "mission1", camba / "mission3"]
    assert main(["evaluate", *map(str, folders), "--competition", "2025", "--runs", "1", "--workers", "2",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out

    run = json.loads((out / "run.json").read_text())
    assert (run["competition"], run["runs"]) == ("2025", 1)
    # the first 20 in writing order: the natural order of the names (fewer than 20 here: all of them)
    for d, folder in zip(run["draws"], folders):
        names = sorted((p.name for p in folder.glob("*.yaml")),
                       key=lambda n: [int(x) for x in n.split("-")[:5]])  # DD-MM-hh-mm-ss as numbers
        assert [f.rsplit("/", 1)[-1] for f in d["drawn"]] == names and d["tests"] == len(names)

    board = {row["case_study"]: row for row in _rows(out / "leaderboard.csv")}
    scores = {row["file"]: row for row in _rows(out / "test-scores.csv")}
    for folder in folders:
        files = sorted(folder.glob("*.yaml"))
        by_hand = _hand_scores(out / "runs.csv", [f.absolute() for f in files])
        for f, score in by_hand.items():
            assert float(scores[f]["test_score"]) == pytest.approx(score, rel=1e-3, abs=1e-5)
        row = board[folder.name]
        assert float(row["failure"]) == pytest.approx(sum(by_hand.values()), rel=1e-3)  # no duplicates in CAMBA
        assert int(row["failing"]) == sum(s > 0 for s in by_hand.values())
        assert float(row["diversity"]) == pytest.approx(_hand_diversity(files), abs=1e-6)
        assert (row["r_f"], row["r_d"], row["rank"], row["tests"], row["drawn"]) == ("1", "1", "1", str(len(files)),
                                                                                      str(len(files)))
        assert f"{folder.name}: {folder.name}: {len(files)} of {len(files)} tests drawn" in printed
        assert f"failure {float(row['failure']):.2f}, diversity {float(row['diversity']):.2f}" in printed
        assert f"{folder.name}: {len(files)} tests, fewer than the 20 the 2025 edition evaluates" in printed
    report = (out / "report.md").read_text()
    assert "## Competition scoring" in report and "| mission1 | mission1 | 18 | 18 |" in report
    assert (out / "leaderboard.png").read_bytes()[:8] == PNG_MAGIC


@pytest.mark.slow
def test_camba_mission3_scored_as_2024_matches_a_hand_computation(camba, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["evaluate", str(camba / "mission3"), "--competition", "2024", "--runs", "2", "--workers", "2",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    files = [f.absolute() for f in sorted((camba / "mission3").glob("*.yaml"))]
    by_hand = _hand_scores(out / "runs.csv", files)
    row = _rows(out / "leaderboard.csv")[0]
    scores = _rows(out / "test-scores.csv")
    alike = sum(r["same_as"] != "" for r in scores)
    assert int(row["alike"]) == alike and float(row["sim_pen"]) == pytest.approx(1 - alike / 3)
    assert float(row["rest"]) == 0.0  # 3 tests: none beyond the 20
    assert float(row["failure"]) == pytest.approx(sum(by_hand.values()), rel=1e-3)
    assert float(row["score"]) == pytest.approx(sum(by_hand.values()) * (1 - alike / 3), rel=1e-3)
    assert f"score {float(row['score']):.2f} = ({float(row['failure']):.2f} + rest 0.00)" in printed
    assert len(_rows(out / "runs.csv")) == 6  # --runs 2 overrides the edition's 5


@pytest.mark.slow
def test_2024_flies_a_box_narrower_than_2_m_where_2025_and_2026_refuse_it(camba, tmp_path, capsys):
    """2024 bounded the count, the ground, overlaps and the area, not a box's size: a 1 m wide box is flown and scored.
    2025 draws it and scores it 0 unflown; 2026 evaluates the first valid tests in rank order, so it is not drawn."""
    folder = tmp_path / "tool"
    folder.mkdir()
    names = sorted(p.name for p in (camba / "mission3").glob("*.yaml"))[:2]
    narrow = yaml.safe_load((camba / "mission3" / names[0]).read_text())
    narrow["simulation"]["obstacles"][0]["size"]["w"] = 1.0
    (folder / "test_0.yaml").write_text(yaml.safe_dump(narrow))
    shutil.copy(camba / "mission3" / names[1], folder / "test_1.yaml")
    shutil.copytree(camba / "case_studies", tmp_path / "case_studies")
    for year, drawn, flown, invalid in (("2024", 2, 2, ""), ("2025", 2, 1, "obstacles[0]."),
                                        ("2026", 1, 1, None)):
        out = tmp_path / year
        assert main(["evaluate", str(folder), "--competition", year, "--runs", "1", "--workers", "2",
                     "--out", str(out)]) == 0
        scores = _rows(out / "test-scores.csv")
        assert len(scores) == drawn and len(_rows(out / "runs.csv")) == flown, year
        first = scores[0]
        if invalid is None:  # 2026: the narrow test is not among those evaluated
            assert first["file"].endswith("test_1.yaml")
        else:
            assert first["file"].endswith("test_0.yaml") and first["invalid"].startswith(invalid), (year, first)
            assert (" 1 is outside the competition's [2, 20]" in first["invalid"]) == (year == "2025")
    (folder / "test_1.yaml").unlink()  # the narrow test alone: 2026 has nothing to evaluate, in one line
    capsys.readouterr()
    assert main(["evaluate", str(folder), "--competition", "2026", "--out", str(tmp_path / "none")]) == 2
    assert re.search(r"tool: none of its 1 tests keeps the 2026 edition's rules \(test_0.yaml: obstacles\[0\]\.[lw]: "
                     r"1 is outside", _one_line(capsys)) and not (tmp_path / "none").exists()


# --- resume, ranking ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_the_draw_is_recorded_and_a_resume_scores_the_same_tests(camba, tmp_path, monkeypatch):
    """2024 draws 2 of mission3's 3 tests here (the edition made small: the same code, fewer flights); after more
    tests join the folder, --resume still scores the draw recorded in run.json, flying nothing."""
    monkeypatch.setitem(scoring.EDITIONS, "2024", scoring.Edition("2024", 2, 1, "random"))
    folder = tmp_path / "tool"
    shutil.copytree(camba / "mission3", folder)
    shutil.copytree(camba / "case_studies", tmp_path / "case_studies")
    out = tmp_path / "out"
    assert main(["evaluate", str(folder), "--competition", "2024", "--random-seed", "5", "--workers", "1",
                 "--out", str(out)]) == 0
    drawn = json.loads((out / "run.json").read_text())["draws"][0]["drawn"]
    assert tuple(drawn) == tuple(str(p.absolute()) for p in scoring.draw(sorted(folder.glob("*.yaml")),
                                                                          scoring.EDITIONS["2024"], 5))
    first = _rows(out / "test-scores.csv")
    assert [r["file"] for r in first] == drawn and len(_rows(out / "runs.csv")) == 2  # 1 run each (the edition's)

    for i in range(3):  # the folder changes: a new draw would differ
        shutil.copy(CAMBA / "12-11-12-44-14-5O9PN.yaml", folder / f"00-0{i}-extra.yaml")
    (out / "report.md").unlink()
    assert main(["evaluate", "--resume", str(out)]) == 0
    assert _rows(out / "test-scores.csv") == first
    assert "(2 runs flown before, read back from the store)" in (out / "report.md").read_text()  # none flown now


@pytest.mark.slow
def test_two_folders_on_one_case_study_are_ranked(camba, tmp_path, capsys):
    """Two 'tools' on mission3: one with two of CAMBA's tests, one with the third and a duplicate of it."""
    a, b = tmp_path / "tool-a", tmp_path / "tool-b"
    a.mkdir(), b.mkdir()
    names = sorted(p.name for p in (camba / "mission3").glob("*.yaml"))
    for name in names[:2]:
        shutil.copy(camba / "mission3" / name, a)
    shutil.copy(camba / "mission3" / names[2], b / "test_0.yaml")
    shutil.copy(camba / "mission3" / names[2], b / "test_1.yaml")  # the same ground: a duplicate, counted once
    shutil.copytree(camba / "case_studies", tmp_path / "case_studies")
    out = tmp_path / "out"
    assert main(["evaluate", str(a), str(b), "--competition", "2025", "--runs", "1", "--workers", "2",
                 "--out", str(out)]) == 0
    rows = {row["folder"].rsplit("/", 1)[-1]: row for row in _rows(out / "leaderboard.csv")}
    assert rows["tool-b"]["alike"] == "1" and rows["tool-b"]["diversity"] == ""  # one layout left: no pair
    assert rows["tool-a"]["r_d"] == "1" and rows["tool-b"]["r_d"] == "2"  # a diversity beats none
    fa, fb = float(rows["tool-a"]["failure"]), float(rows["tool-b"]["failure"])
    assert (rows["tool-a"]["r_f"], rows["tool-b"]["r_f"]) == (("1", "2") if fa > fb else ("2", "1") if fb > fa
                                                              else ("1", "1"))
    for row in rows.values():
        assert float(row["r"]) == pytest.approx(0.75 * int(row["r_f"]) + 0.25 * int(row["r_d"]))
    scores = [r for r in _rows(out / "test-scores.csv") if r["folder"].endswith("tool-b")]
    assert [r["same_as"] for r in scores] == ["", "0"] and float(rows["tool-b"]["failure"]) == pytest.approx(
        float(scores[0]["test_score"]), abs=1e-6)


# --- bad input: one line, exit 2, nothing flown ---------------------------------------------------------------------
def test_unknown_edition(camba, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["evaluate", str(camba / "mission3"), "--competition", "2023", "--out", str(out)]) == 2
    assert _one_line(capsys) == "error: --competition: expected one of 2024, 2025, 2026, got '2023'"
    assert not out.exists()


def test_folder_without_yaml(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    out = tmp_path / "out"
    assert main(["evaluate", str(tmp_path / "empty"), "--competition", "2025", "--out", str(out)]) == 2
    assert _one_line(capsys) == f"error: {tmp_path / 'empty'}: no test YAML (*.yaml, *.yml) in this folder"
    assert not out.exists()


def test_folder_mixing_case_studies(tmp_path, capsys, shared_data):
    out = tmp_path / "out"
    assert main(["evaluate", str(CAMBA), "--competition", "2024", "--out", str(out)]) == 2
    assert _one_line(capsys) == (f"error: {CAMBA.absolute()}: tests of 2 case studies (mission1: 18 "
                                 f"(12-11-11-42-23-5O9PN.yaml, ...); mission3: 3 (02-12-16-24-05-5O9PN.yaml, ...)); "
                                 f"a folder holds one case study's tests: put each in a folder of its own")
    assert not out.exists()


def test_a_file_is_not_a_folder(camba, tmp_path, capsys):
    test = next((camba / "mission3").glob("*.yaml"))
    assert main(["evaluate", str(test), "--competition", "2025", "--out", str(tmp_path / "out")]) == 2
    assert _one_line(capsys) == (f"error: {test}: --competition scores folders (a tool's output), and this is a "
                                 f"file")
