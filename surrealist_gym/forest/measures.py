"""What can be measured about the track's scenarios before they fly: the one place for preflight.py's measures.

``starter_kit/preflight.py`` (the track's kit) reports, from the scenarios alone: ``input_div``, the spread of the
declared factors that the track's scorer reports (TRACK2027.md section 4: preflight.py computes it exactly), the
split between the corridor bands (tight: corridor <= 4.5 m, wide above; the rank key averages the two), how close
the poles stand to the route, and the tightest free lateral width of each lane, which ``starter_kit/validate.py``
measures (its ``check_navigable``) and reports below 0.40 m, as blocked below 0.05 m (TRACK2027.md section 3).
:mod:`.rules` uses the distances and widths from here.

Example:
    >>> from surrealist_gym.forest.scenario import Poles, Scenario
    >>> s = Scenario("s0", 7, 20.0, 0.1, 2.0, 0.03, 0.0, 2.0, 1.5, ((0.0, -12.0), (0.0, 12.0)),
    ...              Poles(((0.0, 0.0),), 0.05, 3.0))
    >>> round(free_lateral_width(s), 3), band(s).value
    (0.062, 'tight')
"""
from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from enum import Enum
from typing import Iterable, Sequence

import shapely

from ..errors import FrozenDict
from .scenario import Scenario
from .space import (
    BLOCKED_WIDTH_M,
    INPUT_DIV_FACTORS,
    SCENARIO_RANGES,
    STATION_STEP_M,
    SWEPT_RADIUS_M,
    TIGHT_BAND_CORRIDOR_M,
)

Point = tuple[float, float]


class Band(str, Enum):
    """A scenario's corridor band: the rank key averages its breadth over the two (TRACK2027.md section 4)."""

    TIGHT = "tight"  # corridor <= 4.5 m
    WIDE = "wide"


def band(scenario: Scenario) -> Band:
    """The scenario's corridor band (preflight.py ``BAND_CUT``: tight at and below 4.5 m)."""
    return Band.TIGHT if scenario.corridor <= TIGHT_BAND_CORRIDOR_M else Band.WIDE


def route_distance(p: Point, patrol: Sequence[Point]) -> float:
    """Distance [m] from ``p`` to the route's polyline (at least two waypoints; shapely)."""
    return float(shapely.LineString(patrol).distance(shapely.Point(p)))


def pole_route_distances(scenario: Scenario) -> tuple[float, ...]:
    """Each pole's distance [m] to the route (empty without poles or with a single waypoint)."""
    if len(scenario.patrol) < 2:
        return ()
    return tuple(route_distance(p, scenario.patrol) for p in scenario.obstacle.xy)


def nearest_pole_to_route(scenario: Scenario) -> float | None:
    """The least of :func:`pole_route_distances` [m], None without poles (preflight.py ``nearest_to_route``)."""
    return min(pole_route_distances(scenario), default=None)


def station_and_offset(p: Point, patrol: Sequence[Point]) -> tuple[float, float]:
    """Where ``p`` sits along the route: (arc length [m] of its nearest point on the route, signed lateral offset [m]
    from that leg's line, positive to the left), the leg nearest first; (0, 0) if every leg has zero length."""
    best, start = None, 0.0
    for a, b in zip(patrol, patrol[1:]):
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        if length > 0:
            ux, uy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
            along = max(0.0, min(length, (p[0] - a[0]) * ux + (p[1] - a[1]) * uy))
            offset = (p[0] - a[0]) * -uy + (p[1] - a[1]) * ux
            distance = math.hypot(p[0] - (a[0] + ux * along), p[1] - (a[1] + uy * along))
            if best is None or distance < best[0]:
                best = (distance, start + along, offset)
        start += length
    return (best[1], best[2]) if best else (0.0, 0.0)


def widest_gap(shadows: Iterable[tuple[float, float]], half: float) -> float:
    """The widest free stretch [m] of ``[-half, half]`` left between the lateral ``shadows`` (intervals) [m]."""
    widest, edge = 0.0, -half
    for low, high in sorted(shadows):
        if low > edge:
            widest = max(widest, low - edge)
        edge = max(edge, high)
    return max(widest, half - edge)


