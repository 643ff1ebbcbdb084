"""The track's scenario and its ``submission.json`` as immutable values, read and written exactly.

A scenario (``../shared/TRACK2027.md`` section 3; the track's README, "Building a generator") is a forest ``seed``,
the field's half-width ``area`` [m], the mapping ``voxel`` [m], the lane's width ``corridor`` [m], the tree
``density`` [trees/m^2], ``wind`` [m/s], the planner's ``ego_max_vel`` [m/s], the flight altitude ``alt`` [m], the
commanded route ``patrol`` (waypoints [m]) and its ``obstacle``: poles (``xy`` [m], ``radius`` [m], ``height`` [m]).
A submission is its generator's ``submission`` name and its ``scenarios``.

Reading checks the form only, in the order ``starter_kit/validate.py`` checks it: each field present, of its JSON
type and finite, no field beyond the flight's (validate.py ``FLIGHT_KEYS``) and the provenance ones
(``METADATA_KEYS``). The numbers are kept as the file gives them (an integer stays one), so a scenario read and
written back gives the same JSON values, and validate.py's fingerprints, which tell ``6`` from ``6.0``, are ours
too. The track's rules (ranges, route, poles, the submission's count and distinctness) are :mod:`.rules`'.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any

from ..errors import FrozenDict, read_text
from .space import FLIGHT_FIELDS, METADATA_FIELDS, OBSTACLE_FIELDS, SAFE_TOKEN, InvalidScenario, Rule

#: A scenario's numbers besides its seed, in the order validate.py checks them.
NUMBER_FIELDS = ("density", "area", "corridor", "ego_max_vel", "wind", "alt", "voxel")
_SUBMISSION_FIELDS = ("submission", "scenarios")
_TOKEN = "a token of 1-64 letters, digits, '_' or '-'"


def is_number(value: Any) -> bool:
    """Whether ``value`` is a finite JSON number: an int or a float, not a bool (validate.py ``isnum``)."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool) and value == value
            and abs(value) != math.inf)


def shown(value: Any, limit: int = 40) -> str:
    """``repr(value)`` for a one-line message, cut to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def frozen_json(value: Any) -> Any:
    """A JSON value made immutable: objects as :class:`FrozenDict`, arrays as tuples."""
    if isinstance(value, dict):
        return FrozenDict({key: frozen_json(item) for key, item in value.items()})
    if isinstance(value, (list, tuple)):
        return tuple(frozen_json(item) for item in value)
    return value


def thawed_json(value: Any) -> Any:
    """The JSON value a :func:`frozen_json` value stands for (objects as dicts, arrays as lists)."""
    if isinstance(value, dict):
        return {key: thawed_json(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [thawed_json(item) for item in value]
    return value


def point(value: Any, where: str, rule: Rule) -> tuple[float, float]:
    """``value`` as an ``(x, y)`` pair [m] if it is ``[x, y]`` with finite numbers (validate.py ``is_xy``), else a
    one-line error naming ``where``."""
    if not isinstance(value, (list, tuple)) or len(value) != 2 or not all(is_number(c) for c in value):
        raise InvalidScenario(f"{where}: expected [x, y] with finite numbers, got {shown(value)}", rule)
    return (value[0], value[1])


@dataclass(frozen=True, slots=True)
class Poles:
    """A scenario's obstacle: poles standing in the lane (``{"type": "poles", "xy", "radius", "height"}``).

    Attributes:
        xy: the poles' positions [m], as (x, y) pairs.
        radius: each pole's radius [m].
        height: each pole's height [m].
    """

    xy: tuple[tuple[float, float], ...]
    radius: float
    height: float

    def __post_init__(self):
        for name in ("radius", "height"):
            if not is_number(getattr(self, name)):
                raise InvalidScenario(f"obstacle.{name}: expected a finite number, got {shown(getattr(self, name))}",
                                      Rule.OBSTACLE_NUMBER)
        if not isinstance(self.xy, (list, tuple)):
            raise InvalidScenario(f"obstacle.xy: expected a list of [x, y] pole positions, got {shown(self.xy)}",
                                  Rule.POLE_COUNT)
        object.__setattr__(self, "xy", tuple(point(p, f"obstacle.xy[{j}]", Rule.POLE_FORM)
                                             for j, p in enumerate(self.xy)))

    @classmethod
    def from_json(cls, obj: Any) -> Poles:
        """The poles of a scenario's ``obstacle`` object; a one-line :class:`InvalidScenario` if it is not one."""
        if not isinstance(obj, dict) or obj.get("type") != "poles":
            raise InvalidScenario(f"obstacle: expected {{\"type\": \"poles\", ...}}, got {shown(obj)}",
                                  Rule.OBSTACLE_TYPE)
        poles = cls(xy=obj.get("xy"), radius=obj.get("radius"), height=obj.get("height"))
        unknown = sorted(set(obj) - set(OBSTACLE_FIELDS))
        if unknown:
            raise InvalidScenario(f"obstacle: unknown field(s) {unknown}; expected only {list(OBSTACLE_FIELDS)}",
                                  Rule.UNKNOWN_OBSTACLE_FIELD)
        return poles

    def to_json(self) -> dict:
        """The ``obstacle`` object as the file writes it."""
        return {"type": "poles", "xy": [list(p) for p in self.xy], "radius": self.radius, "height": self.height}


