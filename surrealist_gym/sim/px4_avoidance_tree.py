"""The compiled kernels of PX4-Avoidance's local planner (:mod:`surrealist_gym.sim.px4_avoidance`): the point cloud
memory, the polar histogram, its smoothing and cost matrix, and the look-ahead tree search (``_build_tree``).

The behaviour and its sources are described in :mod:`surrealist_gym.sim.px4_avoidance`, which re-exports these
names; the planner class there calls them once per cycle.

The kernels take the planner's constant settings as one :class:`KernelSettings` (a named tuple, which numba passes
as a tuple of its fields), the per-cycle state (vehicle position, velocity, goal, the mission line's point) as
3-tuples, and the cost search's work buffers as one :class:`_Work` (the dense reference) or :class:`TreeWork`.

Two versions of the tree search: :func:`_build_tree_reference` is PX4-Avoidance's as written, each expansion a
dense 30 x 60 histogram, cost matrix and smoothing (:func:`_best_cells`); :func:`_build_tree`, which the planner
calls, gives the same paths bit for bit (the same operations in the same order, no fastmath) on sparse buffers:
each expansion (:func:`_expand`) touches only the cells its points fall in and smooths only where a sum can change.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

ALPHA_RES = 6.0  # histogram cell [deg] (avoidance/include/avoidance/histogram.h)
N_E, N_Z = 30, 60
SUB_RES = 2.0  # subsampling cell of the point cloud [deg] (ALPHA_RES / 3)
N_E2, N_Z2 = 90, 180
MAX_NODES = 512


class KernelSettings(NamedTuple):
    """The planner's constant settings as the kernels read them (built once per planner from its config by
    :func:`surrealist_gym.sim.px4_avoidance.kernel_settings`). Every float field holds a float and every int field an
    int, so numba compiles one specialisation.

    Attributes:
        min_range / max_range: the sensor's range; also the memory radius and the tree's reach [m].
        pitch_cost / yaw_cost: cost per squared degree of elevation / azimuth error.
        velocity_cost: cost per m/s of ``|v| - u . v``.
        obstacle_cost: distance at which a cell's obstacle cost is half its maximum [m].
        heuristic_weight: the tree's heuristic cost per metre to the goal.
        smoothing_radius: radius of the conic smoothing kernel [histogram cells].
        children / expansions: children per node and expanded nodes of the tree.
        node_distance: distance from a node to its children [m].
        max_point_age: age at which a remembered point is forgotten [s].
        fov_h / fov_v: the camera's field of view [deg].
    """

    min_range: float
    max_range: float
    pitch_cost: float
    yaw_cost: float
    velocity_cost: float
    obstacle_cost: float
    heuristic_weight: float
    smoothing_radius: int
    children: int
    expansions: int
    node_distance: float
    max_point_age: float
    fov_h: float
    fov_v: float


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


# --- compiled kernels --------------------------------------------------------------------------------------------
_R2D = 180.0 / math.pi


@njit(cache=True, inline="always")
def _atan2_deg(y, x):  # pragma: no cover - compiled
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


@njit(cache=True, inline="always")
def _hist_index(dx, dy, dz, res):  # pragma: no cover - compiled
    """(elevation index, azimuth index) of a direction in a histogram of ``res`` degree cells."""
    h = math.sqrt(dx * dx + dy * dy)
    az = _atan2_deg(dy, dx)
    el = _atan2_deg(dz, h)
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
def _process_cloud(new, old, old_age, vehicle, view, elapsed, settings, out, out_age):  # pragma: no cover - compiled
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
        ie, iz = _hist_index(dx, dy, dz, SUB_RES)
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
        ie, iz = _hist_index(dx, dy, dz, SUB_RES)
        if occupied[ie, iz]:
            continue
        # pointInsideFOV in the body frame: the camera would see the point if it were still there
        off_az = (_atan2_deg(dy, dx) - yaw_deg + 180.0) % 360.0 - 180.0
        off_el = _atan2_deg(dz, math.sqrt(dx * dx + dy * dy)) - pitch_deg
        if abs(off_az) <= half_h and abs(off_el) <= half_v:
            continue
        occupied[ie, iz] = True
        out[k, 0], out[k, 1], out[k, 2] = old[i, 0], old[i, 1], old[i, 2]
        out_age[k] = old_age[i] + elapsed
        k += 1
    return k


@njit(cache=True)
def _histogram(cloud, ox, oy, oz, dist, count):  # pragma: no cover - compiled
    """Fill ``dist`` (N_E x N_Z) with the mean distance of the cloud's points per cell seen from (ox, oy, oz);
    ``count`` is a work buffer of the same shape."""
    count[:, :] = 0.0
    dist[:, :] = 0.0
    for i in range(cloud.shape[0]):
        dx, dy, dz = cloud[i, 0] - ox, cloud[i, 1] - oy, cloud[i, 2] - oz
        ie, iz = _hist_index(dx, dy, dz, ALPHA_RES)
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
def _smooth_columns(matrix, radius, padded, box):  # pragma: no cover - compiled
    """smoothPolarMatrix, first half: pad with the polar wrap rules, then the conic kernel (1, r/(r+1), ...,
    1/(r+1)), summed, along elevation, as two running box sums of length r + 1. ``padded`` (ne + 2r, nz + 2r)
    holds the result; ``box`` (>= max(ne, nz) + r) is a work buffer. :func:`_smooth_row` finishes a row."""
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
def _smooth_row(padded, radius, e, box, out):  # pragma: no cover - compiled
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
        _smooth_columns(obst, radius, padded, box)
    # goal and line directions from the origin
    dgx, dgy, dgz = gx - ox, gy - oy, gz - oz
    dist_goal = math.sqrt(dgx * dgx + dgy * dgy + dgz * dgz)
    az_goal = math.atan2(dgy, dgx) * _R2D
    el_goal = math.atan2(dgz, math.sqrt(dgx * dgx + dgy * dgy)) * _R2D
    az_line = math.atan2(cy - oy, cx - ox) * _R2D
    # obstacle in the goal's window (goal cell +-5 azimuth, +-2 elevation cells, distance in (0.2, 15) m)?
    ge, gz_i = _hist_index(dgx, dgy, dgz, ALPHA_RES)
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
        cos_a[z] = math.cos(az / _R2D)
        sin_a[z] = math.sin(az / _R2D)
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
        ce, se = math.cos(el / _R2D), math.sin(el / _R2D)
        if smooth:
            _smooth_row(padded, radius, e, box, obst_row)
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
def _build_tree_reference(cloud, vehicle, velocity, goal, line, settings, path):  # pragma: no cover - compiled
    """StarPlanner::buildLookAheadTree as PX4-Avoidance computes it, the readable reference of :func:`_build_tree`
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
            el = (cand_e[j] * ALPHA_RES + 0.5 * ALPHA_RES - 90.0) / _R2D
            az = (cand_z[j] * ALPHA_RES + 0.5 * ALPHA_RES - 180.0) / _R2D
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


