"""The look-ahead tree search of PX4-Avoidance's local planner (``StarPlanner::buildLookAheadTree``,
:func:`build_tree`), the one the planner (:mod:`surrealist_gym.sim.avoidance.px4.local_planner`) calls once per cycle.

It gives the same paths as PX4-Avoidance's search as written
(:func:`~surrealist_gym.sim.reference.px4_tree.build_tree_reference`), bit for bit (the same operations
in the same order, no fastmath), on sparse buffers: each expansion
(:func:`~surrealist_gym.sim.avoidance.px4.expansion.expand_node`) touches only the cells its points fall in and smooths
only where a sum can change, and the next node to expand is the top of a binary heap. The buffers are one
:class:`TreeWork` (:func:`tree_work`), allocated once per planner and reused by every build.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .expansion import expand_node
from .settings import ALPHA_RES, MAX_NODES, N_E, N_Z, R2D, KernelSettings


class TreeWork(NamedTuple):
    """The buffers of :func:`build_tree`, allocated once per planner (:func:`tree_work`) and reused by every build.
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
        line, box, box4, row, row_c, sel: two padded histogram rows, the running sums of one line and of four, two
            smoothed rows of N_Z costs, a row's total costs, the azimuths of a row that can enter the cheapest cells.
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
    sel: np.ndarray
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
def new_tree_work(radius, children):  # pragma: no cover - compiled
    """A :class:`TreeWork` for a smoothing radius of ``radius`` cells and ``children`` children per node."""
    n_cols, n_rows = N_Z + 2 * radius, N_E + 2 * radius
    cos_a, sin_a, cos_e, sin_e = np.empty(N_Z), np.empty(N_Z), np.empty(N_E), np.empty(N_E)
    for z in range(N_Z):  # the expressions of _best_cells, so the same bits
        az = z * ALPHA_RES + 0.5 * ALPHA_RES - 180.0
        cos_a[z], sin_a[z] = math.cos(az / R2D), math.sin(az / R2D)
    for e in range(N_E):
        el = e * ALPHA_RES + 0.5 * ALPHA_RES - 90.0
        cos_e[e], sin_e[e] = math.cos(el / R2D), math.sin(el / R2D)
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
                    np.empty(N_Z, dtype=np.int64),
                    np.empty(N_Z), np.empty(N_E), np.zeros(N_E, dtype=np.bool_),
                    cos_a, sin_a, cos_e, sin_e,
                    np.empty(children, dtype=np.int64), np.empty(children, dtype=np.int64), np.empty(children))


def tree_work(settings: KernelSettings) -> TreeWork:
    """The reusable buffers of :func:`build_tree` for a planner with these settings."""
    return new_tree_work(settings.smoothing_radius, settings.children)


@njit(cache=True)
def _heap_less(a, b, total):  # pragma: no cover - compiled
    """Whether node ``a`` comes before node ``b`` in the open set: the lower total cost, the lower index among
    equal costs (the node a scan in index order with a strict ``<`` finds first)."""
    return total[a] < total[b] or (total[a] == total[b] and a < b)


@njit(cache=True)
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


@njit(cache=True)
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
def build_tree(cloud, vehicle, velocity, goal, line, settings, path, work=None):  # pragma: no cover - compiled
    """StarPlanner::buildLookAheadTree from ``vehicle`` (x, y, z) with ``velocity`` toward ``goal``, ``line`` the
    mission line's point (each a 3-tuple); writes the path deepest node first into ``path``, returns its length
    (0 when the vehicle's histogram is empty). ``work``: the planner's :func:`tree_work` (allocated here when
    None). The same result as :func:`build_tree_reference`, bit for bit: each expansion is :func:`expand_node`; a
    child is checked against the nodes near its parent only (a node within 0.2 m of the child lies within
    ``node_distance`` + 0.2 m of the parent; the list takes 1 mm more, far above the rounding of coordinates); the
    next node to expand, the reference's scan for the cheapest open node within ``max_range`` of the vehicle (the
    first one among equal costs), is the top of a binary heap of those nodes ordered by (cost, index)."""
    if work is None:
        work = new_tree_work(settings.smoothing_radius, settings.children)
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
        k, occupied = expand_node(points, pcell, pdist, (ox, oy, oz), u, goal, line, settings, work)
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
