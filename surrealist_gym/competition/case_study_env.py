"""Surrealist-CaseStudy-v0: generate tests for a UAV Testing Competition case study, under the competition's rules.

The seed is the case study's mission with ``obstacles`` boxes (:func:`~surrealist_gym.competition.rules.seed_layout`);
the action is one value in [-1, 1] per box and field (x, y, l, w, h, r), mapped linearly onto the competition's bounds
(:func:`~surrealist_gym.competition.rules.layout_mutators`), so any agent of ``search/`` can search it. A test that
breaks the rules (an overlap), that puts a box within the 1.5 m safety distance of the take-off or landing point (every
run would fail before flying: :func:`~surrealist_gym.competition.rules.endpoint_failure`) or that the feasibility check
finds walled off is not flown: it costs no budget and ``info["invalid"]`` gives the reason. The reward is the paper's
eq. 2 on the competition's distance; the UAV is the PX4 SITL profile (``px4-v1.12-sitl-iris``) unless ``uav`` names
another. ``wind=True`` adds the wind mutators.

Example::

    env = gym.make("Surrealist-CaseStudy-v0", case_study="mission2", budget=200)
"""
from __future__ import annotations

from ..envs.base import EnvSetup, SurrealistEnv
from ..errors import InvalidTestCase
from ..evaluation import GenerationObjective
from ..outcomes import Measure
from .rules import RULES, check_rules, endpoint_failure, layout_mutators, load_case_study, seed_layout

DEFAULT_UAV = "px4-v1.12-sitl-iris"


class CaseStudyEnv(SurrealistEnv):
    """Generate failing tests for one case study of the competition."""

    # uniform layouts of three boxes overlap or wall the mission off most of the time; those steps cost no
    # simulation, so an episode may take many of them
    steps_per_budget = 50

    def __init__(self, case_study="mission1", obstacles: int = 3, runs: int = 1, budget: int = 200,
                 aggregate: str = "riskiest", executor=None, store=None, random_seed: int = 0, sim_config=None,
                 workers: int | None = None, uav=None, wind: bool = False, feasibility: bool = True,
                 rules=RULES):
        self.case_study = load_case_study(case_study)
        self.rules = rules
        self.feasibility = feasibility
        self.aggregate = aggregate
        self.distance_measure = Measure.COMPETITION
        seed = self.case_study.with_obstacles(seed_layout(obstacles, rules))
        mutators = layout_mutators(seed, rules)
        if wind:
            from ..mutators import wind_mutators
            mutators += wind_mutators()
        if uav is None and sim_config is None:
            uav = DEFAULT_UAV
        setup = EnvSetup(runs=runs, random_seed=random_seed, sim_config=sim_config, uav=uav, executor=executor,
                         workers=workers, store=store)
        super().__init__(seed, mutators, budget, setup=setup)

    def _objective(self):
        return GenerationObjective(self.aggregate, Measure.COMPETITION.value)

    def test_for(self, action):
        """The test an action stands for; InvalidTestCase when it breaks the rules or cannot be flown through."""
        test = super().test_for(action)
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
