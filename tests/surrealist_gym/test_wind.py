"""Wind as a test property: physical-range checks, wind mutators, and a real flight that the wind moves."""
import dataclasses
import warnings

import numpy as np
import pytest

import surrealist_gym as sg
from surrealist_gym.cli import main
from surrealist_gym.mutators import MutatorKind, WindKind, WindMutator, apply_action, default_mutators, wind_mutators
from surrealist_gym.outcomes import RunStatus
from surrealist_gym.testcase import MAX_WIND_SPEED_MS, Obstacle
from tests.conftest import SHARED_DATA

MISSION1 = SHARED_DATA / "competition" / "case_studies" / "mission1.yaml"


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


@pytest.fixture(scope="module")
def mission1():
    return sg.load_test(MISSION1)


# --- physical range ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fields,reason", [
    ({"velocity_mean": 45}, "'velocity_mean': expected at most 30 m/s"),
    ({"velocity_mean": 8, "velocity_max": 31}, "'velocity_max': expected at most 30 m/s"),
    ({"gust_velocity_mean": 30.5}, "'gust_velocity_mean': expected at most 30 m/s"),
    ({"gust_velocity_max": 100}, "'gust_velocity_max': expected at most 30 m/s"),
    ({"velocity_mean": 8, "velocity_max": 5}, "'velocity_max': expected 0 (not given) or at least velocity_mean"),
    ({"gust_velocity_mean": 4, "gust_velocity_max": 2}, "'gust_velocity_max': expected 0 (not given) or at least"),
    ({"velocity_variance": 901}, "'velocity_variance': expected at most 900 m^2/s^2"),
    ({"gust_velocity_variance": 1e4}, "'gust_velocity_variance': expected at most 900"),
    ({"direction_variance": 1.5}, "'direction_variance': expected at most 1 "),
    ({"gust_direction_variance": 4}, "'gust_direction_variance': expected at most 1 "),
    ({"velocity_mean": 3, "direction": [0, 0, 0]}, "'direction': expected a direction (not all zero)"),
    ({"gust_velocity_max": 2, "gust_direction": [0.0, -0.0, 0]}, "'gust_direction': expected a direction (not all"),
    ({"gust_start": -1}, "'gust_start': expected a finite number >= 0"),
    ({"gust_duration": float("inf")}, "'gust_duration': expected a finite number >= 0"),
    ({"velocity_mean": True}, "'velocity_mean': expected a finite number >= 0"),
])
def test_wind_out_of_range_is_a_one_line_error(fields, reason):
    with pytest.raises(sg.InvalidTestCase) as err:
        sg.Wind(**fields)
    assert reason in str(err.value) and "\n" not in str(err.value)
    assert str(err.value).startswith("wind field ")


@pytest.mark.parametrize("fields", [
    {"velocity_mean": 8.0},  # max 0: not given (the simulator caps at the mean)
    {"velocity_mean": MAX_WIND_SPEED_MS, "velocity_max": MAX_WIND_SPEED_MS, "velocity_variance": 900},
    {"velocity_mean": 5, "velocity_max": 5, "direction": (0, 0, -1), "direction_variance": 1.0},
    {"gust_start": 1e6, "gust_duration": 0.0, "gust_velocity_mean": 3, "gust_velocity_max": 6},
])
def test_wind_in_range_is_accepted(fields):
    wind = sg.Wind(**fields)
    assert all(isinstance(v, float) for k, v in wind.to_dict().items() if not k.endswith("direction"))


