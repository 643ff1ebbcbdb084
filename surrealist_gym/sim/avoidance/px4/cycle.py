"""One cycle of PX4-Avoidance's local planner as a numba kernel: :meth:`Px4LocalPlanner.update
<surrealist_gym.sim.avoidance.px4.local_planner.Px4LocalPlanner.update>` (point cloud memory, look-ahead tree, waypoint
generator, setpoint and yaw smoothing) over plain arrays, for the compiled flight loop.

The class stays the readable reference (behaviour and sources: :mod:`surrealist_gym.sim.avoidance.px4.local_planner`);
the kernel does the same arithmetic in the same order (CPython's ``math.remainder`` and ``math.hypot`` reproduced by
:mod:`~surrealist_gym.sim.compiled.cpython_math`), so both give the same bits (tests/surrealist_gym/sim/
test_px4_cycle.py replays recorded flights through both).

State of one planner (:func:`initial_state`):
- ``cloud`` (n, 3) and ``age`` (n,): the remembered points [m] and their ages [s]; the kernel returns new arrays;
- ``path`` (MAX_NODES, 3): the last tree's path, vehicle first, its length in ``state[PATH_LEN]``;
- ``state``: the scalars below (NaN where the class holds None).

Constants of one planner (:func:`constants`): the :class:`KernelSettings` and a float vector (``C_*`` indices).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...compiled.cpython_math import py_hypot, py_remainder
from .cloud import process_cloud
from .settings import MAX_NODES
from .tree import build_tree

# state vector; BUILT_AT, BUILT_GOAL: where the last tree was built and toward what; REUSED: the cycles since
# that kept its path
T_PREV, PATH_T, SPEED, SP, SP_V, YAW, YAW_RATE, YAW_AT_GOAL, PATH_LEN = 0, 1, 2, 3, 6, 9, 10, 11, 12
BUILT_AT, BUILT_GOAL, REUSED = 13, 16, 19
STATE_SIZE = 20
# constants vector
C_CRUISE, C_LINE_BAND, C_HEADING_OFFSET, C_SMOOTH_XY, C_SMOOTH_Z, C_SPEED_TAU = 0, 1, 2, 3, 4, 5
C_REUSE_M, C_REUSE_MAX = 6, 7
# the output's state code
DIRECT, TRY_PATH = 0, 1
_TWO_PI = 2.0 * math.pi


def initial_state() -> np.ndarray:
    """A planner's state after :meth:`Px4LocalPlanner.reset`: no time, no setpoint, no yaw, an empty path."""
    s = np.zeros(STATE_SIZE)
    s[T_PREV] = s[YAW] = s[YAW_AT_GOAL] = math.nan
    s[SP:SP + 3] = math.nan
    s[BUILT_AT:BUILT_AT + 6] = math.nan
    return s


def constants(planner, reuse_m: float = 0.0, reuse_max: int = 0) -> np.ndarray:
    """The float constants of a :class:`~surrealist_gym.sim.avoidance.px4.local_planner.Px4LocalPlanner` (its config,
    cruise speed after the sensor limit, the line band and the heading offset), as the kernel reads them, and the
    tree's reuse while hovering (:func:`cycle`; 0: a tree every cycle, as the class)."""
    c = planner.config
    return np.array([planner.cruise, planner._line_band, planner._heading_offset, c.smoothing_speed_xy,
                     c.smoothing_speed_z, c.speed_filter_tau_s, reuse_m, reuse_max], dtype=np.float64)


@njit(cache=True)
def point_on_path(path, n, length):  # pragma: no cover - compiled
    """The point ``length`` metres along the polyline ``path[:n]`` (vehicle first) as (found, x, y, z); found False
    past its end."""
    for i in range(n - 1):
        dx, dy, dz = path[i + 1, 0] - path[i, 0], path[i + 1, 1] - path[i, 1], path[i + 1, 2] - path[i, 2]
        seg = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length <= seg:
            f = length / seg if seg > 0 else 0.0
            return True, path[i, 0] + f * dx, path[i, 1] + f * dy, path[i, 2] + f * dz
        length -= seg
    return False, 0.0, 0.0, 0.0


