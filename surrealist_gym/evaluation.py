"""Evaluating a test case: memo first, else n simulations on an executor, then the fitness; every evaluation is
stored in SQLite as it completes.

Run i of a test flies with a seed derived from (test, base seed, i), so the same test always gets the same runs
and the memo is exact. Objectives turn the runs of a test into a fitness (maximised) and the terms behind it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Protocol, Sequence

import numpy as np

from .fitness import average_runs, generation_fitness, is_unsafe
from .metrics import dtw, frechet
from .store import EvaluationStore, StoredEvaluation
from .testcase import TestCase
from .trajectory import Trajectory


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What the search keeps of one run."""

    seed: int                # base seed; the run's noise derives from (test, seed, index)
    index: int
    status: str
    min_distance: float      # 3-D, over all obstacles [m]
    min_distance_2d: float   # footprint distance, as the paper [m]
    duration: float          # simulated seconds

    @classmethod
    def of(cls, run) -> "RunSummary":
        status = getattr(run.status, "value", run.status)
        return cls(int(run.seed), int(run.index), str(status), float(run.min_distance),
                   float(run.min_distance_2d), float(run.duration))

    def to_dict(self) -> dict:
        return {"seed": self.seed, "index": self.index, "status": self.status, "min_distance": self.min_distance,
                "min_distance_2d": self.min_distance_2d, "duration": self.duration}


@dataclass(frozen=True, slots=True)
class Evaluation:
    """The evaluation of one test case.

    Attributes:
        fitness: maximised; ``-inf`` when no run could be simulated.
        terms: the fitness terms (replication: dtw, frechet; generation: sum_dist, min_dist, riskiest, unsafe).
        trajectory: the trajectory the fitness judged (replication: the average of the runs; generation: the
            riskiest run), (N, 3) [m].
        cached: True when answered without simulating: from the evaluator's memory or its store (a resumed
            search reads back what the interrupted one simulated). Whether it costs budget is the env's call.
    """

    test: TestCase
    fitness: float
    runs: tuple[RunSummary, ...]
    terms: dict = field(default_factory=dict)
    trajectory: np.ndarray | None = None
    cached: bool = False
    sim_seconds: float = 0.0

    @property
    def statuses(self) -> tuple[str, ...]:
        return tuple(r.status for r in self.runs)


class Objective(Protocol):
    """Turns the simulated runs of a test into ``(fitness, terms, judged trajectory)``."""

    def __call__(self, test: TestCase, runs: Sequence) -> tuple[float, dict, np.ndarray | None]: ...


@dataclass(frozen=True)
class ReplicationObjective:
    """Paper RQ1: ``-DTW(reference, average of the runs)``; DBA averaging, or soft-DTW as the authors' code."""

    reference: Trajectory
    averaging: str = "dba"

    def __call__(self, test, runs):
        trajectories = [r.trajectory for r in runs if len(r.trajectory) > 0]
        if not trajectories:
            return -np.inf, {}, None
        averaged = np.asarray(average_runs(trajectories, self.averaging))
        return (-dtw(self.reference, averaged),
                {"dtw": dtw(self.reference, averaged), "frechet": frechet(self.reference, averaged)}, averaged)


@dataclass(frozen=True)
class GenerationObjective:
    """Paper RQ2, eq. 2: ``-(sum_dist + 2 min_dist)`` of the riskiest run (or the mean over runs)."""

    aggregate: str = "riskiest"

    def __call__(self, test, runs):
        flown = [r for r in runs if len(r.trajectory) > 0]
        if not flown or not test.obstacles:
            return -np.inf, {}, None
        result = generation_fitness([r.trajectory for r in flown], test.obstacles, self.aggregate)
        terms = {"sum_dist": list(result.sum_dist), "min_dist": list(result.min_dist), "riskiest": result.riskiest,
                 "unsafe": sum(is_unsafe(r.min_distance_2d) for r in flown),
                 "crash": sum(str(getattr(r.status, "value", r.status)) == "collision" for r in flown)}
        return result.fitness, terms, np.asarray(flown[result.riskiest].trajectory.xyz)


class Evaluator:
    """Memo + store + executor + objective. One per search."""

    def __init__(self, objective: Objective, runs: int = 5, seed: int = 0, sim_config=None, executor=None,
                 store: EvaluationStore | None = None):
        from .executors import make_executor
        from .sim import SimConfig

        if runs < 1:
            raise ValueError(f"runs must be >= 1, got {runs}")
        self.objective = objective
        self.runs = runs
        self.seed = seed
        self.sim_config = sim_config if sim_config is not None else SimConfig()
        self.executor = make_executor(executor)
        self.store = store
        self._memo: dict[str, Evaluation] = {}
        self.simulations = 0
        self.replayed_seconds = 0.0  # simulation time of the evaluations read back from the store

    def evaluate(self, test: TestCase) -> Evaluation:
        key = test.key()
        if key in self._memo:
            return _as_cached(self._memo[key])
        if self.store is not None:
            stored = self.store.get(key)
            if stored is not None:
                evaluation = _from_stored(test, stored)
                self.replayed_seconds += stored.sim_seconds
                self._memo[key] = evaluation
                return evaluation
        start = time.perf_counter()
        results = self.executor.run(test, range(self.runs), self.seed, self.sim_config)
        sim_seconds = time.perf_counter() - start
        self.simulations += self.runs
        fitness, terms, trajectory = self.objective(test, results)
        evaluation = Evaluation(test, float(fitness), tuple(RunSummary.of(r) for r in results), terms,
                                trajectory, cached=False, sim_seconds=sim_seconds)
        self._memo[key] = evaluation
        if self.store is not None:
            self.store.add(_to_stored(evaluation, [self.seed] * self.runs))
        return evaluation

    def close(self) -> None:
        self.executor.close()


def _as_cached(evaluation: Evaluation) -> Evaluation:
    return Evaluation(evaluation.test, evaluation.fitness, evaluation.runs, evaluation.terms, evaluation.trajectory,
                      cached=True)


def _to_stored(evaluation: Evaluation, seeds) -> StoredEvaluation:
    test = evaluation.test
    info = {"terms": evaluation.terms,
            "trajectory": None if evaluation.trajectory is None else np.round(evaluation.trajectory, 6).tolist()}
    return StoredEvaluation(test.key(), {"obstacles": [o.to_dict() for o in test.obstacles]}, tuple(seeds),
                            tuple(r.to_dict() for r in evaluation.runs),
                            None if not np.isfinite(evaluation.fitness) else evaluation.fitness, info,
                            sim_seconds=evaluation.sim_seconds)


def _from_stored(test: TestCase, stored: StoredEvaluation) -> Evaluation:
    trajectory = stored.info.get("trajectory")
    fitness = -np.inf if stored.fitness is None else stored.fitness
    return Evaluation(test, fitness, tuple(RunSummary(**r) for r in stored.runs), stored.info.get("terms", {}),
                      None if trajectory is None else np.asarray(trajectory), cached=True,
                      sim_seconds=stored.sim_seconds)
