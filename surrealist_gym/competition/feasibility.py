"""Feasibility of a test before it is flown: does a free corridor join each mission leg's start and goal?

For each leg (from the takeoff point, home at the origin, to each mission item with a position; NAV_LAND flies at
the previous altitude) the check takes the footprints of the obstacles that reach the leg's flight altitude (boxes
from :meth:`~surrealist_gym.testcase.Obstacle.footprint`, cylinders as discs of diameter ``l``), grows each by the
clearance, and removes them from a bounded flight region: the points within ``max_offset_m`` of the leg's straight
track. The leg is feasible when its start and goal reach the same connected piece of what is left. An endpoint
reaches a piece within clearance + acceptance radius of it along a straight line that crosses no footprint (PX4 flies
much closer to a single box face than half the gap it passes); the takeoff and landing points must also be clear of
every obstacle below the altitude. Everything is in the test's local frame: x north, y east, z up [m]. The defaults
and the measurements behind them: ``docs/feasibility.md``.

Example:
    >>> from surrealist_gym.aerialist import load_test
    >>> from surrealist_gym.testcase import Obstacle
    >>> test = load_test("../shared/data/competition/case_studies/mission1.yaml")       # doctest: +SKIP
    >>> wall = [Obstacle(20, 20, 20, x, 26, r=45) for x in (-28.5, 0.0, 28.5)]             # doctest: +SKIP
    >>> infeasible(test.with_obstacles(wall))                                              # doctest: +SKIP
    'obstacles[0], obstacles[1] and obstacles[2] wall off the leg to mission item 1 (LAND) within 30 m of its track
    (widest gap 0.2 m < 6 m)'
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

from ..mission import Command
from ..testcase import Obstacle, Shape, TestCase

_EPS = 1e-6  # [m] "touches": shapely's distance between a piece and a grown footprint it borders is ~0


@dataclass(frozen=True, slots=True)
class FeasibilityConfig:
    """Parameters of :func:`infeasible`; the measurements behind the defaults are in ``docs/feasibility.md``.

    Attributes:
        clearance_m: half the narrowest gap between two obstacles that PX4-Avoidance flies through [m]; each
            footprint grows by it, so a gap narrower than twice this is closed. 3.0 m: the narrowest gap a
            recorded rilast-mission1 flight crossed is 6.09 m (``trajectories.csv``), and no flown rilast or CAMBA
            layout needs a narrower one within ``max_offset_m``. Set the UAV's own radius (0.4 m: the SITL Iris'
            rotor tips, 0.255 m + 0.128 m from its centre) to close only the gaps it cannot fit through.
        max_offset_m: how far from a leg's straight track the UAV may fly around obstacles [m]. 30 m: on the
            rilast-mission1 data, the flown layout that needs the widest detour to keep its labelled distance from
            every box reaches 27.4 m from the track, and the 24 recorded trajectories stray up to 22.7 m.
        acceptance_radius_m: a start or goal counts as reached within this distance [m]. 0.5 m: the competition's
            NAV_ACC_RAD (``case_studies/mission-params.csv``).
        altitude_margin_m: an obstacle blocks a leg flown at altitude a when it spans (a - margin, a + margin) [m].
            0.5 m: the competition's NAV_MC_ALT_RAD, the altitude error PX4 accepts at a waypoint.
    """

    clearance_m: float = 3.0
    max_offset_m: float = 30.0
    acceptance_radius_m: float = 0.5
    altitude_margin_m: float = 0.5

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value < 0 or (f.name == "max_offset_m" and value == 0):
                raise ValueError(f"FeasibilityConfig.{f.name}: expected a finite number >= 0"
                                 f"{' (> 0)' if f.name == 'max_offset_m' else ''} [m], got {value!r}")
            object.__setattr__(self, f.name, float(value))


@dataclass(frozen=True, slots=True)
class _Leg:
    name: str  # "the leg to mission item 1 (LAND)"
    start: tuple[float, float]
    goal: tuple[float, float]
    altitude: float  # [m] above home
    start_column: bool  # the UAV climbs (takeoff) at the start / descends (land) at the goal: every obstacle below
    goal_column: bool   # the altitude blocks that point


def _legs(test: TestCase) -> list[_Leg]:
    """The horizontal legs of the test's mission, from the takeoff point (home, the origin) on."""
    out: list[_Leg] = []
    pos, alt, column = (0.0, 0.0), None, True
    for i, item in enumerate(test.mission.items if test.mission is not None else ()):
        if item.command == Command.TAKEOFF:
            alt = item.z
            continue
        if item.command == Command.RETURN_TO_LAUNCH:
            goal, z, land = (0.0, 0.0), alt, True
        elif item.has_position:
            land = item.command == Command.LAND
            goal, z = (item.x, item.y), (alt if land else item.z)
        else:
            continue  # speed changes
        if z is None or math.isnan(z):  # no takeoff before it: the item's own altitude (an RTL's: the ground)
            z = 0.0 if math.isnan(item.z) else item.z
        out.append(_Leg(f"the leg to mission item {i} ({item.command.name})", pos, goal, z, column, land))
        pos, alt, column = goal, z, land
    return out


def infeasible(test: TestCase, config: FeasibilityConfig = FeasibilityConfig()) -> str | None:
    """Why the test cannot be flown to its end (one line naming the obstacles), or None when it can.

    Args:
        test: a test case with a mission.
        config: the check's parameters.

    Returns:
        None when a free corridor joins each leg's start and goal at its flight altitude, else the first leg's
        reason, e.g. ``obstacles[0] and obstacles[2] wall off the leg to mission item 2 (WAYPOINT) within 30 m of
        its track (widest gap 0.6 m < 6 m)`` or ``the goal of the leg to mission item 1 (LAND) lies inside
        obstacles[1]``.
    """
    mission_legs = _legs(test)
    if not mission_legs:
        return "the test has no mission leg to fly (no mission item with a position)"
    shapes = [_footprint(o) for o in test.obstacles]
    for leg in mission_legs:
        reason = _leg_reason(leg, test.obstacles, shapes, config)
        if reason is not None:
            return reason
    return None


