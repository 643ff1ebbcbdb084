"""PX4's avoidance flight task (:class:`~surrealist_gym.sim.navigation.flight_task.AvoidanceFlightTask`) as numba
kernels over the navigator's state vector (:mod:`~surrealist_gym.sim.navigation.navigator_state`), for the compiled
flight loop (docs/compiled-loop.md). The class stays the readable reference; each kernel follows one of its methods line
by line with the same floating-point operations in the same order
(tests/surrealist_gym/sim/navigation/test_navigator_kernels.py).
"""
from __future__ import annotations

import math

from numba import njit

from ..compiled.cpython_math import py_hypot
from .flight_task import COS_TURN, TURN_MIN_SPEED, stopping_speed
from .navigator_state import (
    P_MPC_ACC_DOWN_MAX,
    P_MPC_ACC_HOR,
    P_MPC_ACC_UP_MAX,
    P_MPC_JERK_AUTO,
    P_MPC_XY_ERR_MAX,
    P_MPC_Z_VEL_MAX_DN,
    P_MPC_Z_VEL_MAX_UP,
    P_NAV_ACC_RAD,
    S_TASK_ACC,
    S_TASK_ACTIVE,
    S_TASK_CRUISE,
    S_TASK_MAX_SPEED_PREV,
    S_TASK_POS,
    S_TASK_TURNING,
    S_TASK_VEL,
    line_projection,
)

__all__ = ["task_start", "task_target", "task_update"]

_stopping_speed = njit(cache=True)(stopping_speed)  # the flight task's own function, compiled


@njit(cache=True)
def task_start(state, cruise, pos, vel):  # pragma: no cover - compiled
    """AvoidanceFlightTask.__init__: the trajectory starts at the vehicle's position and velocity."""
    state[S_TASK_ACTIVE] = 1.0
    state[S_TASK_CRUISE] = cruise
    for i in range(3):
        state[S_TASK_POS + i] = pos[i]
        state[S_TASK_VEL + i] = vel[i]
        state[S_TASK_ACC + i] = 0.0
    state[S_TASK_MAX_SPEED_PREV] = cruise
    state[S_TASK_TURNING] = 0.0


@njit(cache=True)
def task_target(params, pos, prev, goal):  # pragma: no cover - compiled
    """AvoidanceFlightTask.target: PX4's own target (x, y, z): the mission item, the previous one, or the foot of
    the perpendicular on the line ("offtrack")."""
    r = params[P_NAV_ACC_RAD]
    ok, along, cx, cy = line_projection(pos[0], pos[1], prev[0], prev[1], goal[0], goal[1])
    if not ok:
        return goal[0], goal[1], goal[2]
    if along > 1.0:
        return goal[0], goal[1], goal[2]
    if along < 0.0 and py_hypot(pos[0] - prev[0], pos[1] - prev[1]) > r:
        return prev[0], prev[1], prev[2]
    if py_hypot(pos[0] - cx, pos[1] - cy) > r:
        return cx, cy, goal[2]
    return goal[0], goal[1], goal[2]


@njit(cache=True)
def task_update(state, params, dt, pos, setpoint, prev, goal):  # pragma: no cover - compiled
    """AvoidanceFlightTask.update: one cycle toward the injected ``setpoint``; returns the (position, velocity,
    acceleration) setpoints (x, y, z up) and advances the task's trajectory in ``state``."""
    tp, tv, ta = S_TASK_POS, S_TASK_VEL, S_TASK_ACC
    # the turning check against PX4's own target
    tgt = task_target(params, pos, prev, goal)
    vxy = py_hypot(state[tv], state[tv + 1])
    tx, ty = tgt[0] - state[tp], tgt[1] - state[tp + 1]
    to_target = py_hypot(tx, ty)
    turning = (vxy > TURN_MIN_SPEED and to_target > params[P_NAV_ACC_RAD]
               and (state[tv] * tx + state[tv + 1] * ty) / (vxy * to_target) < COS_TURN)
    state[S_TASK_TURNING] = 1.0 if turning else 0.0
    # speed that stops at the injected point
    jerk = max(params[P_MPC_JERK_AUTO], 1e-3)
    dx, dy, dz = setpoint[0] - state[tp], setpoint[1] - state[tp + 1], setpoint[2] - state[tp + 2]
    dxy = py_hypot(dx, dy)
    xy_speed = min(state[S_TASK_CRUISE], _stopping_speed(jerk, params[P_MPC_ACC_HOR], dxy))
    if dz >= 0.0:
        z_speed = min(params[P_MPC_Z_VEL_MAX_UP], _stopping_speed(jerk, params[P_MPC_ACC_UP_MAX], dz))
    else:
        z_speed = min(params[P_MPC_Z_VEL_MAX_DN], _stopping_speed(jerk, params[P_MPC_ACC_DOWN_MAX], -dz))
    if turning:
        xy_speed = min(state[S_TASK_MAX_SPEED_PREV], xy_speed)
    else:
        state[S_TASK_MAX_SPEED_PREV] = xy_speed
    d = math.sqrt(dxy * dxy + dz * dz)
    if d > 1e-6:
        s = math.sqrt(xy_speed * xy_speed + z_speed * z_speed) / d
        vt0, vt1, vt2 = dx * s, dy * s, dz * s
        h = py_hypot(vt0, vt1)
        if h > xy_speed > 0.0:
            vt0, vt1 = vt0 * xy_speed / h, vt1 * xy_speed / h
        vt2 = max(-z_speed, min(z_speed, vt2))
    else:
        vt0, vt1, vt2 = 0.0, 0.0, 0.0
    # time stretch while the vehicle lags behind the trajectory
    ex, ey = state[tp] - pos[0], state[tp + 1] - pos[1]
    stretch = 1.0
    if ex * state[tv] + ey * state[tv + 1] > 0.0:
        stretch = 1.0 - min(max(py_hypot(ex, ey) / max(params[P_MPC_XY_ERR_MAX], 1e-3), 0.0), 1.0)
    step = dt * stretch
    for i in range(3):
        v_target = vt0 if i == 0 else (vt1 if i == 1 else vt2)
        if i < 2:
            a_max = params[P_MPC_ACC_HOR]
        else:
            a_max = params[P_MPC_ACC_UP_MAX] if v_target > state[tv + i] else params[P_MPC_ACC_DOWN_MAX]
        dv = v_target - state[tv + i]
        want = math.copysign(min(math.sqrt(2.0 * jerk * abs(dv)), a_max), dv)
        da = want - state[ta + i]
        lim = jerk * step
        state[ta + i] += max(-lim, min(lim, da))
        new_v = state[tv + i] + state[ta + i] * step
        if (dv > 0.0 and new_v > v_target) or (dv < 0.0 and new_v < v_target):
            new_v, state[ta + i] = v_target, 0.0
        state[tp + i] += 0.5 * (state[tv + i] + new_v) * step
        state[tv + i] = new_v
    return ((state[tp], state[tp + 1], state[tp + 2]), (state[tv], state[tv + 1], state[tv + 2]),
            (state[ta], state[ta + 1], state[ta + 2]))
