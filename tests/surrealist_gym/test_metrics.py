"""DTW, Fréchet, soft-DTW and barycenters: golden value, plain-Python references, similaritymeasures and tslearn."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import similaritymeasures

from surrealist_gym import metrics
from surrealist_gym.metrics import dba, dtw, dtw_path, frechet, medoid_index, soft_dtw, soft_dtw_barycenter
from surrealist_gym.trajectory import Trajectory

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # tslearn warns that h5py is missing
    from tslearn.barycenters import dtw_barycenter_averaging, softdtw_barycenter
    from tslearn.metrics import soft_dtw as tslearn_soft_dtw
    from tslearn.utils import to_time_series_dataset

from tests.conftest import REFERENCE_CSV


# --- plain-Python references (readable, slow) ------------------------------------------------------------------
def _table(a, b, combine):
    n, m = len(a), len(b)
    acc = [[math.inf] * (m + 1) for _ in range(n + 1)]
    acc[0][0] = 0.0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            d = math.dist(a[i - 1], b[j - 1])
            acc[i][j] = combine(d, min(acc[i - 1][j], acc[i][j - 1], acc[i - 1][j - 1]))
    return acc[n][m]


def python_dtw(a, b) -> float:
    return _table(np.asarray(a).tolist(), np.asarray(b).tolist(), lambda d, prev: d + prev)


def python_frechet(a, b) -> float:
    return _table(np.asarray(a).tolist(), np.asarray(b).tolist(), max)


# --- fixtures --------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ref(shared_data) -> Trajectory:
    return Trajectory.read_csv(REFERENCE_CSV)


def _noisy_runs(ref: Trajectory, n_runs: int = 5, seed: int = 1, noise: float = 0.3) -> list[np.ndarray]:
    """Runs of different lengths: the reference resampled to 80.. points, plus Gaussian noise [m]."""
    rng = np.random.default_rng(seed)
    runs = []
    for k in range(n_runs):
        n = 80 + 3 * k
        idx = np.linspace(0, len(ref) - 1, n)
        xyz = np.column_stack([np.interp(idx, np.arange(len(ref)), ref.xyz[:, d]) for d in range(3)])
        runs.append(xyz + rng.normal(0.0, noise, xyz.shape))
    return runs


def _helix(n: int = 40) -> np.ndarray:
    """Points about 2.4 m apart, so that small shifts never change the optimal alignment."""
    s = np.linspace(0, 4 * np.pi, n)
    return np.column_stack([10 * np.cos(s), 10 * np.sin(s), 2 * s])


# --- DTW -------------------------------------------------------------------------------------------------------
def test_dtw_golden_value_on_the_reference_trajectory(ref):
    assert round(dtw(ref, ref.shifted(dx=0.5)), 2) == 33.01


@pytest.mark.parametrize("n, m, dims", [(1, 1, 3), (1, 7, 3), (9, 1, 3), (30, 45, 3), (60, 20, 2)])
def test_dtw_matches_plain_python_and_similaritymeasures(n, m, dims):
    rng = np.random.default_rng(n * 100 + m)
    a, b = rng.normal(size=(n, dims)) * 5, rng.normal(size=(m, dims)) * 5
    value = dtw(a, b)
    assert value == pytest.approx(python_dtw(a, b), rel=1e-12)
    assert value == pytest.approx(similaritymeasures.dtw(a, b)[0], rel=1e-12)


def test_dtw_matches_similaritymeasures_on_real_trajectories(ref):
    for run in _noisy_runs(ref, n_runs=3):
        assert dtw(ref, run) == pytest.approx(similaritymeasures.dtw(ref.xyz, run)[0], rel=1e-12)


def test_dtw_identities(ref):
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(25, 3)), rng.normal(size=(31, 3))
    assert dtw(a, a) == 0.0
    assert dtw(ref, ref) == 0.0
    assert dtw(a, b) == pytest.approx(dtw(b, a), rel=1e-12)
    assert dtw(a, b) >= frechet(a, b)  # a sum along the best path is at least its largest term
    # Equal lengths: the diagonal path bounds DTW; well-separated points make it exact.
    shift = np.array([0.3, -0.2, 0.1])
    assert dtw(ref, ref.xyz + shift) <= len(ref) * np.linalg.norm(shift) + 1e-9
    helix = _helix()
    assert dtw(helix, helix + shift) == pytest.approx(len(helix) * np.linalg.norm(shift), rel=1e-12)


def test_dtw_accepts_trajectories_read_only_arrays_and_lists(ref):
    arr = ref.xyz.copy()
    assert not ref.xyz.flags.writeable
    assert dtw(ref, arr + 1.0) == dtw(arr, arr + 1.0) == dtw(arr.tolist(), (arr + 1.0).tolist())


def test_bad_inputs_raise_value_error():
    with pytest.raises(ValueError, match="at least one point"):
        dtw(np.zeros((0, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="same number of coordinates"):
        frechet(np.zeros((3, 2)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="shape"):
        dtw(np.zeros(3), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="gamma"):
        soft_dtw(np.zeros((3, 3)), np.zeros((3, 3)), gamma=0.0)
    with pytest.raises(ValueError, match="init"):
        dba([np.zeros((3, 3)), np.ones((3, 3))], init="mean")


def test_dtw_path_is_a_valid_warping_path_with_the_dtw_cost():
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(17, 3)), rng.normal(size=(23, 3))
    path, value = dtw_path(a, b)
    assert tuple(path[0]) == (0, 0) and tuple(path[-1]) == (16, 22)
    steps = {tuple(s) for s in np.diff(path, axis=0)}
    assert steps <= {(1, 0), (0, 1), (1, 1)}
    assert value == pytest.approx(dtw(a, b), rel=1e-12)
    assert np.linalg.norm(a[path[:, 0]] - b[path[:, 1]], axis=1).sum() == pytest.approx(value, rel=1e-12)


# --- Fréchet ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n, m, dims", [(1, 1, 3), (1, 6, 3), (30, 45, 3), (50, 20, 2)])
def test_frechet_matches_plain_python_and_similaritymeasures(n, m, dims):
    rng = np.random.default_rng(n * 7 + m)
    a, b = rng.normal(size=(n, dims)) * 5, rng.normal(size=(m, dims)) * 5
    value = frechet(a, b)
    assert value == pytest.approx(python_frechet(a, b), rel=1e-12)
    assert value == pytest.approx(similaritymeasures.frechet_dist(a, b), rel=1e-12)


def test_frechet_on_real_trajectories_and_metric_properties(ref):
    runs = _noisy_runs(ref, n_runs=3)
    for run in runs:
        assert frechet(ref, run) == pytest.approx(similaritymeasures.frechet_dist(ref.xyz, run), rel=1e-12)
    assert frechet(ref, ref.shifted(dx=0.5)) == pytest.approx(0.5)
    a, b, c = runs
    assert frechet(a, a) == 0.0
    assert frechet(a, b) == pytest.approx(frechet(b, a))
    assert frechet(a, c) <= frechet(a, b) + frechet(b, c) + 1e-12


# --- soft-DTW --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("gamma", [0.1, 1.0, 20.0])
def test_soft_dtw_matches_tslearn(gamma):
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(12, 3)) * 3, rng.normal(size=(15, 3)) * 3
    assert soft_dtw(a, b, gamma) == pytest.approx(tslearn_soft_dtw(a, b, gamma=gamma), rel=1e-9)


def test_soft_dtw_gradient_matches_finite_differences():
    rng = np.random.default_rng(6)
    z, x = rng.normal(size=(6, 3)), rng.normal(size=(8, 3))
    value, grad = metrics._soft_dtw_grad(z, x, 2.0)
    assert value == pytest.approx(soft_dtw(z, x, 2.0))
    h = 1e-6
    for i, d in [(0, 0), (2, 1), (5, 2), (3, 0)]:
        zp, zm = z.copy(), z.copy()
        zp[i, d] += h
        zm[i, d] -= h
        numeric = (soft_dtw(zp, x, 2.0) - soft_dtw(zm, x, 2.0)) / (2 * h)
        assert grad[i, d] == pytest.approx(numeric, rel=1e-5, abs=1e-7)


# --- barycenters -----------------------------------------------------------------------------------------------
def _sum_dtw(z, runs) -> float:
    return sum(dtw(z, r) for r in runs)


def _sum_soft_dtw(z, runs, gamma) -> float:
    return sum(soft_dtw(z, r, gamma) for r in runs)


def test_medoid_is_the_run_with_the_smallest_summed_dtw(ref):
    runs = _noisy_runs(ref)
    sums = [sum(dtw(r, s) for s in runs) for r in runs]
    assert medoid_index(runs) == int(np.argmin(sums))


def test_barycenters_of_shifted_copies_recover_the_mean():
    helix = _helix()
    shifts = [np.array([dx, 0.2 * dx, -0.1 * dx]) for dx in (-0.3, -0.1, 0.0, 0.2, 0.5)]
    runs = [helix + s for s in shifts]
    mean = helix + np.mean(shifts, axis=0)
    init = runs[medoid_index(runs)]
    np.testing.assert_allclose(dba(runs), mean, atol=1e-9)
    np.testing.assert_allclose(dtw_barycenter_averaging(to_time_series_dataset(runs), init_barycenter=init),
                               mean, atol=1e-9)
    # gamma small against the squared point spacing (~6 m^2): close to the mean; tslearn agrees.
    ours = soft_dtw_barycenter(runs, gamma=0.01)
    theirs = softdtw_barycenter(to_time_series_dataset(runs), gamma=0.01, init=init.copy())
    np.testing.assert_allclose(ours, mean, atol=1e-3)
    np.testing.assert_allclose(ours, theirs, atol=1e-6)


def test_dba_with_runs_of_different_lengths_is_no_worse_than_tslearn(ref):
    runs = _noisy_runs(ref)
    init = runs[medoid_index(runs)]
    ours = dba(runs)
    theirs = dtw_barycenter_averaging(to_time_series_dataset(runs), init_barycenter=init.copy())
    assert ours.shape == init.shape
    # Our objective is the paper's (Euclidean) summed DTW; tslearn's DBA minimises the squared one.
    assert _sum_dtw(ours, runs) <= _sum_dtw(init, runs)
    assert _sum_dtw(ours, runs) <= _sum_dtw(theirs, runs) * 1.01
    assert frechet(ours, theirs) < 1.0


def test_soft_dtw_barycenter_matches_tslearn_with_the_same_gamma_and_init(ref):
    runs = _noisy_runs(ref)
    init = runs[medoid_index(runs)]
    ours = soft_dtw_barycenter(runs, gamma=20.0)
    theirs = softdtw_barycenter(to_time_series_dataset(runs), gamma=20.0, init=init.copy())
    obj_ours, obj_theirs = _sum_soft_dtw(ours, runs, 20.0), _sum_soft_dtw(theirs, runs, 20.0)
    assert obj_ours < _sum_soft_dtw(init, runs, 20.0)
    assert obj_ours <= obj_theirs + 1e-6 * abs(obj_theirs)
    assert frechet(ours, theirs) < 0.1


def test_barycenters_keep_the_input_type(ref):
    runs = [Trajectory.from_array(r) for r in _noisy_runs(ref, n_runs=3)]
    k = medoid_index(runs)
    for bary in (dba(runs), soft_dtw_barycenter(runs, max_iter=5)):
        assert isinstance(bary, Trajectory)
        assert len(bary) == len(runs[k])
        np.testing.assert_array_equal(bary.t, runs[k].t)
    assert isinstance(dba([r.xyz for r in runs]), np.ndarray)
    assert dba(runs[:1]) == runs[0]
    start = runs[0].xyz[::2]
    assert len(dba(runs, init=start)) == len(start)
