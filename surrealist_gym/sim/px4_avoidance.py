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
from numba import njit

from ..geometry import line_projection

__all__ = ["Px4AvoidanceConfig", "Px4LocalPlanner", "Px4PlannerOutput"]

ALPHA_RES = 6.0  # histogram cell [deg] (avoidance/include/avoidance/histogram.h)
N_E, N_Z = 30, 60
SUB_RES = 2.0  # subsampling cell of the point cloud [deg] (ALPHA_RES / 3)
N_E2, N_Z2 = 90, 180
MAX_NODES = 512


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
class Px4PlannerOutput:
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


def sensor_limited_speed(acc: float, jerk: float, sensor_range: float) -> float:
    """The planner's speed limit from its sensor range: the positive root of u^2 + 2 a (a/j) u - 2 a R = 0."""
    b = 2.0 * acc * acc / max(jerk, 1e-6)
    return 0.5 * (-b + math.sqrt(b * b + 8.0 * acc * sensor_range))


class Px4LocalPlanner:
    """The planner and waypoint generator of one vehicle; call :meth:`update` once per planner cycle.

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
        self._params = np.array([
            c.min_sensor_range, c.max_sensor_range, c.pitch_cost_param, c.yaw_cost_param, c.velocity_cost_param,
            c.obstacle_cost_param, c.tree_heuristic_weight,
            float(int(math.ceil(c.smoothing_margin_degrees / ALPHA_RES))),
            float(c.children_per_node), float(c.n_expanded_nodes), c.tree_node_distance, c.max_point_age_s,
            c.fov_h_deg, c.fov_v_deg], dtype=np.float64)
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
        gx, gy, gz = float(goal[0]), float(goal[1]), float(goal[2])
        new = np.ascontiguousarray(hits, dtype=np.float64).reshape(-1, 3)
        n_max = new.shape[0] + self._cloud.shape[0]
        out, out_age = np.empty((n_max, 3)), np.empty(n_max)
        n = _process_cloud(new, self._cloud, self._age, px, py, pz, math.degrees(yaw), math.degrees(pitch),
                           dt, self._params, out, out_age)
        self._cloud, self._age = out[:n], out_age[:n]
        # closest point on the mission line at goal altitude, or the goal when near the line (determineStrategy)
        cl = _closest_on_line(px, py, (float(prev_goal[0]), float(prev_goal[1])), (gx, gy), self._line_band)
        cpt = (cl[0], cl[1], gz) if cl is not None else (gx, gy, gz)
        built = False
        if n > 0:
            path = np.empty((MAX_NODES, 3))
            k = _build_tree(self._cloud, px, py, pz, float(velocity[0]), float(velocity[1]), float(velocity[2]),
                            gx, gy, gz, cpt[0], cpt[1], cpt[2], self._params, path)
            if k > 0:
                self._path, self._path_t, built = path[:k][::-1].copy(), t, True
        # waypoint generator
        dist_goal = math.sqrt((gx - px) ** 2 + (gy - py) ** 2 + (gz - pz) ** 2)
        state = "direct"
        aim = None
        if self._path.shape[0] >= 2:
            aim = _point_on_path(self._path, c.tree_node_distance + self.cruise * (t - self._path_t))
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
            self._sp, self._sp_v = (px, py, pz), (float(velocity[0]), float(velocity[1]), float(velocity[2]))
        at_goal = math.dist(adapted, (gx, gy, gz)) < 0.1
        kp = (c.smoothing_speed_xy, c.smoothing_speed_xy, c.smoothing_speed_z)
        sp, sv = list(self._sp), list(self._sp_v)
        for i in range(3):
            ref = 0.0 if at_goal else float(velocity[i])
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


def _closest_on_line(px, py, a, b, near: float):
    """The vehicle's projection on the line a -> b, or None when a == b or the vehicle is within ``near`` of it."""
    projection = line_projection(px, py, a, b)
    if projection is None or math.hypot(px - projection[1], py - projection[2]) < near:
        return None
    return projection[1], projection[2]