def test_aerialist_master_s_own_wind_loads_its_missing_gust_blowing_nothing(mission1):
    """Aerialist master's Wind (third_party, the 2026 key set) writes a gust it lacks as gust_direction [0, 0, 0]."""
    import importlib.util

    path = SHARED_DATA.parent / "third_party" / "aerialist-master" / "aerialist" / "px4" / "wind.py"
    if not path.is_file():
        pytest.skip(f"needs Aerialist master in {path.parent}")
    spec = importlib.util.spec_from_file_location("aerialist_master_wind", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    written = module.Wind(3, 5.0, (1, 0, 0)).to_dict()
    assert written["gust_direction"] == [0, 0, 0]
    wind = sg.Wind(**written)
    assert wind.gust_direction == (1.0, 0.0, 0.0) and wind.gust_velocity_mean == 0 and wind.velocity_mean == 3
    calm = dataclasses.replace(mission1, wind=wind)
    assert sg.simulate(calm, runs=1, seed=0)[0].status != RunStatus.ERROR


def test_integer_and_float_speeds_give_one_key(mission1):
    a = dataclasses.replace(mission1, wind=sg.Wind(velocity_mean=8, direction=(0, 1, 0)))
    b = dataclasses.replace(mission1, wind=sg.Wind(velocity_mean=8.0, direction=(0.0, 1.0, 0.0)))
    assert a.key() == b.key()


@pytest.mark.parametrize("wind,field", [
    ("{velocity_mean: 45, direction: [1, 0, 0]}", "'velocity_mean'"),
    ("{velocity_mean: 8, velocity_max: 5}", "'velocity_max'"),
    ("{velocity_mean: 8, direction: [0, 0, 0]}", "'direction'"),
    ("{velocity_mean: 8, direction_variance: 4}", "'direction_variance'"),
])
def test_simulate_cli_bad_wind_one_line_exit_2(tmp_path, capsys, wind, field):
    case_studies = MISSION1.parent
    (tmp_path / "bad.yaml").write_text(
        f"drone:\n  port: ros\n  params_file: {case_studies / 'mission-params.csv'}\n"
        f"  mission_file: {case_studies / 'mission1.plan'}\n"
        f"simulation:\n  simulator: ros\n  headless: true\n  wind: {wind}\n"
        f"test:\n  commands_file: {case_studies / 'mission-commands.csv'}\n")
    code = main(["simulate", str(tmp_path / "bad.yaml"), "--runs", "1", "--out", str(tmp_path / "out"),
                 "--allow-outside", str(case_studies)])  # it names the shared case study's files
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "bad.yaml: field 'wind': wind field " + field in err


# --- mutators ---------------------------------------------------------------------------------------------------
def test_wind_mutators_interface():
    speed, direction = wind_mutators()
    assert (speed.name, direction.name) == ("wind.speed", "wind.direction")
    assert (speed.low, speed.high, speed.default_step, speed.min_step, speed.default_value) == (-10, 10, 2, 0.1, 0)
    assert (direction.low, direction.high, direction.default_step, direction.min_step) == (-180, 180, 30, 0.5)
    (only,) = wind_mutators(speed_range=(-4.0, 6.0), kinds=["speed"])
    assert (only.kind, only.low, only.high) == (WindKind.SPEED, -4.0, 6.0)
    assert [m.kind for m in wind_mutators(kinds=("direction", "speed"))] == [WindKind.DIRECTION, WindKind.SPEED]
    with pytest.raises(sg.InvalidTestCase, match="wind mutator kind 'gust': expected one of"):
        wind_mutators(kinds=["gust"])
    with pytest.raises(sg.InvalidTestCase, match="expected a range low < high"):
        wind_mutators(speed_range=(5.0, -5.0))
    with pytest.raises(dataclasses.FrozenInstanceError):
        speed.low = 0.0


def test_speed_adds_to_the_mean_and_starts_from_calm(mission1):
    speed = WindMutator(WindKind.SPEED)
    assert mission1.wind is None and speed.apply(mission1, 0.0) is mission1
    windy = speed.apply(mission1, 8.0)
    assert windy.wind == sg.Wind(velocity_mean=8.0) and windy.wind.direction == sg.Wind().direction
    assert speed.apply(windy, -3.0).wind.velocity_mean == pytest.approx(5.0)
    capped = dataclasses.replace(mission1, wind=sg.Wind(velocity_mean=4.0, velocity_max=6.0, velocity_variance=1.0))
    assert speed.apply(capped, 1.0).wind.velocity_max == 6.0  # still above the mean: kept
    raised = speed.apply(capped, 5.0).wind
    assert (raised.velocity_mean, raised.velocity_max, raised.velocity_variance) == (9.0, 9.0, 1.0)
    assert speed.apply(capped, -4.0).wind.velocity_mean == 0.0


def test_speed_stays_within_its_physical_range(mission1):
    speed = WindMutator(WindKind.SPEED, low=-20.0, high=20.0)
    assert speed.valid_range(mission1) == (0.0, 20.0)
    windy = speed.apply(speed.apply(mission1, 5.0), 20.0)  # 25 m/s
    assert speed.valid_range(windy) == (-20.0, pytest.approx(MAX_WIND_SPEED_MS - 25.0))
    _, high = speed.valid_range(windy)
    assert speed.apply(windy, high).wind.velocity_mean == MAX_WIND_SPEED_MS
    too_fast = r"^mutator wind.speed by \+6: mean speed 31 m/s is outside \[0, 30\]$"
    with pytest.raises(sg.InvalidTestCase, match=too_fast):
        speed.apply(windy, 6.0)
    with pytest.raises(sg.InvalidTestCase, match=r"mutator wind.speed by -1: mean speed -1 m/s is outside"):
        speed.apply(mission1, -1.0)


def test_direction_turns_from_north_toward_east_and_keeps_the_vertical(mission1):
    direction = WindMutator(WindKind.DIRECTION)
    assert direction.valid_range(mission1) == (-180.0, 180.0)
    east = direction.apply(mission1, 90.0).wind
    assert east.direction == (0.0, 1.0, 0.0) and east.velocity_mean == 0.0
    tilted = dataclasses.replace(mission1, wind=sg.Wind(velocity_mean=6.0, direction=(0.0, 2.0, -0.5)))
    turned = direction.apply(tilted, 90.0).wind  # east -> south, length and vertical kept
    assert turned.direction == (-2.0, 0.0, -0.5) and turned.velocity_mean == 6.0
    back = direction.apply(direction.apply(tilted, 30.0), -30.0).wind.direction
    assert back == pytest.approx(tilted.wind.direction)
    assert direction.apply(tilted, 180.0).wind.direction == direction.apply(tilted, -180.0).wind.direction


def test_speed_and_direction_commute(mission1):
    speed, direction = wind_mutators()
    a = direction.apply(speed.apply(mission1, 8.0), 90.0)
    b = speed.apply(direction.apply(mission1, 90.0), 8.0)
    assert a == b and a.key() == b.key()
    assert a.wind == sg.Wind(velocity_mean=8.0, direction=(0.0, 1.0, 0.0))


def test_wind_changes_the_key_and_round_trips(mission1, tmp_path):
    speed, direction = wind_mutators()
    keys = {mission1.key(), speed.apply(mission1, 8.0).key(), direction.apply(speed.apply(mission1, 8.0), 45.0).key(),
            speed.apply(mission1, 8.5).key()}
    assert len(keys) == 4
    windy = direction.apply(speed.apply(mission1, 7.3), -63.0)
    sg.save_test(windy, tmp_path / "windy.yaml")
    again = sg.load_test(tmp_path / "windy.yaml", allow_outside=[MISSION1.parent])  # save_test names them absolute
    assert again.wind == windy.wind and again.key() == windy.key()


def test_apply_action_with_obstacle_and_wind_mutators(mission1):
    seed = mission1.with_obstacles([Obstacle(4, 4, 15, 10, 25)])
    mutators = default_mutators(seed, kinds=(MutatorKind.MOVE_X, MutatorKind.MOVE_Y)) + wind_mutators()
    assert [m.name for m in mutators] == ["obstacle0.x", "obstacle0.y", "wind.speed", "wind.direction"]
    assert apply_action(seed, mutators, [0, 0, 0, 0]) is seed
    test = apply_action(seed, mutators, [0.5, -0.25, 0.8, 0.5])
    assert (test.obstacles[0].x, test.obstacles[0].y) == (20.0, 20.0)
    assert test.wind.velocity_mean == 8.0 and test.wind.direction == pytest.approx((0.0, 1.0, 0.0))
    assert apply_action(seed, mutators, [0.5, -0.25, 0.8, 0.5]).key() == test.key()
    assert apply_action(seed, mutators, [0.5, -0.25, 0.8, 0.6]).key() != test.key()
    with pytest.raises(sg.InvalidTestCase, match="mutator wind.speed by -5: mean speed -5 m/s"):
        apply_action(seed, mutators, [0, 0, -0.5, 0])
    low, high = zip(*(m.valid_range(seed) for m in mutators))
    assert (low[2], high[2]) == (0.0, 10.0)


# --- a real flight ----------------------------------------------------------------------------------------------
def test_crosswind_moves_the_uav_off_its_track(mission1):
    """mission1 flies ~53 m east (and 3.3 m north) at 10 m: an 8 m/s wind blowing toward north pushes the Iris
    north of its track, the same wind turned to south pushes it south; without wind it stays within centimetres."""
    from surrealist_gym.sim.profiles import load_profile
    from surrealist_gym.sim.runner import simulate

    config = load_profile("px4-v1.12-sitl-iris").sim_config()
    speed, direction = wind_mutators()
    north = speed.apply(mission1, 8.0)
    south = direction.apply(north, 180.0)

    land = mission1.mission.items[-1]
    track = np.array([land.x, land.y]) / np.hypot(land.x, land.y)
    north_of_track = np.array([track[1], -track[0]])  # the track's normal in (north, east); the track runs east

    def cross_track(test):
        (run,) = simulate(test, runs=1, seed=0, config=config)
        assert run.status == RunStatus.SUCCESS
        xy, up = run.true_xyz[:, :2], run.true_xyz[:, 2]
        return xy[up > 1.0] @ north_of_track  # airborne offset from the straight track, positive north [m]

    calm, pushed_north, pushed_south = cross_track(mission1), cross_track(north), cross_track(south)
    assert np.abs(calm).max() < 0.2
    assert pushed_north.max() > 0.5 and pushed_north.min() > -0.2
    assert pushed_south.min() < -0.5 and pushed_south.max() < 0.2
