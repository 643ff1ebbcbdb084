"""PX4-Avoidance's look-ahead tree search as written (``StarPlanner::buildLookAheadTree``,
:func:`build_tree_reference`): the readable reference that the planner's
:func:`~surrealist_gym.sim.avoidance.px4.tree.build_tree` is tested against (the same paths, bit for bit).

Each expansion is one :func:`_best_cells` on dense 30 x 60 matrices: the polar histogram (:func:`_histogram`), its
obstacle cost matrix smoothed by the conic kernel (``smoothPolarMatrix``: :func:`smooth_columns`, then
:func:`smooth_row` for each row the search visits), and the cost matrix's cheapest cells (``getCostMatrix``). The
search's work buffers are one :class:`_Work`, shared by its expansions. The behaviour and its sources are described
in :mod:`surrealist_gym.sim.avoidance.px4.local_planner`.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..avoidance.px4.cloud import hist_index
from ..avoidance.px4.settings import ALPHA_RES, MAX_NODES, N_E, N_Z, R2D


class _Work(NamedTuple):
    """The work buffers of one tree search, shared by its expansions: histogram (``dist``, ``count``), obstacle
    costs, the smoothing's padded matrix and running sums, and the cheapest cells (elevation, azimuth, cost)."""

    dist: np.ndarray
    count: np.ndarray
    obst: np.ndarray
    padded: np.ndarray
    box: np.ndarray
    cand_e: np.ndarray
    cand_z: np.ndarray
    cand_c: np.ndarray


@njit(cache=True)
def _histogram(cloud, ox, oy, oz, dist, count):  # pragma: no cover - compiled
    """Fill ``dist`` (N_E x N_Z) with the mean distance of the cloud's points per cell seen from (ox, oy, oz);
    ``count`` is a work buffer of the same shape."""
    count[:, :] = 0.0
    dist[:, :] = 0.0
    for i in range(cloud.shape[0]):
        dx, dy, dz = cloud[i, 0] - ox, cloud[i, 1] - oy, cloud[i, 2] - oz
        ie, iz = hist_index(dx, dy, dz, ALPHA_RES)
        dist[ie, iz] += math.sqrt(dx * dx + dy * dy + dz * dz)
        count[ie, iz] += 1.0
    n = 0
    for e in range(N_E):
        for z in range(N_Z):
            if count[e, z] > 0:
                dist[e, z] /= count[e, z]
                n += 1
    return n


@njit(cache=True)
def smooth_columns(matrix, radius, padded, box):  # pragma: no cover - compiled
    """smoothPolarMatrix, first half: pad with the polar wrap rules, then the conic kernel (1, r/(r+1), ...,
    1/(r+1)), summed, along elevation, as two running box sums of length r + 1. ``padded`` (ne + 2r, nz + 2r)
    holds the result; ``box`` (>= max(ne, nz) + r) is a work buffer. :func:`smooth_row` finishes a row."""
    r = radius
    ne, nz = matrix.shape
    half = nz // 2
    length = r + 1
    padded[:, :] = 0.0
    padded[r:r + ne, r:r + nz] = matrix
    for i in range(r):  # rows beyond the poles: the opposite azimuth, mirrored in elevation
        for z in range(nz):
            zs = (z + half) % nz
            padded[r - 1 - i, r + z] = matrix[i, zs]
            padded[r + ne + i, r + z] = matrix[ne - 1 - i, zs]
    for row in range(ne + 2 * r):  # azimuth wrap
        for i in range(r):
            padded[row, i] = padded[row, nz + i]
            padded[row, r + nz + i] = padded[row, r + i]
    m = ne + r
    for z in range(nz + 2 * r):  # all-zero columns stay zero
        nonzero = False
        for row in range(ne + 2 * r):
            if padded[row, z] != 0.0:
                nonzero = True
                break
        if not nonzero:
            continue
        s = 0.0
        for j in range(length):
            s += padded[j, z]
        box[0] = s
        for j in range(1, m):
            s += padded[j + length - 1, z] - padded[j - 1, z]
            box[j] = s
        s = 0.0
        for j in range(length):
            s += box[j]
        padded[r, z] = s / length
        for i in range(1, ne):  # writes row r + i, reads box only: safe in place
            s += box[i + length - 1] - box[i - 1]
            padded[r + i, z] = s / length


@njit(cache=True)
def smooth_row(padded, radius, e, box, out):  # pragma: no cover - compiled
    """smoothPolarMatrix, second half for elevation row ``e``: the conic kernel along azimuth into ``out``."""
    r = radius
    nz = out.shape[0]
    length = r + 1
    row = r + e
    m = nz + r
    s = 0.0
    for j in range(length):
        s += padded[row, j]
    box[0] = s
    for j in range(1, m):
        s += padded[row, j + length - 1] - padded[row, j - 1]
        box[j] = s
    s = 0.0
    for j in range(length):
        s += box[j]
    out[0] = s / length
    for i in range(1, nz):
        s += box[i + length - 1] - box[i - 1]
        out[i] = s / length


