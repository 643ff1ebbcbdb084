import json
import math
import warnings

import pytest

import surrealist_gym as sg
from surrealist_gym.mission import Command, geo_to_local, local_to_geo
from tests.conftest import EXPERIMENTS, FORMATS

VALID_PLANS = {
    "mavsdk_qgroundcontrol_sample.plan": [22, 16, 16, 16, 20],
    "mavsdk_qgroundcontrol_sample_with_survey.plan": [16] * 8,
    "mavsdk_qgroundcontrol_sample_with_digicam_control.plan": [],
    "mavsdk_qgroundcontrol_sample_with_structured_scan.plan": [],
}
INVALID_PLANS = {
    "mavsdk_qgroundcontrol_sample_with_survey_missing_items.plan": "survey has no generated",
    "mavsdk_qgroundcontrol_sample_with_survey_wrong_version.plan": "unsupported survey version 9",
    "mavsdk_qgroundcontrol_sample_without_mission.plan": "no 'mission' section",
    "mavsdk_qgroundcontrol_sample_wrong_mission_version.plan": "unsupported mission version 7",
    "mavsdk_qgroundcontrol_sample_wrong_overall_version.plan": "unsupported plan version 42",
}


@pytest.mark.parametrize("name,commands", VALID_PLANS.items())
def test_valid_plans_load(name, commands):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mission = sg.read_mission(FORMATS / "plan" / name)
    assert [int(it.command) for it in mission.items] == commands


@pytest.mark.parametrize("name,reason", INVALID_PLANS.items())
def test_invalid_plans_rejected_with_one_line(name, reason):
    with pytest.raises(sg.MissionError) as err:
        sg.read_mission(FORMATS / "plan" / name)
    message = str(err.value)
    assert reason in message and name in message and "\n" not in message


def test_camera_items_are_skipped_quietly_and_unknown_items_named_in_a_warning(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # auto1.plan opens with MAV_CMD 530 (SET_CAMERA_MODE): no flight effect
        mission = sg.read_mission(EXPERIMENTS / "auto1.plan")
    assert any("530" in s and "SET_CAMERA_MODE" in s for s in mission.skipped)
    assert [it.command for it in mission.items] == [Command.TAKEOFF, Command.WAYPOINT, Command.LAND]
    plan = json.loads((EXPERIMENTS / "auto1.plan").read_text())
    plan["mission"]["items"][0]["command"] = 31000  # a command nothing here knows
    (tmp_path / "odd.plan").write_text(json.dumps(plan))
    with pytest.warns(UserWarning, match="MAV_CMD 31000 is not supported"):
        mission = sg.read_mission(tmp_path / "odd.plan")
    assert any("31000" in s for s in mission.skipped)


def test_case0_plan_in_local_frame():
    mission = sg.read_plan(EXPERIMENTS / "case0.plan")
    takeoff, land = mission.items
    assert takeoff.command == Command.TAKEOFF and (takeoff.x, takeoff.y, takeoff.z) == (0.0, 0.0, 3.0)
    # the real flight ended at (-16.21, 6.28): the land item lies ~0.7 m from there
    assert land.command == Command.LAND
    assert math.hypot(land.x + 16.21, land.y - 6.28) < 1.0
    assert mission.home[:2] == (47.496095399999994, 8.7327818)


@pytest.mark.parametrize("name,count", [("dronekit_mpmission.txt", 6), ("mavsdk_mission_planner_sample.txt", 4),
                                        ("qgc_MissionPlanner.waypoints", 5), ("pymavlink_fence-110.txt", 0)])
def test_wpl_files(name, count):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mission = sg.read_mission(FORMATS / "waypoints" / name)
    assert len(mission.items) == count


def test_wpl_absolute_altitude_is_relative_to_home():
    # frame 0 is MAV_FRAME_GLOBAL (AMSL): 100 m AMSL with home at 584 m lies below home, which is warned about
    with pytest.warns(UserWarning, match="below home"):
        mission = sg.read_waypoints(FORMATS / "waypoints" / "dronekit_mpmission.txt")
    assert mission.home[2] == pytest.approx(584.0)
    assert mission.items[0].z == pytest.approx(100.0 - 584.0)


def test_plan_round_trip(tmp_path):
    mission = sg.read_plan(EXPERIMENTS / "case0.plan")
    sg.write_plan(mission, tmp_path / "out.plan")
    again = sg.read_plan(tmp_path / "out.plan")
    for a, b in zip(mission.items, again.items):
        assert a.command == b.command
        assert (a.x, a.y, a.z) == pytest.approx((b.x, b.y, b.z), abs=1e-6)


def test_projection_round_trip():
    lat0, lon0 = 47.3977419, 8.5455938
    north, east = geo_to_local(47.39768051930175, 8.546310969707491, lat0, lon0)
    assert math.hypot(north, east) == pytest.approx(54.4, abs=0.1)
    assert local_to_geo(north, east, lat0, lon0) == pytest.approx((47.39768051930175, 8.546310969707491), abs=1e-9)


@pytest.mark.parametrize("content,reason", [
    (b"{not json", "invalid JSON"), (b"\x00\x01\x02", "invalid JSON"), (b'{"fileType": "Map"}', "fileType"),
    (b"QGC WPL 110\n0\t1\t0\t16\n", "expected 12 columns"), (b"QGC WPL 120\n", "unsupported WPL version"),
])
def test_bad_files_one_line(tmp_path, content, reason):
    path = tmp_path / "bad.plan"
    path.write_bytes(content)
    with pytest.raises(sg.MissionError, match=reason) as err:
        sg.read_mission(path)
    assert "bad.plan" in str(err.value) and "\n" not in str(err.value)


def test_missing_file():
    with pytest.raises(sg.MissionError, match="cannot read mission file"):
        sg.read_mission("/nonexistent/mission.plan")
