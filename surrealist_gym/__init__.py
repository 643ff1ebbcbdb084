"""surrealist-gym: simulation-based testing of drones in the neighbourhood of real flights.

Public face::

    import surrealist_gym as sg
    flight = sg.read_flight("case0.ulg")      # FlightLog from .ulg / .tlog / .bin
    traj = flight.trajectory                   # the paper's pipeline: 0.5 s windows
    sg.dtw(a, b); sg.frechet(a, b)            # Trajectory or (N, 3) arrays
    test = sg.load_test("seed.yaml"); sg.save_test(test, "out.yaml")
"""
from __future__ import annotations

import os as _os
import sys as _sys
from importlib import resources as _resources

from .aerialist import load_test, save_test
from .errors import (
    DependencyNotInstalled,
    InvalidTestCase,
    LogFormatError,
    MissionError,
    SimulationError,
    SurrealistError,
    UnknownAgent,
)
from .mission import Command, Mission, MissionItem, read_mission, read_plan, read_waypoints, write_plan
from .testcase import Obstacle, RuntimeCommand, Shape, TestCase, Wind
from .trajectory import Trajectory

__version__ = "0.1.0"


def _kernel_cache() -> None:
    """Numba caches the compiled simulator in the user's cache folder (``$XDG_CACHE_HOME``, else ``~/.cache``, on
    Windows ``%LOCALAPPDATA%``; then ``surrealist-gym/numba``), not beside the installed package, which the user may
    not own. ``NUMBA_CACHE_DIR``, when set, wins (it is numba's setting, shared by all numba code in the process)."""
    if _os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = _os.environ.get("XDG_CACHE_HOME") or (_os.environ.get("LOCALAPPDATA") if _os.name == "nt" else None)
    folder = _os.path.join(base or _os.path.join(_os.path.expanduser("~"), ".cache"), "surrealist-gym", "numba")
    _os.environ["NUMBA_CACHE_DIR"] = folder  # read when numba is imported, and by worker processes
    if "numba" in _sys.modules:  # imported already: its config read the environment before this
        _sys.modules["numba"].config.CACHE_DIR = folder


_kernel_cache()


def _register_envs() -> None:
    """Register the envs (idempotent); entry points are strings, so nothing heavy is imported until make()."""
    from gymnasium.envs.registration import register, registry

    for env_id, entry_point in (("Surrealist-Replicate-v0", "surrealist_gym.envs.flyable:replicate"),
                                ("Surrealist-Generate-v0", "surrealist_gym.envs.flyable:generate"),
                                ("Surrealist-CaseStudy-v1",
                                 "surrealist_gym.competition.case_study_env:flyable_case_study"),
                                ("Surrealist-Missions-v0", "surrealist_gym.competition.missions:MissionCaseStudies")):
        if env_id not in registry:
            register(id=env_id, entry_point=entry_point)


_register_envs()


def data_path(name: str) -> str:
    """Path of a file bundled with the package: ``case0.ulg``, ``case0.plan``, ``rq1-seed1.yaml``, ..."""
    return str(_resources.files(__package__).joinpath("data", name))


def __getattr__(name: str):
    # Late imports keep `import surrealist_gym` fast and let each part be built independently.
    if name in {"read_flight", "FlightLog"}:
        from . import logs
        return getattr(logs, name)
    if name in {"dtw", "frechet", "dba", "soft_dtw_barycenter"}:
        from . import metrics
        return getattr(metrics, name)
    if name in {"simulate"}:
        from . import sim
        return getattr(sim, name)
    raise AttributeError(f"module 'surrealist_gym' has no attribute {name!r}")


__all__ = [
    "Command", "DependencyNotInstalled", "InvalidTestCase", "LogFormatError", "Mission", "MissionError",
    "MissionItem", "Obstacle", "RuntimeCommand", "Shape", "SimulationError", "SurrealistError", "TestCase",
    "Trajectory", "UnknownAgent", "Wind", "data_path", "load_test", "read_mission", "read_plan", "read_waypoints",
    "save_test", "write_plan", "read_flight", "FlightLog", "dtw", "frechet", "dba", "soft_dtw_barycenter",
    "simulate",
]
