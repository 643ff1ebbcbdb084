"""Evaluating a test case: memo first, else n simulations on an executor, then the fitness; every evaluation is
stored in SQLite as it completes.

Run i of a test flies with a seed derived from (test, base seed, i) (or from (base seed, i) alone with
``SimConfig.common_noise``; a store holds one noise mode), so the same test always gets the same runs and the memo
is exact. Objectives turn the runs of a test into a :class:`Score`: a fitness (maximised), the terms behind it and
the trajectory judged. Each run keeps its trajectory, so ``evaluate(test, runs=k)`` scores the first k runs alone on
demand: from the runs already flown or stored, else by flying only those; evaluating the test in full later flies
only the rest, with the same seeds, so the result is the same as in one go.
"""
from __future__ import annotations

import math
import sqlite3
import time
from dataclasses import dataclass, field, replace
from typing import Protocol, Sequence

import numpy as np

from .errors import SurrealistError
from .fitness import generation_fitness, replication_fitness
from .metrics import frechet
from .outcomes import Measure, judged_distance, outcomes
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
    trajectory: np.ndarray | None = field(default=None, compare=False, repr=False)  # (N, 3) [m]; None: not kept

    @classmethod
    def of(cls, run) -> "RunSummary":
        """The summary of a simulated run (a RunResult or a stored run)."""
        status = getattr(run.status, "value", run.status)
        trajectory = getattr(run.trajectory, "xyz", run.trajectory)
        return cls(int(run.seed), int(run.index), str(status), float(run.min_distance),
                   float(run.min_distance_2d), float(run.duration),
                   float(getattr(run, "competition_distance", math.nan)), np.asarray(trajectory, dtype=np.float64))

    def to_dict(self) -> dict:
        """The figures as JSON values (without the trajectory)."""
        return {"seed": self.seed, "index": self.index, "status": self.status, "min_distance": self.min_distance,
                "min_distance_2d": self.min_distance_2d, "duration": self.duration,
                "competition_distance": self.competition_distance}


@dataclass(frozen=True, slots=True)
class Evaluation:
    """The evaluation of one test case.

    Attributes:
        fitness: maximised; ``-inf`` when no run could be simulated.
        terms: the fitness terms (replication: dtw, frechet; generation: sum_dist, min_dist, riskiest, unsafe).
        runs: what is kept of each run judged (with its trajectory).
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
        """The status of each run, in order."""
        return tuple(r.status for r in self.runs)


@dataclass(frozen=True)
class Score:
    """What an objective makes of the runs of a test.

    Attributes:
        fitness: maximised; ``-inf`` when no run can be judged.
        terms: the fitness terms (replication: dtw, frechet; generation: sum_dist, min_dist, riskiest, unsafe, crash).
        trajectory: the trajectory the fitness judged (replication: the average of the runs; generation: the
            riskiest run), (N, 3) [m].
    """

    fitness: float
    terms: dict = field(default_factory=dict)
    trajectory: np.ndarray | None = None


NO_SCORE = Score(-np.inf)


class Objective(Protocol):
    """Turns the runs of a test (each with a ``trajectory``: a Trajectory or (N, 3) points) into a :class:`Score`."""

    def __call__(self, test: TestCase, runs: Sequence) -> Score:
        """The score of ``test`` from its runs."""


@dataclass(frozen=True)
class ReplicationObjective:
    """Paper RQ1: ``-DTW(reference, average of the runs)``; DBA averaging, or soft-DTW as the authors' code."""

    reference: Trajectory
    averaging: str = "dba"

    def __call__(self, test, runs):
        """The fitness ``-DTW`` of the runs' average to the reference, with the DTW, Fréchet distance and average."""
        trajectories = [r.trajectory for r in runs if len(r.trajectory) > 0]
        if not trajectories:
            return NO_SCORE
        fitness, averaged = replication_fitness(self.reference, trajectories, self.averaging)
        averaged = np.asarray(getattr(averaged, "xyz", averaged))
        return Score(fitness, {"dtw": -fitness, "frechet": frechet(self.reference, averaged)}, averaged)


