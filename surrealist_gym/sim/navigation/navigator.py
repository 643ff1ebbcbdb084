"""PX4 mission mode, simplified: the state machine that turns mission items into setpoints.

Frame: x north, y east, z up [m] above home (the mission frame); :meth:`Navigator.update` returns NED
setpoints for :class:`~surrealist_gym.sim.vehicle.control.PositionControl`. Behaviour (PX4 navigator, FlightTaskAuto*):

- TAKEOFF climbs vertically to max(item altitude, MIS_TAKEOFF_ALT), the climb speed ramping to MPC_TKO_SPEED over
  MPC_TKO_RAMP_T; accepted within NAV_MC_ALT_RAD.
- WAYPOINT flies the straight line from the previous setpoint at MPC_XY_CRUISE (or the last CHANGE_SPEED), the
  speed changing at most MPC_ACC_HOR and braking before the waypoint; accepted within the item's acceptance radius
  (else NAV_ACC_RAD) horizontally and NAV_MC_ALT_RAD vertically, then held for the item's hold time.
- LAND flies to the land position at the current altitude, then descends: MPC_Z_VEL_MAX_DN above MPC_LAND_ALT1,
  MPC_LAND_SPEED below MPC_LAND_ALT2, linear in between. Landed when on the ground with vertical speed below
  LNDMC_Z_VEL_MAX and horizontal below LNDMC_XY_VEL_MAX for LNDMC_TRIG_TIME; disarm COM_DISARM_LAND later.
- RETURN_TO_LAUNCH climbs to RTL_RETURN_ALT if lower, returns home at that altitude and lands.
- CHANGE_SPEED sets the horizontal cruise speed.
- Yaw follows MPC_YAW_MODE (0 next waypoint, 1 home, 2 away from home, 3 along the velocity), rate limited by
  MPC_YAWRAUTO_MAX. With avoidance, horizontal flight follows the planner's velocity and yaw (PX4's
  ``injectAvoidanceSetpoints``); takeoff and the final descent stay with the navigator.
Not modelled: MIS_YAW_ERR heading acceptance, loiter items, geofence, failsafes.
"""
from __future__ import annotations

import math
from enum import Enum

from ...geometry import line_projection
from ...mission import Command, Mission
from .flight_task import AvoidanceFlightTask

NAN = float("nan")


class Phase(str, Enum):
    """What the navigator is doing."""

    IDLE = "idle"            # armed on the ground, waiting for the mission start
    TAKEOFF = "takeoff"
    CRUISE = "cruise"        # flying toward a position item (waypoint, land approach, RTL return)
    CLIMB = "climb"          # RTL climb
    DESCEND = "descend"      # landing
    HOLD = "hold"            # holding at a waypoint (hold time) or at the end of a mission without landing
    LANDED = "landed"
    DONE = "done"            # disarmed after landing, or mission finished in the air


