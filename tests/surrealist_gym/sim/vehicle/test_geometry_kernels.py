"""The closed-form geometry kernels against the depth sensor (bit for bit) and PyBullet (rays, contacts,
distances) on random scenes of turned boxes and cylinders."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.sim.sensing.sensor import DepthSensor, DepthSensorConfig
from surrealist_gym.sim.vehicle import geometry_kernels as gk
from surrealist_gym.sim.vehicle.airframe import IRIS
from surrealist_gym.sim.vehicle.pybullet_quiet import pb
from surrealist_gym.sim.vehicle.world import World
from surrealist_gym.testcase import Obstacle, Shape

FLIP = np.array([1.0, 1.0, -1.0])  # z up <-> PyBullet's NED
PB_MARGIN = 1.2e-3  # PyBullet's cylinder rays, box edges and GJK distances: within its 1 mm collision margin


def _random_obstacles(rng, shape: Shape, n: int) -> list[Obstacle]:
    out = []
    for _ in range(n):
        x, y, z, h = rng.uniform(-12, 12), rng.uniform(-12, 12), rng.uniform(0, 2), rng.uniform(2, 15)
        if shape == Shape.BOX:
            out.append(Obstacle(rng.uniform(1, 8), rng.uniform(1, 8), h, x, y, z, rng.uniform(0, 360)))
        else:
            out.append(Obstacle(rng.uniform(1, 6), 1.0, h, x, y, z, 0.0, Shape.CYLINDER))
    return out


def _resized(scene: np.ndarray, m: float) -> np.ndarray:
    """The scene with every solid grown by m [m] on each side (shrunk when m < 0)."""
    out = scene.copy()
    for col in (gk.COL_HX, gk.COL_HY, gk.COL_HZ, gk.COL_Z1):
        out[:, col] += m
    out[:, gk.COL_Z0] -= m
    return out


def test_rays_equal_the_depth_sensor():
    rng = np.random.default_rng(0)
    obstacles = _random_obstacles(rng, Shape.BOX, 3) + _random_obstacles(rng, Shape.CYLINDER, 2)
    sensor = DepthSensor(obstacles, DepthSensorConfig(rays_h=30, rays_v=23, range_min=0.5, range_max=18.0,
                                                      returns_ground=True, noise_std=0.0))
    scene = gk.scene_array(obstacles)
    rays = sensor._rays
    for _ in range(20):
        p = np.array([rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(0.5, 10)])
        yaw = rng.uniform(-math.pi, math.pi)
        c, s = math.cos(yaw), math.sin(yaw)
        d = np.stack([rays[:, 0] * c - rays[:, 1] * s, rays[:, 0] * s + rays[:, 1] * c, rays[:, 2]], axis=1)
        t, what = np.empty(len(d)), np.empty(len(d), dtype=np.int64)
        gk.cast_rays(np.tile(p, (len(d), 1)), d, 18.0, scene, True, t, what)
        keep = ((what >= 0) | (what == gk.GROUND)) & (t >= 0.5) & (t <= 18.0)
        assert np.array_equal(sensor.scan(p, yaw), p + t[keep, None] * d[keep])


@pytest.mark.parametrize("shape", [Shape.BOX, Shape.CYLINDER])
def test_rays_match_pybullet_ray_test_batch(shape):
    """Same object hit by every ray (origins outside the obstacles); boxes: 99 % of the distances within 1e-6 m;
    all: PyBullet's distance lies between the exact ones to the solids grown and shrunk by PB_MARGIN."""
    rng = np.random.default_rng(1 if shape == Shape.BOX else 2)
    obstacles = _random_obstacles(rng, shape, 4)
    scene = gk.scene_array(obstacles)
    n = 3000
    a = np.column_stack([rng.uniform(-20, 20, n), rng.uniform(-20, 20, n), rng.uniform(0.1, 12, n)])
    b = np.column_stack([rng.uniform(-20, 20, n), rng.uniform(-20, 20, n), rng.uniform(-3, 16, n)])
    t, what = gk.ray_test_batch(a, b, scene, ground=True)
    with World(obstacles, IRIS, 0, 200.0) as world:
        res = []
        for i in range(0, n, 1000):
            res += pb.rayTestBatch((a[i:i + 1000] * FLIP).tolist(), (b[i:i + 1000] * FLIP).tolist(),
                                   physicsClientId=world.cid)
        code = {world.ground: gk.GROUND, -1: gk.MISS, **world.obstacle_index}
    pb_what = np.array([code[r[0]] for r in res])
    pb_t = np.array([r[2] for r in res])
    outside = what != gk.INSIDE
    assert outside.sum() > 0.9 * n
    assert np.array_equal(pb_what[outside], what[outside])
    hit = outside & (what != gk.MISS)
    assert hit.sum() > 0.2 * n and (what >= 0).sum() > 0.1 * n
    length = np.linalg.norm(b - a, axis=1)
    err = np.abs(pb_t - t) * length
    if shape == Shape.BOX:
        assert np.mean(err[hit] <= 1e-6) > 0.99
    t_grown, _ = gk.ray_test_batch(a, b, _resized(scene, PB_MARGIN), ground=True)
    t_shrunk, _ = gk.ray_test_batch(a, b, _resized(scene, -PB_MARGIN), ground=True)
    d_pb = pb_t * length
    assert np.all((d_pb >= t_grown * length - 1e-9) & (d_pb <= t_shrunk * length + 1e-9) | ~outside)


