"""The whole run loop of ``SimConfig(physics="compiled")`` as one numba kernel per run and noise block.

:func:`fly_span` flies one run over outer periods, doing per period what the runner's Python ``_outer`` followed by
:func:`~surrealist_gym.sim.vehicle.compiled_physics.advance` did, in the same order and with the same arithmetic: the
estimate (position, velocity and yaw errors, the wind) from the noise block, the flip check, the true-position and log
records, the depth scan (:func:`~surrealist_gym.sim.sensing.sensor.cast_scan`) and the planner cycle when due
(:func:`px4_cycle.cycle <surrealist_gym.sim.avoidance.px4.cycle.cycle>` or
:func:`reactive_cycle.cycle <surrealist_gym.sim.avoidance.reactive_cycle.cycle>`), the navigator
(:func:`~surrealist_gym.sim.navigation.navigator_kernels.nav_update`), position control or the ground phases, the stuck
check, then the control steps of the period with the ground hold, collisions and the time limit.

It returns to Python (:func:`fly_kernel`) with a stop code: :data:`BLOCK_END` (the next period needs the next noise
block, which Python draws with :meth:`NoiseSource.block <surrealist_gym.sim.sensing.noise.NoiseSource.block>`: the same
generators in the same order as the Python loop), :data:`NEED_SENSOR_NOISE` (fewer range-noise values left than a
scan takes: Python draws more from the run's sensor generator; ``standard_normal(n)`` draws concatenate exactly, so
drawing several scans' worth at once gives the same values) or :data:`ENDED` (the run ended: status, end time and
the obstacle or the phase for the message). The records are preallocated arrays that Python grows between calls.

The Python loop (``runner._fly_compiled_outer``) stays as the reference:
tests/surrealist_gym/sim/compiled/test_compiled_loop.py checks that both give the same results bit for bit.
"""
from __future__ import annotations

import math
import os
import sys
import threading
from contextlib import contextmanager

import numpy as np
from numba import njit, types
from numba.typed import Dict

from ...outcomes import RunStatus
from .. import run_end
from ..avoidance import reactive_cycle
from ..avoidance.px4 import cycle as px4_cycle
from ..avoidance.px4.settings import MAX_NODES
from ..avoidance.px4.tree import new_tree_work
from ..navigation.navigator_kernels import nav_update
from ..navigation.navigator_state import (
    PH_CLIMB,
    PH_CRUISE,
    PH_DESCEND,
    PH_DONE,
    PH_TAKEOFF,
    PHASES,
    PLAN_NONE,
    PLAN_POSITION,
    PLAN_VELOCITY,
    initial_state,
    mission_array,
    nav_armed,
    nav_cruise,
    nav_goal,
    nav_index,
    nav_mission_complete,
    nav_on_ground_phase,
    nav_phase,
    nav_prev,
    nav_target,
    param_vector,
    py_square,
)
from ..sensing.noise import NoiseSource
from ..sensing.sensor import cast_scan
from ..vehicle import rigid_body as rb
from ..vehicle.compiled_physics import advance
from ..vehicle.control import position_step
from ..vehicle.geometry_kernels import GROUND

__all__ = ["compiling", "fly_kernel", "fly_span"]

# stop codes
BLOCK_END, NEED_SENSOR_NOISE, ENDED = 0, 1, 2
# the planner flying the run
NO_PLANNER, SIMPLE_PLANNER, PX4_PLANNER = 0, 1, 2
# statuses (ENDED)
ST_SUCCESS, ST_COLLISION, ST_TIMEOUT, ST_STUCK, ST_ERROR = 1, 2, 3, 4, 5
_STATUS = {ST_SUCCESS: RunStatus.SUCCESS, ST_COLLISION: RunStatus.COLLISION, ST_TIMEOUT: RunStatus.TIMEOUT,
           ST_STUCK: RunStatus.STUCK, ST_ERROR: RunStatus.ERROR}