@njit(cache=True)
def closest_on_line(px, py, ax, ay, bx, by, near):  # pragma: no cover - compiled
    """The vehicle's projection on the line a -> b as (found, x, y); found False when a and b (nearly) coincide or
    the vehicle is within ``near`` of the line (geometry.line_projection, then determineStrategy's band)."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    if length2 < 1e-6:
        return False, 0.0, 0.0
    s = ((px - ax) * dx + (py - ay) * dy) / length2
    fx, fy = ax + s * dx, ay + s * dy
    if py_hypot(px - fx, py - fy) < near:
        return False, 0.0, 0.0
    return True, fx, fy


@njit(cache=True)
def _reuses(state, consts, px, py, pz, gx, gy, gz):  # pragma: no cover - compiled
    """Whether this cycle keeps the last tree's path (:func:`cycle`)."""
    if consts[C_REUSE_M] <= 0.0 or state[PATH_LEN] < 2 or state[REUSED] >= consts[C_REUSE_MAX]:
        return False
    if gx != state[BUILT_GOAL] or gy != state[BUILT_GOAL + 1] or gz != state[BUILT_GOAL + 2]:
        return False
    dx, dy, dz = px - state[BUILT_AT], py - state[BUILT_AT + 1], pz - state[BUILT_AT + 2]
    return dx * dx + dy * dy + dz * dz < consts[C_REUSE_M] * consts[C_REUSE_M]


