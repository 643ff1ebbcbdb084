"""PX4 v1.12's mission flight task (FlightTaskAutoLineSmoothVel) when obstacle avoidance injects the setpoints.

Frame: x north, y east, z up [m] (the navigator's mission frame). Each :meth:`AvoidanceFlightTask.update` is one
position-control cycle. Sources (PX4-Autopilot v1.12 line, ``src/modules/flight_mode_manager/tasks/``):

- ``ObstacleAvoidance::injectAvoidanceSetpoints``: the planner's point replaces the position setpoint (no
  velocity); its yaw replaces the yaw setpoint.
- ``FlightTaskAuto::_updateInternalWaypoints``: PX4's own target is the mission item, or, when the vehicle is more
  than the acceptance radius (NAV_ACC_RAD) off the line from the previous item, the foot of the perpendicular
  on that line ("offtrack").
- ``FlightTaskAutoLineSmoothVel::_getMaxXYSpeed``: as the target is modified, PX4 plans to stop at the injected
  point: speed ``1/2 (-b + sqrt(b^2 + 8 a d))``, ``b = 4 a^2 / j`` (TrajMath ``computeMaxSpeedFromDistance``,
  a = MPC_ACC_HOR, j = MPC_JERK_AUTO, d = horizontal distance from the trajectory's position to the point), at
  most MPC_XY_CRUISE; vertically the same law with MPC_ACC_UP_MAX / MPC_ACC_DOWN_MAX.
- ``_updateTurningCheck`` / ``_prepareSetpoints``: while "turning" (trajectory faster than 0.2 m/s, its velocity
  more than acos(0.98) = 11.5 deg off the bearing to PX4's target, the target farther than the acceptance radius)
  the horizontal speed is capped at its value the last time the trajectory was not turning. With NAV_ACC_RAD =
  0.5 m every detour is "offtrack", so a near-stop during a detour locks the speed at ~0.3 m/s until the vehicle
  regains the line or the goal: the slow crawls of PX4 SITL flights.
- ``VelocitySmoothing``: a jerk-limited (MPC_JERK_AUTO) and acceleration-limited velocity profile per axis whose
  integral is the position setpoint; time runs slower (``1 - error / MPC_XY_ERR_MAX``) while the vehicle lags
  behind it. The profile is approximated by a per-step jerk-limited approach to the velocity target (the
  time-synchronisation of the axes is not modelled).
"""
from __future__ import annotations

import math

from ...geometry import line_projection

__all__ = ["AvoidanceFlightTask", "stopping_speed"]

COS_TURN = 0.98  # _updateTurningCheck: cos of the largest heading error that is not a turn
TURN_MIN_SPEED = 0.2  # m/s


def stopping_speed(jerk: float, acc: float, distance: float) -> float:
    """TrajMath ``computeMaxSpeedFromDistance`` with final speed 0: the speed that can still stop in ``distance``."""
    b = 4.0 * acc * acc / max(jerk, 1e-6)
    return 0.5 * (-b + math.sqrt(b * b + 8.0 * acc * max(distance, 0.0)))


