"""Re-evaluation of a suite of Aerialist tests: fly each test N times and report how often and how badly it fails.

Any folder of Aerialist YAMLs (a generator's output, the competition's) is flown ``runs`` times per test; run i of a
test draws its noise from (test key, seed, i). A run **fails** when it collides or its competition distance
(:attr:`~surrealist_gym.sim.runner.RunResult.competition_distance`) is below 1.5 m. Per test (:class:`TestStats`): the
failure probability with its 95% Clopper-Pearson interval, the competition's points
(:func:`~surrealist_gym.competition.rules.points`; a collision scores 5) as a mean per run and for the median run, and
the closest approach. A run that ends in ``error`` (its simulation raised, or the vehicle's state became invalid) is
neither a pass nor a failure: it is counted apart, and the figures are over the runs flown. Per suite
(:class:`Evaluation`): the failing tests' closest runs offered in turn to a
:class:`~surrealist_gym.competition.suite.Suite` (distinct failures) and their
:func:`~surrealist_gym.competition.suite.diversity`.

The tests are flown by :func:`~surrealist_gym.executors.fly_many` on local workers or a Dask cluster, several at a
time, so every worker stays busy: whole tests (their runs in one world) first, the last round split run by run so that
no worker idles at the end; each run is a :class:`~surrealist_gym.outcomes.RunRecord`. Given a ``store``, each chunk
of runs is written to it (an :class:`~surrealist_gym.store.EvaluationStore`) as it completes, and the runs it holds
already are read back instead of flown: an interrupted evaluation resumes and loses nothing.
:func:`~surrealist_gym.competition.reports.evaluation.write_report` writes the report whole or not at all.

Example::

    >>> tests = load_tests(["../shared/data/competition/camba-collection"])     # doctest: +SKIP
    >>> ev = evaluate(tests, runs=5, workers=2)                                  # doctest: +SKIP
    >>> write_report(ev, "results/camba")                                        # doctest: +SKIP
"""
from __future__ import annotations

import hashlib
import math
import os
import sqlite3
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from ..errors import FrozenDict, InvalidTestCase, SurrealistError, one_line
from ..outcomes import RunRecord, statuses_text
from ..testcase import TestCase
from .reports.tables import rounded

if TYPE_CHECKING:
    from .suite import Suite

__all__ = ["CONFIDENCE", "Evaluation", "TestStats", "evaluate", "evaluation_identity", "regroup", "stored_runs",
           "summarise_test", "uav_decisions"]

CONFIDENCE = 0.95  # of the failure probability's Clopper-Pearson interval


# --- flying -------------------------------------------------------------------------------------------------------
def uav_decisions(tests: Sequence[tuple[Path, TestCase]], uav=None, buffer: float = 0.0) -> list:
    """The UAV each test flies (:func:`~surrealist_gym.sim.uav.decide_uav`: ``uav``, else the test's own), with the
    competition distance's ``buffer``; a bad profile fails once, and a test whose ``uav.*`` settings its UAV cannot
    take (an unknown planner field, a value out of range) is a one-line InvalidTestCase naming its file, before any
    flight."""
    from ..sim.uav import decide_uav

    if uav is not None:
        uav = decide_uav(uav=uav).profile
    decisions = []
    for path, test in tests:
        try:
            decisions.append(decide_uav(test, uav, config={"competition_buffer_m": buffer}))
        except InvalidTestCase as err:
            raise InvalidTestCase(f"{path}: {err}") from None
    return decisions


# --- statistics ----------------------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True, eq=False)
class TestStats:
    """One test's runs and what they come to.

    Attributes:
        file: the YAML. uav: the UAV profile flown. runs: the runs, in run order.
        failures: failing runs; errors: runs that ended in ``error`` (neither passing nor failing); the other figures
            are over the runs flown (``flown``: runs - errors).
        p: the share of the flown runs that fail; ci_low, ci_high: its 95% Clopper-Pearson interval (all nan when
            no run was flown).
        points_mean: the competition's points per run; points_median_run: the points of the median run (runs
            ordered by distance, collisions first; of an even number, the farther of the two middle runs; None
            when no run was flown).
        min_distance, median_distance: the closest approach over the runs [m] (nan without a finite distance).
        suite: what the failure suite said when offered the test's closest failing run ("" for a passing test).
    """

    __test__ = False  # not a pytest class

    file: str
    test: TestCase
    uav: str
    runs: tuple[RunRecord, ...]
    failures: int
    errors: int
    p: float
    ci_low: float
    ci_high: float
    points_mean: float
    points_median_run: int | None
    min_distance: float
    median_distance: float
    suite: str = ""

    @property
    def name(self) -> str:
        """The test file's name without its suffix."""
        return Path(self.file).stem

    @property
    def flown(self) -> int:
        """Runs that did not end in ``error``: the runs the figures are over."""
        return len(self.runs) - self.errors

    @property
    def statuses(self) -> str:
        """How the runs ended, e.g. ``success:4 collision:1``."""
        return statuses_text(self.runs)

    @property
    def closest_failure(self) -> RunRecord | None:
        """The failing run that came closest (a collision first), or None."""
        return next((r for r in _by_risk(self.runs) if r.failed), None)

    def to_row(self) -> dict:
        """The row of ``evaluation.csv``."""
        return {"file": self.file, "runs": len(self.runs), "failures": self.failures, "errors": self.errors,
                "p": rounded(self.p), "ci_low": rounded(self.ci_low), "ci_high": rounded(self.ci_high),
                "points_mean": rounded(self.points_mean),
                "points_median_run": "" if self.points_median_run is None else self.points_median_run,
                "min_distance": rounded(self.min_distance), "median_distance": rounded(self.median_distance),
                "statuses": self.statuses, "uav": self.uav, "suite": self.suite}


