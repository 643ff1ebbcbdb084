"""What the runs of a test came to, judged once for every report: how each run ended (:class:`RunStatus`), the
distance that judges it (:class:`Measure`) against the safety distance, and the counts and rates that the search
results, ``compare``, the paper's tables and the surrogate datasets print.

Example:
    >>> runs = [{"status": "collision", "min_distance_2d": 0.0}, {"status": "success", "min_distance_2d": 2.4}]
    >>> o = outcomes(runs)
    >>> (o.crashes, o.unsafe, o.crash_rate, o.closest)
    (1, 1, 0.5, 0.0)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import Iterable

UNSAFE_DISTANCE_M = 1.5  #: the paper's safety distance, and the competition's soft-failure threshold [m]


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
        return self.crashes / self.runs if self.runs else math.nan

    @property
    def unsafe_rate(self) -> float:
        return self.unsafe / self.runs if self.runs else math.nan

    @property
    def blocked_rate(self) -> float:
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


__all__ = ["BLOCKED", "Measure", "Outcomes", "RunStatus", "UNSAFE_DISTANCE_M", "judged_distance", "measure_for",
           "outcomes", "run_status"]
