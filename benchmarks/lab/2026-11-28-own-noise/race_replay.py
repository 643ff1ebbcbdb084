"""Replay racing rules on greedy alone's stores (each test's own noise): simulations saved, improvements dropped.

    python benchmarks/lab/2026-11-28-own-noise/race_replay.py --problem rq1-seed1 --reps 0-9 [--miss-rate 0.02]

For every candidate of a stored search (in the order evaluated) and every racing stage k, the shortfall of its first
k runs: ``paired`` (the rule under common noise: the incumbent's first k runs minus the candidate's) or ``full``
(the incumbent's fitness over all runs minus the candidate's first k runs). Each repetition's margins are calibrated
on the other repetitions (leave one out) at an equal share of the miss rate per stage. A throwaway probe.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from bench_surrogates import _featurizer  # noqa: E402

from surrogates.dataset import _open, load_dataset  # noqa: E402


def per_run_means(stores, runs):
    """RQ2: the mean per-run fitness -(sum_dist + 2 min_dist) of each evaluation's first k runs, k = 1..runs-1."""
    rows = []
    for path in stores:
        store = _open(path)
        for ev in store:
            terms = (ev.info or {}).get("terms") or {}
            f = -(np.asarray(terms.get("sum_dist", [np.nan] * runs)) + 2 * np.asarray(terms.get("min_dist",
                                                                                                [np.nan] * runs)))
            rows.append([float(np.mean(f[:k])) for k in range(1, runs)])
        store.close()
    return np.asarray(rows)


def rows_of(data, group):
    idx = np.flatnonzero(data.groups == group)
    return data.targets["fitness"][idx], data.first_runs[idx]


def shortfalls(fit, first, rule):
    """Per candidate (rows 1..): (is improvement, (shortfall per stage k=1..n-1))."""
    best, inc = fit[0], 0
    out = []
    for i in range(1, len(fit)):
        if rule == "paired":
            s = first[inc] - first[i]
        else:
            s = best - first[i]
        out.append((fit[i] > best, s))
        if fit[i] > best:
            best, inc = fit[i], i
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--problem", default="rq1-seed1")
    parser.add_argument("--reps", default="0-9")
    parser.add_argument("--miss-rate", type=float, default=0.02)
    parser.add_argument("--stages", default="1,2,3,4")
    parser.add_argument("--proxy", default="first", choices=["first", "mean"],
                        help="first: the fitness of the first k runs; mean (RQ2): their mean per-run fitness")
    args = parser.parse_args()
    a, b = map(int, args.reps.split("-"))
    paper = Path("results/paper")
    stores = [paper / f"{args.problem}-rep{r}.sqlite" for r in range(a, b + 1)]
    stores = [s for s in stores if s.is_file()]
    data = load_dataset(stores, _featurizer(args.problem, False))
    runs = data.first_runs.shape[1] + 1
    if args.proxy == "mean":
        data = type(data)(**{**{f: getattr(data, f) for f in data.__dataclass_fields__},
                             "first_runs": per_run_means(stores, runs)})
    stages = [int(k) for k in args.stages.split(",") if int(k) < runs]
    groups = np.unique(data.groups)
    for rule in ("paired", "full"):
        per = {g: shortfalls(*rows_of(data, g), rule) for g in groups}
        saved = dropped = total_imp = total_sims = 0
        kept_paths = 0
        for g in groups:
            others = [x for h in groups if h != g for x in per[h] if x[0]]
            margins = {k: float(np.quantile([s[k - 1] for _, s in others], 1 - args.miss_rate / len(stages)))
                       for k in stages}
            lost = 0
            for imp, s in per[g]:
                total_sims += runs
                total_imp += imp
                for k in stages:
                    if s[k - 1] > margins[k]:
                        saved += runs - k
                        dropped += imp
                        lost += imp
                        break
            kept_paths += lost == 0
        print(f"{args.problem} {rule}: margins (last fold) {({k: round(m, 2) for k, m in margins.items()})}; "
              f"saved {saved / total_sims:.0%} of simulations, dropped {dropped}/{total_imp} improvements, "
              f"{kept_paths}/{len(groups)} searches drop none")


if __name__ == "__main__":
    main()
