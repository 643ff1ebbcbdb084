"""Trajectory distances (DTW, discrete Fréchet, soft-DTW) and barycenters of repeated runs (DBA, soft-DTW).

The kernels are compiled with numba and take C-contiguous float64 ``(N, D)`` arrays; the public functions accept a
:class:`~surrealist_gym.trajectory.Trajectory` or an ``(N, 3)`` (or ``(N, 2)``) array. Distances are in metres.

* :func:`dtw` is the paper's DTW (eq. 1): the SUM of Euclidean point distances along the optimal warping path,
  steps (1, 0), (0, 1), (1, 1), no normalisation. :func:`dtw_path` also returns that path.
* :func:`frechet` is the discrete Fréchet distance (Eiter and Mannila 1994) [m].
* :func:`dba` averages runs with DTW Barycenter Averaging (Petitjean et al. 2011), as the paper states;
  :func:`soft_dtw_barycenter` with the soft-DTW barycenter (Cuturi and Blondel 2017), as the paper's code did
  (tslearn, gamma 20). Their docstrings describe how the two differ.

Example:
    >>> import numpy as np
    >>> a = np.zeros((3, 3)); b = a + [0.5, 0.0, 0.0]
    >>> round(dtw(a, b), 2), round(frechet(a, b), 2)
    (1.5, 0.5)
"""
from __future__ import annotations

import math
from typing import Sequence, Union

import numpy as np
from numba import njit

from .trajectory import Trajectory, as_points

TrajectoryLike = Union[Trajectory, np.ndarray]


# --- compiled kernels ------------------------------------------------------------------------------------------
@njit(cache=True)
def _dist(a, i, b, j):
    s = 0.0
    for k in range(a.shape[1]):
        d = a[i, k] - b[j, k]
        s += d * d
    return math.sqrt(s)


@njit(cache=True)
def _sq_row(a, i, bt, row):
    """Squared distances from point ``a[i]`` to every point of ``b`` (given transposed, (D, M)) into ``row``."""
    row[:] = 0.0
    for k in range(bt.shape[0]):
        ak = a[i, k]
        for j in range(bt.shape[1]):
            d = ak - bt[k, j]
            row[j] += d * d


@njit(cache=True)
def _dtw_kernel(a, b):
    """DTW value with rolling rows: O(N*M) time, O(M) memory.

    Each row's point distances are computed first (a loop the compiler vectorises), then the recursion.
    """
    n, m = a.shape[0], b.shape[0]
    bt = np.ascontiguousarray(b.T)
    prev = np.empty(m)
    cur = np.empty(m)
    row = np.empty(m)
    _sq_row(a, 0, bt, row)
    acc = 0.0
    for j in range(m):
        acc += math.sqrt(row[j])
        prev[j] = acc
    for i in range(1, n):
        _sq_row(a, i, bt, row)
        for j in range(m):
            row[j] = math.sqrt(row[j])
        left = prev[0] + row[0]
        cur[0] = left
        for j in range(1, m):
            best = prev[j - 1]
            if prev[j] < best:
                best = prev[j]
            if left < best:
                best = left
            left = best + row[j]
            cur[j] = left
        prev, cur = cur, prev
    return prev[m - 1]


@njit(cache=True)
def _dtw_matrix(a, b):
    """Full (N, M) accumulated-cost matrix of the DTW recursion."""
    n, m = a.shape[0], b.shape[0]
    acc = np.empty((n, m))
    acc[0, 0] = _dist(a, 0, b, 0)
    for j in range(1, m):
        acc[0, j] = acc[0, j - 1] + _dist(a, 0, b, j)
    for i in range(1, n):
        acc[i, 0] = acc[i - 1, 0] + _dist(a, i, b, 0)
        for j in range(1, m):
            best = acc[i - 1, j - 1]
            if acc[i - 1, j] < best:
                best = acc[i - 1, j]
            if acc[i, j - 1] < best:
                best = acc[i, j - 1]
            acc[i, j] = best + _dist(a, i, b, j)
    return acc


@njit(cache=True)
def _backtrack(acc):
    """Optimal warping path from (0, 0) to (N-1, M-1) as a (K, 2) int array; ties prefer the diagonal."""
    i, j = acc.shape[0] - 1, acc.shape[1] - 1
    path = np.empty((acc.shape[0] + acc.shape[1] - 1, 2), dtype=np.int64)
    k = 0
    path[k, 0], path[k, 1] = i, j
    while i > 0 or j > 0:
        if i == 0:
            j -= 1
        elif j == 0:
            i -= 1
        else:
            diag, up, left = acc[i - 1, j - 1], acc[i - 1, j], acc[i, j - 1]
            if diag <= up and diag <= left:
                i -= 1
                j -= 1
            elif up <= left:
                i -= 1
            else:
                j -= 1
        k += 1
        path[k, 0], path[k, 1] = i, j
    return path[: k + 1][::-1].copy()


