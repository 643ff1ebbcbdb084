"""The feasibility check: walled-off layouts are rejected with a reason naming the obstacles, PX4's flown ones are not.

The walled-off set and the labelled flights come from ../shared (those tests skip without it, through the
``shared_data`` fixture); the geometric cases build their missions here."""
import re
import warnings
from pathlib import Path

import pytest

from surrealist_gym.aerialist import load_test
from surrealist_gym.competition.feasibility import FeasibilityConfig, infeasible
from surrealist_gym.fidelity.labels import load_labelled_set
from surrealist_gym.mission import Command, Mission, MissionItem
from surrealist_gym.testcase import Obstacle, Shape, TestCase

WALLED_OFF = Path(__file__).resolve().parents[2] / "data" / "walled_off"
NAMES = re.compile(r"obstacles\[\d+\]")


def mission(*items) -> Mission:
    """Takeoff to 10 m at home, then the given (command, x, y, z) items."""
    rows = [MissionItem(Command.TAKEOFF, 0.0, 0.0, 10.0)] + [MissionItem(c, x, y, z) for c, x, y, z in items]
    return Mission(items=tuple(rows), home=(47.0, 8.0, 400.0))


NORTH = mission((Command.LAND, 0.0, 50.0, 0.0))  # takeoff at the origin, land 50 m east


def wall(gap: float, y: float = 25.0, length: float = 40.0) -> list[Obstacle]:
    """Two 2 m thick boxes across the track at y, `gap` apart on the track, each `length` long."""
    half = gap / 2 + length / 2
    return [Obstacle(length, 2, 20, -half, y), Obstacle(length, 2, 20, half, y)]