def _point_on_path(path: np.ndarray, length: float):
    """The point ``length`` metres along the polyline ``path`` (vehicle first), or None past its end."""
    for i in range(path.shape[0] - 1):
        seg = float(np.linalg.norm(path[i + 1] - path[i]))
        if length <= seg:
            f = length / seg if seg > 0 else 0.0
            return tuple(path[i] + f * (path[i + 1] - path[i]))
        length -= seg
    return None


# --- compiled kernels --------------------------------------------------------------------------------------------
_R2D = 180.0 / math.pi


@njit(cache=True, inline="always")
def _atan2_deg(y, x):  # pragma: no cover - compiled
    """atan2 in degrees by a minimax polynomial (error < 1e-4 deg): 3x faster than math.atan2 here."""
    ax, ay = abs(x), abs(y)
    if ax == 0.0 and ay == 0.0:
        return 0.0
    swap = ay > ax
    a = ax / ay if swap else ay / ax
    s = a * a
    r = ((((((-0.0040540580 * s + 0.0218612288) * s - 0.0559098861) * s + 0.0964200441) * s - 0.1390853351) * s
          + 0.1994653599) * s - 0.3332985605) * s * a + a
    if swap:
        r = 1.5707963267948966 - r
    if x < 0.0:
        r = 3.141592653589793 - r
    if y < 0.0:
        r = -r
    return r * 57.29577951308232


@njit(cache=True, inline="always")
def _hist_index(dx, dy, dz, res):  # pragma: no cover - compiled
    """(elevation index, azimuth index) of a direction in a histogram of ``res`` degree cells."""
    h = math.sqrt(dx * dx + dy * dy)
    az = _atan2_deg(dy, dx)
    el = _atan2_deg(dz, h)
    n_z = int(round(360.0 / res))
    n_e = int(round(180.0 / res))
    iz = int(math.floor(az / res + 180.0 / res))
    ie = int(math.floor(el / res + 90.0 / res))
    if iz >= n_z:
        iz -= n_z
    if iz < 0:
        iz += n_z
    if ie >= n_e:
        ie = n_e - 1
    if ie < 0:
        ie = 0
    return ie, iz


@njit(cache=True)
def _process_cloud(new, old, old_age, px, py, pz, yaw_deg, pitch_deg, elapsed, params, out, out_age):
    # pragma: no cover - compiled
    rmin, rmax, max_age, hfov, vfov = params[0], params[1], params[11], params[12], params[13]
    occupied = np.zeros((N_E2, N_Z2), dtype=np.bool_)
    k = 0
    for i in range(new.shape[0]):
        dx, dy, dz = new[i, 0] - px, new[i, 1] - py, new[i, 2] - pz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d <= rmin or d >= rmax:
            continue
        ie, iz = _hist_index(dx, dy, dz, SUB_RES)
        if occupied[ie, iz]:
            continue
        occupied[ie, iz] = True
        out[k, 0], out[k, 1], out[k, 2] = new[i, 0], new[i, 1], new[i, 2]
        out_age[k] = 0.0
        k += 1
    half_h, half_v = 0.5 * hfov, 0.5 * vfov
    for i in range(old.shape[0]):
        if old_age[i] >= max_age:
            continue
        dx, dy, dz = old[i, 0] - px, old[i, 1] - py, old[i, 2] - pz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d >= rmax:
            continue
        ie, iz = _hist_index(dx, dy, dz, SUB_RES)
        if occupied[ie, iz]:
            continue
        # pointInsideFOV in the body frame: the camera would see the point if it were still there
        off_az = (_atan2_deg(dy, dx) - yaw_deg + 180.0) % 360.0 - 180.0
        off_el = _atan2_deg(dz, math.sqrt(dx * dx + dy * dy)) - pitch_deg
        if abs(off_az) <= half_h and abs(off_el) <= half_v:
            continue
        occupied[ie, iz] = True
        out[k, 0], out[k, 1], out[k, 2] = old[i, 0], old[i, 1], old[i, 2]
        out_age[k] = old_age[i] + elapsed
        k += 1
    return k


