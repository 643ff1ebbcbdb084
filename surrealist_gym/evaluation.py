"""Evaluating a test case: memo first, else n simulations on an executor, then the fitness; every evaluation is
stored in SQLite as it completes.

Run i of a test flies with a seed derived from (test, base seed, i) (or from (base seed, i) alone with
``SimConfig.common_noise``; a store holds one noise mode), so the same test always gets the same runs and the memo
is exact. Objectives turn the runs of a test into a :class:`Score`: a fitness (maximised), the terms behind it and
the trajectory judged; the term ``first_runs_fitness`` holds the fitness of its first k runs alone (k = 1 .. n-1), so a search can judge a
partial evaluation, and (replication) ``Evaluation.first_runs_trajectories`` the first k runs' averaged
trajectories, so a partial evaluation's trajectory can be compared like for like. ``evaluate(test, runs=k)`` flies
only the first k runs; evaluating the test in full later flies only the rest, with the same seeds, so the result is
the same as in one go.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Protocol, Sequence

import numpy as np

from .errors import SurrealistError
from .fitness import MIN_DIST_WEIGHT, Aggregate, average_runs, generation_fitness
from .metrics import dtw, frechet
from .outcomes import outcomes
from .store import EvaluationStore, StoredEvaluation
from .testcase import TestCase
from .trajectory import Trajectory


@dataclass(frozen=True, slots=True)
class RunSummary:
    """What the search keeps of one run."""

    seed: int                # base seed; the run's noise derives from (test, seed, index), or (seed, index)
    index: int
    status: str
    min_distance: float      # 3-D, over all obstacles [m]
    min_distance_2d: float   # footprint distance, as the paper [m]
    duration: float          # simulated seconds
    competition_distance: float = math.nan  # footprint to the trajectory's polyline, as Aerialist [m] (nan: not kept)

    @classmethod
    def of(cls, run) -> "RunSummary":
        status = getattr(run.status, "value", run.status)
        return cls(int(run.seed), int(run.index), str(status), float(run.min_distance),
                   float(run.min_distance_2d), float(run.duration),
                   float(getattr(run, "competition_distance", math.nan)))

    def to_dict(self) -> dict:
        return {"seed": self.seed, "index": self.index, "status": self.status, "min_distance": self.min_distance,
                "min_distance_2d": self.min_distance_2d, "duration": self.duration,
                "competition_distance": self.competition_distance}


@dataclass(frozen=True, slots=True)
class Evaluation:
    """The evaluation of one test case.

    Attributes:
        fitness: maximised; ``-inf`` when no run could be simulated.
        terms: the fitness terms (replication: dtw, frechet; generation: sum_dist, min_dist, riskiest, unsafe).
        trajectory: the trajectory the fitness judged (replication: the average of the runs; generation: the
            riskiest run), (N, 3) [m].
        first_runs_trajectories: replication: the averaged trajectory of the first k runs alone (k = 1 .. n-1), to
            compare a partial evaluation's trajectory with this one's over the same runs; () when not kept.
        cached: True when answered without simulating: from the evaluator's memory or its store (a resumed
            search reads back what the interrupted one simulated). Whether it costs budget is the env's call.
    """

    test: TestCase
    fitness: float
    runs: tuple[RunSummary, ...]
    terms: dict = field(default_factory=dict)
    trajectory: np.ndarray | None = None
    first_runs_trajectories: tuple[np.ndarray, ...] = ()
    cached: bool = False
    sim_seconds: float = 0.0

    @property
    def statuses(self) -> tuple[str, ...]:
        return tuple(r.status for r in self.runs)


@dataclass(frozen=True)
class Score:
    """What an objective makes of the runs of a test.

    Attributes:
        fitness: maximised; ``-inf`` when no run can be judged.
        terms: the fitness terms (replication: dtw, frechet; generation: sum_dist, min_dist, riskiest, unsafe, crash;
            both: ``first_runs_fitness``, the fitness of the first k runs alone, k = 1 .. n-1).
        trajectory: the trajectory the fitness judged (replication: the average of the runs; generation: the
            riskiest run), (N, 3) [m].
        first_runs_trajectories: replication: the trajectory judged on the first k runs alone (k = 1 .. n-1).
    """

    fitness: float
    terms: dict = field(default_factory=dict)
    trajectory: np.ndarray | None = None
    first_runs_trajectories: tuple[np.ndarray, ...] = ()


NO_SCORE = Score(-np.inf)


class Objective(Protocol):
    """Turns the simulated runs of a test into a :class:`Score`."""

    def __call__(self, test: TestCase, runs: Sequence) -> Score: ...


@dataclass(frozen=True)
class ReplicationObjective:
    """Paper RQ1: ``-DTW(reference, average of the runs)``; DBA averaging, or soft-DTW as the authors' code."""

    reference: Trajectory
    averaging: str = "dba"

    def __call__(self, test, runs):
        trajectories = [r.trajectory for r in runs if len(r.trajectory) > 0]
        if not trajectories:
            return NO_SCORE
        averaged = np.asarray(average_runs(trajectories, self.averaging))
        first_averaged = tuple(np.asarray(average_runs(trajectories[:k], self.averaging))
                               for k in range(1, len(trajectories)))
        distance = dtw(self.reference, averaged)
        return Score(-distance, {"dtw": distance, "frechet": frechet(self.reference, averaged),
                                 "first_runs_fitness": [-dtw(self.reference, t) for t in first_averaged]},
                     averaged, first_averaged)


