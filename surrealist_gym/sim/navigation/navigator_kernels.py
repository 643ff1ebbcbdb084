"""The navigator (:class:`~surrealist_gym.sim.navigation.navigator.Navigator`) as numba kernels over plain arrays
(:mod:`~surrealist_gym.sim.navigation.navigator_state`), for the compiled flight loop (docs/compiled-loop.md). The class
stays the readable reference; every function here follows one of its methods line by line (named in its docstring), with
the same floating-point operations in the same order, so that a kernel run equals the class bit for bit
(tests/surrealist_gym/sim/navigation/test_navigator_kernels.py replays recorded flights through both). In CRUISE with
PX4-Avoidance, the flight task's kernels (:mod:`~surrealist_gym.sim.navigation.flight_task_kernels`) shape the
setpoints.

:func:`nav_update` is :meth:`Navigator.update`. The planner's output enters as three values
(:func:`~surrealist_gym.sim.navigation.navigator_state.plan_inputs`): a kind (``PLAN_NONE``, ``PLAN_VELOCITY`` for the
simple planner's ``velocity``, ``PLAN_POSITION`` for PX4-Avoidance's ``position``), that 3-vector, and the yaw.
"""
from __future__ import annotations

import math

from numba import njit

from ...mission import Mission
from ..compiled.cpython_math import py_hypot, py_remainder
from .flight_task_kernels import task_start, task_update
from .navigator_state import (
    CMD_CHANGE_SPEED,
    CMD_LAND,
    CMD_RETURN_TO_LAUNCH,
    CMD_TAKEOFF,
    CMD_WAYPOINT,
    M_ACCEPTANCE_RADIUS,
    M_COMMAND,
    M_HOLD_S,
    M_SPEED,
    M_X,
    M_Y,
    M_Z,
    NO_ITEM,
    P_COM_DISARM_LAND,
    P_LNDMC_TRIG_TIME,
    P_LNDMC_XY_VEL_MAX,
    P_LNDMC_Z_VEL_MAX,
    P_MIS_TAKEOFF_ALT,
    P_MPC_ACC_DOWN_MAX,
    P_MPC_ACC_HOR,
    P_MPC_ACC_UP_MAX,
    P_MPC_LAND_ALT1,
    P_MPC_LAND_ALT2,
    P_MPC_LAND_SPEED,
    P_MPC_TKO_RAMP_T,
    P_MPC_TKO_SPEED,
    P_MPC_XY_P,
    P_MPC_YAW_MODE,
    P_MPC_Z_P,
    P_MPC_Z_VEL_MAX_DN,
    P_MPC_Z_VEL_MAX_UP,
    P_NAV_ACC_RAD,
    P_NAV_MC_ALT_RAD,
    P_RTL_RETURN_ALT,
    P_START_TIME,
    P_TAKEOFF_HOLD_S,
    P_YAW_RATE_RAD,
    PH_CLIMB,
    PH_CRUISE,
    PH_DESCEND,
    PH_DONE,
    PH_HOLD,
    PH_IDLE,
    PH_LANDED,
    PH_TAKEOFF,
    PLAN_POSITION,
    PLAN_VELOCITY,
    S_CARROT,
    S_CRUISE,
    S_FINISHED_IN_AIR,
    S_HOLD_UNTIL,
    S_INDEX,
    S_LANDED_AT,
    S_LANDED_SINCE,
    S_PHASE,
    S_PHASE_T0,
    S_PREV,
    S_T,
    S_TARGET,
    S_TASK_ACTIVE,
    S_THEN_LAND,
    S_V_CMD,
    S_YAW_SP,
    initial_state,
    line_projection,
    mission_array,
    nav_armed,
    nav_mission_complete,
    nav_on_ground_phase,
    nav_prev,
    nav_target,
    nav_uses_planner,
    param_vector,
    phase_of,
    plan_inputs,
    py_square,
)

__all__ = ["nav_update", "CompiledNavigator"]

NAN = math.nan

@njit(cache=True)
def _item_count(mission):  # pragma: no cover - compiled
    n = 0
    while n < mission.shape[0] and int(mission[n, M_COMMAND]) != NO_ITEM:
        n += 1
    return n