def test_ray_from_inside_an_obstacle_sees_nothing():
    scene = gk.scene_array([Obstacle(4, 4, 4, 0.0, 0.0), Obstacle(2, 2, 4, 10.0, 0.0, shape=Shape.CYLINDER)])
    assert gk.ray_cast(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 20.0, scene, True) == (0.0, gk.INSIDE)
    assert gk.ray_cast(10.0, 0.0, 1.0, -1.0, 0.0, 0.0, 20.0, scene, True) == (0.0, gk.INSIDE)
    assert gk.ray_cast(0.0, 5.0, 1.0, 0.0, 0.0, -1.0, 20.0, scene, True) == (1.0, gk.GROUND)
    assert gk.ray_cast(0.0, 5.0, 1.0, 0.0, 0.0, -1.0, 20.0, scene, False) == (1.0, gk.MISS)


def _random_pose(rng, obstacles, scale, i):
    """A vehicle pose near obstacle i % 4 (the ground for 3), level-ish or anyhow turned."""
    j = i % 4
    if j < len(obstacles):
        o = obstacles[j]
        ang = rng.uniform(0, 2 * math.pi)
        rad = max(o.l, o.w) * scale / 2 * rng.uniform(0.3, 1.0) + rng.uniform(-0.1, 0.4)
        p = np.array([o.x + rad * math.cos(ang), o.y + rad * math.sin(ang), rng.uniform(o.z - 0.5, o.z + o.h + 0.5)])
    else:
        p = np.array([rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(-0.05, 0.4)])
    if rng.uniform() < 0.5:
        tilt = rng.normal(0, 0.2, 2)
        q = np.array(pb.getQuaternionFromEuler([tilt[0], tilt[1], rng.uniform(-math.pi, math.pi)]))
    else:
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
    return j, p, q


def test_contacts_and_distances_match_pybullet():
    """PyBullet's contact points after collision detection vs :func:`vehicle_contact`'s rules, for the Iris box
    near turned boxes, a raised cylinder and the ground, with the SITL profile's 0.8 collision scale: the same
    contacts except within 1 mm of the GJK threshold; getClosestPoints' distances within PB_MARGIN."""
    rng = np.random.default_rng(3)
    obstacles = [Obstacle(3, 5, 6, 0, 0, 0, 30), Obstacle(4, 4, 5, 10, 0, 1, shape=Shape.CYLINDER),
                 Obstacle(2, 6, 4, 0, 10, 0.5, 77)]
    scale = 0.8
    scene = gk.scene_array(obstacles, scale)
    half = np.array([s / 2 for s in IRIS.size])
    thr = gk.contact_threshold(half)
    touching, near_threshold, errs = 0, 0, []
    with World(obstacles, IRIS, 1, 200.0, 100.0, scale) as world:
        body, cid = world.vehicles[0], world.cid
        for i in range(2000):
            j, p, q = _random_pose(rng, obstacles, scale, i)
            pb.resetBasePositionAndOrientation(body, (p * FLIP).tolist(), q.tolist(), physicsClientId=cid)
            pb.performCollisionDetection(physicsClientId=cid)
            pb_set = set()
            for c in pb.getContactPoints(bodyA=body, physicsClientId=cid):
                other = c[2] if c[1] == body else c[1]
                pb_set.add(gk.GROUND if other == world.ground else world.obstacle_index[other])
            axes = gk.vehicle_axes_ned(*q)
            ours, margin = set(), math.inf
            for k in range(len(obstacles)):
                if scene[k, gk.COL_KIND] == gk.BOX:
                    if gk.boxes_overlap(p, axes, half, scene, k):
                        ours.add(k)
                else:
                    d = gk.vehicle_distance(p, axes, half, scene, k)
                    margin = min(margin, abs(d - thr))
                    if d < thr:
                        ours.add(k)
            g = gk.ground_clearance(p, axes, half)
            margin = min(margin, abs(g - thr))
            if g < thr:
                ours.add(gk.GROUND)
            if ours != pb_set:
                assert margin < 1e-3, (i, ours, pb_set)
                near_threshold += 1
            touching += bool(pb_set)
            first = gk.vehicle_contact(p, axes, half, thr, scene)
            assert (first == gk.MISS) == (not ours) and (first in ours or first == gk.MISS)
            if j < len(obstacles):
                closest = pb.getClosestPoints(body, world.obstacles[j], 0.5, physicsClientId=cid)
                d_pb = min((c[8] for c in closest), default=math.inf)
                if 0.0 < d_pb < 0.5:
                    errs.append(abs(d_pb - gk.vehicle_distance(p, axes, half, scene, j)))
    assert touching > 300 and near_threshold <= 5
    assert len(errs) > 300 and max(errs) < PB_MARGIN


def test_contact_threshold_is_bullets():
    """The Iris box touches a cylinder or the ground at 0.02 x its half diagonal, as measured in PyBullet."""
    assert gk.contact_threshold([0.235, 0.235, 0.055]) == pytest.approx(0.0067372, abs=1e-6)
