"""A local obstacle-avoidance planner in the manner of PX4-Avoidance's local planner (3DVFH+ / VFH*).

World frame: x north, y east, z up [m]; yaw [rad] from north toward east. Each :meth:`LocalPlanner.update`

1. adds the latest depth hits to a memory of voxels (last-seen time per ``voxel_size`` cell) and forgets voxels
   not seen for ``memory_time`` (so obstacles that left the narrow field of view are still avoided);
2. bins the remembered points within ``[range_min, range_max]`` into a polar histogram (``bin_deg`` cells in
   azimuth and elevation), keeping the nearest point of each cell;
3. scores candidate directions (every azimuth bin x the ``elevation_bands_deg``):

   - obstacle cost ``w * (1 + d / sqrt(1 + d^2))`` with ``d = obstacle_cost_center - distance`` for every
     occupied cell, spread over neighbouring directions by a conic kernel of ``smoothing_radius_deg`` (the
     largest contribution counts); directions whose straight line passes a point closer than
     ``safety_margin`` get ``blocked_cost`` on top, so they are taken only when nothing else is left;
   - yaw cost ``yaw_cost_weight * (azimuth difference to the goal [deg])^2``, pitch cost
     ``pitch_cost_weight * (elevation difference [deg])^2`` and velocity cost
     ``velocity_cost_weight * (|v| - u . v)``, which resists turning away from the current velocity;

4. takes the cheapest direction, turns toward it at most ``max_turn_rate_deg_s``, and flies it at
   ``avoid_speed`` when an obstacle ahead is nearer than ``slow_down_distance`` (blending up to the mission
   speed over ``slow_down_ramp``); it stops if every direction is blocked.

With no remembered obstacle in range the planner flies straight at the goal at the mission speed. Near the goal
the speed is capped by ``sqrt(2 * goal_brake_accel * distance)``. The look-ahead tree of PX4's planner is not
modelled; the velocity cost and the turn-rate limit give the smooth, decided detours it produces.

Example::

    >>> import numpy as np
    >>> planner = LocalPlanner()
    >>> out = planner.update(0.0, (0, 0, 3), (0, 0, 0), (30, 0, 3), np.empty((0, 3)), max_speed=5.0)
    >>> out.velocity
    (5.0, 0.0, 0.0)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
from numba import njit, types
from numba.typed import Dict

from .planner import Planner, PlannerCommand

__all__ = ["AvoidanceConfig", "PlannerOutput", "LocalPlanner", "YawMode"]


class YawMode(str, Enum):
    """Where the yaw setpoint (and so the depth camera) points while avoiding."""

    DIRECTION = "direction"  #: along the chosen flight direction: the camera sees where the UAV goes
    GOAL = "goal"  #: toward the goal; the narrow camera then misses the ends of wide obstacles (can dither)



@dataclass(frozen=True, slots=True)
class AvoidanceConfig:
    """Local planner parameters (units in the names or below).

    Attributes:
        cruise_speed: Speed when ``update`` gets no ``max_speed`` [m/s] (PX4's MPC_XY_CRUISE).
        avoid_speed: Speed while an obstacle is near [m/s]; the real PX4 Vision flew ~0.7-0.8 m/s around obstacles.
        slow_down_distance: An obstacle ahead nearer than this [m] imposes ``avoid_speed``.
        near_distance: A remembered point nearer than this [m], in any direction, also imposes ``avoid_speed``.
        slow_down_ramp: Beyond ``slow_down_distance`` the speed rises linearly to the mission speed over this [m].
        goal_brake_accel: Deceleration toward the goal [m/s^2]: speed <= sqrt(2 * a * distance to goal).
        range_min: Remembered points nearer than this are ignored [m] (PX4-Avoidance: 0.2).
        range_max: Remembered points farther than this are ignored [m] (PX4-Avoidance: 15).
        memory_time: A voxel not seen again for this long is forgotten [s] (PX4-Avoidance: ~20).
        voxel_size: Edge of the memory voxels [m].
        bin_deg: Polar histogram cell size in azimuth and elevation [deg] (PX4-Avoidance: 6).
        elevation_bands_deg: Elevations of the candidate directions [deg]; the default (0,) makes detours
            lateral, as in the real flights (PX4's pitch cost strongly favours them).
        obstacle_cost_weight: ``w`` of the obstacle cost ``w * (1 + d / sqrt(1 + d^2))`` (PX4-Avoidance: 5000).
        obstacle_cost_center: Distance at which the obstacle cost is ``w`` [m] (PX4-Avoidance: 8.5).
        smoothing_radius_deg: Radius of the conic kernel that spreads obstacle costs [deg] (~40 in PX4).
        safety_margin: Directions whose straight line passes a point nearer than this are blocked [m].
        blocked_cost: Cost added to a blocked direction (larger than any other cost).
        yaw_cost_weight: Cost per squared degree of azimuth away from the goal (PX4-Avoidance: 3).
        pitch_cost_weight: Cost per squared degree of elevation away from the goal (PX4-Avoidance: 25).
        velocity_cost_weight: Cost per m/s of ``|v| - u . v`` (PX4-Avoidance: 6000).
        yaw_mode: Where the yaw setpoint points while avoiding (with no obstacle: at the goal).
        max_turn_rate_deg_s: Fastest change of the commanded heading while avoiding [deg/s].
        waypoint_distance: Distance of the returned intermediate waypoint along the chosen direction [m].
        altitude_gain: While avoiding, vertical speed per metre of altitude error to the goal [1/s].
        vertical_margin: While avoiding, keep at least this height above the top of remembered obstacle points
            within ``vertical_radius`` horizontally [m] (0 = off). PX4-Avoidance's elevation costs make the real
            PX4 Vision rise over nearby obstacle tops (case0: from 3.3 m to ~4.5 m beside a ~2.5 m container).
        vertical_radius: Horizontal radius of that look-around [m].
        vertical_reach: Only obstacles whose top is at most this far above the vehicle are climbed over [m];
            taller ones (walls, buildings) are passed around laterally.
        max_climb_rate: Cap on that vertical speed [m/s].
        goal_tolerance: Within this distance of the goal the planner commands zero velocity [m].
    """

    cruise_speed: float = 5.0
    avoid_speed: float = 0.75
    slow_down_distance: float = 8.0
    near_distance: float = 4.0
    slow_down_ramp: float = 4.0
    goal_brake_accel: float = 1.0
    range_min: float = 0.2
    range_max: float = 15.0
    memory_time: float = 20.0
    voxel_size: float = 0.25
    bin_deg: float = 6.0
    elevation_bands_deg: tuple[float, ...] = (0.0,)
    obstacle_cost_weight: float = 5000.0
    obstacle_cost_center: float = 8.5
    smoothing_radius_deg: float = 40.0
    safety_margin: float = 2.0
    blocked_cost: float = 1e6
    yaw_cost_weight: float = 3.0
    pitch_cost_weight: float = 25.0
    velocity_cost_weight: float = 6000.0
    yaw_mode: YawMode = YawMode.DIRECTION
    max_turn_rate_deg_s: float = 90.0
    waypoint_distance: float = 2.0
    altitude_gain: float = 0.5
    vertical_margin: float = 1.5
    vertical_radius: float = 4.0
    vertical_reach: float = 1.0
    max_climb_rate: float = 1.0
    goal_tolerance: float = 0.05

    def __post_init__(self):
        for name in ("cruise_speed", "avoid_speed", "goal_brake_accel", "range_max", "memory_time", "voxel_size",
                     "bin_deg", "max_turn_rate_deg_s", "smoothing_radius_deg"):
            value = getattr(self, name)
            if not value > 0:
                raise ValueError(f"AvoidanceConfig.{name}: expected a positive number, got {value!r}")
        object.__setattr__(self, "yaw_mode", YawMode(self.yaw_mode))
        for name in ("slow_down_distance", "near_distance", "slow_down_ramp", "range_min", "safety_margin",
                     "blocked_cost",
                     "yaw_cost_weight", "pitch_cost_weight", "velocity_cost_weight", "obstacle_cost_weight",
                     "waypoint_distance", "altitude_gain", "max_climb_rate", "goal_tolerance", "vertical_margin",
                     "vertical_radius", "vertical_reach"):
            value = getattr(self, name)
            if not value >= 0:
                raise ValueError(f"AvoidanceConfig.{name}: expected a number >= 0, got {value!r}")
        if abs(360.0 / self.bin_deg - round(360.0 / self.bin_deg)) > 1e-9:
            raise ValueError(f"AvoidanceConfig.bin_deg: must divide 360, got {self.bin_deg!r}")
        bands = tuple(float(b) for b in self.elevation_bands_deg)
        if not bands or any(not -90.0 < b < 90.0 for b in bands):
            raise ValueError(f"AvoidanceConfig.elevation_bands_deg: expected angles in (-90, 90), got {bands!r}")
        object.__setattr__(self, "elevation_bands_deg", bands)


@dataclass(frozen=True, slots=True)
class PlannerOutput(PlannerCommand):
    """One planner decision (a velocity setpoint: ``position`` is None).

    Attributes:
        velocity: World-frame velocity setpoint (vx, vy, vz) [m/s].
        yaw: Yaw setpoint [rad] from north toward east.
        waypoint: Intermediate goal point (x, y, z) [m] along the chosen direction.
    """

    velocity: tuple[float, float, float]
    yaw: float
    waypoint: tuple[float, float, float]
    position = None  #: this planner commands a velocity, not a position setpoint


class LocalPlanner(Planner):
    """Chooses a velocity setpoint from a memory of depth hits; call :meth:`update` (or the run loop's
    :meth:`step`) at ~10-20 Hz.

    Args:
        config: Planner parameters.
    """

    def __init__(self, config: AvoidanceConfig = AvoidanceConfig()):
        self.config = c = config
        n_az = int(round(360.0 / c.bin_deg))
        az = -math.pi + (np.arange(n_az) + 0.5) * math.radians(c.bin_deg)
        el = np.radians(np.array(c.elevation_bands_deg))
        ee, aa = np.meshgrid(el, az, indexing="ij")  # (n_bands, n_az)
        self._cand = np.ascontiguousarray(
            np.stack([np.cos(ee) * np.cos(aa), np.cos(ee) * np.sin(aa), np.sin(ee)], axis=-1))
        self._cand_az = np.ascontiguousarray(np.degrees(aa))
        self._cand_el = np.ascontiguousarray(np.degrees(ee))
        self._params = np.array([c.range_min, c.range_max, c.bin_deg, c.obstacle_cost_weight,
                                 c.obstacle_cost_center, c.smoothing_radius_deg, c.safety_margin, c.blocked_cost,
                                 c.yaw_cost_weight, c.pitch_cost_weight, c.velocity_cost_weight,
                                 c.vertical_radius])
        self.reset()

    def reset(self) -> None:
        """Forget the obstacle memory and the previous command (call at the start of each flight)."""
        self._memory = Dict.empty(key_type=types.int64, value_type=types.float64)
        self._t_prev: float | None = None
        self._heading: float | None = None  # last commanded azimuth while avoiding [rad]
        self._yaw: float | None = None

    @property
    def memory_size(self) -> int:
        """Number of remembered voxels."""
        return len(self._memory)

    def step(self, t, position, velocity, yaw, goal, prev_goal, hits, cruise) -> PlannerOutput:
        """The run loop's cycle (:meth:`~surrealist_gym.sim.avoidance.planner.Planner.step`): :meth:`update` at the
        mission's speed; this planner reads neither the yaw nor the mission line."""
        return self.update(t, position, velocity, goal, hits, max_speed=cruise)

    def update(self, t: float, position, velocity, goal, hits: np.ndarray,
               max_speed: float | None = None) -> PlannerOutput:
        """Plan one step.

        Args:
            t: Time [s] (monotonic within a flight; used for the memory and the turn-rate limit).
            position: UAV position (x, y, z) [m].
            velocity: UAV velocity (vx, vy, vz) [m/s].
            goal: Current goal (x, y, z) [m], e.g. the mission's current waypoint.
            hits: ``(K, 3)`` obstacle points [m] from the latest scan (may be empty).
            max_speed: Mission speed [m/s]; ``config.cruise_speed`` when None.

        Returns:
            The velocity and yaw setpoints and the intermediate waypoint.
        """
        c = self.config
        speed_max = c.cruise_speed if max_speed is None else float(max_speed)
        px, py, pz = float(position[0]), float(position[1]), float(position[2])
        gx, gy, gz = float(goal[0]) - px, float(goal[1]) - py, float(goal[2]) - pz
        vx, vy, vz = float(velocity[0]), float(velocity[1]), float(velocity[2])
        dt = 0.0 if self._t_prev is None else min(max(t - self._t_prev, 0.0), 1.0)
        self._t_prev = t
        pts = np.ascontiguousarray(hits, dtype=np.float64).reshape(-1, 3)
        dist_goal = math.sqrt(gx * gx + gy * gy + gz * gz)
        dist_goal_h = math.hypot(gx, gy)
        az_goal = math.atan2(gy, gx) if dist_goal_h > 1e-9 else (self._yaw or 0.0)
        el_goal = math.degrees(math.atan2(gz, dist_goal_h))
        best, blocked, d_near, d_min, top = plan_step(self._memory, pts, t, c.memory_time, c.voxel_size, px, py, pz,
                                                  vx, vy, vz, math.degrees(az_goal), el_goal, self._cand,
                                                  self._cand_az, self._cand_el, self._params)
        speed = min(speed_max, math.sqrt(2.0 * c.goal_brake_accel * dist_goal))
        if dist_goal <= c.goal_tolerance:
            speed = 0.0
        if best < 0:  # nothing in range: straight at the goal
            self._heading = None
            if dist_goal > 1e-9:
                ux, uy, uz = gx / dist_goal, gy / dist_goal, gz / dist_goal
            else:
                ux, uy, uz = 0.0, 0.0, 0.0
            vel = (speed * ux, speed * uy, speed * uz)
            if dist_goal_h > 1e-9:
                self._yaw = az_goal
        else:
            n_az = self._cand.shape[1]
            band, ia = divmod(best, n_az)
            heading = math.radians(self._cand_az[band, ia])
            elev = math.radians(self._cand_el[band, ia])
            if self._heading is not None:
                step = math.radians(c.max_turn_rate_deg_s) * dt
                diff = math.remainder(heading - self._heading, 2.0 * math.pi)
                heading = self._heading + max(-step, min(step, diff))
            self._heading = heading
            if blocked:
                speed = 0.0
            else:
                ramp = (d_near - c.slow_down_distance) / c.slow_down_ramp if c.slow_down_ramp > 0 else (
                    1.0 if d_near > c.slow_down_distance else 0.0)
                ramp = 0.0 if d_min < c.near_distance else max(0.0, min(1.0, ramp))
                avoid = min(c.avoid_speed, speed)
                speed = avoid + (speed - avoid) * ramp
            target_dz = gz
            if c.vertical_margin > 0 and -np.inf < top <= pz + c.vertical_reach:
                target_dz = max(gz, top + c.vertical_margin - pz)
            climb = max(-c.max_climb_rate, min(c.max_climb_rate, c.altitude_gain * target_dz))
            ch = speed * math.cos(elev)
            ux, uy, uz = math.cos(heading) * math.cos(elev), math.sin(heading) * math.cos(elev), math.sin(elev)
            vel = (ch * math.cos(heading), ch * math.sin(heading), speed * math.sin(elev) + climb)
            if c.yaw_mode == YawMode.DIRECTION or dist_goal_h <= 1e-9:
                self._yaw = heading
            else:
                self._yaw = az_goal
        yaw = self._yaw if self._yaw is not None else 0.0
        wd = c.waypoint_distance
        waypoint = (px + wd * ux, py + wd * uy, pz + wd * uz)
        return PlannerOutput(velocity=vel, yaw=math.remainder(yaw, 2.0 * math.pi), waypoint=waypoint)


@njit(cache=True)
def plan_step(memory, hits, t, memory_time, voxel, px, py, pz, vx, vy, vz, az_goal, el_goal, cand, cand_az, cand_el,
          params):  # pragma: no cover - compiled
    """Update the voxel memory, build the polar histogram and score the candidates.

    Returns (best candidate flat index or -1 when no obstacle is in range, whether it is blocked, distance to the
    nearest remembered point ahead of it [m], distance to the nearest remembered point [m], highest z of the
    remembered points within the vertical radius horizontally [m], -inf if none).
    """
    rmin, rmax, bin_deg, w_obs, center, smooth, margin, blocked_cost = (params[0], params[1], params[2], params[3],
                                                                       params[4], params[5], params[6], params[7])
    w_yaw, w_pitch, w_vel, v_radius = params[8], params[9], params[10], params[11]
    top = -np.inf
    off = 1 << 20
    # 1. memory: insert the hits, forget stale voxels
    for i in range(hits.shape[0]):
        ix = int(math.floor(hits[i, 0] / voxel)) + off
        iy = int(math.floor(hits[i, 1] / voxel)) + off
        iz = int(math.floor(hits[i, 2] / voxel)) + off
        memory[(ix << 42) | (iy << 21) | iz] = t
    stale = []
    for key, seen in memory.items():
        if t - seen > memory_time:
            stale.append(key)
    for key in stale:
        del memory[key]
    # 2. polar histogram of the nearest point per cell
    n_az = int(round(360.0 / bin_deg))
    n_el = int(round(180.0 / bin_deg))
    cell_d = np.full(n_el * n_az, np.inf)
    cell_u = np.empty((n_el * n_az, 3))
    occupied = np.empty(n_el * n_az, dtype=np.int64)
    n_occ = 0
    mask = (1 << 21) - 1
    bin_rad = math.radians(bin_deg)
    for key in memory.keys():
        rx = ((key >> 42) - off + 0.5) * voxel - px
        ry = (((key >> 21) & mask) - off + 0.5) * voxel - py
        rz = ((key & mask) - off + 0.5) * voxel - pz
        d = math.sqrt(rx * rx + ry * ry + rz * rz)
        if d < rmin or d > rmax:
            continue
        if rx * rx + ry * ry <= v_radius * v_radius and rz + pz > top:
            top = rz + pz
        ia = int((math.atan2(ry, rx) + math.pi) / bin_rad) % n_az
        ie = min(int((math.asin(rz / d) + 0.5 * math.pi) / bin_rad), n_el - 1)
        cell = ie * n_az + ia
        if cell_d[cell] == np.inf:
            occupied[n_occ] = cell
            n_occ += 1
        if d < cell_d[cell]:
            cell_d[cell] = d
            cell_u[cell, 0] = rx / d
            cell_u[cell, 1] = ry / d
            cell_u[cell, 2] = rz / d
    if n_occ == 0:
        return -1, False, np.inf, np.inf, top
    # 3. candidate costs
    n_b = cand.shape[0]
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    cost = np.empty((n_b, n_az))
    obst = np.zeros((n_b, n_az))
    blocked = np.zeros((n_b, n_az), dtype=np.bool_)
    for b in range(n_b):
        for a in range(n_az):
            da = (cand_az[b, a] - az_goal + 180.0) % 360.0 - 180.0
            de = cand_el[b, a] - el_goal
            dot = cand[b, a, 0] * vx + cand[b, a, 1] * vy + cand[b, a, 2] * vz
            cost[b, a] = w_yaw * da * da + w_pitch * de * de + w_vel * (speed - dot)
    half_n = n_az // 2
    for j in range(n_occ):
        cell = occupied[j]
        d = cell_d[cell]
        x = center - d
        c_obs = w_obs * (1.0 + x / math.sqrt(1.0 + x * x))
        beta = 90.0 if d <= margin else math.degrees(math.asin(margin / d))
        reach = beta + smooth
        cos_beta = math.cos(math.radians(beta))
        cos_reach = math.cos(math.radians(reach)) if reach < 180.0 else -2.0
        ie = cell // n_az
        ia = cell % n_az
        cos_el = math.cos((ie + 0.5) * bin_rad - 0.5 * math.pi)
        if cos_el < 0.05:
            half = half_n
        else:
            half = min(half_n, int(math.ceil(reach / bin_deg / cos_el)) + 1)
        ux, uy, uz = cell_u[cell, 0], cell_u[cell, 1], cell_u[cell, 2]
        for k in range(-half, half + 1 if 2 * half < n_az else half):
            a = (ia + k) % n_az
            for b in range(n_b):
                cs = cand[b, a, 0] * ux + cand[b, a, 1] * uy + cand[b, a, 2] * uz
                if cs <= cos_reach:
                    continue
                if cs > cos_beta:
                    blocked[b, a] = True
                    val = c_obs
                else:
                    sep = math.degrees(math.acos(min(1.0, cs)))
                    val = c_obs * (1.0 - (sep - beta) / smooth)
                if val > obst[b, a]:
                    obst[b, a] = val
    best = 0
    best_cost = np.inf
    for b in range(n_b):
        for a in range(n_az):
            total = cost[b, a] + obst[b, a] + (blocked_cost if blocked[b, a] else 0.0)
            if total < best_cost:
                best_cost = total
                best = b * n_az + a
    bb, ba = best // n_az, best % n_az
    d_near = np.inf
    d_min = np.inf
    for j in range(n_occ):
        cell = occupied[j]
        d_min = min(d_min, cell_d[cell])
        ahead = (cand[bb, ba, 0] * cell_u[cell, 0] + cand[bb, ba, 1] * cell_u[cell, 1]
                 + cand[bb, ba, 2] * cell_u[cell, 2])
        if ahead > 0.0 and cell_d[cell] < d_near:
            d_near = cell_d[cell]
    return best, blocked[bb, ba], d_near, d_min, top