@njit(cache=True)
def _go(state, t, phase, x, y, z, return_x, return_y):  # pragma: no cover - compiled
    """Navigator._go: a new phase toward a target (the RTL climb's carries the return position), the carrot, the
    flight task and the land detector reset."""
    state[S_PHASE] = phase
    state[S_PHASE_T0] = t
    state[S_CARROT:S_CARROT + 3] = NAN
    state[S_TASK_ACTIVE] = 0.0
    state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2] = x, y, z
    state[S_TARGET + 3], state[S_TARGET + 4] = return_x, return_y
    state[S_LANDED_SINCE] = NAN


@njit(cache=True)
def _next_item(state, mission, params, t, pos):  # pragma: no cover - compiled
    """Navigator._next_item: skip to the next item with a flight phase (CHANGE_SPEED items set the cruise speed on
    the way); after the last, hold the last target for 2 s with the mission finished in the air."""
    n = _item_count(mission)
    while True:
        index = int(state[S_INDEX]) + 1
        state[S_INDEX] = index
        if index >= n:
            state[S_PHASE] = PH_HOLD
            state[S_FINISHED_IN_AIR] = 1.0
            if index <= 0:  # no item at all: hold where the vehicle is
                state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2] = pos[0], pos[1], pos[2]
            state[S_TARGET + 3] = state[S_TARGET + 4] = 0.0  # the class keeps target[:3]
            state[S_HOLD_UNTIL] = t + 2.0
            return
        cmd = int(mission[index, M_COMMAND])
        if cmd == CMD_CHANGE_SPEED:
            speed = mission[index, M_SPEED]
            if speed == speed and speed > 0:
                state[S_CRUISE] = speed
            continue
        if cmd == CMD_TAKEOFF:
            z = mission[index, M_Z]
            alt = max(z if z == z else 0.0, params[P_MIS_TAKEOFF_ALT])
            _go(state, t, PH_TAKEOFF, pos[0], pos[1], alt, 0.0, 0.0)
        elif cmd == CMD_WAYPOINT:
            _go(state, t, PH_CRUISE, mission[index, M_X], mission[index, M_Y], mission[index, M_Z], 0.0, 0.0)
        elif cmd == CMD_LAND:
            state[S_THEN_LAND] = 1.0
            prev_z = state[S_PREV + 2]
            alt = prev_z if prev_z > 0.5 else max(pos[2], 0.5)
            _go(state, t, PH_CRUISE, mission[index, M_X], mission[index, M_Y], alt, 0.0, 0.0)
        elif cmd == CMD_RETURN_TO_LAUNCH:
            state[S_THEN_LAND] = 1.0
            alt = max(pos[2], params[P_RTL_RETURN_ALT])
            if alt - pos[2] > params[P_NAV_MC_ALT_RAD]:
                _go(state, t, PH_CLIMB, pos[0], pos[1], alt, 0.0, 0.0)
            else:
                _go(state, t, PH_CRUISE, 0.0, 0.0, alt, 0.0, 0.0)
        return


@njit(cache=True)
def _next_position(state, mission):  # pragma: no cover - compiled
    """Navigator._next_position: (found, x, y, z) of the next item after the current one with a position that is
    not a take-off."""
    n = _item_count(mission)
    for i in range(int(state[S_INDEX]) + 1, n):
        if mission[i, M_X] == mission[i, M_X] and int(mission[i, M_COMMAND]) != CMD_TAKEOFF:
            return True, mission[i, M_X], mission[i, M_Y], mission[i, M_Z]
    return False, 0.0, 0.0, 0.0


@njit(cache=True)
def _passed(state, pos):  # pragma: no cover - compiled
    """Navigator._passed: the vehicle's projection on the line from the previous setpoint lies beyond the target."""
    ok, along, _, _ = line_projection(pos[0], pos[1], state[S_PREV], state[S_PREV + 1], state[S_TARGET],
                                       state[S_TARGET + 1])
    return ok and along > 1.0


