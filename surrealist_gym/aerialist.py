"""The Aerialist test-case YAML: reading (:func:`load_test`) and writing (:func:`save_test`) the
:class:`~surrealist_gym.testcase.TestCase` values, read with the safe YAML loader for files from anywhere
(:func:`~surrealist_gym.errors.safe_yaml`).

The YAML is Aerialist's, as both generations in use read and write it (docs/aerialist-yaml.md): :func:`save_test`
writes what Aerialist master (``robot``/``mission``) and 0.2.x (``drone``/``test``) both load with geometry, and
:func:`load_test` reads what either writes; a field that changes the flight and cannot be simulated is a one-line
error, one that Aerialist's own flight would not miss a one-line warning naming the file.
:func:`~surrealist_gym.results.export_test` writes a YAML whose files travel with its folder.
"""
from __future__ import annotations

import csv
import warnings
from dataclasses import fields
from pathlib import Path

from .errors import InvalidTestCase, MissionError, input_file, one_line, read_text, regular_file, safe_yaml
from .mission import read_mission
from .testcase import Obstacle, RuntimeCommand, Shape, TestCase, Wind, is_finite_number, parse_shape

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
#: The fields that name a file, by section (both generations' section names: robot/drone, mission/test).
FILE_FIELDS = {"robot": ("params_file", "mission_file"), "drone": ("params_file", "mission_file"),
               "mission": ("commands_file",), "test": ("commands_file",)}
#: Aerialist's PX4 ports (RobotConfig, DroneConfig) by the names both generations read; 14550 is a real vehicle's.
PORTS = {"sitl": 14540, "sim": 14540, "px4_sitl": 14540, "ros": 14541, "avoidance": 14541, "px4_ros": 14541,
         "cf": 14550, "hw": 14550, "px4_cf": 14550}
SITL_PORT, AVOIDANCE_PORT, VEHICLE_PORT = 14540, 14541, 14550
SIMULATORS = ("gazebo", "ros", "jmavsim")
AGENTS = ("local", "docker", "k8s")


def load_test(path, allow_outside=()) -> TestCase:
    """Load an Aerialist test-case YAML, as Aerialist master or 0.2.x writes it (docs/aerialist-yaml.md).

    Sections under either generation's names (``robot``/``drone``, ``mission``/``test``; both given: they must be
    equal). Obstacles in the flat form ``[l,w,h,x,y,z,r]*`` or as dicts (``shape`` box or cylinder, ``size.r`` a
    cylinder's radius). The simulation's ``timeout`` (times its ``speed``: Aerialist's clock is the wall's) limits the
    flight. What cannot be flown is a one-line error naming the file and field (a real vehicle's port, an unknown
    simulator or field); what Aerialist's flight would not miss is read with one warning line naming the file
    (a shape name Aerialist reads without geometry, jMAVSim, ``agent.count``). A file the test names is resolved
    and checked by :func:`~surrealist_gym.errors.input_file`: against the YAML's folder, the working folder, then by
    its name in the YAML's folder; it must lie under one of them or a folder of ``allow_outside`` (the command
    line's ``--allow-outside``).
    """
    path = Path(path)
    name = regular_file(path, "test case", InvalidTestCase)
    doc = safe_yaml(read_text(path, "test case", InvalidTestCase), name)
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
        return None if value is None else input_file(value, base, f"{name}: field {key!r}", InvalidTestCase,
                                                  allow_outside=allow_outside)

    mission_file = resolve("mission_file", robot.get("mission_file"))
    mission = None
    if mission_file is not None:
        try:
            mission = read_mission(mission_file)
        except MissionError as err:
            raise InvalidTestCase(f"{name}: field 'mission_file': {err}") from err
    params_file = resolve("params_file", robot.get("params_file"))
    params = dict(_in_field(name, "params_file", _read_params, params_file)) if params_file else {}
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
        commands = _in_field(name, "commands_file", _read_commands, commands_file) if commands_file else ()
    obstacles = parse_obstacles(sim.get("obstacles"), name, notes)
    wind = None
    if sim.get("wind") is not None:
        if not isinstance(sim["wind"], dict):
            raise InvalidTestCase(f"{name}: field 'wind': expected a mapping, got {sim['wind']!r}")
        wind = _construct(Wind, sim["wind"], f"{name}: field 'wind'")
    home = sim.get("home_position")
    if home is not None:
        if not (isinstance(home, list) and len(home) == 3):
            raise InvalidTestCase(f"{name}: field 'home_position': expected [lat, lon, alt], got {home!r}")
        if not all(is_finite_number(v) for v in home) or not (-90 <= home[0] <= 90 and -180 <= home[1] <= 180):
            raise InvalidTestCase(f"{name}: field 'home_position': expected [lat, lon, alt] as numbers (lat in "
                                  f"[-90, 90], lon in [-180, 180]), got {home!r}")
        home = tuple(float(v) for v in home)
    timeout = sim.get("timeout")
    if timeout is not None and not is_finite_number(timeout):
        raise InvalidTestCase(f"{name}: simulation.timeout: expected a number of seconds (0 or less: none), got "
                              f"{timeout!r}")
    log = assertion.get("log_file") if assertion.get("log_file") is not None else own.get("assertion_log")
    if log is not None and not isinstance(log, str):
        raise InvalidTestCase(f"{name}: field 'log_file': expected a file path, got {log!r}")
    reference_log = input_file(log, base, f"{name}: field 'log_file'", InvalidTestCase, True,
                               allow_outside) if log else None
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
    relative to the YAML's folder when the file lies in it, else absolute
    (:func:`~surrealist_gym.results.export_test` copies them in). A real flight named but not at hand goes to the
    ``surrealist`` section, which Aerialist ignores (its assertion would fail to load). A test with ``wind`` or a
    ``timeout`` is master's only: 0.2.x has neither.
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


