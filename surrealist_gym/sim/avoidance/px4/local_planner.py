"""PX4-Avoidance's local planner as Aerialist runs it in SITL: 3DVFH+ with a look-ahead tree, and its waypoint
generator.

The behaviour, its parameters and their sources are in ``../shared/PX4-AVOIDANCE.md`` (PX4/PX4-Avoidance master,
``local_planner/src/nodes/*``, ``local_planner/cfg/LocalPlannerNode.cfg``); the implementation is ours. World frame:
x north, y east, z up [m]; azimuth [deg] from north toward east, elevation [deg] up from the horizontal.

One :meth:`Px4LocalPlanner.update` is one planner cycle (~10 Hz):

1. **Point cloud and memory** (``processPointcloud``): the camera's new points within ``(min_sensor_range,
   max_sensor_range)`` are subsampled to one per 2 deg polar cell around the vehicle; an older point is kept when it
   is younger than ``max_point_age_s``, within range, its 2 deg cell got no new point and it lies outside the
   camera's field of view (body frame).
2. **Polar histogram** (6 deg cells, 30 x 60): the mean distance of the points per cell, 0 = empty.
3. **Look-ahead tree** (``StarPlanner::buildLookAheadTree``), built only when the vehicle's own histogram is not
   empty: from the vehicle, up to ``n_expanded_nodes`` expansions of the cheapest open node within
   ``max_sensor_range``; each expansion builds the histogram and the cost matrix at the node and adds a child
   ``tree_node_distance`` away in each of the ``children_per_node`` cheapest directions (none within 0.2 m of an
   existing node). Cost of a direction (``getCostMatrix``): the obstacle cost ``5000 (1 + d / sqrt(1 + d^2))``,
   ``d = obstacle_cost_param - distance``, smoothed by a conic kernel of ``smoothing_margin_degrees`` (summed, not
   normalised), plus ``velocity_cost_param (|v| - u.v)``, ``yaw_cost_param`` times the squared azimuth error to
   the goal (split half and half with the azimuth to the mission line when no obstacle lies in the goal's
   window), and ``pitch_cost_param`` times the squared elevation error (stronger within 5 m of the goal). The
   path goes from the vehicle to the first open node of the greatest depth. (Near the poles the planner evaluates
   every ``1 / cos(elevation)``-th azimuth and interpolates; here every cell is evaluated.)
4. **Waypoint generator** (``WaypointGenerator``): TRY_PATH follows the path from its first node at the cruise
   speed since the tree was built, DIRECT (no tree, or the path used up) heads for the goal. The speed is the
   cruise speed times a field-of-view factor (``1 - 2 |bearing error| / fov_h_deg``, 0 outside the camera's
   horizontal field of view: ``scaleToFOV`` with one camera), low-passed (0.9 s), at most the distance to the
   goal; the setpoint lies that far ahead and is smoothed by a critically damped filter (gains
   ``smoothing_speed_xy`` / ``_z``). The yaw setpoint turns toward the direction flown, plus
   ``heading_offset_deg`` (0 in the code; the SITL Iris profile's measured 16 deg, which through the field-of-view
   factor also sets the pace).

The output is PX4's ``vehicle_trajectory_waypoint`` point: a position setpoint (no velocity) and a yaw.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..planner import Planner, PlannerCommand
from .cloud import process_cloud
from .cycle import closest_on_line, point_on_path
from .settings import ALPHA_RES, MAX_NODES, KernelSettings
from .tree import build_tree

__all__ = ["KernelSettings", "Px4AvoidanceConfig", "Px4LocalPlanner", "Px4PlannerOutput", "kernel_settings"]


@dataclass(frozen=True, slots=True)
class Px4AvoidanceConfig:
    """Parameters of the local planner; defaults are ``LocalPlannerNode.cfg``'s, which Aerialist's launch file keeps.

    Attributes:
        max_sensor_range: Points farther than this are dropped; also the memory radius, the tree's reach and the
            sensor-limited speed [m] (cfg 15).
        min_sensor_range: Points nearer than this are dropped [m] (cfg 0.2).
        pitch_cost_param / yaw_cost_param: Cost per squared degree of elevation / azimuth error (cfg 25 / 3).
        velocity_cost_param: Cost per m/s of ``|v| - u . v`` (cfg 6000).
        obstacle_cost_param: Distance at which a cell's obstacle cost is half its maximum [m] (cfg 8.5).
        tree_heuristic_weight: Heuristic cost per metre to the goal (cfg 35).
        max_point_age_s: Age at which a remembered point is forgotten [s] (cfg 20).
        smoothing_speed_xy / smoothing_speed_z: P gains of the setpoint smoothing filter (cfg 10 / 3).
        smoothing_margin_degrees: Radius of the conic kernel that spreads obstacle costs [deg] (cfg 40).
        children_per_node / n_expanded_nodes / tree_node_distance: the tree (cfg 8 / 40 / 2 m).
        fov_h_deg / fov_v_deg: The field of view the planner learns from the camera's clouds [deg] (the SITL
            Iris depth camera: 59 x 46).
        speed_filter_tau_s: Time constant of the speed low-pass [s] (waypoint_generator.cpp, 0.9).
        max_speed_sensor: Whether the cruise speed is capped by the sensor-limited speed (the positive root of
            ``u^2 + 2 a (a / j) u - 2 a R = 0`` with MPC_ACC_HOR, MPC_JERK_MAX and max_sensor_range).
        heading_offset_deg: The vehicle's heading relative to the yaw the planner asks for [deg, clockwise]; 0 in the
            code as read. A measurement: see the SITL Iris profile.
    """

    max_sensor_range: float = 15.0
    min_sensor_range: float = 0.2
    pitch_cost_param: float = 25.0
    yaw_cost_param: float = 3.0
    velocity_cost_param: float = 6000.0
    obstacle_cost_param: float = 8.5
    tree_heuristic_weight: float = 35.0
    max_point_age_s: float = 20.0
    smoothing_speed_xy: float = 10.0
    smoothing_speed_z: float = 3.0
    smoothing_margin_degrees: float = 40.0
    children_per_node: int = 8
    n_expanded_nodes: int = 40
    tree_node_distance: float = 2.0
    fov_h_deg: float = 59.0
    fov_v_deg: float = 46.0
    speed_filter_tau_s: float = 0.9
    max_speed_sensor: bool = True
    heading_offset_deg: float = 0.0

    def __post_init__(self):
        for name in ("max_sensor_range", "tree_node_distance", "fov_h_deg", "fov_v_deg", "speed_filter_tau_s",
                     "smoothing_speed_xy", "smoothing_speed_z", "max_point_age_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0 and math.isfinite(value)):
                raise ValueError(f"Px4AvoidanceConfig.{name}: expected a positive number, got {value!r}")
        for name in ("min_sensor_range", "pitch_cost_param", "yaw_cost_param", "velocity_cost_param",
                     "obstacle_cost_param", "tree_heuristic_weight", "smoothing_margin_degrees"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value >= 0 and math.isfinite(value)):
                raise ValueError(f"Px4AvoidanceConfig.{name}: expected a number >= 0, got {value!r}")
        for name in ("children_per_node", "n_expanded_nodes"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 64:
                raise ValueError(f"Px4AvoidanceConfig.{name}: expected an int in [1, 64], got {value!r}")
        if self.min_sensor_range >= self.max_sensor_range:
            raise ValueError("Px4AvoidanceConfig: min_sensor_range must be below max_sensor_range")
        if not (isinstance(self.heading_offset_deg, (int, float)) and -90.0 <= self.heading_offset_deg <= 90.0):
            raise ValueError(f"Px4AvoidanceConfig.heading_offset_deg: expected a number in [-90, 90], got "
                             f"{self.heading_offset_deg!r}")


@dataclass(frozen=True, slots=True)
class Px4PlannerOutput(PlannerCommand):
    """One cycle's message to PX4 and what produced it.

    Attributes:
        position: Smoothed position setpoint (x, y, z up) [m] (``point_1`` of the trajectory message).
        yaw: Yaw setpoint [rad] from north toward east.
        state: ``"try_path"`` (following the tree) or ``"direct"`` (heading for the goal).
        speed: The adapted speed of this cycle [m/s] (before smoothing).
        path: The tree path of this cycle, vehicle first, as an (n, 3) array (empty when no tree was built).
        points: Number of points in the planner's cloud (new and remembered).
    """

    position: tuple[float, float, float]
    yaw: float
    state: str
    speed: float
    path: np.ndarray
    points: int


def kernel_settings(config: Px4AvoidanceConfig) -> KernelSettings:
    """The config's settings as the compiled kernels read them: floats as floats (a YAML ``15`` too, so numba
    compiles one specialisation), the smoothing margin as a radius in histogram cells."""
    c = config
    return KernelSettings(
        min_range=float(c.min_sensor_range), max_range=float(c.max_sensor_range),
        pitch_cost=float(c.pitch_cost_param), yaw_cost=float(c.yaw_cost_param),
        velocity_cost=float(c.velocity_cost_param), obstacle_cost=float(c.obstacle_cost_param),
        heuristic_weight=float(c.tree_heuristic_weight),
        smoothing_radius=int(math.ceil(c.smoothing_margin_degrees / ALPHA_RES)),
        children=int(c.children_per_node), expansions=int(c.n_expanded_nodes),
        node_distance=float(c.tree_node_distance), max_point_age=float(c.max_point_age_s),
        fov_h=float(c.fov_h_deg), fov_v=float(c.fov_v_deg))


def sensor_limited_speed(acc: float, jerk: float, sensor_range: float) -> float:
    """The planner's speed limit from its sensor range: the positive root of u^2 + 2 a (a/j) u - 2 a R = 0."""
    b = 2.0 * acc * acc / max(jerk, 1e-6)
    return 0.5 * (-b + math.sqrt(b * b + 8.0 * acc * sensor_range))


