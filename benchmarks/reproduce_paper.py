"""Reproduce the paper's Table 3 (RQ1, seeds 1 and 2) and Table 4 (RQ2) with repetitions, and print markdown.

    python benchmarks/reproduce_paper.py [--repetitions 10] [--workers 2] [--out results/paper] [--only rq1-seed1]
                                         [--common-noise]

Each repetition is one search with its own base seed (the simulation noise); its evaluations are stored in
``OUT/<problem>-rep<N>.sqlite``, so an interrupted run resumes where it stopped. The paper's figures are printed
beside ours. ``--common-noise`` flies every test's run i with the same noise (``SimConfig.common_noise``; default out
``results/paper-crn``).
"""
from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

import surrealist_gym as sg
from search import AdaptiveGreedy
from surrealist_gym.envs.generate import GenerateEnv
from surrealist_gym.envs.replicate import ReplicateEnv
from surrealist_gym.outcomes import UNSAFE_DISTANCE_M, outcomes
from surrealist_gym.sim import SimConfig
from surrealist_gym.statistics import cohens_d, compare, reduction, vargha_delaney_a12

PAPER = {
    "rq1-seed1": {"seed_dtw": 383.5, "best_dtw": 63.15, "seed_frechet": 6.87, "best_frechet": 1.14, "budget": 74.8,
                  "eval_s": 152.9},
    "rq1-seed2": {"seed_dtw": 116.1, "best_dtw": 59.1, "seed_frechet": 2.25, "best_frechet": 1.05, "budget": 65,
                  "eval_s": 152.9},
    "rq2": {"seed_min": 3.36, "best_min": 0.0, "crash": 0.25, "unsafe": 0.84, "budget": 36.8, "eval_s": 388},
}


def run_one(problem: str, rep: int, out: Path, workers: int, common_noise: bool = False) -> dict:
    """One repetition; returns its figures (and caches them in OUT/<problem>-rep<N>.json)."""
    cached = out / f"{problem}-rep{rep}.json"
    if cached.is_file():
        return json.loads(cached.read_text())
    store = out / f"{problem}-rep{rep}.sqlite"
    start = time.perf_counter()
    sim_config = SimConfig(common_noise=common_noise)
    if problem.startswith("rq1"):
        env = ReplicateEnv(seed_test=sg.data_path(f"{problem}.yaml"), budget=100, runs=5, store=store,
                           random_seed=rep, workers=workers, sim_config=sim_config)
        result = AdaptiveGreedy("authors").run(env, seed=rep)
        seed, best = env.seed_evaluation, env.best
        row = {"seed_dtw": seed.terms["dtw"], "best_dtw": best.terms["dtw"], "seed_frechet": seed.terms["frechet"],
               "best_frechet": best.terms["frechet"]}
    else:
        env = GenerateEnv(budget=50, runs=10, store=store, random_seed=rep, workers=workers, sim_config=sim_config)
        result = AdaptiveGreedy("paper").run(env, seed=rep)
        seed, best = env.seed_evaluation, env.best
        best_o = outcomes(best.runs)
        row = {"seed_min": outcomes(seed.runs).closest, "best_min": best_o.closest,
               "seed_fitness": seed.fitness, "best_fitness": best.fitness,
               "crash": best_o.crash_rate, "unsafe": best_o.unsafe_rate}
    wall = time.perf_counter() - start
    row.update(budget=result.evaluations_to_best, evaluations=result.evaluations, wall_s=wall,
               eval_s=wall / max(1, result.evaluations), simulations=env.evaluator.simulations)
    env.close()
    cached.write_text(json.dumps(row, indent=1))
    return row


def _mean(rows, key) -> float:
    return float(np.mean([r[key] for r in rows]))