# the loop state of one run (the runner's _Run fields), float64
L_STEP = 0          # control steps taken
L_THRUST = 1        # thrust setpoint
L_Q_SP = 2          # 4 values: attitude setpoint (w, x, y, z)
L_ARMED = 6
L_INTEG = 7         # 1: the rate integrators run
L_GROUND = 8        # 1: the ground was touched since the last navigator update
L_HELD = 9          # 1: resting on the ground at the starting pose (the hold)
L_PLANNED = 10      # 1 once the planner ran
L_PLAN_KIND = 11    # the last planner output (navigator_kernels.plan_inputs): kind, vector (3), yaw
L_PLAN_VEC = 12
L_PLAN_YAW = 15
L_ANCHOR_SET = 16   # the stuck check's anchor: set, distance, time, phase, item
L_ANCHOR = 17
L_ANCHOR_T = 18
L_ANCHOR_PHASE = 19
L_ANCHOR_INDEX = 20
L_N_TRUE = 21       # rows written in the records
L_N_LOG = 22
L_SENSOR_AT = 23    # next unused range-noise value
L_SIZE = 24


@njit(cache=True, nogil=True)
def fly_span(ls, s, rest, kp, ks, pp, ps, noise, k_first, true, log,
             dt, outer_div, outer_dt, log_div, max_steps, rest_z, stuck_on, stuck_w, stuck_d,
             n_sub, body, half, scene, threshold,
             nav, mission, nav_params,
             kind, rays, boxes, cyls, rmin, rmax, see_ground, sensor_noise, noisy, hits,
             cloud, age, path, pstate, settings, pconsts,
             memory, sstate, cand, cand_az, cand_el, sparams, sconsts):  # pragma: no cover - compiled
    """Fly one run from its loop state ``ls`` (:data:`L_SIZE`, in place) until a stop (module docstring).

    Args:
        s, rest: the rigid-body state (in place) and its resting pose (the hold). kp, ks, pp, ps: inner loop and
            position control parameters and states. noise: the block (n, 11) of outer steps ``k_first`` on
            (NoiseSource.block). true (n, 4), log (n, 8): the records, with room for a block's periods and the last
            record. nav, mission, nav_params: the navigator (navigator_kernels). kind: NO_PLANNER, SIMPLE_PLANNER
            or PX4_PLANNER; rays ... see_ground: the depth sensor (DepthSensor's arrays); sensor_noise: the range
            noise values (zeros when not ``noisy``); hits: the scan's buffer. cloud ... pconsts: PX4-Avoidance's
            state (px4_avoidance_cycle); memory ... sconsts: the simple planner's (avoidance_cycle); the other
            planner's are placeholders, with its constants None, so its branch is pruned and never compiled.

    Returns:
        (stop code, status, end time, info, cloud, age): ``info`` the obstacle row of a collision, else the
        navigator's phase code; ``cloud``, ``age`` PX4-Avoidance's point memory (as given for other planners).
    """
    n_rays = rays.shape[0]
    k_end = k_first + noise.shape[0]
    tree = new_tree_work(settings.smoothing_radius, settings.children)  # the look-ahead tree's buffers, this call's
    while True:
        step = int(ls[L_STEP])
        k = step // outer_div
        if k >= k_end:
            return BLOCK_END, 0, 0.0, 0, cloud, age
        if kind != NO_PLANNER and noisy and int(ls[L_SENSOR_AT]) + n_rays > sensor_noise.shape[0]:
            return NEED_SENSOR_NOISE, 0, 0.0, 0, cloud, age
        t = step * dt
        n = min(outer_div, max_steps - step)
        row = k - k_first
        pe0, pe1, pe2 = noise[row, 0], noise[row, 1], noise[row, 2]
        ve0, ve1, ve2 = noise[row, 3], noise[row, 4], noise[row, 5]
        wind = (noise[row, 7], noise[row, 8], noise[row, 9])
        status = 0
        info = 0
        end_t = t
        # --- runner._outer
        qx, qy, qz, qw = s[3], s[4], s[5], s[6]
        yaw = math.atan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz)) + noise[row, 6]
        if not (math.isfinite(s[0]) and math.isfinite(s[2])) or 1 - 2 * (qx * qx + qy * qy) < -0.1:
            status = ST_ERROR
        else:
            ex, ey, ez = s[0] + pe0, s[1] + pe1, s[2] - rest_z + pe2
            evx, evy, evz = s[7] + ve0, s[8] + ve1, s[9] + ve2
            pos_up, vel_up = (ex, ey, -ez), (evx, evy, -evz)
            i = int(ls[L_N_TRUE])
            true[i, 0], true[i, 1], true[i, 2], true[i, 3] = t, s[0], s[1], -s[2]
            ls[L_N_TRUE] = i + 1
            if k % log_div == 0:
                i = int(ls[L_N_LOG])
                log[i, 0], log[i, 1], log[i, 2], log[i, 3] = t, ex, ey, ez
                log[i, 4], log[i, 5], log[i, 6], log[i, 7] = evx, evy, evz, yaw
                ls[L_N_LOG] = i + 1
            plan_kind = PLAN_NONE
            plan_vec = (0.0, 0.0, 0.0)
            plan_yaw = 0.0
            if kind != NO_PLANNER and nav_phase(nav) == PH_CRUISE:  # nav.uses_planner
                if noise[row, 10] != 0.0 or ls[L_PLANNED] == 0.0:  # NoiseSource.plans
                    if noisy:
                        at = int(ls[L_SENSOR_AT])
                        range_noise = sensor_noise[at:at + n_rays]
                        ls[L_SENSOR_AT] = at + n_rays
                    else:
                        range_noise = sensor_noise[:n_rays]
                    m = cast_scan(s[0], s[1], -s[2], math.cos(yaw), math.sin(yaw), rays, boxes, cyls, rmin, rmax,
                              range_noise, hits, see_ground)
                    for j in range(m):
                        hits[j, 0] = hits[j, 0] + pe0
                        hits[j, 1] = hits[j, 1] + pe1
                        hits[j, 2] = hits[j, 2] + -pe2
                    # pconsts / sconsts are None for the planners not flown: numba prunes their branches before
                    # typing, so a profile compiles only its own planner (fly_kernel)
                    if pconsts is not None:
                        out = px4_cycle.cycle(cloud, age, path, pstate, settings, pconsts, t, pos_up,
                                                        vel_up, yaw, nav_goal(nav), nav_prev(nav), hits[:m], 0.0, tree)
                        cloud, age = out[0], out[1]
                        ls[L_PLAN_KIND] = PLAN_POSITION
                        ls[L_PLAN_VEC], ls[L_PLAN_VEC + 1], ls[L_PLAN_VEC + 2] = out[2], out[3], out[4]
                        ls[L_PLAN_YAW] = out[5]
                    elif sconsts is not None:
                        vel, vyaw, _ = reactive_cycle.cycle(memory, sstate, cand, cand_az, cand_el, sparams,
                                                             sconsts, t, pos_up, vel_up, nav_goal(nav), hits[:m],
                                                             nav_cruise(nav))
                        ls[L_PLAN_KIND] = PLAN_VELOCITY
                        ls[L_PLAN_VEC], ls[L_PLAN_VEC + 1], ls[L_PLAN_VEC + 2] = vel[0], vel[1], vel[2]
                        ls[L_PLAN_YAW] = vyaw
                    ls[L_PLANNED] = 1.0
                plan_kind = int(ls[L_PLAN_KIND])
                plan_vec = (ls[L_PLAN_VEC], ls[L_PLAN_VEC + 1], ls[L_PLAN_VEC + 2])
                plan_yaw = ls[L_PLAN_YAW]
            pos_sp, vel_ff, acc_ff, yaw_sp = nav_update(nav, mission, nav_params, t, pos_up, vel_up, yaw, outer_dt,
                                                        ls[L_GROUND] != 0.0, plan_kind, plan_vec, plan_yaw)
            ls[L_GROUND] = 0.0  # collects the contacts of the next outer period
            if nav_mission_complete(nav):
                status = ST_SUCCESS
                info = nav_phase(nav)
            else:
                on_ground = nav_on_ground_phase(nav)
                ls[L_ARMED] = 1.0 if nav_armed(nav) else 0.0
                ls[L_INTEG] = 0.0 if on_ground else 1.0
                if on_ground:
                    ps[:] = 0.0
                    ls[L_THRUST] = 0.0
                    ls[L_Q_SP], ls[L_Q_SP + 1] = math.cos(yaw_sp / 2), 0.0
                    ls[L_Q_SP + 2], ls[L_Q_SP + 3] = 0.0, math.sin(yaw_sp / 2)
                else:
                    q0, q1, q2, q3, thrust = position_step((ex, ey, ez), (evx, evy, evz), pos_sp, vel_ff, acc_ff,
                                                           yaw_sp, outer_dt, pp, ps)
                    ls[L_Q_SP], ls[L_Q_SP + 1], ls[L_Q_SP + 2], ls[L_Q_SP + 3] = q0, q1, q2, q3
                    ls[L_THRUST] = thrust
                # stuck: the distance to the current goal has not shrunk by stuck_d during the last stuck_w s
                ph = nav_phase(nav)
                if stuck_on and (ph == PH_CRUISE or ph == PH_TAKEOFF or ph == PH_CLIMB or ph == PH_DESCEND):
                    g0, g1, g2 = nav_target(nav)
                    gz = 0.0 if ph == PH_DESCEND else g2
                    d = math.sqrt(py_square(g0 - s[0], nav_params) + py_square(g1 - s[1], nav_params)
                                  + py_square(gz + s[2], nav_params))
                    idx = nav_index(nav)
                    if (ls[L_ANCHOR_SET] == 0.0 or ls[L_ANCHOR_PHASE] != ph or ls[L_ANCHOR_INDEX] != idx
                            or d < ls[L_ANCHOR] - stuck_d):
                        ls[L_ANCHOR_SET], ls[L_ANCHOR], ls[L_ANCHOR_T] = 1.0, d, t
                        ls[L_ANCHOR_PHASE], ls[L_ANCHOR_INDEX] = ph, idx
                    elif t - ls[L_ANCHOR_T] > stuck_w:
                        status = ST_STUCK
                        info = ph
                else:
                    ls[L_ANCHOR_SET] = 0.0
        # --- compiled_physics.fly: the control steps of the period
        if status != 0:
            # as in PyBullet's loop, the ended vehicle still takes this step (with no force) before its record
            rb.step(s, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), dt, n_sub, body, half)
        else:
            q_sp = (ls[L_Q_SP], ls[L_Q_SP + 1], ls[L_Q_SP + 2], ls[L_Q_SP + 3])
            what, taken, held = advance(s, q_sp, ls[L_THRUST], wind, dt, ls[L_ARMED] != 0.0, ls[L_INTEG] != 0.0,
                                        kp, ks, n, n_sub, body, half, scene, threshold, ls[L_HELD] != 0.0, rest)
            ls[L_HELD] = 1.0 if held else 0.0
            if what >= 0:
                status, info, end_t = ST_COLLISION, what, (step + taken) * dt
            elif what == GROUND:
                ls[L_GROUND] = 1.0
        step += n
        ls[L_STEP] = step
        if status == 0 and step >= max_steps:
            status, info, end_t = ST_TIMEOUT, nav_phase(nav), step * dt
        if status != 0:  # runner._record: the last state
            qx, qy, qz, qw = s[3], s[4], s[5], s[6]
            yaw = math.atan2(2 * (qx * qy + qw * qz), 1 - 2 * (qy * qy + qz * qz))
            i = int(ls[L_N_LOG])
            if i == 0 or log[i - 1, 0] < end_t:
                log[i, 0], log[i, 1], log[i, 2], log[i, 3] = end_t, s[0] + pe0, s[1] + pe1, s[2] - rest_z + pe2
                log[i, 4], log[i, 5], log[i, 6], log[i, 7] = s[7] + ve0, s[8] + ve1, s[9] + ve2, yaw
                ls[L_N_LOG] = i + 1
            i = int(ls[L_N_TRUE])
            if i == 0 or true[i - 1, 0] < end_t:
                true[i, 0], true[i, 1], true[i, 2], true[i, 3] = end_t, s[0], s[1], -s[2]
                ls[L_N_TRUE] = i + 1
            return ENDED, status, end_t, info, cloud, age


