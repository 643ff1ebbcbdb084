"""The point cloud kernels of PX4-Avoidance's local planner (:mod:`surrealist_gym.sim.avoidance.px4.local_planner`): the
polar cell of a direction (:func:`hist_index`, with the polynomial atan2 :func:`atan2_deg`), which bins points into the
cloud's subsampling cells and the histograms' cells, and the point cloud memory (``processPointcloud``,
:func:`process_cloud`), which the planner calls once per cycle.

The behaviour and its sources are described in :mod:`surrealist_gym.sim.avoidance.px4.local_planner`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .settings import N_E2, N_Z2, SUB_RES


@njit(cache=True)
def atan2_deg(y, x):  # pragma: no cover - compiled
    """atan2 in degrees by a minimax polynomial (error < 1e-4 deg): 3x faster than math.atan2 here."""
    ax, ay = abs(x), abs(y)
    if ax == 0.0 and ay == 0.0:
        return 0.0
    swap = ay > ax
    a = ax / ay if swap else ay / ax
    s = a * a
    r = ((((((-0.0040540580 * s + 0.0218612288) * s - 0.0559098861) * s + 0.0964200441) * s - 0.1390853351) * s
          + 0.1994653599) * s - 0.3332985605) * s * a + a
    if swap:
        r = 1.5707963267948966 - r
    if x < 0.0:
        r = 3.141592653589793 - r
    if y < 0.0:
        r = -r
    return r * 57.29577951308232


@njit(cache=True)
def hist_index(dx, dy, dz, res):  # pragma: no cover - compiled
    """(elevation index, azimuth index) of a direction in a histogram of ``res`` degree cells."""
    h = math.sqrt(dx * dx + dy * dy)
    az = atan2_deg(dy, dx)
    el = atan2_deg(dz, h)
    n_z = int(round(360.0 / res))
    n_e = int(round(180.0 / res))
    iz = int(math.floor(az / res + 180.0 / res))
    ie = int(math.floor(el / res + 90.0 / res))
    if iz >= n_z:
        iz -= n_z
    if iz < 0:
        iz += n_z
    if ie >= n_e:
        ie = n_e - 1
    if ie < 0:
        ie = 0
    return ie, iz


@njit(cache=True)
def process_cloud(new, old, old_age, vehicle, view, elapsed, settings, out, out_age):  # pragma: no cover - compiled
    """processPointcloud: the new points ``new`` (subsampled per 2 deg cell) and the remembered ``old`` (ages
    ``old_age`` [s]) that are kept, seen from ``vehicle`` (x, y, z) with the camera's ``view`` (yaw, pitch) [deg],
    ``elapsed`` [s] after the last cycle; writes them into ``out`` / ``out_age`` and returns their count."""
    px, py, pz = vehicle
    yaw_deg, pitch_deg = view
    rmin, rmax, max_age = settings.min_range, settings.max_range, settings.max_point_age
    hfov, vfov = settings.fov_h, settings.fov_v
    occupied = np.zeros((N_E2, N_Z2), dtype=np.bool_)
    k = 0
    for i in range(new.shape[0]):
        dx, dy, dz = new[i, 0] - px, new[i, 1] - py, new[i, 2] - pz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d <= rmin or d >= rmax:
            continue
        ie, iz = hist_index(dx, dy, dz, SUB_RES)
        if occupied[ie, iz]:
            continue
        occupied[ie, iz] = True
        out[k, 0], out[k, 1], out[k, 2] = new[i, 0], new[i, 1], new[i, 2]
        out_age[k] = 0.0
        k += 1
    half_h, half_v = 0.5 * hfov, 0.5 * vfov
    for i in range(old.shape[0]):
        if old_age[i] >= max_age:
            continue
        dx, dy, dz = old[i, 0] - px, old[i, 1] - py, old[i, 2] - pz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d >= rmax:
            continue
        ie, iz = hist_index(dx, dy, dz, SUB_RES)
        if occupied[ie, iz]:
            continue
        # pointInsideFOV in the body frame: the camera would see the point if it were still there
        off_az = (atan2_deg(dy, dx) - yaw_deg + 180.0) % 360.0 - 180.0
        off_el = atan2_deg(dz, math.sqrt(dx * dx + dy * dy)) - pitch_deg
        if abs(off_az) <= half_h and abs(off_el) <= half_v:
            continue
        occupied[ie, iz] = True
        out[k, 0], out[k, 1], out[k, 2] = old[i, 0], old[i, 1], old[i, 2]
        out_age[k] = old_age[i] + elapsed
        k += 1
    return k