def table_rq1(problem: str, rows: list[dict]) -> str:
    paper = PAPER[problem]
    seed_dtw, best_dtw = [r["seed_dtw"] for r in rows], [r["best_dtw"] for r in rows]
    p, test = compare(seed_dtw, best_dtw)
    lines = [f"| {problem} ({len(rows)} repetitions) | paper | ours (mean) | ours (min - max) |", "|---|---|---|---|"]
    for key, label, unit in (("seed_dtw", "Seed DTW", ""), ("best_dtw", "Best DTW", ""),
                             ("seed_frechet", "Seed Frechet", " m"), ("best_frechet", "Best Frechet", " m")):
        values = [r[key] for r in rows]
        lines.append(f"| {label} | {paper[key]}{unit} | {np.mean(values):.2f}{unit} | "
                     f"{min(values):.2f} - {max(values):.2f} |")
    dtw_red = reduction(_mean(rows, "best_dtw"), _mean(rows, "seed_dtw"))
    fr_red = reduction(_mean(rows, "best_frechet"), _mean(rows, "seed_frechet"))
    paper_dtw_red = reduction(paper["best_dtw"], paper["seed_dtw"])
    paper_fr_red = reduction(paper["best_frechet"], paper["seed_frechet"])
    lines += [f"| DTW reduction | {paper_dtw_red:.1%} | {dtw_red:.1%} | |",
              f"| Frechet reduction | {paper_fr_red:.1%} | {fr_red:.1%} | |",
              f"| p-value seed vs best DTW ({test}) | << 0.01 | {p:.2g} | |",
              f"| effect size: Cohen's d / A12 | 7.9 / - | {abs(cohens_d(seed_dtw, best_dtw)):.1f} / "
              f"{vargha_delaney_a12(seed_dtw, best_dtw):.2f} | |",
              f"| needed budget (evaluations to best) | {paper['budget']} | {_mean(rows, 'budget'):.1f} | "
              f"{min(r['budget'] for r in rows)} - {max(r['budget'] for r in rows)} |",
              f"| evaluation time (5 runs) | {paper['eval_s']} s | {_mean(rows, 'eval_s'):.2f} s | |",
              f"| whole search (100 evaluations) | ~4-5 h | {_mean(rows, 'wall_s'):.0f} s | "
              f"{min(r['wall_s'] for r in rows):.0f} - {max(r['wall_s'] for r in rows):.0f} s |"]
    return "\n".join(lines)


def table_rq2(rows: list[dict]) -> str:
    paper = PAPER["rq2"]
    seed_fit, best_fit = [r["seed_fitness"] for r in rows], [r["best_fitness"] for r in rows]
    p, test = compare(seed_fit, best_fit)
    lines = [f"| rq2 ({len(rows)} repetitions) | paper | ours (mean) | ours (min - max) |", "|---|---|---|---|",
             f"| Seed min distance | {paper['seed_min']} m | {_mean(rows, 'seed_min'):.2f} m | "
             f"{min(r['seed_min'] for r in rows):.2f} - {max(r['seed_min'] for r in rows):.2f} |",
             f"| Best min distance | {paper['best_min']} m | {_mean(rows, 'best_min'):.2f} m | "
             f"{min(r['best_min'] for r in rows):.2f} - {max(r['best_min'] for r in rows):.2f} |",
             f"| crash rate (runs of the best test) | {paper['crash']:.0%} | {_mean(rows, 'crash'):.0%} | |",
             f"| unsafe rate (< 1.5 m) | {paper['unsafe']:.0%} | {_mean(rows, 'unsafe'):.0%} | |",
             f"| repetitions with an unsafe run | - | "
             f"{sum(r['best_min'] < UNSAFE_DISTANCE_M for r in rows)} / {len(rows)} | |",
             f"| p-value seed vs best fitness ({test}) | - | {p:.2g} | |",
             f"| effect size A12 (best vs seed fitness) | - | {vargha_delaney_a12(best_fit, seed_fit):.2f} | |",
             f"| needed budget | {paper['budget']} | {_mean(rows, 'budget'):.1f} | |",
             f"| evaluation time (10 runs) | {paper['eval_s']} s | {_mean(rows, 'eval_s'):.2f} s | |",
             f"| whole search (50 evaluations) | ~5 h | {_mean(rows, 'wall_s'):.0f} s | |"]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="default results/paper (--common-noise: results/paper-crn)")
    parser.add_argument("--only", choices=["rq1-seed1", "rq1-seed2", "rq2"], action="append")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: run i of every test flies with the same noise")
    args = parser.parse_args()
    warnings.simplefilter("ignore", UserWarning)
    out = Path(args.out or ("results/paper-crn" if args.common_noise else "results/paper"))
    out.mkdir(parents=True, exist_ok=True)
    for problem in args.only or ["rq1-seed1", "rq1-seed2", "rq2"]:
        rows = []
        for rep in range(args.repetitions):
            rows.append(run_one(problem, rep, out, args.workers, args.common_noise))
            print(f"{problem} rep {rep}: " + ", ".join(f"{k}={v:.3g}" for k, v in rows[-1].items()), flush=True)
        print()
        print(table_rq2(rows) if problem == "rq2" else table_rq1(problem, rows))
        print(flush=True)


if __name__ == "__main__":
    main()
