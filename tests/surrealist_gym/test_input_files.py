"""A test reads only what it should (issue 44): its files resolve against the YAML's folder, the working folder or by
name in the YAML's folder (the competition's case_studies/ one folder up), never by walking up parents; they lie
under those folders or one allowed; kernel files, FIFOs, folders and oversized files are refused; errors name the
file and field, never its contents. Real seeds from ../shared/data and real files built in tmp_path."""
from __future__ import annotations

import os
import random
import shutil
import warnings

import pytest

import surrealist_gym as sg
from surrealist_gym.errors import InvalidLabels, InvalidTestCase, MissionError, read_text
from surrealist_gym.testcase import Obstacle, Shape, first_overlap
from tests.conftest import CASE_STUDIES, EXPERIMENTS

SECRET = "hunter2-do-not-echo"


def _yaml(folder, body: str):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "t.yaml"
    path.write_text(body)
    return path


def _refused(path, *names, allow_outside=()) -> str:
    with pytest.raises(InvalidTestCase) as err:
        sg.load_test(path, allow_outside=allow_outside)
    text = str(err.value)
    assert "\n" not in text and SECRET not in text, text
    for name in names:
        assert str(name) in text, (name, text)
    return text


def test_no_lookup_walks_up_parent_folders(tmp_path, monkeypatch):
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")  # the working folder holds none of the files
    (tmp_path / "etc").mkdir()
    (tmp_path / "etc" / "passwd").write_text(f"root:{SECRET}\n")
    path = _yaml(tmp_path / "a" / "b", "robot:\n  mission_file: etc/passwd\n")  # the old loader found ../../etc/passwd
    assert "not found" in _refused(path, "t.yaml", "mission_file", "etc/passwd")


@pytest.mark.parametrize("value", ["{outside}/secret.csv", "../../outside/secret.csv", "link.csv"])
def test_a_file_outside_the_yaml_folder_and_working_folder_is_refused_unless_allowed(tmp_path, monkeypatch, value):
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")  # the working folder holds none of the files
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.csv").write_text(f"MPC_XY_CRUISE, {SECRET}\n")
    folder = tmp_path / "tests" / "t1"
    path = _yaml(folder, f"robot:\n  params_file: {value.format(outside=outside)}\n")
    (folder / "link.csv").symlink_to(outside / "secret.csv")  # a link inside pointing out counts as outside
    monkeypatch.chdir(tmp_path / "tests")  # the working folder holds the YAML's folder but not outside/
    assert "lies outside" in _refused(path, "params_file", "--allow-outside")
    # allowed: read, and its bad line named without being quoted
    assert "line 1" in _refused(path, "params_file", "secret.csv", allow_outside=[outside])


def test_the_working_folder_is_allowed(tmp_path, monkeypatch):
    shutil.copy(EXPERIMENTS / "case0.plan", tmp_path / "case0.plan")
    path = _yaml(tmp_path / "deep" / "er", "robot:\n  mission_file: case0.plan\n")
    monkeypatch.chdir(tmp_path)  # Aerialist's rule: relative to the working folder
    assert sg.load_test(path).mission_file == str(tmp_path / "case0.plan")


@pytest.mark.parametrize("value", ["/proc/self/environ", "/proc/kmsg", "/sys/kernel/mm/transparent_hugepage/enabled"])
def test_kernel_files_are_refused_even_when_allowed(tmp_path, monkeypatch, value):
    monkeypatch.setenv("SURREALIST_TEST_SECRET", SECRET)
    path = _yaml(tmp_path, f"robot:\n  params_file: {value}\n")
    if not os.path.exists(value):
        pytest.skip(f"{value} is not on this machine")
    assert "lies outside" in _refused(path, "params_file")
    assert "kernel" in _refused(path, "params_file", value.split("/")[1], allow_outside=["/"])


@pytest.mark.parametrize("kind", ["fifo", "folder", "device"])
def test_special_files_are_refused(tmp_path, kind):
    target = {"fifo": tmp_path / "p.csv", "folder": tmp_path / "p.csv", "device": "/dev/zero"}[kind]
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "folder":
        target.mkdir()
    path = _yaml(tmp_path, f"robot:\n  params_file: {target}\n")
    text = _refused(path, "params_file", allow_outside=["/dev"])
    assert {"fifo": "FIFO", "folder": "a folder", "device": "a device"}[kind] in text


def test_size_limit(tmp_path):
    big = tmp_path / "p.csv"
    with open(big, "wb") as f:
        f.truncate(17 * 1024 * 1024)  # sparse: more than MAX_TEXT_BYTES without writing it
    assert "more than" in _refused(_yaml(tmp_path, "robot:\n  params_file: p.csv\n"), "params_file", "p.csv")
    small = tmp_path / "s.txt"
    small.write_text("x" * 11)
    with pytest.raises(InvalidTestCase, match="more than"):
        read_text(small, "file", InvalidTestCase, max_bytes=10)


@pytest.mark.parametrize("name", ["p.csv", "c.csv"])
def test_a_csv_field_over_csv_limit_is_one_line(tmp_path, name):
    (tmp_path / name).write_text("MPC_XY_CRUISE, " + "9" * 140_000 + "\n")
    field = "params_file" if name == "p.csv" else "commands_file"
    section = "robot" if name == "p.csv" else "mission"
    text = _refused(_yaml(tmp_path, f"{section}:\n  {field}: {name}\n"), field, name)
    assert "field limit" in text and "9999" not in text


