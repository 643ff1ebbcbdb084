"""Missions: QGroundControl ``.plan`` (read and write) and MAVLink ``QGC WPL 110`` (read).

Items are converted to local coordinates relative to a home position with PX4's azimuthal equidistant projection:
x north, y east, z up (metres above home), the same frame as trajectories and obstacles.
The home is, unless given: the position of the first item when it is a takeoff (where the vehicle starts),
else the plan's ``plannedHomePosition`` (or, in a WPL file, item 0).
"""
from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, field
from enum import IntEnum

from .errors import MissionError, read_text, regular_file

EARTH_RADIUS_M = 6371000.0  # PX4 CONSTANTS_RADIUS_OF_EARTH


class Command(IntEnum):
    """The MAV_CMD items the simulated UAV flies."""

    WAYPOINT = 16
    RETURN_TO_LAUNCH = 20
    LAND = 21
    TAKEOFF = 22
    CHANGE_SPEED = 178


NAV_COMMANDS = {Command.WAYPOINT, Command.RETURN_TO_LAUNCH, Command.LAND, Command.TAKEOFF}
#: Mission items that drive a camera or gimbal, not the vehicle (MAVLink's MAV_CMD list): PX4's mission mode runs
#: them without changing the flight, so they are skipped without a warning (the competition's missions open with 530).
NO_FLIGHT_EFFECT = {203: "DO_DIGICAM_CONTROL", 205: "DO_MOUNT_CONTROL", 206: "DO_SET_CAM_TRIGG_DIST",
                    530: "SET_CAMERA_MODE", 2000: "IMAGE_START_CAPTURE", 2001: "IMAGE_STOP_CAPTURE",
                    2500: "VIDEO_START_CAPTURE", 2501: "VIDEO_STOP_CAPTURE"}
# MAV_FRAME values whose altitude is relative to home (or terrain, treated as home here) / absolute (AMSL).
_RELATIVE_FRAMES = {3, 6, 10, 11}
_GLOBAL_FRAMES = {0, 5}
_MISSION_FRAME = 2
_SUPPORTED_SURVEY_VERSIONS = range(3, 6)
_SUPPORTED_TRANSECT_VERSIONS = range(1, 3)


def geo_to_local(lat: float, lon: float, lat0: float, lon0: float) -> tuple[float, float]:
    """(north, east) metres of (lat, lon) from (lat0, lon0): PX4's azimuthal equidistant map projection."""
    la, la0 = math.radians(lat), math.radians(lat0)
    dlon = math.radians(lon - lon0)
    cos_c = math.sin(la0) * math.sin(la) + math.cos(la0) * math.cos(la) * math.cos(dlon)
    c = math.acos(max(-1.0, min(1.0, cos_c)))
    k = 1.0 if abs(c) < 1e-12 else c / math.sin(c)
    north = k * (math.cos(la0) * math.sin(la) - math.sin(la0) * math.cos(la) * math.cos(dlon)) * EARTH_RADIUS_M
    east = k * math.cos(la) * math.sin(dlon) * EARTH_RADIUS_M
    return north, east


def local_to_geo(north: float, east: float, lat0: float, lon0: float) -> tuple[float, float]:
    """Inverse of :func:`geo_to_local`."""
    x, y = north / EARTH_RADIUS_M, east / EARTH_RADIUS_M
    la0, lo0 = math.radians(lat0), math.radians(lon0)
    c = math.hypot(x, y)
    if c < 1e-15:
        return lat0, lon0
    sin_c, cos_c = math.sin(c), math.cos(c)
    lat = math.asin(cos_c * math.sin(la0) + x * sin_c * math.cos(la0) / c)
    lon = lo0 + math.atan2(y * sin_c, c * math.cos(la0) * cos_c - x * math.sin(la0) * sin_c)
    return math.degrees(lat), math.degrees(lon)


