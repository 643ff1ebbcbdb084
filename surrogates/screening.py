"""Screening rules: each answers ``verdict(test, incumbent, best_fitness) -> Skip | None`` for a candidate test
against the incumbent (the test with the best real fitness so far): a :class:`Skip` (what to tell the inner agent,
and why) or None to simulate it.

* :class:`LowFidelityShortfall` (``lowfi``): the candidate's low-fidelity fitness (:mod:`surrogates.lowfi`) falls
  short of the incumbent's by more than a margin calibrated on past searches (:mod:`surrogates.replay`).
* :class:`ModelImprovement` (``ei`` / ``pi``): the surrogate's expected improvement, or probability of improvement,
  is below a threshold.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass(frozen=True, slots=True)
class Skip:
    """A candidate not simulated: the fitness the inner agent is told, and why (logged in ``skipped.json``)."""

    told: float
    why: dict = field(default_factory=dict)


@dataclass(frozen=True)
class LowFidelityShortfall:
    """Skip when the low-fidelity fitness falls short of the incumbent's by more than ``margin``; the inner agent is
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


__all__ = ["LowFidelityShortfall", "ModelImprovement", "Skip"]