@njit(cache=True)
def _frechet_kernel(a, b):
    """Discrete Fréchet distance with rolling rows, on squared distances (min and max commute with sqrt)."""
    n, m = a.shape[0], b.shape[0]
    bt = np.ascontiguousarray(b.T)
    prev = np.empty(m)
    cur = np.empty(m)
    row = np.empty(m)
    _sq_row(a, 0, bt, row)
    prev[0] = row[0]
    for j in range(1, m):
        prev[j] = max(prev[j - 1], row[j])
    for i in range(1, n):
        _sq_row(a, i, bt, row)
        left = max(prev[0], row[0])
        cur[0] = left
        for j in range(1, m):
            best = prev[j - 1]
            if prev[j] < best:
                best = prev[j]
            if left < best:
                best = left
            left = max(best, row[j])
            cur[j] = left
        prev, cur = cur, prev
    return math.sqrt(prev[m - 1])


@njit(cache=True)
def _dba_accumulate(bary, series, sums, counts):
    """Align ``series`` to ``bary`` by DTW; add each series point to the sum of its barycenter point. Returns DTW."""
    acc = _dtw_matrix(bary, series)
    path = _backtrack(acc)
    for k in range(path.shape[0]):
        i, j = path[k, 0], path[k, 1]
        for d in range(bary.shape[1]):
            sums[i, d] += series[j, d]
        counts[i] += 1
    return acc[bary.shape[0] - 1, series.shape[0] - 1]


@njit(cache=True)
def _softmin3(a, b, c, gamma):
    m = min(a, min(b, c))
    if m == np.inf:
        return np.inf
    s = math.exp((m - a) / gamma) + math.exp((m - b) / gamma) + math.exp((m - c) / gamma)
    return m - gamma * math.log(s)


@njit(cache=True)
def _soft_dtw_grad(z, x, gamma):
    """Soft-DTW with squared Euclidean cost: value and gradient with respect to ``z`` (Cuturi & Blondel, alg. 1-2)."""
    n, m, dim = z.shape[0], x.shape[0], z.shape[1]
    cost = np.zeros((n + 2, m + 2))
    for i in range(n):
        for j in range(m):
            s = 0.0
            for d in range(dim):
                diff = z[i, d] - x[j, d]
                s += diff * diff
            cost[i + 1, j + 1] = s
    r = np.full((n + 2, m + 2), np.inf)
    r[0, 0] = 0.0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            r[i, j] = cost[i, j] + _softmin3(r[i - 1, j - 1], r[i - 1, j], r[i, j - 1], gamma)
    value = r[n, m]
    # Backward pass: e[i, j] = d value / d cost[i, j].
    for i in range(1, n + 1):
        r[i, m + 1] = -np.inf
    for j in range(1, m + 1):
        r[n + 1, j] = -np.inf
    r[n + 1, m + 1] = value
    e = np.zeros((n + 2, m + 2))
    e[n + 1, m + 1] = 1.0
    for j in range(m, 0, -1):
        for i in range(n, 0, -1):
            ea = math.exp((r[i + 1, j] - r[i, j] - cost[i + 1, j]) / gamma)
            eb = math.exp((r[i, j + 1] - r[i, j] - cost[i, j + 1]) / gamma)
            ec = math.exp((r[i + 1, j + 1] - r[i, j] - cost[i + 1, j + 1]) / gamma)
            e[i, j] = e[i + 1, j] * ea + e[i, j + 1] * eb + e[i + 1, j + 1] * ec
    grad = np.zeros((n, dim))
    for i in range(n):
        for j in range(m):
            w = e[i + 1, j + 1]
            if w != 0.0:
                for d in range(dim):
                    grad[i, d] += 2.0 * w * (z[i, d] - x[j, d])
    return value, grad


# --- helpers ---------------------------------------------------------------------------------------------------
def _points(x, name: str = "trajectory") -> np.ndarray:
    """A C-contiguous, writeable float64 (N, D) array (one numba specialisation for every caller)."""
    pts = np.ascontiguousarray(as_points(x), dtype=np.float64)
    if not pts.flags.writeable:
        pts = pts.copy()
    if pts.shape[0] == 0:
        raise ValueError(f"{name}: expected at least one point, got none")
    return pts


def _pair(a, b) -> tuple[np.ndarray, np.ndarray]:
    pa, pb = _points(a, "a"), _points(b, "b")
    if pa.shape[1] != pb.shape[1]:
        raise ValueError(f"a and b must have the same number of coordinates, got {pa.shape[1]} and {pb.shape[1]}")
    return pa, pb