@njit(cache=True)
def _best_cells(cloud, origin, velocity, goal, line, settings, work):  # pragma: no cover - compiled
    """Histogram and cost matrix at ``origin`` (x, y, z) with ``velocity``, toward ``goal`` with the mission line's
    point ``line``; fill ``work``'s cheapest cells (``cand_*``, ascending cost); return their count."""
    ox, oy, oz = origin
    vx, vy, vz = velocity
    gx, gy, gz = goal
    cx, cy, cz = line
    dist, count, obst, padded, box = work.dist, work.count, work.obst, work.padded, work.box
    cand_e, cand_z, cand_c = work.cand_e, work.cand_z, work.cand_c
    rmin, rmax = settings.min_range, settings.max_range
    w_pitch, w_yaw, w_vel, obst_param = settings.pitch_cost, settings.yaw_cost, settings.velocity_cost, \
        settings.obstacle_cost
    radius = settings.smoothing_radius
    n_best = settings.children
    _histogram(cloud, ox, oy, oz, dist, count)
    obst[:, :] = 0.0
    any_obstacle = False
    for e in range(N_E):
        for z in range(N_Z):
            d = dist[e, z]
            if d > 0.0:
                x = obst_param - d
                obst[e, z] = 5000.0 * (1.0 + x / math.sqrt(1.0 + x * x))
                any_obstacle = True
    smooth = any_obstacle and radius > 0
    if smooth:
        smooth_columns(obst, radius, padded, box)
    # goal and line directions from the origin
    dgx, dgy, dgz = gx - ox, gy - oy, gz - oz
    dist_goal = math.sqrt(dgx * dgx + dgy * dgy + dgz * dgz)
    az_goal = math.atan2(dgy, dgx) * R2D
    el_goal = math.atan2(dgz, math.sqrt(dgx * dgx + dgy * dgy)) * R2D
    az_line = math.atan2(cy - oy, cx - ox) * R2D
    # obstacle in the goal's window (goal cell +-5 azimuth, +-2 elevation cells, distance in (0.2, 15) m)?
    ge, gz_i = hist_index(dgx, dgy, dgz, ALPHA_RES)
    blocked = False
    for de in range(-2, 3):
        e = ge + de
        if e < 0 or e >= N_E:
            continue
        for dz_ in range(-5, 6):
            z = (gz_i + dz_) % N_Z
            if rmin < dist[e, z] < rmax:
                blocked = True
    w_line = 0.0 if blocked else 0.5
    pitch_scale = 1.0
    if dist_goal < 5.0:
        pitch_scale = 1.0 / max((0.2 * dist_goal) ** 2, 1e-6)
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    yaw_cost = np.empty(N_Z)
    cos_a = np.empty(N_Z)
    sin_a = np.empty(N_Z)
    for z in range(N_Z):
        az = z * ALPHA_RES + 0.5 * ALPHA_RES - 180.0
        a = (az - az_goal + 180.0) % 360.0 - 180.0
        b = (az - az_line + 180.0) % 360.0 - 180.0
        yaw_cost[z] = w_yaw * ((1.0 - w_line) * a * a + w_line * b * b)
        cos_a[z] = math.cos(az / R2D)
        sin_a[z] = math.sin(az / R2D)
    min_yaw = yaw_cost.min()
    row_cost = np.empty(N_E)
    for e in range(N_E):
        de = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0 - el_goal
        row_cost[e] = w_pitch * de * de * pitch_scale
    obst_row = np.zeros(N_Z)
    n = 0
    # rows by increasing pitch cost; a row whose every cost is at least its pitch cost plus the least yaw cost
    # (obstacle and velocity costs are >= 0) cannot beat a full candidate list, and is skipped
    for e in np.argsort(row_cost, kind="mergesort"):
        pitch_cost = row_cost[e]
        if n == n_best and pitch_cost + min_yaw >= cand_c[n - 1]:
            break
        el = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0
        ce, se = math.cos(el / R2D), math.sin(el / R2D)
        if smooth:
            smooth_row(padded, radius, e, box, obst_row)
        else:
            for z in range(N_Z):
                obst_row[z] = obst[e, z]
        for z in range(N_Z):
            dot = ce * (cos_a[z] * vx + sin_a[z] * vy) + se * vz
            cost = obst_row[z] + yaw_cost[z] + pitch_cost + w_vel * (speed - dot)
            # keep the n_best cheapest, sorted ascending
            if n < n_best:
                j = n
                n += 1
            elif cost < cand_c[n - 1]:
                j = n - 1
            else:
                continue
            while j > 0 and cand_c[j - 1] > cost:
                cand_c[j], cand_e[j], cand_z[j] = cand_c[j - 1], cand_e[j - 1], cand_z[j - 1]
                j -= 1
            cand_c[j], cand_e[j], cand_z[j] = cost, e, z
    return n


