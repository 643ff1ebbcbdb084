"""The PX4-Avoidance model: its kernels against direct computations, memory, tree, waypoint generator, flight task."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from surrealist_gym import load_test
from surrealist_gym.sim import simulate
from surrealist_gym.sim.avoidance.px4 import local_planner as px4_avoidance
from surrealist_gym.sim.avoidance.px4.cloud import atan2_deg, hist_index
from surrealist_gym.sim.avoidance.px4.expansion import cell_index, mod360
from surrealist_gym.sim.avoidance.px4.local_planner import Px4AvoidanceConfig, Px4LocalPlanner, kernel_settings
from surrealist_gym.sim.avoidance.px4.settings import ALPHA_RES, MAX_NODES, N_E, N_Z, KernelSettings
from surrealist_gym.sim.avoidance.px4.tree import tree_work
from surrealist_gym.sim.config import PX4_DEFAULTS
from surrealist_gym.sim.navigation.flight_task import AvoidanceFlightTask, stopping_speed
from surrealist_gym.sim.profiles import SITL_IRIS, load_profile
from surrealist_gym.sim.reference.px4_tree import build_tree_reference, smooth_columns, smooth_row
from surrealist_gym.sim.sensing.sensor import DepthSensor
from surrealist_gym.testcase import Obstacle
from tests.conftest import CASE_STUDIES, SHARED_DATA, fly_the_python_outer_loop

CAMERA = SITL_IRIS.sensor_config()
RILAST = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"


def _direct_smoothing(matrix: np.ndarray, r: int) -> np.ndarray:
    """smoothPolarMatrix written out: polar padding, then the conic kernel in elevation and azimuth."""
    ne, nz = matrix.shape
    kernel = np.array([max(0.0, 1.0 + r - abs(i - r)) for i in range(2 * r + 1)])
    kernel /= kernel.max()
    padded = np.zeros((ne + 2 * r, nz + 2 * r))
    padded[r:r + ne, r:r + nz] = matrix
    for i in range(r):
        for z in range(nz):
            padded[r - 1 - i, r + z] = matrix[i, (z + nz // 2) % nz]
            padded[r + ne + i, r + z] = matrix[ne - 1 - i, (z + nz // 2) % nz]
    padded[:, :r] = padded[:, nz:nz + r]
    padded[:, r + nz:] = padded[:, r:2 * r]
    rows = padded.copy()
    for z in range(nz + 2 * r):
        for e in range(ne):
            rows[e + r, z] = (padded[e:e + 2 * r + 1, z] * kernel).sum()
    out = np.zeros_like(matrix)
    for e in range(ne):
        for z in range(nz):
            out[e, z] = (rows[r + e, z:z + 2 * r + 1] * kernel).sum()
    return out


def test_running_sum_smoothing_equals_the_conic_kernel():
    rng = np.random.default_rng(3)
    matrix = rng.random((N_E, N_Z)) * (rng.random((N_E, N_Z)) < 0.15) * 1e4
    matrix[0, 5] = matrix[N_E - 1, 40] = 9000.0  # cells at the poles exercise the padding
    expected = _direct_smoothing(matrix, 7)
    got = matrix.copy()
    padded, box = np.empty((N_E + 14, N_Z + 14)), np.empty(N_Z + 14)
    smooth_columns(got, 7, padded, box)  # the planner smooths the columns, then each row it visits
    for e in range(N_E):
        smooth_row(padded, 7, e, box, got[e])
    assert np.abs(got - expected).max() < 1e-6 * expected.max()


def test_fast_atan2_is_within_a_ten_thousandth_of_a_degree():
    rng = np.random.default_rng(0)
    worst = max(abs(atan2_deg(y, x) - math.degrees(math.atan2(y, x))) for y, x in rng.normal(size=(20000, 2)))
    assert worst < 1e-4


def test_branch_free_cell_index_and_modulo_are_the_kernels_bits():
    """build_tree's vectorizable pieces against the operations they replace: the flat cell of hist_index (random
    directions, cell boundaries, the axes, the origin) and Python's ``% 360.0`` on its range (-360, 720)."""
    rng = np.random.default_rng(5)
    dirs = [tuple(v) for v in rng.normal(size=(20000, 3)) * rng.choice([1e-3, 1.0, 30.0], size=(20000, 1))]
    for az in np.arange(-180.0, 181.0, ALPHA_RES):  # on the azimuth boundaries, level and tilted
        for el in (-90.0, -48.0, 0.0, 6.0, 90.0):
            dirs.append((math.cos(math.radians(el)) * math.cos(math.radians(az)),
                         math.cos(math.radians(el)) * math.sin(math.radians(az)), math.sin(math.radians(el))))
    dirs += [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -2.0), (-0.0, 0.0, 1.0)]
    for d in dirs:
        ie, iz = hist_index(*d, ALPHA_RES)
        assert cell_index(*d) == ie * N_Z + iz, d
    xs = np.concatenate([rng.uniform(-360.0, 720.0, 20000), [-359.9999, -1e-300, -0.0, 0.0, 359.99999, 360.0, 719.9]])
    for x in xs:
        want, got = x % 360.0 - 180.0, mod360(x) - 180.0
        assert got == want, x


