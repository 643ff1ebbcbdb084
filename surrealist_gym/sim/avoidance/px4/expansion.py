"""One expansion of the look-ahead tree on sparse buffers (:func:`expand_node`): the histogram and cost matrix at a node
and its cheapest cells, with the same result as the dense reference's
:func:`~surrealist_gym.sim.reference.px4_tree._best_cells`, bit for bit (the same operations in the same
order, no fastmath).

An expansion touches only the cells its points fall in and smooths (:mod:`~surrealist_gym.sim.avoidance.px4.smoothing`)
only where a sum can change; its buffers, zero between expansions, are the tree search's
:class:`~surrealist_gym.sim.avoidance.px4.tree.TreeWork`. The helpers are written so that the loops calling them
vectorize: the flat cell of a direction (:func:`cell_index`, :func:`_atan2_deg_select`) and the modulo
(:func:`mod360`) with selects instead of branches; :func:`_next_row` gives the rows in the search's order.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .cloud import hist_index
from .settings import ALPHA_RES, N_E, N_Z, R2D
from .smoothing import conic_line, conic_lines2, conic_lines4


@njit(cache=True)
def mod360(x):  # pragma: no cover - compiled
    """``x % 360.0`` for x in (-360, 720) or NaN, the operations Python's modulo does there: x + 360 below 0, x - 360
    (exact: Sterbenz) from 360 on, x itself between (where Python gives -0.0 as 0.0; subtracting 180 then gives
    the same). :func:`expand_node` calls it with ``az - az_goal + 180`` in [-177, 537] (``az_goal`` from atan2).
    Without the ``%`` (fmod), which the vectorized loop would compute for every cell."""
    if x < 0.0:
        return x + 360.0
    if x >= 360.0:
        return x - 360.0
    return x


@njit(cache=True, error_model="numpy")
def _atan2_deg_select(y, x):  # pragma: no cover - compiled
    """:func:`atan2_deg` (the same bits) written with selects instead of branches, so that loops calling it
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


@njit(cache=True, error_model="numpy")
def cell_index(dx, dy, dz):  # pragma: no cover - compiled
    """The flat histogram cell ``ie * N_Z + iz`` of ``hist_index(dx, dy, dz, ALPHA_RES)``, the same bits, with
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
def expand_node(points, pcell, pdist, origin, velocity, goal, line, settings, work):  # pragma: no cover - compiled
    """:func:`_best_cells` (the histogram and cost matrix at ``origin``, the cheapest cells into ``work.cand_*``)
    with the same result, for the cloud ``points`` (3, n) (x, y, z rows; ``pcell`` and ``pdist`` (n,) are work
    buffers), on sparse buffers: the histogram only in the cells the points fall in, their obstacle
    costs put in the padded matrix with its polar wrap, the smoothing along elevation only in the columns that hold
    a cost (:func:`conic_line`), along azimuth only in the rows the search visits. Returns (the number of cells,
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
        pcell[i] = cell_index(dx, dy, dz)
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
                hi[cc] = 0  # the column holds a cost (hi rests at -1); listed below
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
                    hi[cc] = 0
                    top, bottom = min(top, row), max(bottom, row)
    # the columns that hold a cost, listed in order (without a branch; listing them as the cells came read back
    # each mark just stored): each column's smoothing is its own, so the order of the list changes no result
    for cc in range(N_Z + 2 * r):
        cols[n_cols] = cc
        n_cols += hi[cc] == 0
    smooth = occupied and r > 0
    first, last = N_Z + 2 * r, -1  # the first and last listed columns
    if n_cols > 0:
        first, last = cols[0], cols[n_cols - 1]
    if smooth:  # the listed columns four at a time (a last group repeats its last column)
        for k in range(0, n_cols, 4):
            c0, c1 = cols[k], cols[min(k + 1, n_cols - 1)]
            c2, c3 = cols[min(k + 2, n_cols - 1)], cols[min(k + 3, n_cols - 1)]
            conic_lines4(col, c0, c1, c2, c3, top, bottom, r, N_E, work.box4, work.colsm)
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
        a = mod360(az - az_goal + 180.0) - 180.0
        b = mod360(az - az_line + 180.0) - 180.0
        yaw_cost[z] = w_yaw * ((1.0 - w_line) * a * a + w_line * b * b)
    min_yaw = yaw_cost.min()
    for e in range(N_E):
        de = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0 - el_goal
        row_cost[e] = w_pitch * de * de * pitch_scale
        row_seen[e] = False
    obst_row, padded_row, rc, sel = work.row, work.line, work.row_c, work.sel
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
            # (smooth_row), with the next row when there is one: two chains of additions at once
            ahead = _next_row(row_cost, row_seen)
            if ahead >= 0:
                for k in range(n_cols):
                    padded_row[0, cols[k]] = work.colsm[cols[k], e]
                    padded_row[1, cols[k]] = work.colsm[cols[k], ahead]
                conic_lines2(padded_row, first, last, r, N_Z, work.box4, obst_row)
                for k in range(n_cols):
                    padded_row[0, cols[k]] = padded_row[1, cols[k]] = 0.0
            else:
                for k in range(n_cols):
                    padded_row[0, cols[k]] = work.colsm[cols[k], e]
                conic_line(padded_row, 0, first, last, r, N_Z, work.box, obst_row, 0)
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
        # about the goal's azimuth bound them: a cell dearer than all of those cannot be among them, and is skipped;
        # with the list full, only a cell cheaper than its dearest now can enter (the dearest only falls): those are
        # listed first, without a branch, and only they are inserted
        if n == n_best:
            thr = cand_c[n - 1]
            m = 0
            for z in range(N_Z):
                sel[m] = z
                m += rc[z] < thr
            for q in range(m):
                z = sel[q]
                cost = rc[z]
                if cost < cand_c[n - 1]:
                    j = n - 1
                    while j > 0 and cand_c[j - 1] > cost:
                        cand_c[j], cand_e[j], cand_z[j] = cand_c[j - 1], cand_e[j - 1], cand_z[j - 1]
                        j -= 1
                    cand_c[j], cand_e[j], cand_z[j] = cost, e, z
            continue
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