class AvoidanceFlightTask:
    """The trajectory PX4 generates from injected avoidance setpoints, for one vehicle and one mission leg.

    Args:
        params: resolved PX4 parameters.
        cruise: the mission speed [m/s] (MPC_XY_CRUISE or the mission's CHANGE_SPEED).
        position, velocity: the vehicle's state at the start (x, y, z up) [m], [m/s].
    """

    def __init__(self, params, cruise: float, position, velocity):
        self.p = params
        self.cruise = cruise
        self.pos = [float(v) for v in position]
        self.vel = [float(v) for v in velocity]
        self.acc = [0.0, 0.0, 0.0]
        self.max_speed_prev = cruise
        self.turning = False

    def target(self, pos, prev, goal) -> tuple[float, float, float]:
        """PX4's own target: the mission item, the previous one, or the foot of the perpendicular on the line."""
        r = self.p["NAV_ACC_RAD"]
        projection = line_projection(pos[0], pos[1], prev, goal)
        if projection is None:
            return goal
        along, cx, cy = projection
        if along > 1.0:
            return goal  # target behind
        if along < 0.0 and math.hypot(pos[0] - prev[0], pos[1] - prev[1]) > r:
            return prev  # previous in front
        if math.hypot(pos[0] - cx, pos[1] - cy) > r:
            return (cx, cy, goal[2])  # offtrack
        return goal

    def update(self, dt: float, pos, setpoint, prev, goal):
        """One cycle toward the injected ``setpoint``; returns (position, velocity, acceleration) setpoints."""
        p = self.p
        tp, tv = self.pos, self.vel
        # the turning check against PX4's own target
        tgt = self.target(pos, prev, goal)
        vxy = math.hypot(tv[0], tv[1])
        tx, ty = tgt[0] - tp[0], tgt[1] - tp[1]
        to_target = math.hypot(tx, ty)
        self.turning = (vxy > TURN_MIN_SPEED and to_target > p["NAV_ACC_RAD"]
                        and (tv[0] * tx + tv[1] * ty) / (vxy * to_target) < COS_TURN)
        # speed that stops at the injected point
        jerk = max(p["MPC_JERK_AUTO"], 1e-3)
        dx, dy, dz = setpoint[0] - tp[0], setpoint[1] - tp[1], setpoint[2] - tp[2]
        dxy = math.hypot(dx, dy)
        xy_speed = min(self.cruise, stopping_speed(jerk, p["MPC_ACC_HOR"], dxy))
        if dz >= 0.0:
            z_speed = min(p["MPC_Z_VEL_MAX_UP"], stopping_speed(jerk, p["MPC_ACC_UP_MAX"], dz))
        else:
            z_speed = min(p["MPC_Z_VEL_MAX_DN"], stopping_speed(jerk, p["MPC_ACC_DOWN_MAX"], -dz))
        if self.turning:
            xy_speed = min(self.max_speed_prev, xy_speed)
        else:
            self.max_speed_prev = xy_speed
        d = math.sqrt(dxy * dxy + dz * dz)
        if d > 1e-6:
            s = math.sqrt(xy_speed * xy_speed + z_speed * z_speed) / d
            v_target = [dx * s, dy * s, dz * s]
            h = math.hypot(v_target[0], v_target[1])
            if h > xy_speed > 0.0:
                v_target[0], v_target[1] = v_target[0] * xy_speed / h, v_target[1] * xy_speed / h
            v_target[2] = max(-z_speed, min(z_speed, v_target[2]))
        else:
            v_target = [0.0, 0.0, 0.0]
        # time stretch while the vehicle lags behind the trajectory
        ex, ey = tp[0] - pos[0], tp[1] - pos[1]
        stretch = 1.0
        if ex * tv[0] + ey * tv[1] > 0.0:
            stretch = 1.0 - min(max(math.hypot(ex, ey) / max(p["MPC_XY_ERR_MAX"], 1e-3), 0.0), 1.0)
        step = dt * stretch
        for i in range(3):
            a_max = p["MPC_ACC_HOR"] if i < 2 else (p["MPC_ACC_UP_MAX"] if v_target[i] > tv[i] else
                                                   p["MPC_ACC_DOWN_MAX"])
            dv = v_target[i] - tv[i]
            # the acceleration that still reaches the target velocity without overshoot at this jerk
            want = math.copysign(min(math.sqrt(2.0 * jerk * abs(dv)), a_max), dv)
            da = want - self.acc[i]
            lim = jerk * step
            self.acc[i] += max(-lim, min(lim, da))
            new_v = tv[i] + self.acc[i] * step
            if (dv > 0.0 and new_v > v_target[i]) or (dv < 0.0 and new_v < v_target[i]):
                new_v, self.acc[i] = v_target[i], 0.0
            tp[i] += 0.5 * (tv[i] + new_v) * step
            tv[i] = new_v
        return tuple(tp), tuple(tv), tuple(self.acc)