@dataclass(frozen=True)
class GenerationObjective:
    """Paper RQ2, eq. 2: ``-(sum_dist + 2 min_dist)`` of the riskiest run (or the mean over runs); ``measure``
    chooses the distance of ``min_dist`` and of the unsafe count (:class:`~surrealist_gym.fitness.Measure`)."""

    aggregate: str = "riskiest"
    measure: str = "paper"

    def __call__(self, test, runs):
        flown = [r for r in runs if len(r.trajectory) > 0]
        if not flown or not test.obstacles:
            return NO_SCORE
        result = generation_fitness([r.trajectory for r in flown], test.obstacles, self.aggregate,
                                    measure=self.measure)
        judged = outcomes(flown, self.measure)
        terms = {"sum_dist": list(result.sum_dist), "min_dist": list(result.min_dist), "riskiest": result.riskiest,
                 "unsafe": judged.unsafe, "crash": judged.crashes,
                 "first_runs_fitness": _first_runs_fitness(result)}
        return Score(result.fitness, terms, np.asarray(flown[result.riskiest].trajectory.xyz))


def _first_runs_fitness(result) -> list[float]:
    """Generation fitness of the first k runs alone, k = 1 .. n-1, from the per-run distances."""
    scores = np.asarray(result.sum_dist) + MIN_DIST_WEIGHT * np.asarray(result.min_dist)
    if result.aggregate is Aggregate.RISKIEST:
        first = np.minimum.accumulate(scores)
    else:
        first = np.cumsum(scores) / np.arange(1, len(scores) + 1)
    return [float(-v) for v in first[:-1]]


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
        self.sim_config = SimConfig.coerce(sim_config)  # a mapping from gym.make or compare's env_kwargs too
        self.executor = make_executor(executor)
        self.store = store
        if store is not None:
            _check_noise_mode(store, self.sim_config.common_noise)
            store.claim(search_identity(objective, runs, seed, self.sim_config))
        self._memo: dict[str, Evaluation] = {}
        self._flown: dict[str, list] = {}  # the runs of partial evaluations, by test key
        self._flown_seconds: dict[str, float] = {}
        self.simulations = 0
        self.replayed_seconds = 0.0  # simulation time of the evaluations read back from the store

    def evaluate(self, test: TestCase, runs: int | None = None) -> Evaluation:
        """The evaluation of ``test``: from the memo, else the store, else simulated (and stored).

        ``runs=k`` (< n): a partial evaluation judged on the first k runs alone (the fitness of the objective on
        them; ``len(result.runs) == k``), neither stored nor memoised as the test's evaluation; its runs are kept, so
        a later full evaluation of the test flies only the remaining ones. A test already evaluated in full is
        answered from its ``first_runs_fitness`` term without flying (one stored without it flies its first runs).
        """
        n = self.runs if runs is None else max(1, min(int(runs), self.runs))
        key = test.key()
        known = self._memo.get(key) or self._from_store(test)
        if known is not None and (n == self.runs or len(known.terms.get("first_runs_fitness") or ()) >= n):
            return _as_cached(known) if n == self.runs else _first_runs(known, n)
        flown = self._flown.get(key, [])
        start = time.perf_counter()
        if len(flown) < n:
            fresh = self.executor.run(test, range(len(flown), n), self.seed, self.sim_config)
            self.simulations += len(fresh)
            flown = flown + list(fresh)
        sim_seconds = self._flown_seconds.pop(key, 0.0) + time.perf_counter() - start
        score = self.objective(test, flown)
        evaluation = Evaluation(test, float(score.fitness), tuple(RunSummary.of(r) for r in flown), dict(score.terms),
                                score.trajectory, tuple(score.first_runs_trajectories), cached=False,
                                sim_seconds=sim_seconds)
        if n < self.runs:
            self._flown[key], self._flown_seconds[key] = flown, sim_seconds
            return evaluation
        self._flown.pop(key, None)
        self._memo[key] = evaluation
        if self.store is not None:
            self.store.add(_to_stored(evaluation, [self.seed] * self.runs, self.sim_config.common_noise))
        return evaluation

    def _from_store(self, test: TestCase) -> Evaluation | None:
        stored = None if self.store is None else self.store.get(test.key())
        if stored is None:
            return None
        evaluation = _from_stored(test, stored)
        self.replayed_seconds += stored.sim_seconds
        self._memo[test.key()] = evaluation
        return evaluation

    def close(self) -> None:
        self.executor.close()


