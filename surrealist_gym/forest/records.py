"""The track's flown data as immutable values: the kit's flight records and the train manifest's records.

- ``flights/*.json`` (the track's kit; TRACK2027.md section 3): one flight each, with its scenario's numbers
  (``params``), its route, the lane's centre line as sampled points, the forest as flown (trees: x, y, scale,
  species), the poles, and the flown track (rows of t, x, y, z and a fifth column the kit does not name, at 0.1 s).
  A flight record holds neither the forest seed nor the poles' height: :meth:`FlightRecord.scenario` takes them
  (the train manifest's record of the same scenario has both).
- ``data/train/manifest.jsonl`` (TRACK2027.md section 6): one flight a line, with its scenario, the scene as
  delivered, the outcome and, for a collision, the mechanisms it reached ([object, part, phase]; null when the
  contact record could not be read). Only the train split is read: a record of any other split is skipped, since
  the val split is held out (TRACK2027.md section 6).

A record that is not of this form gets a one-line :class:`~surrealist_gym.errors.LogFormatError` naming the file
(and line), the field and what is wrong.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from ..errors import FrozenDict, LogFormatError, read_text
from .scenario import NUMBER_FIELDS, Poles, Scenario, frozen_json, is_number, parse_json, point, shown
from .space import InvalidScenario, Rule

TRAIN_SPLIT = "train"
_MAX_BYTES = 64 * 1024 * 1024  # a manifest of some thousand flights; the train split's is 0.5 MB


class Outcome(str, Enum):
    """How a flight ended (TRACK2027.md section 6); only a collision is a failure."""

    GOAL = "goal"
    COLLISION = "collision"
    FAILED = "failed"
    TIMEOUT = "timeout"


class StruckObject(str, Enum):
    """What a collision struck (TRACK2027.md section 4)."""

    POLE = "pole"
    TREE = "tree"
    TERRAIN = "terrain"


class VehiclePart(str, Enum):
    """The part of the vehicle that struck (TRACK2027.md section 4)."""

    BODY = "body"
    ROTOR = "rotor"


class RoutePhase(str, Enum):
    """Where on the route a strike fell: a turn within 3.0 m of a waypoint, a leg otherwise (TRACK2027.md 4)."""

    TURN = "turn"
    LEG = "leg"


class Species(str, Enum):
    """A tree's species in the procedural forest (TRACK2027.md section 3)."""

    BIRCH = "birch"
    PINE = "pine"
    SPRUCE = "spruce"


@dataclass(frozen=True, slots=True)
class Mechanism:
    """One of the 12 failure mechanisms a collision reaches: (object, vehicle part, route phase)."""

    struck: StruckObject
    part: VehiclePart
    phase: RoutePhase


@dataclass(frozen=True, slots=True)
class Tree:
    """A tree of a flown forest: position x, y [m], scale and species."""

    x: float
    y: float
    scale: float
    species: Species


@dataclass(frozen=True, slots=True)
class TrackSample:
    """A row of a flown track: time t [s], position x, y, z [m], and the kit's unnamed fifth column."""

    t: float
    x: float
    y: float
    z: float
    fifth: float


class _Fields:
    """Reads one JSON object's fields, each checked, into values; errors name ``where`` and the field."""

    def __init__(self, obj: Any, where: str, name: str = ""):
        if not isinstance(obj, dict):
            raise LogFormatError(f"{where}: {name or 'record'}: expected an object, got {shown(obj)}")
        self.obj, self.where, self.prefix = obj, where, f"{name}." if name else ""

    def bad(self, key: str, expected: str) -> LogFormatError:
        value = self.obj.get(key)
        got = "nothing (missing)" if key not in self.obj else shown(value)
        return LogFormatError(f"{self.where}: {self.prefix}{key}: expected {expected}, got {got}")

    def number(self, key: str) -> float:
        if not is_number(self.obj.get(key)):
            raise self.bad(key, "a finite number")
        return self.obj[key]

    def integer(self, key: str) -> int:
        value = self.obj.get(key)
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.bad(key, "an integer")
        return value

    def flag(self, key: str) -> bool:
        if not isinstance(self.obj.get(key), bool):
            raise self.bad(key, "true or false")
        return self.obj[key]

    def text(self, key: str, optional: bool = False) -> str | None:
        value = self.obj.get(key)
        if not (isinstance(value, str) or (optional and value is None and key in self.obj)):
            raise self.bad(key, "a string" + (" or null" if optional else ""))
        return value

    def choice(self, key: str, enum: type[Enum]) -> Any:
        try:
            return enum(self.obj.get(key))
        except ValueError:
            raise self.bad(key, f"one of {[e.value for e in enum]}") from None

    def rows(self, key: str, width: int) -> list:
        value = self.obj.get(key)
        if not isinstance(value, list) or not all(isinstance(r, list) and len(r) == width for r in value):
            raise self.bad(key, f"a list of rows of {width}")
        return value

    def points(self, key: str) -> tuple[tuple[float, float], ...]:
        try:
            rows = self.rows(key, 2)
            return tuple(point(p, f"{self.prefix}{key}[{j}]", Rule.WAYPOINT_FORM) for j, p in enumerate(rows))
        except InvalidScenario as err:
            raise LogFormatError(f"{self.where}: {err}") from None

    def mechanisms(self, key: str) -> tuple[Mechanism, ...] | None:
        value = self.obj.get(key)
        if value is None and key in self.obj:
            return None
        try:
            return tuple(Mechanism(StruckObject(o), VehiclePart(p), RoutePhase(h)) for o, p, h in self.rows(key, 3))
        except ValueError:
            raise self.bad(key, "[object, part, phase] rows of pole|tree|terrain, body|rotor, turn|leg") from None

    def mapping(self, key: str) -> FrozenDict:
        if not isinstance(self.obj.get(key), dict):
            raise self.bad(key, "an object")
        return frozen_json(self.obj[key])

    def params(self, key: str = "params") -> FrozenDict:
        inner = _Fields(self.obj.get(key), self.where, self.prefix + key)
        return FrozenDict({name: inner.number(name) for name in NUMBER_FIELDS})

    def extra(self, known: tuple[str, ...]) -> FrozenDict:
        return frozen_json({k: v for k, v in self.obj.items() if k not in known})


