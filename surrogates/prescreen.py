"""Pre-screening: a wrapper around any agent that simulates only the candidates a surrogate finds promising.

:class:`Prescreened` asks the inner agent for candidates, scores each with the surrogate (mean and standard
deviation of the fitness on the model's scale) and applies an uncertainty-aware rule against the best real
fitness so far: expected improvement (``ei``, skip when EI < ``threshold`` x the spread of the training targets)
or probability of improvement (``pi``, skip when P(improvement) < ``threshold``). A skipped candidate is not
simulated and costs no budget: the inner agent is told a pessimistic fitness (the prediction minus ``pessimism``
standard deviations, never above the best) with ``info["skipped"] = True`` and ``info["memo"] = True`` (so
budget-aware agents do not count it), and it is logged in :attr:`Prescreened.skipped`. Promising candidates go
through ``env.step`` as usual, the most promising of one ``ask`` first (by predicted mean), each screened against
the best so far including the earlier results of the same ``ask`` (the inner agent is told the results in the
order it asked). In online mode (no model to start from) or with ``retrain_every`` set, the model is
retrained on its training data plus the real evaluations of the episode every ``retrain_every`` evaluations once
``min_points`` exist. ``max_skips`` consecutive skips force the next candidate to be simulated, so an agent that
never stops on its own (random search) still spends its budget.

Example:
    >>> import gymnasium as gym, surrealist_gym
    >>> from search import AdaptiveGreedy
    >>> env = gym.make("Surrealist-Generate-v0", budget=4, runs=1, executor="inline")
    >>> result = Prescreened(AdaptiveGreedy("paper", seed=0), "online", seed=0).run(env, seed=0)
    >>> result.evaluations <= 4
    True
"""
from __future__ import annotations

import itertools
import logging
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from search.base import Agent, SearchResult
from surrealist_gym.errors import InvalidTestCase, SurrealistError

from .dataset import Featurizer
from .models import SurrogateModel

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class PrescreenConfig:
    """How candidates are screened and the model retrained.

    Attributes:
        rule: ``ei`` (expected improvement) or ``pi`` (probability of improvement).
        threshold: EI below ``threshold`` x std of the training targets (``ei``), or P(improvement) below it
            (``pi``), skips a candidate.
        pessimism: a skipped candidate is told ``mean - pessimism x std`` (capped below the best).
        min_points: real evaluations needed before an online model is first trained.
        retrain_every: retrain after this many new real evaluations (0: never retrain a pre-trained model;
            an online model always retrains).
        max_skips: consecutive skips after which the next candidate is simulated anyway.
        kind: model kind of an online model (``ensemble`` or ``knn``).
        lowfi: an online model's features include a low-fidelity flight of each test (one ~0.1 s flight per
            candidate screened; see :mod:`surrogates.lowfi`).
    """

    rule: str = "ei"
    threshold: float = 0.01
    pessimism: float = 1.0
    min_points: int = 10
    retrain_every: int = 5
    max_skips: int = 20
    kind: str = "ensemble"
    lowfi: bool = True

    def __post_init__(self):
        if self.rule not in ("ei", "pi"):
            raise ValueError(f"prescreen rule: expected 'ei' or 'pi', got {self.rule!r}")


