"""Test cases: immutable ``TestCase`` and ``Obstacle`` values, and the Aerialist YAML they load from and save to.

Obstacle frame (PRODUCT.md): ``x, y`` = footprint centre (x north, y east), ``z`` = base height (0 = on the ground),
``r`` = yaw in degrees, positive from north toward east; ``l`` along the obstacle's x axis, ``w`` along y, ``h`` up.
A cylinder has diameter ``l`` (= ``w``); Aerialist's YAML gives its radius as ``size.r``.

The YAML is Aerialist's, as both generations in use read and write it (docs/aerialist-yaml.md): :func:`save_test`
writes what Aerialist master (``robot``/``mission``) and 0.2.x (``drone``/``test``) both load with geometry, and
:func:`load_test` reads what either writes; a field that changes the flight and cannot be simulated is a one-line
error, one that Aerialist's own flight would not miss a one-line warning naming the file. :func:`export_test` writes
a YAML whose files travel with its folder.
"""
from __future__ import annotations

import csv
import functools
import json
import math
import shutil
import warnings
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from pathlib import Path
from typing import Mapping

from .errors import InvalidTestCase, MissionError, regular_file
from .frozendict import FrozenDict
from .mission import Mission, read_mission
from .ranges import param_problem


class Shape(str, Enum):
    BOX = "box"
    CYLINDER = "cylinder"


#: Shape names read (in any case), by the shape they mean. Aerialist compares ``box`` and ``cylinder`` with ``==``
#: and builds any other name without geometry: the YAML loader reads the others (surrealist-gym's earlier ``BOX``
#: and ``TREE``) with a warning.
_SHAPE_NAMES = {"box": Shape.BOX, "apartment": Shape.BOX, "cylinder": Shape.CYLINDER, "tree": Shape.CYLINDER}
MAX_EXTENT_M = 10_000.0  # [m] obstacles beyond this size or distance are a typo, not a test