def _port(value) -> int | None:
    """The port number Aerialist makes of a ``port`` field (None: Aerialist's RobotConfig sets none)."""
    if isinstance(value, str):
        return int(value) if value.isdigit() else PORTS.get(value)
    return value if isinstance(value, int) and not isinstance(value, bool) else None


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
        if not is_finite_number(value) or value <= 0:
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
            isinstance(w, dict) and is_finite_number(w.get("x")) and is_finite_number(w.get("y")) for w in waypoints)):
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


def _relative(file: str, base: Path) -> str:
    """``file`` relative to ``base`` when it lies inside it, else absolute."""
    path = Path(file).resolve()
    return str(path.relative_to(base)) if path.is_relative_to(base) else str(path)


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


def parse_obstacles(raw, name, notes: list | None = None) -> tuple[Obstacle, ...]:
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
            shape = parse_shape("box" if given is None else given)
            if given not in (None, "box", "cylinder"):
                odd.setdefault(f"shape {given!r} is read as {shape.value}, but Aerialist builds no geometry for it "
                               f"(write {shape.value!r})", []).append(i)
            if "angle" in pos:
                odd.setdefault("position.angle is read as r, which is what Aerialist reads", []).append(i)
            length, width = size.get("l"), size.get("w")
            radius = size.get("r", 0)
            if not is_finite_number(radius) or radius < 0:
                raise InvalidTestCase(f"size 'r': expected a number >= 0 (a cylinder's radius), got {radius!r}")
            if shape == Shape.CYLINDER and radius > 0:
                if any(is_finite_number(v) and v and abs(v - 2 * radius) > 1e-9 for v in (length, width)):
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


def _in_field(name: str, key: str, read, path: str):
    """``read(path)``, its error prefixed with the YAML and the field that names the file."""
    try:
        return read(path)
    except InvalidTestCase as err:
        raise InvalidTestCase(f"{name}: field {key!r}: {err}") from None


def _csv_rows(path: str, what: str) -> list[tuple[int, list[str]]]:
    """The numbered rows of a CSV file; a malformed one (a field over csv's limit, a NUL) is a one-line error."""
    try:
        return list(enumerate(csv.reader(read_text(path, what, InvalidTestCase).splitlines()), start=1))
    except csv.Error as err:
        raise InvalidTestCase(f"{path}: not a {what} (CSV: {one_line(err, 60)})") from None


def _read_params(path: str) -> list[tuple[str, float]]:
    """PX4 parameters from ``NAME, value`` lines (no header). Errors name the line, never quote it (a test may name
    any file: docs/aerialist-yaml.md)."""
    from .errors import RANGES, UAV_SETTING_PREFIX, param_problem

    out = []
    for n, row in _csv_rows(path, "params file"):
        if not row or not row[0].strip() or row[0].strip().startswith("#"):
            continue
        if len(row) < 2:
            raise InvalidTestCase(f"{path}: line {n}: expected 'NAME, value'")
        name = row[0].strip()
        shown = f"parameter {name}" if name in RANGES or name.startswith(UAV_SETTING_PREFIX) else "the parameter"
        try:
            value = float(row[1])
        except ValueError:
            raise InvalidTestCase(f"{path}: line {n}: {shown}: its value is not a number") from None
        bad = param_problem(name, value)
        if bad:
            raise InvalidTestCase(f"{path}: line {n}: {shown}: {bad}")
        out.append((name, int(value) if value.is_integer() and "." not in row[1] else value))
    return out


def _read_commands(path: str) -> tuple[RuntimeCommand, ...]:
    rows = [(n, r) for n, r in _csv_rows(path, "commands file") if r and any(c.strip() for c in r)]
    if rows and rows[0][1][0].strip() == "timestamp":
        rows = rows[1:]
    out = []
    for n, row in rows:
        try:
            values = [float(c) for c in row]
        except ValueError:
            raise InvalidTestCase(f"{path}: line {n}: expected numbers timestamp,mode,x,y,z,r") from None
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


# --- safe loading ------------------------------------------------------------------------------------------------
