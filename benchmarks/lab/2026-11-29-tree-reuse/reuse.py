"""Reusing PX4-Avoidance's look-ahead tree while the vehicle hovers: speed against fidelity, on rilast-mission1.

    python benchmarks/lab/2026-11-29-tree-reuse/reuse.py [--settings 0.1:4,0.2:4] [--seed 0] [--workers 2]

Flies the 1,350 labelled tests once (``px4-v1.12-sitl-iris``, the same noise in every pass) with a tree every
cycle, then with ``SimConfig.tree_reuse_m`` / ``tree_reuse_cycles`` at each setting (``METRES:CYCLES``). Per pass:
wall time (and as a ratio of the first pass, measured in the same run), time-outs, the close-region AUC for PX4's soft
failures on each half (docs/fidelity.md: development = even run numbers, held-out = odd) and over all; against the
first pass, the runs whose status changed and those whose distance moved by more than 0.05 m; the close region's
best recall at precision >= 0.6 over all tests (its threshold).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "benchmarks"))
DATA = ROOT.parent / "shared" / "data" / "competition" / "rilast-mission1" / "tests.csv"


def settings(text: str) -> tuple[tuple[float, int], ...]:
    """``0.1:4,0.2:4`` -> ((0.1, 4), (0.2, 4))."""
    try:
        return tuple((float(m), int(c)) for m, c in (part.split(":") for part in text.split(",")))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected METRES:CYCLES,..., got {text!r}") from None


def one_pass(lset, config, seed: int, workers: int):
    """(report, wall) of one pass."""
    from surrealist_gym.fidelity.measure import build_report, fly_labelled_set

    start = time.perf_counter()
    outcomes = fly_labelled_set(lset, 1, seed, config, workers)
    wall = time.perf_counter() - start
    return build_report(lset, outcomes, uav=config.profile, wall_s=wall), wall


def close_auc(report) -> dict:
    """Close-region AUC on each half and all, and the best recall at precision >= 0.6 over all (``recall``)."""
    from fidelity_split import half
    from surrealist_gym.fidelity.measure import region_stats

    rows = [r for r in report.rows if r.both_flew and r.label.distance < report.close_m]
    out = {}
    for name in ("dev", "held-out", "all"):
        part = [r for r in rows if name == "all" or half(r.label.test_id) == name]
        stats = region_stats(np.array([r.label.distance for r in part]), np.array([r.distance for r in part]),
                             np.array([r.failure_probability for r in part]))
        out[name] = stats.auc
    out["recall"] = f"{stats.best_recall:.2f} ({stats.best_threshold_m:.2f} m)"
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settings", type=settings, default=((0.1, 4), (0.2, 4)))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)

    from surrealist_gym.fidelity.labels import load_labelled_set
    from surrealist_gym.sim.uav import decide_uav

    lset = load_labelled_set(DATA)
    base = decide_uav(uav="px4-v1.12-sitl-iris").config
    first, first_wall = None, None
    print(f"{len(lset.tests)} rilast-mission1 tests, 1 run each (seed {args.seed}), {args.workers} workers")
    print(f"{'reuse':>10} {'wall':>8} {'ratio':>6} {'time-outs':>10} {'AUC dev':>8} {'held-out':>9} {'all':>6} "
          f"{'status changed':>15} {'distance moved':>15} {'best recall':>12}")
    for metres, cycles in ((0.0, 0),) + args.settings:
        report, wall = one_pass(lset, replace(base, tree_reuse_m=metres, tree_reuse_cycles=cycles), args.seed,
                                args.workers)
        runs = [r.runs[0] for r in report.rows]
        if first is None:
            first, first_wall = runs, wall
        changed = sum(a.status != b.status for a, b in zip(first, runs))
        moved = sum(not (math.isfinite(a.distance) and math.isfinite(b.distance)
                         and abs(a.distance - b.distance) <= 0.05) and a.distance != b.distance
                    for a, b in zip(first, runs))
        auc = close_auc(report)
        label = "off" if metres == 0 else f"{metres:g}m/{cycles}"
        print(f"{label:>10} {wall:>7.1f}s {wall / first_wall:>6.2f} {sum(r.status == 'timeout' for r in runs):>10} "
              f"{auc['dev']:>8.3f} {auc['held-out']:>9.3f} {auc['all']:>6.3f} {changed:>15} {moved:>15} "
              f"{auc['recall']:>12}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
