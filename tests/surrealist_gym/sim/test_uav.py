"""Which UAV flies: decide_uav, the one place that decides, and the record a results folder keeps of it."""
from __future__ import annotations

import dataclasses
import json

import pytest

from surrealist_gym import load_test
from surrealist_gym.cli import main
from surrealist_gym.errors import InvalidProfile, InvalidTestCase
from surrealist_gym.logs import read_flight
from surrealist_gym.sim.config import SimConfig
from surrealist_gym.sim.profiles import SITL_IRIS, VISION_CASE0, profile_for_flight, save_profile
from surrealist_gym.sim.uav import DEFAULT_UAV, UavDecision, decide_uav, flown_config
from tests.conftest import CASE0_ULG, EXPERIMENTS, SHARED_DATA

MISSION1 = SHARED_DATA / "competition" / "case_studies" / "mission1.yaml"
RQ1_SEED = SHARED_DATA / "surrealist" / "experiments" / "rq1-seed1.yaml"  # replicates case0.ulg


def test_a_preset_named_by_the_user_wins(shared_data):
    """A preset named by the user flies, whatever the log or the test."""
    chosen = decide_uav(load_test(RQ1_SEED), "px4-v1.12-sitl-iris", flight=read_flight(CASE0_ULG))
    assert chosen.profile is SITL_IRIS and chosen.config == SITL_IRIS.sim_config()
    assert chosen.reasons == ("px4-v1.12-sitl-iris: --uav px4-v1.12-sitl-iris",)
    assert decide_uav(load_test(MISSION1), "px4-vision-case0").profile is VISION_CASE0
    assert decide_uav(uav=VISION_CASE0).profile is VISION_CASE0  # a profile value passes through


def test_a_profile_file_named_by_the_user_wins(tmp_path, shared_data):
    path = tmp_path / "narrow.yaml"
    save_profile(dataclasses.replace(SITL_IRIS, name="narrow", sensor={**SITL_IRIS.sensor, "fov_h_deg": 40.0}), path)
    chosen = decide_uav(load_test(RQ1_SEED), path, flight=read_flight(CASE0_ULG))
    assert chosen.profile.name == "narrow" and chosen.config.sensor_config.fov_h_deg == 40.0
    assert chosen.reasons[0] == "narrow: --uav narrow (a profile file)"


def test_no_choice_and_a_log_flies_the_logs_vehicle(shared_data):
    """No choice and a log: the log's own vehicle (over the test's default)."""
    assert decide_uav(load_test(MISSION1), flight=read_flight(CASE0_ULG)).profile == VISION_CASE0
    m0 = read_flight(EXPERIMENTS / "m0.ulg")  # PX4 SITL Iris, on the ground longer than the preset
    chosen = decide_uav(flight=m0)
    assert chosen.profile == profile_for_flight(m0) and chosen.profile.vehicle == SITL_IRIS.vehicle
    assert "the vehicle of the log" in chosen.reasons[0] and "m0.ulg" in chosen.reasons[0]


def test_no_choice_follows_the_test(shared_data):
    assert load_test(RQ1_SEED).replicates_flight
    assert decide_uav(load_test(RQ1_SEED)).profile is VISION_CASE0
    assert decide_uav(load_test(MISSION1)).profile is SITL_IRIS
    assert decide_uav().profile is SITL_IRIS and DEFAULT_UAV == SITL_IRIS.name  # nothing known: the competition's


def test_overrides_sit_under_the_profile_and_a_full_simconfig_flies_as_given(shared_data):
    chosen = decide_uav(load_test(MISSION1), config={"common_noise": True, "competition_buffer_m": 0.5})
    assert chosen.config == SITL_IRIS.sim_config(SimConfig(common_noise=True, competition_buffer_m=0.5))
    assert chosen.reasons[1] == "overrides: common_noise=True, competition_buffer_m=0.5"
    bare = SimConfig(timeout_s=42.0)
    given = decide_uav(load_test(MISSION1), config=bare)
    assert given.config is bare and given.profile is None and given.name == "custom SimConfig"
    assert decide_uav(load_test(MISSION1), "px4-vision-case0", config=bare).config.vehicle == VISION_CASE0.vehicle


def test_the_tests_uav_settings_are_checked_and_recorded_but_applied_when_it_flies(shared_data):
    test = load_test(MISSION1)
    tuned = dataclasses.replace(test, params={**test.params, "uav.takeoff_delay_s": 3.0})
    chosen = decide_uav(tuned)
    assert chosen.config == decide_uav(test).config  # the base the search mutates from
    assert chosen.reasons[-1] == "the test's settings: uav.takeoff_delay_s=3"
    assert flown_config(chosen.config, tuned).takeoff_delay_s == 3.0
    bad = dataclasses.replace(test, params={**test.params, "uav.planner.no_such_field": 1.0})
    with pytest.raises(InvalidTestCase, match=r"^params\.uav\.planner\.no_such_field"):
        decide_uav(bad)


def test_a_decision_passes_through_and_is_recorded(tmp_path, shared_data):
    chosen = decide_uav(flight=read_flight(CASE0_ULG))
    assert decide_uav(load_test(MISSION1), chosen) is chosen
    assert isinstance(chosen, UavDecision)
    record = json.loads(chosen.write(tmp_path).read_text())
    assert record["uav"] == chosen.name and record["reasons"] == list(chosen.reasons)
    assert record["profile"]["vehicle"] == chosen.profile.vehicle.value


@pytest.mark.parametrize("choice, message", [
    ("no-such-uav",
     "--uav 'no-such-uav': not a preset (px4-v1.12-sitl-iris, px4-vision-case0, px4-vision-sitl) nor a .yaml file"),
    ("missing.yaml", "--uav missing.yaml: cannot read profile"),
])
def test_a_bad_choice_is_one_line_naming_the_option(choice, message):
    with pytest.raises(InvalidProfile) as err:
        decide_uav(uav=choice)
    assert str(err.value).startswith(message) and "\n" not in str(err.value)
    with pytest.raises(InvalidProfile, match=r"^uav 'no-such-uav'"):
        decide_uav(uav="no-such-uav", option="uav")


def test_simulate_records_the_uav_and_refuses_vehicle(tmp_path, capsys, shared_data):
    assert main(["simulate", str(MISSION1), "--runs", "1", "--no-plot", "--no-ulog", "--out", str(tmp_path / "o"),
                 "--uav", "px4-vision-sitl"]) == 0
    record = json.loads((tmp_path / "o" / "uav.json").read_text())
    assert record["uav"] == "px4-vision-sitl" and record["reasons"][0].startswith("px4-vision-sitl: --uav")
    assert main(["simulate", str(MISSION1), "--vehicle", "iris"]) == 2
    assert "--uav names the UAV" in capsys.readouterr().err