@dataclass(frozen=True)
class GenerationObjective:
    """Paper RQ2, eq. 2: ``-(sum_dist + 2 min_dist)`` of the riskiest run (or the mean over runs); ``measure``
    chooses the distance of ``min_dist`` and of the unsafe count (:class:`~surrealist_gym.fitness.Measure`)."""

    aggregate: str = "riskiest"
    measure: str = "paper"

    def __call__(self, test, runs):
        """The generation fitness of the flown runs against the test's obstacles, with their outcomes."""
        flown = [r for r in runs if len(r.trajectory) > 0]
        if not flown or not test.obstacles:
            return NO_SCORE
        kept = [judged_distance(r, Measure.COMPETITION) for r in flown]  # each run's own, as it was flown
        result = generation_fitness([r.trajectory for r in flown], test.obstacles, self.aggregate,
                                    measure=self.measure, competition=None if np.isnan(kept).any() else kept)
        judged = outcomes(flown, self.measure)
        terms = {"sum_dist": list(result.sum_dist), "min_dist": list(result.min_dist), "riskiest": result.riskiest,
                 "unsafe": judged.unsafe, "crash": judged.crashes}
        riskiest = flown[result.riskiest].trajectory
        return Score(result.fitness, terms, np.asarray(getattr(riskiest, "xyz", riskiest)))


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
        self._partial: dict[str, tuple[tuple[RunSummary, ...], float]] = {}  # runs flown by partial evaluations
        self._first_runs: dict[tuple[str, int], Evaluation] = {}  # first-k scores of tests known in full
        self.simulations = 0  # flown by this evaluator
        self._uncounted = 0  # of those, not yet counted in the store (a dropped candidate's runs, until the next add)
        self.replayed_seconds = 0.0  # simulation time of the evaluations read back from the store

    def reseeded(self, seed: int) -> "Evaluator":
        """An evaluator like this one whose runs draw their noise from ``seed`` (a new episode's seed), on the same
        executor, with a memo of its own. A store holds one search's evaluations, so an evaluator with a store keeps
        its seed (ValueError)."""
        if self.store is not None:
            raise ValueError(f"{self.store.path}: holds the evaluations of the search with random seed {self.seed}; "
                             f"to fly with seed {seed}, make the env with random_seed={seed} and a store of its own")
        return Evaluator(self.objective, self.runs, seed, self.sim_config, self.executor)

    def evaluate(self, test: TestCase, runs: int | None = None) -> Evaluation:
        """The evaluation of ``test``: from the memo, else the store, else simulated (and stored).

        ``runs=k`` (< n): the objective's score of the first k runs alone (``len(result.runs) == k``), not stored
        as the test's evaluation. Runs already flown or stored are reused (the score of a test known in full is
        kept, as racing and the plateau test ask for it again); those flown here are kept, so a later full
        evaluation of the test flies only the rest.
        """
        n = self.runs if runs is None else max(1, min(int(runs), self.runs))
        key = test.key()
        known = self._memo.get(key) or self._from_store(test)
        if known is not None and n == self.runs:
            return replace(known, cached=True)
        if known is not None and all(r.trajectory is not None for r in known.runs[:n]):
            if (key, n) not in self._first_runs:
                self._first_runs[key, n] = self._judge(test, known.runs[:n], 0.0, cached=True)
            return self._first_runs[key, n]
        flown, sim_seconds = self._partial.get(key, ((), 0.0))
        if len(flown) < n:
            start = time.perf_counter()
            fresh = self.executor.run(test, range(len(flown), n), self.seed, self.sim_config)
            self.simulations += len(fresh)
            self._uncounted += len(fresh)
            flown = flown + tuple(RunSummary.of(r) for r in fresh)
            sim_seconds += time.perf_counter() - start
        evaluation = self._judge(test, flown[:n], sim_seconds)
        if n < self.runs:
            self._partial[key] = flown, sim_seconds
            return evaluation
        self._partial.pop(key, None)
        self._memo[key] = evaluation
        if self.store is not None:
            self.store.add(_to_stored(evaluation, [self.seed] * self.runs, self.sim_config.common_noise),
                           simulations=self._uncounted)
            self._uncounted = 0
        return evaluation

    def _judge(self, test: TestCase, runs: tuple[RunSummary, ...], sim_seconds: float,
               cached: bool = False) -> Evaluation:
        score = self.objective(test, runs)
        return Evaluation(test, float(score.fitness), runs, dict(score.terms), score.trajectory, cached=cached,
                          sim_seconds=sim_seconds)

    def _from_store(self, test: TestCase) -> Evaluation | None:
        stored = None if self.store is None else self.store.get(test.key())
        if stored is None:
            return None
        evaluation = _from_stored(test, stored)
        self.replayed_seconds += stored.sim_seconds
        self._memo[test.key()] = evaluation
        return evaluation

    @property
    def search_simulations(self) -> int:
        """The simulations of the whole search: with a store, those of earlier processes that wrote to it too."""
        return self.simulations if self.store is None else self.store.simulations + self._uncounted

    def close(self) -> None:
        """Close the executor; with a store, first record the simulations it has not counted yet."""
        self.executor.close()
        if self.store is not None and self._uncounted:
            try:
                self.store.count_simulations(self._uncounted)
                self._uncounted = 0
            except sqlite3.Error:  # a full disk: the count of dropped candidates' runs is lost, no evaluation
                pass


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
    identity = {"problem": problem, "runs": int(runs), "seed": int(seed), "uav": sim_config.profile,
                "common_noise": bool(sim_config.common_noise), "sim": digest(sim_config), "version": __version__}
    return identity | named_physics([sim_config])