@njit(cache=True)
def _histogram(cloud, ox, oy, oz, dist, count):  # pragma: no cover - compiled
    """Fill ``dist`` (N_E x N_Z) with the mean distance of the cloud's points per cell seen from (ox, oy, oz);
    ``count`` is a work buffer of the same shape."""
    count[:, :] = 0.0
    dist[:, :] = 0.0
    for i in range(cloud.shape[0]):
        dx, dy, dz = cloud[i, 0] - ox, cloud[i, 1] - oy, cloud[i, 2] - oz
        ie, iz = _hist_index(dx, dy, dz, ALPHA_RES)
        dist[ie, iz] += math.sqrt(dx * dx + dy * dy + dz * dz)
        count[ie, iz] += 1.0
    n = 0
    for e in range(N_E):
        for z in range(N_Z):
            if count[e, z] > 0:
                dist[e, z] /= count[e, z]
                n += 1
    return n


@njit(cache=True)
def _smooth_columns(matrix, radius, padded, box):  # pragma: no cover - compiled
    """smoothPolarMatrix, first half: pad with the polar wrap rules, then the conic kernel (1, r/(r+1), ...,
    1/(r+1)), summed, along elevation, as two running box sums of length r + 1. ``padded`` (ne + 2r, nz + 2r)
    holds the result; ``box`` (>= max(ne, nz) + r) is a work buffer. :func:`_smooth_row` finishes a row."""
    r = radius
    ne, nz = matrix.shape
    half = nz // 2
    length = r + 1
    padded[:, :] = 0.0
    padded[r:r + ne, r:r + nz] = matrix
    for i in range(r):  # rows beyond the poles: the opposite azimuth, mirrored in elevation
        for z in range(nz):
            zs = (z + half) % nz
            padded[r - 1 - i, r + z] = matrix[i, zs]
            padded[r + ne + i, r + z] = matrix[ne - 1 - i, zs]
    for row in range(ne + 2 * r):  # azimuth wrap
        for i in range(r):
            padded[row, i] = padded[row, nz + i]
            padded[row, r + nz + i] = padded[row, r + i]
    m = ne + r
    for z in range(nz + 2 * r):  # all-zero columns stay zero
        nonzero = False
        for row in range(ne + 2 * r):
            if padded[row, z] != 0.0:
                nonzero = True
                break
        if not nonzero:
            continue
        s = 0.0
        for j in range(length):
            s += padded[j, z]
        box[0] = s
        for j in range(1, m):
            s += padded[j + length - 1, z] - padded[j - 1, z]
            box[j] = s
        s = 0.0
        for j in range(length):
            s += box[j]
        padded[r, z] = s / length
        for i in range(1, ne):  # writes row r + i, reads box only: safe in place
            s += box[i + length - 1] - box[i - 1]
            padded[r + i, z] = s / length


@njit(cache=True)
def _smooth_row(padded, radius, e, box, out):  # pragma: no cover - compiled
    """smoothPolarMatrix, second half for elevation row ``e``: the conic kernel along azimuth into ``out``."""
    r = radius
    nz = out.shape[0]
    length = r + 1
    row = r + e
    m = nz + r
    s = 0.0
    for j in range(length):
        s += padded[row, j]
    box[0] = s
    for j in range(1, m):
        s += padded[row, j + length - 1] - padded[row, j - 1]
        box[j] = s
    s = 0.0
    for j in range(length):
        s += box[j]
    out[0] = s / length
    for i in range(1, nz):
        s += box[i + length - 1] - box[i - 1]
        out[i] = s / length