@njit(cache=True)
def cycle(cloud, age, path, state, settings, consts, t, position, velocity, yaw, goal, prev_goal, hits,
          pitch, work=None):  # pragma: no cover - compiled
    """One planner cycle (Px4LocalPlanner.update): updates ``path`` and ``state`` in place and returns
    (cloud, age, x, y, z, yaw_sp, state code, speed, built, points): the new cloud memory, the smoothed position
    setpoint, the yaw setpoint [rad], DIRECT or TRY_PATH, the adapted speed, whether a tree was built this cycle
    (its path is then ``path[:state[PATH_LEN]]``) and the number of points in the cloud. ``work``: the tree's
    buffers (:func:`~surrealist_gym.sim.avoidance.px4.tree.tree_work`), reused across cycles; allocated per build
    when None.

    With ``consts[C_REUSE_M]`` > 0 (the compiled loop's ``SimConfig.tree_reuse_m``), a cycle whose vehicle is within
    that distance of where the last tree was built, toward the same goal, keeps that tree's path as if built now, up
    to ``consts[C_REUSE_MAX]`` cycles in a row: a hovering vehicle builds a tree every few cycles instead of every
    one. The class always builds."""
    t_prev = state[T_PREV]
    dt = 0.1 if math.isnan(t_prev) else min(max(t - t_prev, 1e-3), 1.0)
    state[T_PREV] = t
    px, py, pz = position
    vx, vy, vz = velocity
    gx, gy, gz = goal
    n_max = hits.shape[0] + cloud.shape[0]
    out, out_age = np.empty((n_max, 3)), np.empty(n_max)
    n = process_cloud(hits, cloud, age, (px, py, pz), (math.degrees(yaw), math.degrees(pitch)), dt, settings,
                       out, out_age)
    cloud, age = out[:n], out_age[:n]
    found, cx, cy = closest_on_line(px, py, prev_goal[0], prev_goal[1], gx, gy, consts[C_LINE_BAND])
    cpt = (cx, cy, gz) if found else (gx, gy, gz)
    built = False
    if n > 0 and _reuses(state, consts, px, py, pz, gx, gy, gz):  # the last tree's path, as if built now
        state[PATH_T] = t
        state[REUSED] += 1.0
    elif n > 0:  # a new tree
        state[BUILT_AT], state[BUILT_AT + 1], state[BUILT_AT + 2] = px, py, pz
        state[BUILT_GOAL], state[BUILT_GOAL + 1], state[BUILT_GOAL + 2] = gx, gy, gz
        state[REUSED] = 0.0
        tree = np.empty((MAX_NODES, 3))
        k = build_tree(cloud, (px, py, pz), (vx, vy, vz), (gx, gy, gz), cpt, settings, tree, work)
        if k > 0:
            for i in range(k):  # the tree's path is deepest node first: reversed, vehicle first
                path[i, 0], path[i, 1], path[i, 2] = tree[k - 1 - i, 0], tree[k - 1 - i, 1], tree[k - 1 - i, 2]
            state[PATH_LEN], state[PATH_T], built = k, t, True
    # waypoint generator
    cruise = consts[C_CRUISE]
    dx, dy, dz = gx - px, gy - py, gz - pz
    dist_goal = math.sqrt(dx * dx + dy * dy + dz * dz)
    code = DIRECT
    aimed = False
    aim_x, aim_y, aim_z = gx, gy, gz
    if state[PATH_LEN] >= 2:
        aimed, x, y, z = point_on_path(path, int(state[PATH_LEN]),
                                       settings.node_distance + cruise * (t - state[PATH_T]))
        if not aimed:
            state[PATH_LEN] = 0
        else:
            code = TRY_PATH
            aim_x, aim_y, aim_z = x, y, z
    ax, ay, az = aim_x - px, aim_y - py, aim_z - pz
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if norm > 1e-6:
        ux, uy, uz = ax / norm, ay / norm, az / norm
    else:
        ux, uy, uz = 0.0, 0.0, 0.0
    if dist_goal < 1.0:  # adaptSpeed: at the goal, aim at it at the distance left; the yaw is latched
        d = max(dist_goal, 1e-6)
        ux, uy, uz = (gx - px) / d, (gy - py) / d, (gz - pz) / d
        target = dist_goal
        if math.isnan(state[YAW_AT_GOAL]):
            state[YAW_AT_GOAL] = state[YAW] if not math.isnan(state[YAW]) else yaw
    else:
        # scaleToFOV with one camera: a linear ramp over the whole field of view, 0 outside
        heading = math.atan2(uy, ux) if abs(ux) + abs(uy) > 1e-9 else yaw
        off = abs(math.degrees(py_remainder(heading - yaw, _TWO_PI)))
        target = cruise * max(0.0, 1.0 - 2.0 * off / settings.fov_h)
        state[YAW_AT_GOAL] = math.nan
    alpha = dt / (consts[C_SPEED_TAU] + dt)
    state[SPEED] += alpha * (target - state[SPEED])
    speed = min(state[SPEED], dist_goal)
    adapted = (px + ux * speed, py + uy * speed, pz + uz * speed)
    # smoothWaypoint: critically damped filter toward the adapted point; reference: the vehicle's velocity
    # (0 when the adapted point is the goal)
    if math.isnan(state[SP]):
        state[SP], state[SP + 1], state[SP + 2] = px, py, pz
        state[SP_V], state[SP_V + 1], state[SP_V + 2] = vx, vy, vz
    ex, ey, ez = adapted[0] - gx, adapted[1] - gy, adapted[2] - gz
    at_goal = math.sqrt(ex * ex + ey * ey + ez * ez) < 0.1
    vel = (vx, vy, vz)
    for i in range(3):
        kp = consts[C_SMOOTH_Z] if i == 2 else consts[C_SMOOTH_XY]
        ref = 0.0 if at_goal else vel[i]
        acc = kp * (adapted[i] - state[SP + i]) + 2.0 * math.sqrt(kp) * (ref - state[SP_V + i])
        state[SP_V + i] += acc * dt
        state[SP + i] += state[SP_V + i] * dt
    # nextSmoothYaw: toward the point aimed at, through the same filter (xy gain)
    if math.isnan(state[YAW]):
        state[YAW], state[YAW_RATE] = yaw, 0.0
    if not math.isnan(state[YAW_AT_GOAL]):
        want = state[YAW_AT_GOAL]
    elif py_hypot(ax, ay) > 0.1:
        want = math.atan2(ay, ax)
    else:
        want = yaw
    err = py_remainder(want - state[YAW], _TWO_PI)
    kyaw = consts[C_SMOOTH_XY]
    state[YAW_RATE] += (kyaw * err - 2.0 * math.sqrt(kyaw) * state[YAW_RATE]) * dt
    state[YAW] = py_remainder(state[YAW] + state[YAW_RATE] * dt, _TWO_PI)
    yaw_sp = py_remainder(state[YAW] + consts[C_HEADING_OFFSET], _TWO_PI)
    return (cloud, age, state[SP], state[SP + 1], state[SP + 2], yaw_sp, code, speed, built, n)