def _rilast(test_id: str):
    with open(RILAST, newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["test_id"] == test_id)
    obstacles = [Obstacle(**o) for o in json.loads(row["obstacles"])]
    return load_test(CASE_STUDIES / "mission1.yaml").with_obstacles(obstacles)


@pytest.mark.filterwarnings("ignore:.*is not supported")
def test_tree_kernel_gives_the_reference_paths_on_a_recorded_flight(monkeypatch):
    """Every look-ahead tree build of a flight (mission1 + rilast random_run3_194, SITL Iris: ~260 builds, 180 points
    on average, up to ~500) replayed through the sparse build_tree, with one planner's reused buffers and with its
    own, and through the dense build_tree_reference: the same paths, bit for bit."""
    if not RILAST.is_file():
        pytest.skip("no rilast-mission1 tests in ../shared/data")
    calls, build = [], px4_avoidance.build_tree

    def recording(cloud, *args):
        calls.append((cloud.copy(), *args[:-1]))
        return build(cloud, *args)

    monkeypatch.setattr(px4_avoidance, "build_tree", recording)
    fly_the_python_outer_loop(monkeypatch)
    simulate(_rilast("random_run3_194"), runs=1, seed=0, config=load_profile("px4-v1.12-sitl-iris").sim_config())
    monkeypatch.undo()
    assert len(calls) > 100
    work = tree_work(calls[0][5])
    want, got, own = np.empty((MAX_NODES, 3)), np.empty((MAX_NODES, 3)), np.empty((MAX_NODES, 3))
    lengths = []
    for args in calls:
        k = build_tree_reference(*args, want)
        assert build(*args, got, work) == k and build(*args, own) == k
        assert np.array_equal(got[:k], want[:k]) and np.array_equal(own[:k], want[:k])
        lengths.append(k)
    assert max(lengths) >= 5  # real trees, not only the vehicle


def test_stopping_speed_is_trajmath():
    # 1/2 (-b + sqrt(b^2 + 8 a d)), b = 4 a^2 / j with MPC_ACC_HOR 3, MPC_JERK_AUTO 4 (PX4-AVOIDANCE.md section 4)
    assert [round(stopping_speed(4.0, 3.0, d), 2) for d in (0.5, 1, 2, 3, 5)] == [0.32, 0.62, 1.18, 1.68, 2.59]


def test_nothing_in_view_flies_direct_with_the_speed_low_pass():
    planner = Px4LocalPlanner(Px4AvoidanceConfig())
    outs = [planner.update(0.1 * k, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), math.pi / 2, (0.0, 50.0, 10.0),
                           (0.0, 0.0, 10.0), np.empty((0, 3))) for k in range(1, 11)]
    assert all(o.state == "direct" for o in outs)
    speeds = [o.speed for o in outs]
    assert speeds == sorted(speeds) and 0 < speeds[0] < 0.6 and speeds[-1] < 5.0  # 0.9 s low-pass toward 5 m/s
    assert outs[-1].position[1] > 0.1 and abs(outs[-1].position[0]) < 1e-6


def test_goal_outside_the_field_of_view_stops_the_advance():
    # facing north, the goal due south: scaleToFOV gives 0, so the setpoint stays where the vehicle is
    planner = Px4LocalPlanner(Px4AvoidanceConfig())
    out = None
    for k in range(1, 11):
        out = planner.update(0.1 * k, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 0.0, (-50.0, 0.0, 10.0), (0.0, 0.0, 10.0),
                             np.empty((0, 3)))
    assert out.speed == 0.0 and math.dist(out.position, (0.0, 0.0, 10.0)) < 1e-9


