"""The navigator and flight-task kernels (sim/navigation/navigator_kernels) equal the readable classes (Navigator,
AvoidanceFlightTask) bit for bit.

Real flights record every ``Navigator.update`` call (its inputs, the planner's output, what it returned and the
navigator's properties after it): the case0 replication seed (PX4 Vision, the simple planner's velocity
setpoints), a rilast mission1 test on the ``px4-v1.12-sitl-iris`` profile (PX4-Avoidance's position setpoints
through the flight task), QGroundControl's sample plan (take-off, waypoints, return to launch with its climb,
landing, disarm; no avoidance) and a small mission with a speed change, a hold, an acceptance radius, a take-off
hold and an end in the air. Each call sequence is replayed through the kernel from its initial state and every
output and property must be equal (NaN where NaN) at every call.
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field, replace

import numpy as np
import pytest

from surrealist_gym import Mission, MissionItem, Obstacle, TestCase, load_test
from surrealist_gym.geometry import line_projection
from surrealist_gym.mission import Command, read_mission
from surrealist_gym.sim import SimConfig, runner, simulate
from surrealist_gym.sim.compiled import cpython_math as cm
from surrealist_gym.sim.config import PX4_DEFAULTS
from surrealist_gym.sim.navigation import flight_task_kernels as fk, navigator_kernels as nk, navigator_state as ns
from surrealist_gym.sim.navigation.flight_task import AvoidanceFlightTask
from surrealist_gym.sim.navigation.navigator import Navigator, Phase
from surrealist_gym.sim.profiles import load_profile
from tests.conftest import CASE_STUDIES, EXPERIMENTS, FORMATS, SHARED_DATA, fly_the_python_outer_loop

RILAST = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"
QGC_SAMPLE = FORMATS / "plan" / "mavsdk_qgroundcontrol_sample.plan"


@dataclass
class _Recording:
    """One navigator's construction and its update calls: (args, planner output, returned value, properties)."""

    mission: Mission
    params: dict
    start_time: float
    takeoff_hold_s: float
    calls: list = field(default_factory=list)


def _properties(nav) -> tuple:
    """What the run loop reads of a navigator after an update (target in full: five values in the RTL climb)."""
    return (nav.phase, nav.index, nav.mission_complete, nav.armed, nav.on_ground_phase, nav.uses_planner,
            tuple(nav.goal()), tuple(nav.target), tuple(nav.prev), nav.cruise)


def _fly(test, config) -> list[_Recording]:
    """Fly one run of ``test`` with Navigator's ``__init__`` and ``update`` wrapped to record."""
    recordings = []
    init, update = Navigator.__init__, Navigator.update

    def recording_init(self, mission, params, start_time, takeoff_hold_s=0.0):
        init(self, mission, params, start_time, takeoff_hold_s)
        recordings.append(_Recording(mission, dict(params), start_time, takeoff_hold_s))
        self._recording = recordings[-1]

    def recording_update(self, t, pos, vel, yaw, dt, ground_contact, planner=None):
        out = update(self, t, pos, vel, yaw, dt, ground_contact, planner)
        self._recording.calls.append(((t, pos, vel, yaw, dt, ground_contact), planner, out, _properties(self)))
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Navigator, "__init__", recording_init)
        mp.setattr(Navigator, "update", recording_update)
        fly_the_python_outer_loop(mp)
        (result,) = simulate(test, runs=1, seed=0, config=config)
    assert len(recordings) == 1 and recordings[0].calls
    return recordings


def _rilast(test_id: str):
    with open(RILAST, newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["test_id"] == test_id)
    obstacles = [Obstacle(**o) for o in json.loads(row["obstacles"])]
    return load_test(CASE_STUDIES / "mission1.yaml").with_obstacles(obstacles)


def _small_mission() -> TestCase:
    """Take-off, a speed change, a waypoint with its own acceptance radius and a 2 s hold, a climbing waypoint;
    the mission ends in the air."""
    items = (MissionItem(Command.TAKEOFF, 0.0, 0.0, 3.0), MissionItem(Command.CHANGE_SPEED, speed=2.0),
             MissionItem(Command.WAYPOINT, 8.0, 0.0, 3.0, acceptance_radius=1.5, hold_s=2.0),
             MissionItem(Command.WAYPOINT, 8.0, 6.0, 5.0))
    return TestCase(mission=Mission(items=items, home=(47.0, 8.0, 400.0)))