class Prescreened(Agent):
    """Wrap ``agent`` so that only candidates with a real chance of improving are simulated.

    Args:
        agent: the inner agent (any :class:`~search.base.Agent`).
        model: a trained :class:`~surrogates.models.SurrogateModel`, the path of a saved one, or ``"online"``.
        config: a :class:`PrescreenConfig`.
        seed: seed of the inner agent's search and of the model's training.
    """

    def __init__(self, agent: Agent, model: SurrogateModel | str | Path = "online",
                 config: PrescreenConfig | None = None, seed: int | None = None):
        super().__init__(seed if seed is not None else agent.seed)
        self.inner = agent
        self.name = f"{agent.name}+prescreen"
        self.config = config or PrescreenConfig()
        if isinstance(model, (str, Path)) and str(model) != "online":
            model = SurrogateModel.load(model)
        self._initial = None if isinstance(model, str) else model
        self.model: SurrogateModel | None = None
        self.skipped: list[dict] = []
        self.retrains = 0

    # --- the run: some candidates are answered without env.step ---------------------------------------------
    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Search on ``env`` until the inner agent stops or the budget is spent; the result counts real
        evaluations only (``history`` holds the fitness of each simulated or memo step)."""
        seed = seed if seed is not None else self.seed
        _, info = env.reset(seed=seed)
        self.setup(env, info)
        self.inner.setup(env, info)
        done = False
        while not done and not self.stop():
            self._candidates = candidates = self.inner.ask()
            self.ask()
            results: list[tuple | None] = [None] * len(candidates)
            real = []
            best = self.best[1]
            order, predictions = self._most_promising_first(candidates)
            for i in order:  # a better first result raises the bar for the rest
                if done:
                    break
                skip = self._screen(candidates[i], best, predictions[i])
                if skip is not None:
                    results[i] = (candidates[i], skip["told_fitness"], skip["info"])
                    continue
                reward, step_info, done = self._step(env, candidates[i], callback)
                results[i] = (candidates[i], reward, step_info)
                real.append(results[i])
                best = max(best, reward)
            told = list(itertools.takewhile(lambda r: r is not None, results))  # in the order asked
            self.tell([a for a, _, _ in real], [f for _, f, _ in real], [i for _, _, i in real])
            self.inner.tell([a for a, _, _ in told], [f for _, f, _ in told], [i for _, _, i in told])
        if not self._stop_reason:
            self._stop_reason = self.inner.stop().get("reason", "")
        return self.result

    def stop(self) -> dict:
        return super().stop() or self.inner.stop()

    # --- Agent hooks ---------------------------------------------------------------------------------------------
    def _setup(self, info: dict) -> None:
        self.skipped = []
        self.retrains = 0
        self._consecutive = 0
        self._featurizer = self._initial.featurizer if self._initial is not None else Featurizer.for_env(self._env, self.config.lowfi)
        self._X: list[np.ndarray] = []
        self._y: list[float] = []
        self._since_retrain = 0
        self.model = self._initial
        self._add_point(info)

    def _ask(self) -> list[np.ndarray]:  # the inner agent's candidates (run() tells back the simulated ones)
        return self._candidates

    def _tell(self, actions, fitnesses, infos) -> None:
        for info in infos:
            if not info.get("memo") and not info.get("invalid"):
                self._add_point(info)
        self._maybe_retrain()

    # --- screening -----------------------------------------------------------------------------------------------
    def _prediction(self, action) -> tuple | None:
        """(test, mean, std) on the model's scale, or None when the candidate is free (invalid or a memo hit)."""
        try:
            test = self._env.test_for(action)
        except InvalidTestCase:
            return None  # the env rejects it for free
        if test.key() in self._env._episode_keys:
            return None  # a memo hit costs nothing
        mean, std = self.model.predict(self._featurizer.transform([test]))
        return test, float(mean[0]), max(float(std[0]), 1e-9)

    def _most_promising_first(self, candidates) -> tuple[list[int], list]:
        """Candidate indices, free ones first, then by predicted fitness (the order asked without a model), and
        the predictions (``_prediction`` of each candidate; None without a model)."""
        if self.model is None:
            return list(range(len(candidates))), [None] * len(candidates)
        predictions = [self._prediction(a) for a in candidates]

        def priority(i):
            p = predictions[i]
            return -np.inf if p is None else (-p[1] if np.isfinite(p[1]) else np.inf)
        return sorted(range(len(candidates)), key=priority), predictions

    def _screen(self, action, best_fitness: float, prediction) -> dict | None:
        """None to simulate the candidate, else the log entry of a skip (with what the inner agent is told)."""
        if self.model is None or self._consecutive >= self.config.max_skips:
            self._consecutive = 0
            return None
        if prediction is None:
            return None
        test, mean, std = prediction
        best = float(self.model.to_scale(best_fitness))
        z = (mean - best) / std
        cdf = 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))
        if self.config.rule == "pi":
            score, limit = cdf, self.config.threshold
        else:
            pdf = math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)
            score = std * (z * cdf + pdf)
            limit = self.config.threshold * self._target_scale()
        if score >= limit:
            self._consecutive = 0
            return None
        self._consecutive += 1
        told = float(self.model.from_scale(min(mean - self.config.pessimism * std, best)))
        told = min(told, best_fitness - 1e-9 * max(1.0, abs(best_fitness)))
        env = self._env
        entry = {"action": np.asarray(action, dtype=np.float64).tolist(), "test_key": test.key(),
                 "obstacles": [o.to_list() for o in test.obstacles], "predicted_mean": mean, "predicted_std": std,
                 "score": score, "told_fitness": told, "after_evaluations": env.budget - env.budget_left}
        info = {"fitness": told, "memo": True, "skipped": True, "invalid": None, "test": test,
                "evaluations": env.budget - env.budget_left, "budget_left": env.budget_left,
                "simulations": env._simulations, "best_fitness": None if env.best is None else env.best.fitness,
                "predicted": (mean, std)}
        log.info("skipped candidate %s: predicted %.3f +/- %.3f, %s %.3g < %.3g", entry["action"], mean, std,
                 self.config.rule, score, limit)
        self.skipped.append(entry)
        return {"told_fitness": told, "info": info}

    def _target_scale(self) -> float:
        y = self.model.to_scale(self.model.train_y)
        return float(np.std(y)) or 1.0

    # --- online training -----------------------------------------------------------------------------------------
    def _add_point(self, info: dict) -> None:
        test, fitness = info.get("test"), info.get("fitness")
        if test is None or fitness is None or not np.isfinite(fitness):
            return
        self._X.append(self._featurizer.features(test.obstacles))
        self._y.append(float(fitness))
        self._since_retrain += 1

    def _maybe_retrain(self) -> None:
        cfg = self.config
        online = self._initial is None
        if not online and cfg.retrain_every <= 0:
            return
        if online and len(self._y) < cfg.min_points:
            return
        if self.model is not None and self._since_retrain < max(cfg.retrain_every, 1):
            return
        X, y = np.asarray(self._X), np.asarray(self._y)
        if self._initial is not None:
            X = np.concatenate([self._initial.train_X, X])
            y = np.concatenate([self._initial.train_y, y])
            kind, config = self._initial.kind, asdict(self._initial.regressor.config)
        else:
            kind, config = cfg.kind, None
        model = SurrogateModel(self._featurizer, kind, "fitness", config, seed=(self.seed or 0) + self.retrains)
        self.model = model.fit(X, y)
        self.retrains += 1
        self._since_retrain = 0
        log.info("surrogate retrained on %d evaluations", len(y))


def wrap(agent: Agent, spec: str | Path | None, env=None, config: PrescreenConfig | None = None) -> Agent:
    """The agent the command line runs for ``--surrogate SPEC``: ``agent`` itself when SPEC is empty, else
    ``Prescreened(agent, SPEC)`` (SPEC ``online`` or a model folder from ``surrealist surrogate train``).

    A pre-trained model must have been trained for the env's problem: its featurizer's mission path must match
    the env's seed test (checked when ``env`` is given).
    """
    if not spec:
        return agent
    wrapped = Prescreened(agent, spec if str(spec) == "online" else SurrogateModel.load(spec), config)
    if env is not None and wrapped._initial is not None:
        ours = Featurizer.for_env(env).path
        theirs = wrapped._initial.featurizer.path
        if ours.shape != theirs.shape or not np.allclose(ours, theirs, atol=0.5):
            raise SurrealistError(f"{spec}: the model was trained on another mission (path {theirs.round(1).tolist()}"
                                  f", this problem's is {ours.round(1).tolist()})")
    return wrapped