def _as_cached(evaluation: Evaluation) -> Evaluation:
    return Evaluation(evaluation.test, evaluation.fitness, evaluation.runs, evaluation.terms, evaluation.trajectory,
                      evaluation.first_runs_trajectories, cached=True)


def _first_runs(evaluation: Evaluation, k: int) -> Evaluation:
    """A full evaluation judged on its first k runs alone (from its ``first_runs_fitness`` term, and its first k
    runs' trajectory when kept)."""
    first = evaluation.terms["first_runs_fitness"]
    trajectories = evaluation.first_runs_trajectories
    return Evaluation(evaluation.test, float(first[k - 1]), evaluation.runs[:k], {"first_runs_fitness": first[:k - 1]},
                      trajectories[k - 1] if len(trajectories) >= k else None, trajectories[:k - 1], cached=True)


def search_identity(objective, runs: int, seed: int, sim_config) -> dict:
    """What every stored fitness of a search depends on: the problem (objective and its settings, a replication's
    reference trajectory by digest), the runs per evaluation, the base seed, the simulator settings (digest, with the
    UAV profile's name) and, recorded but not compared, the package version."""
    import hashlib
    from dataclasses import fields, is_dataclass

    from . import __version__

    def digest(value) -> str:
        return hashlib.sha1(value if isinstance(value, bytes) else repr(value).encode()).hexdigest()[:16]

    problem = {"objective": type(objective).__name__}
    if is_dataclass(objective):
        for f in fields(objective):
            value = getattr(objective, f.name)
            xyz = getattr(value, "xyz", value)
            problem[f.name] = (digest(np.round(np.asarray(xyz, dtype=np.float64), 6).tobytes())
                               if isinstance(xyz, np.ndarray) else getattr(value, "value", value))
    return {"problem": problem, "runs": int(runs), "seed": int(seed), "uav": sim_config.profile,
            "common_noise": bool(sim_config.common_noise), "sim": digest(sim_config), "version": __version__}


def flown_with_common_noise(stored: StoredEvaluation) -> bool:
    """The noise mode a stored evaluation was flown with (``SimConfig.common_noise``)."""
    return bool((stored.info or {}).get("common_noise", False))


def describe_noise(common_noise: bool | None) -> str:
    """A noise mode in words, for messages (None: evaluations of both modes)."""
    if common_noise is None:
        return "a mix of both noise modes"
    return "common noise" if common_noise else "each test's own noise"


def _check_noise_mode(store: EvaluationStore, common_noise: bool) -> None:
    """A store holds one noise mode: reading back evaluations flown under the other would mix two problems."""
    first = next(iter(store), None)
    if first is not None and flown_with_common_noise(first) != common_noise:
        held = describe_noise(not common_noise)
        raise SurrealistError(f"{store.path}: holds evaluations flown with {held}, this search flies with "
                              f"{'common' if common_noise else 'its own'} noise (use another store or results "
                              f"folder, or match --common-noise)")


def _to_stored(evaluation: Evaluation, seeds, common_noise: bool = False) -> StoredEvaluation:
    test = evaluation.test
    info = {"terms": evaluation.terms,
            "trajectory": None if evaluation.trajectory is None else np.round(evaluation.trajectory, 6).tolist()}
    if evaluation.first_runs_trajectories:
        info["first_runs_trajectories"] = [np.round(t, 6).tolist() for t in evaluation.first_runs_trajectories]
    if common_noise:
        info["common_noise"] = True
    return StoredEvaluation(test.key(), {"obstacles": [o.to_dict() for o in test.obstacles]}, tuple(seeds),
                            tuple(r.to_dict() for r in evaluation.runs),
                            None if not np.isfinite(evaluation.fitness) else evaluation.fitness, info,
                            sim_seconds=evaluation.sim_seconds)


def _from_stored(test: TestCase, stored: StoredEvaluation) -> Evaluation:
    trajectory = stored.info.get("trajectory")
    fitness = -np.inf if stored.fitness is None else stored.fitness
    return Evaluation(test, fitness, tuple(RunSummary(**r) for r in stored.runs), stored.info.get("terms", {}),
                      None if trajectory is None else np.asarray(trajectory),
                      tuple(np.asarray(t) for t in stored.info.get("first_runs_trajectories", ())), cached=True,
                      sim_seconds=stored.sim_seconds)