def _by_risk(runs: Sequence[RunRecord]) -> list[RunRecord]:
    """The runs, collisions first, then by distance (closest first), then by index."""
    return sorted(runs, key=lambda r: (r.status != "collision", r.distance, r.index))


def summarise_test(file, test: TestCase, runs: Sequence[RunRecord], uav: str = "") -> TestStats:
    """The statistics of one test's runs: over the runs flown; those that ended in ``error`` are counted apart."""
    from scipy.stats import binomtest

    flown = [r for r in runs if r.flown]
    n, k = len(flown), sum(r.failed for r in flown)
    low = high = math.nan
    if n:
        ci = binomtest(k, n).proportion_ci(confidence_level=CONFIDENCE, method="exact")
        low, high = float(ci.low), float(ci.high)
    finite = [r.distance for r in flown if math.isfinite(r.distance)]
    return TestStats(os.fspath(file), test, uav, tuple(runs), k, len(runs) - n, k / n if n else math.nan, low, high,
                     float(np.mean([r.points for r in flown])) if n else math.nan,
                     _by_risk(flown)[n // 2].points if n else None,
                     float(np.min(finite)) if finite else math.nan, float(np.median(finite)) if finite else math.nan)


@dataclass(frozen=True, slots=True, eq=False)
class Evaluation:
    """A suite re-evaluated: its tests' statistics, the distinct failures and their diversity.

    Attributes:
        runs, seed: runs per test and base seed; uav: the profile given (None: each test's default). tests: per-test
        statistics, in input order. suite: the distinct failures (a :class:`~surrealist_gym.competition.suite.Suite` of
        the failing tests' closest runs). diversity: their :func:`~surrealist_gym.competition.suite.diversity` over all
        failing tests. workers, wall_s: the executor's workers (local processes or Dask workers) and flying time [s]
        (of this call). stored: runs read back from the store, flown before this call.
    """

    runs: int
    seed: int
    uav: str | None
    tests: tuple[TestStats, ...]
    suite: "Suite"
    diversity: FrozenDict
    workers: int
    wall_s: float
    stored: int = 0

    @property
    def failing(self) -> tuple[TestStats, ...]:
        """The tests with at least one failing run."""
        return tuple(t for t in self.tests if t.failures)


def evaluate(tests: Sequence[tuple[Path, TestCase]], runs: int = 5, seed: int = 0, uav=None,
             workers: int | None = None, progress: Callable[[int, int], None] | None = None, store=None,
             identity: dict | None = None, buffer: float = 0.0, executor=None) -> Evaluation:
    """Fly ``runs`` runs of each (file, test) (from :func:`load_tests`) and compute the report's figures.

    ``uav``: a profile name, YAML or :class:`~surrealist_gym.sim.profiles.UavProfile` for every test (default: each
    test's own, :func:`~surrealist_gym.sim.uav.decide_uav`). ``store``: an SQLite file
    (:class:`~surrealist_gym.store.EvaluationStore`) that holds this evaluation's runs: those it holds are read back,
    not flown, and each chunk flown is written to it as it completes. It records the evaluation's identity
    (:func:`evaluation_identity`, with ``identity``: anything else the runs depend on), so a store of another
    evaluation is refused in one line. ``buffer``: the competition distance's polyline buffer [m] (``--buffer``,
    ``SimConfig.competition_buffer_m``). ``executor``: where the runs fly, a Dask scheduler's address, a
    ``distributed.Client`` or an executor (:func:`~surrealist_gym.executors.make_executor`; default ``workers``
    local processes, all cores and at most 8; 1: this process)."""
    from ..executors import executor_for, fly_many
    from .suite import Suite

    if runs < 1:
        raise SurrealistError(f"runs: expected a whole number >= 1, got {runs!r}")
    decisions = uav_decisions(tests, uav, buffer)
    configs = [d.config for d in decisions]
    have: list[dict] = [{} for _ in tests]
    db = None
    with executor_for(executor, workers) as flying:
        try:
            if store is not None:
                from ..store import EvaluationStore

                db = EvaluationStore(store)
                db.claim({**evaluation_identity(tests, runs, seed, configs), **(identity or {})})
                for row in db:
                    have[row.info["test"]].update(
                        (r["index"], RunRecord.from_dict(r, t)) for r, t in zip(row.runs, row.info["trajectories"]))
            start = time.perf_counter()
            flown = fly_many([t for _, t in tests], runs, seed, configs, flying, progress=progress, have=have,
                             done=None if db is None else lambda i, records: _store(db, i, *tests[i], records))
            wall = time.perf_counter() - start
        finally:
            if db is not None:
                db.close()
    stats = [summarise_test(path, test, records, decision.name)
             for (path, test), records, decision in zip(tests, flown, decisions)]
    return _with_suite(Evaluation(runs, seed, None if uav is None else decisions[0].name, tuple(stats), Suite(),
                                  FrozenDict(), flying.workers, wall, sum(map(len, have))))


def _with_suite(ev: Evaluation) -> Evaluation:
    """The evaluation with its tests' closest failing runs offered in order to a new Suite, and their diversity."""
    from .suite import Member, Suite, diversity

    stats, suite, members = list(ev.tests), Suite(), []
    for i, st in enumerate(stats):
        if (run := st.closest_failure) is not None:
            members.append(Member(st.test, run.distance, run.trajectory, evaluation=i + 1, status=run.status))
            suite, what = suite.offer(members[-1])
            stats[i] = replace(st, suite=what)
    return replace(ev, tests=tuple(stats), suite=suite, diversity=FrozenDict(diversity(members)))


def regroup(ev: Evaluation, order: Sequence[int], files: Sequence) -> Evaluation:
    """The evaluation of the same runs with its tests in another ``order`` (indices into ``ev.tests``) and named by
    ``files``; the distinct failures and diversity are those of the new order."""
    return _with_suite(replace(ev, tests=tuple(replace(ev.tests[i], file=os.fspath(f), suite="")
                                               for i, f in zip(order, files))))


def evaluation_identity(tests: Sequence[tuple[Path, TestCase]], runs: int, seed: int, configs: Sequence) -> dict:
    """What the runs of an evaluation depend on: its tests (file and a digest of ``TestCase.key()``, in order), the
    runs per test, the base seed, the UAV profiles, the simulator settings (digest) and physics; and, recorded but
    not compared, the package version."""
    from .. import __version__
    from ..evaluation import named_physics

    def digest(value) -> str:
        return hashlib.sha1(value.encode()).hexdigest()[:16]

    return {"command": "evaluate", "tests": [[os.fspath(path), digest(test.key())] for path, test in tests],
            "runs": int(runs), "seed": int(seed), "uav": sorted({c.profile for c in configs}),
            "sim": digest(repr(list(configs))), "version": __version__} | named_physics(configs)


def stored_runs(store, tests: Sequence[TestCase]) -> list[tuple[RunRecord, ...]]:
    """The runs a search flew of each test, read from its store (``evaluations.sqlite``), as the re-evaluation keeps
    runs (without their trajectories); empty for a test the store does not hold."""
    from ..store import EvaluationStore

    with EvaluationStore(store) as db:
        rows = [db.get(test.key()) for test in tests]
    return [() if row is None else tuple(
        RunRecord(int(r["index"]), str(r["status"]), float(r.get("competition_distance", math.nan)),
                  float(r["duration"])) for r in row.runs) for row in rows]


def _store(db, i: int, path, test: TestCase, records: list[RunRecord]) -> None:
    """Write a chunk of runs of test ``i`` (with their trajectories, for the report) and commit it."""
    from ..store import StoredEvaluation

    try:
        db.add(StoredEvaluation(test.key(), {"file": os.fspath(path)}, tuple(r.index for r in records),
                                tuple(r.to_dict() for r in records), None,
                                {"test": i, "trajectories": [r.trajectory.xyz.tolist() for r in records]}))
    except (sqlite3.Error, OSError) as err:
        raise SurrealistError(f"{db.path}: cannot store the runs ({one_line(err)}); the runs stored before are "
                              f"kept, and resuming flies the rest") from None
