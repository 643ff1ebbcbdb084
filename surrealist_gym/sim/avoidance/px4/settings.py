"""The constants and settings shared by PX4-Avoidance's compiled kernels
(:mod:`surrealist_gym.sim.avoidance.px4.local_planner`): the polar histogram's cell and size, the point cloud's
subsampling cell and size, the tree's node capacity, and :class:`KernelSettings`.

The kernels take the planner's constant settings as one :class:`KernelSettings` (a named tuple, which numba passes
as a tuple of its fields) and the per-cycle state (vehicle position, velocity, goal, the mission line's point) as
3-tuples.
"""
from __future__ import annotations

import math
from typing import NamedTuple

ALPHA_RES = 6.0  # histogram cell [deg] (avoidance/include/avoidance/histogram.h)
N_E, N_Z = 30, 60
SUB_RES = 2.0  # subsampling cell of the point cloud [deg] (ALPHA_RES / 3)
N_E2, N_Z2 = 90, 180
MAX_NODES = 512
R2D = 180.0 / math.pi


class KernelSettings(NamedTuple):
    """The planner's constant settings as the kernels read them (built once per planner from its config by
    :func:`surrealist_gym.sim.avoidance.px4.local_planner.kernel_settings`). Every float field holds a float and every
    int field an int, so numba compiles one specialisation.

    Attributes:
        min_range / max_range: the sensor's range; also the memory radius and the tree's reach [m].
        pitch_cost / yaw_cost: cost per squared degree of elevation / azimuth error.
        velocity_cost: cost per m/s of ``|v| - u . v``.
        obstacle_cost: distance at which a cell's obstacle cost is half its maximum [m].
        heuristic_weight: the tree's heuristic cost per metre to the goal.
        smoothing_radius: radius of the conic smoothing kernel [histogram cells].
        children / expansions: children per node and expanded nodes of the tree.
        node_distance: distance from a node to its children [m].
        max_point_age: age at which a remembered point is forgotten [s].
        fov_h / fov_v: the camera's field of view [deg].
    """

    min_range: float
    max_range: float
    pitch_cost: float
    yaw_cost: float
    velocity_cost: float
    obstacle_cost: float
    heuristic_weight: float
    smoothing_radius: int
    children: int
    expansions: int
    node_distance: float
    max_point_age: float
    fov_h: float
    fov_v: float
