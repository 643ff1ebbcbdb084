"""Compare agents on one problem: every agent, every repetition, the same env seeds; Table 2 metrics and statistics.

Repetition ``r`` of every agent runs on the env built with ``random_seed=S + r`` (the simulation noise; ``S`` the base
seed, 0 by default) and the agent seeded with ``S + r``, so agents differ only in what they propose. Each search
stores its evaluations in its own SQLite file under ``OUT/searches/``; a finished search is cached as JSON beside it,
so calling :func:`compare` again on the same folder does no simulation for it, and an interrupted one replays its
stored evaluations (the env answers them without simulating) and goes on. Writes ``compare.md``, ``compare.csv``
(per agent), ``pairwise.csv``, ``searches.csv`` (per search) and ``convergence.png`` (best fitness against
simulations, median and quartiles).

Example:
    >>> compare("Surrealist-Generate-v0", ["greedy", "random"], repetitions=3, budget=10, runs=1,
    ...         out="results/cmp", executor="inline")                                     # doctest: +SKIP
"""
from __future__ import annotations

import csv
import itertools
import math
import re
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .metrics import SearchMetrics
from .registry import agent_label, make_agent
from .repetitions import run_repetition

SETTINGS_FILE = "compare.json"
#: The searches' evaluation stores (a folder holding a row of them is kept on failure).
STORES = ("searches/*.sqlite", "evaluations")
# (metric key, column title, format); a metric absent from every search of a problem is left out of the tables
METRICS = (
    ("best_fitness", "best fitness", ".2f"),
    ("evaluations_to_best", "evaluations to best", ".1f"),
    ("simulations_to_best", "simulations to best", ".1f"),
    ("best_dtw", "best DTW", ".1f"),
    ("dtw_reduction", "DTW reduction", ".1%"),
    ("best_frechet", "best Fréchet [m]", ".2f"),
    ("frechet_reduction", "Fréchet reduction", ".1%"),
    ("best_min_distance", "best min distance [m]", ".2f"),
    ("min_distance_reduction", "min distance reduction", ".1%"),
    ("crash_rate", "crash rate", ".0%"),
    ("unsafe_rate", "unsafe rate", ".0%"),
    ("wall_seconds", "wall time [s]", ".1f"),
)
PAIRED = (("best_fitness", "final fitness"), ("simulations_to_best", "simulations to best"))


@dataclass(frozen=True, slots=True)
class SearchRecord:
    """One finished search of an agent: its metrics (with its convergence trace)."""

    agent: str
    repetition: int
    metrics: SearchMetrics
    new_simulations: int = 0  # simulated by this call (0 for a search read back from its JSON)


@dataclass(frozen=True, slots=True)
class CompareResult:
    """What :func:`compare` wrote: the searches, per-agent summary rows and pairwise statistics."""

    searches: tuple[SearchRecord, ...]
    summary: tuple[dict, ...]
    pairwise: tuple[dict, ...]
    out: Path

    @property
    def new_simulations(self) -> int:
        """Simulations flown by this call over all searches (those read back from their JSON count 0)."""
        return sum(s.new_simulations for s in self.searches)