def _footprint(o: Obstacle):
    from shapely.geometry import Point, Polygon

    return Point(o.x, o.y).buffer(o.l / 2, quad_segs=16) if o.shape == Shape.CYLINDER else Polygon(o.footprint())


def _leg_reason(leg: _Leg, obstacles, shapes, cfg: FeasibilityConfig) -> str | None:
    from shapely.geometry import LineString, Point
    from shapely.ops import unary_union

    lo, hi = leg.altitude - cfg.altitude_margin_m, leg.altitude + cfg.altitude_margin_m
    blocking = [i for i, o in enumerate(obstacles) if o.z < hi and o.z + o.h > lo]
    below = [i for i, o in enumerate(obstacles) if o.z < hi]  # what a vertical climb/descent passes
    ends = (("start", leg.start, leg.start_column), ("goal", leg.goal, leg.goal_column))
    for which, p, column in ends:
        inside = [i for i in (below if column else blocking) if shapes[i].intersects(Point(p))]
        if inside:
            what = "takeoff point" if which == "start" and column else f"{which} of {leg.name}"
            return f"the {what} lies inside " + " and ".join(f"obstacles[{i}]" for i in inside)
    track = LineString([leg.start, leg.goal]) if leg.start != leg.goal else Point(leg.start)
    region = track.buffer(cfg.max_offset_m)
    grown = {i: shapes[i].buffer(cfg.clearance_m) for i in blocking}
    union = unary_union(list(grown.values()))
    free = region.difference(union) if grown else region
    pieces = [g for g in getattr(free, "geoms", [free]) if not g.is_empty]
    near = {which: _reachable(p, pieces, [shapes[i] for i in blocking], cfg) for which, p, _ in ends}
    if near["start"] & near["goal"]:
        return None
    for which, p, _ in ends:
        if not near[which]:
            reach = 2 * cfg.clearance_m + cfg.acceptance_radius_m
            around = [i for i in blocking if shapes[i].distance(Point(p)) <= reach]
            return _blocked(around, "box in", f"the {which} of {leg.name}", shapes, cfg)
    touching = {k: {i for i, g in grown.items() if g.distance(pieces[k]) < _EPS} for k in range(len(pieces))}
    clusters = [{i for i, g in grown.items() if g.intersects(part)} for part in getattr(union, "geoms", [union])]
    walls = _walls(clusters, touching, near["start"], near["goal"])
    for which in ("goal", "start"):  # a pocket: the endpoint's pieces do not reach the region's edge
        if all(pieces[k].distance(region.exterior) > _EPS for k in near[which]):
            return _blocked(walls, "box in", f"the {which} of {leg.name}", shapes, cfg)
    return _blocked(walls, "wall off", f"{leg.name} within {cfg.max_offset_m:g} m of its track", shapes, cfg)


def _blocked(indices, verb: str, what: str, shapes, cfg: FeasibilityConfig) -> str:
    """The reason ``obstacles[0] and obstacles[2] <verb> <what> (<detail>)``; the detail is the widest of the closed
    gaps between the named obstacles, or that they span the flight region."""
    indices = sorted(indices)
    names = [f"obstacles[{i}]" for i in indices]
    if len(names) == 1:
        subject, verb = names[0], verb.replace("box", "boxes").replace("wall", "walls")
    else:
        subject = ", ".join(names[:-1]) + " and " + names[-1]
    gaps = [shapes[i].distance(shapes[j]) for i in indices for j in indices if i < j]
    closed = [d for d in gaps if d < 2 * cfg.clearance_m]
    detail = (f"widest gap {max(closed):.1f} m < {2 * cfg.clearance_m:g} m" if closed else
              f"{'it spans' if len(names) == 1 else 'they span'} the flight region")
    return f"{subject} {verb} {what} ({detail})"


def _reachable(p, pieces, shapes, cfg: FeasibilityConfig) -> set[int]:
    """The free pieces an endpoint reaches: within clearance + acceptance radius along a straight segment that
    crosses no footprint (PX4 passes a single box face much closer than half the gap it flies through)."""
    from shapely.geometry import LineString, Point
    from shapely.ops import nearest_points

    point, reach = Point(p), cfg.clearance_m + cfg.acceptance_radius_m
    out = set()
    for k, piece in enumerate(pieces):
        if piece.distance(point) > reach:
            continue
        q = nearest_points(piece, point)[0]
        if q.distance(point) < _EPS or not any(s.intersects(LineString([point, q])) for s in shapes):
            out.add(k)
    return out


def _walls(clusters, touching, start, goal) -> set[int]:
    """The obstacles that separate the start's pieces from the goal's: each cluster of touching grown footprints
    that borders both, else (a band of pieces between them) the clusters that border the start's or the goal's
    pieces and some other piece; a cluster that borders a single piece is a hole in it, not a wall."""
    def borders(cluster, pieces) -> bool:
        return any(touching[k] & cluster for k in pieces)

    for one, other in ((start, goal), (start, set(touching) - start), (goal, set(touching) - goal)):
        found = [c for c in clusters if borders(c, one) and borders(c, other)]
        if found:
            return set().union(*found)
    return set().union(*clusters)