# --- distances -------------------------------------------------------------------------------------------------
def dtw(a: TrajectoryLike, b: TrajectoryLike) -> float:
    """The paper's DTW distance (eq. 1): sum of Euclidean distances [m] along the optimal warping path.

    Classic recursion ``D[i, j] = ||a_i - b_j|| + min(D[i-1, j], D[i, j-1], D[i-1, j-1])`` with no window and no
    normalisation (not the square root of summed squares). O(N*M) time, O(M) memory.

    Args:
        a: a Trajectory or an (N, 3) array of points [m].
        b: a Trajectory or an (M, 3) array of points [m].

    Returns:
        The DTW distance (a sum of distances, so it grows with the trajectories' lengths).
    """
    pa, pb = _pair(a, b)
    return float(_dtw_kernel(pa, pb))


def dtw_path(a: TrajectoryLike, b: TrajectoryLike) -> tuple[np.ndarray, float]:
    """The optimal warping path of :func:`dtw` and its value.

    Returns:
        ``(path, distance)``: ``path`` is a (K, 2) int array of index pairs ``(i, j)`` from (0, 0) to (N-1, M-1)
        (ties prefer the diagonal step); ``distance`` equals ``dtw(a, b)``. Uses O(N*M) memory.
    """
    pa, pb = _pair(a, b)
    acc = _dtw_matrix(pa, pb)
    return _backtrack(acc), float(acc[-1, -1])


def frechet(a: TrajectoryLike, b: TrajectoryLike) -> float:
    """Discrete Fréchet distance [m] (Eiter and Mannila 1994): the smallest max point distance over couplings."""
    pa, pb = _pair(a, b)
    return float(_frechet_kernel(pa, pb))


def soft_dtw(a: TrajectoryLike, b: TrajectoryLike, gamma: float = 1.0) -> float:
    """Soft-DTW (Cuturi and Blondel 2017) with the squared Euclidean cost [m^2], smoothing ``gamma`` [m^2].

    Tends to DTW with squared distances as ``gamma`` -> 0; can be negative. This is the objective that
    :func:`soft_dtw_barycenter` minimises (summed over the runs).
    """
    if not gamma > 0:
        raise ValueError(f"gamma must be positive, got {gamma!r}")
    pa, pb = _pair(a, b)
    return float(_soft_dtw_grad(pa, pb, float(gamma))[0])


# --- barycenters -----------------------------------------------------------------------------------------------
def _dataset(trajectories) -> tuple[list[np.ndarray], list]:
    items = list(trajectories)
    if not items:
        raise ValueError("trajectories: expected at least one trajectory, got none")
    series = [_points(x, f"trajectories[{k}]") for k, x in enumerate(items)]
    dims = {s.shape[1] for s in series}
    if len(dims) != 1:
        raise ValueError(f"trajectories: all must have the same number of coordinates, got {sorted(dims)}")
    return series, items


def medoid_index(trajectories: Sequence[TrajectoryLike]) -> int:
    """Index of the DTW medoid: the trajectory with the smallest sum of :func:`dtw` to all the others."""
    series, _ = _dataset(trajectories)
    n = len(series)
    dist = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1, n):
            dist[i, j] = dist[j, i] = _dtw_kernel(series[i], series[j])
    return int(np.argmin(dist.sum(axis=1)))


def _initial(series: list[np.ndarray], items: list, init) -> tuple[np.ndarray, np.ndarray | None]:
    """Starting barycenter and its time stamps (when it comes from a Trajectory)."""
    if isinstance(init, str):
        if init != "medoid":
            raise ValueError(f"init: expected 'medoid' or an (L, D) array / Trajectory, got {init!r}")
        k = medoid_index(series)
        start, src = series[k].copy(), items[k]
    else:
        start, src = _points(init, "init").copy(), init
        if start.shape[1] != series[0].shape[1]:
            raise ValueError(f"init: expected {series[0].shape[1]} coordinates, got {start.shape[1]}")
    return start, (src.t if isinstance(src, Trajectory) else None)


def _result(bary: np.ndarray, t: np.ndarray | None, items: list):
    if not all(isinstance(x, Trajectory) for x in items) or bary.shape[1] != 3:
        return bary
    if t is None or len(t) != len(bary):
        step = float(np.median(np.diff(items[0].t))) if len(items[0]) > 1 else 0.5
        t = np.arange(len(bary)) * step
    return Trajectory(t, bary)


