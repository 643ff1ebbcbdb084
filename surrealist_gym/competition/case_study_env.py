"""Surrealist-CaseStudy-v1: generate tests for a UAV Testing Competition case study, under the competition's rules.

The case study is a name, an Aerialist YAML or a test (its obstacles dropped: a drawn case study,
:mod:`~surrealist_gym.competition.missions`). The seed is the case study's mission with ``obstacles`` boxes
(:func:`~surrealist_gym.competition.rules.seed_layout`). The action space is the rules' box: one value in [-1, 1]
per box and field (x, y, l, w, h, r), -1 the rule's low bound, +1 its high bound, linearly between
(:func:`~surrealist_gym.competition.rules.layout_mutators`), so every action (``action_space.sample()`` too) gives
boxes within the rules' ranges and any agent of ``search/`` can search it; the seed is the action
``env.seed_action``. What the ranges cannot rule out is refused: boxes that overlap, a box within the
1.5 m safety distance of the take-off or landing point (every run would fail before flying:
:func:`~surrealist_gym.competition.rules.endpoint_failure`) and a layout the feasibility check finds walled off. Such
a test is not flown: it costs no budget, the reward is the env's penalty and ``info["invalid"]`` gives the reason
(``overlap``, ``degenerate: ...``, ``infeasible: ...``). The reward is the paper's eq. 2 on the competition's
distance; the UAV is the PX4 SITL profile (``px4-v1.12-sitl-iris``) unless ``uav`` names another. ``wind=True`` adds
the wind mutators. ``render_mode="rgb_array"`` draws the last flight's top view.

Example::

    env = gym.make("Surrealist-CaseStudy-v1", case_study="mission2", budget=200)
"""
from __future__ import annotations

import numpy as np

from ..envs.base import EnvSetup, SurrealistEnv
from ..envs.flyable import maker
from ..errors import InvalidTestCase
from ..evaluation import GenerationObjective
from ..mutators import mutated_obstacles
from ..outcomes import Measure
from ..testcase import Obstacle, TestCase
from .rules import RULES, check_rules, endpoint_failure, layout_mutators, load_case_study, seed_layout


class CaseStudyEnv(SurrealistEnv):
    """Generate failing tests for one case study of the competition."""

    # three uniform boxes still overlap or wall the mission off often; those steps cost no simulation, so an
    # episode may take many of them
    steps_per_budget = 50

    def __init__(self, case_study: str | TestCase = "mission1", obstacles: int = 3, runs: int = 1, budget: int = 200,
                 aggregate: str = "riskiest", executor=None, store=None, random_seed: int = 0, sim_config=None,
                 workers: int | None = None, uav=None, wind: bool = False, feasibility: bool = True,
                 rules=RULES, render_mode: str | None = None):
        self.case_study = (case_study.with_obstacles(()) if isinstance(case_study, TestCase)
                           else load_case_study(case_study))
        self.rules = rules
        self.feasibility = feasibility
        self.aggregate = aggregate
        self.distance_measure = Measure.COMPETITION
        seed = self.case_study.with_obstacles(seed_layout(obstacles, rules))
        mutators = layout_mutators(seed, rules)
        if wind:
            from ..mutators import wind_mutators
            mutators += wind_mutators()
        setup = EnvSetup(runs=runs, random_seed=random_seed, sim_config=sim_config, uav=uav, executor=executor,
                         workers=workers, store=store)
        super().__init__(seed, mutators, budget, setup=setup, render_mode=render_mode)

    def _objective(self):
        return GenerationObjective(self.aggregate, Measure.COMPETITION.value)

    def boxes_for(self, action) -> tuple[Obstacle, ...]:
        """The boxes an action stands for, nothing else checked or flown: each field is the rule's low bound at -1 and
        its high bound at +1 (the layout mutators' decoding, :func:`~surrealist_gym.mutators.mutated_obstacles`), so
        they are always within the rules' ranges; they may overlap."""
        return mutated_obstacles(self.seed_test, self.mutators, np.asarray(action, dtype=np.float64).reshape(-1))

    def test_for(self, action) -> TestCase:
        """The test an action stands for; InvalidTestCase when its boxes overlap, when a box is within the safety
        distance of the take-off or landing point, or when the mission cannot be flown through."""
        test = super().test_for(action)  # overlapping boxes are refused here
        check_rules(test, self.rules)
        degenerate = endpoint_failure(test)
        if degenerate is not None:
            raise InvalidTestCase(f"degenerate: {degenerate}")
        if self.feasibility:
            from .feasibility import infeasible

            reason = infeasible(test)
            if reason is not None:
                raise InvalidTestCase(f"infeasible: {reason}")
        return test


flyable_case_study = maker(CaseStudyEnv)  # Surrealist-CaseStudy-v1's entry point
