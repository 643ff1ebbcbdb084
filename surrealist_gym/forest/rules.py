"""The track's rules: a submission is accepted exactly when ``starter_kit/validate.py`` accepts it.

validate.py (the track's kit) is the only gate: a submission it rejects is not flown (TRACK2027.md section 3). Its
rules, in its order, are those of :class:`~.space.Rule`; the form of each field is checked when the file is read
(:mod:`.scenario`), the rest here:

- per scenario (:func:`check_scenario`, usable on any scenario alone): each number within its range, 2-6 waypoints
  each 3.0 m inside the field's edge, legs of 8-34 m, interior turns of 25-160 deg (measured on the coordinates as
  written, the rounded ones), at most 10 poles radius 0.02-0.10 m and height 1-5 m, each inside the field, inside the
  lane (at most corridor / 2 from the route), at least 3.0 m from every waypoint and 1.5 m from every other pole;
  and the tightest free lateral width (:func:`.measures.free_lateral_width`), reported under 0.40 m (tight) and
  under 0.05 m (blocked), never refused;
- per submission (:func:`check_submission`): exactly 20 scenarios, unique ids, no two scenarios identical apart
  from their id, and at least 5 distinct recipes once the forest seed is ignored.

The first rule broken raises a one-line :class:`~.space.InvalidScenario` naming the file, the scenario, the field
and the :class:`~.space.Rule`: the rule validate.py names, for a file that breaks one. A file that breaks several is
refused all the same, though the rule named may differ, since the form of every scenario is checked on reading,
before validate.py would count them. validate.py also refuses a lane narrower than the vehicle (0.888 m); with the
corridor at least 2.0 m wide that cannot happen, and it is not repeated here.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

from .measures import free_lateral_width, route_distance
from .scenario import Scenario, Submission, read_submission
from .space import (
    BLOCKED_WIDTH_M,
    EDGE_MARGIN_M,
    LEG_M,
    MAX_POLES,
    MIN_RECIPES,
    POLE_RANGES,
    POLE_SEPARATION_M,
    POLE_WAYPOINT_CLEARANCE_M,
    SCENARIO_RANGES,
    SCENARIOS_PER_SUBMISSION,
    TIGHT_WIDTH_M,
    TURN_DEG,
    WAYPOINT_COUNT,
    InvalidScenario,
    Rule,
)


@dataclass(frozen=True, slots=True)
class ScenarioCheck:
    """An admissible scenario's lane, as validate.py reports it.

    Attributes:
        scenario_id: the scenario's id.
        free_width: the tightest free lateral width [m] between its poles; None without poles.
    """

    scenario_id: str
    free_width: float | None

    @property
    def tight(self) -> bool:
        """Whether the lane leaves less than 0.40 m of free lateral width (reported, admissible)."""
        return self.free_width is not None and self.free_width < TIGHT_WIDTH_M

    @property
    def blocked(self) -> bool:
        """Whether the lane leaves less than 0.05 m: passable only by leaving it (reported, admissible)."""
        return self.free_width is not None and self.free_width < BLOCKED_WIDTH_M


@dataclass(frozen=True, slots=True)
class SubmissionCheck:
    """An accepted submission: its name, each scenario's check and how many distinct recipes it holds."""

    name: str
    scenarios: tuple[ScenarioCheck, ...]
    recipes: int

    @property
    def tight_lanes(self) -> tuple[ScenarioCheck, ...]:
        """The scenarios whose lane validate.py reports (free lateral width under 0.40 m), in the file's order."""
        return tuple(c for c in self.scenarios if c.tight)


def turn_deg(a, b, c) -> float:
    """The turn [deg] at ``b`` on the path a-b-c: 0 straight on, 180 a reversal (180 if a leg has no length)."""
    ux, uy, vx, vy = b[0] - a[0], b[1] - a[1], c[0] - b[0], c[1] - b[1]
    nu, nv = math.hypot(ux, uy), math.hypot(vx, vy)
    if nu == 0 or nv == 0:
        return 180.0
    return math.degrees(math.acos(max(-1.0, min(1.0, (ux * vx + uy * vy) / (nu * nv)))))