def test_heading_offset_turns_the_yaw_setpoint_and_slows_the_advance():
    """The yaw setpoint is the course plus heading_offset_deg; a vehicle that holds it sees its course 16 deg off the
    camera axis, and scaleToFOV scales the speed by 1 - 2 * 16 / 59."""
    east, goal = math.pi / 2, (0.0, 50.0, 10.0)
    straight = Px4LocalPlanner(Px4AvoidanceConfig())
    crabbed = Px4LocalPlanner(Px4AvoidanceConfig(heading_offset_deg=-16.0))
    for k in range(1, 101):
        a = straight.update(0.1 * k, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), east, goal, (0.0, 0.0, 10.0), np.empty((0, 3)))
        b = crabbed.update(0.1 * k, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), east - math.radians(16.0), goal,
                           (0.0, 0.0, 10.0), np.empty((0, 3)))
    assert abs(a.yaw - east) < 1e-6
    assert math.degrees(b.yaw - east) == pytest.approx(-16.0, abs=1e-6)
    assert a.speed == pytest.approx(5.0, rel=1e-3)
    assert b.speed == pytest.approx(5.0 * (1.0 - 32.0 / 59.0), rel=1e-3)
    with pytest.raises(ValueError, match="heading_offset_deg"):
        Px4AvoidanceConfig(heading_offset_deg=120.0)


def test_a_wall_ahead_builds_a_tree_that_goes_around_it():
    wall = Obstacle(l=4.0, w=10.0, h=20.0, x=12.0, y=1.0)  # across the path 10-14 m north, from y -4 to 6
    sensor = DepthSensor([wall], CAMERA)
    planner = Px4LocalPlanner(Px4AvoidanceConfig())
    hits = sensor.scan((0.0, 0.0, 10.0), 0.0)
    out = planner.update(0.1, (0.0, 0.0, 10.0), (1.0, 0.0, 0.0), 0.0, (40.0, 0.0, 10.0), (0.0, 0.0, 10.0), hits)
    assert out.state == "try_path" and len(out.path) >= 3
    assert out.path[0].tolist() == [0.0, 0.0, 10.0]
    end = out.path[-1]
    assert math.dist(out.path[1], out.path[0]) == pytest.approx(2.0, abs=1e-6)  # tree_node_distance
    assert end[1] < -4.0 or end[1] > 6.0 or end[0] < 10.0  # the path leaves the wall's shadow or stops before it
    # deterministic: the same inputs give the same path
    again = Px4LocalPlanner(Px4AvoidanceConfig()).update(0.1, (0.0, 0.0, 10.0), (1.0, 0.0, 0.0), 0.0,
                                                         (40.0, 0.0, 10.0), (0.0, 0.0, 10.0), hits)
    assert np.array_equal(again.path, out.path)


def test_kernel_settings_are_the_config_fields():
    config = Px4AvoidanceConfig(max_sensor_range=12, min_sensor_range=0.5, pitch_cost_param=20, yaw_cost_param=4.0,
                                velocity_cost_param=5000.0, obstacle_cost_param=7.5, tree_heuristic_weight=30.0,
                                max_point_age_s=10.0, smoothing_margin_degrees=31.0, children_per_node=6,
                                n_expanded_nodes=30, tree_node_distance=1.5, fov_h_deg=60.0, fov_v_deg=45.0)
    settings = kernel_settings(config)
    assert settings == KernelSettings(min_range=0.5, max_range=12.0, pitch_cost=20.0, yaw_cost=4.0,
                                      velocity_cost=5000.0, obstacle_cost=7.5, heuristic_weight=30.0,
                                      smoothing_radius=6, children=6, expansions=30, node_distance=1.5,
                                      max_point_age=10.0, fov_h=60.0, fov_v=45.0)  # radius: ceil(31 / 6) cells
    # a YAML's 12 and 20 reach the kernels as floats: one numba specialisation, the same flights
    assert all(type(v) is (int if f in ("smoothing_radius", "children", "expansions") else float)
               for f, v in settings._asdict().items())
    assert kernel_settings(Px4AvoidanceConfig()).smoothing_radius == 7  # the cfg's 40 deg