@njit(cache=True)
def _best_cells(cloud, ox, oy, oz, vx, vy, vz, gx, gy, gz, cx, cy, cz, params, dist, count, obst, padded, box,
                cand_e, cand_z, cand_c):
    # pragma: no cover - compiled
    """Histogram and cost matrix at (ox, oy, oz) with velocity v; fill the cheapest cells; return their count."""
    rmin, rmax = params[0], params[1]
    w_pitch, w_yaw, w_vel, obst_param = params[2], params[3], params[4], params[5]
    radius = int(params[7])
    n_best = int(params[8])
    _histogram(cloud, ox, oy, oz, dist, count)
    obst[:, :] = 0.0
    any_obstacle = False
    for e in range(N_E):
        for z in range(N_Z):
            d = dist[e, z]
            if d > 0.0:
                x = obst_param - d
                obst[e, z] = 5000.0 * (1.0 + x / math.sqrt(1.0 + x * x))
                any_obstacle = True
    smooth = any_obstacle and radius > 0
    if smooth:
        _smooth_columns(obst, radius, padded, box)
    # goal and line directions from the origin
    dgx, dgy, dgz = gx - ox, gy - oy, gz - oz
    dist_goal = math.sqrt(dgx * dgx + dgy * dgy + dgz * dgz)
    az_goal = math.atan2(dgy, dgx) * _R2D
    el_goal = math.atan2(dgz, math.sqrt(dgx * dgx + dgy * dgy)) * _R2D
    az_line = math.atan2(cy - oy, cx - ox) * _R2D
    # obstacle in the goal's window (goal cell +-5 azimuth, +-2 elevation cells, distance in (0.2, 15) m)?
    ge, gz_i = _hist_index(dgx, dgy, dgz, ALPHA_RES)
    blocked = False
    for de in range(-2, 3):
        e = ge + de
        if e < 0 or e >= N_E:
            continue
        for dz_ in range(-5, 6):
            z = (gz_i + dz_) % N_Z
            if rmin < dist[e, z] < rmax:
                blocked = True
    w_line = 0.0 if blocked else 0.5
    pitch_scale = 1.0
    if dist_goal < 5.0:
        pitch_scale = 1.0 / max((0.2 * dist_goal) ** 2, 1e-6)
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    yaw_cost = np.empty(N_Z)
    cos_a = np.empty(N_Z)
    sin_a = np.empty(N_Z)
    for z in range(N_Z):
        az = z * ALPHA_RES + 0.5 * ALPHA_RES - 180.0
        a = (az - az_goal + 180.0) % 360.0 - 180.0
        b = (az - az_line + 180.0) % 360.0 - 180.0
        yaw_cost[z] = w_yaw * ((1.0 - w_line) * a * a + w_line * b * b)
        cos_a[z] = math.cos(az / _R2D)
        sin_a[z] = math.sin(az / _R2D)
    min_yaw = yaw_cost.min()
    row_cost = np.empty(N_E)
    for e in range(N_E):
        de = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0 - el_goal
        row_cost[e] = w_pitch * de * de * pitch_scale
    obst_row = np.zeros(N_Z)
    n = 0
    # rows by increasing pitch cost; a row whose every cost is at least its pitch cost plus the least yaw cost
    # (obstacle and velocity costs are >= 0) cannot beat a full candidate list, and is skipped
    for e in np.argsort(row_cost, kind="mergesort"):
        pitch_cost = row_cost[e]
        if n == n_best and pitch_cost + min_yaw >= cand_c[n - 1]:
            break
        el = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0
        ce, se = math.cos(el / _R2D), math.sin(el / _R2D)
        if smooth:
            _smooth_row(padded, radius, e, box, obst_row)
        else:
            for z in range(N_Z):
                obst_row[z] = obst[e, z]
        for z in range(N_Z):
            dot = ce * (cos_a[z] * vx + sin_a[z] * vy) + se * vz
            cost = obst_row[z] + yaw_cost[z] + pitch_cost + w_vel * (speed - dot)
            # keep the n_best cheapest, sorted ascending
            if n < n_best:
                j = n
                n += 1
            elif cost < cand_c[n - 1]:
                j = n - 1
            else:
                continue
            while j > 0 and cand_c[j - 1] > cost:
                cand_c[j], cand_e[j], cand_z[j] = cand_c[j - 1], cand_e[j - 1], cand_z[j - 1]
                j -= 1
            cand_c[j], cand_e[j], cand_z[j] = cost, e, z
    return n


