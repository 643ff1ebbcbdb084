import dataclasses
import shutil
import warnings

import pytest

import surrealist_gym as sg
from surrealist_gym.testcase import Obstacle, Shape
from tests.conftest import EXPERIMENTS, SHARED_DATA

COMPETITION = SHARED_DATA / "competition" / "case_studies"


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


def test_rq1_seed1_loads_unchanged():
    test = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    assert test.obstacles == (Obstacle(3, 3, 3, -8.64, 1.74, 0, 158.8),)
    assert [it.command for it in test.mission.items] == [sg.Command.TAKEOFF, sg.Command.LAND]
    assert test.params["NAV_ACC_RAD"] == 0.5 and test.params["MIS_TAKEOFF_ALT"] == 1.0
    assert test.commands == (sg.RuntimeCommand(1, 3, 0, 0, 0.5, 0),)
    assert test.reference_log.endswith("case0.ulg")


@pytest.mark.parametrize("name", ["rq1-seed2.yaml", "rq2-seed.yaml"])
def test_other_seeds_load(name):
    test = sg.load_test(EXPERIMENTS / name)
    assert test.mission is not None and len(test.obstacles) >= 1


def test_rq2_seed_has_two_boxes_first_one_moves():
    test = sg.load_test(EXPERIMENTS / "rq2-seed.yaml")
    assert [o.to_list() for o in test.obstacles] == [[7.625, 5.0625, 20, 17.1875, 17.53125, 0, 0],
                                                     [7.625, 5.0625, 20, -6.375, 17.53125, 0, 0]]


@pytest.mark.parametrize("n", [1, 2, 3])
def test_competition_case_studies_load(n):
    test = sg.load_test(COMPETITION / f"mission{n}.yaml")
    assert test.obstacles == () and test.mission.items[0].command == sg.Command.TAKEOFF
    assert test.params  # mission-params.csv


def test_bundled_seed_resolves_by_file_name():
    test = sg.load_test(sg.data_path("rq1-seed1.yaml"))
    assert test.mission.items == sg.load_test(EXPERIMENTS / "rq1-seed1.yaml").mission.items


def test_save_load_round_trip(tmp_path):
    test = sg.load_test(EXPERIMENTS / "rq2-seed.yaml")
    test = dataclasses.replace(test, wind=sg.Wind(velocity_mean=2.0, direction=(0, 1, 0)),
                               obstacles=test.obstacles + (Obstacle(2, 2, 5, 40, -20, 0, 0, Shape.CYLINDER),))
    sg.save_test(test, tmp_path / "t.yaml")
    again = sg.load_test(tmp_path / "t.yaml", allow_outside=[EXPERIMENTS])  # save_test names them absolute
    assert again == test
    assert again.key() == test.key()


def test_dict_obstacle_form_with_angle_and_tree(tmp_path):
    shutil.copy(EXPERIMENTS / "case0.plan", tmp_path / "case0.plan")
    (tmp_path / "t.yaml").write_text(
        "robot:\n  mission_file: case0.plan\nsimulation:\n  obstacles:\n"
        "  - size: {l: 2, w: 3, h: 4}\n    position: {x: 1, y: 2, z: 0, angle: 30}\n    shape: BOX\n"
        "  - size: {l: 1, h: 6}\n    position: {x: 10, y: 10}\n    shape: TREE\n")
    test = sg.load_test(tmp_path / "t.yaml")
    assert test.obstacles[0] == Obstacle(2, 3, 4, 1, 2, 0, 30)
    assert test.obstacles[1].shape == Shape.CYLINDER and test.obstacles[1].w == 1