def test_a_planner_cycle_before_a_wall_gives_the_stored_path():
    """The tree's path in front of the wall as the kernels gave it when they took a parameter array (pins the
    kernels' behaviour, not only its shape): 2 m steps 3 deg down and 45 deg left, around the wall's west end."""
    wall = Obstacle(l=4.0, w=10.0, h=20.0, x=12.0, y=1.0)
    hits = DepthSensor([wall], CAMERA).scan((0.0, 0.0, 10.0), 0.0)
    planner = Px4LocalPlanner(Px4AvoidanceConfig(max_sensor_range=15))  # an int, as a YAML gives it
    outs = [planner.update(0.1 * k, (0.0, 0.0, 10.0), (1.0, 0.0, 0.0), 0.0, (40.0, 0.0, 10.0), (0.0, 0.0, 10.0), hits)
            for k in (1, 2, 3)]
    expected = [[0.0, 0.0, 10.0], [1.4122754318362525, -1.4122754318362523, 9.895328087514113],
                [2.5000606841287256, -3.087317829995638, 9.790656175028225],
                [3.756976542780057, -4.63947964984798, 9.895328087514113], [5.309138362632399, -5.89639550849931, 10.0]]
    for out in outs:
        assert out.state == "try_path" and out.points == 538 and out.speed == 0.0
        assert out.path == pytest.approx(np.array(expected), abs=1e-9)
    assert [o.yaw for o in outs] == pytest.approx([-0.07853981633974483, -0.1780925260562795, -0.2754131375177661],
                                                  abs=1e-12)
    assert outs[-1].position == pytest.approx((0.2673245553203368, 0.0, 10.0), abs=1e-12)


def test_memory_keeps_points_outside_the_view_and_forgets_those_in_view():
    box = Obstacle(l=2.0, w=2.0, h=20.0, x=6.0, y=0.0)
    hits = DepthSensor([box], CAMERA).scan((0.0, 0.0, 10.0), 0.0)
    planner = Px4LocalPlanner(Px4AvoidanceConfig())
    planner.update(0.1, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 0.0, (0.0, 40.0, 10.0), (0.0, 0.0, 10.0), hits)
    seen = len(planner.cloud)
    assert seen > 50
    # turned east: the box is outside the view and no new points arrive -> remembered
    planner.update(0.2, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), math.pi / 2, (0.0, 40.0, 10.0), (0.0, 0.0, 10.0),
                   np.empty((0, 3)))
    assert len(planner.cloud) == seen
    # back north with nothing returned (the box gone): points in view are dropped
    planner.update(0.3, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 0.0, (0.0, 40.0, 10.0), (0.0, 0.0, 10.0),
                   np.empty((0, 3)))
    assert len(planner.cloud) == 0
    # and a remembered point is forgotten after max_point_age_s
    short = Px4LocalPlanner(Px4AvoidanceConfig(max_point_age_s=0.5))
    short.update(0.1, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 0.0, (0.0, 40.0, 10.0), (0.0, 0.0, 10.0), hits)
    for k in range(2, 12):
        short.update(0.1 * k, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), math.pi / 2, (0.0, 40.0, 10.0), (0.0, 0.0, 10.0),
                     np.empty((0, 3)))
    assert len(short.cloud) == 0


def _fly_task(task, setpoint_of, steps=400, dt=0.02, prev=(0.0, 0.0, 10.0), goal=(0.0, 50.0, 10.0)):
    """Integrate the task with a vehicle that follows the trajectory exactly; return the speeds."""
    speeds = []
    pos = tuple(task.pos)
    for _ in range(steps):
        p, v, _ = task.update(dt, pos, setpoint_of(pos), prev, goal)
        pos = p
        speeds.append(math.hypot(v[0], v[1]))
    return speeds


def test_flight_task_stops_at_the_injected_setpoint_speed():
    params = dict(PX4_DEFAULTS, NAV_ACC_RAD=0.5)
    task = AvoidanceFlightTask(params, 5.0, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0))
    speeds = _fly_task(task, lambda pos: (pos[0], pos[1] + 2.0, 10.0))  # always 2 m ahead, along the line
    assert speeds[-1] == pytest.approx(stopping_speed(4.0, 3.0, 2.0), abs=0.05)
    assert not task.turning


def test_flight_task_locks_the_speed_while_turning_off_the_line():
    """Starting slowly away from the mission line, PX4 keeps the speed it had when it last was not turning."""
    params = dict(PX4_DEFAULTS, NAV_ACC_RAD=0.5)
    task = AvoidanceFlightTask(params, 5.0, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0))
    lead = [0.0]

    def setpoint(pos):  # a setpoint that grows from 0 to 3 m ahead, 60 deg off the line (toward north-east)
        lead[0] = min(3.0, lead[0] + 0.01)
        return (pos[0] + lead[0] * math.cos(math.radians(30)), pos[1] + lead[0] * math.sin(math.radians(30)), 10.0)

    speeds = _fly_task(task, setpoint, steps=1500)
    assert task.turning
    assert max(speeds[-500:]) < 0.5 < stopping_speed(4.0, 3.0, 3.0)  # locked near where it crossed 0.2 m/s