@pytest.fixture(scope="module")
def flights(shared_data) -> dict[str, _Recording]:
    iris = load_profile("px4-v1.12-sitl-iris").sim_config()
    qgc = TestCase(mission=read_mission(QGC_SAMPLE))  # its camera item (MAV_CMD 2000) is skipped, quietly
    return {
        "case0 seed1 (PX4 Vision, simple planner)": _fly(load_test(EXPERIMENTS / "rq1-seed1.yaml"), None)[0],
        "rilast random_run3_194 (SITL Iris, PX4-Avoidance)": _fly(_rilast("random_run3_194"), iris)[0],
        "QGC sample plan, RTL (no avoidance)": _fly(qgc, SimConfig(avoidance=False))[0],
        "speed change, hold, end in the air": _fly(_small_mission(), SimConfig(
            avoidance=False, takeoff_hold_s=1.0, takeoff_delay_s=1.0))[0],
    }


def _same(a, b) -> bool:
    """Equal floats, NaN equal to NaN (both flattened)."""
    return len(a) == len(b) and all(x == y or (x != x and y != y) for x, y in zip(a, b))


def _flat(out) -> list[float]:
    pos, vel, acc, yaw = out
    return [*pos, *vel, *acc, yaw]


def _kernel_properties(state) -> tuple:
    target = tuple(state[ns.S_TARGET:ns.S_TARGET + 5])
    return (ns.phase_of(state), ns.nav_index(state), ns.nav_mission_complete(state), ns.nav_armed(state),
            ns.nav_on_ground_phase(state), ns.nav_uses_planner(state), ns.nav_goal(state), target, ns.nav_prev(state),
            ns.nav_cruise(state))


def _assert_replay_equal(rec: _Recording, expected=None, params=None) -> int:
    """Replay ``rec``'s calls through the kernel; each output and property must equal ``expected`` (default: what
    the class returned in the flight). Returns the number of calls."""
    params = rec.params if params is None else params
    p = ns.param_vector(params, rec.start_time, rec.takeoff_hold_s)
    mission = ns.mission_array(rec.mission)
    state = ns.initial_state(p)
    expected = expected or [(out, props) for _, _, out, props in rec.calls]
    for i, ((args, planner, _, _), (out, props)) in enumerate(zip(rec.calls, expected)):
        t, pos, vel, yaw, dt, ground = args
        kind, vector, plan_yaw = ns.plan_inputs(planner)
        got = nk.nav_update(state, mission, p, t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw)
        assert _same(_flat(got), _flat(out)), (i, t, props[0], _flat(got), _flat(out))
        mine = _kernel_properties(state)
        assert mine[:6] == props[:6], (i, t, mine[:6], props[:6])
        # goal() and target are the class's whole target: five values in the RTL climb, the kernel's goal three
        assert _same(mine[6], props[6][:3]) and _same(mine[7][:len(props[7])], props[7]), (i, t, mine, props)
        assert _same(mine[8], props[8]) and mine[9] == props[9], (i, t, mine, props)
    return len(rec.calls)


def _class_replay(rec: _Recording, params: dict) -> list:
    """The class's outputs and properties on ``rec``'s inputs with other parameters."""
    nav = Navigator(rec.mission, params, rec.start_time, rec.takeoff_hold_s)
    expected = []
    for args, planner, _, _ in rec.calls:
        out = nav.update(*args, planner)
        expected.append((out, _properties(nav)))
    return expected


# --- recorded flights ---------------------------------------------------------------------------------------------
def test_recorded_flights_cover_the_navigator(flights):
    """The four flights pass through every phase, both planner outputs and every mission command."""
    phases, kinds, commands = set(), set(), set()
    for rec in flights.values():
        phases |= {props[0] for *_, props in rec.calls}
        kinds |= {ns.plan_inputs(planner)[0] for _, planner, _, _ in rec.calls}
        commands |= {it.command for it in rec.mission.items}
    assert phases == set(Phase)
    assert kinds == {ns.PLAN_NONE, ns.PLAN_VELOCITY, ns.PLAN_POSITION}
    assert commands == set(Command)


@pytest.mark.parametrize("name", ["case0 seed1 (PX4 Vision, simple planner)",
                                  "rilast random_run3_194 (SITL Iris, PX4-Avoidance)",
                                  "QGC sample plan, RTL (no avoidance)", "speed change, hold, end in the air"])
