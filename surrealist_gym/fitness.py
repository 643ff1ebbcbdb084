"""Fitness functions of the paper's two search problems (both maximised), pure functions over trajectories.

* Replication (Section 3.2): ``-DTW(reference, barycenter of the n simulated runs)``.
* Generation (Section 3.3, eq. 2): a run's score is ``sum_dist + 2 * min_dist`` with ``sum_dist`` the minimum over
  trajectory points of the summed distances to all obstacles and ``min_dist`` the minimum over points and
  obstacles; a test scores as its riskiest run (smallest score), or, as an option, the mean; fitness = -score.

Distances to obstacles are the paper's 2-D footprint distances by default (``dims=3`` accounts for height). With
``measure="competition"`` a run's ``min_dist`` is the UAV Testing Competition's (Aerialist's) distance instead: box
footprint to the polyline of the trajectory (:func:`~surrealist_gym.geometry.competition_distance`).

Example:
    >>> import numpy as np
    >>> from surrealist_gym.testcase import Obstacle
    >>> run = np.array([[0.0, 0.0, 2.0], [5.0, 0.0, 2.0]])
    >>> box = Obstacle(l=2, w=2, h=5, x=5, y=4)
    >>> generation_fitness([run], [box]).fitness   # min_dist 3 m, sum_dist 3 m -> -(3 + 2*3)
    -9.0
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Sequence

import numpy as np

from .geometry import competition_distance, obstacle_distances
from .metrics import TrajectoryLike, dba, dtw, soft_dtw_barycenter
from .outcomes import Measure
from .testcase import Obstacle
from .trajectory import as_points

MIN_DIST_WEIGHT = 2.0


class Averaging(str, Enum):
    """How the n runs of one test are averaged before the DTW to the reference."""

    DBA = "dba"  #: DTW Barycenter Averaging, as the paper states
    SOFT_DTW = "soft_dtw"  #: soft-DTW barycenter (gamma 20), as the paper's code did


class Aggregate(str, Enum):
    """How the n runs of one test are combined into the generation fitness."""

    RISKIEST = "riskiest"  #: the run with the smallest score, as the paper and its code do
    MEAN = "mean"  #: the mean score over the runs


def _choice(enum: type[Enum], value, name: str):
    try:
        return enum(value)
    except ValueError as err:
        options = ", ".join(repr(m.value) for m in enum)
        raise ValueError(f"{name}: expected one of {options}, got {value!r}") from err


def average_runs(runs: Sequence[TrajectoryLike], averaging: Averaging | str = Averaging.DBA,
                 gamma: float = 20.0):
    """The averaged trajectory of the runs (a single run is returned as it is)."""
    method = _choice(Averaging, averaging, "averaging")
    runs = list(runs)
    if not runs:
        raise ValueError("runs: expected at least one run, got none")
    if len(runs) == 1:
        return runs[0]
    if method is Averaging.DBA:
        return dba(runs)
    return soft_dtw_barycenter(runs, gamma=gamma)


def replication_fitness(reference: TrajectoryLike, runs: Sequence[TrajectoryLike],
                        averaging: Averaging | str = Averaging.DBA, gamma: float = 20.0):
    """Fitness of a replication test: ``-dtw(reference, average of the runs)`` (maximised; 0 is perfect).

    Args:
        reference: the real flight's trajectory.
        runs: the n simulated runs of the test (a single run is used as it is).
        averaging: ``"dba"`` (default, the paper's text) or ``"soft_dtw"`` (the paper's code).
        gamma: soft-DTW smoothing [m^2], used with ``"soft_dtw"`` only.

    Returns:
        ``(fitness, averaged_trajectory)``; the average is a Trajectory when the runs are Trajectories.
    """
    averaged = average_runs(runs, averaging, gamma)
    return -dtw(reference, averaged), averaged


@dataclass(frozen=True, slots=True)
class GenerationFitness:
    """Generation fitness of one test over its runs (paper eq. 2); distances in metres.

    Attributes:
        fitness: ``-score`` of the test (maximised).
        sum_dist: per run, min over points of the summed distances to all obstacles [m].
        min_dist: per run, min over points and obstacles [m].
        riskiest: index of the run with the smallest score (ties: the first).
        aggregate: how the runs were combined.
    """

    fitness: float
    sum_dist: tuple[float, ...]
    min_dist: tuple[float, ...]
    riskiest: int
    aggregate: Aggregate = Aggregate.RISKIEST

    @property
    def scores(self) -> tuple[float, ...]:
        """Per-run score ``sum_dist + 2 * min_dist`` [m]."""
        return tuple(s + MIN_DIST_WEIGHT * m for s, m in zip(self.sum_dist, self.min_dist))

    @property
    def min_distance(self) -> float:
        """Smallest min_dist over all runs [m]."""
        return min(self.min_dist)


def run_distances(run: TrajectoryLike, obstacles: Sequence[Obstacle], dims: int = 2) -> tuple[float, float]:
    """``(sum_dist, min_dist)`` of one run [m], as defined in the paper's eq. 2."""
    if not obstacles:
        raise ValueError("obstacles: expected at least one obstacle, got none")
    pts = as_points(run)
    if pts.shape[0] == 0:
        raise ValueError("run: expected at least one point, got none")
    d = obstacle_distances(pts, obstacles, dims=dims)
    return float(d.sum(axis=1).min()), float(d.min())


def generation_fitness(runs: Sequence[TrajectoryLike], obstacles: Sequence[Obstacle],
                       aggregate: Aggregate | str = Aggregate.RISKIEST, dims: int = 2,
                       measure: Measure | str = Measure.PAPER,
                       competition: Sequence[float] | None = None) -> GenerationFitness:
    """Fitness of a generation test (paper eq. 2): ``-(sum_dist + 2 * min_dist)`` of its riskiest run.

    Args:
        runs: the n simulated runs (Trajectories or (N, 3) arrays [m]).
        obstacles: all obstacles of the test, including the generated one.
        aggregate: ``"riskiest"`` (default: the run with the smallest score, as the paper) or ``"mean"``.
        dims: 2 for the paper's footprint distance, 3 to account for obstacle base and top.
        measure: ``"paper"`` (default) or ``"competition"``: the run's ``min_dist`` is then the competition's
            distance (footprint to the trajectory's polyline).
        competition: with ``measure="competition"``, the runs' competition distances as flown (a simulated run's
            ``competition_distance``: Aerialist's pipeline on its logged samples); default: measured on ``runs``.

    Returns:
        A :class:`GenerationFitness`.
    """
    how = _choice(Aggregate, aggregate, "aggregate")
    runs = list(runs)
    if not runs:
        raise ValueError("runs: expected at least one run, got none")
    per_run = [run_distances(r, obstacles, dims) for r in runs]
    sums = tuple(s for s, _ in per_run)
    if Measure(measure) is Measure.COMPETITION and competition is not None:
        mins = tuple(float(d) for d in competition)
    elif Measure(measure) is Measure.COMPETITION:
        mins = tuple(competition_distance(r, obstacles) for r in runs)
    else:
        mins = tuple(m for _, m in per_run)
    scores = np.array(sums) + MIN_DIST_WEIGHT * np.array(mins)
    riskiest = int(np.argmin(scores))
    score = float(scores[riskiest]) if how is Aggregate.RISKIEST else float(scores.mean())
    return GenerationFitness(-score, sums, mins, riskiest, how)



__all__ = ["Aggregate", "Averaging", "GenerationFitness", "MIN_DIST_WEIGHT", "average_runs", "generation_fitness",
           "replication_fitness", "run_distances"]
