"""Reproduce the paper's Table 3 (RQ1, seeds 1 and 2) and Table 4 (RQ2) with repetitions, and print markdown.

    python benchmarks/reproduce_paper.py [--repetitions 10] [--workers 2] [--out results/paper] [--only rq1-seed1]
                                         [--common-noise]

Each repetition is one search with its own base seed (the simulation noise); its evaluations are stored in
``OUT/<problem>-rep<N>.sqlite``, so an interrupted run resumes where it stopped, and its metrics in
``OUT/<problem>-rep<N>.json`` (``search.repetitions``; a JSON of an older version is rewritten by replaying the
store). The paper's figures are printed beside ours. ``--common-noise`` flies every test's run i with the same noise
(``SimConfig.common_noise``; default out ``results/paper-crn``).
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

import surrealist_gym as sg
from search import AdaptiveGreedy
from search.metrics import SearchMetrics
from search.repetitions import run_repetition
from search.statistics import cohens_d, compare, reduction, vargha_delaney_a12
from surrealist_gym.envs.generate import GenerateEnv
from surrealist_gym.envs.replicate import ReplicateEnv
from surrealist_gym.outcomes import UNSAFE_DISTANCE_M
from surrealist_gym.sim import SimConfig

PAPER = {  # the paper's figures, by SearchMetrics name (eval_s: seconds per evaluation)
    "rq1-seed1": {"seed_dtw": 383.5, "best_dtw": 63.15, "seed_frechet": 6.87, "best_frechet": 1.14,
                  "evaluations_to_best": 74.8, "eval_s": 152.9},
    "rq1-seed2": {"seed_dtw": 116.1, "best_dtw": 59.1, "seed_frechet": 2.25, "best_frechet": 1.05,
                  "evaluations_to_best": 65, "eval_s": 152.9},
    "rq2": {"seed_min_distance": 3.36, "best_min_distance": 0.0, "crash_rate": 0.25, "unsafe_rate": 0.84,
            "evaluations_to_best": 36.8, "eval_s": 388},
}


def paper_env(problem: str, rep: int, store=None, common_noise: bool = False, workers: int | None = None,
              executor=None, uav=None, search_uav: bool = False):
    """The env of a paper problem (case0 seeds: budget 100, 5 runs; RQ2: budget 50, 10 runs), noise of repetition
    ``rep``; it flies ``uav`` (a preset such as ``px4-vision-sitl``, or a profile: ``surrealist calibrate``) when
    given, and RQ1 searches its settings with ``search_uav``."""
    options = dict(store=store, random_seed=rep, workers=workers, executor=executor,
                   sim_config=SimConfig(common_noise=common_noise))
    if uav is not None:
        options.update(uav=uav, sim_config={"common_noise": common_noise})
    if problem == "rq2":
        return GenerateEnv(budget=50, runs=10, **options)
    return ReplicateEnv(seed_test=sg.data_path(f"{problem}.yaml"), budget=100, runs=5, uav_mutators=search_uav,
                        **options)


def paper_agent(problem: str) -> AdaptiveGreedy:
    return AdaptiveGreedy("paper" if problem == "rq2" else "authors")


def run_one(problem: str, rep: int, out: Path, workers: int, common_noise: bool = False, uav=None,
            search_uav: bool = False) -> SearchMetrics:
    """One repetition, cached in OUT/<problem>-rep<N>.json (its evaluations in OUT/<problem>-rep<N>.sqlite)."""
    def make_env(store):
        return paper_env(problem, rep, store, common_noise, workers, uav=uav, search_uav=search_uav)

    return run_repetition(out / f"{problem}-rep{rep}", make_env, lambda: paper_agent(problem), rep).metrics


def _values(rows, key) -> list[float]:
    return [r.wall_seconds / max(1, r.evaluations) if key == "eval_s" else getattr(r, key) for r in rows]


def _mean(rows, key) -> float:
    return float(np.mean(_values(rows, key)))


def _span(rows, key, spec: str) -> str:
    values = _values(rows, key)
    return f"{min(values):{spec}} - {max(values):{spec}}"


def table_rq1(problem: str, rows: list[SearchMetrics]) -> str:
    paper = PAPER[problem]
    seed_dtw, best_dtw = _values(rows, "seed_dtw"), _values(rows, "best_dtw")
    p, test = compare(seed_dtw, best_dtw)
    lines = [f"| {problem} ({len(rows)} repetitions) | paper | ours (mean) | ours (min - max) |", "|---|---|---|---|"]
    for key, label, unit in (("seed_dtw", "Seed DTW", ""), ("best_dtw", "Best DTW", ""),
                             ("seed_frechet", "Seed Frechet", " m"), ("best_frechet", "Best Frechet", " m")):
        lines.append(f"| {label} | {paper[key]}{unit} | {_mean(rows, key):.2f}{unit} | {_span(rows, key, '.2f')} |")
    dtw_red = reduction(_mean(rows, "best_dtw"), _mean(rows, "seed_dtw"))
    fr_red = reduction(_mean(rows, "best_frechet"), _mean(rows, "seed_frechet"))
    paper_dtw_red = reduction(paper["best_dtw"], paper["seed_dtw"])
    paper_fr_red = reduction(paper["best_frechet"], paper["seed_frechet"])
    lines += [f"| DTW reduction | {paper_dtw_red:.1%} | {dtw_red:.1%} | |",
              f"| Frechet reduction | {paper_fr_red:.1%} | {fr_red:.1%} | |",
              f"| p-value seed vs best DTW ({test}) | << 0.01 | {p:.2g} | |",
              f"| effect size: Cohen's d / A12 | 7.9 / - | {abs(cohens_d(seed_dtw, best_dtw)):.1f} / "
              f"{vargha_delaney_a12(seed_dtw, best_dtw):.2f} | |",
              f"| needed budget (evaluations to best) | {paper['evaluations_to_best']} | "
              f"{_mean(rows, 'evaluations_to_best'):.1f} | {_span(rows, 'evaluations_to_best', '')} |",
              f"| evaluation time (5 runs) | {paper['eval_s']} s | {_mean(rows, 'eval_s'):.2f} s | |",
              f"| whole search (100 evaluations) | ~4-5 h | {_mean(rows, 'wall_seconds'):.0f} s | "
              f"{_span(rows, 'wall_seconds', '.0f')} s |"]
    return "\n".join(lines)


def table_rq2(rows: list[SearchMetrics]) -> str:
    paper = PAPER["rq2"]
    seed_fit, best_fit = _values(rows, "seed_fitness"), _values(rows, "best_fitness")
    p, test = compare(seed_fit, best_fit)
    lines = [f"| rq2 ({len(rows)} repetitions) | paper | ours (mean) | ours (min - max) |", "|---|---|---|---|",
             f"| Seed min distance | {paper['seed_min_distance']} m | {_mean(rows, 'seed_min_distance'):.2f} m | "
             f"{_span(rows, 'seed_min_distance', '.2f')} |",
             f"| Best min distance | {paper['best_min_distance']} m | {_mean(rows, 'best_min_distance'):.2f} m | "
             f"{_span(rows, 'best_min_distance', '.2f')} |",
             f"| crash rate (runs of the best test) | {paper['crash_rate']:.0%} | {_mean(rows, 'crash_rate'):.0%} | |",
             f"| unsafe rate (< {UNSAFE_DISTANCE_M} m) | {paper['unsafe_rate']:.0%} | "
             f"{_mean(rows, 'unsafe_rate'):.0%} | |",
             f"| repetitions with an unsafe run | - | "
             f"{sum(r.best_min_distance < UNSAFE_DISTANCE_M for r in rows)} / {len(rows)} | |",
             f"| p-value seed vs best fitness ({test}) | - | {p:.2g} | |",
             f"| effect size A12 (best vs seed fitness) | - | {vargha_delaney_a12(best_fit, seed_fit):.2f} | |",
             f"| needed budget | {paper['evaluations_to_best']} | {_mean(rows, 'evaluations_to_best'):.1f} | |",
             f"| evaluation time (10 runs) | {paper['eval_s']} s | {_mean(rows, 'eval_s'):.2f} s | |",
             f"| whole search (50 evaluations) | ~5 h | {_mean(rows, 'wall_seconds'):.0f} s | |"]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="default results/paper (--common-noise: results/paper-crn)")
    parser.add_argument("--only", choices=["rq1-seed1", "rq1-seed2", "rq2"], action="append")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: run i of every test flies with the same noise")
    parser.add_argument("--uav", default=None, help="fly this UAV profile: a preset (px4-vision-sitl: the paper's "
                                                    "Gazebo set-up) or a YAML (e.g. surrealist calibrate case0.ulg "
                                                    "--seed rq1-seed1.yaml --profile case0-uav.yaml)")
    parser.add_argument("--search-uav", action="store_true", help="RQ1: search the UAV's settings too")
    args = parser.parse_args()
    warnings.simplefilter("ignore", UserWarning)
    out = Path(args.out or ("results/paper-crn" if args.common_noise else "results/paper"))
    out.mkdir(parents=True, exist_ok=True)
    for problem in args.only or ["rq1-seed1", "rq1-seed2", "rq2"]:
        rows = []
        for rep in range(args.repetitions):
            rows.append(run_one(problem, rep, out, args.workers, args.common_noise, args.uav, args.search_uav))
            print(f"{problem} rep {rep}: " + ", ".join(f"{k}={v:.3g}" for k, v in rows[-1].figures().items()),
                  flush=True)
        print()
        print(table_rq2(rows) if problem == "rq2" else table_rq1(problem, rows))
        print(flush=True)


if __name__ == "__main__":
    main()