def test_errors_never_quote_the_file(tmp_path):
    (tmp_path / "p.csv").write_text(f"{SECRET}\n")
    assert "line 1" in _refused(_yaml(tmp_path, "robot:\n  params_file: p.csv\n"), "params_file")
    (tmp_path / "p.csv").write_text(f"{SECRET}, {SECRET}\n")  # an unknown parameter's name is not shown
    assert "the parameter" in _refused(_yaml(tmp_path, "robot:\n  params_file: p.csv\n"), "params_file")
    (tmp_path / "p.csv").write_text(f"MPC_XY_CRUISE, {SECRET}\n")
    assert "MPC_XY_CRUISE" in _refused(_yaml(tmp_path, "robot:\n  params_file: p.csv\n"), "params_file")
    (tmp_path / "m.plan").write_text(f"QGC WPL {SECRET}\n")
    _refused(_yaml(tmp_path, "robot:\n  mission_file: m.plan\n"), "mission_file")


def test_deeply_nested_plan_is_one_line(tmp_path):
    (tmp_path / "m.plan").write_text("[" * 50_000 + "]" * 50_000)
    with pytest.raises(MissionError, match="nested too deeply"):
        sg.read_mission(tmp_path / "m.plan")


@pytest.mark.parametrize("folder", ["experiments", "packaged"])
def test_the_paper_seeds_load_from_anywhere(tmp_path, monkeypatch, folder):
    monkeypatch.chdir(tmp_path)  # neither the seeds' repository root nor ours
    base = EXPERIMENTS if folder == "experiments" else os.path.dirname(sg.data_path("rq1-seed1.yaml"))
    for name in ("rq1-seed1.yaml", "rq1-seed2.yaml", "rq2-seed.yaml"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # rq2's camera item (MAV_CMD 530) is skipped quietly
            test = sg.load_test(os.path.join(base, name))
        assert test.mission is not None and test.params and test.commands
        assert os.path.dirname(test.mission_file) == str(base)


def test_the_competition_layout_from_the_tools_folder_only(tmp_path, monkeypatch):
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")  # the working folder holds none of the files
    shutil.copytree(CASE_STUDIES, tmp_path / "tool" / "case_studies")
    body = "robot:\n  mission_file: case_studies/mission1.plan\n"
    test = sg.load_test(_yaml(tmp_path / "tool" / "generated_tests", body))
    assert test.mission_file == str(tmp_path / "tool" / "case_studies" / "mission1.plan")
    # tools write into generated_tests/<time stamp>/ (CAMBA, the reference generator): still the tool's folder
    test = sg.load_test(_yaml(tmp_path / "tool" / "generated_tests" / "28-11-19-56-47", body))
    assert test.mission_file == str(tmp_path / "tool" / "case_studies" / "mission1.plan")
    # AmbieGen's folder is generated_tests-01/<time stamp>/
    test = sg.load_test(_yaml(tmp_path / "tool" / "generated_tests-01" / "29-11-10-28-27", body))
    assert test.mission_file == str(tmp_path / "tool" / "case_studies" / "mission1.plan")
    _refused(_yaml(tmp_path / "tool" / "a" / "b", body), "mission_file", "not found")


def test_first_overlap_is_the_pairwise_answer():
    rng = random.Random(44)
    for _ in range(300):
        obstacles = [Obstacle(rng.uniform(1, 10), rng.uniform(1, 10), rng.uniform(1, 10), rng.uniform(-30, 30),
                              rng.uniform(-30, 30), rng.choice([0, 0, 5]), rng.uniform(0, 90),
                              rng.choice([Shape.BOX, Shape.CYLINDER])) for _ in range(rng.randint(2, 8))]
        brute = next(((i, j) for i in range(len(obstacles)) for j in range(i + 1, len(obstacles))
                      if obstacles[i].overlaps(obstacles[j])), None)
        assert first_overlap(obstacles) == brute


def test_thousands_of_boxes_are_checked():
    grid = [Obstacle(1, 1, 1, 3 * (k % 60), 3 * (k // 60), 0, 0) for k in range(3000)]
    assert first_overlap(grid) is None
    tower = [Obstacle(1, 1, 1, 0, 0, 2 * k, 0) for k in range(3000)]  # every footprint meets: heights decide
    assert first_overlap(tower) is None
    assert first_overlap(grid + [Obstacle(1, 1, 1, 0.5, 0.5, 0, 0)]) == (0, 3000)
    with pytest.raises(InvalidTestCase, match=r"obstacles\[0\] and obstacles\[3000\] overlap"):
        sg.TestCase(obstacles=tuple(grid) + (Obstacle(1, 1, 1, 0.5, 0.5, 0, 0),))


def test_fidelity_labels_with_obstacles_nested_deeply(tmp_path):
    from surrealist_gym.fidelity.labels import load_labelled_set

    nested = "[" * 50_000 + "]" * 50_000
    (tmp_path / "tests.csv").write_text(f'test_id,obstacles,px4_min_distance_2d\nt1,"{nested}",1.0\n')
    with pytest.raises(InvalidLabels, match="nested too deeply"):
        load_labelled_set(tmp_path / "tests.csv", mission=CASE_STUDIES / "mission1.yaml")


def test_a_tools_case_studies_beside_the_tests_folder(tmp_path, monkeypatch):
    """surrealist compete writes the tests a tool sends into out/flights/, naming the tool copy's files absolute."""
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")
    shutil.copytree(CASE_STUDIES, tmp_path / "out" / "tool" / "case_studies")
    shutil.copytree(CASE_STUDIES, tmp_path / "out" / "tool" / "elsewhere")
    plan = tmp_path / "out" / "tool" / "case_studies" / "mission1.plan"
    test = sg.load_test(_yaml(tmp_path / "out" / "flights", f"robot:\n  mission_file: {plan}\n"))
    assert test.mission_file == str(plan)
    other = tmp_path / "out" / "tool" / "elsewhere" / "mission1.plan"
    _refused(_yaml(tmp_path / "out" / "flights", f"robot:\n  mission_file: {other}\n"), "lies outside")
