"""Wall times of the compiled DTW / Fréchet kernels and of the two barycenters (no assertions).

Run: ``python benchmarks/bench_dtw.py [--repeat 30]``. Prints, for two 1000-point 3-D trajectories, the median
time of ``dtw`` and ``frechet`` after a warm-up call (the first call, which compiles or loads numba's cache, is
reported separately), the same for a baseline (``similaritymeasures``, pure Python loops over a scipy cost matrix)
measured in the same run, and the median time of ``dba`` and ``soft_dtw_barycenter`` (gamma 20) of 5 runs of
~90 points, the paper's replication case.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numba
import numpy as np

REFERENCE_CSV = Path(__file__).resolve().parents[2] / "shared" / "data" / "reference" / "case0_reference_trajectory.csv"


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def first_call(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def random_walk(n: int, rng: np.random.Generator) -> np.ndarray:
    return np.cumsum(rng.normal(0.0, 0.5, (n, 3)), axis=0)


def replication_runs(rng: np.random.Generator, n_runs: int = 5) -> list:
    from surrealist_gym.trajectory import Trajectory

    if REFERENCE_CSV.is_file():
        ref = Trajectory.read_csv(REFERENCE_CSV).xyz
    else:
        ref = random_walk(86, rng)
    runs = []
    for k in range(n_runs):
        n = 86 + 2 * k
        idx = np.linspace(0, len(ref) - 1, n)
        xyz = np.column_stack([np.interp(idx, np.arange(len(ref)), ref[:, d]) for d in range(3)])
        runs.append(Trajectory.from_array(xyz + rng.normal(0.0, 0.3, xyz.shape)))
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="points per trajectory (default 1000)")
    parser.add_argument("--repeat", type=int, default=30, help="timed calls per kernel (default 30)")
    parser.add_argument("--baseline-repeat", type=int, default=3, help="timed baseline calls (default 3)")
    args = parser.parse_args()

    t0 = time.perf_counter()
    from surrealist_gym import metrics
    import_s = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    a, b = random_walk(args.n, rng), random_walk(args.n, rng)

    print(f"numba {numba.__version__}, numpy {np.__version__}; import surrealist_gym.metrics: {import_s * 1e3:.0f} ms")
    print(f"two {args.n}-point 3-D trajectories, median of {args.repeat} calls after warm-up")
    first = {name: first_call(lambda f=f: f(a, b)) for name, f in (("dtw", metrics.dtw), ("frechet", metrics.frechet))}
    cache = "cache hit" if metrics._dtw_kernel.stats.cache_hits else "compiled"
    fresh_dtw = numba.njit(metrics._dtw_kernel.py_func)
    fresh_s = first_call(lambda: fresh_dtw(np.ascontiguousarray(a), np.ascontiguousarray(b)))
    print(f"  first call (numba {cache}): dtw {first['dtw'] * 1e3:.0f} ms, frechet {first['frechet'] * 1e3:.0f} ms;"
          f" fresh compile + call of the dtw kernel without cache: {fresh_s * 1e3:.0f} ms")

    ours = {"dtw": median_time(lambda: metrics.dtw(a, b), args.repeat),
            "frechet": median_time(lambda: metrics.frechet(a, b), args.repeat)}
    try:
        import similaritymeasures
    except ImportError:
        similaritymeasures = None
    for name in ("dtw", "frechet"):
        line = f"  {name:8s} {ours[name] * 1e3:8.2f} ms"
        if similaritymeasures is not None:
            base_fn = (lambda: similaritymeasures.dtw(a, b)) if name == "dtw" else (
                lambda: similaritymeasures.frechet_dist(a, b))
            base = median_time(base_fn, args.baseline_repeat)
            line += f"   baseline similaritymeasures.{'dtw' if name == 'dtw' else 'frechet_dist'}:" \
                    f" {base * 1e3:8.1f} ms   speed-up x{base / ours[name]:.0f}"
        print(line)
    print(f"  dtw target <= 10 ms: {'met' if ours['dtw'] <= 0.010 else 'NOT met'}")

    runs = replication_runs(rng)
    lengths = ", ".join(str(len(r)) for r in runs)
    print(f"barycenters of {len(runs)} runs ({lengths} points), median of {max(args.repeat // 5, 3)} calls after"
          f" warm-up")
    for name, fn in (("dba", lambda: metrics.dba(runs)),
                     ("soft_dtw_barycenter(gamma=20)", lambda: metrics.soft_dtw_barycenter(runs, gamma=20.0))):
        warm = first_call(fn)
        t = median_time(fn, max(args.repeat // 5, 3))
        print(f"  {name:30s} {t * 1e3:8.2f} ms   (first call {warm * 1e3:.0f} ms)")


if __name__ == "__main__":
    main()