@njit(cache=True)
def _build_tree(cloud, px, py, pz, vx, vy, vz, gx, gy, gz, cx, cy, cz, params, path):
    # pragma: no cover - compiled
    """StarPlanner::buildLookAheadTree; writes the path deepest node first into ``path``, returns its length
    (0 when the vehicle's histogram is empty)."""
    rmax, w_h, n_best, n_exp, step = params[1], params[6], int(params[8]), int(params[9]), params[10]
    pos = np.empty((MAX_NODES, 3))
    parent = np.empty(MAX_NODES, dtype=np.int64)
    depth = np.empty(MAX_NODES, dtype=np.int64)
    total = np.empty(MAX_NODES)
    heur = np.empty(MAX_NODES)
    closed = np.zeros(MAX_NODES, dtype=np.bool_)
    dist = np.empty((N_E, N_Z))
    count = np.empty((N_E, N_Z))
    obst = np.empty((N_E, N_Z))
    radius = int(params[7])
    padded = np.empty((N_E + 2 * radius, N_Z + 2 * radius))
    box = np.empty(N_Z + 2 * radius)
    cand_e = np.empty(n_best, dtype=np.int64)
    cand_z = np.empty(n_best, dtype=np.int64)
    cand_c = np.empty(n_best)
    pos[0, 0], pos[0, 1], pos[0, 2] = px, py, pz
    parent[0], depth[0] = -1, 0
    h0 = w_h * math.sqrt((gx - px) ** 2 + (gy - py) ** 2 + (gz - pz) ** 2)
    total[0], heur[0] = h0, h0
    size = 1
    origin = 0
    for it in range(n_exp):
        ox, oy, oz = pos[origin, 0], pos[origin, 1], pos[origin, 2]
        if origin == 0:
            ux, uy, uz = vx, vy, vz
        else:
            p = parent[origin]
            ux, uy, uz = ox - pos[p, 0], oy - pos[p, 1], oz - pos[p, 2]
        k = _best_cells(cloud, ox, oy, oz, ux, uy, uz, gx, gy, gz, cx, cy, cz, params, dist, count, obst, padded,
                        box, cand_e, cand_z, cand_c)
        if it == 0:
            empty = True
            for e in range(N_E):
                for z in range(N_Z):
                    if dist[e, z] > 0.0:
                        empty = False
            if empty:
                return 0
        for j in range(k):
            if size >= MAX_NODES:
                break
            el = (cand_e[j] * ALPHA_RES + 0.5 * ALPHA_RES - 90.0) / _R2D
            az = (cand_z[j] * ALPHA_RES + 0.5 * ALPHA_RES - 180.0) / _R2D
            nx = ox + step * math.cos(el) * math.cos(az)
            ny = oy + step * math.cos(el) * math.sin(az)
            nz = oz + step * math.sin(el)
            close = False
            for i in range(size):
                if (pos[i, 0] - nx) ** 2 + (pos[i, 1] - ny) ** 2 + (pos[i, 2] - nz) ** 2 < 0.04:
                    close = True
                    break
            if close:
                continue
            pos[size, 0], pos[size, 1], pos[size, 2] = nx, ny, nz
            parent[size], depth[size] = origin, depth[origin] + 1
            h = w_h * math.sqrt((gx - nx) ** 2 + (gy - ny) ** 2 + (gz - nz) ** 2)
            heur[size] = h
            total[size] = total[origin] - heur[origin] + cand_c[j] + h
            size += 1
        closed[origin] = True
        best = -1
        best_cost = np.inf
        for i in range(size):
            if closed[i]:
                continue
            d2 = (pos[i, 0] - px) ** 2 + (pos[i, 1] - py) ** 2 + (pos[i, 2] - pz) ** 2
            if total[i] < best_cost and d2 < rmax * rmax:
                best_cost = total[i]
                best = i
        if best < 0:
            break
        origin = best
    # the path ends at the first open node of the greatest depth (PR #555), the root when none is open
    end, deepest = 0, 0
    for i in range(size):
        if not closed[i] and depth[i] > deepest:
            end, deepest = i, depth[i]
    n = 0
    while end >= 0:
        path[n, 0], path[n, 1], path[n, 2] = pos[end, 0], pos[end, 1], pos[end, 2]
        n += 1
        end = parent[end]
    return n
