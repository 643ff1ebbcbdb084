"""Online training: the model in force, retrained on the search's own real evaluations as they arrive.

A pre-trained model retrains on its own training data plus the search's evaluations (as one more search of its
stores) every ``retrain_every`` new ones (0: never); without one, a model is first trained once ``min_points``
evaluations arrived, then retrained as often (:class:`~surrogates.config.OnlineConfig`).
"""
from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .config import OnlineConfig
from .dataset import Featurizer, stack_rows
from .models import SurrogateModel


class OnlineTraining:
    """The model in force and the real evaluations it learns from.

    Args:
        initial: a pre-trained model, or None (online: a model of ``config.kind`` is trained from scratch).
        featurizer: how a test becomes features (the pre-trained model's own).
        config: when to (re)train.
        evaluator: the env's evaluator: the fitness of an evaluation's first runs, its runs, its noise mode.
        first_runs: keep the fitness of each evaluation's first 1..n-1 runs (racing calibrates on them).
        seed: a (re)training's seed is ``seed`` plus the retrains before it.
    """

    def __init__(self, initial: SurrogateModel | None, featurizer: Featurizer, config: OnlineConfig, evaluator,
                 first_runs: bool, seed: int | None = None):
        self.initial = initial
        self.model = initial
        self.featurizer = featurizer
        self.config = config
        self.retrains = 0
        self._evaluator = evaluator
        self._first_runs = first_runs
        self._seed = seed or 0
        self._X: list[np.ndarray] = []
        self._y: list[float] = []
        self._first: list[list[float]] = []
        self._new = 0  # evaluations added since the last (re)training

    def add(self, info: dict) -> None:
        """Learn from a real evaluation (its env ``info``: test and fitness); one without a finite fitness is
        ignored."""
        test, fitness = info.get("test"), info.get("fitness")
        if test is None or fitness is None or not np.isfinite(fitness):
            return
        self._X.append(self.featurizer.features(test.obstacles))
        self._y.append(float(fitness))
        evaluator = self._evaluator
        self._first.append([evaluator.evaluate(test, runs=k).fitness for k in range(1, evaluator.runs)]
                           if self._first_runs else [])
        self._new += 1

    @property
    def due(self) -> bool:
        """Whether to (re)train now: enough new evaluations for the config (never for a pre-trained model with
        ``retrain_every`` 0)."""
        cfg = self.config
        if self.initial is not None and cfg.retrain_every <= 0:
            return False
        if self.initial is None and len(self._y) < cfg.min_points:
            return False
        return self.model is None or self._new >= max(cfg.retrain_every, 1)

    def retrain(self) -> SurrogateModel:
        """Train a new model in force on the evaluations so far (after the pre-trained model's own data); it keeps
        the noise mode of the search."""
        X, y = np.asarray(self._X), np.asarray(self._y)
        first = stack_rows(self._first)
        groups = np.zeros(len(y), dtype=np.int64)  # the episode is one search
        initial = self.initial
        if initial is not None:
            X = np.concatenate([initial.train_X, X])
            y = np.concatenate([initial.train_y, y])
            first = stack_rows([*initial.train_first_runs, *first])
            groups = np.concatenate([initial.train_groups, groups + int(initial.train_groups.max()) + 1])
            kind, config = initial.kind, asdict(initial.regressor.config)
        else:
            kind, config = self.config.kind, None
        model = SurrogateModel(self.featurizer, kind, "fitness", config, seed=self._seed + self.retrains)
        self.model = model.fit(X, y, groups, first)
        model.common_noise = self._evaluator.sim_config.common_noise
        self.retrains += 1
        self._new = 0
        return self.model


__all__ = ["OnlineTraining"]