@dataclass(frozen=True, slots=True)
class FlightRecord:
    """One of the kit's flight records (``flights/*.json``): a flown scenario, its forest and its track.

    Attributes:
        id: the scenario's id (as in the train manifest).
        outcome: how the flight ended.
        mechanism: the mechanisms its collision reached (empty without one; None if the contact was not read).
        params: the scenario's numbers (density, area, corridor, ego_max_vel, wind, alt, voxel).
        route: the commanded route's waypoints (x, y) [m].
        lane: the lane's centre line as sampled points (x, y) [m].
        trees: the forest as flown.
        poles: the poles' positions (x, y) [m].
        pole_radius: the poles' radius [m].
        t_end: when the flight ended [s].
        clip_start: where the track's clip starts [s].
        track: the flown track at 0.1 s.
        extra: the record's other fields, if any.
    """

    id: str
    outcome: Outcome
    mechanism: tuple[Mechanism, ...] | None
    params: FrozenDict
    route: tuple[tuple[float, float], ...]
    lane: tuple[tuple[float, float], ...]
    trees: tuple[Tree, ...]
    poles: tuple[tuple[float, float], ...]
    pole_radius: float
    t_end: float
    clip_start: float
    track: tuple[TrackSample, ...]
    extra: FrozenDict = field(default_factory=FrozenDict)

    def scenario(self, seed: int, pole_height: float) -> Scenario:
        """The scenario flown, given what the record lacks: the forest ``seed`` and the poles' height [m]."""
        return Scenario(id=self.id, seed=seed, patrol=self.route, obstacle=Poles(self.poles, self.pole_radius,
                                                                                 pole_height), **self.params)


_FLIGHT_FIELDS = ("id", "outcome", "mechanism", "params", "area", "corridor", "route", "lane", "trees", "poles",
                  "pole_radius", "t_end", "clip_start", "track")


def read_flight(path: str | os.PathLike) -> FlightRecord:
    """A flight record of the kit (``flights/*.json``); a one-line :class:`LogFormatError` naming the file and the
    field if it is not one."""
    where = os.fspath(path)
    doc = parse_json(read_text(where, "flight record", LogFormatError, _MAX_BYTES), where, LogFormatError)
    f = _Fields(doc, where)
    params = f.params()
    for key in ("area", "corridor"):
        if f.number(key) != params[key]:
            raise f.bad(key, f"params.{key} ({params[key]})")
    trees = []
    for j, (x, y, scale, species) in enumerate(f.rows("trees", 4)):
        tree = _Fields({"x": x, "y": y, "scale": scale, "species": species}, where, f"trees[{j}]")
        trees.append(Tree(tree.number("x"), tree.number("y"), tree.number("scale"), tree.choice("species", Species)))
    track = []
    for j, row in enumerate(f.rows("track", 5)):
        if not all(is_number(v) for v in row):
            raise LogFormatError(f"{where}: track[{j}]: expected 5 finite numbers, got {shown(row)}")
        track.append(TrackSample(*row))
    return FlightRecord(id=f.text("id"), outcome=f.choice("outcome", Outcome), mechanism=f.mechanisms("mechanism"),
                        params=params, route=f.points("route"), lane=f.points("lane"), trees=tuple(trees),
                        poles=f.points("poles"), pole_radius=f.number("pole_radius"), t_end=f.number("t_end"),
                        clip_start=f.number("clip_start"), track=tuple(track), extra=f.extra(_FLIGHT_FIELDS))


class CollectionStatus(str, Enum):
    """Whether a flight gave a usable record (TRACK2027.md section 6: ``collection_status``)."""

    VALID = "valid"
    INVALID = "invalid"


