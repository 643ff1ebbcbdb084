"""The rilast fidelity figures on the development and held-out halves (docs/fidelity.md: even / odd run numbers).

    python benchmarks/fidelity_split.py OUT/fidelity.csv [--close 3]

Reads the per-test rows ``surrealist fidelity`` wrote and prints, for all tests both flew and for the close region
(theirs < ``--close`` m), on each half: tests, Spearman, AUC for PX4's soft failures, precision / recall of ours
< 1.5 m, and the best recall at precision >= 0.6 (``surrealist_gym.fidelity.measure.region_stats``).
"""
from __future__ import annotations

import argparse
import math
import re

import pandas as pd

from surrealist_gym.fidelity.measure import region_stats


def half(test_id: str) -> str:
    """``dev`` for an even run number (random_run0_..., ga_run2_...), ``held-out`` for an odd one."""
    m = re.search(r"run(\d+)_", test_id)
    if m is None:
        raise ValueError(f"{test_id}: no run number")
    return "dev" if int(m.group(1)) % 2 == 0 else "held-out"


def split_figures(rows: pd.DataFrame, close: float = 3.0) -> dict:
    """``{(half, region): RegionStats}`` of the tests both flew."""
    both = rows[(rows.their_result == "flown") & rows.our_distance_m.apply(lambda v: math.isfinite(float(v)))]
    both = both.assign(half=both.test.map(half))
    out = {}
    for name in ("dev", "held-out", "all"):
        part = both if name == "all" else both[both.half == name]
        for region in ("all", "close"):
            sel = part if region == "all" else part[part.their_distance_m < close]
            out[name, region] = region_stats(sel.their_distance_m.to_numpy(float), sel.our_distance_m.to_numpy(float),
                                             sel.our_failure_probability.to_numpy(float))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("csv")
    parser.add_argument("--close", type=float, default=3.0)
    args = parser.parse_args()
    figures = split_figures(pd.read_csv(args.csv), args.close)
    print("| half | region | tests | Spearman | AUC | precision / recall (< 1.5 m) | best recall (t) | failure rate "
          "PX4 / ours |")
    print("|---|---|---|---|---|---|---|---|")
    for (name, region), s in figures.items():
        print(f"| {name} | {region} | {s.tests} | {s.spearman:.2f} | {s.auc:.3f} | {s.precision:.2f} / "
              f"{s.recall:.2f} | {s.best_recall:.2f} ({s.best_threshold_m:.2f} m) | {s.their_failure_rate:.2f} / "
              f"{s.our_failure_rate:.2f} |")


if __name__ == "__main__":
    main()