def _slug(name: str) -> str:
    """A file-name stem for an agent name (``ppo:results/policies/x.zip`` holds a colon, slashes and dots)."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_")


def compare(env_id: str, agents: Sequence[str], repetitions: int = 10, budget: int = 100, runs: int | None = None,
            out="results/compare", env_kwargs: dict | None = None, executor=None, workers: int | None = None,
            parallel: int = 1, progress: Callable[[dict], None] | None = None, random_seed: int = 0
            ) -> CompareResult:
    """Run every agent ``repetitions`` times on the same problems, then write the tables and the plot.

    Args:
        env_id: a registered Surrealist env id.
        agents: agent names for :func:`~search.registry.make_agent` (``greedy``, ``random``, ``cmaes``,
            ``ppo:POLICY.zip``, ...).
        repetitions: searches per agent; repetition r uses env seed r and agent seed r.
        budget: evaluations per search.
        runs: simulations per evaluation (None = the env's default).
        out: results folder (a :class:`~surrealist_gym.results.ResultsFolder`, its settings in ``compare.json``);
            calling again on it resumes (budget, runs, env and env_kwargs must match; one writer at a time).
        env_kwargs: further keyword arguments of the env (JSON values, e.g. ``{"seed_test": "seed2.yaml"}``).
        executor: "process" (default), "inline", a Dask address or a ``distributed.Client``.
        workers: local worker processes (process executor).
        parallel: searches run at the same time (threads sharing the executor; useful when runs < workers).
        progress: called with ``{"agent", "repetition", "evaluations", "budget", "done"}`` after every step.
        random_seed: base seed: repetition r uses env seed ``random_seed + r`` and agent seed ``random_seed + r``.
    """
    from surrealist_gym.results import ResultsFolder

    if repetitions < 1 or budget < 1 or not agents:
        raise ValueError(f"compare: expected agents, repetitions >= 1 and budget >= 1; got {list(agents)}, "
                         f"{repetitions}, {budget}")
    for name in agents:  # fail early on a bad name, before any simulation
        make_agent(name, seed=0)
    settings = {"env_id": env_id, "budget": budget, "runs": runs, "env_kwargs": env_kwargs or {}}
    if random_seed:  # recorded when not 0, so a folder written before the option existed still resumes
        settings["random_seed"] = int(random_seed)
    folder = ResultsFolder.claim(out, "compare", settings, settings_file=SETTINGS_FILE, stores=(STORES,))
    with folder.keeping("the same command (the same --out) resumes it", "evaluation(s)"):
        return _compare(env_id, agents, repetitions, budget, runs, folder.path, settings, env_kwargs, executor,
                        workers, parallel, progress, random_seed)


def _compare(env_id, agents, repetitions, budget, runs, out: Path, settings, env_kwargs, executor, workers, parallel,
             progress, random_seed) -> CompareResult:
    from surrealist_gym.executors import InlineExecutor, SharedExecutor, make_executor

    (out / "searches").mkdir(exist_ok=True)
    real = make_executor(executor, workers)
    shared = SharedExecutor(real)
    lock = threading.Lock()
    tasks = [(name, rep) for name in agents for rep in range(repetitions)]

    def one(task):
        return _one_search(env_id, task[0], task[1], budget, runs, env_kwargs or {}, shared, out, progress, lock,
                           random_seed)

    try:
        if parallel > 1 and not isinstance(real, InlineExecutor):
            with ThreadPoolExecutor(max_workers=parallel) as pool:
                records = list(pool.map(one, tasks))
        else:
            records = [one(task) for task in tasks]
    finally:
        real.close()
    summary, pairwise = _summarise(records, list(agents))
    _write_reports(out, settings, records, summary, pairwise, list(agents))
    return CompareResult(tuple(records), tuple(summary), tuple(pairwise), out)


def _one_search(env_id, name, rep, budget, runs, env_kwargs, executor, out, progress, lock,
                random_seed: int = 0) -> SearchRecord:
    import gymnasium as gym

    from surrealist_gym.sim.uav import UAV_RECORD

    seed = random_seed + rep

    def make_env(store):
        # the bare env (flyable=False): agents compared on the paper's semantics, an invalid test refused
        kwargs = dict(env_kwargs, budget=budget, random_seed=seed, store=str(store), executor=executor, flyable=False)
        env = gym.make(env_id, **(kwargs if runs is None else dict(kwargs, runs=runs)))
        if not (out / UAV_RECORD).exists():  # the UAV the searches fly and why (all of them alike)
            env.unwrapped.uav.write(out)
        return env

    def report(evaluations, done: bool) -> None:
        if progress is not None:
            with lock:
                progress({"agent": name, "repetition": rep, "evaluations": evaluations, "budget": budget,
                          "done": done})

    finished = run_repetition(out / "searches" / f"{_slug(name)}-rep{rep}", make_env,
                              lambda: make_agent(name, seed=seed), seed,
                              lambda info: report(info["evaluations"], False))
    report(budget, True)
    return SearchRecord(name, rep, finished.metrics, finished.new_simulations)


def _values(records, agent: str, key: str) -> list[float]:
    vals = [getattr(r.metrics, key) for r in records if r.agent == agent]
    return [float(v) for v in vals if v is not None and math.isfinite(float(v))]


def _summarise(records, agents: list[str]) -> tuple[list[dict], list[dict]]:
    from .statistics import a12_magnitude, compare as significance, vargha_delaney_a12

    summary = []
    for agent in agents:
        row = {"agent": agent, "label": agent_label(agent), "searches": sum(r.agent == agent for r in records)}
        for key, _, _ in METRICS:
            vals = _values(records, agent, key)
            if vals:
                row[f"{key}_mean"], row[f"{key}_std"] = float(np.mean(vals)), float(np.std(vals, ddof=0))
                row[f"{key}_median"] = float(np.median(vals))
        summary.append(row)
    pairwise = []
    for a, b in itertools.combinations(agents, 2):
        row = {"agent_a": a, "agent_b": b}
        for key, _ in PAIRED:
            xa, xb = _values(records, a, key), _values(records, b, key)
            try:
                p, test = significance(xa, xb)
            except ValueError:  # fewer than 3 values per agent: no test
                p, test = float("nan"), "n/a"
            a12 = vargha_delaney_a12(xa, xb) if xa and xb else float("nan")
            row.update({f"{key}_p": p, f"{key}_test": test, f"{key}_a12": a12,
                        f"{key}_magnitude": a12_magnitude(a12) if math.isfinite(a12) else "n/a"})
        pairwise.append(row)
    return summary, pairwise


def _write_reports(out: Path, settings: dict, records, summary, pairwise, agents) -> None:
    present = [(k, t, f) for k, t, f in METRICS if any(f"{k}_mean" in row for row in summary)]
    with open(out / "compare.csv", "w", newline="") as f:
        keys = ["agent", "label", "searches"] + [f"{k}_{s}" for k, _, _ in present for s in ("mean", "std", "median")]
        writer = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(summary)
    with open(out / "pairwise.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(pairwise[0]) if pairwise else ["agent_a", "agent_b"])
        writer.writeheader()
        writer.writerows(pairwise)
    with open(out / "searches.csv", "w", newline="") as f:
        figures = [r.metrics.figures() for r in records]
        keys = sorted({k for row in figures for k in row})
        writer = csv.writer(f)
        writer.writerow(["agent", "repetition"] + keys)
        for r, row in zip(records, figures):
            writer.writerow([r.agent, r.repetition] + [row.get(k, "") for k in keys])
    (out / "compare.md").write_text(_markdown(settings, summary, pairwise, present))
    _plot_convergence(out / "convergence.png", records, agents, settings["env_id"])


def _fmt(value, spec: str) -> str:
    return "n/a" if value is None or not math.isfinite(value) else format(value, spec)


def _base(settings) -> str:
    """The base seed as the report writes it before ``r``: nothing for 0."""
    return f"{settings['random_seed']} + " if settings.get("random_seed") else ""


def _markdown(settings, summary, pairwise, present) -> str:
    lines = [f"# Comparison on {settings['env_id']}", "",
             f"Budget {settings['budget']} evaluations, runs per evaluation: {settings['runs'] or 'env default'}, "
             f"env options: {settings['env_kwargs'] or 'defaults'}. Mean ± standard deviation over the "
             f"repetitions (repetition r: env seed {_base(settings)}r, agent seed {_base(settings)}r).", "",
             "| agent | searches | " + " | ".join(t for _, t, _ in present) + " |",
             "|---|---|" + "---|" * len(present)]
    for row in summary:
        cells = [f"{_fmt(row.get(f'{k}_mean'), f)} ± {_fmt(row.get(f'{k}_std'), f)}" for k, _, f in present]
        lines.append(f"| {row['label']} | {row['searches']} | " + " | ".join(cells) + " |")
    lines += ["", "Pairwise: p-value (Shapiro-Wilk, then ANOVA or Mann-Whitney U) and Vargha-Delaney A12, the "
              "probability that a search of A has the larger value than one of B: on final fitness, A12 > 0.5 "
              "means A finds fitter tests; on simulations to best, A12 > 0.5 means A needs MORE simulations to "
              "reach its best.", "",
              "| A | B | final fitness p | A12 (A fitter) | simulations to best p | A12 (A needs more) |",
              "|---|---|---|---|---|---|"]
    for row in pairwise:
        cells = []
        for key, _ in PAIRED:
            cells += [f"{_fmt(row[f'{key}_p'], '.3g')} ({row[f'{key}_test']})",
                      f"{_fmt(row[f'{key}_a12'], '.2f')} ({row[f'{key}_magnitude']})"]
        lines.append(f"| {agent_label(row['agent_a'])} | {agent_label(row['agent_b'])} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def convergence_curves(records, agent: str) -> tuple[np.ndarray, np.ndarray]:
    """Simulations grid and best-fitness curves (one row per search of ``agent``; NaN before its first point)."""
    traces = [r.metrics.trace for r in records if r.agent == agent]
    top = max((t[-1][1] for t in traces), default=0)
    grid = np.arange(0, top + 1)
    curves = np.full((len(traces), grid.size), np.nan)
    for i, trace in enumerate(traces):
        sims = np.array([t[1] for t in trace])
        best = np.maximum.accumulate(np.array([t[2] for t in trace]))
        idx = np.searchsorted(sims, grid, side="right") - 1
        curves[i, idx >= 0] = best[idx[idx >= 0]]
    return grid, curves


def _plot_convergence(path: Path, records, agents, title: str) -> None:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:
        from surrealist_gym.errors import DependencyNotInstalled
        raise DependencyNotInstalled("the convergence plot needs matplotlib: pip install matplotlib") from err
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for agent in agents:
        grid, curves = convergence_curves(records, agent)
        if not curves.size:
            continue
        ok = np.isfinite(curves).any(axis=0)
        with np.errstate(all="ignore"):
            q1, med, q3 = (np.nanpercentile(curves[:, ok], q, axis=0) for q in (25, 50, 75))
        line, = ax.plot(grid[ok], med, label=agent_label(agent), drawstyle="steps-post")
        ax.fill_between(grid[ok], q1, q3, color=line.get_color(), alpha=0.2, step="post")
    ax.set_xlabel("simulations")
    ax.set_ylabel("best fitness (median, quartiles)")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
