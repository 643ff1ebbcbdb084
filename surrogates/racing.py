"""Racing: a candidate flies its runs in stages and is dropped at the first stage whose runs fall behind the
incumbent's same first runs by more than a margin, or (with common random numbers) score exactly as they did.

:class:`Racing` is the env with partial evaluations: ``race(action, k)`` flies a test's first k runs, charged to the
budget as k/n of an evaluation, and ``step`` on it later flies and charges only the rest. The margins per stage are
calibrated like the screening margin (:mod:`surrogates.replay`), on the fitness of the first k runs of the stored
evaluations a model learnt from.
"""
from __future__ import annotations

import numpy as np

from surrealist_gym.envs.wrapper import SurrealistWrapper
from surrealist_gym.evaluation import Evaluation

from .models import SurrogateModel
from .replay import replay_margin, replayed_improvements

TIE_TOLERANCE = 1e-9  # relative: first runs whose fitness differs by less score as a tie (identical flights)


def is_tie(incumbent: float, candidate: float) -> bool:
    """Whether two first-runs fitness values are equal (finite, within :data:`TIE_TOLERANCE`)."""
    return abs(incumbent - candidate) <= TIE_TOLERANCE * max(1.0, abs(candidate))


def race_verdict(incumbent: float, candidate: float, margin: float | None, drop_ties: bool) -> str | None:
    """Racing's rule on the fitness of the same first runs: ``"tie"`` (scored exactly as the incumbent's, with
    ``drop_ties``), ``"behind"`` (short of it by more than ``margin``) or None (fly on)."""
    if drop_ties and is_tie(incumbent, candidate):
        return "tie"
    return "behind" if margin is not None and incumbent - candidate > margin else None


def tie_improvements(first_runs, fitness, groups) -> int:
    """How many real improvements of past searches scored exactly as their incumbent on their first k runs at some
    stage (``first_runs``: (rows, k) fitness of the first 1..k runs, NaN where unknown); racing with ``drop_ties``
    would have dropped them."""
    first_runs = np.asarray(first_runs, dtype=np.float64).reshape(len(fitness), -1)
    return sum(any(np.isfinite(a) and np.isfinite(b) and is_tie(a, b) for a, b in zip(theirs, ours))
               for theirs, ours in replayed_improvements(first_runs, fitness, groups))


def race_margin(model: SurrogateModel, first_runs: int, miss_rate: float = 0.02) -> float | None:
    """:func:`~surrogates.replay.replay_margin` of the fitness of the first ``first_runs`` runs on a model's
    training data; None when its stores hold no such fitness."""
    first = model.train_first_runs
    if first is None or first.shape[1] < first_runs:
        return None
    return replay_margin(first[:, first_runs - 1], model.train_y, model.train_groups, miss_rate)


class Racing(SurrealistWrapper):
    """A Surrealist env whose tests can be evaluated on their first runs alone (:meth:`race`)."""

    def __init__(self, env):
        super().__init__(env)
        self._raced: dict[str, int] = {}  # runs flown by race() of tests not stepped on, by test key

    @property
    def budget_left(self) -> int:
        """The env's budget left, less the raced runs (in whole evaluations)."""
        return self.inner.budget_left - sum(self._raced.values()) // self.inner.evaluator.runs

    @property
    def simulations(self) -> int:
        """Runs simulated in this episode, the raced ones included."""
        return self.inner.simulations + sum(self._raced.values())

    def race(self, action, runs: int) -> Evaluation:
        """The evaluation of the action's test on its first ``runs`` runs alone (flying those not flown yet; a test
        evaluated in the episode is answered from its runs). Raises InvalidTestCase for an invalid action."""
        test = self.inner.test_for(action)
        evaluation = self.inner.evaluator.evaluate(test, runs=runs)
        if not self.inner.evaluated(test):
            self._raced[test.key()] = max(self._raced.get(test.key(), 0), len(evaluation.runs))
        return evaluation

    def reset(self, **kwargs):
        """Reset the env and forget the tests raced so far."""
        self._raced = {}
        return self.env.reset(**kwargs)

    def step(self, action):
        """Step the env; ``info`` carries the racing budget left, and the episode is truncated once it is spent."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        test = info.get("test")
        if test is not None and not info.get("memo"):
            self._raced.pop(test.key(), None)  # the env charged the whole evaluation
        info.update(budget_left=self.budget_left, simulations=self.simulations)
        return obs, reward, terminated, truncated or self.budget_left <= 0, info


__all__ = ["TIE_TOLERANCE", "Racing", "is_tie", "race_margin", "race_verdict", "tie_improvements"]
