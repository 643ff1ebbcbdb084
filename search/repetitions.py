"""One repetition of a search, cached: ``STEM.json`` holds its finished :class:`~search.metrics.SearchMetrics` and
``STEM.sqlite`` its evaluations, so a finished repetition is read back and an interrupted one replays what it
stored (the env answers it without simulating) and goes on. ``compare``, ``benchmarks/reproduce_paper.py`` and
``benchmarks/bench_surrogates.py`` run their searches through :func:`run_repetition`.

Example:
    >>> import gymnasium as gym, surrealist_gym
    >>> from search import RandomSearch
    >>> def env(store):
    ...     return gym.make("Surrealist-Generate-v0", budget=3, runs=1, random_seed=0, store=store,
    ...                     executor="inline")
    >>> run_repetition("results/rep0", env, lambda: RandomSearch(seed=0), seed=0).metrics   # doctest: +SKIP
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .base import Agent
from .metrics import SearchMetrics, search_metrics


@dataclass(frozen=True, slots=True)
class Repetition:
    """A repetition's metrics, and the runs this call simulated (0 when read back from its JSON or its store)."""

    metrics: SearchMetrics
    new_simulations: int = 0


def run_repetition(stem, make_env: Callable[[Path], object], make_agent: Callable[[], Agent], seed: int,
                   callback: Callable[[dict], None] | None = None) -> Repetition:
    """Run ``make_agent()`` on ``make_env(STEM.sqlite)`` with ``seed``, unless ``STEM.json`` holds the finished
    search; ``callback`` gets each step's info. A JSON that is not SearchMetrics (an older format) is rewritten from
    the search replayed from its store."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    cached = stem.parent / f"{stem.name}.json"  # not with_suffix: a stem may hold dots ("miss0.02")
    if cached.is_file():
        try:
            return Repetition(SearchMetrics.from_json(json.loads(cached.read_text())))
        except TypeError:  # an older format: replay the search from its store
            pass
    trace: list[tuple[int, int, float]] = []

    def step(info: dict) -> None:
        trace.append((int(info["evaluations"]), int(info["simulations"]), float(info["best_fitness"])))
        if callback is not None:
            callback(info)

    env = make_env(stem.parent / f"{stem.name}.sqlite")
    try:
        agent = make_agent()
        start = time.perf_counter()
        result = agent.run(env, seed=seed, callback=step)
        evaluator = env.unwrapped.evaluator
        metrics = search_metrics(env, result, trace, time.perf_counter() - start + evaluator.replayed_seconds)
        simulated = evaluator.simulations
    finally:
        env.close()
    cached.write_text(json.dumps(metrics.to_json()) + "\n")
    return Repetition(metrics, simulated)