@pytest.fixture(scope="module")
def rilast(shared_data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_labelled_set(shared_data / "competition" / "rilast-mission1" / "tests.csv")


@pytest.mark.parametrize("path", sorted(WALLED_OFF.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_walled_off_layout_is_rejected_with_a_reason_naming_obstacles(path, shared_data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # mission2/3's camera item
        test = load_test(path, allow_outside=[shared_data / "competition" / "case_studies"])
    reason = infeasible(test)
    assert reason is not None and "\n" not in reason
    assert NAMES.search(reason)


def test_the_walled_off_set_covers_missions_1_to_3():
    assert {p.name[:2] for p in WALLED_OFF.glob("*.yaml")} == {"m1", "m2", "m3"}


def test_every_layout_px4_flew_to_the_end_is_accepted(rilast, shared_data):
    flown = [(lab.test_id, t) for lab, t in zip(rilast.labels, rilast.tests) if lab.result == "flown"]
    assert len(flown) > 1000
    assert [(tid, infeasible(t)) for tid, t in flown if infeasible(t) is not None] == []
    camba = load_labelled_set(shared_data / "competition" / "camba-collection")
    assert [infeasible(t) for t in camba.tests] == [None] * len(camba)


def test_an_open_layout_is_feasible():
    assert infeasible(TestCase(mission=NORTH)) is None
    assert infeasible(TestCase(mission=NORTH, obstacles=[Obstacle(10, 10, 20, 0, 25)])) is None


def test_the_reason_names_the_wall_and_its_widest_gap_not_the_other_obstacles():
    far = Obstacle(4, 4, 20, 20, 5)  # beside the track, not part of the wall
    reason = infeasible(TestCase(mission=NORTH, obstacles=[far, *wall(1.5)]))
    assert reason == ("obstacles[1] and obstacles[2] wall off the leg to mission item 1 (LAND) within 30 m of its "
                      "track (widest gap 1.5 m < 6 m)")


def test_a_gap_is_closed_below_twice_the_clearance():
    assert infeasible(TestCase(mission=NORTH, obstacles=wall(5.5))) is not None
    assert infeasible(TestCase(mission=NORTH, obstacles=wall(6.5))) is None
    assert infeasible(TestCase(mission=NORTH, obstacles=wall(1.0)), FeasibilityConfig(clearance_m=0.4)) is None


def test_the_flight_region_is_bounded_by_max_offset():
    across = [Obstacle(50, 2, 20, 0, 25)]  # 25 m either side of the track
    assert infeasible(TestCase(mission=NORTH, obstacles=across)) is None
    reason = infeasible(TestCase(mission=NORTH, obstacles=across), FeasibilityConfig(max_offset_m=20))
    assert reason == ("obstacles[0] walls off the leg to mission item 1 (LAND) within 20 m of its track "
                      "(it spans the flight region)")


def test_only_obstacles_at_the_flight_altitude_block():
    low, floating = [Obstacle(80, 2, 9, 0, 25)], [Obstacle(80, 2, 5, 0, 25, z=11)]
    assert infeasible(TestCase(mission=NORTH, obstacles=low)) is None
    assert infeasible(TestCase(mission=NORTH, obstacles=floating)) is None
    assert infeasible(TestCase(mission=NORTH, obstacles=[Obstacle(80, 2, 9.8, 0, 25)])) is not None  # within 0.5 m


def test_takeoff_and_landing_points_inside_an_obstacle():
    assert infeasible(TestCase(mission=NORTH, obstacles=[Obstacle(4, 4, 20, 0, 50)])) == \
        "the goal of the leg to mission item 1 (LAND) lies inside obstacles[0]"
    assert infeasible(TestCase(mission=NORTH, obstacles=[Obstacle(4, 4, 3, 0, 50)])) == \
        "the goal of the leg to mission item 1 (LAND) lies inside obstacles[0]"  # the descent lands on it
    assert infeasible(TestCase(mission=NORTH, obstacles=[Obstacle(4, 4, 3, 1, 0)])) == \
        "the takeoff point lies inside obstacles[0]"
    waypoint = mission((Command.WAYPOINT, 0.0, 25.0, 10.0), (Command.LAND, 0.0, 50.0, 0.0))
    assert infeasible(TestCase(mission=waypoint, obstacles=[Obstacle(4, 4, 3, 0, 25)])) is None  # flown over


def test_a_goal_near_a_box_face_is_reachable():
    near = [Obstacle(10, 10, 20, 0, 56)]  # 1 m beyond the landing point
    assert infeasible(TestCase(mission=NORTH, obstacles=near)) is None


def test_a_boxed_in_goal_names_its_pocket():
    pocket = [Obstacle(2, 14, 20, -5, 50), Obstacle(2, 14, 20, 5, 50), Obstacle(8, 2, 20, 0, 58),
              Obstacle(8, 2, 20, 0, 42)]
    reason = infeasible(TestCase(mission=NORTH, obstacles=pocket))
    assert reason.startswith("obstacles[0], obstacles[1], obstacles[2] and obstacles[3] box in the goal of the leg "
                             "to mission item 1 (LAND)")


def test_cylinders_are_discs_of_diameter_l():
    trees = [Obstacle(10, 10, 20, x, 25, shape=Shape.CYLINDER) for x in (-25.5, -15.25, -5, 5, 15.25, 25.5)]
    reason = infeasible(TestCase(mission=NORTH, obstacles=trees))
    assert reason is not None and "widest gap 0.2 m < 6 m" in reason


def test_the_reason_names_the_blocked_leg():
    out_and_back = mission((Command.WAYPOINT, 0.0, 50.0, 10.0), (Command.WAYPOINT, -20.0, 50.0, 10.0),
                           (Command.LAND, -20.0, 0.0, 0.0))
    lateral = [Obstacle(2, 30, 20, -10, 36), Obstacle(2, 30, 20, -10, 66.5)]  # cuts the lateral leg only
    reason = infeasible(TestCase(mission=out_and_back, obstacles=lateral))
    assert "the leg to mission item 2 (WAYPOINT)" in reason


def test_a_test_without_a_mission_gets_a_reason():
    assert infeasible(TestCase()) == "the test has no mission leg to fly (no mission item with a position)"


def test_config_is_checked():
    with pytest.raises(ValueError, match="clearance_m"):
        FeasibilityConfig(clearance_m=-1)
    with pytest.raises(ValueError, match="max_offset_m"):
        FeasibilityConfig(max_offset_m=0)
    with pytest.raises(TypeError):
        FeasibilityConfig(clearance=1)  # type: ignore[call-arg]
