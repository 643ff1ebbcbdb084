"""What the runs of a test came to, judged once for every report: how each run ended (:class:`RunStatus`), the
distance that judges it (:class:`Measure`) against the safety distance, and the counts and rates that the search
results, ``compare``, the paper's tables and the surrogate datasets print. :class:`RunRecord` is what a report keeps
of a run (the re-evaluation's and the fidelity measure's runs, :func:`~surrealist_gym.executors.fly_many`'s result),
with the competition's points of a run (:func:`points`, :func:`run_points`); :func:`status_counts` counts how runs
ended, for every report.

Example:
    >>> runs = [{"status": "collision", "min_distance_2d": 0.0}, {"status": "success", "min_distance_2d": 2.4}]
    >>> o = outcomes(runs)
    >>> (o.crashes, o.unsafe, o.crash_rate, o.closest)
    (1, 1, 0.5, 0.0)
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from enum import Enum
from typing import Iterable

import numpy as np

from .trajectory import Trajectory, airborne_time

UNSAFE_DISTANCE_M = 1.5  #: the paper's safety distance, and the competition's soft-failure threshold [m]
#: The UAV Testing Competition's points of a run by its competition distance [m]: (below this distance, points),
#: checked in order; a collision scores 5 (:func:`run_points`).
POINTS = ((0.25, 5), (1.0, 2), (UNSAFE_DISTANCE_M, 1))


class RunStatus(str, Enum):
    """How a run ended."""

    SUCCESS = "success"      # mission completed (landed and disarmed, or last item reached in the air)
    COLLISION = "collision"  # PyBullet contact between the vehicle and an obstacle
    TIMEOUT = "timeout"      # simulated-time limit reached
    STUCK = "stuck"          # no progress for SimConfig.stuck_window_s (early stopping, only when asked for)
    ERROR = "error"          # the vehicle flipped or its state became invalid


BLOCKED = (RunStatus.TIMEOUT, RunStatus.STUCK)  #: a run that never finished its mission


class Measure(str, Enum):
    """Which distance judges a run against the safety distance."""

    PAPER = "paper"  #: the vehicle's 2-D clearance to the box footprints (the paper's min_dist)
    COMPETITION = "competition"  #: footprint to the 0.5 s trajectory's polyline (Aerialist, the UAV Testing
    #: Competition)


def measure_for(test) -> Measure:
    """The paper's measure for a test around a real flight (its assertion names a log), the competition's for any
    other Aerialist test."""
    return Measure.PAPER if getattr(test, "replicates_flight", False) else Measure.COMPETITION


def _field(run, name: str, default=None):
    return run.get(name, default) if isinstance(run, dict) else getattr(run, name, default)


def judged_distance(run, measure: Measure | str = Measure.PAPER) -> float:
    """The distance a run (a RunResult, a RunSummary or a stored run's dict) is judged by [m]; nan if not kept."""
    key = "competition_distance" if Measure(measure) is Measure.COMPETITION else "min_distance_2d"
    value = _field(run, key)
    return float(value) if value is not None else math.nan


def run_status(run) -> RunStatus:
    """How a run ended, from a RunResult, a RunSummary or a stored run's dict."""
    return RunStatus(getattr(_field(run, "status"), "value", _field(run, "status")))


@dataclass(frozen=True, slots=True)
class Outcomes:
    """Counts over the runs of one test; ``closest`` is the smallest judged distance [m] (inf without runs)."""

    runs: int
    crashes: int
    unsafe: int
    blocked: int
    closest: float

    @property
    def crash_rate(self) -> float:
        """Share of the runs that crashed (nan without runs)."""
        return self.crashes / self.runs if self.runs else math.nan

    @property
    def unsafe_rate(self) -> float:
        """Share of the runs that were unsafe (nan without runs)."""
        return self.unsafe / self.runs if self.runs else math.nan

    @property
    def blocked_rate(self) -> float:
        """Share of the runs that were blocked (nan without runs)."""
        return self.blocked / self.runs if self.runs else math.nan


def outcomes(runs: Iterable, measure: Measure | str = Measure.PAPER) -> Outcomes:
    """Crashes (:attr:`RunStatus.COLLISION`), unsafe runs (judged distance below :data:`UNSAFE_DISTANCE_M`),
    blocked runs (timeout or stuck) and the closest judged distance over ``runs``."""
    runs = list(runs)
    statuses = [run_status(r) for r in runs]
    distances = [judged_distance(r, measure) for r in runs]
    return Outcomes(runs=len(runs), crashes=sum(s is RunStatus.COLLISION for s in statuses),
                    unsafe=sum(d < UNSAFE_DISTANCE_M for d in distances), blocked=sum(s in BLOCKED for s in statuses),
                    closest=min((d for d in distances if not math.isnan(d)), default=math.inf))


def points(distance: float) -> int:
    """The competition's points of one run with this competition distance [m] (0 when not a soft failure)."""
    if not math.isfinite(distance):
        return 0
    return next((p for limit, p in POINTS if distance < limit), 0)


def run_points(status, distance: float) -> int:
    """The competition's points of a run: 5 for a collision (as a distance of 0), else :func:`points`."""
    return 5 if getattr(status, "value", status) == RunStatus.COLLISION.value else points(distance)


def status_counts(runs: Iterable) -> Counter:
    """How many runs ended in each status (a status's value -> runs), in the order they first appear."""
    return Counter(str(getattr(s, "value", s)) for s in (_field(r, "status") for r in runs))


def statuses_text(runs: Iterable) -> str:
    """How the runs ended, e.g. ``success:4 collision:1`` (the reports' statuses column)."""
    return " ".join(f"{s}:{n}" for s, n in status_counts(runs).items())


def _no_flight() -> Trajectory:
    return Trajectory(np.zeros(0), np.zeros((0, 3)))


@dataclass(frozen=True, slots=True)
class RunRecord:
    """What a report keeps of one run: a value (equal records are the same run, flight included).

    Attributes:
        index: the run's index (its noise derives from the test, the base seed and it).
        status: how it ended (a :class:`RunStatus` value). A run in ``error`` was not flown to an end: it neither
            passes nor fails.
        distance: its competition distance [m] (inf without obstacles; nan without a flight).
        duration: simulated time from arming to the end [s].
        trajectory: the flight through the paper's pipeline (0.5 s means; x north, y east, z up) [m]; an (N, 3)
            array given is taken as sampled every 0.5 s (:meth:`Trajectory.from_array`).
        message: a one-line description of the end.
        airborne: time from the first to the last moment above 0.3 m [s]
            (:func:`~surrealist_gym.trajectory.airborne_time` of the true positions; 0 when not kept).
    """

    index: int
    status: str
    distance: float
    duration: float
    trajectory: Trajectory = field(default_factory=_no_flight, repr=False, hash=False)
    message: str = ""
    airborne: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "status", str(getattr(self.status, "value", self.status)))
        if not isinstance(self.trajectory, Trajectory):
            xyz = np.asarray(self.trajectory, dtype=np.float64).reshape(-1, 3)
            object.__setattr__(self, "trajectory", Trajectory.from_array(xyz))

    @classmethod
    def of(cls, run) -> "RunRecord":
        """The record of a simulated run (a RunResult, or an executor's failed run)."""
        trajectory = run.trajectory
        true_t, true_xyz = getattr(run, "true_t", None), getattr(run, "true_xyz", None)
        return cls(int(run.index), run.status, float(run.competition_distance) if len(trajectory) else math.nan,
                   float(run.duration), trajectory, str(run.message),
                   airborne_time(true_t, true_xyz) if true_t is not None and len(true_t) else 0.0)

    @property
    def competition_distance(self) -> float:
        """:attr:`distance`, under the name :func:`judged_distance` reads."""
        return self.distance

    @property
    def flown(self) -> bool:
        """Whether the run ended in anything but ``error`` (only such runs pass or fail)."""
        return self.status != RunStatus.ERROR.value

    @property
    def failed(self) -> bool:
        """A flown run that collided or came within 1.5 m (competition distance)."""
        return self.flown and (self.status == RunStatus.COLLISION.value or self.distance < UNSAFE_DISTANCE_M)

    @property
    def points(self) -> int:
        """The competition's points of the run (:func:`run_points`)."""
        return run_points(self.status, self.distance)

    def to_dict(self) -> dict:
        """The run as a store keeps it (its trajectory apart: :meth:`from_dict` takes it back)."""
        return {"index": self.index, "status": self.status, "distance": self.distance, "duration": self.duration,
                "message": self.message, "airborne": self.airborne}

    @classmethod
    def from_dict(cls, run: dict, trajectory=()) -> "RunRecord":
        """A run from :meth:`to_dict` and its (N, 3) trajectory (stores written before ``airborne`` read as 0)."""
        return cls(int(run["index"]), run["status"], float(run["distance"]), float(run["duration"]), trajectory,
                   run.get("message", ""), float(run.get("airborne", 0.0)))


__all__ = ["BLOCKED", "Measure", "Outcomes", "POINTS", "RunRecord", "RunStatus", "UNSAFE_DISTANCE_M",
           "judged_distance", "measure_for", "outcomes", "points", "run_points", "run_status", "status_counts",
           "statuses_text"]
