import math

import numpy as np
import pytest

from surrealist_gym.geometry import competition_distance, competition_distances, obstacle_distances
from surrealist_gym.testcase import Obstacle, Shape
from surrealist_gym.trajectory import Trajectory


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


# --- the competition's distance ----------------------------------------------------------------------------------
def _rilast_flights():
    """The 24 PX4 trajectories of rilast-mission1 with their obstacles and labelled 2-D distance."""
    import csv
    import json

    from tests.conftest import SHARED_DATA

    folder = SHARED_DATA / "competition" / "rilast-mission1"
    with open(folder / "tests.csv", newline="") as f:
        tests = {r["test_id"]: r for r in csv.DictReader(f)}
    points: dict[str, list] = {}
    with open(folder / "trajectories.csv", newline="") as f:
        for r in csv.DictReader(f):
            points.setdefault(r["test_id"], []).append((int(r["sample"]), float(r["x"]), float(r["y"]),
                                                        float(r["z"])))
    out = []
    for test_id, rows in points.items():
        rows.sort()
        traj = Trajectory(0.5 * np.array([r[0] for r in rows]), np.array([r[1:] for r in rows]))
        obstacles = [Obstacle(**o) for o in json.loads(tests[test_id]["obstacles"])]
        out.append((test_id, traj, obstacles, float(tests[test_id]["px4_min_distance_2d"])))
    return out


def test_competition_distance_reproduces_px4_labels(shared_data):
    flights = _rilast_flights()
    assert len(flights) == 24
    errors = [abs(competition_distance(traj, obs) - label) for _, traj, obs, label in flights]
    assert max(errors) < 1e-3  # the labels carry 4 decimals
    for _, traj, obs, label in flights:
        buffered = competition_distance(traj, obs, buffer=0.125)
        assert buffered == pytest.approx(max(label - 0.125, 0.0), abs=1e-3)


def test_competition_distance_is_per_obstacle_minimum(shared_data):
    _, traj, obs, label = _rilast_flights()[0]
    per = competition_distances(traj, obs)
    assert per.shape == (len(obs),) and per.min() == pytest.approx(label, abs=1e-3)
    assert competition_distances(traj.xyz, obs).tolist() == per.tolist()  # arrays work as trajectories


def test_competition_distance_segment_not_only_points():
    box = Obstacle(2, 2, 20, 0, 0, 0, 0)  # x, y in [-1, 1]
    # both points 5 m away, but the segment between them passes 2 m from the box: the polyline counts
    assert competition_distance([[-5, 3, 10], [5, 3, 10]], [box]) == pytest.approx(2.0)
    assert obstacle_distances([[-5, 3, 10], [5, 3, 10]], [box]).min() > 4.0


def test_competition_distance_crossing_below_and_above_the_top():
    box = Obstacle(2, 2, 5, 0, 0, 0, 0)  # top at 5 m
    assert competition_distance([[-5, 0, 3], [5, 0, 3]], [box]) == 0.0
    assert competition_distance([[-5, 0, 8], [5, 0, 8]], [box]) == pytest.approx(3.0)
    # climbing across: z is interpolated along the segment; lowest inside the footprint at x = -1: z = 6
    assert competition_distance([[-3, 0, 5], [3, 0, 8]], [box]) == pytest.approx(1.0)
    raised = Obstacle(2, 2, 5, 0, 0, 2, 0)  # base at 2 m, top at 7 m
    assert competition_distance([[-5, 0, 8], [5, 0, 8]], [raised]) == pytest.approx(1.0)
    # the buffer lowers the height gap as well, floored at 0
    assert competition_distance([[-5, 0, 8], [5, 0, 8]], [box], buffer=0.125) == pytest.approx(2.875)
    assert competition_distance([[-5, 0, 3], [5, 0, 3]], [box], buffer=0.125) == 0.0


def test_competition_distance_rotation_and_shapes():
    wall = Obstacle(10, 0.2, 20, 0, 0, 0, 90)  # along y (east) after the rotation
    assert competition_distance([[4, -10, 10], [4, 10, 10]], [wall]) == pytest.approx(3.9)
    assert competition_distance([[0, 6, 10]], [wall]) == pytest.approx(1.0)  # one point: point distance
    cyl = Obstacle(2, 2, 20, 0, 0, 0, 0, Shape.CYLINDER)
    assert competition_distance([[3, -5, 10], [3, 5, 10]], [cyl]) == pytest.approx(2.0)
    assert competition_distance([[0, 0, 10]], []) == math.inf
    with pytest.raises(ValueError, match="no points"):
        competition_distance(np.zeros((0, 3)), [wall])