@njit(cache=True)
def _reached(state, mission, params, pos):  # pragma: no cover - compiled
    """Navigator._reached: within the item's acceptance radius (NAV_ACC_RAD without one; at most
    max(NAV_ACC_RAD, 0.1) for LAND and RTL) horizontally and max(NAV_MC_ALT_RAD, 0.1) vertically; with the flight
    task, passing the target along the line counts."""
    index = int(state[S_INDEX])
    has_item = 0 <= index < _item_count(mission)
    rad = params[P_NAV_ACC_RAD]
    if has_item and mission[index, M_ACCEPTANCE_RADIUS] > 0:
        rad = mission[index, M_ACCEPTANCE_RADIUS]
    if has_item:
        cmd = int(mission[index, M_COMMAND])
        if cmd == CMD_LAND or cmd == CMD_RETURN_TO_LAUNCH:
            rad = min(rad, max(params[P_NAV_ACC_RAD], 0.1))
    dh = py_hypot(pos[0] - state[S_TARGET], pos[1] - state[S_TARGET + 1])
    if state[S_TASK_ACTIVE] != 0.0 and _passed(state, pos):
        rad = dh + 0.5
    return dh < rad and abs(pos[2] - state[S_TARGET + 2]) < max(params[P_NAV_MC_ALT_RAD], 0.1)


@njit(cache=True)
def _advance(state, mission, params, t, pos, vel, ground_contact):  # pragma: no cover - compiled
    """Navigator._advance: the phase transitions of one step."""
    ph = int(state[S_PHASE])
    if ph == PH_IDLE:
        if t >= params[P_START_TIME]:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = pos[0], pos[1], 0.0
            _next_item(state, mission, params, t, pos)
    elif ph == PH_TAKEOFF or ph == PH_CLIMB:
        if abs(pos[2] - state[S_TARGET + 2]) < params[P_NAV_MC_ALT_RAD]:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = pos[0], pos[1], state[S_TARGET + 2]
            if ph == PH_CLIMB:
                _go(state, t, PH_CRUISE, state[S_TARGET + 3], state[S_TARGET + 4], state[S_TARGET + 2], 0.0, 0.0)
            elif params[P_TAKEOFF_HOLD_S] > 0:
                _go(state, t, PH_HOLD, state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2], 0.0, 0.0)
                state[S_HOLD_UNTIL] = t + params[P_TAKEOFF_HOLD_S]
            else:
                _next_item(state, mission, params, t, pos)
    elif ph == PH_CRUISE:
        if _reached(state, mission, params, pos):
            target_x, target_y, target_z = state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]
            if state[S_THEN_LAND] != 0.0:
                _go(state, t, PH_DESCEND, target_x, target_y, target_z, 0.0, 0.0)
            else:
                hold_s = mission[int(state[S_INDEX]), M_HOLD_S]
                _go(state, t, PH_HOLD, target_x, target_y, target_z, 0.0, 0.0)
                state[S_HOLD_UNTIL] = t + max(hold_s, 0.0)
    elif ph == PH_HOLD:
        if t >= state[S_HOLD_UNTIL] and state[S_FINISHED_IN_AIR] == 0.0:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = state[S_TARGET], state[S_TARGET + 1], \
                state[S_TARGET + 2]
            _next_item(state, mission, params, t, pos)
    elif ph == PH_DESCEND:
        vz_ok = abs(vel[2]) < params[P_LNDMC_Z_VEL_MAX]
        vxy_ok = py_hypot(vel[0], vel[1]) < params[P_LNDMC_XY_VEL_MAX]
        if ground_contact and vz_ok and vxy_ok:
            if state[S_LANDED_SINCE] != state[S_LANDED_SINCE]:
                state[S_LANDED_SINCE] = t
            elif t - state[S_LANDED_SINCE] >= params[P_LNDMC_TRIG_TIME]:
                state[S_PHASE], state[S_LANDED_AT] = PH_LANDED, t
        else:
            state[S_LANDED_SINCE] = NAN
    elif ph == PH_LANDED:
        if t - state[S_LANDED_AT] >= max(params[P_COM_DISARM_LAND], 0.0):
            state[S_PHASE] = PH_DONE