@dataclass(frozen=True, slots=True, eq=False)
class MissionItem:
    """One flyable mission item in the local frame (x north, y east, z up above home, metres).

    ``speed`` is set for CHANGE_SPEED items (m/s); ``acceptance_radius`` is the item's own radius (0: use
    NAV_ACC_RAD). Positionless items (RTL, speed change) have x = y = z = nan.
    """

    command: Command
    x: float = math.nan
    y: float = math.nan
    z: float = math.nan
    acceptance_radius: float = 0.0
    speed: float = math.nan
    hold_s: float = 0.0

    @property
    def has_position(self) -> bool:
        """Whether the item has a position (x is not nan)."""
        return not math.isnan(self.x)

    def _values(self) -> tuple:
        return (int(self.command), self.x, self.y, self.z, self.acceptance_radius, self.speed, self.hold_s)

    def __eq__(self, other) -> bool:  # nan fields (no position, no speed) compare equal to nan
        if not isinstance(other, MissionItem):
            return NotImplemented
        return all(a == b or (a != a and b != b) for a, b in zip(self._values(), other._values()))

    def __hash__(self) -> int:
        return hash(tuple(repr(v) for v in self._values()))


@dataclass(frozen=True, slots=True)
class Mission:
    """An immutable mission: flyable items in the local frame, the home they are relative to, and what was skipped."""

    items: tuple[MissionItem, ...]
    home: tuple[float, float, float]  # lat deg, lon deg, alt m AMSL
    cruise_speed: float | None = None
    skipped: tuple[str, ...] = field(default=())  # descriptions of items that were not converted
    source: str | None = None

    def __post_init__(self):
        object.__setattr__(self, "items", tuple(self.items))
        object.__setattr__(self, "skipped", tuple(self.skipped))

    @property
    def waypoints(self) -> list[tuple[float, float, float]]:
        """Positions of the items that have one, in order."""
        return [(it.x, it.y, it.z) for it in self.items if it.has_position]

    def to_plan(self) -> dict:
        """The QGroundControl plan dictionary of this mission (items in MAV_FRAME_GLOBAL_RELATIVE_ALT)."""
        lat0, lon0, alt0 = self.home
        items = []
        for seq, it in enumerate(self.items, start=1):
            if it.has_position:
                lat, lon = local_to_geo(it.x, it.y, lat0, lon0)
                params = [it.hold_s, it.acceptance_radius, 0, None, lat, lon, it.z]
                frame, altitude = 3, it.z
            else:
                speed = 0 if math.isnan(it.speed) else it.speed
                params = [1, speed, -1, 0, 0, 0, 0] if it.command == Command.CHANGE_SPEED else [0] * 7
                frame, altitude = 2, None
            item = {"autoContinue": True, "command": int(it.command), "doJumpId": seq, "frame": frame,
                    "params": params, "type": "SimpleItem"}
            if altitude is not None:
                item.update({"AMSLAltAboveTerrain": None, "Altitude": altitude, "AltitudeMode": 1})
            items.append(item)
        mission = {"cruiseSpeed": self.cruise_speed or 15, "firmwareType": 12, "globalPlanAltitudeMode": 1,
                   "hoverSpeed": 5, "items": items, "plannedHomePosition": list(self.home), "vehicleType": 2,
                   "version": 2}
        return {"fileType": "Plan", "geoFence": {"circles": [], "polygons": [], "version": 2},
                "groundStation": "QGroundControl", "mission": mission,
                "rallyPoints": {"points": [], "version": 2}, "version": 1}


# --- reading ------------------------------------------------------------------------------------------------------
def read_mission(path, home: tuple[float, float] | None = None) -> Mission:
    """Read a ``.plan`` (JSON) or ``QGC WPL 110`` file, chosen by its content."""
    name = regular_file(path, "mission file", MissionError)
    try:
        with open(path, "rb") as f:
            head = f.read(64)
    except OSError as err:
        raise MissionError(f"{name}: cannot read mission file ({err.strerror})") from err
    if head.lstrip().startswith(b"QGC WPL"):
        return read_waypoints(path, home)
    return read_plan(path, home)


