"""PX4's multicopter cascade in plain floats (no numpy per step: small-array numpy costs microseconds per call).

Position P -> velocity PID -> thrust vector and attitude setpoint (:class:`PositionControl`, PX4
``PositionControl.cpp``), attitude P with tilt prioritised over yaw -> body-rate PID -> normalised torques ->
quad-X mixer -> motor commands (:class:`AttitudeRateControl`, PX4 ``AttitudeControl.cpp``, ``RateControl.cpp``,
``MultirotorMixer``). Frames: world NED, body FRD; quaternions ``(w, x, y, z)`` rotate body to world.
"""
from __future__ import annotations

import math

from numba import njit

from .airframe import GRAVITY, VehicleParams

_S = math.sqrt(0.5)
# PX4 quad X: rotor 1 front-right CCW, 2 back-left CCW, 3 front-left CW, 4 back-right CW.
# Mixer rows (roll, pitch, yaw) and the rotor positions (x forward, y right) as multiples of arm/sqrt(2).
_MIX = ((-_S, _S, 1.0), (_S, -_S, 1.0), (_S, _S, -1.0), (-_S, -_S, -1.0))
_POS = ((1.0, 1.0), (-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0))


def qmul(a, b):
    """Hamilton product of two (w, x, y, z) quaternions."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


@njit(cache=True)
def _quat_from_matrix(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    tr = r00 + r11 + r22
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        return (0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s)
    if r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        return ((r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s)
    if r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        return ((r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s)
    s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
    return ((r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s)


class PositionControl:
    """PX4 position and velocity control (mc_pos_control), one instance per vehicle, run at the outer rate."""

    __slots__ = ("xy_p", "z_p", "vxy_p", "vxy_i", "vxy_d", "vz_p", "vz_i", "vz_d", "vel_max_xy", "vel_up",
                 "vel_dn", "tilt_max", "hover", "thr_min", "thr_max", "int_x", "int_y", "int_z", "prev_v",
                 "acc_f")

    def __init__(self, p: dict):
        self.xy_p, self.z_p = p["MPC_XY_P"], p["MPC_Z_P"]
        self.vxy_p, self.vxy_i, self.vxy_d = p["MPC_XY_VEL_P_ACC"], p["MPC_XY_VEL_I_ACC"], p["MPC_XY_VEL_D_ACC"]
        self.vz_p, self.vz_i, self.vz_d = p["MPC_Z_VEL_P_ACC"], p["MPC_Z_VEL_I_ACC"], p["MPC_Z_VEL_D_ACC"]
        self.vel_max_xy = p["MPC_XY_VEL_MAX"]
        self.vel_up, self.vel_dn = p["MPC_Z_VEL_MAX_UP"], p["MPC_Z_VEL_MAX_DN"]
        self.tilt_max = math.radians(p["MPC_TILTMAX_AIR"])
        self.hover, self.thr_min, self.thr_max = p["MPC_THR_HOVER"], p["MPC_THR_MIN"], p["MPC_THR_MAX"]
        self.reset()

    def reset(self) -> None:
        """Clear the integrators and the derivative filter."""
        self.int_x = self.int_y = self.int_z = 0.0
        self.prev_v = None
        self.acc_f = (0.0, 0.0, 0.0)

    def update(self, pos, vel, pos_sp, vel_ff, yaw_sp: float, dt: float, acc_ff=(0.0, 0.0, 0.0)):
        """One control step.

        Args:
            pos, vel: estimated NED position [m] and velocity [m/s].
            pos_sp: NED position setpoint; a nan component is not position-controlled.
            vel_ff: NED velocity feed-forward [m/s] (the setpoint when the position component is nan).
            yaw_sp: heading setpoint [rad]. dt: time since the last update [s].
            acc_ff: NED acceleration feed-forward [m/s^2] (the trajectory's acceleration).

        Returns:
            (q_sp, thrust): attitude setpoint (w, x, y, z) and collective thrust command in [0, 1].
        """
        # position P, velocity limits (horizontal: keep the direction; vertical: asymmetric)
        vx = vel_ff[0] if pos_sp[0] != pos_sp[0] else vel_ff[0] + self.xy_p * (pos_sp[0] - pos[0])
        vy = vel_ff[1] if pos_sp[1] != pos_sp[1] else vel_ff[1] + self.xy_p * (pos_sp[1] - pos[1])
        vz = vel_ff[2] if pos_sp[2] != pos_sp[2] else vel_ff[2] + self.z_p * (pos_sp[2] - pos[2])
        sp = math.hypot(vx, vy)
        if sp > self.vel_max_xy:
            vx, vy = vx * self.vel_max_xy / sp, vy * self.vel_max_xy / sp
        vz = min(max(vz, -self.vel_up), self.vel_dn)
        # velocity PID -> acceleration (derivative on the measured, low-passed acceleration)
        if self.prev_v is not None and dt > 0:
            a = 0.5
            self.acc_f = tuple(a * f + (1 - a) * (v - q) / dt for f, v, q in zip(self.acc_f, vel, self.prev_v))
        self.prev_v = vel
        ex, ey, ez = vx - vel[0], vy - vel[1], vz - vel[2]
        ax = acc_ff[0] + self.vxy_p * ex + self.int_x - self.vxy_d * self.acc_f[0]
        ay = acc_ff[1] + self.vxy_p * ey + self.int_y - self.vxy_d * self.acc_f[1]
        az = acc_ff[2] + self.vz_p * ez + self.int_z - self.vz_d * self.acc_f[2]
        # acceleration -> thrust vector, tilt limit, vertical priority
        bx, by, bz = -ax, -ay, GRAVITY
        n = math.sqrt(bx * bx + by * by + bz * bz)
        bx, by, bz = bx / n, by / n, bz / n
        tilt = math.acos(max(-1.0, min(1.0, bz)))
        if tilt > self.tilt_max:
            h = math.hypot(bx, by)
            bx, by, bz = bx / h * math.sin(self.tilt_max), by / h * math.sin(self.tilt_max), math.cos(self.tilt_max)
        thr_ned_z = az * (self.hover / GRAVITY) - self.hover
        collective = thr_ned_z / bz
        tx, ty = bx * collective, by * collective
        tz = min(max(thr_ned_z, -self.thr_max), -self.thr_min)
        # anti-windup, vertical
        if (tz >= -self.thr_min and ez >= 0.0) or (tz <= -self.thr_max and ez <= 0.0):
            ez = 0.0
        # horizontal margin
        xy_max = math.sqrt(max(self.thr_max ** 2 - tz * tz, 0.0))
        txy = math.hypot(tx, ty)
        if txy > xy_max:
            tx, ty = tx * xy_max / txy, ty * xy_max / txy
        # tracking anti-windup, horizontal
        arw = 2.0 / self.vxy_p
        ex -= arw * (ax - tx * (GRAVITY / self.hover))
        ey -= arw * (ay - ty * (GRAVITY / self.hover))
        self.int_x += ex * self.vxy_i * dt
        self.int_y += ey * self.vxy_i * dt
        self.int_z += ez * self.vz_i * dt
        self.int_z = max(-GRAVITY, min(GRAVITY, self.int_z))
        thrust = math.sqrt(tx * tx + ty * ty + tz * tz)
        return attitude_from_thrust(tx, ty, tz, yaw_sp), thrust


class AttitudeRateControl:
    """PX4 attitude P and body-rate PID, quad-X mixer and first-order motors; run at the physics rate.

    ``update`` takes the true attitude and body rates (PyBullet's), returns the body force and torque.
    """

    __slots__ = ("att_p", "yaw_w", "rate_max", "rp", "ri", "rd", "int_lim", "integ", "prev_rate", "u",
                 "tmax", "curve", "alpha_up", "alpha_dn", "km", "arm", "idle")

    def __init__(self, p: dict, vehicle: VehicleParams, dt: float):
        yaw_w = min(max(p["MC_YAW_WEIGHT"], 0.0), 1.0)
        self.yaw_w = yaw_w
        self.att_p = (p["MC_ROLL_P"], p["MC_PITCH_P"], p["MC_YAW_P"] / yaw_w if yaw_w > 1e-4 else p["MC_YAW_P"])
        self.rate_max = tuple(math.radians(p[k]) for k in ("MC_ROLLRATE_MAX", "MC_PITCHRATE_MAX", "MC_YAWRATE_MAX"))
        ks = (p["MC_ROLLRATE_K"], p["MC_PITCHRATE_K"], p["MC_YAWRATE_K"])
        self.rp = tuple(k * p[n] for k, n in zip(ks, ("MC_ROLLRATE_P", "MC_PITCHRATE_P", "MC_YAWRATE_P")))
        self.ri = tuple(k * p[n] for k, n in zip(ks, ("MC_ROLLRATE_I", "MC_PITCHRATE_I", "MC_YAWRATE_I")))
        self.rd = tuple(k * p[n] for k, n in zip(ks, ("MC_ROLLRATE_D", "MC_PITCHRATE_D", "MC_YAWRATE_D")))
        self.int_lim = (p["MC_RR_INT_LIM"], p["MC_PR_INT_LIM"], p["MC_YR_INT_LIM"])
        self.tmax, self.curve = vehicle.max_thrust, vehicle.thrust_curve
        self.alpha_up = 1.0 - math.exp(-dt / vehicle.motor_tau_up)
        self.alpha_dn = 1.0 - math.exp(-dt / vehicle.motor_tau_down)
        self.km, self.arm = vehicle.moment_constant, vehicle.arm_length * _S
        self.idle = 0.05  # armed idle actuator command (PX4 PWM_MIN spins the motors slowly)
        self.reset()

    def reset(self) -> None:
        """Clear the rate integrators and stop the motors."""
        self.integ = [0.0, 0.0, 0.0]
        self.prev_rate = (0.0, 0.0, 0.0)
        self.u = [0.0, 0.0, 0.0, 0.0]

    def update(self, q, rate, q_sp, thrust: float, dt: float, armed: bool = True, integrate: bool = True):
        """One inner-loop step.

        Args:
            q: attitude (w, x, y, z). rate: body rates (p, q, r) [rad/s].
            q_sp: attitude setpoint; thrust: collective command in [0, 1].
            armed: motors spin; integrate: update the rate integrators (off on the ground, as PX4 does).

        Returns:
            (fz, tx, ty, tz): body-frame force along z (negative = up) [N] and torques [N m].
        """
        if not armed:
            self.integ = [0.0, 0.0, 0.0]
            cmd = (0.0, 0.0, 0.0, 0.0)
        else:
            rsp = self._attitude(q, q_sp)
            tau = [0.0, 0.0, 0.0]
            for i in range(3):
                e = rsp[i] - rate[i]
                d = (rate[i] - self.prev_rate[i]) / dt
                tau[i] = self.rp[i] * e + self.integ[i] - self.rd[i] * d
                if integrate:
                    self.integ[i] = min(max(self.integ[i] + self.ri[i] * e * dt, -self.int_lim[i]), self.int_lim[i])
            cmd = self._mix(thrust, tau)
        self.prev_rate = rate
        fz = tx = ty = tz = 0.0
        u, f, arm = self.u, self.curve, self.arm
        for i in range(4):
            c = cmd[i]
            u[i] += (self.alpha_up if c > u[i] else self.alpha_dn) * (c - u[i])
            t = self.tmax * (f * u[i] * u[i] + (1.0 - f) * u[i])
            fz -= t
            px, py = _POS[i]
            tx -= py * arm * t
            ty += px * arm * t
            tz += _MIX[i][2] * self.km * t
        return fz, tx, ty, tz

    def _attitude(self, q, qd):
        w, x, y, z = q
        # current and desired body z axes (third columns of the rotation matrices)
        ezx, ezy, ezz = 2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)
        dw, dx, dy, dz = qd
        edx, edy, edz = 2 * (dx * dz + dw * dy), 2 * (dy * dz - dw * dx), 1 - 2 * (dx * dx + dy * dy)
        cx, cy, cz = ezy * edz - ezz * edy, ezz * edx - ezx * edz, ezx * edy - ezy * edx
        dot = ezx * edx + ezy * edy + ezz * edz
        if dot < -0.99999:
            qd_red = qd
        else:
            rw = dot + 1.0
            n = math.sqrt(rw * rw + cx * cx + cy * cy + cz * cz)
            qd_red = qmul((rw / n, cx / n, cy / n, cz / n), q)
            # mix in the yaw with weight yaw_w
            iw, ix, iy, iz = qd_red[0], -qd_red[1], -qd_red[2], -qd_red[3]
            mw, mx, my, mz = qmul((iw, ix, iy, iz), qd)
            if mw < 0:
                mw, mz = -mw, -mz
            mw, mz = min(max(mw, -1.0), 1.0), min(max(mz, -1.0), 1.0)
            yw = self.yaw_w
            qd = qmul(qd_red, (math.cos(yw * math.acos(mw)), 0.0, 0.0, math.sin(yw * math.asin(mz))))
        ew, ex, ey, ez = qmul((w, -x, -y, -z), qd)
        s = 2.0 if ew >= 0 else -2.0
        out = []
        for i, e in enumerate((ex, ey, ez)):
            r = s * e * self.att_p[i]
            m = self.rate_max[i]
            out.append(m if r > m else (-m if r < -m else r))
        return out

    def _mix(self, thrust: float, tau):
        r, p, yw = tau
        rp = [m[0] * r + m[1] * p for m in _MIX]
        lo, hi = min(rp), max(rp)
        if hi - lo > 1.0:  # not even full range fits roll/pitch: scale them down
            k = 1.0 / (hi - lo)
            rp = [v * k for v in rp]
            lo, hi = lo * k, hi * k
        t = thrust
        if t + hi > 1.0:
            t = 1.0 - hi
        if t + lo < self.idle:
            t = self.idle - lo
        # yaw gets what is left
        room = min(min(1.0 - (t + v), (t + v) - self.idle) for v in rp)
        yw = min(max(yw, -max(room, 0.0)), max(room, 0.0))
        return tuple(min(max(t + v + m[2] * yw, self.idle), 1.0) for v, m in zip(rp, _MIX))


# --- compiled inner loop ---------------------------------------------------------------------------------------
# The same computation as AttitudeRateControl.update (the readable reference, checked against this in the tests),
# plus the body-to-world rotation and the drag/wind force, as one numba call per vehicle and physics step.
# State layout: [0:3] rate integrators, [3:6] previous body rates, [6:10] motor commands.

def kernel_params(p: dict, vehicle: VehicleParams, dt: float, drag=(0.0, 0.0, 0.0)):
    """The float64 parameter vector of :func:`inner_step` (built once per run)."""
    import numpy as np

    ref = AttitudeRateControl(p, vehicle, dt)
    return np.array([*ref.att_p, ref.yaw_w, *ref.rate_max, *ref.rp, *ref.ri, *ref.rd, *ref.int_lim, ref.tmax,
                     ref.curve, ref.alpha_up, ref.alpha_dn, ref.km, ref.arm, ref.idle, *drag], dtype=np.float64)



@njit(cache=True)
def _qm(aw, ax, ay, az, bw, bx, by, bz):
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


@njit(cache=True)
def inner_step(orn, lin, ang, q_sp, thrust, wind, dt, armed, integrate, P, S):
    """Compiled physics-rate step: attitude and rate control, mixer, motor lag and drag; the world-frame force and
    torque (fx, fy, fz, tx, ty, tz). State S: [0:3] rate integrators, [3:6] previous rates, [6:10] motor outputs."""
    qx, qy, qz, qw = orn
    r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
    r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
    r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
    wx, wy, wz = ang
    rate0 = r00 * wx + r10 * wy + r20 * wz
    rate1 = r01 * wx + r11 * wy + r21 * wz
    rate2 = r02 * wx + r12 * wy + r22 * wz
    idle = P[25]
    c0 = c1 = c2 = c3 = 0.0
    if not armed:
        S[0] = S[1] = S[2] = 0.0
    else:
        # attitude: reduced (tilt) attitude first, yaw mixed in with weight yaw_w
        dw, dx, dy, dz = q_sp
        ezx, ezy, ezz = r02, r12, r22
        edx, edy, edz = 2 * (dx * dz + dw * dy), 2 * (dy * dz - dw * dx), 1 - 2 * (dx * dx + dy * dy)
        cx, cy, cz = ezy * edz - ezz * edy, ezz * edx - ezx * edz, ezx * edy - ezy * edx
        dot = ezx * edx + ezy * edy + ezz * edz
        if dot >= -0.99999:
            rw = dot + 1.0
            n = math.sqrt(rw * rw + cx * cx + cy * cy + cz * cz)
            aw, ax, ay, az = _qm(rw / n, cx / n, cy / n, cz / n, qw, qx, qy, qz)
            mw, mx, my, mz = _qm(aw, -ax, -ay, -az, dw, dx, dy, dz)
            if mw < 0:
                mw, mz = -mw, -mz
            mw, mz = min(max(mw, -1.0), 1.0), min(max(mz, -1.0), 1.0)
            yw = P[3]
            dw, dx, dy, dz = _qm(aw, ax, ay, az, math.cos(yw * math.acos(mw)), 0.0, 0.0,
                                 math.sin(yw * math.asin(mz)))
        ew, ex, ey, ez = _qm(qw, -qx, -qy, -qz, dw, dx, dy, dz)
        s = 2.0 if ew >= 0 else -2.0
        rsp0 = min(max(s * ex * P[0], -P[4]), P[4])
        rsp1 = min(max(s * ey * P[1], -P[5]), P[5])
        rsp2 = min(max(s * ez * P[2], -P[6]), P[6])
        # rate PID
        e0, e1, e2 = rsp0 - rate0, rsp1 - rate1, rsp2 - rate2
        t0 = P[7] * e0 + S[0] - P[13] * (rate0 - S[3]) / dt
        t1 = P[8] * e1 + S[1] - P[14] * (rate1 - S[4]) / dt
        t2 = P[9] * e2 + S[2] - P[15] * (rate2 - S[5]) / dt
        if integrate:
            S[0] = min(max(S[0] + P[10] * e0 * dt, -P[16]), P[16])
            S[1] = min(max(S[1] + P[11] * e1 * dt, -P[17]), P[17])
            S[2] = min(max(S[2] + P[12] * e2 * dt, -P[18]), P[18])
        # mixer (quad X, PX4 order), roll/pitch first, then yaw in the remaining room
        k = 0.7071067811865476
        v0, v1, v2, v3 = -k * t0 + k * t1, k * t0 - k * t1, k * t0 + k * t1, -k * t0 - k * t1
        lo, hi = min(min(v0, v1), min(v2, v3)), max(max(v0, v1), max(v2, v3))
        if hi - lo > 1.0:
            sc = 1.0 / (hi - lo)
            v0, v1, v2, v3, lo, hi = v0 * sc, v1 * sc, v2 * sc, v3 * sc, lo * sc, hi * sc
        th = thrust
        if th + hi > 1.0:
            th = 1.0 - hi
        if th + lo < idle:
            th = idle - lo
        room = min(1.0 - (th + hi), (th + lo) - idle)
        room = max(room, 0.0)
        yv = min(max(t2, -room), room)
        c0 = min(max(th + v0 + yv, idle), 1.0)
        c1 = min(max(th + v1 + yv, idle), 1.0)
        c2 = min(max(th + v2 - yv, idle), 1.0)
        c3 = min(max(th + v3 - yv, idle), 1.0)
    S[3], S[4], S[5] = rate0, rate1, rate2
    tmax, f, km, arm = P[19], P[20], P[23], P[24]
    fz = tx = ty = tz = 0.0
    for i in range(4):
        c = c0 if i == 0 else (c1 if i == 1 else (c2 if i == 2 else c3))
        u = S[6 + i]
        u += (P[21] if c > u else P[22]) * (c - u)
        S[6 + i] = u
        t = tmax * (f * u * u + (1.0 - f) * u)
        fz -= t
        px = 1.0 if (i == 0 or i == 2) else -1.0
        py = 1.0 if (i == 0 or i == 3) else -1.0
        tx -= py * arm * t
        ty += px * arm * t
        tz += (km * t) if i < 2 else (-km * t)
    ux, uy, uz = wind[0] - lin[0], wind[1] - lin[1], wind[2] - lin[2]
    quad = P[28] * math.sqrt(ux * ux + uy * uy + uz * uz)
    fx_w = r02 * fz + (P[26] + quad) * ux
    fy_w = r12 * fz + (P[26] + quad) * uy
    fz_w = r22 * fz + (P[27] + quad) * uz
    return (fx_w, fy_w, fz_w, r00 * tx + r01 * ty + r02 * tz, r10 * tx + r11 * ty + r12 * tz,
            r20 * tx + r21 * ty + r22 * tz)



def position_params(p: dict):
    """The float64 parameter vector of :func:`position_step` (built once per run)."""
    import numpy as np

    ref = PositionControl(p)
    return np.array([ref.xy_p, ref.z_p, ref.vxy_p, ref.vxy_i, ref.vxy_d, ref.vz_p, ref.vz_i, ref.vz_d,
                     ref.vel_max_xy, ref.vel_up, ref.vel_dn, ref.tilt_max, ref.hover, ref.thr_min, ref.thr_max],
                    dtype=np.float64)


@njit(cache=True)
def attitude_from_thrust(tx, ty, tz, yaw):
    """PX4 ``bodyzToAttitude``: the quaternion whose body z axis is opposite the thrust vector, with heading yaw."""
    n = math.sqrt(tx * tx + ty * ty + tz * tz)
    if n < 1e-9:
        zx, zy, zz = 0.0, 0.0, 1.0
    else:
        zx, zy, zz = -tx / n, -ty / n, -tz / n
    cx, cy = -math.sin(yaw), math.cos(yaw)
    xx, xy, xz = cy * zz, -cx * zz, cx * zy - cy * zx
    m = math.sqrt(xx * xx + xy * xy + xz * xz)
    if m < 1e-9:
        xx, xy, xz = 1.0, 0.0, 0.0
    else:
        xx, xy, xz = xx / m, xy / m, xz / m
    yx, yy, yz = zy * xz - zz * xy, zz * xx - zx * xz, zx * xy - zy * xx
    return _quat_from_matrix(xx, yx, zx, xy, yy, zy, xz, yz, zz)


@njit(cache=True)
def position_step(pos, vel, pos_sp, vel_ff, acc_ff, yaw_sp, dt, P, S):
    """Compiled :meth:`PositionControl.update` (same maths). State S: [0:3] integrators, [3:6] previous
    velocity, [6:9] filtered acceleration, [9] 1 when [3:6] is valid. Returns (qw, qx, qy, qz, thrust)."""
    g = 9.80665
    vx = vel_ff[0] if pos_sp[0] != pos_sp[0] else vel_ff[0] + P[0] * (pos_sp[0] - pos[0])
    vy = vel_ff[1] if pos_sp[1] != pos_sp[1] else vel_ff[1] + P[0] * (pos_sp[1] - pos[1])
    vz = vel_ff[2] if pos_sp[2] != pos_sp[2] else vel_ff[2] + P[1] * (pos_sp[2] - pos[2])
    sp = math.hypot(vx, vy)
    if sp > P[8]:
        vx, vy = vx * P[8] / sp, vy * P[8] / sp
    vz = min(max(vz, -P[9]), P[10])
    if S[9] > 0.5 and dt > 0:
        for i in range(3):
            S[6 + i] = 0.5 * S[6 + i] + 0.5 * (vel[i] - S[3 + i]) / dt
    S[3], S[4], S[5], S[9] = vel[0], vel[1], vel[2], 1.0
    ex, ey, ez = vx - vel[0], vy - vel[1], vz - vel[2]
    ax = acc_ff[0] + P[2] * ex + S[0] - P[4] * S[6]
    ay = acc_ff[1] + P[2] * ey + S[1] - P[4] * S[7]
    az = acc_ff[2] + P[5] * ez + S[2] - P[7] * S[8]
    bx, by, bz = -ax, -ay, g
    n = math.sqrt(bx * bx + by * by + bz * bz)
    bx, by, bz = bx / n, by / n, bz / n
    tilt = math.acos(max(-1.0, min(1.0, bz)))
    if tilt > P[11]:
        h = math.hypot(bx, by)
        bx, by, bz = bx / h * math.sin(P[11]), by / h * math.sin(P[11]), math.cos(P[11])
    hover, thr_min, thr_max = P[12], P[13], P[14]
    thr_ned_z = az * (hover / g) - hover
    collective = thr_ned_z / bz
    tx, ty = bx * collective, by * collective
    tz = min(max(thr_ned_z, -thr_max), -thr_min)
    if (tz >= -thr_min and ez >= 0.0) or (tz <= -thr_max and ez <= 0.0):
        ez = 0.0
    xy_max = math.sqrt(max(thr_max * thr_max - tz * tz, 0.0))
    txy = math.hypot(tx, ty)
    if txy > xy_max:
        tx, ty = tx * xy_max / txy, ty * xy_max / txy
    arw = 2.0 / P[2]
    ex -= arw * (ax - tx * (g / hover))
    ey -= arw * (ay - ty * (g / hover))
    S[0] += ex * P[3] * dt
    S[1] += ey * P[3] * dt
    S[2] = max(-g, min(g, S[2] + ez * P[6] * dt))
    q = attitude_from_thrust(tx, ty, tz, yaw_sp)
    return (q[0], q[1], q[2], q[3], math.sqrt(tx * tx + ty * ty + tz * tz))