def test_kernel_equals_navigator_on_a_recorded_flight(flights, name):
    rec = flights[name]
    assert _assert_replay_equal(rec) > 700
    assert rec.calls[-1][3][2]  # the flight ran to the mission's end


@pytest.mark.parametrize("yaw_mode", [1, 2, 3])
@pytest.mark.parametrize("name", ["QGC sample plan, RTL (no avoidance)", "speed change, hold, end in the air"])
def test_kernel_equals_navigator_in_every_yaw_mode(flights, name, yaw_mode):
    """The flights' inputs again, with MPC_YAW_MODE 1 (home), 2 (away from home), 3 (along the velocity)."""
    rec = flights[name]
    params = dict(rec.params, MPC_YAW_MODE=yaw_mode)
    _assert_replay_equal(rec, _class_replay(rec, params), params)


def test_a_mission_padded_for_a_batch_flies_the_same(flights):
    rec = flights["case0 seed1 (PX4 Vision, simple planner)"]
    p = ns.param_vector(rec.params, rec.start_time, rec.takeoff_hold_s)
    short, padded = ns.mission_array(rec.mission), ns.mission_array(rec.mission, rows=6)
    assert padded.shape == (6, ns.N_MISSION_FIELDS) and (padded[2:, ns.M_COMMAND] == ns.NO_ITEM).all()
    a, b = ns.initial_state(p), ns.initial_state(p)
    for (t, pos, vel, yaw, dt, ground), planner, _, _ in rec.calls:
        kind, vector, plan_yaw = ns.plan_inputs(planner)
        out_a = nk.nav_update(a, short, p, t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw)
        out_b = nk.nav_update(b, padded, p, t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw)
        assert _same(_flat(out_a), _flat(out_b))
    assert _same(a, b)
    with pytest.raises(ValueError):
        ns.mission_array(rec.mission, rows=1)


def test_the_comparison_sees_one_ulp(flights):
    """The replay check fails when one parameter of the kernel moves by one ulp (MPC_XY_P: the carrot, the
    approach cap and the line's braking)."""
    rec = flights["case0 seed1 (PX4 Vision, simple planner)"]
    params = dict(rec.params, MPC_XY_P=float(np.nextafter(rec.params["MPC_XY_P"], math.inf)))
    with pytest.raises(AssertionError):
        _assert_replay_equal(rec, params=params)


def test_compiled_navigator_flies_the_same_run(shared_data):
    """The run loop with CompiledNavigator in place of Navigator: the same true trajectory, bit for bit."""
    test, config = _rilast("random_run3_194"), load_profile("px4-v1.12-sitl-iris").sim_config()
    config = replace(config, timeout_s=40.0)
    with pytest.MonkeyPatch.context() as mp:
        fly_the_python_outer_loop(mp)  # the loop that calls runner.Navigator
        (a,) = simulate(test, runs=1, seed=0, config=config)
        mp.setattr(runner, "Navigator", nk.CompiledNavigator)
        (b,) = simulate(test, runs=1, seed=0, config=config)
    assert a.status == b.status and a.message == b.message
    assert np.array_equal(a.true_xyz, b.true_xyz) and np.array_equal(a.true_t, b.true_t)


# --- the flight task on its own ---------------------------------------------------------------------------------
@pytest.mark.parametrize("nav_acc_rad", [0.5, 2.0])
def test_task_kernel_equals_flight_task(nav_acc_rad):
    """Random legs: the vehicle wanders around the trajectory, the injected point jumps (turns, the speed lock)."""
    params = dict(PX4_DEFAULTS, NAV_ACC_RAD=nav_acc_rad)
    p = ns.param_vector(params)
    rng = np.random.default_rng(11)
    turning_seen = 0
    for _ in range(20):
        pos, vel = tuple((rng.normal(size=3) * 3).tolist()), tuple(rng.normal(size=3).tolist())
        prev, goal = tuple((rng.normal(size=3) * 10).tolist()), tuple((rng.normal(size=3) * 10).tolist())
        cruise = float(rng.uniform(1, 6))
        ref, state = AvoidanceFlightTask(params, cruise, pos, vel), np.zeros(ns.N_STATE)
        fk.task_start(state, cruise, pos, vel)
        setpoint = tuple((rng.normal(size=3) * 5).tolist())
        for _ in range(100):
            if rng.uniform() < 0.1:
                setpoint = tuple((rng.normal(size=3) * 5).tolist())
            pos = tuple((np.array(ref.pos) + rng.normal(size=3) * 0.3).tolist())
            expected = ref.update(0.02, pos, setpoint, prev, goal)
            got = fk.task_update(state, p, 0.02, pos, setpoint, prev, goal)
            assert _same([*got[0], *got[1], *got[2]], [*expected[0], *expected[1], *expected[2]])
            assert bool(state[ns.S_TASK_TURNING]) == ref.turning
            assert state[ns.S_TASK_MAX_SPEED_PREV] == ref.max_speed_prev
            assert fk.task_target(p, pos, prev, goal) == tuple(ref.target(pos, prev, goal))
            turning_seen += ref.turning
    assert turning_seen > 0


