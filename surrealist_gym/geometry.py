"""Distances between points and obstacles, vectorised over points (numpy), and the competition's distance.

The paper measures distance in the horizontal plane to the obstacle's footprint (its reference code uses 2-D
shapely geometry); ``dims=3`` also accounts for the obstacle's base and top. :func:`competition_distance` is
Aerialist's and the UAV Testing Competition's measure of a whole flight: footprint to the 0.5 s polyline (shapely).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .errors import SurrealistError
from .testcase import Obstacle, Shape


def obstacle_distances(points, obstacles: Sequence[Obstacle], dims: int = 2) -> np.ndarray:
    """(N, M) distances from N points (x, y[, z]) to M obstacles; 0 inside (or, 2-D, above/below) an obstacle."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim == 1:
        pts = pts[None, :]
    if dims not in (2, 3):
        raise ValueError(f"dims must be 2 or 3, got {dims}")
    if dims == 3 and pts.shape[1] < 3:
        raise ValueError("3-D distances need (N, 3) points")
    out = np.empty((pts.shape[0], len(obstacles)))
    for j, obs in enumerate(obstacles):
        dx, dy = pts[:, 0] - obs.x, pts[:, 1] - obs.y
        if obs.shape == Shape.CYLINDER:
            ex = np.maximum(np.hypot(dx, dy) - obs.l / 2, 0.0)
            ey = np.zeros_like(ex)
        else:
            c, s = math.cos(math.radians(obs.r)), math.sin(math.radians(obs.r))
            ex = np.maximum(np.abs(c * dx + s * dy) - obs.l / 2, 0.0)
            ey = np.maximum(np.abs(-s * dx + c * dy) - obs.w / 2, 0.0)
        if dims == 2:
            out[:, j] = np.hypot(ex, ey)
        else:
            ez = np.maximum(np.maximum(obs.z - pts[:, 2], pts[:, 2] - (obs.z + obs.h)), 0.0)
            out[:, j] = np.sqrt(ex * ex + ey * ey + ez * ez)
    return out


def line_projection(px: float, py: float, a, b) -> tuple[float, float, float] | None:
    """Projection of the point (px, py) on the line through ``a`` and ``b`` in the x-y plane: (fraction along
    a -> b, foot x, foot y), or None when a and b (nearly) coincide. Plain floats, for the simulator's loops."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    if length2 < 1e-6:
        return None
    s = ((px - a[0]) * dx + (py - a[1]) * dy) / length2
    return s, a[0] + s * dx, a[1] + s * dy


def competition_distances(trajectory, obstacles: Sequence[Obstacle], buffer: float = 0.0) -> np.ndarray:
    """Per-obstacle 2-D competition distance [m] of a trajectory: Aerialist's (and the UAV Testing Competition's).

    The distance between the obstacle's footprint (a box's full l x w rectangle, :meth:`Obstacle.footprint`; a
    cylinder's disc of diameter l) and the polyline through the trajectory's points (the paper's 0.5 s windows),
    in the x-y plane. Where the polyline crosses the footprint and its lowest point inside it (z interpolated
    linearly along each segment) lies above the obstacle's top, the distance is that height gap instead.
    ``buffer`` widens the polyline (Aerialist since Oct 2024: 0.125 m), so the figure drops by it, floored at 0.

    Args:
        trajectory: a :class:`~surrealist_gym.trajectory.Trajectory` or an (N, 3) array x, y, z [m] (z up).
        obstacles: the test's obstacles, in the trajectory's frame.
        buffer: half width added to the polyline [m].

    Returns:
        (M,) distances [m], one per obstacle.

    Example::

        >>> box = Obstacle(4, 2, 20, 0, 5, 0, 0)                      # y in [4, 6]
        >>> competition_distances([[0, 0, 10], [0, 3, 10]], [box]).tolist()
        [1.0]
    """
    import shapely

    from .trajectory import as_points

    pts = as_points(trajectory)
    if len(pts) == 0:
        raise ValueError("competition distance: the trajectory has no points")
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    line = shapely.LineString(pts[:, :2]) if len(pts) > 1 else shapely.Point(pts[0, :2])
    out = np.empty(len(obstacles))
    for j, obs in enumerate(obstacles):
        if obs.shape == Shape.CYLINDER:
            centre = shapely.Point(obs.x, obs.y)
            dist = max(centre.distance(line) - obs.l / 2, 0.0)
            area = centre.buffer(obs.l / 2, quad_segs=32)
        else:
            area = shapely.Polygon(obs.footprint())
            dist = area.distance(line)
        if dist == 0.0:
            lowest = _lowest_z_inside(pts, area)
            top = obs.z + obs.h
            if lowest > top:
                dist = lowest - top
        out[j] = max(dist - buffer, 0.0)
    return out


def competition_distance(trajectory, obstacles: Sequence[Obstacle], buffer: float = 0.0) -> float:
    """The 2-D competition distance [m]: the minimum of :func:`competition_distances` (inf without obstacles).

    Example::

        >>> competition_distance([[0, 0, 10], [0, 3, 10]], [Obstacle(4, 2, 20, 0, 5, 0, 0)], buffer=0.125)
        0.875
    """
    if not obstacles:
        return math.inf
    return float(competition_distances(trajectory, obstacles, buffer).min())


def _lowest_z_inside(pts: np.ndarray, area) -> float:
    """Lowest z [m] of the polyline ``pts`` (N, 3) where it lies inside the polygon ``area`` (inf if nowhere)."""
    import shapely

    if len(pts) == 1:
        return float(pts[0, 2]) if area.intersects(shapely.Point(pts[0, :2])) else math.inf
    a, b = pts[:-1], pts[1:]
    segments = shapely.linestrings(np.stack([a[:, :2], b[:, :2]], axis=1))
    hit = np.flatnonzero(shapely.intersects(segments, area))
    if hit.size == 0:
        return math.inf
    clipped = shapely.intersection(segments[hit], area)
    xy, which = shapely.get_coordinates(clipped, return_index=True)
    seg = hit[which]
    d = b[seg, :2] - a[seg, :2]
    length2 = np.einsum("ij,ij->i", d, d)
    frac = np.where(length2 > 0, np.einsum("ij,ij->i", xy - a[seg, :2], d) / np.where(length2 > 0, length2, 1), 0)
    z = a[seg, 2] + np.clip(frac, 0.0, 1.0) * (b[seg, 2] - a[seg, 2])
    return float(z.min())


def check_buffer(value, where: str = "--buffer") -> float:
    """``value`` if it is a polyline buffer [m] for :func:`competition_distance` (a finite number >= 0), else a
    one-line SurrealistError naming ``where``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < float("inf"):
        raise SurrealistError(f"{where}: expected a non-negative number of metres, got {value!r}")
    return float(value)
