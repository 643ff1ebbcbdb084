"""One cycle of the reactive local planner (:class:`~surrealist_gym.sim.avoidance.reactive.LocalPlanner`, the planner
tuned to the real PX4 Vision) as a numba kernel, for the compiled flight loop.

The class stays the readable reference (behaviour and sources: :mod:`surrealist_gym.sim.avoidance.reactive`); the kernel
does the same arithmetic in the same order, CPython's ``math.hypot`` and ``math.remainder`` included, so both give the
same bits (tests/surrealist_gym/sim/avoidance/test_reactive_cycle.py replays recorded flights through both).

State of one planner: the voxel memory (the class's numba typed dict) and a float vector (``S_*`` indices: NaN where
the class holds None). Constants (:func:`constants`): the class's candidate directions, its ``plan_step`` parameter
vector and a float vector of the config (``C_*`` indices).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..compiled.cpython_math import py_hypot, py_remainder
from .reactive import YawMode, plan_step

S_T_PREV, S_HEADING, S_YAW = 0, 1, 2
STATE_SIZE = 3
(C_CRUISE, C_BRAKE, C_GOAL_TOL, C_TURN_RATE, C_SLOW_DIST, C_SLOW_RAMP, C_NEAR, C_AVOID_SPEED, C_V_MARGIN, C_V_REACH,
 C_CLIMB_MAX, C_ALT_GAIN, C_YAW_DIRECTION, C_WAYPOINT, C_MEMORY_TIME, C_VOXEL) = range(16)
_TWO_PI = 2.0 * math.pi


def initial_state() -> np.ndarray:
    """A planner's state after :meth:`LocalPlanner.reset`: no previous time, heading or yaw."""
    return np.full(STATE_SIZE, math.nan)


def constants(planner) -> np.ndarray:
    """The float constants of a :class:`~surrealist_gym.sim.avoidance.reactive.LocalPlanner`'s config, as the kernel
    reads them."""
    c = planner.config
    return np.array([c.cruise_speed, c.goal_brake_accel, c.goal_tolerance, c.max_turn_rate_deg_s,
                     c.slow_down_distance, c.slow_down_ramp, c.near_distance, c.avoid_speed, c.vertical_margin,
                     c.vertical_reach, c.max_climb_rate, c.altitude_gain, float(c.yaw_mode == YawMode.DIRECTION),
                     c.waypoint_distance, c.memory_time, c.voxel_size], dtype=np.float64)


@njit(cache=True)
def cycle(memory, state, cand, cand_az, cand_el, params, consts, t, position, velocity, goal, hits,
          max_speed):  # pragma: no cover - compiled
    """One planner cycle (LocalPlanner.update with ``max_speed``, NaN for the config's cruise speed): updates
    ``memory`` and ``state`` in place and returns the velocity setpoint (vx, vy, vz), the yaw setpoint [rad] and
    the intermediate waypoint (x, y, z)."""
    speed_max = consts[C_CRUISE] if math.isnan(max_speed) else max_speed
    px, py, pz = position
    gx, gy, gz = goal[0] - px, goal[1] - py, goal[2] - pz
    vx, vy, vz = velocity
    t_prev = state[S_T_PREV]
    dt = 0.0 if math.isnan(t_prev) else min(max(t - t_prev, 0.0), 1.0)
    state[S_T_PREV] = t
    dist_goal = math.sqrt(gx * gx + gy * gy + gz * gz)
    dist_goal_h = py_hypot(gx, gy)
    if dist_goal_h > 1e-9:
        az_goal = math.atan2(gy, gx)
    else:
        az_goal = 0.0 if math.isnan(state[S_YAW]) else state[S_YAW]
    el_goal = math.degrees(math.atan2(gz, dist_goal_h))
    best, blocked, d_near, d_min, top = plan_step(memory, hits, t, consts[C_MEMORY_TIME], consts[C_VOXEL], px, py, pz,
                                              vx, vy, vz, math.degrees(az_goal), el_goal, cand, cand_az, cand_el,
                                              params)
    speed = min(speed_max, math.sqrt(2.0 * consts[C_BRAKE] * dist_goal))
    if dist_goal <= consts[C_GOAL_TOL]:
        speed = 0.0
    if best < 0:  # nothing in range: straight at the goal
        state[S_HEADING] = math.nan
        if dist_goal > 1e-9:
            ux, uy, uz = gx / dist_goal, gy / dist_goal, gz / dist_goal
        else:
            ux, uy, uz = 0.0, 0.0, 0.0
        vel = (speed * ux, speed * uy, speed * uz)
        if dist_goal_h > 1e-9:
            state[S_YAW] = az_goal
    else:
        n_az = cand.shape[1]
        band, ia = best // n_az, best % n_az
        heading = math.radians(cand_az[band, ia])
        elev = math.radians(cand_el[band, ia])
        if not math.isnan(state[S_HEADING]):
            step = math.radians(consts[C_TURN_RATE]) * dt
            diff = py_remainder(heading - state[S_HEADING], _TWO_PI)
            heading = state[S_HEADING] + max(-step, min(step, diff))
        state[S_HEADING] = heading
        if blocked:
            speed = 0.0
        else:
            slow_dist, slow_ramp = consts[C_SLOW_DIST], consts[C_SLOW_RAMP]
            if slow_ramp > 0:
                ramp = (d_near - slow_dist) / slow_ramp
            else:
                ramp = 1.0 if d_near > slow_dist else 0.0
            ramp = 0.0 if d_min < consts[C_NEAR] else max(0.0, min(1.0, ramp))
            avoid = min(consts[C_AVOID_SPEED], speed)
            speed = avoid + (speed - avoid) * ramp
        target_dz = gz
        if consts[C_V_MARGIN] > 0 and -np.inf < top <= pz + consts[C_V_REACH]:
            target_dz = max(gz, top + consts[C_V_MARGIN] - pz)
        climb = max(-consts[C_CLIMB_MAX], min(consts[C_CLIMB_MAX], consts[C_ALT_GAIN] * target_dz))
        ch = speed * math.cos(elev)
        ux, uy, uz = math.cos(heading) * math.cos(elev), math.sin(heading) * math.cos(elev), math.sin(elev)
        vel = (ch * math.cos(heading), ch * math.sin(heading), speed * math.sin(elev) + climb)
        if consts[C_YAW_DIRECTION] > 0 or dist_goal_h <= 1e-9:
            state[S_YAW] = heading
        else:
            state[S_YAW] = az_goal
    yaw = 0.0 if math.isnan(state[S_YAW]) else state[S_YAW]
    wd = consts[C_WAYPOINT]
    return vel, py_remainder(yaw, _TWO_PI), (px + wd * ux, py + wd * uy, pz + wd * uz)