# --- the tree search on sparse buffers ---------------------------------------------------------------------------
class TreeWork(NamedTuple):
    """The buffers of :func:`_build_tree`, allocated once per planner (:func:`tree_work`) and reused by every build.
    Between expansions the histogram (``dist``, ``count``), the padded obstacle matrix (``col``) and ``line`` are
    all zero: each expansion clears what it wrote, so it touches only the cells its points fall in.

    Attributes:
        pos, parent, depth, total, heur, closed: the tree's nodes (position as x, y, z rows, parent, depth, cost
            from the root plus heuristic, heuristic, expanded); near: a list of nodes; heap: the open nodes that can
            be expanded, a binary heap by (cost, index).
        dist, count, cells: the histogram's sums of distances and point counts (N_E x N_Z, flat) and the list of
            the cells that hold points; mean, cell_cost: their mean distances and obstacle costs, in list order.
        col, cols, hi: smoothPolarMatrix's padded obstacle cost matrix, one row per padded column
            ((N_Z + 2r) x (N_E + 2r)); the list of the columns that hold a cost, and whether a column is listed
            (0, else -1).
        colsm: each listed column smoothed along elevation (N_E values).
        line, box, box4, row, row_c: two padded histogram rows, the running sums of one line and of four, two
            smoothed rows of N_Z costs, a row's total costs.
        yaw_cost, row_cost, row_seen: the per-azimuth yaw costs, per-elevation pitch costs, rows already searched.
        cos_a, sin_a, cos_e, sin_e: cosine and sine of each cell's azimuth and elevation (its centre).
        cand_e, cand_z, cand_c: the cheapest cells (elevation, azimuth, cost), ascending cost.
    """

    pos: np.ndarray
    parent: np.ndarray
    depth: np.ndarray
    total: np.ndarray
    heur: np.ndarray
    closed: np.ndarray
    near: np.ndarray
    heap: np.ndarray
    dist: np.ndarray
    count: np.ndarray
    cells: np.ndarray
    mean: np.ndarray
    cell_cost: np.ndarray
    col: np.ndarray
    cols: np.ndarray
    hi: np.ndarray
    colsm: np.ndarray
    line: np.ndarray
    box: np.ndarray
    box4: np.ndarray
    row: np.ndarray
    row_c: np.ndarray
    yaw_cost: np.ndarray
    row_cost: np.ndarray
    row_seen: np.ndarray
    cos_a: np.ndarray
    sin_a: np.ndarray
    cos_e: np.ndarray
    sin_e: np.ndarray
    cand_e: np.ndarray
    cand_z: np.ndarray
    cand_c: np.ndarray


