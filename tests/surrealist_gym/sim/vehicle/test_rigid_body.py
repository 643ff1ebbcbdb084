"""The numba rigid body against PyBullet: the same open-loop motor commands give the same free flight (to
rounding), the ground contact approximates Bullet's solver within millimetres."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.sim.vehicle import rigid_body as rb
from surrealist_gym.sim.vehicle.airframe import IRIS
from surrealist_gym.sim.vehicle.pybullet_quiet import pb
from surrealist_gym.sim.vehicle.world import World

DT, N_SUB = 0.01, 2  # the SITL profile's control step and PyBullet sub-steps (physics 200 Hz)


def _motor_forces(q, vel, u):
    """World force and torque of four rotor commands u (quad X, PX4 order) and linear drag, at attitude q."""
    qx, qy, qz, qw = q
    r = np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
                  [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
                  [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]])
    thrust = IRIS.max_thrust * u ** 2
    arm = IRIS.arm_length * math.sqrt(0.5)
    px, py, spin = (1, -1, 1, -1), (1, -1, -1, 1), (1, 1, -1, -1)
    torque = np.array([-sum(py[i] * arm * thrust[i] for i in range(4)), sum(px[i] * arm * thrust[i] for i in range(4)),
                       sum(spin[i] * IRIS.moment_constant * thrust[i] for i in range(4))])
    force = r @ np.array([0.0, 0.0, -thrust.sum()]) - IRIS.drag_xy * np.asarray(vel)
    return tuple(force), tuple(r @ torque)


def _commands(k):
    t, h = k * DT, IRIS.hover_command
    return np.array([h + 0.02 * math.sin(3 * t), h + 0.02 * math.sin(3 * t + 1), h - 0.015 * math.sin(2 * t),
                     h + 0.01 * math.cos(5 * t)]) + 0.003


@pytest.mark.parametrize("damping", [0.0, 0.04])
def test_open_loop_free_flight_equals_pybullet(damping):
    """3 s of the same motor commands from a turned, moving start (the vehicle speeds up to ~25 m/s and turns at
    up to ~1.4 rad/s): positions within 1e-9 m, attitude quaternions within 1e-9 (measured: ~1e-14), up to the
    sign PyBullet reports them with."""
    q0 = pb.getQuaternionFromEuler([0.1, -0.05, 0.7])
    v0, w0 = (1.0, 0.5, -0.2), (0.3, -0.2, 0.5)
    state = rb.initial_state((0.0, 0.0, -20.0))
    state[3:7], state[7:10], state[10:13] = q0, v0, w0
    body, free = rb.body_params(IRIS, damping, damping), np.zeros(0)
    with World((), IRIS, 1, 200.0, 100.0) as world:
        b, cid = world.vehicles[0], world.cid
        pb.changeDynamics(b, -1, linearDamping=damping, angularDamping=damping, physicsClientId=cid)
        pb.resetBasePositionAndOrientation(b, [0.0, 0.0, -20.0], q0, physicsClientId=cid)
        pb.resetBaseVelocity(b, v0, w0, physicsClientId=cid)
        for k in range(300):
            pos, q = pb.getBasePositionAndOrientation(b, physicsClientId=cid)
            lin, ang = pb.getBaseVelocity(b, physicsClientId=cid)
            np.testing.assert_allclose(state[0:3], pos, rtol=0, atol=1e-9)
            sign = 1.0 if np.dot(state[3:7], q) >= 0 else -1.0  # PyBullet reports q or -q (the same attitude)
            np.testing.assert_allclose(sign * state[3:7], q, rtol=0, atol=1e-9)
            np.testing.assert_allclose(state[7:13], lin + ang, rtol=0, atol=1e-9)
            u = _commands(k)
            force, torque = _motor_forces(q, lin, u)
            pb.applyExternalForce(b, -1, force, pos, pb.WORLD_FRAME, physicsClientId=cid)
            pb.applyExternalTorque(b, -1, torque, pb.WORLD_FRAME, physicsClientId=cid)
            pb.stepSimulation(physicsClientId=cid)
            force, torque = _motor_forces(state[3:7], state[7:10], u)
            rb.step(state, force, torque, DT, N_SUB, body, free)
    assert np.linalg.norm(lin) > 10.0 and np.linalg.norm(ang) > 0.5  # the flight went somewhere


@pytest.mark.parametrize("case", ["rest", "touchdown", "tilted touchdown"])
def test_ground_contact_approximates_pybullet(case):
    """Motors off on the ground, or falling onto it at ~1.2 m/s (level, or tilted and turning): over 1 s the
    height stays within 1 mm of PyBullet's, the horizontal position within 1 cm, the attitude within 1e-2."""
    half, body = np.array([s / 2 for s in IRIS.size]), rb.body_params(IRIS)
    with World((), IRIS, 1, 200.0, 100.0) as world:
        b, cid = world.vehicles[0], world.cid
        p0, q0, v0, w0 = [0.0, 0.0, world.rest_z], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        if case != "rest":
            p0, v0 = [0.0, 0.0, world.rest_z - 0.05], [0.3, 0.1, 0.8]
        if case == "tilted touchdown":
            p0, q0, w0 = [0.0, 0.0, world.rest_z - 0.08], list(pb.getQuaternionFromEuler([0.08, -0.05, 0.3])), \
                [0.2, 0.1, 0.3]
        pb.resetBasePositionAndOrientation(b, p0, q0, physicsClientId=cid)
        pb.resetBaseVelocity(b, v0, w0, physicsClientId=cid)
        state = rb.initial_state(p0)
        state[3:7], state[7:10], state[10:13] = q0, v0, w0
        for _ in range(100):
            pb.stepSimulation(physicsClientId=cid)
            rb.step(state, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), DT, N_SUB, body, half)
            pos, q = pb.getBasePositionAndOrientation(b, physicsClientId=cid)
            assert abs(state[2] - pos[2]) < 1e-3
            assert np.abs(state[0:2] - pos[0:2]).max() < 1e-2
            assert min(np.abs(state[3:7] - q).max(), np.abs(state[3:7] + q).max()) < 1e-2
        assert abs(pos[2] - world.rest_z) < 1e-4 and abs(state[2] - world.rest_z) < 1e-4  # both at rest
