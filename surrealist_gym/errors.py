"""Errors for bad input: each message is one line naming the file or field, the bad value and what was expected; and
the safe reading of input files from anywhere (:func:`input_file`, :func:`read_text`, :func:`safe_yaml`).

The command line turns any :class:`SurrealistError` into exit code 2 with its message on stderr.

The physical ranges of the values that set up the simulated UAV are here too (:data:`RANGES`, :func:`problem`,
:func:`param_problem`: a value outside its range is refused in such a line), with :class:`FrozenDict`, the
read-only mapping that holds a test's, a log's or a profile's values.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass


class SurrealistError(Exception):
    """Base class of every error caused by bad input or a missing optional dependency."""


class LogFormatError(SurrealistError):
    """A flight log cannot be read, or lacks the data asked for (e.g. no valid local position)."""


class MissionError(SurrealistError):
    """A mission file (.plan, QGC WPL) is invalid or holds items that cannot be flown."""


class InvalidTestCase(SurrealistError):
    """A test case (or its YAML) is invalid: wrong field, non-positive size, overlapping obstacles, missing file."""


class InvalidProfile(SurrealistError):
    """A UAV profile (preset name or YAML) is unknown or holds an unknown key or an out-of-range value."""


class InvalidLabels(SurrealistError):
    """A labelled set for ``surrealist fidelity`` is invalid: missing column, unknown test, non-numeric value."""


class SimulationError(SurrealistError):
    """A simulation could not be set up from the given test case."""


class UnknownAgent(SurrealistError):
    """An agent name that is not registered."""


class DependencyNotInstalled(SurrealistError):
    """An optional dependency is missing; the message names the pip command that installs it."""


def one_line(err: Exception, limit: int = 80) -> str:
    """A foreign exception's text for a SurrealistError message: on one line (SQLite and pymavlink quote text with
    its line breaks), at most ``limit`` characters."""
    return " ".join(str(err).split())[:limit]


class InfrastructureError(SurrealistError):
    """The machinery that runs simulations failed (a worker or pool died, a scheduler was lost), not the simulation:
    never stored as a result; the search stops and ``--resume`` re-flies what is missing."""


def regular_file(path, what: str, error: type[SurrealistError] = SurrealistError, empty_ok: bool = True,
                 max_bytes: int | None = None) -> str:
    """``path`` (as a string) if it names an existing regular file, else a one-line ``error``: missing, or what it is
    instead (a folder, a FIFO, a device, a socket), or empty when ``empty_ok`` is False. Checked with ``stat``, which
    does not open the file, so an input that is a FIFO or a device is refused instead of blocking its reader. Every
    reader of an input file calls it before opening it. ``what`` names the input ("log file", "test case"). A file
    of the kernel's (under /proc or /sys: regular to ``stat``, but endless, blocking or secret) is refused, and so is
    one larger than ``max_bytes``."""
    import os
    import stat

    name = os.fspath(path)
    try:
        info = os.stat(name)
    except OSError as err:
        raise error(f"{name}: cannot read {what} ({err.strerror or err})") from None
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode)
                else "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else "a special file")
        raise error(f"{name}: {kind}, not a regular file ({what} expected)")
    real = os.path.realpath(name)
    kernel = next((root for root in KERNEL_FOLDERS if real == root or real.startswith(root + "/")), None)
    if kernel:
        raise error(f"{name}: a file of the kernel's ({kernel}), not a regular file ({what} expected)")
    if max_bytes is not None and info.st_size > max_bytes:
        raise error(f"{name}: {info.st_size} bytes, more than the {max_bytes} a {what} may hold")
    if not empty_ok and info.st_size == 0:
        raise error(f"{name}: an empty file, no {what} in it")
    return name


#: Folders of the kernel's files: never an input (/proc/kmsg blocks, /proc/self/environ is the environment).
KERNEL_FOLDERS = ("/proc", "/sys")
#: The most bytes a test's own text files (its YAML, mission, params and commands files) may hold.
MAX_TEXT_BYTES = 16 * 1024 * 1024


def read_text(path, what: str, error: type[SurrealistError] = SurrealistError, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """A UTF-8 text file of at most ``max_bytes`` (:func:`regular_file` first; read no further than the limit, should
    the file grow), else a one-line ``error`` naming the file, never quoting it."""
    name = regular_file(path, what, error, max_bytes=max_bytes)
    try:
        with open(name, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as err:
        raise error(f"{name}: cannot read {what} ({err.strerror or err})") from None
    if len(data) > max_bytes:
        raise error(f"{name}: more than the {max_bytes} bytes a {what} may hold")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(f"{name}: not UTF-8 text (byte {err.start})") from None


#: The environment variable holding the folders (``os.pathsep``-separated) a test may read files under besides its
#: YAML's folder and the working folder; ``--allow-outside PATH`` sets it (worker processes inherit it).
ALLOW_OUTSIDE_ENV = "SURREALIST_ALLOW_OUTSIDE"


def allowed_folders(base, allow_outside=()) -> tuple:
    """The folders a test whose YAML is in ``base`` may read files under: ``base``, the working folder, the
    competition's ``case_studies`` of a tool's folder (:func:`tool_folders`) and the folders of
    ``$SURREALIST_ALLOW_OUTSIDE`` and ``allow_outside`` (all with their links resolved)."""
    import os
    from pathlib import Path

    extra = [p for p in os.environ.get(ALLOW_OUTSIDE_ENV, "").split(os.pathsep) if p] + list(allow_outside)
    layout = [folder / CASE_STUDIES for folder in tool_folders(base)]
    return tuple(Path(p).expanduser().resolve() for p in (base, Path.cwd(), *layout, *extra))


#: The competition's layout: a tool writes its tests into a folder of its own (``generated_tests/``) and names the
#: case study's files from the tool's folder (``case_studies/mission1.plan``), Aerialist's working folder there.
CASE_STUDIES = "case_studies"
GENERATED_TESTS = "generated_tests"  # where the competition's tools write their tests, in folders of their own


def tool_folders(base) -> list:
    """The folders a competition test in ``base`` may name ``case_studies/...`` from: the folder above ``base`` (a
    tool's ``generated_tests/``), and the tool's folder when ``base`` lies deeper in its ``generated_tests/`` (tools
    write ``generated_tests/<time stamp>/``, AmbieGen ``generated_tests-01/<time stamp>/``, and Aerialist resolves
    from the tool's folder, its working folder)."""
    from pathlib import Path

    base = Path(base)
    return [base.parent] + [p.parent for p in base.parents
                            if p.name.startswith(GENERATED_TESTS) and p.parent != base.parent]


def _a_tools_case_study(path, base) -> bool:
    """Whether ``path`` lies in a ``case_studies`` folder of a tool's folder beside ``base`` (``surrealist compete``
    writes the tests a tool sends into ``flights/``, naming its copy's ``tool/case_studies/...`` by absolute path)."""
    from pathlib import Path

    parent = Path(base).resolve().parent
    return any(folder.name == CASE_STUDIES and folder.parent.parent == parent for folder in Path(path).parents)


def input_file(value, base, where: str, error: type[SurrealistError] = SurrealistError, missing_ok: bool = False,
               allow_outside=()):
    """The file a test's field names, resolved as Aerialist resolves it: an absolute path as it is, a relative one
    against the YAML's folder ``base``, then the working folder, then by its name in ``base`` (the paper's seeds name
    paths relative to their repository root: ``experiments/case0.plan``), and a path in the competition's
    ``case_studies/`` also from a tool's folder (:func:`tool_folders`). Never by walking up parents. The
    file must lie (links resolved) under :func:`allowed_folders` or in a tool's ``case_studies`` beside ``base``
    (:func:`_a_tools_case_study`), and be a regular file (:func:`regular_file`). Else
    a one-line ``error`` naming the field (``where``) and the path, never the file's contents; a file not found is
    None when ``missing_ok``."""
    from pathlib import Path

    if not isinstance(value, str) or not value.strip():
        raise error(f"{where}: expected a file path, got {value!r}")
    given = Path(value).expanduser()
    base = Path(base)
    tries = [given] if given.is_absolute() else [base / given, Path.cwd() / given, base / given.name]
    if not given.is_absolute() and given.parts[0] == CASE_STUDIES:  # the competition's layout: from a tool's folder
        tries += [folder / given for folder in tool_folders(base)]
    found = [p.resolve() for p in tries if p.exists()]
    if not found:
        if missing_ok:
            return None
        raise error(f"{where}: file {value!r} not found (looked in the YAML's folder and the working folder)")
    roots = allowed_folders(base, allow_outside)
    inside = next((p for p in found if any(p.is_relative_to(root) for root in roots)
                   or _a_tools_case_study(p, base)), None)
    if inside is None:
        shown = f"{value!r}" + (f" ({found[0]})" if str(found[0]) != value else "")
        raise error(f"{where}: file {shown} lies outside the YAML's folder and the working folder; "
                    f"--allow-outside FOLDER lets tests read files under FOLDER")
    try:
        return regular_file(str(inside), "file", error)
    except SurrealistError as err:
        raise error(f"{where}: {err}") from None


def safe_yaml(text: str, name: str):
    """``yaml.safe_load`` for files from anywhere: aliases only while they expand to a small document (not an alias
    bomb); nesting too deep is an error, not a crash; numbers as in YAML 1.2 (``1e9``) and numpy's (:func:`_loader`)."""
    import yaml

    loader = None
    try:  # one parse: the node graph is composed once, measured, then constructed
        loader = _loader()(text)
        node = loader.get_single_node()
        if node is not None and _expanded(node, {}) > MAX_YAML_NODES:
            raise InvalidTestCase(f"{name}: YAML aliases (*name) expand to more than {MAX_YAML_NODES} nodes")
        return None if node is None else loader.construct_document(node)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        raise InvalidTestCase(f"{name}: invalid YAML{where}") from None
    except RecursionError:
        raise InvalidTestCase(f"{name}: YAML nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()


#: The tag Aerialist master's ``to_yaml`` gives an assertion's variable (its Trajectory class), read as its name.
TRAJECTORY_TAG = "tag:yaml.org,2002:python/name:aerialist.px4.trajectory.Trajectory"


MAX_YAML_NODES, _APPLY = 100_000, "tag:yaml.org,2002:python/object/apply:"  # a test YAML has some hundred nodes


def _expanded(node, sizes: dict) -> int:
    """How many nodes a composed YAML node stands for with its aliases expanded (a node within itself counts 0)."""
    if id(node) not in sizes:
        sizes[id(node)] = 0
        items = node.value if isinstance(node.value, list) else []  # a scalar's value is its text
        kids = [v for item in items for v in (item if isinstance(item, tuple) else (item,))]  # mappings: key, value
        sizes[id(node)] = 1 + sum(_expanded(v, sizes) for v in kids)
    return sizes[id(node)]


def _numpy_scalar(loader, node):
    """``!!python/object/apply:numpy...scalar [dtype, !!binary bytes]``: the number, when the dtype is numeric."""
    import numpy as np
    import yaml

    try:
        dtype_node, data = node.value
        spec = {k.value: v for k, v in dtype_node.value}
        dtype = np.dtype(spec["args"].value[0].value).newbyteorder(spec["state"].value[1].value)
        if dtype_node.tag == _APPLY + "numpy.dtype" and dtype.kind in "biuf":
            return np.frombuffer(loader.construct_yaml_binary(data), dtype=dtype, count=1)[0].item()
    except (ValueError, TypeError, KeyError, IndexError, AttributeError):
        pass
    raise yaml.constructor.ConstructorError(None, None, "not a numpy number", node.start_mark)


@functools.cache
def _loader():
    """A SafeLoader with YAML 1.2's floats (``1e9``, ``-2E-3``), Aerialist master's tag of the trajectory variable
    read as ``trajectory``, and numpy numbers as PyYAML's full dumper writes them (PALM's tests: without calling
    anything, :func:`_numpy_scalar`); no other Python tag."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    exponent = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent, list("-+0123456789"))
    Loader.add_constructor(TRAJECTORY_TAG, lambda loader, node: "trajectory")
    for module in ("numpy._core.multiarray", "numpy.core.multiarray"):  # numpy 2 and 1
        Loader.add_constructor(f"{_APPLY}{module}.scalar", _numpy_scalar)
    return Loader
# Physical ranges of the values that set up the simulated UAV (:data:`RANGES`, :func:`problem`,
# :func:`param_problem`): one table for UAV profiles (``params``, ``planner``, ``sensor``, ``noise``, timings)
# and for a test's PX4 ``params`` and ``uav.*`` settings; and :class:`FrozenDict`, the read-only mapping that
# holds such values (a test's, a log's or a profile's parameters) inside frozen dataclasses.
#
# Keys are spelt as a profile spells them: a PX4 parameter by its name (``MPC_XY_CRUISE``), a profile field by its
# name (``takeoff_delay_s``), a planner, camera or noise field with its section (``planner.cruise_speed``,
# ``sensor.rays_h``, ``noise.pos_noise_std``); a test's ``uav.<setting>`` param is checked as ``<setting>``. A value
# outside its range would fly a UAV that times out, flies away or divides by zero, so it is refused before anything
# flies, in one line naming the field. A numeric value without an entry need only be finite.
#
# PX4 parameters: the upper bounds are the ``@max`` of PX4 v1.12's parameter metadata (the firmware generation of
# case0.ulg and of Aerialist's SITL), from the ``*_params.c`` files that generate the parameter reference
# (https://docs.px4.io/v1.12/en/advanced_config/parameter_reference.html): ``mc_pos_control_params.c`` (e.g.
# MPC_XY_CRUISE and MPC_XY_VEL_MAX at most 20 m/s, MPC_Z_VEL_MAX_UP 8, MPC_Z_VEL_MAX_DN 4, MPC_TKO_SPEED 5,
# accelerations 15 m/s^2, MPC_JERK_AUTO 80 and MPC_JERK_MAX 500 m/s^3, thrusts 1), ``navigator_params.c``
# (NAV_ACC_RAD and NAV_MC_ALT_RAD at most 200 m), ``mission_params.c`` (MIS_TAKEOFF_ALT 80 m, MIS_YAW_ERR 90 deg),
# ``rtl_params.c`` (RTL_RETURN_ALT 150 m, RTL_LAND_DELAY 300 s), ``mc_att_control_params.c`` and
# ``mc_rate_control_params.c`` (gains, rate limits 1800 deg/s) and ``commander_params.c`` (COM_DISARM_LAND 20 s).
# Where the metadata gives no maximum, the bound is named beside the entry. The lower bounds are where the simulated
# UAV stops being one, not PX4's ``@min`` (which PX4 itself does not enforce and which flights do go below, e.g. a
# cruise speed under 3 m/s): a speed, an acceleration, a jerk, the hover thrust and the velocity gain the controller
# divides by must be > 0; gains, radii and altitudes >= 0.


class FrozenDict(dict):
    """A read-only dict: hashable, picklable (unlike ``types.MappingProxyType``), and equal to a plain dict."""

    def _readonly(self, *args, **kwargs):
        raise TypeError(f"{type(self).__name__} is read-only")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _readonly

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.items())))

    def __reduce__(self):
        return (type(self), (dict(self),))


UAV_SETTING_PREFIX = "uav."  # a test's params named uav.<setting> set the simulated UAV, not PX4
UAV_TIMINGS = ("takeoff_delay_s", "takeoff_hold_s")  # the UAV settings that are profile fields, not the planner's


@dataclass(frozen=True, slots=True)
class Range:
    """A closed or half-open interval of finite numbers, with its unit for messages."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    unit: str = ""

    def holds(self, value: float) -> bool:
        """Whether ``value`` lies in the range (each end open or closed as set)."""
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def __str__(self) -> str:
        if self.high == math.inf:
            text = f"{'>' if self.low_open else '>='} {self.low:g}"
        else:
            text = f"in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"
        return text + (f" {self.unit}" if self.unit else "")


def _speed(high: float) -> Range:
    return Range(0.0, high, low_open=True, unit="m/s")


def _accel(high: float) -> Range:
    return Range(0.0, high, low_open=True, unit="m/s^2")


def _gain(high: float = math.inf, positive: bool = False) -> Range:
    return Range(0.0, high, low_open=positive)


_METRES = "m"
_SECONDS = "s"
_THRUST = Range(0.0, 1.0, low_open=True)  # normalised thrust: 0 cannot lift, above 1 is more than the motors give
_FLAG = Range(0.0, 1.0)
_NOISE_M = Range(0.0, 10.0, unit=_METRES)  # a position error beyond 10 m is no estimator's
_TAU = Range(0.0, 3600.0, low_open=True, unit=_SECONDS)
_MAX_S = 3600.0  # [s] an hour on the ground or at a hold is longer than any battery lasts

RANGES = FrozenDict({
    # --- PX4 parameters the simulator reads (sim/config.py: PX4_DEFAULTS), PX4 v1.12 metadata maxima ---
    "MPC_XY_CRUISE": _speed(20.0), "MPC_XY_VEL_MAX": _speed(20.0),
    "MPC_Z_VEL_MAX_UP": _speed(8.0), "MPC_Z_VEL_MAX_DN": _speed(4.0), "MPC_TKO_SPEED": _speed(5.0),
    "MPC_LAND_SPEED": _speed(4.0),  # no @max in the metadata: bounded by the descent limit's (MPC_Z_VEL_MAX_DN)
    "MPC_ACC_HOR": _accel(15.0), "MPC_ACC_UP_MAX": _accel(15.0), "MPC_ACC_DOWN_MAX": _accel(15.0),
    "MPC_JERK_AUTO": Range(0.0, 80.0, low_open=True, unit="m/s^3"),
    "MPC_JERK_MAX": Range(0.0, 500.0, low_open=True, unit="m/s^3"),
    "MPC_THR_HOVER": Range(0.0, 1.0, low_open=True, high_open=True),  # the controller divides by it
    "MPC_THR_MIN": _THRUST, "MPC_THR_MAX": _THRUST, "MPC_USE_HTE": _FLAG,
    "MPC_TILTMAX_AIR": Range(0.0, 89.0, low_open=True, unit="deg"),
    "MPC_XY_P": _gain(2.0, positive=True), "MPC_Z_P": _gain(1.5, positive=True),
    "MPC_XY_VEL_P_ACC": _gain(5.0, positive=True),  # the anti-windup divides by it
    "MPC_XY_VEL_I_ACC": _gain(60.0), "MPC_XY_VEL_D_ACC": _gain(2.0),
    "MPC_Z_VEL_P_ACC": _gain(15.0, positive=True), "MPC_Z_VEL_I_ACC": _gain(3.0), "MPC_Z_VEL_D_ACC": _gain(2.0),
    "MPC_XY_TRAJ_P": _gain(1.0, positive=True), "MPC_XY_ERR_MAX": Range(0.0, 10.0, low_open=True),
    "MPC_TKO_RAMP_T": Range(0.0, 5.0, unit=_SECONDS),
    "MPC_LAND_ALT1": Range(0.0, 122.0, unit=_METRES), "MPC_LAND_ALT2": Range(0.0, 122.0, unit=_METRES),
    "MPC_YAWRAUTO_MAX": Range(0.0, 360.0, low_open=True, unit="deg/s"), "MPC_YAW_MODE": Range(0.0, 4.0),
    "MC_ROLL_P": _gain(12.0), "MC_PITCH_P": _gain(12.0), "MC_YAW_P": _gain(5.0), "MC_YAW_WEIGHT": _gain(1.0),
    "MC_ROLLRATE_P": _gain(0.5), "MC_ROLLRATE_I": _gain(), "MC_ROLLRATE_D": _gain(0.01),
    "MC_ROLLRATE_K": _gain(5.0, positive=True),
    "MC_PITCHRATE_P": _gain(0.6), "MC_PITCHRATE_I": _gain(), "MC_PITCHRATE_D": _gain(),
    "MC_PITCHRATE_K": _gain(5.0, positive=True),
    "MC_YAWRATE_P": _gain(0.6), "MC_YAWRATE_I": _gain(), "MC_YAWRATE_D": _gain(),
    "MC_YAWRATE_K": _gain(5.0, positive=True),
    "MC_ROLLRATE_MAX": Range(0.0, 1800.0, unit="deg/s"), "MC_PITCHRATE_MAX": Range(0.0, 1800.0, unit="deg/s"),
    "MC_YAWRATE_MAX": Range(0.0, 1800.0, unit="deg/s"),
    "MC_RR_INT_LIM": _gain(), "MC_PR_INT_LIM": _gain(), "MC_YR_INT_LIM": _gain(), "THR_MDL_FAC": _gain(1.0),
    "NAV_ACC_RAD": Range(0.0, 200.0, low_open=True, unit=_METRES),
    "NAV_MC_ALT_RAD": Range(0.0, 200.0, low_open=True, unit=_METRES),
    "MIS_TAKEOFF_ALT": Range(0.0, 80.0, unit=_METRES), "MIS_YAW_ERR": Range(0.0, 90.0, unit="deg"),
    "RTL_RETURN_ALT": Range(0.0, 150.0, unit=_METRES), "RTL_LAND_DELAY": Range(-1.0, 300.0, unit=_SECONDS),
    # the land detector's thresholds have no @max: bounded as the speeds above
    "LNDMC_Z_VEL_MAX": _speed(8.0), "LNDMC_XY_VEL_MAX": _speed(20.0),
    "LNDMC_TRIG_TIME": Range(0.0, 10.0, low_open=True, unit=_SECONDS),
    "COM_DISARM_LAND": Range(-1.0, 20.0, unit=_SECONDS), "COM_OBS_AVOID": _FLAG,
    # --- UAV profile fields and the UAV settings a test's uav.* params set ---
    "takeoff_delay_s": Range(0.0, _MAX_S, unit=_SECONDS), "takeoff_hold_s": Range(0.0, _MAX_S, unit=_SECONDS),
    "timeout_s": Range(0.0, 86_400.0, low_open=True, unit=_SECONDS),  # a day of simulated time
    "obstacle_collision_scale": Range(0.0, 1.0, low_open=True),
    # --- planners (sim/avoidance: reactive.py, px4/local_planner.py): speeds bounded as PX4's cruise and climb ---
    "planner.cruise_speed": _speed(20.0), "planner.avoid_speed": _speed(20.0),
    "planner.max_climb_rate": Range(0.0, 8.0, unit="m/s"), "planner.goal_brake_accel": _accel(15.0),
    "planner.max_turn_rate_deg_s": Range(0.0, 1800.0, low_open=True, unit="deg/s"),
    "planner.range_max": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "planner.max_sensor_range": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "planner.memory_time": _TAU, "planner.max_point_age_s": _TAU,
    "planner.heading_offset_deg": Range(-90.0, 90.0, unit="deg"),
    # --- depth camera (sim/sensing/sensor.py): rays cost time as their product, so a few hundred per axis at most ---
    "sensor.rays_h": Range(1.0, 512.0), "sensor.rays_v": Range(1.0, 512.0),
    "sensor.range_max": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "sensor.noise_std": _NOISE_M,
    # --- run-to-run variation (sim/config.py: NoiseConfig) ---
    "noise.pos_noise_std": _NOISE_M, "noise.pos_drift_std": _NOISE_M,
    "noise.vel_noise_std": Range(0.0, 10.0, unit="m/s"),
    "noise.turbulence_std": Range(0.0, 30.0, unit="m/s"),  # the wind bound of testcase.MAX_WIND_SPEED_MS
    "noise.pos_drift_tau_s": _TAU, "noise.turbulence_tau_s": _TAU,
    "noise.planner_jitter_s": Range(0.0, 5.0, unit=_SECONDS), "noise.start_jitter_s": Range(0.0, 60.0, unit=_SECONDS),
})


def problem(key: str, value) -> str | None:
    """What is wrong with ``value`` for ``key`` (None when nothing is): a number outside the key's physical range
    (:data:`RANGES`), anything but a finite number for a key with a range, or a non-finite number for any key
    (other values, such as a planner's flags, are left to the field's own type)."""
    rng = RANGES.get(key)
    number = not isinstance(value, bool) and isinstance(value, (int, float))
    if rng is None:
        return f"expected a finite number, got {value!r}" if number and not math.isfinite(value) else None
    if not number or not math.isfinite(value):
        return f"expected a finite number {rng}, got {value!r}"
    return None if rng.holds(value) else f"expected a number {rng}, got {value:g}"


def param_problem(name: str, value) -> str | None:
    """What is wrong with a test's param ``name`` (a PX4 parameter, or a UAV setting ``uav.<setting>``: a timing or
    ``planner.<field>``), or None; a param must be a finite number. (Whether a planner field exists depends on the
    UAV's avoidance model: sim/profiles.py: with_uav_settings checks that.)"""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"expected a number, got {value!r}"
    key = name.removeprefix(UAV_SETTING_PREFIX) if name.startswith(UAV_SETTING_PREFIX) else name
    if name.startswith(UAV_SETTING_PREFIX) and key not in UAV_TIMINGS and not key.startswith("planner."):
        return f"unknown UAV setting (expected one of {list(UAV_TIMINGS)} or planner.<field>)"
    return problem(key, value) or (None if math.isfinite(value) else f"expected a finite number, got {value!r}")
