"""DepthSensor: analytic ray casting against boxes and cylinders, field of view, range limits, noise."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.sim.sensing.sensor import DepthSensor, DepthSensorConfig
from surrealist_gym.testcase import Obstacle, Shape

# odd ray counts put one ray exactly on the optical axis
AXIS = DepthSensorConfig(rays_h=33, rays_v=13)


def _axis_hit(hits, position, yaw):
    """The hit on the optical axis (the one with the smallest lateral and vertical offset)."""
    rel = hits - np.asarray(position)
    lateral = np.abs(-math.sin(yaw) * rel[:, 0] + math.cos(yaw) * rel[:, 1]) + np.abs(rel[:, 2])
    return hits[np.argmin(lateral)]


def test_box_straight_ahead_hits_its_front_face():
    box = Obstacle(2.0, 6.0, 4.0, 5.0, 0.0)  # front face at x = 4
    hits = DepthSensor([box], AXIS).scan((0.0, 0.0, 2.0), 0.0)
    assert len(hits) > 100
    np.testing.assert_allclose(hits[:, 0], 4.0, atol=1e-9)
    np.testing.assert_allclose(_axis_hit(hits, (0, 0, 2), 0.0), (4.0, 0.0, 2.0), atol=1e-9)
    # the face spans y in [-3, 3] at 4 m: the 59 deg FOV cuts it at 4 * tan(29.5 deg)
    assert np.abs(hits[:, 1]).max() == pytest.approx(4.0 * math.tan(math.radians(29.5)), abs=1e-9)


def test_yawed_camera_and_rotated_box():
    box = Obstacle(2.0, 2.0, 3.0, 0.0, 5.0, 0.0, r=45.0)  # due east, a corner pointing at the camera
    position, yaw = (0.0, 0.0, 1.5), math.radians(90.0)
    hits = DepthSensor([box], AXIS).scan(position, yaw)
    assert len(hits) > 0
    np.testing.assert_allclose(obstacle_distances(hits, [box], dims=3), 0.0, atol=1e-9)  # all on the surface
    corner = 5.0 - math.sqrt(2.0)
    axis = _axis_hit(hits, position, yaw)
    assert np.linalg.norm(axis - np.asarray(position)) == pytest.approx(corner, abs=1e-9)
    assert np.linalg.norm(hits - np.asarray(position), axis=1).min() == pytest.approx(corner, abs=1e-9)
    odd = Obstacle(3.0, 1.0, 3.0, -4.0, -4.0, 0.5, r=-30.0)
    hits = DepthSensor([odd], AXIS).scan((0.0, 0.0, 2.0), math.radians(-135.0))
    assert len(hits) > 0
    np.testing.assert_allclose(obstacle_distances(hits, [odd], dims=3), 0.0, atol=1e-9)


def test_cylinder_side_and_top():
    cyl = Obstacle(2.0, 2.0, 2.0, 5.0, 0.0, 0.0, shape=Shape.CYLINDER)  # radius 1, top at 2 m
    position = (0.0, 0.0, 1.0)
    hits = DepthSensor([cyl], AXIS).scan(position, 0.0)
    np.testing.assert_allclose(_axis_hit(hits, position, 0.0), (4.0, 0.0, 1.0), atol=1e-9)
    np.testing.assert_allclose(obstacle_distances(hits, [cyl], dims=3), 0.0, atol=1e-9)
    # from above the cylinder, looking at it, some rays land on its top disc
    hits = DepthSensor([cyl], AXIS).scan((2.5, 0.0, 3.0), 0.0)
    top = hits[np.abs(hits[:, 2] - 2.0) < 1e-9]
    assert len(top) > 0
    assert np.hypot(top[:, 0] - 5.0, top[:, 1]).max() <= 1.0 + 1e-9


def test_nearest_obstacle_occludes_the_farther_one():
    near, far = Obstacle(1.0, 1.0, 4.0, 3.0, 0.0), Obstacle(1.0, 6.0, 4.0, 7.0, 0.0)
    hits = DepthSensor([far, near], AXIS).scan((0.0, 0.0, 2.0), 0.0)
    behind_near = np.abs(hits[:, 1]) < 0.5 * 2.5 / 3.0  # inside the near box's shadow
    assert behind_near.any()
    np.testing.assert_allclose(hits[behind_near, 0], 2.5, atol=1e-9)


def test_nothing_behind_or_outside_the_field_of_view():
    sensor = DepthSensor([Obstacle(1.0, 1.0, 4.0, -5.0, 0.0)])
    assert sensor.scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)
    assert len(sensor.scan((0.0, 0.0, 2.0), math.pi)) > 0
    side = Obstacle(0.5, 0.5, 4.0, 5.0 * math.cos(math.radians(40)), 5.0 * math.sin(math.radians(40)))
    assert DepthSensor([side]).scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)  # 40 deg > 29.5 deg half FOV
    assert len(DepthSensor([side]).scan((0.0, 0.0, 2.0), math.radians(40))) > 0
    high = Obstacle(1.0, 4.0, 1.0, 3.0, 0.0, z=6.0)  # 30 deg up and more, above the 23 deg half FOV
    assert DepthSensor([high]).scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)


def test_range_limits():
    far = Obstacle(1.0, 4.0, 4.0, 10.6, 0.0)  # face at 10.1 m > range_max
    assert DepthSensor([far]).scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)
    assert len(DepthSensor([far], DepthSensorConfig(range_max=15.0)).scan((0.0, 0.0, 2.0), 0.0)) > 0
    close = Obstacle(1.0, 4.0, 4.0, 0.6, 0.0)  # face at 0.1 m < range_min everywhere in the FOV
    assert DepthSensor([close]).scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)
    inside = Obstacle(4.0, 4.0, 4.0, 0.0, 0.0)
    assert DepthSensor([inside]).scan((0.0, 0.0, 2.0), 0.0).shape == (0, 3)


def test_ground_is_never_returned():
    assert DepthSensor([]).scan((0.0, 0.0, 1.0), 0.0).shape == (0, 3)
    hits = DepthSensor([Obstacle(1.0, 4.0, 0.5, 4.0, 0.0)]).scan((0.0, 0.0, 1.0), 0.0)
    assert len(hits) > 0 and hits[:, 2].min() >= 0.0


def test_noise_is_reproducible_and_only_from_the_given_rng():
    box = Obstacle(2.0, 6.0, 4.0, 5.0, 0.0)
    sensor = DepthSensor([box], DepthSensorConfig(noise_std=0.05))
    exact = sensor.scan((0.0, 0.0, 2.0), 0.0)
    a = sensor.scan((0.0, 0.0, 2.0), 0.0, np.random.default_rng(7))
    b = sensor.scan((0.0, 0.0, 2.0), 0.0, np.random.default_rng(7))
    c = sensor.scan((0.0, 0.0, 2.0), 0.0, np.random.default_rng(8))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    np.testing.assert_array_equal(exact, sensor.scan((0.0, 0.0, 2.0), 0.0))
    assert a.shape == exact.shape
    err = np.linalg.norm(a - [0.0, 0.0, 2.0], axis=1) - np.linalg.norm(exact - [0.0, 0.0, 2.0], axis=1)
    assert 0.03 < err.std() < 0.07
    # the rng advances by one draw per ray, whatever is hit
    rng1, rng2 = np.random.default_rng(3), np.random.default_rng(3)
    sensor.scan((0.0, 0.0, 2.0), 0.0, rng1)
    DepthSensor([], DepthSensorConfig(noise_std=0.05)).scan((0.0, 0.0, 2.0), 0.0, rng2)
    assert rng1.random() == rng2.random()


def test_scan_returns_a_fresh_array():
    sensor = DepthSensor([Obstacle(2.0, 4.0, 4.0, 5.0, 0.0)])
    first = sensor.scan((0.0, 0.0, 2.0), 0.0)
    kept = first.copy()
    sensor.scan((0.0, 0.0, 2.0), 0.3)
    np.testing.assert_array_equal(first, kept)
    assert sensor.n_rays == 32 * 12


@pytest.mark.parametrize("bad", [dict(fov_h_deg=0.0), dict(fov_v_deg=180.0), dict(range_min=5.0, range_max=4.0),
                                 dict(rays_h=0), dict(rays_v=2.5), dict(noise_std=-0.1)])
def test_config_rejects_bad_values(bad):
    with pytest.raises(ValueError):
        DepthSensorConfig(**bad)
