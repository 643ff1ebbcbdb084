"""Distances between points and obstacles, vectorised over points (numpy).

The paper measures distance in the horizontal plane to the obstacle's footprint (its reference code uses 2-D
shapely geometry); ``dims=3`` also accounts for the obstacle's base and top.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

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
