"""Racing: a candidate flies its runs in stages and is dropped at the first stage whose runs fall behind the
incumbent by more than a margin, or (with common random numbers) score exactly as the incumbent's same runs did.

Behind what? Under common random numbers (``against="paired"``), the incumbent's same first runs: run i of both met
the same noise, so the comparison is paired. Under each test's own noise (``against="fitness"``), the incumbent's
fitness over all its runs: its first runs met other noise than the candidate's, and the question the greedy asks is
whether the candidate's fitness over all its runs will beat that figure, which is known exactly.

:class:`Racing` is the env with partial evaluations: ``race(action, k)`` flies a test's first k runs, charged to the
budget as k/n of an evaluation, and ``step`` on it later flies and charges only the rest. :class:`Race` is the rule
for the model in force: its margin per stage, calibrated like the screening margin (:mod:`surrogates.replay`) on the
fitness of the first k runs of the stored evaluations a model learnt from, and whether ties drop.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrealist_gym.envs.wrapper import SurrealistWrapper
from surrealist_gym.evaluation import Evaluation

from .config import RaceConfig
from .models import SurrogateModel
from .replay import replay_margin, replayed_improvements
from .screening import Skip

TIE_TOLERANCE = 1e-9  # relative: first runs whose fitness differs by less score as a tie (identical flights)


def is_tie(incumbent: float, candidate: float) -> bool:
    """Whether two first-runs fitness values are equal (finite, within :data:`TIE_TOLERANCE`)."""
    return abs(incumbent - candidate) <= TIE_TOLERANCE * max(1.0, abs(candidate))


def race_verdict(incumbent: float, candidate: float, margin: float | None, drop_ties: bool) -> str | None:
    """Racing's rule on the fitness of the candidate's first runs against the incumbent's (its same first runs, or
    its fitness): ``"tie"`` (scored exactly as the incumbent's, with ``drop_ties``), ``"behind"`` (short of it by
    more than ``margin``) or None (fly on)."""
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


AGAINST = ("paired", "fitness")  # what a candidate's first runs race against: the incumbent's same runs, its fitness


def race_margin(model: SurrogateModel, first_runs: int, miss_rate: float = 0.02,
                against: str = "paired") -> float | None:
    """:func:`~surrogates.replay.replay_margin` of the fitness of the first ``first_runs`` runs on a model's
    training data, from the incumbent's same first runs (``paired``) or its fitness over all runs (``fitness``);
    None when its stores hold no such fitness."""
    first = model.train_first_runs
    if first is None or first.shape[1] < first_runs:
        return None
    return replay_margin(first[:, first_runs - 1], model.train_y, model.train_groups, miss_rate,
                         against_fitness=against == "fitness")


@dataclass(frozen=True, slots=True)
class Race:
    """Racing's rule for the model in force: the margin per stage, as (run count, margin) pairs in increasing run
    counts (a margin None: not calibrated), whether a tie drops a candidate, and what the first runs race against
    (``paired``: the incumbent's same first runs; ``fitness``: its fitness over all runs). No stages: racing is
    off."""

    margins: tuple[tuple[int, float | None], ...] = ()
    drop_ties: bool = False
    against: str = "paired"

    @classmethod
    def calibrated(cls, config: RaceConfig, model: SurrogateModel | None, miss_rate: float,
                   common_noise: bool) -> "Race":
        """The configured margin at every stage, else one per stage calibrated on the model's training data at an
        equal share of ``miss_rate``; ties drop as configured, else (None) under common noise unless a tie improved
        in the model's training stores. The first runs race against what is configured, else (None) the
        incumbent's same runs under common noise and its fitness under each test's own."""
        stages = config.stages
        against = config.against or ("paired" if common_noise else "fitness")
        if config.margin is not None:
            margins = tuple((k, float(config.margin)) for k in stages)
        else:
            share = miss_rate / max(len(stages), 1)
            margins = tuple((k, None if model is None else race_margin(model, k, share, against)) for k in stages)
        drop_ties = config.drop_ties
        if drop_ties is None:
            drop_ties = bool(common_noise) and (model is None or not tie_improvements(
                model.train_first_runs, model.train_y, model.train_groups))
        return cls(margins, drop_ties, against)

    def verdict(self, env: "Racing", action, incumbent, best_fitness: float) -> Skip | None:
        """Fly the candidate's first runs stage by stage (``env.race``) against the same first runs of the incumbent
        test (``paired``) or its fitness ``best_fitness`` (``fitness``): a :class:`~surrogates.screening.Skip` told
        the best minus its shortfall at the first stage it falls behind (or ties), or None to fly the rest. None at
        once without an incumbent or a margin to race on."""
        for k, margin in self.margins:
            if incumbent is None or (margin is None and not self.drop_ties):
                return None
            theirs = (best_fitness if self.against == "fitness"
                      else env.evaluator.evaluate(incumbent, runs=k).fitness)
            flown = env.race(action, k)
            verdict = race_verdict(theirs, flown.fitness, margin, self.drop_ties)
            if verdict:
                shortfall = float(theirs - flown.fitness)
                why = {"first_runs": k, "first_runs_fitness": float(flown.fitness), "race_shortfall": shortfall,
                       "race_margin": margin, "tie": verdict == "tie", "race_against": self.against}
                return Skip(best_fitness - shortfall, why, flown)
        return None


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


__all__ = ["AGAINST", "TIE_TOLERANCE", "Race", "Racing", "is_tie", "race_margin", "race_verdict", "tie_improvements"]