class Px4LocalPlanner(Planner):
    """The planner and waypoint generator of one vehicle; call :meth:`update` (or the run loop's :meth:`step`) once
    per planner cycle.

    Args:
        config: Planner parameters.
        cruise_speed: The mission speed [m/s] (MPC_XY_CRUISE, or the mission's DO_CHANGE_SPEED).
        acc_hor / jerk_max: MPC_ACC_HOR [m/s^2] and MPC_JERK_MAX [m/s^3] for the sensor-limited speed.
    """

    def __init__(self, config: Px4AvoidanceConfig = Px4AvoidanceConfig(), cruise_speed: float = 5.0,
                 acc_hor: float = 3.0, jerk_max: float = 8.0):
        c = self.config = config
        limit = sensor_limited_speed(acc_hor, jerk_max, c.max_sensor_range) if c.max_speed_sensor else math.inf
        self.cruise = min(float(cruise_speed), limit)
        self._line_band = float(cruise_speed)  # determineStrategy compares the line distance with MPC_XY_CRUISE
        self._settings = kernel_settings(c)
        self._heading_offset = math.radians(c.heading_offset_deg)
        self.reset()

    def reset(self) -> None:
        """Forget the cloud, the path and the filters (call at the start of each flight)."""
        self._cloud = np.empty((0, 3))
        self._age = np.empty(0)
        self._t = None
        self._path = np.empty((0, 3))
        self._path_t = 0.0
        self._speed = 0.0
        self._sp = None  # smoothed setpoint position
        self._sp_v = (0.0, 0.0, 0.0)
        self._yaw = None
        self._yaw_rate = 0.0
        self._yaw_at_goal = None

    @property
    def cloud(self) -> np.ndarray:
        """The planner's current point cloud (new and remembered points) [m]."""
        return self._cloud

    def step(self, t, position, velocity, yaw, goal, prev_goal, hits, cruise) -> Px4PlannerOutput:
        """The run loop's cycle (:meth:`~surrealist_gym.sim.avoidance.planner.Planner.step`): :meth:`update`, level; the
        speed is the cruise speed the planner was built with (PX4-Avoidance reads MPC_XY_CRUISE at start-up)."""
        return self.update(t, position, velocity, yaw, goal, prev_goal, hits)

    def update(self, t: float, position, velocity, yaw: float, goal, prev_goal, hits: np.ndarray,
               pitch: float = 0.0) -> Px4PlannerOutput:
        """One planner cycle.

        Args:
            t: Time [s]. position, velocity: the vehicle's estimate (x, y, z up) [m], [m/s]. yaw: heading [rad].
            goal: The current mission target (x, y, z up) [m]. prev_goal: the previous one (the mission line).
            hits: (K, 3) world points of the camera's latest cloud [m]. pitch: the vehicle's pitch [rad].
        """
        c = self.config
        dt = 0.1 if self._t is None else min(max(t - self._t, 1e-3), 1.0)
        self._t = t
        px, py, pz = float(position[0]), float(position[1]), float(position[2])
        vel = (float(velocity[0]), float(velocity[1]), float(velocity[2]))
        gx, gy, gz = float(goal[0]), float(goal[1]), float(goal[2])
        new = np.ascontiguousarray(hits, dtype=np.float64).reshape(-1, 3)
        n_max = new.shape[0] + self._cloud.shape[0]
        out, out_age = np.empty((n_max, 3)), np.empty(n_max)
        n = process_cloud(new, self._cloud, self._age, (px, py, pz), (math.degrees(yaw), math.degrees(pitch)),
                           dt, self._settings, out, out_age)
        self._cloud, self._age = out[:n], out_age[:n]
        # closest point on the mission line at goal altitude, or the goal when near the line (determineStrategy)
        on_line, cx, cy = closest_on_line(px, py, float(prev_goal[0]), float(prev_goal[1]), gx, gy, self._line_band)
        cpt = (cx, cy, gz) if on_line else (gx, gy, gz)
        built = False
        if n > 0:
            path = np.empty((MAX_NODES, 3))
            k = build_tree(self._cloud, (px, py, pz), vel, (gx, gy, gz), cpt, self._settings, path)
            if k > 0:
                self._path, self._path_t, built = path[:k][::-1].copy(), t, True
        # waypoint generator
        dx, dy, dz = gx - px, gy - py, gz - pz
        dist_goal = math.sqrt(dx * dx + dy * dy + dz * dz)
        state = "direct"
        aim = None
        if self._path.shape[0] >= 2:
            found, *point = point_on_path(self._path, self._path.shape[0],
                                          c.tree_node_distance + self.cruise * (t - self._path_t))
            aim = tuple(point) if found else None
            if aim is None:
                self._path = np.empty((0, 3))
            else:
                state = "try_path"
        if aim is None:
            aim = (gx, gy, gz)
        ax, ay, az = aim[0] - px, aim[1] - py, aim[2] - pz
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        ux, uy, uz = (ax / norm, ay / norm, az / norm) if norm > 1e-6 else (0.0, 0.0, 0.0)
        if dist_goal < 1.0:  # adaptSpeed: at the goal, aim at it at the distance left; the yaw is latched
            ux, uy, uz = ((gx - px) / max(dist_goal, 1e-6), (gy - py) / max(dist_goal, 1e-6),
                          (gz - pz) / max(dist_goal, 1e-6))
            target = dist_goal
            if self._yaw_at_goal is None:
                self._yaw_at_goal = self._yaw if self._yaw is not None else yaw
        else:
            # scaleToFOV with one camera: a linear ramp over the whole field of view, 0 outside
            heading = math.atan2(uy, ux) if abs(ux) + abs(uy) > 1e-9 else yaw
            off = abs(math.degrees(math.remainder(heading - yaw, 2.0 * math.pi)))
            target = self.cruise * max(0.0, 1.0 - 2.0 * off / c.fov_h_deg)
            self._yaw_at_goal = None
        alpha = dt / (c.speed_filter_tau_s + dt)
        self._speed += alpha * (target - self._speed)
        speed = min(self._speed, dist_goal)
        adapted = (px + ux * speed, py + uy * speed, pz + uz * speed)
        # smoothWaypoint: critically damped filter toward the adapted point; reference: the vehicle's velocity
        # (0 when the adapted point is the goal)
        if self._sp is None:
            self._sp, self._sp_v = (px, py, pz), vel
        at_goal = math.dist(adapted, (gx, gy, gz)) < 0.1
        kp = (c.smoothing_speed_xy, c.smoothing_speed_xy, c.smoothing_speed_z)
        sp, sv = list(self._sp), list(self._sp_v)
        for i in range(3):
            ref = 0.0 if at_goal else vel[i]
            acc = kp[i] * (adapted[i] - sp[i]) + 2.0 * math.sqrt(kp[i]) * (ref - sv[i])
            sv[i] += acc * dt
            sp[i] += sv[i] * dt
        self._sp, self._sp_v = tuple(sp), tuple(sv)
        # nextSmoothYaw: toward the point aimed at, through the same filter (xy gain)
        if self._yaw is None:
            self._yaw, self._yaw_rate = yaw, 0.0
        if self._yaw_at_goal is not None:
            want = self._yaw_at_goal
        elif math.hypot(ax, ay) > 0.1:
            want = math.atan2(ay, ax)
        else:
            want = yaw
        err = math.remainder(want - self._yaw, 2.0 * math.pi)
        kyaw = c.smoothing_speed_xy
        self._yaw_rate += (kyaw * err - 2.0 * math.sqrt(kyaw) * self._yaw_rate) * dt
        self._yaw = math.remainder(self._yaw + self._yaw_rate * dt, 2.0 * math.pi)
        yaw_sp = math.remainder(self._yaw + self._heading_offset, 2.0 * math.pi)
        return Px4PlannerOutput(position=self._sp, yaw=yaw_sp, state=state, speed=speed,
                                path=self._path if built else np.empty((0, 3)), points=n)
