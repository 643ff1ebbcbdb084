"""The simulated UAV under test: a PX4-like quadrotor flying a mission in PyBullet, with optional avoidance.

Public face::

    import surrealist_gym as sg
    results = sg.simulate(test, runs=5, seed=0)      # one RunResult per run
    results[0].status, results[0].min_distance, results[0].duration, results[0].trajectory

No gymnasium import here (the envs build on this package).
"""
from __future__ import annotations

from .config import PX4_DEFAULTS, NoiseConfig, SimConfig, VehicleModel
from .runner import Clearance, LocalPosition, RunResult, RunStatus, simulate, simulate_runs
from .vehicle import IRIS, PRESETS, PX4_VISION, VehicleParams, preset

__all__ = ["Clearance", "IRIS", "LocalPosition", "NoiseConfig", "PRESETS", "PX4_DEFAULTS", "PX4_VISION",
           "RunResult", "RunStatus", "SimConfig", "VehicleModel", "VehicleParams", "preset", "simulate",
           "simulate_runs"]