def check_scenario(scenario: Scenario, source: str = "") -> ScenarioCheck:
    """Check one scenario against the track's per-scenario rules, in validate.py's order; its lane's report, or a
    one-line :class:`InvalidScenario` naming ``source`` (the file), the scenario, the field and the rule."""
    def broken(field: str, problem: str, rule: Rule) -> InvalidScenario:
        return InvalidScenario(f"{source + ': ' if source else ''}scenario {scenario.id}: {field}: {problem}", rule)

    for name, bounds in SCENARIO_RANGES.items():
        if not bounds.holds(getattr(scenario, name)):
            raise broken(name, f"{getattr(scenario, name)} out of {bounds}", Rule.RANGE)
    patrol, area = scenario.patrol, scenario.area
    if not WAYPOINT_COUNT.holds(len(patrol)):
        raise broken("patrol", f"{len(patrol)} waypoints, expected {WAYPOINT_COUNT}", Rule.WAYPOINTS)
    limit = area - EDGE_MARGIN_M
    for j, (x, y) in enumerate(patrol):
        if abs(x) > limit or abs(y) > limit:
            raise broken(f"patrol[{j}]", f"({x}, {y}) outside +-{limit:g} m (the {area:g} m field less the "
                         f"{EDGE_MARGIN_M:g} m margin)", Rule.EDGE_MARGIN)
    for j, (a, b) in enumerate(zip(patrol, patrol[1:])):
        leg = math.hypot(b[0] - a[0], b[1] - a[1])
        if not LEG_M.holds(leg):
            raise broken("patrol", f"leg {j} (waypoints {j}-{j + 1}) is {leg:.2f} m, out of {LEG_M}", Rule.LEG)
    for j in range(1, len(patrol) - 1):
        turn = turn_deg(*patrol[j - 1:j + 2])
        if not TURN_DEG.holds(turn):
            raise broken(f"patrol[{j}]", f"turn of {turn:.1f} deg, out of {TURN_DEG}", Rule.TURN)
    poles = scenario.obstacle
    for name, bounds in POLE_RANGES.items():
        if not bounds.holds(getattr(poles, name)):
            raise broken(f"obstacle.{name}", f"{getattr(poles, name)} out of {bounds}", Rule.RANGE)
    if len(poles.xy) > MAX_POLES:
        raise broken("obstacle.xy", f"{len(poles.xy)} poles, at most {MAX_POLES}", Rule.POLE_COUNT)
    for j, p in enumerate(poles.xy):
        where = f"obstacle.xy[{j}]"
        if abs(p[0]) > area or abs(p[1]) > area:
            raise broken(where, f"({p[0]}, {p[1]}) outside the +-{area:g} m field", Rule.POLE_EXTENT)
        off_route = route_distance(p, patrol)
        if off_route > scenario.corridor / 2:
            raise broken(where, f"{off_route:.2f} m from the route, outside the {scenario.corridor / 2:g} m "
                         f"half-lane", Rule.POLE_LANE)
        to_waypoint = min(math.hypot(p[0] - w[0], p[1] - w[1]) for w in patrol)
        if to_waypoint < POLE_WAYPOINT_CLEARANCE_M:
            raise broken(where, f"{to_waypoint:.2f} m from a waypoint, under {POLE_WAYPOINT_CLEARANCE_M:g} m",
                         Rule.POLE_WAYPOINT)
        for k, q in enumerate(poles.xy[:j]):
            apart = math.hypot(p[0] - q[0], p[1] - q[1])
            if apart < POLE_SEPARATION_M:
                raise broken(where, f"{apart:.2f} m from pole {k}, under {POLE_SEPARATION_M:g} m",
                             Rule.POLE_SEPARATION)
    return ScenarioCheck(scenario.id, free_lateral_width(scenario))


def flight_fingerprint(scenario: Scenario) -> str:
    """What makes the flight: the scenario's JSON without its id and provenance, its poles sorted, as canonical
    text (validate.py hashes the same text: two scenarios with one fingerprint are the same flight)."""
    return json.dumps(canonical_flight(scenario), sort_keys=True, separators=(",", ":"))


def recipe_fingerprint(scenario: Scenario) -> str:
    """The scenario's recipe: :func:`flight_fingerprint` without the forest seed (validate.py)."""
    canon = canonical_flight(scenario)
    del canon["seed"]
    return json.dumps(canon, sort_keys=True, separators=(",", ":"))


def canonical_flight(scenario: Scenario) -> dict:
    """The scenario's JSON object less its id and provenance, its poles sorted and made floats (validate.py)."""
    fields = scenario.to_json()
    canon = {key: fields[key] for key in fields if key not in ("id", *scenario.metadata)}
    canon["obstacle"] = dict(canon["obstacle"], xy=sorted([float(c) for c in p] for p in scenario.obstacle.xy))
    return canon


def check_submission(submission: Submission, source: str = "") -> SubmissionCheck:
    """Check a submission as validate.py does, in its order: 20 scenarios; then each scenario's id unique, its
    rules (:func:`check_scenario`) and no earlier scenario identical apart from the id; then at least 5 distinct
    recipes. The accepted submission's report, or a one-line :class:`InvalidScenario` naming ``source`` (the file)."""
    where = source + ": " if source else ""
    scenarios = submission.scenarios
    if len(scenarios) != SCENARIOS_PER_SUBMISSION:
        raise InvalidScenario(f"{where}scenarios: {len(scenarios)} of them, expected exactly "
                              f"{SCENARIOS_PER_SUBMISSION}", Rule.COUNT)
    checks, ids, flights, recipes = [], set(), {}, {}
    for scenario in scenarios:
        if scenario.id in ids:
            raise InvalidScenario(f"{where}scenario {scenario.id}: id: used by an earlier scenario", Rule.DUPLICATE_ID)
        ids.add(scenario.id)
        checks.append(check_scenario(scenario, source))
        flight = flight_fingerprint(scenario)
        if flight in flights:
            raise InvalidScenario(f"{where}scenario {scenario.id}: identical to scenario {flights[flight]} apart from "
                                  f"its id", Rule.DUPLICATE_SCENARIO)
        flights[flight] = scenario.id
        recipes.setdefault(recipe_fingerprint(scenario), []).append(scenario.id)
    if len(recipes) < MIN_RECIPES:
        largest = max(recipes.values(), key=len)
        raise InvalidScenario(f"{where}scenarios: {len(recipes)} distinct recipes once the seed is ignored "
                              f"({len(largest)} share the recipe of {largest[0]}), expected at least {MIN_RECIPES}",
                              Rule.RECIPES)
    return SubmissionCheck(submission.name, tuple(checks), len(recipes))


def validate_file(path: str | os.PathLike) -> SubmissionCheck:
    """Read and check a ``submission.json`` as validate.py does (:func:`~.scenario.read_submission`, then
    :func:`check_submission`); a one-line :class:`InvalidScenario` naming the file for the first rule broken."""
    return check_submission(read_submission(path), os.fspath(path))
