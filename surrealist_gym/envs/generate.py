"""Surrealist-Generate-v0: find nearby test cases that make the UAV unsafe or crash (paper RQ2).

Reward: paper eq. 2, ``-(sum_dist + 2 min_dist)`` of the riskiest of the n runs (or their mean). ``min_dist`` and
"unsafe" follow the paper for a seed around a real flight, the UAV Testing Competition's distance for any other
Aerialist test (``distance=`` chooses; :class:`~surrealist_gym.fitness.Measure`). Defaults are the paper's RQ2: the
``auto1.plan`` mission with the ``rq2-seed.yaml`` obstacles, 10 runs, budget 50, move mutators on the first
obstacle only.
"""
from __future__ import annotations

from ..aerialist import load_test
from ..evaluation import GenerationObjective
from ..mutators import MOVE_KINDS, default_mutators
from ..outcomes import Measure, measure_for
from ..testcase import TestCase
from .base import EnvSetup, SurrealistEnv


class GenerateEnv(SurrealistEnv):
    """Generate risky tests in the neighbourhood of a seed test."""

    def __init__(self, seed_test=None, runs: int = 10, budget: int = 50, mutators=None,
                 aggregate: str = "riskiest", executor=None, store=None, random_seed: int = 0, sim_config=None,
                 workers: int | None = None, uav=None, distance: str | None = None, render_mode: str | None = None):
        from .. import data_path

        if seed_test is None:
            seed_test = data_path("rq2-seed.yaml")
        if not isinstance(seed_test, TestCase):
            seed_test = load_test(seed_test)
        self.aggregate = aggregate
        self.distance_measure = Measure(distance) if distance is not None else measure_for(seed_test)
        mutators = mutators or default_mutators(seed_test, MOVE_KINDS, obstacles=[0])
        setup = EnvSetup(runs=runs, random_seed=random_seed, sim_config=sim_config, uav=uav, executor=executor,
                         workers=workers, store=store)
        super().__init__(seed_test, mutators, budget, setup=setup, render_mode=render_mode)

    def _objective(self):
        return GenerationObjective(self.aggregate, self.distance_measure.value)
