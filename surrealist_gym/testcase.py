"""Test cases: immutable ``TestCase`` and ``Obstacle`` values, and the Aerialist YAML they load from and save to.

Obstacle frame (PRODUCT.md): ``x, y`` = footprint centre (x north, y east), ``z`` = base height (0 = on the ground),
``r`` = yaw in degrees, positive from north toward east; ``l`` along the obstacle's x axis, ``w`` along y, ``h`` up.
A cylinder (Aerialist's TREE) has diameter ``l`` (= ``w``).
"""
from __future__ import annotations

import csv
import functools
import json
import math
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
        """Aerialist's dict form."""
        shape = "BOX" if self.shape == Shape.BOX else "TREE"
        return {"size": {"l": self.l, "w": self.w, "h": self.h},
                "position": {"x": self.x, "y": self.y, "z": self.z, "r": self.r}, "shape": shape}


def _parse_shape(value) -> Shape:
    if isinstance(value, Shape):
        return value
    shape = _SHAPE_NAMES.get(str(value).lower())
    if shape is None:
        raise InvalidTestCase(f"obstacle field 'shape': unknown shape {value!r} (expected BOX or TREE/CYLINDER)")
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
    A mutation makes a new value (``dataclasses.replace`` or :meth:`with_obstacles`).
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

    def __post_init__(self):
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
        return json.dumps({
            "mission": None if self.mission is None else self.mission.to_plan()["mission"]["items"],
            "home": None if self.mission is None else list(self.mission.home),
            "obstacles": [[round(v, 9) for v in o.to_list()] + [o.shape.value] for o in self.obstacles],
            "params": dict(sorted(self.params.items())),
            "wind": None if self.wind is None else self.wind.to_dict(),
            "commands": [c.to_dict() for c in self.commands],
        }, sort_keys=True)


# --- YAML --------------------------------------------------------------------------------------------------------
_SECTIONS = {"robot", "drone", "simulation", "mission", "test", "assertion", "agent"}
_ROBOT_KEYS = {"port", "params", "params_file", "mission_file"}
_SIM_KEYS = {"simulator", "world", "speed", "headless", "obstacles", "home_position", "wind", "timeout",
             "world_file_name"}
_MISSION_KEYS = {"commands", "commands_file", "speed", "waypoints"}
_ASSERT_KEYS = {"log_file", "variable", "expectation"}


def load_test(path) -> TestCase:
    """Load an Aerialist test-case YAML (legacy ``drone``/``test`` or current ``robot``/``mission`` keys).

    Relative file paths are resolved against the YAML's folder, then its parents (the paper's seeds name paths
    relative to their repository root), then by file name in the YAML's folder.
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
    robot = _section(doc, name, "robot", "drone", _ROBOT_KEYS)
    sim = _section(doc, name, "simulation", None, _SIM_KEYS)
    mis = _section(doc, name, "mission", "test", _MISSION_KEYS)
    assertion = _section(doc, name, "assertion", None, _ASSERT_KEYS)
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
    if _uses_avoidance(robot, sim) and "COM_OBS_AVOID" not in params:
        params["COM_OBS_AVOID"] = 1  # Aerialist's ROS set-up flies PX4-Avoidance
    commands_file = resolve("commands_file", mis.get("commands_file"))
    if mis.get("commands") is not None:
        commands = _parse_commands(mis["commands"], name)
    else:
        commands = _read_commands(commands_file) if commands_file else ()
    obstacles = _parse_obstacles(sim.get("obstacles"), name)
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
    log = assertion.get("log_file")
    reference_log = _resolve_path(log, base) if isinstance(log, str) else None
    try:
        return TestCase(mission=mission, obstacles=obstacles, params=params, wind=wind, commands=commands,
                        mission_file=mission_file, params_file=params_file, commands_file=commands_file,
                        reference_log=reference_log, home=home,
                        assertion_log=log if isinstance(log, str) and log and reference_log is None else None)
    except InvalidTestCase as err:
        raise InvalidTestCase(f"{name}: {err}") from err


def save_test(test: TestCase, path, legacy: bool = False) -> None:
    """Save as Aerialist YAML (current ``robot``/``mission`` keys, or legacy ``drone``/``test``).

    Obstacles are written in the dict form; parameters inline; file paths relative to the YAML's folder when
    possible. :func:`load_test` reads the file back to an equal test case.
    """
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
    mission: dict = {}
    if test.commands:
        mission["commands"] = [c.to_dict() for c in test.commands]
    if test.commands_file:
        mission["commands_file"] = _relative(test.commands_file, base)
    doc = {"drone" if legacy else "robot": robot, "simulation": sim, "test" if legacy else "mission": mission}
    if test.reference_log:
        doc["assertion"] = {"log_file": _relative(test.reference_log, base), "variable": "trajectory"}
    elif test.assertion_log:
        doc["assertion"] = {"log_file": test.assertion_log, "variable": "trajectory"}
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump(doc, f, sort_keys=False)


def _uses_avoidance(robot: dict, sim: dict) -> bool:
    """Aerialist runs PX4 with PX4-Avoidance when the robot port or the simulator is 'ros' (or 'avoidance')."""
    return str(robot.get("port", "")).lower() in {"ros", "px4_ros", "avoidance"} or \
        str(sim.get("simulator", "")).lower() == "ros"


def _section(doc, name, key, legacy, allowed) -> dict:
    value = doc.get(key)
    if value is None and legacy is not None:
        value = doc.get(legacy)
        key = legacy if value is not None else key
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InvalidTestCase(f"{name}: section {key!r}: expected a mapping, got {value!r}")
    unknown = set(value) - allowed
    if unknown:
        raise InvalidTestCase(f"{name}: {key}.{sorted(unknown)[0]}: unknown field (expected one of {sorted(allowed)})")
    return value


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


@functools.cache
def _loader():
    """A SafeLoader whose floats include exponents without a dot (``1e9``, ``-2E-3``), as in YAML 1.2."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    exponent = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent, list("-+0123456789"))
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


def _parse_obstacles(raw, name) -> tuple[Obstacle, ...]:
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
    out = []
    for i, item in enumerate(raw):
        where = f"{name}: obstacles[{i}]"
        if not isinstance(item, dict):
            raise InvalidTestCase(f"{where}: expected a mapping with size and position, got {item!r}")
        unknown = set(item) - {"size", "position", "shape"}
        if unknown:
            raise InvalidTestCase(f"{where}.{sorted(unknown)[0]}: unknown field (expected size, position, shape)")
        size, pos = item.get("size"), item.get("position")
        if not isinstance(size, dict) or not isinstance(pos, dict):
            raise InvalidTestCase(f"{where}: needs 'size' {{l, w, h}} and 'position' {{x, y, z, r}}")
        bad = (set(size) - {"l", "w", "h"}) or (set(pos) - {"x", "y", "z", "r", "angle"})
        if bad:
            raise InvalidTestCase(f"{where}: unknown field {sorted(bad)[0]!r}")
        try:
            shape = _parse_shape(item.get("shape", "BOX"))
            length = size.get("l")
            width = size.get("w", length if shape == Shape.CYLINDER else None)
            r = pos.get("r", pos.get("angle", 0.0))
            out.append(Obstacle(length, width, size.get("h"), pos.get("x"), pos.get("y"), pos.get("z", 0.0),
                                r, shape))
        except InvalidTestCase as err:
            raise InvalidTestCase(f"{where}: {err}") from err
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