@dataclass(frozen=True, slots=True)
class Obstacle:
    """A box or cylinder obstacle (metres, degrees)."""

    l: float
    w: float
    h: float
    x: float
    y: float
    z: float = 0.0
    r: float = 0.0
    shape: Shape = Shape.BOX

    def __post_init__(self):
        for name in ("l", "w", "h", "x", "y", "z", "r"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InvalidTestCase(f"obstacle field {name!r}: expected a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        for name in ("l", "w", "h"):
            if getattr(self, name) <= 0:
                raise InvalidTestCase(f"obstacle size {name!r} must be positive, got {getattr(self, name):g}")
        for name in ("l", "w", "h", "x", "y", "z"):
            if abs(getattr(self, name)) > MAX_EXTENT_M:
                raise InvalidTestCase(f"obstacle field {name!r}: expected at most {MAX_EXTENT_M:g} m in size, got "
                                      f"{getattr(self, name):g}")
        if self.z < 0:
            raise InvalidTestCase(f"obstacle position 'z' (base height) must be >= 0, got {self.z:g}")
        object.__setattr__(self, "shape", _parse_shape(self.shape))
        if self.shape == Shape.CYLINDER:
            object.__setattr__(self, "w", self.l)  # a cylinder's size is its diameter l

    # --- geometry -----------------------------------------------------------------------------------------------
    def footprint(self) -> list[tuple[float, float]]:
        """Corners of the box footprint (counter-clockwise in the x-y plane); for a cylinder, of its bounding box."""
        c, s = math.cos(math.radians(self.r)), math.sin(math.radians(self.r))
        half = [(self.l / 2, self.w / 2), (-self.l / 2, self.w / 2), (-self.l / 2, -self.w / 2),
                (self.l / 2, -self.w / 2)]
        return [(self.x + c * a - s * b, self.y + s * a + c * b) for a, b in half]

    def overlaps(self, other: "Obstacle") -> bool:
        """Whether the two solids intersect (separating-axis test on footprints, then heights)."""
        if self.z >= other.z + other.h or other.z >= self.z + self.h:
            return False
        if self.shape == Shape.CYLINDER and other.shape == Shape.CYLINDER:
            return math.hypot(self.x - other.x, self.y - other.y) < (self.l + other.l) / 2
        if Shape.CYLINDER in (self.shape, other.shape):
            cyl, box = (self, other) if self.shape == Shape.CYLINDER else (other, self)
            return box.distance_2d(cyl.x, cyl.y) < cyl.l / 2
        return _polygons_intersect(self.footprint(), other.footprint())

    def distance_2d(self, px: float, py: float) -> float:
        """Distance from a point to the footprint (0 inside)."""
        dx, dy = px - self.x, py - self.y
        if self.shape == Shape.CYLINDER:
            return max(0.0, math.hypot(dx, dy) - self.l / 2)
        c, s = math.cos(math.radians(self.r)), math.sin(math.radians(self.r))
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        ex, ey = max(abs(lx) - self.l / 2, 0.0), max(abs(ly) - self.w / 2, 0.0)
        return math.hypot(ex, ey)

    # --- Aerialist forms ----------------------------------------------------------------------------------------
    def to_list(self) -> list[float]:
        """Aerialist's flat form ``[l, w, h, x, y, z, r]``."""
        return [self.l, self.w, self.h, self.x, self.y, self.z, self.r]

    def to_dict(self) -> dict:
        """Aerialist's dict form, as both generations read it: ``shape`` ``box`` or ``cylinder`` (lower case),
        ``size.r`` a cylinder's radius (0 for a box)."""
        return {"shape": self.shape.value,
                "size": {"l": self.l, "w": self.w, "h": self.h, "r": self.l / 2 if self.shape == Shape.CYLINDER else 0},
                "position": {"x": self.x, "y": self.y, "z": self.z, "r": self.r}}


def _parse_shape(value) -> Shape:
    if isinstance(value, Shape):
        return value
    shape = _SHAPE_NAMES.get(value.lower()) if isinstance(value, str) else None
    if shape is None:
        raise InvalidTestCase(f"obstacle field 'shape': unknown shape {value!r} (expected box or cylinder)")
    return shape


def _polygons_intersect(a, b) -> bool:
    for poly in (a, b):
        for i in range(len(poly)):
            (x1, y1), (x2, y2) = poly[i], poly[(i + 1) % len(poly)]
            nx, ny = y1 - y2, x2 - x1
            pa = [nx * x + ny * y for x, y in a]
            pb = [nx * x + ny * y for x, y in b]
            if max(pa) <= min(pb) + 1e-9 or max(pb) <= min(pa) + 1e-9:
                return False
    return True


@dataclass(frozen=True, slots=True)
class RuntimeCommand:
    """An Aerialist runtime command (``timestamp,mode,x,y,z,r``); mode 3 with timestamp 1 = arm and start mission."""

    timestamp: float
    mode: int
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    r: float = 0.0

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if not _finite(value):
                raise InvalidTestCase(f"command field {f.name!r}: expected a finite number, got {value!r}")
        if self.timestamp < 0:
            raise InvalidTestCase(f"command field 'timestamp': expected a number >= 0 [s], got {self.timestamp:g}")
        if self.mode != int(self.mode):
            raise InvalidTestCase(f"command field 'mode': expected a whole number, got {self.mode:g}")
        object.__setattr__(self, "mode", int(self.mode))

    def to_dict(self) -> dict:
        return {"timestamp": self.timestamp, "mode": self.mode, "x": self.x, "y": self.y, "z": self.z, "r": self.r}


# Physical range of a test's wind. 30 m/s is Beaufort force 11 ("violent storm", 28.5-32.6 m/s) and well past what a
# ~1.5 kg Iris can hold: even at PX4's 45 degree tilt limit (MPC_TILTMAX_AIR) its horizontal thrust, m g = 14.7 N,
# only balances the modelled Iris' drag (sim/vehicle.py: 0.21 v + 0.02 v^2 N) at ~22 m/s, and the simulated SITL Iris
# already drifts ~70 m off mission1's track in a 15 m/s crosswind. A larger speed is a typo or a unit mix-up (km/h
# for m/s), not a test; up to the bound, a test may still probe winds the vehicle cannot hold.
MAX_WIND_SPEED_MS = 30.0  # [m/s] bound of every wind speed (means and maxima)
# The speed's standard deviation may reach the bound itself, so a variance up to its square [m^2/s^2].
MAX_WIND_SPEED_VARIANCE = MAX_WIND_SPEED_MS ** 2
# The plugin adds N(0, variance) to each component of the (normalised) mean direction. At a standard deviation of 1
# the noise is as large as the mean direction, so the direction is close to uniform, and Gazebo, which does not
# renormalise the drawn vector, already doubles the mean speed; a larger variance no longer describes a direction.
MAX_WIND_DIRECTION_VARIANCE = 1.0
_WIND_SPEED_VARIANCES = ("velocity_variance", "gust_velocity_variance")
_WIND_DIRECTION_VARIANCES = ("direction_variance", "gust_direction_variance")
_WIND_TIMES = ("gust_start", "gust_duration")


@dataclass(frozen=True, slots=True)
class Wind:
    """Wind in Aerialist's (Gazebo wind plugin) terms; speeds m/s, times s, directions as 3-vectors (NED).

    Checked against a physical range (one-line :class:`InvalidTestCase` naming the field): every number finite and
    >= 0; speeds at most :data:`MAX_WIND_SPEED_MS`; speed variances at most :data:`MAX_WIND_SPEED_VARIANCE`,
    direction variances at most :data:`MAX_WIND_DIRECTION_VARIANCE`; directions not all zero (the plugin normalises
    them); a maximum speed, when given (non-zero), at least its mean. A maximum of 0 means "not given" (the default,
    as when an Aerialist file leaves it out): the simulator then caps the speed at its mean. Gazebo itself would
    take an explicit 0 literally and blow no wind at all.
    """

    velocity_mean: float = 0.0
    velocity_max: float = 0.0
    velocity_variance: float = 0.0
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    direction_variance: float = 0.0
    gust_start: float = 0.0
    gust_duration: float = 0.0
    gust_velocity_mean: float = 0.0
    gust_velocity_max: float = 0.0
    gust_velocity_variance: float = 0.0
    gust_direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    gust_direction_variance: float = 0.0

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name.endswith("direction"):
                if not (isinstance(v, (list, tuple)) and len(v) == 3 and all(_finite(c) for c in v)):
                    raise InvalidTestCase(f"wind field {f.name!r}: expected 3 finite numbers, got {v!r}")
                if not any(c != 0 for c in v):
                    raise InvalidTestCase(f"wind field {f.name!r}: expected a direction (not all zero), got {v!r}")
                object.__setattr__(self, f.name, tuple(float(c) for c in v))
                continue
            if not _finite(v) or v < 0:
                raise InvalidTestCase(f"wind field {f.name!r}: expected a finite number >= 0, got {v!r}")
            bound, expected = _wind_bound(f.name)
            if v > bound:
                raise InvalidTestCase(f"wind field {f.name!r}: expected {expected}, got {v:g}")
            object.__setattr__(self, f.name, float(v))  # 8 and 8.0 are one wind, so one key
        for prefix in ("", "gust_"):
            mean, vmax = getattr(self, prefix + "velocity_mean"), getattr(self, prefix + "velocity_max")
            if vmax != 0 and vmax < mean:
                raise InvalidTestCase(f"wind field {prefix + 'velocity_max'!r}: expected 0 (not given) or at least "
                                      f"{prefix}velocity_mean ({mean:g} m/s), got {vmax:g}")

    def to_dict(self) -> dict:
        return {f.name: (list(getattr(self, f.name)) if f.name.endswith("direction") else getattr(self, f.name))
                for f in fields(self)}


def _wind_bound(name: str) -> tuple[float, str]:
    """The largest physical value of a scalar wind field, and the range as a message states it."""
    if name in _WIND_TIMES:
        return math.inf, "a finite number >= 0 [s]"
    if name in _WIND_SPEED_VARIANCES:
        return MAX_WIND_SPEED_VARIANCE, f"at most {MAX_WIND_SPEED_VARIANCE:g} m^2/s^2 (a standard deviation of " \
                                        f"{MAX_WIND_SPEED_MS:g} m/s)"
    if name in _WIND_DIRECTION_VARIANCES:
        return MAX_WIND_DIRECTION_VARIANCE, f"at most {MAX_WIND_DIRECTION_VARIANCE:g} (a standard deviation as " \
                                            f"large as the unit direction)"
    return MAX_WIND_SPEED_MS, f"at most {MAX_WIND_SPEED_MS:g} m/s (Beaufort 11, a violent storm)"


@dataclass(frozen=True, slots=True)
class TestCase:
    """One simulation-based test: mission, obstacles, UAV parameters, wind, runtime commands, reference log.

    File references are kept as absolute paths (``mission_file``, ``params_file``, ``commands_file``,
    ``reference_log``); ``mission`` and ``params`` hold their loaded contents. ``assertion_log`` is the real flight
    the YAML's assertion names, as written, when the file is not at hand (else ``reference_log`` holds it).
    ``timeout`` is the test's own time limit [s of simulated time] (Aerialist's ``simulation.timeout``), None when it
    gives none. A mutation makes a new value (``dataclasses.replace`` or :meth:`with_obstacles`).
    """

    __test__ = False  # not a pytest class

    mission: Mission | None = None
    obstacles: tuple[Obstacle, ...] = ()
    params: Mapping[str, float] = field(default_factory=dict)
    wind: Wind | None = None
    commands: tuple[RuntimeCommand, ...] = ()
    mission_file: str | None = None
    params_file: str | None = None
    commands_file: str | None = None
    reference_log: str | None = None
    home: tuple[float, float, float] | None = None
    assertion_log: str | None = None
    timeout: float | None = None

    def __post_init__(self):
        if self.timeout is not None:
            if not _finite(self.timeout) or self.timeout <= 0:
                raise InvalidTestCase(f"timeout: expected a positive number of seconds, got {self.timeout!r}")
            object.__setattr__(self, "timeout", float(self.timeout))
        obstacles = tuple(self.obstacles)
        for i, o in enumerate(obstacles):
            if not isinstance(o, Obstacle):
                raise InvalidTestCase(f"obstacles[{i}]: expected an Obstacle, got {type(o).__name__}")
        for i in range(len(obstacles)):
            for j in range(i + 1, len(obstacles)):
                if obstacles[i].overlaps(obstacles[j]):
                    raise InvalidTestCase(f"obstacles[{i}] and obstacles[{j}] overlap")
        object.__setattr__(self, "obstacles", obstacles)
        object.__setattr__(self, "commands", tuple(self.commands))
        params = {}
        for k, v in dict(self.params).items():
            bad = param_problem(str(k), v)  # a PX4 parameter or uav.* setting in its physical range
            if bad:
                raise InvalidTestCase(f"params.{k}: {bad}")
            params[str(k)] = v
        object.__setattr__(self, "params", FrozenDict(params))
        if self.mission is not None and not isinstance(self.mission, Mission):
            raise InvalidTestCase(f"mission: expected a Mission, got {type(self.mission).__name__}")

    def __hash__(self) -> int:
        return hash(self.key())

    def with_obstacles(self, obstacles) -> "TestCase":
        """A new test case with other obstacles (checked for validity)."""
        return replace(self, obstacles=tuple(obstacles))

    @property
    def replicates_flight(self) -> bool:
        """Whether the test stands for a real flight (its assertion names a log, as the paper's seeds do)."""
        return bool(self.reference_log or self.assertion_log)

    def key(self) -> str:
        """A canonical JSON string of what the simulation depends on (memo and store key)."""
        what = {
            "mission": None if self.mission is None else self.mission.to_plan()["mission"]["items"],
            "home": None if self.mission is None else list(self.mission.home),
            "obstacles": [[round(v, 9) for v in o.to_list()] + [o.shape.value] for o in self.obstacles],
            "params": dict(sorted(self.params.items())),
            "wind": None if self.wind is None else self.wind.to_dict(),
            "commands": [c.to_dict() for c in self.commands],
        }
        if self.timeout is not None:  # only then: the keys of tests without one stay as they were
            what["timeout"] = self.timeout
        return json.dumps(what, sort_keys=True)


# --- YAML --------------------------------------------------------------------------------------------------------
#: Top-level sections: Aerialist master's (robot, simulation, mission, assertion, agent), 0.2.x's (drone, test) and
#: ``surrealist``, which both Aerialist generations ignore: it names a real flight the assertion cannot (not at hand).
_SECTIONS = {"robot", "drone", "simulation", "mission", "test", "assertion", "agent", "surrealist"}
_ROBOT_KEYS = {"port", "params", "params_file", "mission_file"}
_SIM_KEYS = {"simulator", "world", "speed", "headless", "obstacles", "home_position", "wind", "timeout"}
_MISSION_KEYS = {"commands", "commands_file", "speed", "waypoints"}
_ASSERT_KEYS = {"log_file", "variable"}
_AGENT_KEYS = {"engine", "count", "path", "id"}
_OWN_KEYS = {"assertion_log"}
#: Aerialist's PX4 ports (RobotConfig, DroneConfig) by the names both generations read; 14550 is a real vehicle's.
PORTS = {"sitl": 14540, "sim": 14540, "px4_sitl": 14540, "ros": 14541, "avoidance": 14541, "px4_ros": 14541,
         "cf": 14550, "hw": 14550, "px4_cf": 14550}
SITL_PORT, AVOIDANCE_PORT, VEHICLE_PORT = 14540, 14541, 14550
SIMULATORS = ("gazebo", "ros", "jmavsim")
AGENTS = ("local", "docker", "k8s")
#: Where :func:`export_test` copies the files a test names (the folder the competition's own YAMLs name them in).
FILES_FOLDER = "case_studies"
_FILE_FIELDS = ("mission_file", "params_file", "commands_file", "reference_log")
README_TITLE = "# Aerialist test cases"


def load_test(path) -> TestCase:
    """Load an Aerialist test-case YAML, as Aerialist master or 0.2.x writes it (docs/aerialist-yaml.md).

    Sections under either generation's names (``robot``/``drone``, ``mission``/``test``; both given: they must be
    equal). Obstacles in the flat form ``[l,w,h,x,y,z,r]*`` or as dicts (``shape`` box or cylinder, ``size.r`` a
    cylinder's radius). The simulation's ``timeout`` (times its ``speed``: Aerialist's clock is the wall's) limits the
    flight. What cannot be flown is a one-line error naming the file and field (a real vehicle's port, an unknown
    simulator or field); what Aerialist's flight would not miss is read with one warning line naming the file
    (a shape name Aerialist reads without geometry, jMAVSim, ``agent.count``). Relative file paths are resolved
    against the YAML's folder, then its parents (the paper's seeds name paths relative to their repository root),
    then by file name in the YAML's folder.
    """
    path = Path(path)
    name = regular_file(path, "test case", InvalidTestCase)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise InvalidTestCase(f"{name}: cannot read test case ({err.strerror})") from err
    except UnicodeDecodeError as err:
        raise InvalidTestCase(f"{name}: not UTF-8 text (byte {err.start})") from None
    doc = safe_yaml(text, name)
    if not isinstance(doc, dict):
        raise InvalidTestCase(f"{name}: expected a mapping with sections {sorted(_SECTIONS)}")
    unknown = set(doc) - _SECTIONS
    if unknown:
        raise InvalidTestCase(f"{name}: unknown section {sorted(unknown)[0]!r} (expected {sorted(_SECTIONS)})")
    robot, robot_key = _section(doc, name, "robot", "drone", _ROBOT_KEYS)
    sim, _ = _section(doc, name, "simulation", None, _SIM_KEYS)
    mis, mission_key = _section(doc, name, "mission", "test", _MISSION_KEYS)
    assertion, _ = _section(doc, name, "assertion", None, _ASSERT_KEYS)
    agent, _ = _section(doc, name, "agent", None, _AGENT_KEYS)
    own, _ = _section(doc, name, "surrealist", None, _OWN_KEYS)
    notes: list[str] = []  # read with a warning: one line for the file
    avoidance = _uses_avoidance(robot, robot_key, sim, name, notes)
    speed = _check_run_settings(sim, mis, mission_key, assertion, agent, name, notes)
    base = path.resolve().parent

    def resolve(key: str, value) -> str | None:
        if value is None:
            return None
        if not isinstance(value, str):
            raise InvalidTestCase(f"{name}: field {key!r}: expected a file path, got {value!r}")
        found = _resolve_path(value, base)
        if found is None:
            raise InvalidTestCase(f"{name}: field {key!r}: file {value!r} not found")
        return found

    mission_file = resolve("mission_file", robot.get("mission_file"))
    mission = None
    if mission_file is not None:
        try:
            mission = read_mission(mission_file)
        except MissionError as err:
            raise InvalidTestCase(f"{name}: field 'mission_file': {err}") from err
    params_file = resolve("params_file", robot.get("params_file"))
    params = dict(_read_params(params_file)) if params_file else {}
    inline = robot.get("params")
    if inline is not None:
        if not isinstance(inline, dict):
            raise InvalidTestCase(f"{name}: field 'params': expected a mapping NAME: value, got {inline!r}")
        params.update(inline)
    if avoidance and "COM_OBS_AVOID" not in params:
        params["COM_OBS_AVOID"] = 1  # Aerialist's ROS set-up flies PX4-Avoidance
    commands_file = resolve("commands_file", mis.get("commands_file"))
    if mis.get("commands") is not None:
        commands = _parse_commands(mis["commands"], name)
    else:
        commands = _read_commands(commands_file) if commands_file else ()
    obstacles = _parse_obstacles(sim.get("obstacles"), name, notes)
    wind = None
    if sim.get("wind") is not None:
        if not isinstance(sim["wind"], dict):
            raise InvalidTestCase(f"{name}: field 'wind': expected a mapping, got {sim['wind']!r}")
        wind = _construct(Wind, sim["wind"], f"{name}: field 'wind'")
    home = sim.get("home_position")
    if home is not None:
        if not (isinstance(home, list) and len(home) == 3):
            raise InvalidTestCase(f"{name}: field 'home_position': expected [lat, lon, alt], got {home!r}")
        if not all(_finite(v) for v in home) or not (-90 <= home[0] <= 90 and -180 <= home[1] <= 180):
            raise InvalidTestCase(f"{name}: field 'home_position': expected [lat, lon, alt] as numbers (lat in "
                                  f"[-90, 90], lon in [-180, 180]), got {home!r}")
        home = tuple(float(v) for v in home)
    timeout = sim.get("timeout")
    if timeout is not None and not _finite(timeout):
        raise InvalidTestCase(f"{name}: simulation.timeout: expected a number of seconds (0 or less: none), got "
                              f"{timeout!r}")
    log = assertion.get("log_file") if assertion.get("log_file") is not None else own.get("assertion_log")
    if log is not None and not isinstance(log, str):
        raise InvalidTestCase(f"{name}: field 'log_file': expected a file path, got {log!r}")
    reference_log = _resolve_path(log, base) if log else None
    if notes:
        warnings.warn(f"{name}: " + "; ".join(notes), stacklevel=2)
    try:
        return TestCase(mission=mission, obstacles=obstacles, params=params, wind=wind, commands=commands,
                        mission_file=mission_file, params_file=params_file, commands_file=commands_file,
                        reference_log=reference_log, home=home,
                        assertion_log=log if log and reference_log is None else None,
                        timeout=timeout * speed if timeout is not None and timeout > 0 else None)
    except InvalidTestCase as err:
        raise InvalidTestCase(f"{name}: {err}") from err


def save_test(test: TestCase, path) -> None:
    """Save as an Aerialist YAML that Aerialist master and 0.2.x both load with geometry, and :func:`load_test`
    reads back to an equal test case.

    Master reads ``robot``/``mission`` and, given them, ignores ``drone``/``test`` without a warning; 0.2.x reads
    only ``drone``/``test``: so those sections are written under both names. Obstacles in the dict form with
    ``shape`` ``box`` or ``cylinder`` and ``size.r`` (:meth:`Obstacle.to_dict`); parameters inline; file paths
    relative to the YAML's folder when the file lies in it, else absolute (:func:`export_test` copies them in). A
    real flight named but not at hand goes to the ``surrealist`` section, which Aerialist ignores (its assertion
    would fail to load). A test with ``wind`` or a ``timeout`` is master's only: 0.2.x has neither.
    """
    import copy

    import yaml

    path = Path(path)
    base = path.resolve().parent
    avoidance = bool(test.params.get("COM_OBS_AVOID", 0))
    robot: dict = {"port": "ros" if avoidance else "sitl"}
    if test.params:
        robot["params"] = dict(test.params)
    if test.params_file:
        robot["params_file"] = _relative(test.params_file, base)
    if test.mission_file:
        robot["mission_file"] = _relative(test.mission_file, base)
    sim: dict = {"simulator": "ros" if avoidance else "gazebo", "speed": 1, "headless": True,
                 "obstacles": [o.to_dict() for o in test.obstacles]}
    if test.home is not None:
        sim["home_position"] = list(test.home)
    if test.wind is not None:
        sim["wind"] = test.wind.to_dict()
    if test.timeout is not None:
        sim["timeout"] = test.timeout
    mission: dict = {}
    if test.commands:
        mission["commands"] = [c.to_dict() for c in test.commands]
    if test.commands_file:
        mission["commands_file"] = _relative(test.commands_file, base)
    # each section its own copy: YAML would write a shared one as an alias, which Aerialist reads and we refuse
    doc = {"robot": robot, "drone": copy.deepcopy(robot), "simulation": sim,
           "mission": mission, "test": copy.deepcopy(mission)}
    if test.reference_log:
        doc["assertion"] = {"log_file": _relative(test.reference_log, base), "variable": "trajectory"}
    elif test.assertion_log:
        doc["surrealist"] = {"assertion_log": test.assertion_log}
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump(doc, f, sort_keys=False)


def export_test(test: TestCase, path) -> None:
    """Save the test at ``path`` (:func:`save_test`) as a file that travels with its folder: every file it names
    (mission, parameters, commands, the assertion's flight log) is copied into ``FILES_FOLDER`` beside it and named
    by a path relative to the YAML's folder, and the folder gets a README saying to run Aerialist from it (Aerialist
    opens relative paths from its working directory). Files of the same name and other content get ``-2``, ``-3``,
    ... A copy that fails is a one-line SurrealistError.

    Example::

        >>> export_test(load_test("seed.yaml"), "out/best.yaml")  # out/case_studies/auto1.plan, ...  # doctest: +SKIP
    """
    path = Path(path)
    folder = path.parent
    copies = {key: _copy_into(getattr(test, key), folder / FILES_FOLDER)
              for key in _FILE_FIELDS if getattr(test, key)}
    save_test(replace(test, **copies), path)
    _write_readme(folder)


def _copy_into(source: str, files: Path) -> str:
    """``source`` copied into the folder ``files`` under its own name (or ``NAME-2`` ... when another file holds
    it); the copy's absolute path. A file already there with the same bytes is the copy."""
    from .errors import SurrealistError

    source_path = Path(source)
    try:
        data = source_path.read_bytes()
        files.mkdir(parents=True, exist_ok=True)
        target, n = files / source_path.name, 1
        while target.exists() and target.read_bytes() != data:
            n += 1
            target = files / f"{source_path.stem}-{n}{source_path.suffix}"
        if not target.exists():
            shutil.copyfile(source_path, target)
    except OSError as err:
        raise SurrealistError(f"{source}: cannot copy it into {files} ({err.strerror or err})") from None
    return str(target.resolve())


def _write_readme(folder: Path) -> None:
    """The folder's README (not written over one that is not ours)."""
    readme = folder / "README.md"
    if readme.exists() and not readme.read_text(encoding="utf-8", errors="replace").startswith(README_TITLE):
        return
    readme.write_text(
        f"{README_TITLE}\n\n"
        f"The YAML files in this folder load in Aerialist master (`robot`/`mission` keys), Aerialist 0.2.x "
        f"(`drone`/`test` keys) and surrealist-gym. They name their mission, parameter and command files (and any "
        f"flight log) by paths relative to this folder, in `{FILES_FOLDER}/`.\n\n"
        f"Aerialist opens relative paths from its working directory: run it from this folder, e.g.\n\n"
        f"    cd {folder.name}\n"
        f"    python3 -m aerialist exec --test NAME.yaml\n\n"
        f"surrealist-gym resolves them against the YAML's folder, from anywhere: "
        f"`surrealist simulate {folder.name}/NAME.yaml`. The folder moves as a whole.\n", encoding="utf-8")


def _port(value) -> int | None:
    """The port number Aerialist makes of a ``port`` field (None: Aerialist's RobotConfig sets none)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        return int(value) if value.isdigit() else PORTS.get(value)
    return None


def _uses_avoidance(robot: dict, key: str, sim: dict, name: str, notes: list) -> bool:
    """Whether Aerialist's set-up flies PX4-Avoidance: the robot's port is ``ros`` (14541) or the simulator is
    ``ros``. A port or simulator that cannot be simulated is an error; jMAVSim is flown with a warning."""
    port = robot.get("port")
    if port is not None:
        number = _port(port)
        if number == VEHICLE_PORT:
            raise InvalidTestCase(f"{name}: {key}.port: {port!r} is a real vehicle's (Aerialist's cf/hw port "
                                  f"{VEHICLE_PORT}), which cannot be simulated; expected sitl ({SITL_PORT}) or ros "
                                  f"({AVOIDANCE_PORT}, PX4-Avoidance)")
        if number not in (SITL_PORT, AVOIDANCE_PORT):
            raise InvalidTestCase(f"{name}: {key}.port: {port!r} is no PX4 SITL port of Aerialist's; expected sitl "
                                  f"({SITL_PORT}) or ros ({AVOIDANCE_PORT}, PX4-Avoidance)")
        port = number
    simulator = sim.get("simulator")
    if simulator is not None and simulator not in SIMULATORS:
        raise InvalidTestCase(f"{name}: simulation.simulator: {simulator!r}: expected gazebo, ros (with "
                              f"PX4-Avoidance) or jmavsim")
    if simulator == "jmavsim":
        notes.append("simulation.simulator jmavsim: flown as gazebo is, on the UAV profile's vehicle (--uav), not "
                     "jMAVSim's quadrotor")
    return port == AVOIDANCE_PORT or simulator == "ros"


def _check_run_settings(sim: dict, mis: dict, mission_key: str, assertion: dict, agent: dict, name: str,
                        notes: list) -> float:
    """Check the fields that say how Aerialist runs PX4, not what it flies (docs/aerialist-yaml.md: world, speed,
    headless, waypoints, agent, the assertion's variable); returns the simulation's speed factor."""
    def positive(where: str, value) -> float:
        if not _finite(value) or value <= 0:
            raise InvalidTestCase(f"{name}: {where}: expected a positive number, got {value!r}")
        return float(value)

    speed = positive("simulation.speed", sim["speed"]) if sim.get("speed") is not None else 1.0
    if mis.get("speed") is not None:
        positive(f"{mission_key}.speed", mis["speed"])
    for key, kind, what in (("headless", bool, "true or false"), ("world", str, "a world's name")):
        if sim.get(key) is not None and not isinstance(sim[key], kind):
            raise InvalidTestCase(f"{name}: simulation.{key}: expected {what}, got {sim[key]!r}")
    waypoints = mis.get("waypoints")
    if waypoints is not None and not (isinstance(waypoints, list) and all(
            isinstance(w, dict) and _finite(w.get("x")) and _finite(w.get("y")) for w in waypoints)):
        raise InvalidTestCase(f"{name}: {mission_key}.waypoints: expected a list of positions {{x, y, z, r}}, got "
                              f"{waypoints!r}")
    if agent:
        if agent.get("engine") not in AGENTS:
            raise InvalidTestCase(f"{name}: agent.engine: {agent.get('engine')!r}: expected one of {', '.join(AGENTS)}")
        count = agent.get("count", 1)
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise InvalidTestCase(f"{name}: agent.count: expected a whole number >= 1, got {count!r}")
        if count != 1:
            notes.append(f"agent.count {count}: Aerialist's agent would fly {count} runs; the command's --runs sets "
                         f"them here")
    variable = assertion.get("variable")
    if variable is not None and variable != "trajectory":
        raise InvalidTestCase(f"{name}: assertion.variable: {variable!r}: only 'trajectory' is supported")
    return speed


def _section(doc, name, key, legacy, allowed) -> tuple[dict, str]:
    """A section and the name it was read under; given under both names (Aerialist master reads ``key``, 0.2.x
    ``legacy``), the two must be equal."""
    value = doc.get(key)
    if legacy is not None and doc.get(legacy) is not None:
        if value is None:
            value, key = doc[legacy], legacy
        elif value != doc[legacy]:
            raise InvalidTestCase(f"{name}: sections {key!r} and {legacy!r} differ (Aerialist master reads {key}, "
                                  f"0.2.x {legacy}): give one, or the same in both")
    if value is None:
        return {}, key
    if not isinstance(value, dict):
        raise InvalidTestCase(f"{name}: section {key!r}: expected a mapping, got {value!r}")
    unknown = set(value) - allowed
    if unknown:
        raise InvalidTestCase(f"{name}: {key}.{sorted(unknown)[0]}: unknown field (expected one of {sorted(allowed)})")
    return value, key


def _resolve_path(value: str, base: Path) -> str | None:
    candidate = Path(value).expanduser()
    if candidate.is_absolute():
        return str(candidate) if candidate.is_file() else None
    for folder in (base, *base.parents):
        if (folder / candidate).is_file():
            return str((folder / candidate).resolve())
    if (base / candidate.name).is_file():
        return str((base / candidate.name).resolve())
    return None


def _relative(file: str, base: Path) -> str:
    """``file`` relative to ``base`` when it lies inside it, else absolute."""
    path = Path(file).resolve()
    return str(path.relative_to(base)) if path.is_relative_to(base) else str(path)


def _finite(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


def safe_yaml(text: str, name: str):
    """``yaml.safe_load`` for files from anywhere: no aliases (an alias bomb expands to gigabytes; Aerialist files
    have none), nesting too deep for the parser is an error, not a crash, and numbers read as YAML 1.2 reads them
    (``1e9`` is a number, not a string)."""
    import yaml

    try:
        if any(isinstance(token, yaml.AliasToken) for token in yaml.scan(text)):
            raise InvalidTestCase(f"{name}: YAML aliases (*name) are not supported")
        return yaml.load(text, Loader=_loader())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        raise InvalidTestCase(f"{name}: invalid YAML{where}") from None
    except RecursionError:
        raise InvalidTestCase(f"{name}: YAML nested too deeply") from None


#: The tag Aerialist master's ``to_yaml`` gives an assertion's variable (its Trajectory class), read as its name.
TRAJECTORY_TAG = "tag:yaml.org,2002:python/name:aerialist.px4.trajectory.Trajectory"


@functools.cache
def _loader():
    """A SafeLoader whose floats include exponents without a dot (``1e9``, ``-2E-3``), as in YAML 1.2, and that
    reads Aerialist master's tag of the trajectory variable as ``trajectory`` (no other Python tag)."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    exponent = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent, list("-+0123456789"))
    Loader.add_constructor(TRAJECTORY_TAG, lambda loader, node: "trajectory")
    return Loader


def _construct(cls, values: dict, where: str):
    names = {f.name for f in fields(cls)}
    unknown = set(values) - names
    if unknown:
        raise InvalidTestCase(f"{where}.{sorted(unknown)[0]}: unknown field (expected one of {sorted(names)})")
    try:
        return cls(**values)
    except InvalidTestCase as err:
        raise InvalidTestCase(f"{where}: {err}") from err
    except TypeError:  # a required field left out
        missing = [f.name for f in fields(cls) if f.name not in values]
        raise InvalidTestCase(f"{where}: missing field {missing[0] if missing else '?'!r}") from None


def _parse_obstacles(raw, name, notes: list | None = None) -> tuple[Obstacle, ...]:
    """The obstacles of a YAML's ``simulation.obstacles``; what Aerialist reads otherwise is added to ``notes``."""
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise InvalidTestCase(f"{name}: field 'obstacles': expected a list, got {raw!r}")
    if raw and not isinstance(raw[0], dict):
        if len(raw) % 7:
            raise InvalidTestCase(f"{name}: field 'obstacles': flat form needs 7 numbers per obstacle "
                                  f"[l,w,h,x,y,z,r], got {len(raw)}")
        out = []
        for i in range(0, len(raw), 7):
            try:
                out.append(Obstacle(*raw[i:i + 7]))
            except InvalidTestCase as err:
                raise InvalidTestCase(f"{name}: obstacles[{i // 7}]: {err}") from err
        return tuple(out)
    out, odd = [], {}  # odd: what Aerialist reads otherwise -> the obstacles concerned
    for i, item in enumerate(raw):
        where = f"{name}: obstacles[{i}]"
        if not isinstance(item, dict):
            raise InvalidTestCase(f"{where}: expected a mapping with size and position, got {item!r}")
        unknown = set(item) - {"size", "position", "shape"}
        if unknown:
            raise InvalidTestCase(f"{where}.{sorted(unknown)[0]}: unknown field (expected size, position, shape)")
        size, pos = item.get("size"), item.get("position")
        if not isinstance(size, dict) or not isinstance(pos, dict):
            raise InvalidTestCase(f"{where}: needs 'size' {{l, w, h, r}} and 'position' {{x, y, z, r}}")
        bad = (set(size) - {"l", "w", "h", "r"}) or (set(pos) - {"x", "y", "z", "r", "angle"})
        if bad:
            raise InvalidTestCase(f"{where}: unknown field {sorted(bad)[0]!r}")
        try:
            given = item.get("shape")
            shape = _parse_shape("box" if given is None else given)
            if given not in (None, "box", "cylinder"):
                odd.setdefault(f"shape {given!r} is read as {shape.value}, but Aerialist builds no geometry for it "
                               f"(write {shape.value!r})", []).append(i)
            if "angle" in pos:
                odd.setdefault("position.angle is read as r, which is what Aerialist reads", []).append(i)
            length, width = size.get("l"), size.get("w")
            radius = size.get("r", 0)
            if not _finite(radius) or radius < 0:
                raise InvalidTestCase(f"size 'r': expected a number >= 0 (a cylinder's radius), got {radius!r}")
            if shape == Shape.CYLINDER and radius > 0:
                if any(_finite(v) and v and abs(v - 2 * radius) > 1e-9 for v in (length, width)):
                    odd.setdefault("a cylinder's l and w other than 2 r are ignored (its size is its radius r, as "
                                   "Aerialist measures it)", []).append(i)
                length = width = 2 * radius
            elif shape == Shape.CYLINDER and given == "cylinder":
                raise InvalidTestCase("size 'r': a cylinder needs its radius r > 0 (Aerialist gives it no area "
                                      "otherwise)")
            elif shape == Shape.CYLINDER:
                width = length  # surrealist-gym's earlier TREE: diameter l
            elif radius:
                odd.setdefault("size.r of a box is ignored (it is a cylinder's radius; Aerialist ignores it too)",
                               []).append(i)
            out.append(Obstacle(length, width, size.get("h"), pos.get("x"), pos.get("y"), pos.get("z", 0.0),
                                pos.get("r", pos.get("angle", 0.0)), shape))
        except InvalidTestCase as err:
            raise InvalidTestCase(f"{where}: {err}") from err
    if notes is not None:
        notes.extend(f"obstacles {', '.join(map(str, which))}: {what}" for what, which in odd.items())
    return tuple(out)


def _read_params(path: str) -> list[tuple[str, float]]:
    """PX4 parameters from ``NAME, value`` lines (no header)."""
    out = []
    for n, row in enumerate(csv.reader(_text_lines(path)), start=1):
        if not row or not row[0].strip() or row[0].strip().startswith("#"):
            continue
        if len(row) < 2:
            raise InvalidTestCase(f"{path}: line {n}: expected 'NAME, value', got {','.join(row)!r}")
        try:
            value = float(row[1])
        except ValueError as err:
            raise InvalidTestCase(f"{path}: line {n}: parameter {row[0].strip()}: not a number {row[1]!r}") from err
        bad = param_problem(row[0].strip(), value)
        if bad:
            raise InvalidTestCase(f"{path}: line {n}: parameter {row[0].strip()}: {bad}")
        out.append((row[0].strip(), int(value) if value.is_integer() and "." not in row[1] else value))
    return out


def _text_lines(path: str) -> list[str]:
    """The lines of a UTF-8 text file (a one-line error naming the file otherwise)."""
    regular_file(path, "file", InvalidTestCase)
    try:
        return Path(path).read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as err:
        raise InvalidTestCase(f"{path}: not UTF-8 text (byte {err.start})") from None
    except OSError as err:
        raise InvalidTestCase(f"{path}: cannot read ({err.strerror})") from None


def _read_commands(path: str) -> tuple[RuntimeCommand, ...]:
    rows = [r for r in csv.reader(_text_lines(path)) if r and any(c.strip() for c in r)]
    if rows and rows[0][0].strip() == "timestamp":
        rows = rows[1:]
    out = []
    for n, row in enumerate(rows, start=2):
        try:
            values = [float(c) for c in row]
        except ValueError as err:
            raise InvalidTestCase(f"{path}: line {n}: expected numbers timestamp,mode,x,y,z,r") from err
        if len(values) != 6:
            raise InvalidTestCase(f"{path}: line {n}: expected 6 columns timestamp,mode,x,y,z,r, got {len(values)}")
        try:
            out.append(RuntimeCommand(*values))
        except InvalidTestCase as err:
            raise InvalidTestCase(f"{path}: line {n}: {err}") from None
    return tuple(out)


def _parse_commands(raw, name) -> tuple[RuntimeCommand, ...]:
    if not isinstance(raw, list):
        raise InvalidTestCase(f"{name}: field 'commands': expected a list, got {raw!r}")
    out = []
    for i, c in enumerate(raw):
        if not isinstance(c, dict):
            raise InvalidTestCase(f"{name}: commands[{i}]: expected a mapping timestamp, mode, x, y, z, r")
        out.append(_construct(RuntimeCommand, c, f"{name}: commands[{i}]"))
    return tuple(out)