@njit(cache=True)
def _tree_work(radius, children):  # pragma: no cover - compiled
    """A :class:`TreeWork` for a smoothing radius of ``radius`` cells and ``children`` children per node."""
    n_cols, n_rows = N_Z + 2 * radius, N_E + 2 * radius
    cos_a, sin_a, cos_e, sin_e = np.empty(N_Z), np.empty(N_Z), np.empty(N_E), np.empty(N_E)
    for z in range(N_Z):  # the expressions of _best_cells, so the same bits
        az = z * ALPHA_RES + 0.5 * ALPHA_RES - 180.0
        cos_a[z], sin_a[z] = math.cos(az / _R2D), math.sin(az / _R2D)
    for e in range(N_E):
        el = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0
        cos_e[e], sin_e[e] = math.cos(el / _R2D), math.sin(el / _R2D)
    return TreeWork(np.empty((3, MAX_NODES)), np.empty(MAX_NODES, dtype=np.int64),
                    np.empty(MAX_NODES, dtype=np.int64), np.empty(MAX_NODES), np.empty(MAX_NODES),
                    np.zeros(MAX_NODES, dtype=np.bool_), np.empty(MAX_NODES, dtype=np.int64),
                    np.empty(MAX_NODES, dtype=np.int64),
                    np.zeros(N_E * N_Z), np.zeros(N_E * N_Z), np.empty(N_E * N_Z, dtype=np.int64),
                    np.empty(N_E * N_Z), np.empty(N_E * N_Z),
                    np.zeros((n_cols, n_rows)), np.empty(n_cols, dtype=np.int64), np.full(n_cols, -1, dtype=np.int64),
                    np.empty((n_cols, N_E)),
                    np.zeros((2, n_cols)), np.empty(max(N_E, N_Z) + 2 * radius),
                    np.empty((4, max(N_E, N_Z) + 2 * radius)), np.empty((2, N_Z)), np.empty(N_Z),
                    np.empty(N_Z), np.empty(N_E), np.zeros(N_E, dtype=np.bool_),
                    cos_a, sin_a, cos_e, sin_e,
                    np.empty(children, dtype=np.int64), np.empty(children, dtype=np.int64), np.empty(children))


def tree_work(settings: KernelSettings) -> TreeWork:
    """The reusable buffers of :func:`_build_tree` for a planner with these settings."""
    return _tree_work(settings.smoothing_radius, settings.children)


@njit(cache=True, inline="always")
def _mod360(x):  # pragma: no cover - compiled
    """``x % 360.0`` for x in (-360, 720) or NaN, the operations Python's modulo does there: x + 360 below 0, x - 360
    (exact: Sterbenz) from 360 on, x itself between (where Python gives -0.0 as 0.0; subtracting 180 then gives
    the same). :func:`_expand` calls it with ``az - az_goal + 180`` in [-177, 537] (``az_goal`` from atan2).
    Without the ``%`` (fmod), which the vectorized loop would compute for every cell."""
    if x < 0.0:
        return x + 360.0
    if x >= 360.0:
        return x - 360.0
    return x


@njit(cache=True, inline="always", error_model="numpy")
def _atan2_deg_select(y, x):  # pragma: no cover - compiled
    """:func:`_atan2_deg` (the same bits) written with selects instead of branches, so that loops calling it
    vectorize: ``min / max`` is the ratio it picks; at the origin the 0 / 0 (NaN under ``error_model="numpy"``) is
    replaced by the 0.0 it returns there."""
    ax, ay = abs(x), abs(y)
    a = min(ax, ay) / max(ax, ay)
    s = a * a
    r = ((((((-0.0040540580 * s + 0.0218612288) * s - 0.0559098861) * s + 0.0964200441) * s - 0.1390853351) * s
          + 0.1994653599) * s - 0.3332985605) * s * a + a
    r = 1.5707963267948966 - r if ay > ax else r
    r = 3.141592653589793 - r if x < 0.0 else r
    r = -r if y < 0.0 else r
    return 0.0 if ax == 0.0 and ay == 0.0 else r * 57.29577951308232