def read_plan(path, home: tuple[float, float] | None = None) -> Mission:
    """Read a QGroundControl ``.plan`` file (plan version 1, mission version 2)."""
    name = os.fspath(path)
    text = read_text(path, "mission file", MissionError)
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise MissionError(f"{name}: not a QGroundControl plan (invalid JSON: {err})") from None
    except RecursionError:
        raise MissionError(f"{name}: not a QGroundControl plan (JSON nested too deeply)") from None
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        raise MissionError(f"{name}: not a QGroundControl plan (fileType must be 'Plan')")
    if doc.get("version") != 1:
        raise MissionError(f"{name}: unsupported plan version {doc.get('version')!r} (expected 1)")
    mission = doc.get("mission")
    if not isinstance(mission, dict):
        raise MissionError(f"{name}: plan has no 'mission' section")
    if mission.get("version") != 2:
        raise MissionError(f"{name}: unsupported mission version {mission.get('version')!r} (expected 2)")
    raw_items = mission.get("items")
    if not isinstance(raw_items, list):
        raise MissionError(f"{name}: mission.items must be a list")
    planned = mission.get("plannedHomePosition") or [0.0, 0.0, 0.0]
    simple, skipped = [], []
    for i, item in enumerate(raw_items):
        where = f"{name}: mission.items[{i}]"
        kind = item.get("type") if isinstance(item, dict) else None
        if kind == "SimpleItem":
            simple.append((where, item))
        elif kind == "ComplexItem":
            _expand_complex(item, where, simple, skipped)
        else:
            raise MissionError(f"{where}: unknown item type {kind!r} (expected SimpleItem or ComplexItem)")
    rows = []
    for where, item in simple:
        params = item.get("params")
        if not isinstance(params, list) or len(params) != 7:
            raise MissionError(f"{where}: 'params' must be a list of 7 values")
        rows.append((where, item.get("command"), item.get("frame"), params))
    return _build_mission(name, rows, planned, home, skipped, mission.get("cruiseSpeed"))


def _expand_complex(item: dict, where: str, simple: list, skipped: list) -> None:
    kind = item.get("complexItemType")
    version = item.get("version")
    if kind == "survey":
        if version not in _SUPPORTED_SURVEY_VERSIONS:
            raise MissionError(f"{where}: unsupported survey version {version!r} (expected 3 to 5)")
        transect = item.get("TransectStyleComplexItem")
        if not isinstance(transect, dict):
            raise MissionError(f"{where}: survey has no TransectStyleComplexItem")
        if transect.get("version") not in _SUPPORTED_TRANSECT_VERSIONS:
            raise MissionError(f"{where}: unsupported TransectStyleComplexItem version {transect.get('version')!r}")
        generated = transect.get("Items")
        if not isinstance(generated, list):
            raise MissionError(f"{where}: survey has no generated TransectStyleComplexItem.Items")
        for j, sub in enumerate(generated):
            simple.append((f"{where}.Items[{j}]", sub))
    else:
        skipped.append(f"{where}: complex item {kind!r} (no generated waypoints to fly)")


def read_waypoints(path, home: tuple[float, float] | None = None) -> Mission:
    """Read a MAVLink ``QGC WPL 110`` file; item 0 is the home position."""
    name = os.fspath(path)
    lines = [ln.strip() for ln in read_text(path, "mission file", MissionError).splitlines() if ln.strip()]
    if not lines or not lines[0].startswith("QGC WPL"):
        raise MissionError(f"{name}: not a QGC WPL file (first line must be 'QGC WPL 110')")
    if lines[0].split()[-1] != "110":
        raise MissionError(f"{name}: unsupported WPL version (expected 'QGC WPL 110')")
    rows = []
    planned = None
    for n, line in enumerate(lines[1:], start=2):
        cols = line.split("\t") if "\t" in line else line.split()
        if len(cols) != 12:
            raise MissionError(f"{name}: line {n}: expected 12 columns, got {len(cols)}")
        try:
            seq, frame, command = int(cols[0]), int(cols[2]), int(cols[3])
            params = [float(c) for c in cols[4:11]]
        except ValueError:
            raise MissionError(f"{name}: line {n}: expected numbers (seq, current, frame, command, 7 params)") from None
        if seq == 0 and planned is None:
            planned = params[4:7]
            if command == Command.WAYPOINT:  # item 0 is home, not a waypoint to fly
                continue
        rows.append((f"{name}: line {n}", command, frame, params))
    return _build_mission(name, rows, planned or [0.0, 0.0, 0.0], home, [], None)