@pytest.mark.parametrize("yaml_text,reason", [
    ("simulation:\n  obstacles: [3,3,0, 1,1,0, 0]\n", "size 'h' must be positive"),
    ("simulation:\n  obstacles: [3,3,3, 0,0,0, 0, 3,3,3, 1,1,0, 0]\n", "overlap"),
    ("simulation:\n  obstacles: [3,3,3, 0,0,0]\n", "7 numbers per obstacle"),
    ("simulation:\n  obstacles: [3,3,'big', 0,0,0, 0]\n", "'h': expected a finite number"),
    ("robot:\n  mission_file: nowhere.plan\n", "file 'nowhere.plan' not found"),
    ("robot:\n  mision_file: x.plan\n", "robot.mision_file: unknown field"),
    ("simulaton:\n  speed: 1\n", "unknown section 'simulaton'"),
    ("robot:\n  params: {MPC_XY_CRUISE: fast}\n", "params.MPC_XY_CRUISE: expected a number"),
    ("simulation:\n  wind: {velocity_mean: -1}\n", "wind field 'velocity_mean'"),
    ("simulation: [\n", "invalid YAML"),
    ("- just a list\n", "expected a mapping"),
    ("simulation:\n  home_position: [a, 8.5, 400]\n", "field 'home_position': expected [lat, lon, alt] as numbers"),
    ("simulation:\n  wind: {velocity_mean: 3, direction: [north, 0, 0]}\n", "'direction': expected 3 finite numbers"),
    ("simulation:\n  wind: {velocity_mean: .inf}\n", "'velocity_mean': expected a finite number >= 0"),
    ("simulation:\n  obstacles: [1.0e+9,3,3, 0,0,0, 0]\n", "'l': expected at most 10000 m"),
    ("simulation:\n  obstacles: [1e9,3,3, 0,0,0, 0]\n", "'l': expected at most 10000 m"),  # 1e9 is a number
    ("a: &a [1,1,1,1,1,1,1,1,1,1]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]\nc: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]\n"
     "d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]\ne: [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]\n", "expand to more than 100000 nodes"),
    ("simulation:\n  obstacles: [!!python/object/apply:os.system [ls], 3, 3, 0, 9, 0, 0]\n", "invalid YAML"),
    ("a: " + "[" * 50_000 + "]" * 50_000 + "\n", "YAML nested too deeply"),
])
def test_invalid_yaml_one_line_error(tmp_path, yaml_text, reason):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml_text)
    with pytest.raises(sg.InvalidTestCase) as err:
        sg.load_test(path)
    message = str(err.value)
    assert reason in message and "bad.yaml" in message and "\n" not in message


def test_numpy_numbers_and_small_aliases_load_as_pyyaml_s_dumper_writes_them(tmp_path):
    """A tool that dumps numpy numbers with yaml.dump (PALM) writes each as its dtype (an anchor, then aliases) and
    raw bytes; they read as numbers, and no Python callable runs."""
    import numpy as np
    import yaml

    doc = {"simulation": {"obstacles": [{"size": {"l": np.float64(4.5), "w": np.float64(2.25), "h": 20},
                                         "position": {"x": np.float64(-3.0), "y": 20, "z": 0, "r": np.int64(30)}}]}}
    text = yaml.dump(doc)
    assert "*id001" in text and "python/object/apply:numpy" in text
    (tmp_path / "t.yaml").write_text(text)
    assert sg.load_test(tmp_path / "t.yaml").obstacles[0] == Obstacle(4.5, 2.25, 20, -3.0, 20, 0, 30)


def test_numbers_with_an_exponent_read_as_numbers(tmp_path):
    (tmp_path / "t.yaml").write_text("simulation:\n  obstacles: [3e0,3,3, 1E1,0,0, 0]\n")
    assert sg.load_test(tmp_path / "t.yaml").obstacles[0] == Obstacle(3, 3, 3, 10, 0, 0, 0)


def test_text_that_is_not_utf8_is_a_one_line_error(tmp_path):
    bad = tmp_path / "latin.yaml"
    bad.write_bytes(b"simulation:\n  obstacles: [3,3,3,\xff\xfe,0,0,0]\n")
    with pytest.raises(sg.InvalidTestCase, match="latin.yaml: not UTF-8 text"):
        sg.load_test(bad)
    (tmp_path / "params.csv").write_bytes(b"MPC_XY_CRUISE, 5\n\xffNAV, 3\n")
    test = tmp_path / "test.yaml"
    test.write_text("robot:\n  params_file: params.csv\n")
    with pytest.raises(sg.InvalidTestCase, match="params.csv: not UTF-8 text"):
        sg.load_test(test)


def test_mutation_makes_a_new_value():
    test = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    moved = test.with_obstacles([dataclasses.replace(test.obstacles[0], x=-4.0)])
    assert moved is not test and moved.obstacles[0].x == -4.0 and test.obstacles[0].x == -8.64
    assert moved.key() != test.key()
    with pytest.raises(dataclasses.FrozenInstanceError):
        test.obstacles[0].x = 1.0
    with pytest.raises(TypeError):
        test.params["NAV_ACC_RAD"] = 3


def test_overlap_geometry():
    a = Obstacle(4, 2, 3, 0, 0, 0, 0)
    assert a.overlaps(Obstacle(2, 2, 3, 2.9, 0, 0, 0))
    assert not a.overlaps(Obstacle(2, 2, 3, 3.1, 0, 0, 0))
    assert not a.overlaps(Obstacle(2, 2, 3, 0, 0, 3.5, 0))  # stacked above
    assert a.overlaps(Obstacle(2, 2, 3, 0, 2.3, 0, 45))  # rotated corner reaches in
    assert not a.overlaps(Obstacle(1, 1, 3, 0, 3, 0, 0, Shape.CYLINDER))
