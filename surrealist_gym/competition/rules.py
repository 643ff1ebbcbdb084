"""The UAV Testing Competition (SBFT 2024, ICST/SBFT 2025, 2026): its case studies, its rules on obstacles and its
points.

Sources: the competition's README and case studies (skhatiri/UAV-Testing-Competition, ``snippets/case_studies``) as
summarised in ``shared/PX4-AVOIDANCE.md`` section 1 and ``shared/COMPETITION.md`` section 2: from 2025, at most 3
boxes standing on the ground (z = 0), x in [-40, 30], y in [10, 40], l and w in [2, 20], h in [10, 25] (taller than
the 10 m flight), r in [0, 90] degrees, no overlap (:data:`RULES`); 2024 bounded the count (4), the ground, overlaps
and the area, and no size or turn (:data:`UNBOUNDED_SIZES`, the count set by its edition). A
run is a soft failure below 1.5 m (the 2-D competition distance, :func:`~surrealist_gym.geometry.competition_distance`)
and scores 5 points below 0.25 m, 2 below 1 m, 1 below 1.5 m.

Example:
    >>> points(0.9), points(1.6)
    (2, 0)
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import InvalidTestCase
from ..outcomes import POINTS, UNSAFE_DISTANCE_M, points  # noqa: F401 - a run's points are the core's, named here
from ..testcase import Obstacle, Shape, TestCase

#: Where case-study names are looked up, in order (the competition repository keeps them in snippets/case_studies),
#: before the case studies bundled with the package (mission1-3 and their 2026 wind variants, missionN-wind).
CASE_STUDY_ENV = "SURREALIST_CASE_STUDIES"
CASE_STUDY_FOLDERS = ("case_studies", "snippets/case_studies")


@dataclass(frozen=True, slots=True)
class Rules:
    """The competition's bounds on a test's obstacles (metres, degrees; inclusive)."""

    max_obstacles: int = 3
    x: tuple[float, float] = (-40.0, 30.0)
    y: tuple[float, float] = (10.0, 40.0)
    l: tuple[float, float] = (2.0, 20.0)  # noqa: E741 - the obstacle field it bounds (Obstacle.l)
    w: tuple[float, float] = (2.0, 20.0)
    h: tuple[float, float] = (10.0, 25.0)
    r: tuple[float, float] = (0.0, 90.0)

    def bounds(self, field: str) -> tuple[float, float]:
        """The inclusive (low, high) bounds of an obstacle field (``x``, ``y``, ``l``, ``w``, ``h``, ``r``)."""
        return getattr(self, field)


RULES = Rules()
#: 2024's rules: the area, the ground and no overlap, any size (above 0) and turn.
UNBOUNDED_SIZES = Rules(l=(0.0, math.inf), w=(0.0, math.inf), h=(0.0, math.inf), r=(-math.inf, math.inf))
LAYOUT_FIELDS = ("x", "y", "l", "w", "h", "r")  # what a case-study test chooses of each box


def canonical_box(o: Obstacle) -> Obstacle:
    """The same box turned by r in [0, 90]: a box turned by r + 180 is the box turned by r, and one turned by r + 90
    is the box turned by r with l and w swapped (the competition scored CAMBA's tests, which turn boxes up to 360)."""
    r = o.r % 180.0
    return replace(o, r=r - 90.0, l=o.w, w=o.l) if r > 90.0 else replace(o, r=r)


def violations(test: TestCase, rules: Rules = RULES) -> tuple[str, ...]:
    """Every way the test's obstacles break the competition's rules, one line each naming the field (empty: valid).
    A box is checked as its :func:`canonical_box`; overlaps are refused when the test is made (:class:`TestCase`)."""
    out = []
    if len(test.obstacles) > rules.max_obstacles:
        out.append(f"obstacles: {len(test.obstacles)} boxes, the competition allows at most {rules.max_obstacles}")
    for i, given in enumerate(test.obstacles):
        o = canonical_box(given)
        note = "" if o.r == given.r else f" (checked as the same box turned by r = {o.r:g}" + (
            ", l and w swapped)" if o.l != given.l else ")")
        if o.shape != Shape.BOX:
            out.append(f"obstacles[{i}].shape: {o.shape.value}, the competition allows boxes only")
        if o.z != 0:
            out.append(f"obstacles[{i}].z: {o.z:g}, the competition's boxes stand on the ground (z = 0)")
        for name in LAYOUT_FIELDS:
            low, high = rules.bounds(name)
            value = getattr(o, name)
            if not low - 1e-9 <= value <= high + 1e-9:
                out.append(f"obstacles[{i}].{name}: {value:g} is outside the competition's [{low:g}, {high:g}]"
                           + note)
    return tuple(out)


def endpoint_failure(test: TestCase) -> str | None:
    """Why every run of the test would fail before it flew (None: it would not): a box within the 1.5 m safety
    distance of the take-off point (the origin) or of the landing point, where the UAV climbs or descends vertically
    whatever the planner does. Such a test is a failure of its layout, not of the UAV."""
    if test.mission is None:
        return None
    ends = {"take-off point": (0.0, 0.0)}
    positioned = [item for item in test.mission.items if item.has_position]
    if positioned:
        ends["landing point"] = (positioned[-1].x, positioned[-1].y)
    for name, (x, y) in ends.items():
        for i, o in enumerate(test.obstacles):
            gap = o.distance_2d(x, y)
            if gap < UNSAFE_DISTANCE_M:
                return (f"the {name} is {gap:.2f} m from obstacles[{i}], within the {UNSAFE_DISTANCE_M:g} m safety "
                        f"distance: every run would fail before flying")
    return None


def check_rules(test: TestCase, rules: Rules = RULES) -> None:
    """Raise InvalidTestCase with the first rule the test breaks."""
    broken = violations(test, rules)
    if broken:
        raise InvalidTestCase(broken[0])


# --- case studies ---------------------------------------------------------------------------------------------------
def case_study_path(name) -> Path:
    """The YAML of a case study: a path to an Aerialist YAML, or a name (``mission2``, ``mission2-wind``) looked up in
    ``$SURREALIST_CASE_STUDIES``, then ``case_studies/`` and ``snippets/case_studies/`` under the current folder,
    then among the case studies bundled with the package (:func:`bundled_case_studies`)."""
    given = Path(os.fspath(name))
    if given.suffix in (".yaml", ".yml"):
        if not given.is_file():
            raise InvalidTestCase(f"case study {os.fspath(name)!r}: no such file")
        return given
    folders = [Path(p) for p in os.environ.get(CASE_STUDY_ENV, "").split(os.pathsep) if p]
    folders += [Path(p) for p in CASE_STUDY_FOLDERS] + [bundled_case_studies()]
    for folder in folders:
        if (folder / f"{given.name}.yaml").is_file():
            return folder / f"{given.name}.yaml"
    known = sorted({p.stem for folder in folders if folder.is_dir() for p in folder.glob("*.yaml")})
    where = ", ".join(os.fspath(f) for f in folders)
    raise InvalidTestCase(f"case study {os.fspath(name)!r}: not found in {where}"
                          + (f" (known: {', '.join(known)})" if known else f"; set {CASE_STUDY_ENV} to the "
                             f"competition's case_studies folder"))


def bundled_case_studies() -> Path:
    """The folder of the case studies that ship with the package: the competition's sample case studies mission1-3
    with their plans, parameters and commands (byte for byte), and ``missionN-wind``, the same with the 2026
    example wind (3 m/s mean, 5 m/s max, toward x)."""
    from .. import data_path

    return Path(data_path("case_studies"))


def load_case_study(name) -> TestCase:
    """The case study's mission, parameters and commands as a test without obstacles (its own obstacles dropped)."""
    from ..aerialist import load_test

    path = case_study_path(name)
    test = load_test(path)
    if test.mission is None:
        raise InvalidTestCase(f"{path}: field 'mission_file': a case study needs a mission")
    return test.with_obstacles(())


def seed_layout(count: int = 3, rules: Rules = RULES) -> tuple[Obstacle, ...]:
    """``count`` mid-sized boxes spread along the x bounds at mid y, side by side: a valid start (the env's
    ``seed_action``) from which the env's mutators reach every layout within the rules (:func:`layout_mutators`)."""
    if not 1 <= count <= rules.max_obstacles:
        raise InvalidTestCase(f"obstacles: {count}, the competition allows 1 to {rules.max_obstacles}")
    (x0, x1), y = rules.x, sum(rules.y) / 2
    xs = [x0 + (x1 - x0) * (i + 0.5) / count for i in range(count)]
    mid = {name: sum(rules.bounds(name)) / 2 for name in ("w", "h")}
    side = min(sum(rules.l) / 2, 0.9 * (x1 - x0) / count)  # boxes of the seed never touch
    return tuple(Obstacle(side, mid["w"], mid["h"], x, y, 0.0, rules.r[0]) for x in xs)


def layout_mutators(seed: TestCase, rules: Rules = RULES):
    """One mutator per box and field whose range is exactly the rule's bounds: an action of -1 puts the field at the
    rule's low bound, +1 at its high bound, linearly between (the mutators stay additive, relative to the seed, so
    their values are ``bound - seed``). So every action in [-1, 1] gives boxes within the rules, ``env.action_bounds()``
    is the whole box and the seed is the action ``env.seed_action`` (not 0); overlaps and feasibility are the env's
    to refuse."""
    from ..mutators import Mutator, MutatorKind

    kinds = {"x": MutatorKind.MOVE_X, "y": MutatorKind.MOVE_Y, "r": MutatorKind.ROTATE,
             "l": MutatorKind.RESIZE_L, "w": MutatorKind.RESIZE_W, "h": MutatorKind.RESIZE_H}
    out = []
    for i, box in enumerate(seed.obstacles):
        for name in LAYOUT_FIELDS:
            low, high = rules.bounds(name)
            now = getattr(box, name)
            rotation = name == "r"
            out.append(Mutator(i, kinds[name], default_step=15.0 if rotation else 4.0,
                               min_step=0.5 if rotation else 0.1, low=low - now, high=high - now,
                               lowest=low, highest=high))
    return tuple(out)