def _grown(a: np.ndarray, used: int, room: int) -> np.ndarray:
    """``a`` with at least ``room`` free rows after its first ``used``."""
    if a.shape[0] - used >= room:
        return a
    b = np.empty((max(2 * a.shape[0], used + room), a.shape[1]))
    b[:used] = a[:used]
    return b


def fly_kernel(world, runs: list, cfg, sensor, timeout: float, mission, params) -> None:
    """The run loop of ``SimConfig(physics="compiled")``: each run of ``runs`` (the runner's ``_Run``s, fresh) flown
    by :func:`fly_span` on ``world`` (a :class:`~surrealist_gym.sim.vehicle.compiled_physics.CompiledWorld`); fills each
    run's status, message, end time and records (``log``, ``true`` as arrays) for ``runner._result``.

    Args:
        sensor: the depth sensor (None without avoidance; each run's ``planner`` then is None too).
        timeout: the time limit [s]. mission, params: the test's mission and resolved PX4 parameters (the
            navigator's, as ``runner.simulate_runs`` gives them to
            :class:`~surrealist_gym.sim.navigation.navigator.Navigator`).
    """
    from ..avoidance.px4.local_planner import Px4AvoidanceConfig, kernel_settings
    from ..avoidance.reactive import LocalPlanner


    dt = 1.0 / cfg.control_hz
    outer_div = int(round(cfg.control_hz / cfg.outer_hz))
    outer_dt = outer_div * dt  # as the Python loops'
    plan_div, log_div = int(round(cfg.outer_hz / cfg.planner_hz)), int(round(cfg.outer_hz / cfg.log_hz))
    max_steps = int(math.ceil(timeout * cfg.control_hz))
    stuck_on = cfg.stuck_window_s is not None
    stuck_w = float(cfg.stuck_window_s) if stuck_on else 0.0
    mission_arr = mission_array(mission)
    block = NoiseSource.BLOCK
    if sensor is not None:
        rays, boxes, cyls = sensor._rays, sensor._boxes, sensor._cyls
        sc = sensor.config
        rmin, rmax, see_ground, noise_std = float(sc.range_min), float(sc.range_max), bool(sc.returns_ground), \
            float(sc.noise_std)
    else:
        rays, boxes, cyls = np.zeros((1, 3)), np.zeros((0, 8)), np.zeros((0, 5))
        rmin, rmax, see_ground, noise_std = 0.0, 1.0, False, 0.0
    n_rays = rays.shape[0]
    scans = block // plan_div + 2  # range noise drawn at a time (scans)
    for r in runs:
        s = world.states[r.body]
        rest = s[:7].copy()
        ls = np.zeros(L_SIZE)
        ls[L_THRUST] = r.thrust
        ls[L_Q_SP:L_Q_SP + 4] = r.q_sp
        ls[L_ARMED], ls[L_INTEG], ls[L_GROUND], ls[L_HELD] = float(r.armed), float(r.integ), float(r.ground), \
            float(r.held)
        nav_params = param_vector(params, cfg.takeoff_delay_s + r.noise.start_offset, cfg.takeoff_hold_s)
        nav = initial_state(nav_params)
        planner = r.planner
        kind = NO_PLANNER if planner is None else SIMPLE_PLANNER if isinstance(planner, LocalPlanner) \
            else PX4_PLANNER
        # PX4-Avoidance's state (placeholders for the other planners)
        cloud, age, path = np.empty((0, 3)), np.empty(0), np.empty((MAX_NODES, 3))
        pstate = px4_cycle.initial_state()
        if kind == PX4_PLANNER:
            settings, pconsts = planner._settings, px4_cycle.constants(planner, float(cfg.tree_reuse_m),
                                                                          cfg.tree_reuse_cycles)
        else:
            settings, pconsts = kernel_settings(Px4AvoidanceConfig()), None  # None: its branch is not compiled
        # the simple planner's (placeholders for the others)
        memory = Dict.empty(key_type=types.int64, value_type=types.float64)
        sstate = reactive_cycle.initial_state()
        if kind == SIMPLE_PLANNER:
            cand, cand_az, cand_el = planner._cand, planner._cand_az, planner._cand_el
            sparams, sconsts = planner._params, reactive_cycle.constants(planner)
        else:
            cand, cand_az, cand_el = np.zeros((1, 1, 3)), np.zeros((1, 1)), np.zeros((1, 1))
            sparams, sconsts = np.zeros(12), None
        rng = r.noise.rng
        noisy = kind != NO_PLANNER and rng is not None and noise_std > 0.0
        range_noise = np.empty(0) if noisy else np.zeros(n_rays)
        hits = np.empty((n_rays, 3))
        true, log = np.empty((block + 2, 4)), np.empty((block // log_div + 3, 8))
        k_first, noise = 0, r.noise.block()
        while True:
            true = _grown(true, int(ls[L_N_TRUE]), block + 2)
            log = _grown(log, int(ls[L_N_LOG]), block + 2)
            code, status, end_t, info, cloud, age = fly_span(
                ls, s, rest, r.kp, r.ks, r.pp, r.ps, noise, k_first, true, log,
                dt, outer_div, outer_dt, log_div, max_steps, world.rest_z, stuck_on, stuck_w,
                float(cfg.stuck_distance_m), world.n_sub, world.body, world.half, world.scene, world.threshold,
                nav, mission_arr, nav_params,
                kind, rays, boxes, cyls, rmin, rmax, see_ground, range_noise, noisy, hits,
                cloud, age, path, pstate, settings, pconsts,
                memory, sstate, cand, cand_az, cand_el, sparams, sconsts)
            if code == BLOCK_END:
                k_first, noise = k_first + noise.shape[0], r.noise.block()
            elif code == NEED_SENSOR_NOISE:
                at = int(ls[L_SENSOR_AT])
                range_noise = np.concatenate((range_noise[at:], rng.standard_normal(n_rays * scans) * noise_std))
                ls[L_SENSOR_AT] = 0.0
            else:
                break
        r.status, r.end_t, r.active = _STATUS[status], end_t, False
        r.message = _message(status, end_t, info, cfg, timeout)
        r.log, r.true = log[:int(ls[L_N_LOG])], true[:int(ls[L_N_TRUE])]


QUICK_OPT = "1"  # numba's optimisation level for the loop: as fast as its default 3 here, and compiled sooner


_FIRST_COMPILE = threading.Lock()  # numba's optimisation level is process-wide: one first simulation sets it


@contextmanager
def compiling():
    """Around a simulation. Until the loop is compiled or loaded in this process, say so when no cached loop exists
    (:func:`_notice_compiling`) and compile at numba's optimisation level :data:`QUICK_OPT`, unless ``NUMBA_OPT`` is
    set (the level is numba's process-wide setting, restored after; docs/compiled-loop.md has the measurement).
    Afterwards it does nothing: a process that later flies another planner compiles that one at numba's level."""
    if fly_span.overloads:
        yield
        return
    from numba.core import config

    level = getattr(config, "_process_opt_level", None)  # numba's parser of NUMBA_OPT values
    _FIRST_COMPILE.acquire()
    if fly_span.overloads:  # another thread compiled it while this one waited: fly without the lock
        _FIRST_COMPILE.release()
        yield
        return
    try:
        _notice_compiling()
        if level is None or os.environ.get("NUMBA_OPT"):
            yield
            return
        before, config.OPT = config.OPT, level(QUICK_OPT)
        try:
            yield
        finally:
            config.OPT = before
    finally:
        _FIRST_COMPILE.release()


def _notice_compiling() -> None:
    """Say on stderr that the simulator is being compiled (no cached kernels yet: the first
    simulation after an install or an upgrade). Numba's cache layout is its own, so when it cannot be read, nothing
    is said."""
    try:
        cached = os.path.exists(fly_span._cache._cache_file._index_path)
    except AttributeError:
        return
    if not cached:
        where = os.environ.get("NUMBA_CACHE_DIR") or "numba's cache"
        print(f"surrealist-gym: compiling the simulator into {where} (once per install: {COMPILE_NOTE})",
              file=sys.stderr, flush=True)


COMPILE_NOTE = "about 30 s on a 2-core laptop; later runs start in seconds"


def _message(status: int, t: float, info: int, cfg, timeout: float) -> str:
    """The run's end as the Python loops word it."""
    if status == ST_SUCCESS:
        return run_end.finished(info == PH_DONE, t)
    if status == ST_COLLISION:
        return run_end.collided(info, t)
    if status == ST_TIMEOUT:
        return run_end.timed_out(timeout, PHASES[info].value)
    if status == ST_STUCK:
        return run_end.stuck(cfg.stuck_distance_m, cfg.stuck_window_s, PHASES[info].value, t)
    return run_end.invalid(t)
