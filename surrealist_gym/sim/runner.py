"""The run loop: fly the runs of one test case in one PyBullet world and report each run.

Rates (SimConfig): PyBullet integrates at ``physics_hz``; attitude/rate loops and motors run at ``control_hz``
(one ``stepSimulation`` of physics_hz / control_hz sub-steps each); estimator, navigator and position/velocity
control at ``outer_hz``; depth sensor and avoidance planner at ``planner_hz``; recorded local position at
``log_hz``. The runs of a batch are independent bodies in one world (no vehicle-vehicle collisions), each with its
own controllers, planner and noise, so run ``i`` flies exactly as it would alone (see the tests).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Mapping

import numpy as np

from ..errors import FrozenDict, SimulationError
from ..geometry import competition_distance, obstacle_distances
from ..mission import Command
from ..outcomes import RunStatus
from ..trajectory import Trajectory
from . import run_end
from .compiled.loop import compiling, fly_kernel
from .config import Physics, SimConfig, auto_timeout, resolve_params
from .navigation.navigator import Navigator, Phase
from .sensing.noise import NoiseSource, run_seed_sequence
from .vehicle.airframe import GRAVITY, preset
from .vehicle.compiled_physics import CompiledWorld, fly
from .vehicle.control import inner_step, kernel_params, position_params, position_step
from .vehicle.pybullet_quiet import pb
from .vehicle.world import World

if TYPE_CHECKING:
    from .avoidance.planner import Planner
    from .sensing.sensor import DepthSensor


@dataclass(frozen=True, slots=True)
class Clearance:
    """Closest approach to one obstacle: 3-D and 2-D (footprint) distances [m] and when [s since arming]."""

    obstacle: int
    distance: float
    time: float
    distance_2d: float
    time_2d: float


@dataclass(frozen=True, slots=True, eq=False)
class LocalPosition:
    """Recorded ``vehicle_local_position`` samples (NED, origin at the start position), as a ULog holds them."""

    timestamp_us: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    vz: np.ndarray
    heading: np.ndarray

    def __post_init__(self):
        for name in self.__slots__:
            arr = np.array(getattr(self, name), dtype=np.int64 if name == "timestamp_us" else np.float64)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)


@dataclass(frozen=True, slots=True, eq=False)
class RunResult:
    """The outcome of one simulated run.

    Attributes:
        trajectory: the recorded local position through the paper's pipeline (x north, y east, z up, 0.5 s means).
        status: how the run ended. message: a one-line description of the end.
        min_distance / min_distance_2d: smallest 3-D / 2-D distance from the vehicle's centre to any obstacle
            [m] (inf without obstacles), from ``true_xyz`` with :func:`~surrealist_gym.geometry.obstacle_distances`.
        competition_distance: the competition's (Aerialist's) distance of the run [m]: Aerialist's distance on
            Aerialist's trajectory of the logged samples (:meth:`~surrealist_gym.trajectory.Trajectory.aerialist`,
            :func:`~surrealist_gym.geometry.competition_distance`), its polyline buffered by
            ``SimConfig.competition_buffer_m``; inf without obstacles. Every command's competition distance of a
            simulated run is this one.
        clearances: per-obstacle closest approach.
        duration: simulated time from arming to the end of the run [s].
        seed, index: base seed and run index (the run's seed derives from them and the test's key).
        local_position: the recorded estimated local position (what a ULog holds), ``SimConfig.log_hz``.
        true_t, true_xyz: true positions at the outer-loop rate [s], [m] (x north, y east, z up above the ground).
        params: the PX4 parameters the run used.
    """

    trajectory: Trajectory
    status: RunStatus
    min_distance: float
    min_distance_2d: float
    competition_distance: float
    clearances: tuple[Clearance, ...]
    duration: float
    seed: int
    index: int
    local_position: LocalPosition
    true_t: np.ndarray
    true_xyz: np.ndarray
    message: str = ""
    params: Mapping[str, float] = field(default_factory=dict)


class _Run:
    """Mutable per-vehicle state inside the loop."""

    __slots__ = ("body", "pp", "ps", "kp", "ks", "wind", "armed", "integ", "nav", "planner", "noise", "q_sp", "thrust",
                 "status", "message", "end_t", "log", "true", "plan_out", "anchor", "anchor_t", "anchor_phase",
                 "ground", "active", "index", "held")


def simulate(test, runs: int = 5, seed: int = 0, config: SimConfig | None = None) -> list[RunResult]:
    """Fly ``runs`` runs of a test case; run ``i`` draws its noise from (test.key(), seed, i), or from (seed, i)
    alone with ``config.common_noise``.

    Args:
        test: a :class:`~surrealist_gym.testcase.TestCase` with a mission.
        runs: number of runs (flown together in one world).
        seed: base seed.
        config: simulator configuration (default: the test's UAV, as
            :func:`~surrealist_gym.sim.uav.decide_uav` decides).

    Returns:
        One :class:`RunResult` per run, in run order.

    Example::

        >>> import surrealist_gym as sg
        >>> test = sg.load_test(sg.data_path("rq1-seed1.yaml"))     # doctest: +SKIP
        >>> [r.status.value for r in sg.simulate(test, runs=2)]       # doctest: +SKIP
        ['success', 'success']
    """
    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    if config is None:
        from .uav import decide_uav
        config = decide_uav(test).config
    return simulate_runs(test, range(runs), seed, config)


def simulate_runs(test, indices, seed: int = 0, config: SimConfig | None = None) -> list[RunResult]:
    """Fly the runs with the given indices of a test case together (see :func:`simulate`)."""
    if (config or SimConfig()).physics == Physics.PYBULLET:
        return _simulate_runs(test, indices, seed, config)
    with compiling():  # the first simulation of an install compiles the loop, and says so
        return _simulate_runs(test, indices, seed, config)


def _simulate_runs(test, indices, seed: int, config: SimConfig | None) -> list[RunResult]:
    from .uav import flown_config

    cfg = flown_config(config or SimConfig(), test)  # the test's uav.* params
    indices = [int(i) for i in indices]
    mission = test.mission
    if mission is None or not any(it.has_position for it in mission.items):
        raise SimulationError("test case: the mission has no item with a position to fly to")
    params = resolve_params(test, cfg)
    avoidance = bool(params["COM_OBS_AVOID"]) if cfg.avoidance is None else cfg.avoidance
    vehicle = preset(cfg.vehicle)
    timeout = cfg.timeout_s if cfg.timeout_s is not None else auto_timeout(mission)
    if test.timeout is not None:  # the test's own limit (Aerialist's simulation.timeout) ends it sooner
        timeout = min(timeout, test.timeout)
    outer_dt = 1.0 / cfg.outer_hz
    plan_div = int(round(cfg.outer_hz / cfg.planner_hz))
    noise_key = "" if cfg.common_noise else test.key()
    # PX4's hover thrust estimator (MPC_USE_HTE=1, the default) converges within seconds of the takeoff; it is
    # modelled as converged: the controller's hover thrust is the vehicle's physical one.
    ctl_params = dict(params, MPC_THR_HOVER=vehicle.hover_command) if params.get("MPC_USE_HTE", 1) else params
    world_type = World if cfg.physics == Physics.PYBULLET else CompiledWorld
    with world_type(test.obstacles, vehicle, len(indices), cfg.physics_hz, cfg.control_hz,
                    cfg.obstacle_collision_scale) as world:
        sensor = None
        if avoidance:
            sensor, make_planner = _avoidance(test, cfg, params)
        yaw0 = initial_yaw(mission)
        runs = []
        for body, index in zip(world.vehicles, indices):
            r = _Run()
            r.body, r.index = body, index
            r.pp, r.ps = position_params(ctl_params), np.zeros(10)
            r.kp = kernel_params(params, vehicle, 1.0 / cfg.control_hz,
                                 (vehicle.drag_xy, vehicle.drag_z, vehicle.drag_quad))
            r.ks = np.zeros(10)
            r.wind = (0.0, 0.0, 0.0)
            r.noise = NoiseSource(run_seed_sequence(noise_key, seed, index), cfg.noise, test.wind, outer_dt,
                                  plan_div, cfg.takeoff_delay_s)
            r.nav = Navigator(mission, params, cfg.takeoff_delay_s + r.noise.start_offset, cfg.takeoff_hold_s)
            r.planner = make_planner() if avoidance else None
            r.q_sp, r.thrust = (math.cos(yaw0 / 2), 0.0, 0.0, math.sin(yaw0 / 2)), 0.0
            r.status, r.message, r.end_t = None, "", 0.0
            r.log, r.true, r.plan_out = [], [], None
            r.anchor, r.anchor_t, r.anchor_phase = None, 0.0, None
            r.ground, r.active, r.armed, r.integ, r.held = True, True, True, False, True
            world.set_yaw(body, yaw0)
            runs.append(r)
        if world_type is World:
            _loop(world, runs, cfg, params, vehicle, sensor, timeout)
        else:
            _fly_compiled(world, runs, cfg, sensor, timeout, mission, params)
    return [_result(r, test, cfg, params, seed) for r in runs]


def _avoidance(test, cfg: SimConfig, params) -> tuple[DepthSensor, Callable[[], Planner]]:
    """The depth sensor and a factory of per-run planners (:class:`~surrealist_gym.sim.avoidance.planner.Planner`) for
    the configured avoidance model; the run loop calls their ``step`` and does not care which planner flies."""
    from .config import AvoidanceModel
    from .sensing.sensor import DepthSensor, DepthSensorConfig

    if cfg.avoidance_model == AvoidanceModel.PX4:
        from .avoidance.px4.local_planner import Px4AvoidanceConfig, Px4LocalPlanner
        from .profiles import SITL_IRIS

        sensor = DepthSensor(test.obstacles, cfg.sensor_config or SITL_IRIS.sensor_config())
        plan_cfg = cfg.avoidance_config or Px4AvoidanceConfig()
        return sensor, lambda: Px4LocalPlanner(plan_cfg, params["MPC_XY_CRUISE"], params["MPC_ACC_HOR"],
                                               params["MPC_JERK_MAX"])
    from .avoidance.reactive import AvoidanceConfig, LocalPlanner

    sensor = DepthSensor(test.obstacles, cfg.sensor_config or DepthSensorConfig())
    plan_cfg = cfg.avoidance_config or AvoidanceConfig()
    return sensor, lambda: LocalPlanner(plan_cfg)


def initial_yaw(mission) -> float:
    """Heading of the vehicle on the ground: toward the first position that is not straight above home."""
    for it in mission.items:
        if it.has_position and it.command != Command.TAKEOFF and math.hypot(it.x, it.y) > 1.0:
            return math.atan2(it.y, it.x)
    return 0.0


def _loop(world: World, runs: list[_Run], cfg: SimConfig, params, vehicle, sensor, timeout: float) -> None:
    cid = world.cid
    dt = 1.0 / cfg.control_hz
    outer_div = int(round(cfg.control_hz / cfg.outer_hz))
    log_div = int(round(cfg.outer_hz / cfg.log_hz))
    outer_dt = outer_div * dt
    rest_z = world.rest_z
    inner = inner_step
    obstacle_index = world.obstacle_index
    body_run = {r.body: r for r in runs}
    get_pose, get_vel = pb.getBasePositionAndOrientation, pb.getBaseVelocity
    apply_force, apply_torque, frame = pb.applyExternalForce, pb.applyExternalTorque, pb.WORLD_FRAME
    step_sim, contacts = pb.stepSimulation, pb.getContactPoints
    stuck_w, stuck_d = cfg.stuck_window_s, cfg.stuck_distance_m
    weight = vehicle.mass * GRAVITY
    rest = {r.body: get_pose(r.body, physicsClientId=cid) for r in runs}  # each vehicle's pose on the ground
    reset_pose, reset_vel, still = pb.resetBasePositionAndOrientation, pb.resetBaseVelocity, (0.0, 0.0, 0.0)
    active = list(runs)
    step = 0
    max_steps = int(math.ceil(timeout * cfg.control_hz))
    done = False
    while active:
        outer = step % outer_div == 0
        k = step // outer_div
        t = step * dt
        for r in active:
            body = r.body
            pos, orn = get_pose(body, physicsClientId=cid)
            lin, ang = get_vel(body, physicsClientId=cid)
            if outer and not _outer(r, k, t, pos, lin, orn, outer_dt, log_div, rest_z, sensor, stuck_w,
                                    stuck_d):
                done = True
                continue
            fx, fy, fz, tx, ty, tz = inner(orn, lin, ang, r.q_sp, r.thrust, r.wind, dt, r.armed, r.integ, r.kp,
                                           r.ks)
            if r.held and -fz > weight:
                r.held = False  # the thrust lifts it: from here the physics flies it
            apply_force(body, -1, (fx, fy, fz), pos, frame, physicsClientId=cid)
            apply_torque(body, -1, (tx, ty, tz), frame, physicsClientId=cid)
        step_sim(physicsClientId=cid)
        step += 1
        for c in contacts(physicsClientId=cid):
            a, b = c[1], c[2]
            r = body_run.get(a)
            other = b
            if r is None:
                r, other = body_run.get(b), a
            if r is None or not r.active:
                continue
            if other in obstacle_index:
                r.status, r.end_t, done = RunStatus.COLLISION, step * dt, True
                r.message = run_end.collided(obstacle_index[other], step * dt)
            else:
                r.ground = True
        for r in active:
            if r.held:  # resting on the ground until the thrust first lifts it: held at its starting pose
                reset_pose(r.body, *rest[r.body], physicsClientId=cid)
                reset_vel(r.body, still, still, physicsClientId=cid)
        if step >= max_steps:
            done = True
            for r in active:
                if r.status is None:
                    r.status, r.end_t = RunStatus.TIMEOUT, step * dt
                    r.message = run_end.timed_out(timeout, r.nav.phase.value)
        if not done:
            continue
        done = False
        for r in [r for r in active if r.status is not None]:
            r.active = False
            _record(r, r.end_t, *get_pose(r.body, physicsClientId=cid), *get_vel(r.body, physicsClientId=cid),
                    rest_z, k)
            world.remove(r.body)
            active.remove(r)


def _fly_compiled(world: CompiledWorld, runs: list[_Run], cfg: SimConfig, sensor, timeout: float, mission,
                  params) -> None:
    """The compiled loop (:func:`~surrealist_gym.sim.compiled.loop.fly_kernel`): everything in kernels."""
    fly_kernel(world, runs, cfg, sensor, timeout, mission, params)


def _fly_compiled_outer(world: CompiledWorld, runs: list[_Run], cfg: SimConfig, sensor, timeout: float, mission,
                        params) -> None:
    """The reference of :func:`_fly_compiled` (the same results bit for bit, tests/.../test_compiled_loop): the
    Python :func:`_outer` per outer period, :func:`~surrealist_gym.sim.vehicle.compiled_physics.advance` for the
    rest."""
    outer_dt = int(round(cfg.control_hz / cfg.outer_hz)) * (1.0 / cfg.control_hz)  # as _loop's
    log_div = int(round(cfg.outer_hz / cfg.log_hz))
    rest_z, stuck_w, stuck_d = world.rest_z, cfg.stuck_window_s, cfg.stuck_distance_m

    def outer(r, k, t, pos, lin, orn):
        return _outer(r, k, t, pos, lin, orn, outer_dt, log_div, rest_z, sensor, stuck_w, stuck_d)

    def record(r, t, pos, orn, lin, ang, k):
        _record(r, t, pos, orn, lin, ang, rest_z, k)

    fly(world, runs, cfg, timeout, outer, record)


def _outer(r: _Run, k, t, pos, lin, orn, outer_dt, log_div, rest_z, sensor, stuck_w, stuck_d) -> bool:
    """Estimator, planner, navigator, position control and bookkeeping; False when the run ended."""
    nav = r.nav
    noise = r.noise
    pe, ve, yaw_err, r.wind = noise.at(k)
    qx, qy, qz, qw = orn
    yaw = math.atan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz)) + yaw_err
    if not (math.isfinite(pos[0]) and math.isfinite(pos[2])) or 1 - 2 * (qx * qx + qy * qy) < -0.1:
        r.status, r.end_t = RunStatus.ERROR, t
        r.message = run_end.invalid(t)
        return False
    ex, ey, ez = pos[0] + pe[0], pos[1] + pe[1], pos[2] - rest_z + pe[2]
    evx, evy, evz = lin[0] + ve[0], lin[1] + ve[1], lin[2] + ve[2]
    pos_up, vel_up = (ex, ey, -ez), (evx, evy, -evz)
    r.true.append((t, pos[0], pos[1], -pos[2]))
    if k % log_div == 0:
        r.log.append((t, ex, ey, ez, evx, evy, evz, yaw))
    plan = None
    if r.planner is not None and nav.uses_planner:
        if noise.plans(k) or r.plan_out is None:
            hits = sensor.scan((pos[0], pos[1], -pos[2]), yaw, r.noise.rng)
            if len(hits):
                hits = hits + np.array([pe[0], pe[1], -(pe[2])])
            r.plan_out = r.planner.step(t, pos_up, vel_up, yaw, nav.goal(), nav.prev, hits, nav.cruise)
        plan = r.plan_out
    pos_sp, vel_ff, acc_ff, yaw_sp = nav.update(t, pos_up, vel_up, yaw, outer_dt, r.ground, plan)
    r.ground = False  # collects the contacts of the next outer period
    if nav.mission_complete:
        r.status, r.end_t = RunStatus.SUCCESS, t
        r.message = run_end.finished(nav.phase == Phase.DONE, t)
        return False
    r.armed, r.integ = nav.armed, not nav.on_ground_phase
    if nav.on_ground_phase:
        r.ps[:] = 0.0
        r.thrust = 0.0
        r.q_sp = (math.cos(yaw_sp / 2), 0.0, 0.0, math.sin(yaw_sp / 2))
    else:
        qw, qx, qy, qz, r.thrust = position_step((ex, ey, ez), (evx, evy, evz), pos_sp, vel_ff, acc_ff, yaw_sp,
                                                 outer_dt, r.pp, r.ps)
        r.q_sp = (qw, qx, qy, qz)
    # stuck: the distance to the current goal has not shrunk by stuck_d during the last stuck_w seconds
    if stuck_w is not None and nav.phase in (Phase.CRUISE, Phase.TAKEOFF, Phase.CLIMB, Phase.DESCEND):
        g = nav.target
        gz = 0.0 if nav.phase == Phase.DESCEND else g[2]
        d = math.sqrt((g[0] - pos[0]) ** 2 + (g[1] - pos[1]) ** 2 + (gz + pos[2]) ** 2)
        if r.anchor is None or r.anchor_phase != (nav.phase, nav.index) or d < r.anchor - stuck_d:
            r.anchor, r.anchor_t, r.anchor_phase = d, t, (nav.phase, nav.index)
        elif t - r.anchor_t > stuck_w:
            r.status, r.end_t = RunStatus.STUCK, t
            r.message = run_end.stuck(stuck_d, stuck_w, nav.phase.value, t)
            return False
    else:
        r.anchor = None
    return True


def _record(r: _Run, t, pos, orn, lin, ang, rest_z, kk) -> None:
    pe, ve = r.noise.at(kk)[:2]
    qx, qy, qz, qw = orn
    yaw = math.atan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz))
    if not r.log or r.log[-1][0] < t:
        r.log.append((t, pos[0] + pe[0], pos[1] + pe[1], pos[2] - rest_z + pe[2], lin[0] + ve[0], lin[1] + ve[1],
                      lin[2] + ve[2], yaw))
    if not r.true or r.true[-1][0] < t:
        r.true.append((t, pos[0], pos[1], -pos[2]))


def _result(r: _Run, test, cfg: SimConfig, params, seed: int) -> RunResult:
    log = np.array(r.log, dtype=np.float64)
    ts = np.round(log[:, 0] * 1e6).astype(np.int64)
    lp = LocalPosition(ts, log[:, 1], log[:, 2], log[:, 3], log[:, 4], log[:, 5], log[:, 6], log[:, 7])
    traj = Trajectory.from_local_position(ts, lp.x, lp.y, lp.z, lp.heading)
    true = np.array(r.true, dtype=np.float64)
    true_t, true_xyz = true[:, 0], true[:, 1:4]
    clearances = []
    if test.obstacles:
        d3 = obstacle_distances(true_xyz, test.obstacles, dims=3)
        d2 = obstacle_distances(true_xyz, test.obstacles, dims=2)
        for j in range(len(test.obstacles)):
            i3, i2 = int(np.argmin(d3[:, j])), int(np.argmin(d2[:, j]))
            clearances.append(Clearance(j, float(d3[i3, j]), float(true_t[i3]), float(d2[i2, j]), float(true_t[i2])))
    min3 = min((c.distance for c in clearances), default=math.inf)
    min2 = min((c.distance_2d for c in clearances), default=math.inf)
    true_t.setflags(write=False)
    true_xyz = np.ascontiguousarray(true_xyz)
    true_xyz.setflags(write=False)
    compet = math.inf
    if test.obstacles and len(ts):  # on Aerialist's windows, as its get_distances() on the run's ULog
        compet = competition_distance(Trajectory.aerialist(ts, lp.x, lp.y, lp.z, lp.heading), test.obstacles,
                                      cfg.competition_buffer_m)
    return RunResult(trajectory=traj, status=r.status, min_distance=min3, min_distance_2d=min2,
                     competition_distance=compet, clearances=tuple(clearances), duration=float(r.end_t),
                     seed=int(seed), index=r.index, local_position=lp, true_t=true_t, true_xyz=true_xyz,
                     message=r.message, params=FrozenDict(dict(params)))