def dba(trajectories: Sequence[TrajectoryLike], n_iter: int = 30, init="medoid", tol: float = 1e-6):
    """DTW Barycenter Averaging (Petitjean et al. 2011) with the paper's Euclidean DTW, as the paper states.

    Starting from ``init`` (default: the DTW medoid of the runs, see :func:`medoid_index`; its length is the
    barycenter's length, so runs of different lengths are fine), each iteration aligns every run to the current
    barycenter with :func:`dtw` (hard, single best alignment) and moves each barycenter point to the arithmetic
    mean of the run points aligned to it. Iteration stops after ``n_iter`` updates or when no point moves by more
    than ``tol`` [m].

    The mean update is Petitjean's: for a fixed alignment it minimises the sum of SQUARED distances, so the
    result is an average of the runs (copies of one trajectory shifted by small offsets average to the mean
    offset), not the minimiser of the summed Euclidean DTW (that would be a geometric median per point).

    Differences from :func:`soft_dtw_barycenter`: DBA uses hard alignments under the paper's unsquared Euclidean
    DTW, so the barycenter keeps the runs' shape and sharp corners. The soft-DTW barycenter minimises a smooth
    objective (squared Euclidean cost, every alignment weighted by ``exp(-cost/gamma)``) with L-BFGS; with a large
    ``gamma`` (20 m^2, as the paper's code) it is a smoother average that cuts corners, and it is the one that
    reproduces the paper's reference numbers.

    Args:
        trajectories: the n runs (Trajectories or (N_k, D) arrays; lengths may differ).
        n_iter: maximum number of DBA updates.
        init: ``"medoid"`` or an explicit starting barycenter (array or Trajectory).
        tol: largest point displacement [m] below which iteration stops.

    Returns:
        A Trajectory if all inputs are 3-D Trajectories (time stamps of the starting trajectory), else an array.
    """
    series, items = _dataset(trajectories)
    bary, t = _initial(series, items, init)
    if len(series) > 1:
        for _ in range(max(int(n_iter), 0)):
            sums, counts = np.zeros_like(bary), np.zeros(len(bary))
            for s in series:
                _dba_accumulate(bary, s, sums, counts)
            new = sums / counts[:, None]
            moved = float(np.abs(new - bary).max())
            bary = new
            if moved <= tol:
                break
    return _result(bary, t, items)


def soft_dtw_barycenter(trajectories: Sequence[TrajectoryLike], gamma: float = 20.0, init="medoid",
                        max_iter: int = 50, tol: float = 1e-3):
    """Soft-DTW barycenter (Cuturi and Blondel 2017), as the paper's reference code computed it (gamma 20).

    Minimises ``sum_k soft_dtw(Z, X_k, gamma)`` (squared Euclidean cost, :func:`soft_dtw`) over the barycenter
    ``Z`` with scipy's L-BFGS-B, using the exact gradient from the soft-DTW backward recursion. Same objective,
    defaults (``max_iter`` 50, ``tol`` 1e-3) and unit weights as tslearn's ``softdtw_barycenter``, without
    depending on tslearn. ``init`` defaults to the DTW medoid (tslearn's default, the Euclidean mean, needs
    equal lengths); its length is the barycenter's length.

    Differences from :func:`dba`: every alignment contributes (weighted by ``exp(-cost/gamma)``), so the result is
    smooth in the data and shrinks toward a local average where runs disagree; with ``gamma`` -> 0 it approaches
    a DBA-like barycenter under the squared (not the paper's unsquared) cost.

    Args:
        trajectories: the n runs (Trajectories or (N_k, D) arrays; lengths may differ).
        gamma: soft-min smoothing [m^2]; must be positive.
        init: ``"medoid"`` or an explicit starting barycenter (array or Trajectory).
        max_iter: maximum L-BFGS-B iterations.
        tol: L-BFGS-B tolerance (scipy's ``tol``).

    Returns:
        A Trajectory if all inputs are 3-D Trajectories (time stamps of the starting trajectory), else an array.
    """
    from scipy.optimize import minimize

    if not gamma > 0:
        raise ValueError(f"gamma must be positive, got {gamma!r}")
    series, items = _dataset(trajectories)
    start, t = _initial(series, items, init)
    shape, gamma = start.shape, float(gamma)

    def objective(flat: np.ndarray) -> tuple[float, np.ndarray]:
        z = np.ascontiguousarray(flat.reshape(shape))
        total, grad = 0.0, np.zeros(shape)
        for s in series:
            value, g = _soft_dtw_grad(z, s, gamma)
            total += value
            grad += g
        return total, grad.ravel()

    res = minimize(objective, start.ravel(), method="L-BFGS-B", jac=True, tol=tol,
                   options={"maxiter": int(max_iter)})
    return _result(res.x.reshape(shape), t, items)


__all__ = ["dba", "dtw", "dtw_path", "frechet", "medoid_index", "soft_dtw", "soft_dtw_barycenter"]