@dataclass(frozen=True, slots=True)
class Scenario:
    """One scenario of the track (TRACK2027.md section 3), its numbers as the file gives them.

    Attributes:
        id: a token naming the scenario in its submission.
        seed: the procedural forest's seed.
        area: the field's half-width [m].
        voxel: the mapping's voxel size [m].
        corridor: the width of the lane cleared along the route [m].
        density: trees per square metre over the (2 area)^2 field.
        wind: wind speed [m/s].
        ego_max_vel: the planner's top speed [m/s].
        alt: flight altitude [m].
        patrol: the commanded route, 2-6 waypoints (x, y) [m].
        obstacle: the poles.
        metadata: provenance fields (``stratum``, ``turn_total_deg``, ``note``, ``generator``), never flown.

    Example:
        >>> s = Scenario("s000", 41835, 20.0, 0.10, 4.5, 0.0364, 1.7, 1.56, 2.086, ((8.44, 10.92), (11.65, -5.22)),
        ...              Poles(((9.29, 6.3),), 0.06, 3.0))
        >>> Scenario.from_json(s.to_json()) == s
        True
    """

    id: str
    seed: int
    area: float
    voxel: float
    corridor: float
    density: float
    wind: float
    ego_max_vel: float
    alt: float
    patrol: tuple[tuple[float, float], ...]
    obstacle: Poles
    metadata: FrozenDict = field(default_factory=FrozenDict)

    def __post_init__(self):
        check_head(self.id, self.seed, {name: getattr(self, name) for name in NUMBER_FIELDS})
        object.__setattr__(self, "patrol", patrol_of(self.patrol, self.id))
        if not isinstance(self.obstacle, Poles):
            raise InvalidScenario(f"scenario {self.id}: obstacle: expected Poles, got {shown(self.obstacle)}",
                                  Rule.OBSTACLE_TYPE)
        if not isinstance(self.metadata, dict):
            raise InvalidScenario(f"scenario {self.id}: metadata: expected a mapping, got {shown(self.metadata)}",
                                  Rule.UNKNOWN_FIELD)
        unknown = sorted(set(self.metadata) - set(METADATA_FIELDS))
        if unknown:
            raise InvalidScenario(f"scenario {self.id}: unknown field(s) {unknown}; only {list(FLIGHT_FIELDS)} and "
                                  f"the provenance {list(METADATA_FIELDS)}", Rule.UNKNOWN_FIELD)
        object.__setattr__(self, "metadata", frozen_json(self.metadata))

    @classmethod
    def from_json(cls, obj: Any, index: int | None = None) -> Scenario:
        """The scenario a JSON object holds (``index``: its place in the submission, for messages); a one-line
        :class:`InvalidScenario` naming the scenario and the field if it is not one."""
        if not isinstance(obj, dict):
            raise InvalidScenario(f"scenario {index}: expected an object, got {shown(obj)}", Rule.SCENARIO_OBJECT)
        sid = obj.get("id")
        check_head(sid, obj.get("seed"), {name: obj.get(name) for name in NUMBER_FIELDS}, index)
        patrol = patrol_of(obj.get("patrol"), sid)
        try:
            obstacle = Poles.from_json(obj.get("obstacle"))
        except InvalidScenario as err:
            raise err.within(f"scenario {sid}") from None
        unknown = sorted(set(obj) - set(FLIGHT_FIELDS) - set(METADATA_FIELDS))
        if unknown:
            raise InvalidScenario(f"scenario {sid}: unknown field(s) {unknown}; only {list(FLIGHT_FIELDS)} and the "
                                  f"provenance {list(METADATA_FIELDS)}", Rule.UNKNOWN_FIELD)
        numbers = {name: obj[name] for name in NUMBER_FIELDS}
        return cls(id=sid, seed=obj["seed"], patrol=patrol, obstacle=obstacle, **numbers,
                   metadata={key: obj[key] for key in METADATA_FIELDS if key in obj})

    def to_json(self) -> dict:
        """The scenario's JSON object, fields in the README's order, then its provenance."""
        out = {"id": self.id, "seed": self.seed, "area": self.area, "voxel": self.voxel, "corridor": self.corridor,
               "density": self.density, "wind": self.wind, "ego_max_vel": self.ego_max_vel, "alt": self.alt,
               "patrol": [list(w) for w in self.patrol], "obstacle": self.obstacle.to_json()}
        return {**out, **thawed_json(self.metadata)}


