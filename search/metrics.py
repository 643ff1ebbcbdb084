"""What a search achieved: one typed :class:`SearchMetrics` (the paper's Table 2 figures and the convergence trace),
made by :func:`search_metrics` from the env after the search, and read back from its JSON.

Example:
    >>> import gymnasium as gym, surrealist_gym, search
    >>> env = gym.make("Surrealist-Generate-v0", budget=3, runs=1, executor="inline")      # doctest: +SKIP
    >>> result = search.RandomSearch(seed=0).run(env, seed=0)                               # doctest: +SKIP
    >>> search_metrics(env, result, wall_seconds=1.0).crash_rate                             # doctest: +SKIP
    0.0
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Sequence

from surrealist_gym.outcomes import Measure, outcomes

Point = tuple[int, int, float]  # (evaluations, simulations, best fitness so far) after one step
REDUCTIONS = ("dtw_reduction", "frechet_reduction", "min_distance_reduction")


@dataclass(frozen=True, slots=True)
class SearchMetrics:
    """One finished search. Replication fills the DTW and Fréchet figures, generation the distance [m] and the rates
    (runs of the best test, judged by the env's distance measure); the others stay None. ``trace`` starts with the
    seed's evaluation."""

    seed_fitness: float
    best_fitness: float
    evaluations: int
    evaluations_to_best: int
    simulations: int
    simulations_to_best: int
    wall_seconds: float  # [s], a resumed search's stored simulation time included
    trace: tuple[Point, ...] = ()
    seed_dtw: float | None = None
    best_dtw: float | None = None
    seed_frechet: float | None = None  # [m]
    best_frechet: float | None = None  # [m]
    seed_min_distance: float | None = None  # [m]
    best_min_distance: float | None = None  # [m]
    crash_rate: float | None = None
    unsafe_rate: float | None = None
    real_duration_s: float | None = None  # replication: the real flight's 0.5 s trajectory [s]
    best_duration_s: float | None = None  # replication: the best's averaged trajectory [s]

    @property
    def dtw_reduction(self) -> float | None:
        """Table 2's DTW reduction, ``1 - best_dtw / seed_dtw`` (None without both figures)."""
        return _reduction(self.best_dtw, self.seed_dtw)

    @property
    def frechet_reduction(self) -> float | None:
        """The Fréchet reduction, ``1 - best_frechet / seed_frechet`` (None without both figures)."""
        return _reduction(self.best_frechet, self.seed_frechet)

    @property
    def min_distance_reduction(self) -> float | None:
        """The minimum-distance reduction, ``1 - best / seed`` (None without both figures)."""
        return _reduction(self.best_min_distance, self.seed_min_distance)

    def figures(self) -> dict:
        """The figures by name (reductions included, absent ones left out), as ``compare`` tabulates them."""
        names = [f.name for f in fields(self) if f.name != "trace"] + list(REDUCTIONS)
        return {name: getattr(self, name) for name in names if getattr(self, name) is not None}

    def to_json(self) -> dict:
        """The figures and the convergence trace as JSON values (read back by :meth:`from_json`)."""
        return {**self.figures(), "trace": [list(point) for point in self.trace]}

    @classmethod
    def from_json(cls, data: dict) -> SearchMetrics:
        """Read :meth:`to_json`, or a search file of ``compare`` before SearchMetrics (``{"metrics", "trace"}``).

        Raises:
            TypeError: when a figure every search has is missing (a file of another kind).
        """
        data = {**data.get("metrics", data), "trace": data.get("trace", ())}
        names = {f.name for f in fields(cls)}
        values = {k: v for k, v in data.items() if k in names}
        return cls(**{**values, "trace": tuple((int(e), int(s), float(f)) for e, s, f in values["trace"])})


def search_metrics(env, result, trace: Sequence[Point] = (), wall_seconds: float = 0.0) -> SearchMetrics:
    """The metrics of the search that just ran on ``env`` (a Surrealist env, wrapped or not) and returned
    ``result`` (a :class:`~search.base.SearchResult`); ``trace`` holds the points its steps reported, in order."""
    env = env.unwrapped
    seed, best = env.seed_evaluation, env.best
    simulations = result.simulations or env.simulations  # the agent's layer counts raced runs too
    trace = ((1, len(seed.runs), float(seed.fitness)), *trace)
    extra: dict = {}
    if "dtw" in best.terms:
        extra = {f"{which}_{key}": float(evaluation.terms[key]) for key in ("dtw", "frechet")
                 for which, evaluation in (("seed", seed), ("best", best))}
        reference = getattr(env, "reference", None)
        if reference is not None and best.trajectory is not None:
            extra.update(real_duration_s=float(reference.duration), best_duration_s=0.5 * (len(best.trajectory) - 1))
    if "min_dist" in best.terms or "sum_dist" in best.terms:
        measure = getattr(env, "distance_measure", Measure.PAPER)
        best_o, seed_o = outcomes(best.runs, measure), outcomes(seed.runs, measure)
        extra = {"seed_min_distance": seed_o.closest, "best_min_distance": best_o.closest,
                 "crash_rate": best_o.crash_rate, "unsafe_rate": best_o.unsafe_rate}
    return SearchMetrics(
        seed_fitness=float(seed.fitness), best_fitness=float(best.fitness), evaluations=result.evaluations,
        evaluations_to_best=result.evaluations_to_best, simulations=simulations,
        simulations_to_best=next((s for _, s, f in trace if f >= best.fitness), simulations),
        wall_seconds=round(wall_seconds, 3), trace=tuple(trace), **extra)


def _reduction(best: float | None, seed: float | None) -> float | None:
    """Table 2's ``1 - best / seed``; nan for a zero seed, None without figures."""
    if best is None or seed is None:
        return None
    return 1.0 - best / seed if seed else math.nan
