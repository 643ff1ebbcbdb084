"""Margins calibrated by replaying past searches: how far a cheap proxy of the fitness (the low-fidelity fitness, or
the fitness of a test's first runs) fell short of the incumbent's on the real improvements that past searches made.

A screen that skips candidates whose proxy falls short by more than the margin would have missed only ``miss_rate``
of those improvements.
"""
from __future__ import annotations

import numpy as np

from .lowfi import FITNESS as LOWFI_FITNESS
from .models import SurrogateModel

MIN_IMPROVEMENTS = 10  # improvements needed in the training data to calibrate a margin


def replayed_improvements(values, fitness, groups, known=None):
    """Past searches replayed (rows of one group, in the order evaluated, those with ``known`` True): for every real
    improvement (a fitness above the best so far), its incumbent's value and its own (rows of ``values``)."""
    values, fitness, groups = np.asarray(values), np.asarray(fitness), np.asarray(groups)
    for group in np.unique(groups):
        rows = groups == group if known is None else (groups == group) & known
        best, incumbent = -np.inf, None
        for value, real in zip(values[rows], fitness[rows]):
            if real > best:
                if incumbent is not None:
                    yield incumbent, value
                best, incumbent = real, value


def improvement_shortfalls(proxy, fitness, groups, against_fitness: bool = False) -> list[float]:
    """For every real improvement of past searches (:func:`replayed_improvements`), the incumbent's proxy minus its
    own, or (``against_fitness``) the incumbent's real fitness minus the improvement's proxy. Rows whose proxy is
    unknown (NaN) are skipped."""
    proxy, fitness = np.asarray(proxy), np.asarray(fitness)
    known = np.isfinite(proxy)
    if against_fitness:
        pairs = replayed_improvements(np.stack([fitness, proxy], axis=1), fitness, groups, known)
        return [float(theirs[0] - ours[1]) for theirs, ours in pairs]
    return [float(theirs - ours) for theirs, ours in replayed_improvements(proxy, fitness, groups, known)]


def replay_margin(proxy, fitness, groups, miss_rate: float = 0.02, against_fitness: bool = False) -> float | None:
    """The shortfall in a cheap proxy of the fitness that only ``miss_rate`` of the real improvements of past
    searches exceeded (:func:`improvement_shortfalls`; ``against_fitness``: measured from the incumbent's real
    fitness). None with fewer than ``MIN_IMPROVEMENTS`` improvements."""
    shortfalls = improvement_shortfalls(proxy, fitness, groups, against_fitness)
    if len(shortfalls) < MIN_IMPROVEMENTS:
        return None
    return float(np.quantile(shortfalls, 1.0 - miss_rate))


def model_margin(model: SurrogateModel, miss_rate: float = 0.02) -> float | None:
    """:func:`replay_margin` of the low-fidelity fitness on a model's training data; None for a model without
    low-fidelity features."""
    names = model.featurizer.names
    if LOWFI_FITNESS not in names:
        return None
    return replay_margin(model.train_X[:, names.index(LOWFI_FITNESS)], model.train_y, model.train_groups, miss_rate)


__all__ = ["MIN_IMPROVEMENTS", "improvement_shortfalls", "model_margin", "replay_margin", "replayed_improvements"]