def named_physics(sim_configs) -> dict:
    """The physics of a store's flights, for its identity: named only when not PyBullet, as stores before the
    compiled physics were flown on PyBullet and named none (they resume on PyBullet only); with
    :func:`named_tree_reuse`."""
    names = sorted({c.physics.value for c in sim_configs})
    named = {} if names == ["pybullet"] else {"physics": names[0] if len(names) == 1 else names}
    return named | named_tree_reuse(sim_configs)


def named_tree_reuse(sim_configs) -> dict:
    """The tree's reuse while hovering of a store's flights, for its identity (out of ``SimConfig``'s repr): named
    only where it acts (``SimConfig.reuses_trees``), so stores whose flights it does not change resume as before."""
    reuse = sorted({f"{c.tree_reuse_m:g} m, {c.tree_reuse_cycles} cycles" for c in sim_configs if c.reuses_trees})
    return {"tree_reuse": reuse[0] if len(reuse) == 1 else reuse} if reuse else {}


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
            "trajectory": None if evaluation.trajectory is None else np.round(evaluation.trajectory, 6).tolist(),
            "run_trajectories": [None if r.trajectory is None else r.trajectory.tolist() for r in evaluation.runs]}
    if common_noise:
        info["common_noise"] = True
    return StoredEvaluation(test.key(), {"obstacles": [o.to_dict() for o in test.obstacles]}, tuple(seeds),
                            tuple(r.to_dict() for r in evaluation.runs),
                            None if not np.isfinite(evaluation.fitness) else evaluation.fitness, info,
                            sim_seconds=evaluation.sim_seconds)


def stored_runs(stored: StoredEvaluation) -> tuple[RunSummary, ...]:
    """The runs of a stored evaluation, with their trajectories when the store kept them (stores written before
    runs kept their trajectories did not: None)."""
    kept = (stored.info or {}).get("run_trajectories") or [None] * len(stored.runs)
    return tuple(RunSummary(**r, trajectory=None if t is None else np.asarray(t, dtype=np.float64).reshape(-1, 3))
                 for r, t in zip(stored.runs, kept))


def _from_stored(test: TestCase, stored: StoredEvaluation) -> Evaluation:
    """A stored evaluation; its runs keep their trajectories when the store has them (stores before they were kept
    do not)."""
    trajectory = stored.info.get("trajectory")
    fitness = -np.inf if stored.fitness is None else stored.fitness
    return Evaluation(test, fitness, stored_runs(stored), stored.info.get("terms", {}),
                      None if trajectory is None else np.asarray(trajectory), cached=True,
                      sim_seconds=stored.sim_seconds)