@njit(cache=True, inline="always", error_model="numpy")
def _cell_index(dx, dy, dz):  # pragma: no cover - compiled
    """The flat histogram cell ``ie * N_Z + iz`` of ``_hist_index(dx, dy, dz, ALPHA_RES)``, the same bits, with
    selects instead of branches (:func:`_atan2_deg_select`)."""
    h = math.sqrt(dx * dx + dy * dy)
    az = _atan2_deg_select(dy, dx)
    el = _atan2_deg_select(dz, h)
    iz = int(math.floor(az / ALPHA_RES + 180.0 / ALPHA_RES))
    ie = int(math.floor(el / ALPHA_RES + 90.0 / ALPHA_RES))
    iz = iz - N_Z if iz >= N_Z else iz
    iz = iz + N_Z if iz < 0 else iz
    ie = N_E - 1 if ie >= N_E else ie
    ie = 0 if ie < 0 else ie
    return ie * N_Z + iz


@njit(cache=True)
def _conic_line(src, si, lo, hi, r, n, box, out, oi):  # pragma: no cover - compiled
    """The conic kernel of radius ``r`` along one padded line ``src[si]`` (n + 2r values, zero outside ``[lo, hi]``)
    into ``out[oi, :n]``: the two running box sums of :func:`_smooth_columns` / :func:`_smooth_row`, the same
    additions in the same order, computed only where they can change. Before the first nonzero value enters the
    window a running sum adds zeros and stays 0.0; after the last one leaves it adds ``c - c`` and keeps its value;
    those stretches are written, not summed. ``box`` (>= n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)  # box[j] sums src[si, j:j + length]: 0.0 while j + r < lo
    j1 = min(m - 1, hi + 1)  # and box[hi + 1] from then on
    for j in range(j0):
        box[j] = 0.0
    s = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            s += src[si, j]
        box[0] = s
        start = 1
    for j in range(start, j1 + 1):
        s += src[si, j + length - 1] - src[si, j - 1]
        box[j] = s
    for j in range(j1 + 1, m):
        box[j] = s
    i0 = max(0, j0 - r)  # the second pass over box: 0.0 before j0 and constant after j1, likewise
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[oi, i] = 0.0
    s = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            s += box[j]
        out[oi, 0] = s
        start = 1
    for i in range(start, i1 + 1):
        s += box[i + length - 1] - box[i - 1]
        out[oi, i] = s
    for i in range(i1 + 1, n):
        out[oi, i] = s
    for i in range(n):  # the means, in a loop that vectorizes
        out[oi, i] /= length


@njit(cache=True)
def _conic_lines4(src, ca, cb, cc, cd, lo, hi, r, n, box, out):  # pragma: no cover - compiled
    """:func:`_conic_line` on the four lines ``src[ca]``, ``src[cb]``, ``src[cc]``, ``src[cd]``, each zero outside
    ``[lo, hi]``, into the same rows of ``out``, in lockstep: four independent chains of additions at once. Each
    line's sums are the same bits as alone: a line's sum over its own zeros before its first nonzero value is
    0.0 + (0.0 - 0.0), and after its last one it adds 0.0 (the window's values are equal), so running it over the
    group's range changes nothing. ``box`` (4, >= n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)
    j1 = min(m - 1, hi + 1)
    for j in range(j0):
        box[0, j] = box[1, j] = box[2, j] = box[3, j] = 0.0
    sa = sb = sc = sd = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            sa += src[ca, j]
            sb += src[cb, j]
            sc += src[cc, j]
            sd += src[cd, j]
        box[0, 0], box[1, 0], box[2, 0], box[3, 0] = sa, sb, sc, sd
        start = 1
    for j in range(start, j1 + 1):
        sa += src[ca, j + length - 1] - src[ca, j - 1]
        sb += src[cb, j + length - 1] - src[cb, j - 1]
        sc += src[cc, j + length - 1] - src[cc, j - 1]
        sd += src[cd, j + length - 1] - src[cd, j - 1]
        box[0, j], box[1, j], box[2, j], box[3, j] = sa, sb, sc, sd
    for j in range(j1 + 1, m):
        box[0, j], box[1, j], box[2, j], box[3, j] = sa, sb, sc, sd
    i0 = max(0, j0 - r)
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[ca, i] = out[cb, i] = out[cc, i] = out[cd, i] = 0.0
    sa = sb = sc = sd = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            sa += box[0, j]
            sb += box[1, j]
            sc += box[2, j]
            sd += box[3, j]
        out[ca, 0], out[cb, 0], out[cc, 0], out[cd, 0] = sa, sb, sc, sd
        start = 1
    for i in range(start, i1 + 1):
        sa += box[0, i + length - 1] - box[0, i - 1]
        sb += box[1, i + length - 1] - box[1, i - 1]
        sc += box[2, i + length - 1] - box[2, i - 1]
        sd += box[3, i + length - 1] - box[3, i - 1]
        out[ca, i], out[cb, i], out[cc, i], out[cd, i] = sa, sb, sc, sd
    for i in range(i1 + 1, n):
        out[ca, i], out[cb, i], out[cc, i], out[cd, i] = sa, sb, sc, sd
    for i in range(n):  # the means, in loops that vectorize (a repeated line is divided once)
        out[ca, i] /= length
    if cb != ca:
        for i in range(n):
            out[cb, i] /= length
    if cc != cb:
        for i in range(n):
            out[cc, i] /= length
    if cd != cc:
        for i in range(n):
            out[cd, i] /= length


@njit(cache=True)
def _conic_lines2(src, lo, hi, r, n, box, out):  # pragma: no cover - compiled
    """:func:`_conic_line` on the two lines ``src[0]`` and ``src[1]``, zero outside ``[lo, hi]``, into ``out[0]``
    and ``out[1]`` (``[:n]``), in lockstep: two independent chains of additions at once, each line's sums the same
    bits as alone (:func:`_conic_lines4`). ``box`` (>= 2 rows of n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)
    j1 = min(m - 1, hi + 1)
    for j in range(j0):
        box[0, j] = box[1, j] = 0.0
    sa = sb = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            sa += src[0, j]
            sb += src[1, j]
        box[0, 0], box[1, 0] = sa, sb
        start = 1
    for j in range(start, j1 + 1):
        sa += src[0, j + length - 1] - src[0, j - 1]
        sb += src[1, j + length - 1] - src[1, j - 1]
        box[0, j], box[1, j] = sa, sb
    for j in range(j1 + 1, m):
        box[0, j], box[1, j] = sa, sb
    i0 = max(0, j0 - r)
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[0, i] = out[1, i] = 0.0
    sa = sb = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            sa += box[0, j]
            sb += box[1, j]
        out[0, 0], out[1, 0] = sa, sb
        start = 1
    for i in range(start, i1 + 1):
        sa += box[0, i + length - 1] - box[0, i - 1]
        sb += box[1, i + length - 1] - box[1, i - 1]
        out[0, i], out[1, i] = sa, sb
    for i in range(i1 + 1, n):
        out[0, i], out[1, i] = sa, sb
    for i in range(n):  # the means, in a loop that vectorizes
        out[0, i] /= length
        out[1, i] /= length


@njit(cache=True, inline="always")
def _next_row(row_cost, row_seen):  # pragma: no cover - compiled
    """The unseen row of least pitch cost, the lower index first among equal costs (then seen); -1 when none."""
    e = -1
    for i in range(N_E):
        if not row_seen[i] and (e < 0 or row_cost[i] < row_cost[e]):
            e = i
    if e >= 0:
        row_seen[e] = True
    return e


@njit(cache=True, error_model="numpy")
def _expand(points, pcell, pdist, origin, velocity, goal, line, settings, work):  # pragma: no cover - compiled
    """:func:`_best_cells` (the histogram and cost matrix at ``origin``, the cheapest cells into ``work.cand_*``)
    with the same result, for the cloud ``points`` (3, n) (x, y, z rows; ``pcell`` and ``pdist`` (n,) are work
    buffers), on sparse buffers: the histogram only in the cells the points fall in, their obstacle
    costs put in the padded matrix with its polar wrap, the smoothing along elevation only in the columns that hold
    a cost (:func:`_conic_line`), along azimuth only in the rows the search visits. Returns (the number of cells,
    whether a histogram cell is occupied); leaves ``work``'s sparse buffers zero."""
    ox, oy, oz = origin
    vx, vy, vz = velocity
    gx, gy, gz = goal
    cx, cy, cz = line
    rmin, rmax = settings.min_range, settings.max_range
    w_pitch, w_yaw, w_vel, obst_param = settings.pitch_cost, settings.yaw_cost, settings.velocity_cost, \
        settings.obstacle_cost
    r = settings.smoothing_radius
    n_best = settings.children
    dist, count, cells, col, cols, hi = work.dist, work.count, work.cells, work.col, work.cols, work.hi
    cand_e, cand_z, cand_c = work.cand_e, work.cand_z, work.cand_c
    # the histogram (_histogram): each point's cell and distance (a loop that vectorizes), then the sums in point
    # order, the touched cells listed
    n_points = points.shape[1]
    for i in range(n_points):
        dx, dy, dz = points[0, i] - ox, points[1, i] - oy, points[2, i] - oz
        pcell[i] = _cell_index(dx, dy, dz)
        pdist[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
    n_cells = 0
    for i in range(n_points):
        c = pcell[i]
        cells[n_cells] = c  # kept when the cell was empty (without a branch)
        n_cells += count[c] == 0.0
        dist[c] += pdist[i]
        count[c] += 1.0
    # mean distances and obstacle costs (a loop that vectorizes), then the costs put in the padded matrix (rows
    # beyond the poles: the opposite azimuth, mirrored in elevation)
    mean, cell_cost = work.mean, work.cell_cost
    for k in range(n_cells):  # gathered first, so that the arithmetic vectorizes
        c = cells[k]
        mean[k], cell_cost[k] = dist[c], count[c]
    for k in range(n_cells):
        d = mean[k] / cell_cost[k]
        x = obst_param - d
        mean[k] = d
        cell_cost[k] = 5000.0 * (1.0 + x / math.sqrt(1.0 + x * x))
    n_cols = 0
    top, bottom = N_E + 2 * r, -1  # the first and last rows that hold a cost
    occupied = False
    for k in range(n_cells):
        c = cells[k]
        d = mean[k]
        dist[c] = d
        if d > 0.0:
            cost = cell_cost[k]
            occupied = True
            e, z = c // N_Z, c % N_Z
            if r <= e < N_E - r and r <= z < N_Z - r:  # one place: the cell's own
                cc, row = r + z, r + e
                col[cc, row] = cost
                cols[n_cols] = cc  # listed when new (hi rests at -1)
                n_cols += hi[cc] < 0
                hi[cc] = 0
                top, bottom = min(top, row), max(bottom, row)
                continue
            # the cell's places in the padded matrix: its own and, within r rows of a pole, its mirror beyond the
            # pole (the opposite azimuth); each with its azimuth-wrapped copy within r cells of the wrap
            for place in range(3):
                if place == 0:
                    row, zz = r + e, z
                elif place == 1 and e < r:
                    row, zz = r - 1 - e, (z - N_Z // 2) % N_Z
                elif place == 2 and e >= N_E - r:
                    row, zz = r + N_E + (N_E - 1 - e), (z - N_Z // 2) % N_Z
                else:
                    continue
                for copy in range(3):
                    if copy == 0:
                        cc = r + zz
                    elif copy == 1 and zz >= N_Z - r:
                        cc = zz - (N_Z - r)
                    elif copy == 2 and zz < r:
                        cc = r + N_Z + zz
                    else:
                        continue
                    col[cc, row] = cost
                    cols[n_cols] = cc
                    n_cols += hi[cc] < 0
                    hi[cc] = 0
                    top, bottom = min(top, row), max(bottom, row)
    smooth = occupied and r > 0
    first, last = N_Z + 2 * r, -1  # the first and last listed columns
    for k in range(n_cols):
        first, last = min(first, cols[k]), max(last, cols[k])
    if smooth:  # the listed columns four at a time (a last group repeats its last column)
        for k in range(0, n_cols, 4):
            c0, c1 = cols[k], cols[min(k + 1, n_cols - 1)]
            c2, c3 = cols[min(k + 2, n_cols - 1)], cols[min(k + 3, n_cols - 1)]
            _conic_lines4(col, c0, c1, c2, c3, top, bottom, r, N_E, work.box4, work.colsm)
    # goal and line directions from the origin
    dgx, dgy, dgz = gx - ox, gy - oy, gz - oz
    dist_goal = math.sqrt(dgx * dgx + dgy * dgy + dgz * dgz)
    az_goal = math.atan2(dgy, dgx) * _R2D
    el_goal = math.atan2(dgz, math.sqrt(dgx * dgx + dgy * dgy)) * _R2D
    az_line = math.atan2(cy - oy, cx - ox) * _R2D
    # obstacle in the goal's window (goal cell +-5 azimuth, +-2 elevation cells, distance in (0.2, 15) m)?
    ge, gz_i = _hist_index(dgx, dgy, dgz, ALPHA_RES)
    blocked = False
    for de in range(-2, 3):
        e = ge + de
        if e < 0 or e >= N_E:
            continue
        for dz_ in range(-5, 6):
            z = (gz_i + dz_) % N_Z
            if rmin < dist[e * N_Z + z] < rmax:
                blocked = True
    w_line = 0.0 if blocked else 0.5
    pitch_scale = 1.0
    if dist_goal < 5.0:
        pitch_scale = 1.0 / max((0.2 * dist_goal) ** 2, 1e-6)
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    yaw_cost, row_cost, row_seen = work.yaw_cost, work.row_cost, work.row_seen
    cos_a, sin_a, cos_e, sin_e = work.cos_a, work.sin_a, work.cos_e, work.sin_e
    for z in range(N_Z):
        az = z * ALPHA_RES + 0.5 * ALPHA_RES - 180.0
        a = _mod360(az - az_goal + 180.0) - 180.0
        b = _mod360(az - az_line + 180.0) - 180.0
        yaw_cost[z] = w_yaw * ((1.0 - w_line) * a * a + w_line * b * b)
    min_yaw = yaw_cost.min()
    for e in range(N_E):
        de = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0 - el_goal
        row_cost[e] = w_pitch * de * de * pitch_scale
        row_seen[e] = False
    obst_row, padded_row, rc = work.row, work.line, work.row_c
    n = 0
    ahead = -1  # the next row, smoothed with this one (in obst_row[1])
    for _ in range(N_E):
        # rows by increasing pitch cost, the lower index first among equal costs (a stable sort's order); a row
        # whose every cost is at least its pitch cost plus the least yaw cost (obstacle and velocity costs are
        # >= 0) cannot beat a full candidate list, and ends the search
        if ahead >= 0:
            e, slot, ahead = ahead, 1, -1
        else:
            e, slot = _next_row(row_cost, row_seen), 0
        pitch_cost = row_cost[e]
        if n == n_best and pitch_cost + min_yaw >= cand_c[n - 1]:
            break
        if smooth and slot == 0:  # the row of the column-smoothed matrix, then smoothed along azimuth
            # (_smooth_row), with the next row when there is one: two chains of additions at once
            ahead = _next_row(row_cost, row_seen)
            if ahead >= 0:
                for k in range(n_cols):
                    padded_row[0, cols[k]] = work.colsm[cols[k], e]
                    padded_row[1, cols[k]] = work.colsm[cols[k], ahead]
                _conic_lines2(padded_row, first, last, r, N_Z, work.box4, obst_row)
                for k in range(n_cols):
                    padded_row[0, cols[k]] = padded_row[1, cols[k]] = 0.0
            else:
                for k in range(n_cols):
                    padded_row[0, cols[k]] = work.colsm[cols[k], e]
                _conic_line(padded_row, 0, first, last, r, N_Z, work.box, obst_row, 0)
                for k in range(n_cols):
                    padded_row[0, cols[k]] = 0.0
        elif not smooth:
            for z in range(N_Z):
                obst_row[0, z] = col[r + z, r + e]
        ce, se = cos_e[e], sin_e[e]
        finite = True
        for z in range(N_Z):  # the row's costs (a loop that vectorizes)
            dot = ce * (cos_a[z] * vx + sin_a[z] * vy) + se * vz
            cost = obst_row[slot, z] + yaw_cost[z] + pitch_cost + w_vel * (speed - dot)
            rc[z] = cost
            finite &= abs(cost) < np.inf
        # the first row fills the list with its n_best cheapest cells by (cost, azimuth index), the order the
        # insertion gives (a later cell enters, or passes a listed one, only when strictly cheaper); n_best cells
        # about the goal's azimuth bound them: a cell dearer than all of those cannot be among them, and is skipped
        bound = np.inf
        if n == 0 and n_best <= N_Z and finite:
            bound = -np.inf
            for q in range(n_best):
                bound = max(bound, rc[(gz_i - n_best // 2 + q) % N_Z])
        for z in range(N_Z):
            cost = rc[z]
            if cost > bound:
                continue
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
    # leave the sparse buffers zero
    for k in range(n_cells):
        dist[cells[k]] = 0.0
        count[cells[k]] = 0.0
    for k in range(n_cols):
        c = cols[k]
        for i in range(top, bottom + 1):
            col[c, i] = 0.0
        hi[c] = -1
    return n, occupied


@njit(cache=True, inline="always")
def _heap_less(a, b, total):  # pragma: no cover - compiled
    """Whether node ``a`` comes before node ``b`` in the open set: the lower total cost, the lower index among
    equal costs (the node a scan in index order with a strict ``<`` finds first)."""
    return total[a] < total[b] or (total[a] == total[b] and a < b)


@njit(cache=True, inline="always")
def _heap_push(heap, n, node, total):  # pragma: no cover - compiled
    """Add ``node`` to the binary heap ``heap[:n]`` ordered by :func:`_heap_less`; returns the new size."""
    i = n
    while i > 0:
        up = (i - 1) >> 1
        if not _heap_less(node, heap[up], total):
            break
        heap[i] = heap[up]
        i = up
    heap[i] = node
    return n + 1


@njit(cache=True, inline="always")
def _heap_pop(heap, n, total):  # pragma: no cover - compiled
    """Remove the first node of the binary heap ``heap[:n]`` (n > 0); returns (it, the new size)."""
    top = heap[0]
    n -= 1
    last = heap[n]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and _heap_less(heap[c + 1], heap[c], total):
            c += 1
        if not _heap_less(heap[c], last, total):
            break
        heap[i] = heap[c]
        i = c
    heap[i] = last
    return top, n


@njit(cache=True, error_model="numpy")
def _build_tree(cloud, vehicle, velocity, goal, line, settings, path, work=None):  # pragma: no cover - compiled
    """StarPlanner::buildLookAheadTree from ``vehicle`` (x, y, z) with ``velocity`` toward ``goal``, ``line`` the
    mission line's point (each a 3-tuple); writes the path deepest node first into ``path``, returns its length
    (0 when the vehicle's histogram is empty). ``work``: the planner's :func:`tree_work` (allocated here when
    None). The same result as :func:`_build_tree_reference`, bit for bit: each expansion is :func:`_expand`; a
    child is checked against the nodes near its parent only (a node within 0.2 m of the child lies within
    ``node_distance`` + 0.2 m of the parent; the list takes 1 mm more, far above the rounding of coordinates); the
    next node to expand, the reference's scan for the cheapest open node within ``max_range`` of the vehicle (the
    first one among equal costs), is the top of a binary heap of those nodes ordered by (cost, index)."""
    if work is None:
        work = _tree_work(settings.smoothing_radius, settings.children)
    points = np.ascontiguousarray(cloud.T)
    pcell, pdist = np.empty(cloud.shape[0], dtype=np.int64), np.empty(cloud.shape[0])
    px, py, pz = vehicle
    gx, gy, gz = goal
    rmax, w_h = settings.max_range, settings.heuristic_weight
    n_exp, step = settings.expansions, settings.node_distance
    pos, parent, depth, total, heur = work.pos, work.parent, work.depth, work.total, work.heur
    closed, near, heap = work.closed, work.near, work.heap
    pos_x, pos_y, pos_z = pos[0], pos[1], pos[2]
    cos_a, sin_a, cos_e, sin_e = work.cos_a, work.sin_a, work.cos_e, work.sin_e
    cand_e, cand_z, cand_c = work.cand_e, work.cand_z, work.cand_c
    near2 = (step + 0.201) ** 2
    pos_x[0], pos_y[0], pos_z[0] = px, py, pz
    parent[0], depth[0], closed[0] = -1, 0, False
    h0 = w_h * math.sqrt((gx - px) ** 2 + (gy - py) ** 2 + (gz - pz) ** 2)
    total[0], heur[0] = h0, h0
    size = 1
    n_open = 0  # the heap: open nodes within max_range of the vehicle and of finite cost, but the root
    origin = 0
    for it in range(n_exp):
        ox, oy, oz = pos_x[origin], pos_y[origin], pos_z[origin]
        if origin == 0:
            u = velocity
        else:
            p = parent[origin]
            u = (ox - pos_x[p], oy - pos_y[p], oz - pos_z[p])
        k, occupied = _expand(points, pcell, pdist, (ox, oy, oz), u, goal, line, settings, work)
        if it == 0 and not occupied:
            return 0
        n_near = 0
        for i in range(size):  # listed without a branch
            dx, dy, dz = pos_x[i] - ox, pos_y[i] - oy, pos_z[i] - oz
            near[n_near] = i
            n_near += dx * dx + dy * dy + dz * dz < near2
        for j in range(k):
            if size >= MAX_NODES:
                break
            e, z = cand_e[j], cand_z[j]
            nx = ox + step * cos_e[e] * cos_a[z]
            ny = oy + step * cos_e[e] * sin_a[z]
            nz = oz + step * sin_e[e]
            close = False
            for q in range(n_near):
                i = near[q]
                dx, dy, dz = pos_x[i] - nx, pos_y[i] - ny, pos_z[i] - nz
                if dx * dx + dy * dy + dz * dz < 0.04:
                    close = True
                    break
            if close:
                continue
            pos_x[size], pos_y[size], pos_z[size] = nx, ny, nz
            parent[size], depth[size], closed[size] = origin, depth[origin] + 1, False
            h = w_h * math.sqrt((gx - nx) ** 2 + (gy - ny) ** 2 + (gz - nz) ** 2)
            heur[size] = h
            t = total[origin] - heur[origin] + cand_c[j] + h
            total[size] = t
            dx, dy, dz = nx - px, ny - py, nz - pz
            if dx * dx + dy * dy + dz * dz < rmax * rmax and t < np.inf:
                n_open = _heap_push(heap, n_open, size, total)
            near[n_near] = size
            n_near += 1
            size += 1
        closed[origin] = True
        if n_open == 0:
            break
        origin, n_open = _heap_pop(heap, n_open, total)
    # the path ends at the first open node of the greatest depth (PR #555), the root when none is open
    end, deepest = 0, 0
    for i in range(size):
        if not closed[i] and depth[i] > deepest:
            end, deepest = i, depth[i]
    n = 0
    while end >= 0:
        path[n, 0], path[n, 1], path[n, 2] = pos_x[end], pos_y[end], pos_z[end]
        n += 1
        end = parent[end]
    return n
