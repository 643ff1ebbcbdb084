"""Test cases: immutable ``TestCase`` and ``Obstacle`` values (and ``Shape``, ``Wind``, ``RuntimeCommand``).

Obstacle frame (PRODUCT.md): ``x, y`` = footprint centre (x north, y east), ``z`` = base height (0 = on the ground),
``r`` = yaw in degrees, positive from north toward east; ``l`` along the obstacle's x axis, ``w`` along y, ``h`` up.
A cylinder has diameter ``l`` (= ``w``); Aerialist's YAML gives its radius as ``size.r``.

The Aerialist YAML they load from and save to is read and written by :mod:`surrealist_gym.aerialist`
(:func:`~surrealist_gym.aerialist.load_test`, :func:`~surrealist_gym.aerialist.save_test`).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from typing import Mapping

from .errors import FrozenDict, InvalidTestCase, param_problem
from .mission import Mission


class Shape(str, Enum):
    """An obstacle's shape, as Aerialist's YAML names it."""
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

    l: float  # noqa: E741 - Aerialist's name for the length, kept in our YAML and API
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
        object.__setattr__(self, "shape", parse_shape(self.shape))
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


PAIRWISE_UP_TO = 32  # first_overlap tests this many obstacles pair by pair (cheaper than building a tree)


def first_overlap(obstacles) -> tuple[int, int] | None:
    """The first pair (i < j, in order) of obstacles that overlap, or None. A few obstacles (a test's usual 1-4) are
    tested pair by pair; of more, only the pairs whose footprints' bounding boxes meet and whose heights overlap
    (shapely's STRtree), so thousands of obstacles answer at once."""
    if len(obstacles) < 2:
        return None
    if len(obstacles) <= PAIRWISE_UP_TO:
        return next(((i, j) for i in range(len(obstacles)) for j in range(i + 1, len(obstacles))
                     if obstacles[i].overlaps(obstacles[j])), None)
    import numpy as np
    from shapely import STRtree, box

    corners = [o.footprint() for o in obstacles]
    boxes = [box(min(x for x, _ in c), min(y for _, y in c), max(x for x, _ in c), max(y for _, y in c))
             for c in corners]
    left, right = STRtree(boxes).query(boxes, predicate="intersects")
    keep = left < right
    left, right = left[keep], right[keep]
    base = np.array([o.z for o in obstacles])
    top = base + np.array([o.h for o in obstacles])
    keep = (base[left] < top[right]) & (base[right] < top[left])
    for i, j in sorted(zip(left[keep].tolist(), right[keep].tolist())):
        if obstacles[i].overlaps(obstacles[j]):
            return i, j
    return None


def parse_shape(value) -> Shape:
    """A :class:`Shape` from its value or name (``box``, ``cylinder``); another raises InvalidTestCase."""
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
            if not is_finite_number(value):
                raise InvalidTestCase(f"command field {f.name!r}: expected a finite number, got {value!r}")
        if self.timestamp < 0:
            raise InvalidTestCase(f"command field 'timestamp': expected a number >= 0 [s], got {self.timestamp:g}")
        if self.mode != int(self.mode):
            raise InvalidTestCase(f"command field 'mode': expected a whole number, got {self.mode:g}")
        object.__setattr__(self, "mode", int(self.mode))

    def to_dict(self) -> dict:
        """The command as Aerialist's YAML writes it."""
        return {"timestamp": self.timestamp, "mode": self.mode, "x": self.x, "y": self.y, "z": self.z, "r": self.r}


# Physical range of a test's wind. 30 m/s is Beaufort force 11 ("violent storm", 28.5-32.6 m/s) and well past what a
# ~1.5 kg Iris can hold: even at PX4's 45 degree tilt limit (MPC_TILTMAX_AIR) its horizontal thrust, m g = 14.7 N,
# only balances the modelled Iris' drag (sim/vehicle/airframe.py: 0.21 v + 0.02 v^2 N) at ~22 m/s, and the simulated
# SITL Iris already drifts ~70 m off mission1's track in a 15 m/s crosswind. A larger speed is a typo or a unit mix-up
# (km/h for m/s), not a test; up to the bound, a test may still probe winds the vehicle cannot hold.
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
    them), except that of a wind (or gust) whose speeds are all 0, which blows nothing (Aerialist master's own ``Wind``
    writes a gust it lacks as ``gust_direction: [0, 0, 0]``; it is read as the default direction); a maximum speed,
    when given (non-zero), at least its mean. A maximum of 0 means "not given" (the default, as when an Aerialist
    file leaves it out): the simulator then caps the speed at its mean. Gazebo itself would take an explicit 0
    literally and blow no wind at all.
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
                if not (isinstance(v, (list, tuple)) and len(v) == 3 and all(is_finite_number(c) for c in v)):
                    raise InvalidTestCase(f"wind field {f.name!r}: expected 3 finite numbers, got {v!r}")
                if not any(c != 0 for c in v):
                    prefix = f.name[:-len("direction")]
                    if any(getattr(self, prefix + k) for k in ("velocity_mean", "velocity_max", "velocity_variance")):
                        raise InvalidTestCase(f"wind field {f.name!r}: expected a direction (not all zero), got "
                                              f"{v!r}")
                    v = (1.0, 0.0, 0.0)  # no wind this way: Aerialist master writes a gust it lacks as [0, 0, 0]
                object.__setattr__(self, f.name, tuple(float(c) for c in v))
                continue
            if not is_finite_number(v) or v < 0:
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
        """The wind as YAML values (directions as lists)."""
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
            if not is_finite_number(self.timeout) or self.timeout <= 0:
                raise InvalidTestCase(f"timeout: expected a positive number of seconds, got {self.timeout!r}")
            object.__setattr__(self, "timeout", float(self.timeout))
        obstacles = tuple(self.obstacles)
        for i, o in enumerate(obstacles):
            if not isinstance(o, Obstacle):
                raise InvalidTestCase(f"obstacles[{i}]: expected an Obstacle, got {type(o).__name__}")
        pair = first_overlap(obstacles)
        if pair:
            raise InvalidTestCase(f"obstacles[{pair[0]}] and obstacles[{pair[1]}] overlap")
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


def is_finite_number(value) -> bool:
    """Whether ``value`` is a finite int or float (not a bool)."""
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
