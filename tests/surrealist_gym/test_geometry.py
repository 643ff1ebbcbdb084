import math

import numpy as np
import pytest

from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.testcase import Obstacle, Shape


def test_box_distances_2d_and_3d():
    box = Obstacle(4, 2, 3, 10, 0, 0, 0)  # x in [8, 12], y in [-1, 1], z in [0, 3]
    pts = np.array([[0, 0, 1], [10, 3, 1], [10, 0, 5], [13, 2, 4], [10, 0, 1]], float)
    d2 = obstacle_distances(pts, [box], dims=2)[:, 0]
    d3 = obstacle_distances(pts, [box], dims=3)[:, 0]
    assert d2.tolist() == pytest.approx([8, 2, 0, math.sqrt(2), 0])
    assert d3.tolist() == pytest.approx([8, 2, 2, math.sqrt(3), 0])


def test_rotation_is_from_north_toward_east():
    # a long thin wall along x (north), rotated 90 deg, lies along y (east)
    wall = Obstacle(10, 0.2, 3, 0, 0, 0, 90)
    d = obstacle_distances([[0, 4, 1], [4, 0, 1]], [wall])[:, 0]
    assert d[0] == pytest.approx(0.0) and d[1] == pytest.approx(3.9)


def test_cylinder():
    cyl = Obstacle(2, 2, 5, 0, 0, 0, 0, Shape.CYLINDER)
    assert obstacle_distances([[3, 4, 1]], [cyl])[0, 0] == pytest.approx(4.0)


def test_matches_obstacle_distance_2d_method():
    rng = np.random.default_rng(0)
    obs = [Obstacle(3, 3, 3, -8.64, 1.74, 0, 158.8), Obstacle(2, 5, 3, 4, 4, 0, 30)]
    pts = rng.uniform(-15, 15, size=(50, 3))
    d = obstacle_distances(pts, obs)
    for i, p in enumerate(pts):
        for j, o in enumerate(obs):
            assert d[i, j] == pytest.approx(o.distance_2d(p[0], p[1]))
