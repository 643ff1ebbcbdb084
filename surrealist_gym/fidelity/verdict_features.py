"""What our simulator's runs of a test, and the test's layout, say about PX4's verdict: the features of
:mod:`~surrealist_gym.fidelity.verdict`.

Per test, from its runs (:class:`~surrealist_gym.outcomes.RunRecord`, as :func:`~surrealist_gym.executors.fly_many`
returns them): the competition distance over the runs (min, median, max, spread; capped at :data:`CAP_M`), the share
of runs under 1.5 m, in collision and timed out, the airborne time, the time spent crawling, the vehicle's speed and
the side of the box at the closest approach, the detour off the mission line; and from the test alone: the boxes,
their clearance to the mission line (the straight legs between waypoints), which side of it the nearest box stands,
the narrowest gap between two boxes and where along the mission the nearest box stands.

Example::

    >>> row = test_features(test, runs)          # doctest: +SKIP
    >>> row["d_min"], row["path_clearance"]      # doctest: +SKIP
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..geometry import obstacle_distances
from ..outcomes import UNSAFE_DISTANCE_M, RunRecord, RunStatus

CAP_M = 10.0          #: distances are capped here [m]: beyond it, a test is far from any failure
CRAWL_MPS = 0.5       #: a crawl: horizontal speed below this [m/s] ...
AIRBORNE_M = 1.0      #: ... while higher than this [m]
STEP_M = 0.25         #: the mission line is sampled every STEP_M [m]

#: The distances of our runs (the simulator alone, in features).
DISTANCE_FEATURES = ("d_min", "d_median", "d_max", "log_d_min", "log_d_median", "share_unsafe")
#: Everything our runs say (distances, outcomes, times, the closest approach, the detour): no layout feature.
RUN_FEATURES = DISTANCE_FEATURES + ("d_spread", "share_collision", "share_timeout", "no_distance", "airborne_s",
                                    "crawl_s", "speed_at_closest", "box_on_right_at_closest", "detour_m")
#: The features, in the training table's order.
FEATURES = ("d_min", "d_median", "d_max", "d_spread", "log_d_min", "log_d_median", "share_unsafe",
            "share_collision", "share_timeout", "no_distance", "airborne_s", "crawl_s", "speed_at_closest",
            "box_on_right_at_closest", "detour_m", "obstacles", "path_clearance", "log_path_clearance",
            "blocks_path", "nearest_on_right", "gap_m", "nearest_along", "footprint_area")


def test_features(test, runs: Sequence[RunRecord]) -> dict[str, float]:
    """The features (:data:`FEATURES`) of one test and its runs."""
    return {**run_features(test, runs), **layout_features(test)}


def run_features(test, runs: Sequence[RunRecord]) -> dict[str, float]:
    """What the runs say: distances, outcomes, airborne and crawl time, state at the closest approach, detour."""
    flown = [r for r in runs if r.flown]
    measured = [min(r.distance, CAP_M) for r in flown
                if r.status != RunStatus.TIMEOUT.value and math.isfinite(r.distance)]
    d = np.asarray(measured or [CAP_M])
    n = max(1, len(flown))
    closest = [_closest_state(test, r) for r in flown if len(r.trajectory) > 1]
    line = _mission_line(test)
    detours = [_detour(r.trajectory.xyz, line) for r in flown if len(r.trajectory) > 1 and len(line) > 1]
    return {
        "d_min": float(d.min()), "d_median": float(np.median(d)), "d_max": float(d.max()),
        "d_spread": float(d.max() - d.min()), "log_d_min": math.log(d.min() + 0.1),
        "log_d_median": math.log(float(np.median(d)) + 0.1),
        "share_unsafe": sum(r.failed for r in flown) / n,
        "share_collision": sum(r.status == RunStatus.COLLISION.value for r in flown) / n,
        "share_timeout": sum(r.status == RunStatus.TIMEOUT.value for r in flown) / n,
        "no_distance": float(not measured),
        "airborne_s": float(np.median([r.airborne for r in flown])) if flown else 0.0,
        "crawl_s": float(np.median([_crawl_s(r.trajectory) for r in flown])) if flown else 0.0,
        "speed_at_closest": float(np.median([c[0] for c in closest])) if closest else 0.0,
        "box_on_right_at_closest": float(np.mean([c[1] for c in closest])) if closest else 0.0,
        "detour_m": float(np.median(detours)) if detours else 0.0}


def layout_features(test) -> dict[str, float]:
    """What the layout says: boxes, their clearance to the mission line and side of it, gaps, footprint."""
    boxes = list(test.obstacles)
    line = _mission_line(test)
    features = {"obstacles": float(len(boxes)), "path_clearance": CAP_M, "log_path_clearance": math.log(CAP_M + 0.1),
                "blocks_path": 0.0, "nearest_on_right": 0.0, "gap_m": CAP_M, "nearest_along": 0.0,
                "footprint_area": float(sum(b.l * b.w for b in boxes))}
    if not boxes or len(line) < 2:
        return features
    points = _densify(line)
    dist = obstacle_distances(points, boxes)                     # (points, boxes)
    k, j = np.unravel_index(int(np.argmin(dist)), dist.shape)   # the line's point nearest any box, and that box
    clearance = min(float(dist[k, j]), CAP_M)
    ahead = points[min(k + 1, len(points) - 1)] - points[max(k - 1, 0)]
    side = _right_of(ahead, np.array([boxes[j].x, boxes[j].y]) - points[k])
    features.update(path_clearance=clearance, log_path_clearance=math.log(clearance + 0.1),
                    blocks_path=float(clearance == 0.0), nearest_on_right=side,
                    nearest_along=float(k / max(1, len(points) - 1)), gap_m=_narrowest_gap(boxes))
    return features


def _mission_line(test) -> np.ndarray:
    """The mission's horizontal polyline (x, y) through its waypoints, repeated points dropped."""
    if test.mission is None:
        return np.zeros((0, 2))
    xy = np.array([(x, y) for x, y, _ in test.mission.waypoints], dtype=np.float64).reshape(-1, 2)
    if len(xy) > 1:
        keep = np.r_[True, np.hypot(*np.diff(xy, axis=0).T) > 1e-6]
        xy = xy[keep]
    return xy