@njit(cache=True)
def build_tree_reference(cloud, vehicle, velocity, goal, line, settings, path):  # pragma: no cover - compiled
    """StarPlanner::buildLookAheadTree as PX4-Avoidance computes it, the readable reference of :func:`build_tree`
    (same arguments but ``work``, same result): from ``vehicle`` (x, y, z) with ``velocity`` toward ``goal``,
    ``line`` the mission line's point (each a 3-tuple); writes the path deepest node first into ``path``, returns
    its length (0 when the vehicle's histogram is empty). Each expansion is one :func:`_best_cells` on dense
    30 x 60 matrices."""
    px, py, pz = vehicle
    gx, gy, gz = goal
    rmax, w_h, n_best = settings.max_range, settings.heuristic_weight, settings.children
    n_exp, step = settings.expansions, settings.node_distance
    pos = np.empty((MAX_NODES, 3))
    parent = np.empty(MAX_NODES, dtype=np.int64)
    depth = np.empty(MAX_NODES, dtype=np.int64)
    total = np.empty(MAX_NODES)
    heur = np.empty(MAX_NODES)
    closed = np.zeros(MAX_NODES, dtype=np.bool_)
    radius = settings.smoothing_radius
    work = _Work(np.empty((N_E, N_Z)), np.empty((N_E, N_Z)), np.empty((N_E, N_Z)),
                 np.empty((N_E + 2 * radius, N_Z + 2 * radius)), np.empty(N_Z + 2 * radius),
                 np.empty(n_best, dtype=np.int64), np.empty(n_best, dtype=np.int64), np.empty(n_best))
    dist, cand_e, cand_z, cand_c = work.dist, work.cand_e, work.cand_z, work.cand_c
    pos[0, 0], pos[0, 1], pos[0, 2] = px, py, pz
    parent[0], depth[0] = -1, 0
    h0 = w_h * math.sqrt((gx - px) ** 2 + (gy - py) ** 2 + (gz - pz) ** 2)
    total[0], heur[0] = h0, h0
    size = 1
    origin = 0
    for it in range(n_exp):
        ox, oy, oz = pos[origin, 0], pos[origin, 1], pos[origin, 2]
        if origin == 0:
            u = velocity
        else:
            p = parent[origin]
            u = (ox - pos[p, 0], oy - pos[p, 1], oz - pos[p, 2])
        k = _best_cells(cloud, (ox, oy, oz), u, goal, line, settings, work)
        if it == 0:
            empty = True
            for e in range(N_E):
                for z in range(N_Z):
                    if dist[e, z] > 0.0:
                        empty = False
            if empty:
                return 0
        for j in range(k):
            if size >= MAX_NODES:
                break
            el = (cand_e[j] * ALPHA_RES + 0.5 * ALPHA_RES - 90.0) / R2D
            az = (cand_z[j] * ALPHA_RES + 0.5 * ALPHA_RES - 180.0) / R2D
            nx = ox + step * math.cos(el) * math.cos(az)
            ny = oy + step * math.cos(el) * math.sin(az)
            nz = oz + step * math.sin(el)
            close = False
            for i in range(size):
                if (pos[i, 0] - nx) ** 2 + (pos[i, 1] - ny) ** 2 + (pos[i, 2] - nz) ** 2 < 0.04:
                    close = True
                    break
            if close:
                continue
            pos[size, 0], pos[size, 1], pos[size, 2] = nx, ny, nz
            parent[size], depth[size] = origin, depth[origin] + 1
            h = w_h * math.sqrt((gx - nx) ** 2 + (gy - ny) ** 2 + (gz - nz) ** 2)
            heur[size] = h
            total[size] = total[origin] - heur[origin] + cand_c[j] + h
            size += 1
        closed[origin] = True
        best = -1
        best_cost = np.inf
        for i in range(size):
            if closed[i]:
                continue
            d2 = (pos[i, 0] - px) ** 2 + (pos[i, 1] - py) ** 2 + (pos[i, 2] - pz) ** 2
            if total[i] < best_cost and d2 < rmax * rmax:
                best_cost = total[i]
                best = i
        if best < 0:
            break
        origin = best
    # the path ends at the first open node of the greatest depth (PR #555), the root when none is open
    end, deepest = 0, 0
    for i in range(size):
        if not closed[i] and depth[i] > deepest:
            end, deepest = i, depth[i]
    n = 0
    while end >= 0:
        path[n, 0], path[n, 1], path[n, 2] = pos[end, 0], pos[end, 1], pos[end, 2]
        n += 1
        end = parent[end]
    return n
