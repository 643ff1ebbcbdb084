"""An Aerialist test as Aerialist's ``to_dict()`` (or ``to_yaml()``) gives it, to surrealist-gym's test case.

Aerialist resolves a relative path against the working folder of the process that reads it (COMPETITION.md
section 4), so a test sent from a tool's process names its paths against that tool's folder; they are made
absolute here. Aerialist master writes an obstacle's ``shape`` and its ``size.r`` (a cylinder's radius, 0 for a
box); a cylinder becomes our cylinder of diameter ``2 r``. Aerialist's ports are numbers once loaded
(``ros`` becomes 14541); they are named again so that a ``ros`` robot flies PX4-Avoidance here too. The
``assertion`` and ``agent`` sections are dropped: a competition test names no reference flight.

Example::

    >>> aerialist_doc({"simulation": {"obstacles": [{"size": {"l": 4, "w": 2, "h": 20, "r": 0},
    ...     "position": {"x": 1, "y": 20, "z": 0, "r": 30}, "shape": "box"}]}}, "/tool")["simulation"]
    {'obstacles': [{'size': {'l': 4, 'w': 2, 'h': 20}, 'position': {'x': 1, 'y': 20, 'z': 0, 'r': 30}, 'shape': 'box'}]}
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

from ..errors import InvalidTestCase

#: Aerialist's port numbers (RobotConfig / DroneConfig) by the name a test gives them.
PORT_NAMES = {14540: "sitl", 14541: "ros", 14550: "cf"}
_SIMULATION_KEYS = ("simulator", "world", "speed", "headless", "home_position", "wind", "timeout")


def aerialist_doc(test: Mapping, cwd) -> dict:
    """Our Aerialist YAML document (current keys) of an Aerialist test dict whose relative paths name files in
    ``cwd``."""
    if not isinstance(test, Mapping):
        raise InvalidTestCase(f"expected an Aerialist test (a mapping of sections), got {test!r}")
    robot = _section(test, "robot", "drone")
    simulation = _section(test, "simulation")
    mission = _section(test, "mission", "test")
    doc_robot = {}
    if robot.get("port") is not None:
        doc_robot["port"] = PORT_NAMES.get(robot["port"], robot["port"])
    if robot.get("params") is not None:
        doc_robot["params"] = robot["params"]
    for key in ("params_file", "mission_file"):
        if robot.get(key) is not None:
            doc_robot[key] = _absolute(robot[key], cwd, key)
    doc_simulation = {k: simulation[k] for k in _SIMULATION_KEYS if simulation.get(k) is not None}
    obstacles = simulation.get("obstacles") or []
    if not isinstance(obstacles, list):
        raise InvalidTestCase(f"simulation.obstacles: expected a list, got {obstacles!r}")
    doc_simulation["obstacles"] = [_obstacle(o, i) for i, o in enumerate(obstacles)]
    doc_mission = {}
    if mission.get("commands") is not None:
        doc_mission["commands"] = mission["commands"]
    if mission.get("commands_file") is not None:
        doc_mission["commands_file"] = _absolute(mission["commands_file"], cwd, "commands_file")
    return {"robot": doc_robot, "simulation": doc_simulation, "mission": doc_mission}


def write_test(test: Mapping, cwd, path) -> Path:
    """Write the Aerialist test as our YAML at ``path`` (``load_test`` reads it); returns the path."""
    import yaml

    path = Path(path)
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump(aerialist_doc(test, cwd), f, sort_keys=False)
    return path


def read_aerialist_yaml(path) -> dict:
    """An Aerialist test YAML as a plain dict (a one-line InvalidTestCase for what YAML's safe loader refuses, such
    as the numpy scalars some tools' ``to_yaml`` writes)."""
    import yaml

    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        raise InvalidTestCase(f"{path}: not a plain Aerialist test YAML ({' '.join(str(err).split())[:80]})") from None
    if not isinstance(doc, dict):
        raise InvalidTestCase(f"{path}: expected a mapping of sections, got {doc!r}")
    return doc


def _section(test: Mapping, key: str, legacy: str | None = None) -> Mapping:
    value = test.get(key)
    if value is None and legacy is not None:
        value, key = test.get(legacy), legacy
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise InvalidTestCase(f"section {key!r}: expected a mapping, got {value!r}")
    return value


def _absolute(value, cwd, key: str) -> str:
    if not isinstance(value, str):
        raise InvalidTestCase(f"field {key!r}: expected a file path, got {value!r}")
    return value if os.path.isabs(value) else os.path.normpath(os.path.join(os.fspath(cwd), value))


def _obstacle(raw, i: int) -> dict:
    if not isinstance(raw, Mapping) or not isinstance(raw.get("size"), Mapping) \
            or not isinstance(raw.get("position"), Mapping):
        raise InvalidTestCase(f"obstacles[{i}]: expected a mapping with size and position, got {raw!r}")
    shape = str(raw.get("shape") or "box").lower()
    size, position = raw["size"], raw["position"]
    if shape == "cylinder":
        diameter = 2 * size["r"] if size.get("r") else size.get("l")
        size = {"l": diameter, "w": diameter, "h": size.get("h")}
    elif shape == "box":
        size = {k: size.get(k) for k in ("l", "w", "h")}
    else:
        raise InvalidTestCase(f"obstacles[{i}].shape: {raw.get('shape')!r}: Aerialist gives such an obstacle no "
                              f"geometry (expected box or cylinder)")
    return {"size": size, "position": {k: position.get(k, 0) for k in ("x", "y", "z", "r")}, "shape": shape}