# --- setpoint shaping (Navigator._line_velocity ... _yaw_step) ---------------------------------------------------
@njit(cache=True)
def _line_velocity(state, params, pos):  # pragma: no cover - compiled
    """Navigator._line_velocity: along the line from the previous setpoint to the target at the cruise speed
    (vertical limits on a slope), braking before the target, with a cross-track correction."""
    p00, p01, p02 = state[S_PREV], state[S_PREV + 1], state[S_PREV + 2]
    p10, p11, p12 = state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]
    dx, dy, dz = p10 - p00, p11 - p01, p12 - p02
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    ex, ey, ez = p10 - pos[0], p11 - pos[1], p12 - pos[2]
    dist = math.sqrt(ex * ex + ey * ey + ez * ez)
    if length < 1e-6:
        if dist > 1e-6:
            ux, uy, uz = ex / dist, ey / dist, ez / dist
        else:
            ux, uy, uz = 0.0, 0.0, 0.0
        s = 0.0
    else:
        ux, uy, uz = dx / length, dy / length, dz / length
        s = (pos[0] - p00) * ux + (pos[1] - p01) * uy + (pos[2] - p02) * uz
        s = min(max(s, 0.0), length)
    cx, cy, cz = p00 + ux * s - pos[0], p01 + uy * s - pos[1], p02 + uz * s - pos[2]
    remaining = ex * ux + ey * uy + ez * uz
    hor = py_hypot(ux, uy)
    vmax = state[S_CRUISE] / hor if hor > 1e-6 else params[P_MPC_Z_VEL_MAX_UP]
    if uz > 1e-6:
        vmax = min(vmax, params[P_MPC_Z_VEL_MAX_UP] / uz)
    elif uz < -1e-6:
        vmax = min(vmax, params[P_MPC_Z_VEL_MAX_DN] / -uz)
    brake = 0.5 * params[P_MPC_ACC_HOR]
    along = min(vmax, math.sqrt(2.0 * brake * max(remaining, 0.0)), params[P_MPC_XY_P] * max(remaining, 0.0) + 0.1)
    kp = params[P_MPC_XY_P]
    return along * ux + kp * cx, along * uy + kp * cy, along * uz + kp * cz


@njit(cache=True)
def _approach(state, mission, params, pos, v0, v1, v2):  # pragma: no cover - compiled
    """Navigator._approach: before a stop (landing, the last item) at most MPC_XY_P times the distance left."""
    has_next = _next_position(state, mission)[0]
    if not (state[S_THEN_LAND] != 0.0 or not has_next):
        return v0, v1, v2
    d = math.sqrt(py_square(state[S_TARGET] - pos[0], params) + py_square(state[S_TARGET + 1] - pos[1], params)
                  + py_square(state[S_TARGET + 2] - pos[2], params))
    cap = params[P_MPC_XY_P] * d + 0.1
    n = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if n <= cap:
        return v0, v1, v2
    return v0 * cap / n, v1 * cap / n, v2 * cap / n


@njit(cache=True)
def _carrot(state, params, pos, v0, v1, v2, dt):  # pragma: no cover - compiled
    """Navigator._carrot: the position setpoint moved by the velocity setpoint, kept within 1 m of the vehicle."""
    if state[S_CARROT] != state[S_CARROT]:
        c0, c1, c2 = pos[0], pos[1], pos[2]
    else:
        c0, c1, c2 = state[S_CARROT], state[S_CARROT + 1], state[S_CARROT + 2]
    c0, c1, c2 = c0 + v0 * dt, c1 + v1 * dt, c2 + v2 * dt
    d = math.sqrt(py_square(c0 - pos[0], params) + py_square(c1 - pos[1], params) + py_square(c2 - pos[2], params))
    if d > 1.0:
        c0, c1, c2 = pos[0] + (c0 - pos[0]) / d, pos[1] + (c1 - pos[1]) / d, pos[2] + (c2 - pos[2]) / d
    state[S_CARROT], state[S_CARROT + 1], state[S_CARROT + 2] = c0, c1, c2
    return c0, c1, c2


@njit(cache=True)
def _slew(state, params, v0, v1, v2, dt):  # pragma: no cover - compiled
    """Navigator._slew: the velocity command changes at most MPC_ACC_HOR horizontally, MPC_ACC_UP_MAX /
    MPC_ACC_DOWN_MAX vertically."""
    o0, o1, o2 = state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2]
    ah = params[P_MPC_ACC_HOR] * dt
    dx, dy = v0 - o0, v1 - o1
    d = py_hypot(dx, dy)
    if d > ah:
        dx, dy = dx * ah / d, dy * ah / d
    dz = min(max(v2 - o2, -params[P_MPC_ACC_DOWN_MAX] * dt), params[P_MPC_ACC_UP_MAX] * dt)
    state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2] = o0 + dx, o1 + dy, o2 + dz
    return o0 + dx, o1 + dy, o2 + dz