def free_lateral_width(scenario: Scenario) -> float | None:
    """The tightest free lateral width [m] the lane leaves the vehicle between its poles, as validate.py's
    ``check_navigable`` measures it; None without poles, or if the lane is narrower than the vehicle.

    The vehicle is a point: the lane shrinks by the X500's swept radius (0.444 m) on each side and each pole grows
    by it. At stations every 0.10 m along the route, each pole within reach casts a lateral shadow (the chord of its
    grown disc, the pole placed at its arc length and offset along the route, :func:`station_and_offset`); the
    width there is the widest gap between the shadows, and the measure is its least over the stations where any
    pole casts one (2 half-widths if none does). Reported, not enforced: under 0.40 m tight, under 0.05 m blocked.
    """
    poles, patrol = scenario.obstacle.xy, scenario.patrol
    half = scenario.corridor / 2.0 - SWEPT_RADIUS_M
    if not poles or half <= 0:
        return None
    total = 0.0
    for a, b in zip(patrol, patrol[1:]):
        total += math.hypot(b[0] - a[0], b[1] - a[1])
    placed = [station_and_offset(p, patrol) for p in poles]
    reach = scenario.obstacle.radius + SWEPT_RADIUS_M
    narrowest = 2.0 * half
    for i in range(int(total / STATION_STEP_M) + 2):
        station = min(total, i * STATION_STEP_M)
        shadows = []
        for along, offset in placed:
            if abs(station - along) <= reach:
                chord = math.sqrt(max(0.0, reach * reach - (station - along) ** 2))
                shadows.append((offset - chord, offset + chord))
        if shadows:
            narrowest = min(narrowest, widest_gap(shadows, half))
    return narrowest


def factor_spread(scenarios: Sequence[Scenario], factor: str) -> float | None:
    """The spread of one declared factor: its population standard deviation over half its range, at most 1;
    None for fewer than two scenarios (preflight.py, per factor of ``input_div``)."""
    if len(scenarios) < 2:
        return None
    bounds = SCENARIO_RANGES[factor]
    return min(1.0, statistics.pstdev([getattr(s, factor) for s in scenarios]) / ((bounds.high - bounds.low) / 2))


def input_div(scenarios: Sequence[Scenario]) -> float:
    """``input_div``: the mean spread of density, ego_max_vel, alt, wind and corridor (preflight.py; 0 for fewer
    than two scenarios)."""
    spreads = [factor_spread(scenarios, f) for f in INPUT_DIV_FACTORS]
    return statistics.mean(spreads) if None not in spreads else 0.0


@dataclass(frozen=True, slots=True)
class Preflight:
    """What preflight.py reports about a set of scenarios, as values.

    Attributes:
        input_div: the mean of ``spreads``.
        spreads: each factor's spread (:func:`factor_spread`), by factor; empty for fewer than two scenarios.
        tight: how many scenarios are in the tight band (corridor <= 4.5 m).
        wide: how many are in the wide band.
        nearest_pole: by scenario id, the distance [m] of its nearest pole to the route (scenarios with poles).
        free_width: by scenario id, the tightest free lateral width [m] (scenarios with poles).
        without_poles: how many scenarios place no pole.
    """

    input_div: float
    spreads: FrozenDict
    tight: int
    wide: int
    nearest_pole: FrozenDict
    free_width: FrozenDict
    without_poles: int

    @property
    def tightest(self) -> tuple[float, str] | None:
        """The least free lateral width [m] and its scenario's id (the least id among equals), or None."""
        return min(((w, sid) for sid, w in self.free_width.items()), default=None)

    @property
    def blocked(self) -> int:
        """How many lanes are blocked: free lateral width under 0.05 m (admissible all the same)."""
        return sum(1 for w in self.free_width.values() if w < BLOCKED_WIDTH_M)


def preflight(scenarios: Sequence[Scenario]) -> Preflight:
    """preflight.py's measures of ``scenarios`` (a submission's, or any number)."""
    spreads = {f: factor_spread(scenarios, f) for f in INPUT_DIV_FACTORS}
    spreads = {f: value for f, value in spreads.items() if value is not None}
    nearest = {s.id: d for s in scenarios if (d := nearest_pole_to_route(s)) is not None}
    widths = {s.id: w for s in scenarios if (w := free_lateral_width(s)) is not None}
    tight = sum(1 for s in scenarios if band(s) is Band.TIGHT)
    return Preflight(input_div=input_div(scenarios), spreads=FrozenDict(spreads), tight=tight,
                     wide=len(scenarios) - tight, nearest_pole=FrozenDict(nearest), free_width=FrozenDict(widths),
                     without_poles=sum(1 for s in scenarios if not s.obstacle.xy))