def _densify(line: np.ndarray) -> np.ndarray:
    parts = []
    for a, b in zip(line[:-1], line[1:]):
        n = max(2, int(math.ceil(np.hypot(*(b - a)) / STEP_M)) + 1)
        parts.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    return np.vstack(parts)


def _right_of(ahead: np.ndarray, to_box: np.ndarray) -> float:
    """+1 when the box stands right of the direction ``ahead`` (x north, y east: right is clockwise), -1 left."""
    cross = ahead[0] * to_box[1] - ahead[1] * to_box[0]
    return 1.0 if cross > 0 else -1.0 if cross < 0 else 0.0


def _narrowest_gap(boxes) -> float:
    """The smallest footprint distance between two boxes [m] (capped at CAP_M; CAP_M with one box)."""
    from shapely.geometry import Polygon

    shapes = [Polygon(b.footprint()) for b in boxes]
    gaps = [shapes[a].distance(shapes[b]) for a in range(len(shapes)) for b in range(a + 1, len(shapes))]
    return min([CAP_M, *gaps])


def _speeds(xyz: np.ndarray, dt: float = 0.5) -> np.ndarray:
    v = np.hypot(*np.diff(xyz[:, :2], axis=0).T) / dt
    return np.r_[v, v[-1:]] if len(v) else np.zeros(len(xyz))


def _crawl_s(trajectory, dt: float = 0.5) -> float:
    """Time airborne (above AIRBORNE_M) at a horizontal speed below CRAWL_MPS [s], on the 0.5 s trajectory."""
    xyz = trajectory.xyz
    if len(xyz) < 2:
        return 0.0
    return float(np.sum((_speeds(xyz, dt) < CRAWL_MPS) & (xyz[:, 2] > AIRBORNE_M)) * dt)


def _closest_state(test, run: RunRecord) -> tuple[float, float]:
    """At the trajectory's point nearest a box: horizontal speed [m/s] and whether the box is on the right (+1/-1)."""
    xyz = run.trajectory.xyz
    if not test.obstacles:
        return 0.0, 0.0
    dist = obstacle_distances(xyz[:, :2], test.obstacles)
    k, j = np.unravel_index(int(np.argmin(dist)), dist.shape)
    speeds = _speeds(xyz)
    ahead = xyz[min(k + 1, len(xyz) - 1), :2] - xyz[max(k - 1, 0), :2]
    box = test.obstacles[j]
    return float(speeds[k]), _right_of(ahead, np.array([box.x, box.y]) - xyz[k, :2])


def _detour(xyz: np.ndarray, line: np.ndarray) -> float:
    """The largest horizontal distance of the flight from the mission line [m] (capped at CAP_M)."""
    pts = xyz[:, :2]
    best = np.full(len(pts), np.inf)
    for a, b in zip(line[:-1], line[1:]):
        ab = b - a
        s = np.clip(((pts - a) @ ab) / max(float(ab @ ab), 1e-9), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(pts - (a + s[:, None] * ab)).T))
    return float(min(best.max(), CAP_M)) if len(best) else 0.0


__all__ = ["CAP_M", "DISTANCE_FEATURES", "FEATURES", "RUN_FEATURES", "UNSAFE_DISTANCE_M", "layout_features",
           "run_features", "test_features"]