@njit(cache=True)
def _yaw_mode(state, params, pos, vel, has_target, target_x, target_y):  # pragma: no cover - compiled
    """Navigator._yaw_mode: the heading MPC_YAW_MODE asks for (0 the target, 1 home, 2 away from home, 3 along
    the velocity); the current yaw setpoint when it is undefined (no target, within 1 m, slower than 0.5 m/s)."""
    mode = int(params[P_MPC_YAW_MODE])
    if mode == 1:
        has_target, target_x, target_y = True, 0.0, 0.0
    elif mode == 2:
        has_target, target_x, target_y = True, 2 * pos[0], 2 * pos[1]
    elif mode == 3:
        if py_hypot(vel[0], vel[1]) > 0.5:
            return math.atan2(vel[1], vel[0])
        return state[S_YAW_SP]
    if not has_target:
        return state[S_YAW_SP]
    dx, dy = target_x - pos[0], target_y - pos[1]
    if py_hypot(dx, dy) < 1.0:
        return state[S_YAW_SP]
    return math.atan2(dy, dx)


@njit(cache=True)
def _yaw_step(params, current, target, dt):  # pragma: no cover - compiled
    """Navigator._yaw_step: toward the target heading at most MPC_YAWRAUTO_MAX, wrapped to [-pi, pi]."""
    step = params[P_YAW_RATE_RAD] * dt
    diff = py_remainder(target - current, 2 * math.pi)
    return py_remainder(current + max(-step, min(step, diff)), 2 * math.pi)


# --- one navigator step -------------------------------------------------------------------------------------------
@njit(cache=True)
def nav_update(state, mission, params, t, pos, vel, yaw, dt, ground_contact, plan_kind, plan_vector,
               plan_yaw):  # pragma: no cover - compiled
    """Navigator.update: one navigator step.

    Args:
        state: the navigator's state (:func:`initial_state`), updated in place.
        mission, params: :func:`mission_array`, :func:`param_vector`.
        t: time since arming [s]. pos, vel: estimated position and velocity (x, y, z up) [m], [m/s] (tuples or
            arrays). yaw: estimated heading [rad]. dt: step [s]. ground_contact: the vehicle touches the ground.
        plan_kind, plan_vector, plan_yaw: the latest planner output (:func:`plan_inputs`).

    Returns:
        (pos_sp_ned, vel_ff_ned, acc_ff_ned, yaw_sp) as Navigator.update: NED position setpoint (nan = free),
        velocity and acceleration feed-forward, heading.
    """
    state[S_T] = t
    if state[S_YAW_SP] != state[S_YAW_SP]:
        state[S_YAW_SP] = yaw
    _advance(state, mission, params, t, pos, vel, ground_contact)
    ph = int(state[S_PHASE])
    if ph == PH_IDLE or ph == PH_LANDED or ph == PH_DONE:
        state[S_V_CMD] = state[S_V_CMD + 1] = state[S_V_CMD + 2] = 0.0
        return (NAN, NAN, NAN), (0.0, 0.0, 0.3), (0.0, 0.0, 0.0), state[S_YAW_SP]  # push down: minimum thrust
    pos_sp = (NAN, NAN, NAN)
    vel_sp = (0.0, 0.0, 0.0)
    acc = (0.0, 0.0, 0.0)
    yaw_target = state[S_YAW_SP]
    if ph == PH_TAKEOFF or ph == PH_CLIMB:
        if ph == PH_TAKEOFF:
            ramp = min(1.0, (t - state[S_PHASE_T0]) / max(params[P_MPC_TKO_RAMP_T], 1e-3))
            speed = params[P_MPC_TKO_SPEED]
        else:
            ramp = 1.0
            speed = params[P_MPC_Z_VEL_MAX_UP]
        err = state[S_TARGET + 2] - pos[2]
        vz = min(speed * ramp, math.sqrt(2.0 * 1.0 * max(err, 0.0)), params[P_MPC_Z_P] * err + 0.3 * speed)
        pos_sp, vel_sp = (state[S_TARGET], state[S_TARGET + 1], NAN), (0.0, 0.0, max(vz, -0.5))
        has_next, next_x, next_y, _ = _next_position(state, mission)
        yaw_target = _yaw_mode(state, params, pos, vel, has_next, next_x, next_y)
    elif ph == PH_HOLD:
        pos_sp = (state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2])
    elif ph == PH_DESCEND:
        alt = pos[2]
        a1, a2 = params[P_MPC_LAND_ALT1], params[P_MPC_LAND_ALT2]
        vmax, vland = params[P_MPC_Z_VEL_MAX_DN], params[P_MPC_LAND_SPEED]
        if alt > a1:
            vd = vmax
        elif alt > a2 and a1 > a2:
            vd = vland + (vmax - vland) * (alt - a2) / (a1 - a2)
        else:
            vd = vland
        pos_sp, vel_sp = (state[S_TARGET], state[S_TARGET + 1], NAN), (0.0, 0.0, -vd)
    elif ph == PH_CRUISE:
        if plan_kind == PLAN_POSITION:  # a position setpoint: PX4's flight task
            if state[S_TASK_ACTIVE] == 0.0:
                task_start(state, state[S_CRUISE], pos, vel)
            prev = (state[S_PREV], state[S_PREV + 1], state[S_PREV + 2])
            pos_sp, vel_sp, acc = task_update(state, params, dt, pos, plan_vector, prev, nav_target(state))
            state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2] = vel_sp
            yaw_target = plan_yaw
        else:  # a velocity (or the mission line), slewed, with a position setpoint moving along
            if plan_kind == PLAN_VELOCITY:
                v0, v1, v2 = _approach(state, mission, params, pos, plan_vector[0], plan_vector[1], plan_vector[2])
                yaw_target = plan_yaw
            else:
                v0, v1, v2 = _line_velocity(state, params, pos)
                yaw_target = _yaw_mode(state, params, pos, vel, True, state[S_TARGET], state[S_TARGET + 1])
            o0, o1, o2 = state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2]
            vel_sp = _slew(state, params, v0, v1, v2, dt)
            acc = ((vel_sp[0] - o0) / dt, (vel_sp[1] - o1) / dt, (vel_sp[2] - o2) / dt)
            pos_sp = _carrot(state, params, pos, vel_sp[0], vel_sp[1], vel_sp[2], dt)
    state[S_YAW_SP] = _yaw_step(params, state[S_YAW_SP], yaw_target, dt)
    return ((pos_sp[0], pos_sp[1], -pos_sp[2]), (vel_sp[0], vel_sp[1], -vel_sp[2]), (acc[0], acc[1], -acc[2]),
            state[S_YAW_SP])


