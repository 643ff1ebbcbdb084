"""The template env: an episode is one search from a seed test case.

Action: one value per mutator (``env.mutators``): the mutation of the SEED test, in the mutators' units (metres,
degrees), within each mutator's range. The adaptive greedy's move "param +/- step on one mutator around the best"
is an action vector; CMA-ES and RL propose whole vectors. Reward: the fitness of the mutated test (maximised).
Observation: the action last evaluated (scaled to [-1, 1]), the last and best fitness (scaled by the seed's), and
the share of the budget left. ``reset`` evaluates the seed (one evaluation). A test evaluated before comes from
the memo and costs no budget; an invalid test (overlap, non-positive size) is not simulated, costs no budget and
scores a penalty. The episode is truncated when the budget is spent.

Subclasses override only the hooks ``_objective`` and, if needed, ``_terminated``.
"""
from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

from ..errors import InvalidTestCase
from ..evaluation import Evaluation, Evaluator
from ..store import EvaluationStore
from ..testcase import TestCase

INVALID_STEPS_FACTOR = 4  # an episode also ends after this many steps per unit of budget (invalid actions)


class SurrealistEnv(gym.Env):
    """Base of Surrealist-Replicate-v0 and Surrealist-Generate-v0."""

    metadata = {"render_modes": []}

    def __init__(self, seed_test: TestCase, mutators, budget: int, runs: int, executor=None, store=None,
                 random_seed: int = 0, sim_config=None, workers: int | None = None):
        if budget < 1:
            raise ValueError(f"budget must be >= 1, got {budget}")
        if not mutators:
            raise ValueError("at least one mutator is needed")
        self._seed_test = seed_test
        self._mutators = tuple(mutators)
        self._budget = int(budget)
        store = EvaluationStore(store) if isinstance(store, (str, Path)) else store
        if executor is None and workers is not None:
            from ..executors import LocalPoolExecutor
            executor = LocalPoolExecutor(workers)
        self.evaluator = Evaluator(self._objective(), runs=runs, seed=random_seed, sim_config=sim_config,
                                   executor=executor, store=store)
        low = np.array([m.low for m in self._mutators], dtype=np.float32)
        high = np.array([m.high for m in self._mutators], dtype=np.float32)
        self.action_space = gym.spaces.Box(low, high, dtype=np.float32)
        n = len(self._mutators)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(n + 3,), dtype=np.float32)
        self._evaluations = 0
        self._steps = 0
        self._seed_fitness = 0.0
        self._best: Evaluation | None = None
        self._seed_evaluation: Evaluation | None = None
        self._last_action = np.zeros(n)

    # --- hooks ----------------------------------------------------------------------------------------------------
    def _objective(self):
        raise NotImplementedError

    def _terminated(self, evaluation: Evaluation) -> bool:
        return False

    # --- properties -----------------------------------------------------------------------------------------------
    @property
    def mutators(self):
        """The mutators, in the order of the action vector."""
        return self._mutators

    @property
    def seed_test(self) -> TestCase:
        return self._seed_test

    @property
    def budget(self) -> int:
        return self._budget

    @property
    def budget_left(self) -> int:
        return self._budget - self._evaluations

    @property
    def seed_evaluation(self) -> Evaluation | None:
        """The evaluation of the seed test (made by reset)."""
        return self._seed_evaluation

    @property
    def best(self) -> Evaluation | None:
        """The best evaluation of this episode."""
        return self._best

    def test_for(self, action) -> TestCase:
        """The test case an action stands for (raises InvalidTestCase if it is invalid)."""
        test = self._seed_test
        for mutator, value in zip(self._mutators, np.asarray(action, dtype=np.float64)):
            test = mutator.apply(test, float(value))
        return test

    # --- gymnasium API ----------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._evaluations = 0
        self._steps = 0
        self._last_action = np.zeros(len(self._mutators))
        evaluation = self._evaluate(self._seed_test)
        self._seed_fitness = evaluation.fitness if np.isfinite(evaluation.fitness) else -1.0
        self._seed_evaluation = evaluation
        self._best = evaluation
        return self._observation(evaluation.fitness), self._info(evaluation, None)

    def step(self, action):
        action = np.clip(np.asarray(action, dtype=np.float64).reshape(-1), self.action_space.low,
                         self.action_space.high)
        self._steps += 1
        self._last_action = action
        try:
            test = self.test_for(action)
        except InvalidTestCase as err:
            evaluation, invalid = None, str(err)
        else:
            evaluation, invalid = self._evaluate(test), None
            if evaluation.fitness > self._best.fitness:
                self._best = evaluation
        fitness = self._penalty() if evaluation is None or not np.isfinite(evaluation.fitness) else evaluation.fitness
        truncated = self.budget_left <= 0 or self._steps >= INVALID_STEPS_FACTOR * self._budget
        terminated = evaluation is not None and self._terminated(evaluation)
        return self._observation(fitness), float(fitness), terminated, truncated, self._info(evaluation, invalid)

    def close(self):
        self.evaluator.close()

    # --- internals ------------------------------------------------------------------------------------------------
    def _evaluate(self, test: TestCase) -> Evaluation:
        evaluation = self.evaluator.evaluate(test)
        if not evaluation.memo:
            self._evaluations += 1
        return evaluation

    def _penalty(self) -> float:
        return self._seed_fitness - max(1.0, abs(self._seed_fitness))

    def _observation(self, fitness: float) -> np.ndarray:
        span = np.maximum(self.action_space.high - self.action_space.low, 1e-9) / 2
        centre = (self.action_space.high + self.action_space.low) / 2
        scale = max(1.0, abs(self._seed_fitness))
        fitness = fitness if np.isfinite(fitness) else self._penalty()
        best = self._best.fitness if self._best is not None and np.isfinite(self._best.fitness) else fitness
        obs = np.concatenate([(self._last_action - centre) / span,
                              [fitness / scale, best / scale, self.budget_left / self._budget]])
        return obs.astype(np.float32)

    def _info(self, evaluation: Evaluation | None, invalid: str | None) -> dict:
        info = {"invalid": invalid, "evaluations": self._evaluations, "budget_left": self.budget_left,
                "simulations": self.evaluator.simulations,
                "best_fitness": None if self._best is None else self._best.fitness}
        if evaluation is None:
            info.update(fitness=self._penalty(), memo=False, statuses=(), min_distances=(), terms={})
            return info
        runs = evaluation.runs
        info.update(fitness=evaluation.fitness, memo=evaluation.memo, replayed=evaluation.replayed,
                    test=evaluation.test, statuses=evaluation.statuses,
                    min_distances=tuple(r.min_distance for r in runs),
                    min_distances_2d=tuple(r.min_distance_2d for r in runs), terms=evaluation.terms,
                    trajectory=evaluation.trajectory, sim_seconds=evaluation.sim_seconds)
        return info
