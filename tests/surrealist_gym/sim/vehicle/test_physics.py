"""Analytic cases in the PyBullet world: free fall with the motors off, hover holding its altitude, frames."""
from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest

from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.sim.config import PX4_DEFAULTS
from surrealist_gym.sim.vehicle.airframe import GRAVITY, PX4_VISION
from surrealist_gym.sim.vehicle.control import PositionControl, inner_step, kernel_params
from surrealist_gym.sim.vehicle.world import World
from surrealist_gym.testcase import Obstacle, Shape

HZ = 200.0


def _place(world, body, z_ned):
    pb.resetBasePositionAndOrientation(body, [0, 0, z_ned], [0, 0, 0, 1], physicsClientId=world.cid)


def test_free_fall_with_motors_off():
    with World((), PX4_VISION, 1, HZ) as world:
        body = world.vehicles[0]
        _place(world, body, -30.0)
        kp, ks = kernel_params(dict(PX4_DEFAULTS), PX4_VISION, 1 / HZ), np.zeros(10)
        n = 300  # 1.5 s
        for _ in range(n):
            pos, orn = pb.getBasePositionAndOrientation(body, physicsClientId=world.cid)
            lin, ang = pb.getBaseVelocity(body, physicsClientId=world.cid)
            f = inner_step(orn, lin, ang, (1.0, 0.0, 0.0, 0.0), 0.0, (0.0, 0.0, 0.0), 1 / HZ, False, False, kp, ks)
            assert f == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            pb.stepSimulation(physicsClientId=world.cid)
        pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=world.cid)
        t = n / HZ
        assert pos[2] + 30.0 == pytest.approx(0.5 * GRAVITY * t * t, rel=0.01)  # z down: falls toward +z


def test_hover_holds_altitude():
    params = dict(PX4_DEFAULTS, MPC_THR_HOVER=0.3)
    with World((), PX4_VISION, 1, HZ) as world:
        body, cid = world.vehicles[0], world.cid
        _place(world, body, -3.0)
        kp, ks = kernel_params(params, PX4_VISION, 1 / HZ), np.zeros(10)
        ctl = PositionControl(params)
        q_sp, thrust = (1.0, 0.0, 0.0, 0.0), 0.3
        zs = []
        for step in range(int(10 * HZ)):
            pos, orn = pb.getBasePositionAndOrientation(body, physicsClientId=cid)
            lin, ang = pb.getBaseVelocity(body, physicsClientId=cid)
            if step % 4 == 0:
                q_sp, thrust = ctl.update(pos, lin, (0.0, 0.0, -3.0), (0.0, 0.0, 0.0), 0.0, 4 / HZ)
                zs.append(pos)
            f = inner_step(orn, lin, ang, q_sp, thrust, (0.0, 0.0, 0.0), 1 / HZ, True, True, kp, ks)
            pb.applyExternalForce(body, -1, f[:3], pos, pb.WORLD_FRAME, physicsClientId=cid)
            pb.applyExternalTorque(body, -1, f[3:], pb.WORLD_FRAME, physicsClientId=cid)
            pb.stepSimulation(physicsClientId=cid)
        zs = np.array(zs)
        assert np.abs(zs[:, 2] + 3.0).max() < 0.05
        assert np.abs(zs[:, :2]).max() < 0.01
        # the motors settle at the physical hover command
        assert thrust == pytest.approx(PX4_VISION.hover_command, abs=0.01)


@pytest.mark.parametrize("shape", [Shape.BOX, Shape.CYLINDER])
def test_obstacles_placed_by_the_frame_conventions(shape):
    """Contact points of a probe agree with geometry.obstacle_distances (x north, y east, r from north to east)."""
    obs = Obstacle(4.0, 1.0, 2.0, 5.0, -3.0, 0.5, 30.0, shape)
    with World([obs], PX4_VISION, 0, HZ) as world:
        probe = pb.createCollisionShape(pb.GEOM_SPHERE, radius=0.01, physicsClientId=world.cid)
        rng = np.random.default_rng(0)
        pts = np.column_stack([rng.uniform(1, 9, 400), rng.uniform(-7, 1, 400), rng.uniform(0.0, 3.0, 400)])
        expected = obstacle_distances(pts, [obs], dims=3)[:, 0]
        body = pb.createMultiBody(0, probe, basePosition=[0, 0, -50], physicsClientId=world.cid)
        for p, d in zip(pts, expected):
            pb.resetBasePositionAndOrientation(body, [p[0], p[1], -p[2]], [0, 0, 0, 1], physicsClientId=world.cid)
            got = pb.getClosestPoints(body, world.obstacles[0], 10.0, physicsClientId=world.cid)
            dist = min(c[8] for c in got) + 0.01
            if d > 0.05:
                assert dist == pytest.approx(d, abs=0.02)
