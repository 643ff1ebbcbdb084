"""The PX4 cascade: the compiled inner loop equals the readable reference; thrust-to-attitude geometry."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.sim.config import PX4_DEFAULTS
from surrealist_gym.sim.vehicle.airframe import IRIS, PX4_VISION
from surrealist_gym.sim.vehicle.control import (
    AttitudeRateControl,
    PositionControl,
    attitude_from_thrust,
    inner_step,
    kernel_params,
    position_params,
    position_step,
)


def _matrix(qx, qy, qz, qw):
    return np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
                     [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
                     [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]])


@pytest.mark.parametrize("vehicle", [PX4_VISION, IRIS])
def test_compiled_inner_loop_equals_reference(vehicle):
    params, dt = dict(PX4_DEFAULTS), 1 / 200
    kp, ks = kernel_params(params, vehicle, dt), np.zeros(10)
    ref = AttitudeRateControl(params, vehicle, dt)
    rng = np.random.default_rng(3)
    for _ in range(300):
        q = rng.normal(size=4)
        qx, qy, qz, qw = q / np.linalg.norm(q)
        q_sp = rng.normal(size=4)
        q_sp = tuple(q_sp / np.linalg.norm(q_sp))
        ang, thrust = tuple(rng.normal(size=3)), float(rng.uniform(0, 1))
        out = inner_step((qx, qy, qz, qw), (0.0, 0.0, 0.0), ang, q_sp, thrust, (0.0, 0.0, 0.0), dt, True, True, kp, ks)
        rot = _matrix(qx, qy, qz, qw)
        fz, tx, ty, tz = ref.update((qw, qx, qy, qz), tuple(rot.T @ np.array(ang)), q_sp, thrust, dt)
        expected = np.r_[rot @ np.array([0.0, 0.0, fz]), rot @ np.array([tx, ty, tz])]
        np.testing.assert_allclose(out, expected, atol=1e-9)


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.5, math.pi])
def test_attitude_from_thrust_points_body_z_against_thrust(yaw):
    tx, ty, tz = 0.1, -0.2, -0.5
    w, x, y, z = attitude_from_thrust(tx, ty, tz, yaw)
    rot = _matrix(x, y, z, w)
    n = math.sqrt(tx * tx + ty * ty + tz * tz)
    np.testing.assert_allclose(rot[:, 2], [-tx / n, -ty / n, -tz / n], atol=1e-12)
    # heading of the body x axis projected on the ground
    assert math.remainder(math.atan2(rot[1, 0], rot[0, 0]) - yaw, 2 * math.pi) == pytest.approx(0.0, abs=0.2)


def test_position_control_hover_feedforward():
    params = dict(PX4_DEFAULTS)
    ctl = PositionControl(params)
    q, thrust = ctl.update((0.0, 0.0, -3.0), (0.0, 0.0, 0.0), (0.0, 0.0, -3.0), (0.0, 0.0, 0.0), 0.0, 0.02)
    assert thrust == pytest.approx(params["MPC_THR_HOVER"])
    assert q == pytest.approx((1.0, 0.0, 0.0, 0.0))


def test_position_control_tilt_limited():
    params = dict(PX4_DEFAULTS, MPC_TILTMAX_AIR=20.0)
    ctl = PositionControl(params)
    q, _ = ctl.update((0.0, 0.0, -3.0), (0.0, 0.0, 0.0), (100.0, 0.0, -3.0), (0.0, 0.0, 0.0), 0.0, 0.02)
    w, x, y, z = q
    tilt = math.acos(1 - 2 * (x * x + y * y))
    assert tilt == pytest.approx(math.radians(20.0), abs=1e-6)


def test_compiled_position_control_equals_reference():
    params = dict(PX4_DEFAULTS, MPC_THR_HOVER=0.3, MPC_XY_VEL_MAX=5.0)
    ref, kp, ks = PositionControl(params), position_params(params), np.zeros(10)
    rng = np.random.default_rng(4)
    for i in range(300):
        pos, vel = tuple(rng.normal(size=3) * 5), tuple(rng.normal(size=3) * 2)
        pos_sp = tuple(rng.normal(size=3) * 5)
        if i % 3 == 0:
            pos_sp = (math.nan, math.nan, pos_sp[2])
        vel_ff, yaw = tuple(rng.normal(size=3)), float(rng.uniform(-math.pi, math.pi))
        acc_ff = tuple(rng.normal(size=3))
        q, thrust = ref.update(pos, vel, pos_sp, vel_ff, yaw, 0.02, acc_ff)
        out = position_step(pos, vel, pos_sp, vel_ff, acc_ff, yaw, 0.02, kp, ks)
        np.testing.assert_allclose(out, (*q, thrust), atol=1e-9)
