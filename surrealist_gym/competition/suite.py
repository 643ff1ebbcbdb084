"""Suites of distinct failures: how far apart two failing tests are, and the archive that keeps a suite.

Two failures are the same failure when their flights are alike and the UAV failed at the same obstacle:
- **flight**: the mean distance between matched points of the two trajectories in the x-y plane, along DTW's
  optimal warping path (:func:`trajectory_distance`; the paper's DTW divided by the path's length, so it does not
  grow with the flight's length);
- **the failing obstacle**: the Hausdorff distance between the footprints of the box each flight came closest to
  (:func:`layout_distance` of those boxes). The other boxes of a layout do not count: moving a box the UAV never
  came near does not make a new failure.

:class:`Suite` keeps a failing test only if it differs from every member by at least ``min_flight_m`` in flight AND
``min_layout_m`` in its failing obstacle; a failure alike to exactly one member replaces it when it comes closer to
an obstacle (the elite of its niche, as MAP-Elites keeps one per cell). Members are frozen values.

Example:
    >>> from surrealist_gym.testcase import Obstacle
    >>> a, b = [Obstacle(2, 2, 20, 0, 20)], [Obstacle(2, 2, 20, 3, 20)]
    >>> round(layout_distance(a, b), 6)
    3.0
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np

from ..outcomes import UNSAFE_DISTANCE_M
from ..testcase import Obstacle, Shape, TestCase

MIN_FLIGHT_M = 1.0  # [m] mean point distance below which two flights are alike
MIN_LAYOUT_M = 5.0  # [m] Hausdorff distance below which two failing obstacles are alike


def _xy(trajectory) -> np.ndarray:
    from ..trajectory import as_points

    return np.ascontiguousarray(as_points(trajectory)[:, :2], dtype=np.float64)


def trajectory_distance(a, b) -> float:
    """Mean x-y distance [m] between the points DTW matches: DTW along its optimal path over the path's length."""
    from ..metrics import dtw_path

    path, total = dtw_path(_xy(a), _xy(b))
    return total / len(path)


def footprints(obstacles: Sequence[Obstacle]):
    """The ground the obstacles cover: the union of their footprints (a shapely geometry; a cylinder as a circle)."""
    import shapely

    shapes = [shapely.Point(o.x, o.y).buffer(o.l / 2, quad_segs=16) if o.shape == Shape.CYLINDER
              else shapely.Polygon(o.footprint()) for o in obstacles]
    return shapely.unary_union(shapes)


def layout_distance(a: Sequence[Obstacle], b: Sequence[Obstacle]) -> float:
    """Hausdorff distance [m] between the union of the footprints of two layouts (inf when one is empty)."""
    if not a or not b:
        return 0.0 if not a and not b else math.inf
    return float(footprints(a).hausdorff_distance(footprints(b)))


@dataclass(frozen=True, slots=True)
class Member:
    """One failure of a suite: the test, its closest approach, the flight that came closest and when it was found."""

    test: TestCase
    distance: float          # competition distance of the riskiest run [m]
    trajectory: np.ndarray = field(compare=False, repr=False)  # (N, 3) of that run [m]
    evaluation: int = 0      # the evaluation (1-based, as the env counts) that found it
    status: str = "success"  # how that run ended (collision, success, ...)

    failing_obstacle: Obstacle | None = field(init=False, compare=False, repr=False)  # the box it came closest to

    def __post_init__(self):
        from ..geometry import competition_distances

        traj = np.array(self.trajectory, dtype=np.float64)
        traj.setflags(write=False)
        object.__setattr__(self, "trajectory", traj)
        closest = None  # by the competition's distance, once: every offer compares it with each member
        if self.test.obstacles and len(traj):
            closest = self.test.obstacles[int(np.argmin(competition_distances(traj, self.test.obstacles)))]
        object.__setattr__(self, "failing_obstacle", closest)

    @property
    def points(self) -> int:
        """The competition's points of the member's run (from its status and distance)."""
        from ..outcomes import run_points

        return run_points(self.status, self.distance)


@dataclass(frozen=True, slots=True)
class Suite:
    """An archive of distinct failures (immutable: :meth:`offer` returns the new suite and what happened)."""

    members: tuple[Member, ...] = ()
    min_flight_m: float = MIN_FLIGHT_M
    min_layout_m: float = MIN_LAYOUT_M
    threshold_m: float = UNSAFE_DISTANCE_M

    def __len__(self) -> int:
        return len(self.members)

    def fails(self, distance: float, status: str = "success") -> bool:
        """Whether a run is a failure: a collision, or a competition distance below the threshold."""
        return status == "collision" or (math.isfinite(distance) and distance < self.threshold_m)

    def alike(self, a: Member, b: Member) -> bool:
        """Whether two failures are the same one: alike in flight and in the obstacle they failed at."""
        boxes = [m.failing_obstacle for m in (a, b)]
        return (trajectory_distance(a.trajectory, b.trajectory) < self.min_flight_m
                and layout_distance(*[[o] if o is not None else [] for o in boxes]) < self.min_layout_m)

    def offer(self, candidate: Member) -> tuple["Suite", str]:
        """The suite with ``candidate`` offered: ``added``, ``replaced N`` (it came closer than the member it is
        alike to), ``alike N`` (kept out) or ``passed`` (not a failure)."""
        if not self.fails(candidate.distance, candidate.status):
            return self, "passed"
        twins = [i for i, m in enumerate(self.members) if self.alike(candidate, m)]
        if not twins:
            return replace(self, members=self.members + (candidate,)), "added"
        if len(twins) == 1 and _severity(candidate) > _severity(self.members[twins[0]]):
            members = list(self.members)
            members[twins[0]] = candidate
            return replace(self, members=tuple(members)), f"replaced {twins[0]}"
        return self, f"alike {twins[0]}"


def _severity(member: Member) -> float:
    return math.inf if member.status == "collision" else -member.distance


def diversity(members: Sequence[Member]) -> dict:
    """How far apart the members are: mean and smallest pairwise flight and layout distances [m] (nan below two)."""
    pairs = [(a, b) for i, a in enumerate(members) for b in members[i + 1:]]
    if not pairs:
        return {"members": len(members), "flight_mean_m": math.nan, "flight_min_m": math.nan,
                "layout_mean_m": math.nan, "layout_min_m": math.nan}
    flight = [trajectory_distance(a.trajectory, b.trajectory) for a, b in pairs]
    layout = [layout_distance(a.test.obstacles, b.test.obstacles) for a, b in pairs]
    return {"members": len(members), "flight_mean_m": float(np.mean(flight)), "flight_min_m": float(np.min(flight)),
            "layout_mean_m": float(np.mean(layout)), "layout_min_m": float(np.min(layout))}