# --- a drop-in for the Python run loop -----------------------------------------------------------------------------
class CompiledNavigator:
    """:class:`~surrealist_gym.sim.navigation.navigator.Navigator`'s interface over the kernels (for the Python run loop
    until the whole outer loop is compiled): the same constructor, ``update`` and properties.

    Args:
        mission, params, start_time, takeoff_hold_s: as :class:`~surrealist_gym.sim.navigation.navigator.Navigator`.
    """

    __slots__ = ("state", "mission", "params")

    def __init__(self, mission: Mission, params: dict, start_time: float, takeoff_hold_s: float = 0.0):
        self.mission = mission_array(mission)
        self.params = param_vector(params, start_time, takeoff_hold_s)
        self.state = initial_state(self.params)

    def update(self, t: float, pos, vel, yaw: float, dt: float, ground_contact: bool, planner=None):
        """:meth:`Navigator.update` (see :func:`nav_update`)."""
        kind, vector, plan_yaw = plan_inputs(planner)
        return nav_update(self.state, self.mission, self.params, t, pos, vel, yaw, dt, ground_contact, kind,
                          vector, plan_yaw)

    def goal(self) -> tuple[float, float, float]:
        """The current target (x, y, z up) [m] for the avoidance planner."""
        return nav_target(self.state)

    phase = property(lambda self: phase_of(self.state), doc="Navigator.phase")
    index = property(lambda self: int(self.state[S_INDEX]), doc="Navigator.index")
    cruise = property(lambda self: float(self.state[S_CRUISE]), doc="Navigator.cruise")
    target = property(lambda self: nav_target(self.state), doc="Navigator.target (x, y, z)")
    prev = property(lambda self: nav_prev(self.state), doc="Navigator.prev")
    armed = property(lambda self: nav_armed(self.state), doc="Navigator.armed")
    on_ground_phase = property(lambda self: nav_on_ground_phase(self.state), doc="Navigator.on_ground_phase")
    uses_planner = property(lambda self: nav_uses_planner(self.state), doc="Navigator.uses_planner")
    mission_complete = property(lambda self: nav_mission_complete(self.state), doc="Navigator.mission_complete")