def check_head(sid: Any, seed: Any, numbers: dict, index: int | None = None) -> None:
    """A scenario's id (a token), seed (an integer) and numbers (finite), checked in validate.py's order."""
    if not isinstance(sid, str) or not SAFE_TOKEN.match(sid):
        where = "scenario" if index is None else f"scenario {index}"
        raise InvalidScenario(f"{where}: id: expected {_TOKEN}, got {shown(sid)}", Rule.SCENARIO_ID)
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise InvalidScenario(f"scenario {sid}: seed: expected an integer, got {shown(seed)}", Rule.SEED_INTEGER)
    for name, value in numbers.items():
        if not is_number(value):
            raise InvalidScenario(f"scenario {sid}: {name}: expected a finite number, got {shown(value)}"
                                  f"{' (missing)' if value is None else ''}", Rule.NUMBER)


def patrol_of(value: Any, sid: str) -> tuple[tuple[float, float], ...]:
    """A patrol as a tuple of (x, y) waypoints [m], if it is a list of ``[x, y]``; else a one-line error."""
    if not isinstance(value, (list, tuple)):
        raise InvalidScenario(f"scenario {sid}: patrol: expected a list of [x, y] waypoints, got {shown(value)}",
                              Rule.WAYPOINTS)
    try:
        return tuple(point(w, f"patrol[{j}]", Rule.WAYPOINT_FORM) for j, w in enumerate(value))
    except InvalidScenario as err:
        raise err.within(f"scenario {sid}") from None


@dataclass(frozen=True, slots=True)
class Submission:
    """A generator's ``submission.json``: its name and scenarios (any number: :mod:`.rules` wants 20).

    Attributes:
        name: the generator's name, a token.
        scenarios: the scenarios, in the file's order.
        extra: the file's other top-level fields (the kit's random baseline writes ``generator`` and ``gen_seed``),
            which validate.py does not read; kept so that the file is written back as read.
    """

    name: str
    scenarios: tuple[Scenario, ...]
    extra: FrozenDict = field(default_factory=FrozenDict)

    def __post_init__(self):
        if not isinstance(self.name, str) or not SAFE_TOKEN.match(self.name):
            raise InvalidScenario(f"submission: expected {_TOKEN}, got {shown(self.name)}", Rule.SUBMISSION_NAME)
        object.__setattr__(self, "scenarios", tuple(self.scenarios))
        for k, s in enumerate(self.scenarios):
            if not isinstance(s, Scenario):
                raise InvalidScenario(f"scenario {k}: expected a Scenario, got {shown(s)}", Rule.SCENARIO_OBJECT)
        clash = sorted(set(self.extra) & set(_SUBMISSION_FIELDS))
        if clash:
            raise InvalidScenario(f"extra: {clash} are the submission's own fields", Rule.SUBMISSION_SHAPE)
        object.__setattr__(self, "extra", frozen_json(self.extra))

    @classmethod
    def from_json(cls, obj: Any) -> Submission:
        """The submission a JSON document holds; a one-line :class:`InvalidScenario` if it is not one."""
        if not isinstance(obj, dict) or not isinstance(obj.get("scenarios"), list):
            raise InvalidScenario("expected an object with a 'scenarios' list", Rule.SUBMISSION_SHAPE)
        name = obj.get("submission")
        if not isinstance(name, str) or not SAFE_TOKEN.match(name):
            raise InvalidScenario(f"submission: expected {_TOKEN}, got {shown(name)}", Rule.SUBMISSION_NAME)
        scenarios = tuple(Scenario.from_json(s, k) for k, s in enumerate(obj["scenarios"]))
        return cls(name, scenarios, {key: value for key, value in obj.items() if key not in _SUBMISSION_FIELDS})

    def to_json(self) -> dict:
        """The submission's JSON document."""
        return {"submission": self.name, **thawed_json(self.extra), "scenarios": [s.to_json() for s in self.scenarios]}

    def to_text(self) -> str:
        """The file's text: the same submission gives the same bytes (the track runs a generator twice)."""
        return json.dumps(self.to_json(), indent=1, allow_nan=False) + "\n"


def parse_json(text: str, source: str, error: type[Exception] = InvalidScenario) -> Any:
    """The JSON document in ``text``, or a one-line ``error`` naming ``source`` and the place."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise error(f"{source}: not JSON ({err.msg} at line {err.lineno} column {err.colno})") from None
    except RecursionError:
        raise error(f"{source}: not JSON (nested too deeply)") from None


def read_submission(path: str | os.PathLike) -> Submission:
    """A ``submission.json`` as a :class:`Submission`; a one-line :class:`InvalidScenario` naming the file, the
    scenario and the field if its form is wrong (its rules are :func:`.rules.check_submission`'s)."""
    source = os.fspath(path)
    doc = parse_json(read_text(source, "submission", InvalidScenario), source)
    try:
        return Submission.from_json(doc)
    except InvalidScenario as err:
        raise err.within(source) from None


def write_submission(submission: Submission, path: str | os.PathLike) -> None:
    """Write ``submission`` to ``path`` (:meth:`Submission.to_text`)."""
    with open(path, "w", encoding="utf-8") as f:
        f.write(submission.to_text())