class Navigator:
    """Mission-mode state machine for one vehicle.

    Args:
        mission: the mission (items in the local frame, metres).
        params: PX4 parameters (resolved).
        start_time: mission start after arming [s].
        takeoff_hold_s: time at the take-off altitude before the next item [s] (SimConfig.takeoff_hold_s).
    """

    def __init__(self, mission: Mission, params: dict, start_time: float, takeoff_hold_s: float = 0.0):
        self.items = [it for it in mission.items]
        self.p = params
        self.start_time = start_time
        self.takeoff_hold_s = float(takeoff_hold_s)
        self.cruise = params["MPC_XY_CRUISE"]
        self.phase = Phase.IDLE
        self.index = -1
        self.target = (0.0, 0.0, 0.0)
        self.prev = (0.0, 0.0, 0.0)
        self.hold_until = 0.0
        self.phase_t0 = 0.0
        self.v_cmd = [0.0, 0.0, 0.0]
        self.yaw_sp: float | None = None
        self.landed_since: float | None = None
        self.landed_at = 0.0
        self.then_land = False  # RTL: land after reaching the target
        self.finished_in_air = False
        self.t = 0.0
        self.carrot = None
        self.task: AvoidanceFlightTask | None = None  # PX4's flight task while avoidance injects setpoints

    # --- public --------------------------------------------------------------------------------------------------
    @property
    def uses_planner(self) -> bool:
        """Whether the current phase hands the horizontal flight to the avoidance planner."""
        return self.phase == Phase.CRUISE

    @property
    def armed(self) -> bool:
        """Whether the motors run: in every phase but DONE, and in DONE if the mission ended in the air."""
        return self.phase != Phase.DONE or self.finished_in_air

    @property
    def on_ground_phase(self) -> bool:
        """Whether the UAV is on the ground: idle, landed, or done after landing."""
        return self.phase in (Phase.IDLE, Phase.LANDED) or (self.phase == Phase.DONE and not self.finished_in_air)

    def goal(self) -> tuple[float, float, float]:
        """The current target position (x, y, z up) [m] for the avoidance planner."""
        return self.target

    def update(self, t: float, pos, vel, yaw: float, dt: float, ground_contact: bool, planner=None):
        """One navigator step.

        Args:
            t: time since arming [s]. pos, vel: estimated position and velocity (x, y, z up) [m], [m/s].
            yaw: estimated heading [rad]. dt: step [s]. ground_contact: the vehicle touches the ground.
            planner: the latest PlannerOutput when avoidance is on, else None.

        Returns:
            (pos_sp_ned, vel_ff_ned, acc_ff_ned, yaw_sp): NED position setpoint (nan = free), velocity and
            acceleration feed-forward, heading.
        """
        self.t = t
        if self.yaw_sp is None:
            self.yaw_sp = yaw
        self._advance(t, pos, vel, ground_contact)
        ph = self.phase
        pos_sp, vel_sp, acc = (NAN, NAN, NAN), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        yaw_target = self.yaw_sp
        if ph in (Phase.IDLE, Phase.LANDED, Phase.DONE):
            self.v_cmd = [0.0, 0.0, 0.0]
            return (NAN, NAN, NAN), (0.0, 0.0, 0.3), (0.0, 0.0, 0.0), self.yaw_sp  # push down: minimum thrust
        if ph == Phase.TAKEOFF or ph == Phase.CLIMB:
            ramp = min(1.0, (t - self.phase_t0) / max(self.p["MPC_TKO_RAMP_T"], 1e-3)) if ph == Phase.TAKEOFF else 1.0
            speed = self.p["MPC_TKO_SPEED"] if ph == Phase.TAKEOFF else self.p["MPC_Z_VEL_MAX_UP"]
            err = self.target[2] - pos[2]
            vz = min(speed * ramp, math.sqrt(2.0 * 1.0 * max(err, 0.0)), self.p["MPC_Z_P"] * err + 0.3 * speed)
            pos_sp, vel_sp = (self.target[0], self.target[1], NAN), (0.0, 0.0, max(vz, -0.5))
            yaw_target = self._yaw_mode(pos, vel, self._next_position())
        elif ph == Phase.HOLD:
            pos_sp = self.target
        elif ph == Phase.DESCEND:
            alt = pos[2]
            a1, a2 = self.p["MPC_LAND_ALT1"], self.p["MPC_LAND_ALT2"]
            vmax, vland = self.p["MPC_Z_VEL_MAX_DN"], self.p["MPC_LAND_SPEED"]
            if alt > a1:
                vd = vmax
            elif alt > a2 and a1 > a2:
                vd = vland + (vmax - vland) * (alt - a2) / (a1 - a2)
            else:
                vd = vland
            pos_sp, vel_sp = (self.target[0], self.target[1], NAN), (0.0, 0.0, -vd)
        elif ph == Phase.CRUISE:
            if planner is not None and planner.position is not None:  # a position setpoint: PX4's flight task
                if self.task is None:
                    self.task = AvoidanceFlightTask(self.p, self.cruise, pos, vel)
                pos_sp, vel_sp, acc = self.task.update(dt, pos, planner.position, self.prev, self.target)
                self.v_cmd = list(vel_sp)
                yaw_target = planner.yaw
            else:  # a velocity (or the mission line), slewed, with a position setpoint moving along
                if planner is not None:
                    vel_sp = self._approach(pos, planner.velocity)
                    yaw_target = planner.yaw
                else:
                    vel_sp = self._line_velocity(pos)
                    yaw_target = self._yaw_mode(pos, vel, self.target)
                old = self.v_cmd
                vel_sp = self._slew(vel_sp, dt)
                acc = tuple((vel_sp[i] - old[i]) / dt for i in range(3))
                pos_sp = self._carrot(pos, vel_sp, dt)
        self.yaw_sp = self._yaw_step(self.yaw_sp, yaw_target, dt)
        ned_pos = (pos_sp[0], pos_sp[1], -pos_sp[2])
        return ned_pos, (vel_sp[0], vel_sp[1], -vel_sp[2]), (acc[0], acc[1], -acc[2]), self.yaw_sp

    # --- state machine -------------------------------------------------------------------------------------------
    def _advance(self, t, pos, vel, ground_contact):
        ph = self.phase
        if ph == Phase.IDLE:
            if t >= self.start_time:
                self.prev = (pos[0], pos[1], 0.0)
                self._next_item(t, pos)
        elif ph in (Phase.TAKEOFF, Phase.CLIMB):
            if abs(pos[2] - self.target[2]) < self.p["NAV_MC_ALT_RAD"]:
                self.prev = (pos[0], pos[1], self.target[2])
                if ph == Phase.CLIMB:
                    self._go(t, Phase.CRUISE, (self.target[3], self.target[4], self.target[2]), pos)
                elif self.takeoff_hold_s > 0:
                    self._go(t, Phase.HOLD, self.target, pos)
                    self.hold_until = t + self.takeoff_hold_s
                else:
                    self._next_item(t, pos)
        elif ph == Phase.CRUISE:
            if self._reached(pos):
                if self.then_land:
                    self._go(t, Phase.DESCEND, self.target, pos)
                else:
                    item = self.items[self.index]
                    self._go(t, Phase.HOLD, self.target, pos)
                    self.hold_until = t + max(item.hold_s, 0.0)
        elif ph == Phase.HOLD:
            if t >= self.hold_until and not self.finished_in_air:
                self.prev = self.target
                self._next_item(t, pos)
        elif ph == Phase.DESCEND:
            vz_ok = abs(vel[2]) < self.p["LNDMC_Z_VEL_MAX"]
            vxy_ok = math.hypot(vel[0], vel[1]) < self.p["LNDMC_XY_VEL_MAX"]
            if ground_contact and vz_ok and vxy_ok:
                if self.landed_since is None:
                    self.landed_since = t
                elif t - self.landed_since >= self.p["LNDMC_TRIG_TIME"]:
                    self.phase, self.landed_at = Phase.LANDED, t
            else:
                self.landed_since = None
        elif ph == Phase.LANDED:
            if t - self.landed_at >= max(self.p["COM_DISARM_LAND"], 0.0):
                self.phase = Phase.DONE

    def _next_item(self, t, pos):
        while True:
            self.index += 1
            if self.index >= len(self.items):
                # mission finished without landing: hold the last setpoint for 2 s, then report completion
                self.phase, self.finished_in_air = Phase.HOLD, True
                self.target = tuple(self.target[:3]) if self.index > 0 else (pos[0], pos[1], pos[2])
                self.hold_until = t + 2.0
                return
            it = self.items[self.index]
            cmd = it.command
            if cmd == Command.CHANGE_SPEED:
                if it.speed == it.speed and it.speed > 0:
                    self.cruise = float(it.speed)
                continue
            if cmd == Command.TAKEOFF:
                alt = max(it.z if it.z == it.z else 0.0, self.p["MIS_TAKEOFF_ALT"])
                self._go(t, Phase.TAKEOFF, (pos[0], pos[1], alt), pos)
            elif cmd == Command.WAYPOINT:
                self._go(t, Phase.CRUISE, (it.x, it.y, it.z), pos)
            elif cmd == Command.LAND:
                self.then_land = True
                # PX4 flies to the land position at the altitude it is at (the previous setpoint's), then descends
                alt = self.prev[2] if self.prev[2] > 0.5 else max(pos[2], 0.5)
                self._go(t, Phase.CRUISE, (it.x, it.y, alt), pos)
            elif cmd == Command.RETURN_TO_LAUNCH:
                self.then_land = True
                alt = max(pos[2], self.p["RTL_RETURN_ALT"])
                if alt - pos[2] > self.p["NAV_MC_ALT_RAD"]:
                    self._go(t, Phase.CLIMB, (pos[0], pos[1], alt, 0.0, 0.0), pos)
                else:
                    self._go(t, Phase.CRUISE, (0.0, 0.0, alt), pos)
            return

    def _go(self, t, phase, target, pos):
        self.phase, self.phase_t0 = phase, t
        self.carrot = None
        self.task = None
        self.target = tuple(target)
        self.landed_since = None

    @property
    def mission_complete(self) -> bool:
        """All items done: disarmed after landing, or holding after the last item."""
        return (self.phase == Phase.DONE) or (self.finished_in_air and self.t >= self.hold_until)

    def _reached(self, pos) -> bool:
        it = self.items[self.index] if 0 <= self.index < len(self.items) else None
        rad = it.acceptance_radius if it is not None and it.acceptance_radius > 0 else self.p["NAV_ACC_RAD"]
        if it is not None and it.command in (Command.LAND, Command.RETURN_TO_LAUNCH):
            rad = min(rad, max(self.p["NAV_ACC_RAD"], 0.1))
        dh = math.hypot(pos[0] - self.target[0], pos[1] - self.target[1])
        if self.task is not None and self._passed(pos):
            rad = dh + 0.5  # ObstacleAvoidance::checkAvoidanceProgress: passed along the line counts as reached
        return dh < rad and abs(pos[2] - self.target[2]) < max(self.p["NAV_MC_ALT_RAD"], 0.1)

    def _passed(self, pos) -> bool:
        """Whether the vehicle's projection on the line from the previous item lies beyond the target."""
        projection = line_projection(pos[0], pos[1], self.prev, self.target)
        return projection is not None and projection[0] > 1.0

    def _next_position(self):
        for it in self.items[self.index + 1:]:
            if it.has_position and it.command != Command.TAKEOFF:
                return (it.x, it.y, it.z)
        return None

    # --- setpoint shaping ----------------------------------------------------------------------------------------
    def _line_velocity(self, pos):
        p0, p1 = self.prev, self.target
        dx, dy, dz = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        ex, ey, ez = p1[0] - pos[0], p1[1] - pos[1], p1[2] - pos[2]
        dist = math.sqrt(ex * ex + ey * ey + ez * ez)
        if length < 1e-6:
            ux, uy, uz = (ex / dist, ey / dist, ez / dist) if dist > 1e-6 else (0.0, 0.0, 0.0)
            s = 0.0
        else:
            ux, uy, uz = dx / length, dy / length, dz / length
            s = (pos[0] - p0[0]) * ux + (pos[1] - p0[1]) * uy + (pos[2] - p0[2]) * uz
            s = min(max(s, 0.0), length)
        # closest point on the line, cross-track correction
        cx, cy, cz = p0[0] + ux * s - pos[0], p0[1] + uy * s - pos[1], p0[2] + uz * s - pos[2]
        remaining = ex * ux + ey * uy + ez * uz
        hor = math.hypot(ux, uy)
        vmax = self.cruise / hor if hor > 1e-6 else self.p["MPC_Z_VEL_MAX_UP"]
        if uz > 1e-6:
            vmax = min(vmax, self.p["MPC_Z_VEL_MAX_UP"] / uz)
        elif uz < -1e-6:
            vmax = min(vmax, self.p["MPC_Z_VEL_MAX_DN"] / -uz)
        brake = 0.5 * self.p["MPC_ACC_HOR"]
        along = min(vmax, math.sqrt(2.0 * brake * max(remaining, 0.0)), self.p["MPC_XY_P"] * max(remaining, 0.0) + 0.1)
        kp = self.p["MPC_XY_P"]
        return (along * ux + kp * cx, along * uy + kp * cy, along * uz + kp * cz)

    def _approach(self, pos, v):
        """Before a stop (landing, last item) cap the speed to MPC_XY_P times the distance left, so the vehicle
        arrives slowly instead of overshooting the acceptance radius (PX4 plans the stop into its trajectory)."""
        if not (self.then_land or self._next_position() is None):
            return v
        d = math.sqrt(sum((self.target[i] - pos[i]) ** 2 for i in range(3)))
        cap = self.p["MPC_XY_P"] * d + 0.1
        n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return v if n <= cap else (v[0] * cap / n, v[1] * cap / n, v[2] * cap / n)

    def _carrot(self, pos, v, dt):
        """The position setpoint that moves with the velocity setpoint (PX4's trajectory setpoint: position and
        velocity together, so the position P term removes the velocity loop's lag); kept within 1 m."""
        c = self.carrot
        if c is None:
            c = tuple(pos)
        c = [c[i] + v[i] * dt for i in range(3)]
        d = math.sqrt(sum((c[i] - pos[i]) ** 2 for i in range(3)))
        if d > 1.0:
            c = [pos[i] + (c[i] - pos[i]) / d for i in range(3)]
        self.carrot = tuple(c)
        return self.carrot

    def _slew(self, v, dt):
        """Limit the change of the velocity setpoint: MPC_ACC_HOR horizontally, MPC_ACC_UP_MAX/_DOWN_MAX up/down."""
        out = self.v_cmd
        ah = self.p["MPC_ACC_HOR"] * dt
        dx, dy = v[0] - out[0], v[1] - out[1]
        d = math.hypot(dx, dy)
        if d > ah:
            dx, dy = dx * ah / d, dy * ah / d
        dz = min(max(v[2] - out[2], -self.p["MPC_ACC_DOWN_MAX"] * dt), self.p["MPC_ACC_UP_MAX"] * dt)
        self.v_cmd = [out[0] + dx, out[1] + dy, out[2] + dz]
        return tuple(self.v_cmd)

    def _yaw_mode(self, pos, vel, target):
        mode = int(self.p["MPC_YAW_MODE"])
        if mode == 1:
            target = (0.0, 0.0, 0.0)
        elif mode == 2:
            target = (2 * pos[0], 2 * pos[1], 0.0)
        elif mode == 3:
            if math.hypot(vel[0], vel[1]) > 0.5:
                return math.atan2(vel[1], vel[0])
            return self.yaw_sp
        if target is None:
            return self.yaw_sp
        dx, dy = target[0] - pos[0], target[1] - pos[1]
        if math.hypot(dx, dy) < 1.0:
            return self.yaw_sp
        return math.atan2(dy, dx)

    def _yaw_step(self, current, target, dt):
        step = math.radians(self.p["MPC_YAWRAUTO_MAX"]) * dt
        diff = math.remainder(target - current, 2 * math.pi)
        return math.remainder(current + max(-step, min(step, diff)), 2 * math.pi)