@dataclass(frozen=True, slots=True)
class SceneDelivery:
    """What the scene generator delivered for a flight: trees and poles requested and placed, density."""

    min_spacing: float  # [m] between trees
    trees_requested: int
    trees_placed: int
    poles_requested: int
    poles_placed: int
    density_requested: float  # [trees/m^2]
    density_delivered: float  # [trees/m^2]
    shortfall: bool
    pole_shortfall: bool


@dataclass(frozen=True, slots=True)
class ManifestRecord:
    """One flight of the train manifest (TRACK2027.md section 6).

    Attributes:
        split: the split ("train").
        scenario: the scenario flown (its id is the manifest's ``scenario``).
        repeat: the repeat's number.
        git: the stack's commit.
        scene: what the scene generator delivered.
        outcome: how the flight ended.
        collection_status: whether the flight gave a usable record.
        admissible: whether the flight counts.
        inadmissible_reason: why not, or None.
        invalidated_by: what invalidated it, or None.
        heavy_ok: whether its heavy artefacts (maps, logs) are complete.
        wall_s: wall time of the flight [s].
        failure_reason: the stack's reason for a failure, or None.
        mechanism: the mechanisms its collision reached (empty without one; None if the contact was not read).
        stack, camera, yaw_delivery, artifacts: those blocks of the record, read-only.
        extra: the record's other fields, if any.
    """

    split: str
    scenario: Scenario
    repeat: int
    git: str
    scene: SceneDelivery
    outcome: Outcome
    collection_status: CollectionStatus
    admissible: bool
    inadmissible_reason: str | None
    invalidated_by: str | None
    heavy_ok: bool
    wall_s: float
    failure_reason: str | None
    mechanism: tuple[Mechanism, ...] | None
    stack: FrozenDict
    camera: FrozenDict
    yaw_delivery: FrozenDict
    artifacts: FrozenDict
    extra: FrozenDict = field(default_factory=FrozenDict)

    @property
    def counts(self) -> bool:
        """Whether the flight is valid and admissible (245 of the train split's 267; TRACK2027.md section 6)."""
        return self.collection_status is CollectionStatus.VALID and self.admissible


_RECORD_FIELDS = ("split", "scenario", "repeat", "seed", "git", "params", "patrol", "poles", "scene", "outcome",
                  "collection_status", "wall_s", "admissible", "inadmissible_reason", "heavy_ok", "stack",
                  "failure_reason", "invalidated_by", "camera", "yaw_delivery", "artifacts", "mechanism")


def manifest_record(obj: Any, where: str) -> ManifestRecord:
    """The record a manifest line's object holds; a one-line :class:`LogFormatError` naming ``where`` (the file and
    line) and the field if it is not one."""
    f = _Fields(obj, where)
    try:
        scenario = Scenario.from_json({"id": obj.get("scenario"), "seed": obj.get("seed"), "patrol": obj.get("patrol"),
                                       "obstacle": obj.get("poles"), **f.params()})
    except InvalidScenario as err:
        raise LogFormatError(f"{where}: {err}") from None
    s = _Fields(obj.get("scene"), where, "scene")
    scene = SceneDelivery(s.number("min_spacing"), s.integer("trees_requested"), s.integer("trees_placed"),
                          s.integer("poles_requested"), s.integer("poles_placed"), s.number("density_requested"),
                          s.number("density_delivered"), s.flag("shortfall"), s.flag("pole_shortfall"))
    return ManifestRecord(
        split=f.text("split"), scenario=scenario, repeat=f.integer("repeat"), git=f.text("git"), scene=scene,
        outcome=f.choice("outcome", Outcome), collection_status=f.choice("collection_status", CollectionStatus),
        admissible=f.flag("admissible"), inadmissible_reason=f.text("inadmissible_reason", optional=True),
        invalidated_by=f.text("invalidated_by", optional=True), heavy_ok=f.flag("heavy_ok"),
        wall_s=f.number("wall_s"), failure_reason=f.text("failure_reason", optional=True),
        mechanism=f.mechanisms("mechanism"), stack=f.mapping("stack"), camera=f.mapping("camera"),
        yaw_delivery=f.mapping("yaw_delivery"), artifacts=f.mapping("artifacts"), extra=f.extra(_RECORD_FIELDS))


def read_train_manifest(path: str | os.PathLike) -> tuple[ManifestRecord, ...]:
    """The train split's records of a manifest (``data/train/manifest.jsonl``), in the file's order; records of any
    other split are skipped unread beyond their ``split``. A one-line :class:`LogFormatError` naming the file, the
    line and the field for a record that is not of the form."""
    name = os.fspath(path)
    records = []
    for number, line in enumerate(read_text(name, "manifest", LogFormatError, _MAX_BYTES).splitlines(), start=1):
        if line.strip():
            obj = parse_json(line, f"{name}:{number}", LogFormatError)
            if isinstance(obj, dict) and obj.get("split") != TRAIN_SPLIT:
                continue
            records.append(manifest_record(obj, f"{name}:{number}"))
    return tuple(records)
