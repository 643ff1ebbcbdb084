"""Screening: which candidates are skipped without a simulation.

A rule answers ``verdict(test, incumbent, best_fitness) -> Skip | None`` for a candidate test against the incumbent
(the test with the best real fitness so far): a :class:`Skip` (what to tell the agent, and why) or None to simulate
it.

* :class:`LowFidelityShortfall` (``lowfi``): the candidate's low-fidelity fitness (:mod:`surrogates.lowfi`) falls
  short of the incumbent's by more than a margin calibrated on past searches (:mod:`surrogates.replay`).
* :class:`ModelImprovement` (``ei`` / ``pi``): the surrogate's expected improvement, or probability of improvement,
  is below a threshold.

:func:`screening_rule` picks the rule in force for a model (``auto``: :func:`rule_in_force`); :class:`Screen`
applies it to a stream of candidates, forcing a simulation after ``max_skips`` skips in a row.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .config import ScreenConfig


@dataclass(frozen=True, slots=True)
class Skip:
    """A candidate not simulated (or dropped by racing after its first runs, ``flown``): the fitness the agent is
    told, and why (logged in ``skipped.json``)."""

    told: float
    why: dict = field(default_factory=dict)
    flown: Any = None  # racing: the evaluation of the runs flown (a surrealist_gym.evaluation.Evaluation)


@dataclass(frozen=True)
class LowFidelityShortfall:
    """Skip when the low-fidelity fitness falls short of the incumbent's by more than ``margin``; the agent is
    told the best real fitness minus that shortfall."""

    lowfi: object  # a surrogates.lowfi.LowFidelity
    margin: float
    name: str = "lowfi"

    def verdict(self, test, incumbent, best_fitness: float) -> Skip | None:
        """Skip when the candidate's low-fidelity fitness falls short of the incumbent's by more than ``margin``."""
        if incumbent is None:
            return None
        shortfall = float(self.lowfi.fitness(incumbent.obstacles) - self.lowfi.fitness(test.obstacles))
        if not shortfall > self.margin:
            return None
        return Skip(best_fitness - shortfall, {"lowfi_shortfall": shortfall, "margin": self.margin})


@dataclass(frozen=True)
class ModelImprovement:
    """Skip on the model's expected improvement (``ei``: below ``threshold`` x std of its training targets) or
    probability of improvement (``pi``: below ``threshold``); a skip is told ``mean - pessimism x std``."""

    model: object  # a surrogates.models.SurrogateModel
    predict: Callable  # test -> (mean, std) on the model's scale
    name: str = "ei"
    threshold: float = 0.01
    pessimism: float = 1.0

    def verdict(self, test, incumbent, best_fitness: float) -> Skip | None:
        """Skip when the model's expected (or probable) improvement over the best fitness is below ``threshold``."""
        mean, std = self.predict(test)
        best = float(self.model.to_scale(best_fitness))
        z = (mean - best) / std
        cdf = 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))
        if self.name == "pi":
            score, limit = cdf, self.threshold
        else:
            pdf = math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)
            score = std * (z * cdf + pdf)
            limit = self.threshold * (float(np.std(self.model.to_scale(self.model.train_y))) or 1.0)
        if score >= limit:
            return None
        told = float(self.model.from_scale(min(mean - self.pessimism * std, best)))
        return Skip(told, {"predicted_mean": mean, "predicted_std": std, "score": score, "limit": limit})


def rule_in_force(configured: str, margin: float | None) -> str:
    """The rule a configured one names: ``auto`` is ``lowfi`` once a low-fidelity margin is known, else ``ei``."""
    if configured != "auto":
        return configured
    return "lowfi" if margin is not None else "ei"


def screening_rule(config: ScreenConfig, margin: float | None, lowfi, model, predict: Callable):
    """The rule in force as a rule object: :class:`LowFidelityShortfall` with the low-fidelity simulator ``lowfi``
    and ``margin``, or :class:`ModelImprovement` with ``model`` (``predict``: test -> (mean, std) on its scale);
    None when there is nothing to skip on yet (no margin, no model) or the rule is ``none``."""
    rule = rule_in_force(config.rule, margin)
    if rule == "lowfi" and margin is not None:
        return LowFidelityShortfall(lowfi, margin)
    if rule in ("ei", "pi") and model is not None:
        return ModelImprovement(model, predict, rule, config.threshold, config.pessimism)
    return None


class Screen:
    """A stream of candidates screened by a rule: ``max_skips`` skips in a row force a simulation of the next."""

    def __init__(self, max_skips: int):
        self.max_skips = max_skips
        self.in_a_row = 0  # consecutive skips so far

    def verdict(self, rule, test, incumbent, best_fitness: float) -> Skip | None:
        """The rule's verdict on a candidate (None: simulate it); a free candidate (``test`` None: invalid or a memo
        hit) or one after ``max_skips`` skips in a row is not screened, and ends the row."""
        if test is None or self.in_a_row >= self.max_skips:
            self.in_a_row = 0
            return None
        skip = None if rule is None else rule.verdict(test, incumbent, best_fitness)
        self.in_a_row = 0 if skip is None else self.in_a_row + 1
        return skip


__all__ = ["LowFidelityShortfall", "ModelImprovement", "Screen", "Skip", "rule_in_force", "screening_rule"]