def _build_mission(name, rows, planned, home, skipped, cruise_speed) -> Mission:
    """Convert (where, command, frame, params) rows into a Mission relative to the chosen home."""
    skipped, quiet = list(skipped), []
    usable = []
    for where, command, frame, params in rows:
        if command in NO_FLIGHT_EFFECT:
            quiet.append(f"{where}: MAV_CMD {command} ({NO_FLIGHT_EFFECT[command]}) does not move the vehicle "
                         f"(skipped)")
            continue
        try:
            cmd = Command(command)
        except ValueError:
            skipped.append(f"{where}: MAV_CMD {command} is not supported (skipped)")
            continue
        if cmd in NAV_COMMANDS and cmd != Command.RETURN_TO_LAUNCH and frame not in _RELATIVE_FRAMES | _GLOBAL_FRAMES:
            raise MissionError(f"{where}: MAV_CMD {command} with frame {frame} is not supported "
                               f"(expected a global frame: 0, 3, 5, 6, 10 or 11)")
        usable.append((where, cmd, frame, params))
    for s in skipped:
        warnings.warn(s, stacklevel=3)
    if home is None:
        first_pos = next(((p[4], p[5]) for _, c, _, p in usable if c in NAV_COMMANDS and c != Command.RETURN_TO_LAUNCH),
                         None)
        takeoff_first = usable and usable[0][1] == Command.TAKEOFF
        home = first_pos if takeoff_first and first_pos else (planned[0], planned[1])
    lat0, lon0 = float(home[0]), float(home[1])
    alt0 = float(planned[2]) if len(planned) > 2 and planned[2] is not None else 0.0
    items = []
    for where, cmd, frame, p in usable:
        if cmd == Command.CHANGE_SPEED:
            items.append(MissionItem(cmd, speed=float(p[1])))
        elif cmd == Command.RETURN_TO_LAUNCH:
            items.append(MissionItem(cmd))
        else:
            lat, lon, alt = p[4], p[5], p[6]
            if lat is None or lon is None or alt is None:
                raise MissionError(f"{where}: MAV_CMD {int(cmd)} needs latitude, longitude and altitude")
            if not (-90 <= lat <= 90 and -180 <= lon <= 180):
                raise MissionError(f"{where}: latitude/longitude ({lat}, {lon}) out of range")
            north, east = geo_to_local(lat, lon, lat0, lon0)
            up = float(alt) - alt0 if frame in _GLOBAL_FRAMES else float(alt)
            if up < 0 and cmd != Command.LAND:
                warnings.warn(f"{where}: altitude {up:.1f} m is below home (frame {frame}: "
                              f"{'AMSL' if frame in _GLOBAL_FRAMES else 'relative'})", stacklevel=3)
            radius = float(p[1] or 0.0) if cmd == Command.WAYPOINT else 0.0
            hold = float(p[0] or 0.0) if cmd == Command.WAYPOINT else 0.0
            items.append(MissionItem(cmd, north, east, up, acceptance_radius=radius, hold_s=hold))
    return Mission(tuple(items), (lat0, lon0, alt0), cruise_speed, tuple(quiet + skipped), name)


def write_plan(mission: Mission, path) -> None:
    """Write a mission as a QGroundControl ``.plan`` file that :func:`read_plan` and QGroundControl load."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(mission.to_plan(), f, indent=4)
        f.write("\n")
