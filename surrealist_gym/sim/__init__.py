"""The simulated UAV under test: a PX4-like quadrotor flying a mission in PyBullet, with optional avoidance.

Public face::

    import surrealist_gym as sg
    results = sg.simulate(test, runs=5, seed=0)      # one RunResult per run
    results[0].status, results[0].min_distance, results[0].duration, results[0].trajectory

No gymnasium import here (the envs build on this package). The names below are loaded on first use (PEP 562), so
importing a light module of the package (``sim.config``) loads neither PyBullet nor the run loop.

The rooms: the front door here (``config``, ``profiles``, ``uav``, ``runner``, ``run_end``); ``vehicle``
(airframe, PX4's controllers, rigid-body physics, compiled and PyBullet); ``navigation`` (PX4's navigator and flight
task, in Python and as kernels); ``sensing`` (depth camera, estimator noise and wind); ``avoidance`` (the planner
protocol, the reactive planner, and ``avoidance.px4``: PX4-Avoidance); ``compiled`` (the compiled run loop);
``reference`` (readable Python versions of kernels, which tests and benchmarks compare against).
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "PX4_DEFAULTS": "config", "NoiseConfig": "config", "Physics": "config", "SimConfig": "config",
    "VehicleModel": "config",
    "Clearance": "runner", "LocalPosition": "runner", "RunResult": "runner", "RunStatus": "runner",
    "simulate": "runner", "simulate_runs": "runner",
    "DEFAULT_UAV": "uav", "UavDecision": "uav", "decide_uav": "uav",
    "IRIS": "vehicle.airframe", "VEHICLES": "vehicle.airframe", "PX4_VISION": "vehicle.airframe",
    "VehicleParams": "vehicle.airframe", "preset": "vehicle.airframe",
}


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


__all__ = ["Clearance", "DEFAULT_UAV", "IRIS", "LocalPosition", "NoiseConfig", "PX4_DEFAULTS", "PX4_VISION",
           "Physics", "RunResult", "RunStatus", "SimConfig", "UavDecision", "VEHICLES", "VehicleModel", "VehicleParams",
           "decide_uav", "preset", "simulate", "simulate_runs"]