# --- CPython's arithmetic -------------------------------------------------------------------------------------------
def _random_floats(n, seed):
    rng = np.random.default_rng(seed)
    return (rng.normal(size=n) * np.exp(rng.normal(size=n) * 3)).tolist()


def test_py_hypot_is_cpythons():
    xs, ys = _random_floats(100_000, 1), _random_floats(100_000, 2)
    assert all(cm.py_hypot(x, y) == math.hypot(x, y) for x, y in zip(xs, ys))
    small = np.random.default_rng(3).normal(size=(50_000, 2)) * [1.0, 1e-3]  # the navigator's typical arguments
    assert all(cm.py_hypot(x, y) == math.hypot(x, y) for x, y in small.tolist())
    specials = [(0.0, 0.0), (-0.0, 3.0), (3.0, 4.0), (5e-324, 5e-324), (1e308, 1e308), (math.inf, math.nan),
                (math.nan, 1.0), (-math.inf, 2.0)]
    assert _same([cm.py_hypot(x, y) for x, y in specials], [math.hypot(x, y) for x, y in specials])


def test_py_remainder_is_cpythons():
    xs = _random_floats(50_000, 4)
    two_pi = 2 * math.pi
    assert all(cm.py_remainder(x, two_pi) == math.remainder(x, two_pi) for x in xs)
    halfway = [(3.0, 2.0), (5.0, 2.0), (-3.0, 2.0), (math.pi, two_pi), (-math.pi, two_pi), (0.0, two_pi),
               (-0.0, two_pi), (7.5, 1.0)]
    got = [cm.py_remainder(x, y) for x, y in halfway]
    assert _same(got, [math.remainder(x, y) for x, y in halfway])
    assert [math.copysign(1.0, g) for g in got] == [math.copysign(1.0, math.remainder(x, y)) for x, y in halfway]


def test_py_square_is_cpythons_power():
    """CPython's ``x ** 2`` is libm's pow, which rounds some squares differently from ``x * x``; the kernel calls
    pow."""
    xs = _random_floats(200_000, 5)
    p = ns.param_vector(PX4_DEFAULTS)
    assert any(x * x != x ** 2 for x in xs)  # the case this guards against occurs
    assert all(ns.py_square(x, p) == x ** 2 for x in xs)


def test_line_projection_is_geometrys():
    rng = np.random.default_rng(6)
    for px, py, ax, ay, bx, by in (rng.normal(size=(2000, 6)) * 10).tolist() + [[1.0, 2.0, 3.0, 3.0, 3.0, 3.0005]]:
        ok, s, cx, cy = ns.line_projection(px, py, ax, ay, bx, by)
        ref = line_projection(px, py, (ax, ay), (bx, by))
        assert (ref is None and not ok) or (ok and (s, cx, cy) == ref)


def test_parameter_vector_and_phase_codes():
    p = ns.param_vector(PX4_DEFAULTS, start_time=15.0, takeoff_hold_s=2.0)
    assert p.shape == (ns.N_PARAMS,)
    assert [p[ns.PARAM_NAMES.index(name)] for name in ns.PARAM_NAMES] == [PX4_DEFAULTS[n] for n in ns.PARAM_NAMES]
    assert p[ns.P_START_TIME] == 15.0 and p[ns.P_TAKEOFF_HOLD_S] == 2.0
    assert p[ns.P_YAW_RATE_RAD] == math.radians(PX4_DEFAULTS["MPC_YAWRAUTO_MAX"])
    assert [ns.PHASES[i] for i in (ns.PH_IDLE, ns.PH_CRUISE, ns.PH_DONE)] == [Phase.IDLE, Phase.CRUISE, Phase.DONE]
    state = ns.initial_state(p)
    assert ns.phase_of(state) == Phase.IDLE and ns.nav_index(state) == -1 and ns.nav_cruise(state) == p[0]
