"""Surrealist-Replicate-v0: find the obstacle layout whose simulated flight matches a real one (paper RQ1).

Reward: ``-DTW(real trajectory, average of the n simulated runs)``. Defaults are the paper's RQ1: the bundled
real flight ``case0.ulg``, the paper's seed 1, 5 runs per evaluation, budget 100, all mutators on every obstacle
(authors' order y, x, r, sy, sx, sz).
"""
from __future__ import annotations

import math
from dataclasses import replace

from ..errors import LogFormatError
from ..evaluation import ReplicationObjective
from ..mutators import AUTHORS_ORDER, default_mutators, uav_mutators as uav_mutators_of
from ..sim.config import SimConfig
from ..sim.profiles import default_profile, load_profile
from ..testcase import Obstacle, TestCase, load_test
from .base import SurrealistEnv


class ReplicateEnv(SurrealistEnv):
    """Replicate a real flight by searching obstacle placements."""

    def __init__(self, reference_log=None, seed_test=None, runs: int = 5, budget: int = 100, mutators=None,
                 averaging: str = "dba", executor=None, store=None, random_seed: int = 0, sim_config=None,
                 workers: int | None = None, uav=None, reference_trajectory=None, allow_partial: bool = False,
                 uav_mutators=None):
        """``reference_trajectory`` (a Trajectory) replaces the log's, e.g. a simulated flight with hidden
        obstacles that plays the real one; the seed test then must be given. A damaged log (truncated, or with
        corrupt data skipped) is refused unless ``allow_partial``: its flight may be cut short.

        ``uav``: the UAV profile; by default the log's own (:func:`~surrealist_gym.calibration.profile_for_flight`:
        its vehicle's preset, on the ground as long as the log) unless ``sim_config`` is a full
        :class:`~surrealist_gym.sim.config.SimConfig`. ``uav_mutators``: search the UAV's settings as well as the
        obstacles (paper section 3): True for all of the profile's :data:`~surrealist_gym.sim.profiles.SETTINGS`,
        or their names, or :class:`~surrealist_gym.mutators.UavMutator` values; they come after the obstacles'."""
        from .. import data_path
        from ..logs import read_flight

        if seed_test is not None and not isinstance(seed_test, TestCase):
            seed_test = load_test(seed_test)
        self.flight = None
        if reference_trajectory is not None:
            if seed_test is None:
                raise ValueError("reference_trajectory needs a seed_test")
            self.reference = reference_trajectory
        else:
            if seed_test is None and reference_log is None:
                seed_test = load_test(data_path("rq1-seed1.yaml"))
            if reference_log is None:
                reference_log = seed_test.reference_log or data_path("case0.ulg")
            self.flight = read_flight(reference_log)
            if self.flight.damage and not allow_partial:
                raise LogFormatError(f"{self.flight.path}: {self.flight.damage}; replicating it would replicate a "
                                     f"flight cut short (allow it with --allow-partial)")
            seed_test = replace(seed_test or seed_from_flight(self.flight), reference_log=str(self.flight.path))
            self.reference = self.flight.trajectory
        self.averaging = averaging
        if uav is None and self.flight is not None and not isinstance(sim_config, SimConfig):
            from ..calibration import profile_for_flight
            uav = profile_for_flight(self.flight)
        mutators = tuple(mutators or default_mutators(seed_test, AUTHORS_ORDER))
        if uav_mutators:
            if uav_mutators is True or all(isinstance(m, str) for m in uav_mutators):
                profile = load_profile(uav) if uav is not None else default_profile(seed_test)
                names = None if uav_mutators is True else list(uav_mutators)
                uav_mutators = uav_mutators_of(profile, names)
            mutators += tuple(uav_mutators)
        super().__init__(seed_test, mutators, budget, runs, executor, store, random_seed, sim_config, workers, uav)

    def _objective(self):
        return ReplicationObjective(self.reference, self.averaging)


def seed_from_flight(flight, size: float = 3.0) -> TestCase:
    """The paper's seed for a log without one: a size^3 box near the middle of the straight path, turned along it."""
    if flight.mission is None or len(flight.mission.waypoints) < 2:
        from ..errors import InvalidTestCase
        raise InvalidTestCase(f"{flight.path}: the log holds no mission with two positions to place a seed obstacle "
                              f"on; give a seed test (--seed TEST.yaml)")
    (x0, y0, _), (x1, y1, _) = flight.mission.waypoints[0], flight.mission.waypoints[-1]
    yaw = math.degrees(math.atan2(y1 - y0, x1 - x0))
    box = Obstacle(size, size, size, (x0 + x1) / 2, (y0 + y1) / 2, 0.0, yaw)
    return TestCase(mission=flight.mission, obstacles=(box,), params=dict(flight.params),
                    reference_log=str(flight.path))
