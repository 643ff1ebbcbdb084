"""Pre-screening: a wrapper around any agent that simulates only the candidates worth a simulation
(docs/surrogates.md).

:class:`Prescreened` asks the inner agent for candidates, most promising first, and screens each against the
incumbent (the test with the best real fitness so far) by one rule of :mod:`surrogates.screening` (``lowfi``,
``ei``, ``pi``; ``none`` skips nothing; ``auto`` is ``lowfi`` once a margin is known, else ``ei``), set by a
:class:`PrescreenConfig`.

A skipped candidate is not simulated: the inner agent is told an estimate below the best (``info["skipped"]``).
A candidate that passes may be raced (:mod:`surrogates.racing`): its first runs fly first, the rest only if they
keep up with the incumbent's. An online model (or ``retrain_every``) retrains on the episode's real evaluations;
``max_skips`` consecutive skips force a simulation; ``verify_stop`` restarts the inner agent, unscreened, from the
best test when it stops with budget left. The search is the base agent's ``run`` (on the env wrapped in
:class:`~surrogates.racing.Racing` when racing): a batch of the inner agent's candidates is stepped most promising
first, and the inner agent is told the results in the order it asked.

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
import warnings
from dataclasses import asdict
from pathlib import Path

import numpy as np

from search.base import Agent, SearchResult
from surrealist_gym.envs.wrapper import SurrealistWrapper
from surrealist_gym.errors import InvalidTestCase, SurrealistError
from surrealist_gym.evaluation import describe_noise

from .config import PrescreenConfig, SkipAccounting
from .dataset import Featurizer, stack_rows
from .models import SurrogateModel
from .racing import Racing, race_margin, race_verdict, tie_improvements
from .replay import model_margin
from .screening import LowFidelityShortfall, ModelImprovement, Skip

log = logging.getLogger(__name__)

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
        self.margin: float | None = None
        self.race_margins: dict[int, float | None] = {}  # racing's margin per stage (run count)
        self.skipped: list[dict] = []
        self.retrains = 0
        self.verified_at: int | None = None  # real evaluations when the unscreened verify pass began

    @property
    def dropped(self) -> int:
        """Candidates dropped by racing after their first runs (the rest of :attr:`skipped` were never flown)."""
        return sum(s["rule"] == "race" for s in self.skipped)

    @property
    def inner_budget_left(self) -> int:
        """The budget left with every skipped or dropped candidate spent as a whole evaluation (what the inner
        agent sees with ``SkipAccounting.BUDGET``): the env's budget less its real evaluations and the skips."""
        return self._env.budget - self._env.evaluations - len(self.skipped)

    @property
    def unspent(self) -> int:
        """Budget the skipped and dropped candidates did not spend (raced runs are charged in whole evaluations)."""
        return self._env.budget_left - self.inner_budget_left

    @property
    def race_margin(self) -> float | None:
        """Racing's margin at its first stage (None: racing off or not calibrated yet)."""
        return next(iter(self.race_margins.values()), None)

    @property
    def rule(self) -> str:
        """The rule in force: ``auto`` resolves to ``lowfi`` once a margin is known, else ``ei``."""
        if self.config.screen.rule != "auto":
            return self.config.screen.rule
        return "lowfi" if self.margin is not None else "ei"

    # --- the base run, on the env raced --------------------------------------------------------------------------
    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Search on ``env`` (wrapped in :class:`~surrogates.racing.Racing` when racing) until the inner agent
        stops or the budget is spent; the result counts real evaluations only (``history`` holds the fitness of
        each simulated or memo step)."""
        return super().run(Racing(env) if self.config.race.stages else env, seed, callback)

    def stop(self) -> dict:
        """The env's stop, else the inner agent's (or, with ``SkipAccounting.BUDGET``, its budget spent with the
        skips); with ``verify_stop`` the first inner stop with budget left restarts the inner agent instead, with
        screening and racing off."""
        own = super().stop()
        if own:
            return own
        reason = self._inner_stop()
        if reason and self._verify_stop():
            reason = self._inner_stop()
        if reason:
            self._stop_reason = reason["reason"]
        return reason

    def tell(self, actions, fitnesses, infos) -> None:
        """The batch's results (recorded by ``_step``): the real ones to this agent, in the order simulated, and all
        of them to the inner agent, in the order it asked (up to the first candidate not reached)."""
        stepped = [self._results[i] for i in self._order if self._results[i] is not None]
        real = [(a, f, i) for a, f, i, simulated in stepped if simulated]
        super().tell([a for a, _, _ in real], [f for _, f, _ in real], [i for _, _, i in real])
        told = list(itertools.takewhile(lambda r: r is not None, self._results))
        self.inner.tell([a for a, _, _, _ in told], [f for _, f, _, _ in told], [i for _, _, i, _ in told])

    def _inner_stop(self) -> dict:
        if self._inner_budget_spent:
            return {"reason": "budget spent (skipped and dropped candidates counted as evaluations)"}
        return self.inner.stop()

    @property
    def _inner_budget_spent(self) -> bool:
        """With ``SkipAccounting.BUDGET``, before the verify pass: the inner agent's budget (skips counted) is spent,
        where the env would have ended the search without screening."""
        return (self.config.skips is SkipAccounting.BUDGET and self.verified_at is None
                and self.inner_budget_left <= 0)

    def _verify_stop(self) -> bool:
        """Begin the verify pass (see ``PrescreenConfig.verify_stop``) if due; True when the inner agent goes on."""
        if not self.config.verify_stop or self.verified_at is not None or self._env.budget_left <= 0:
            return False
        self.verified_at = self._evaluations
        self.inner.setup(self._env, self._reset_info, start=self.best)  # the env's own budget: what screening saved
        return not self.inner.stop()

    def _ask(self) -> list[np.ndarray]:
        """The inner agent's candidates, free ones first, then the most promising (by the model)."""
        candidates = self.inner.ask()
        self._predictions: dict[str, tuple[float, float]] = {}
        if self.verified_at is None:
            self._tests = [self._test(a) for a in candidates]
            self._order = self._most_promising_first()
        else:  # the verify pass simulates every candidate: no tests to screen, nothing to predict
            self._tests, self._order = [None] * len(candidates), list(range(len(candidates)))
        self._next = iter(self._order)
        self._results: list[tuple | None] = [None] * len(candidates)
        _, best, incumbent = self.best
        self._bar = (best, incumbent)  # a better result in this batch raises the bar for the rest
        return [candidates[i] for i in self._order]

    def _step(self, env, action, callback=None) -> tuple[float, dict, bool]:
        """The next candidate: told again what it was told before, skipped, dropped by racing, or stepped on. The
        batch is over when the episode is, or (``SkipAccounting.BUDGET``) the inner agent's budget is spent."""
        i = next(self._next)
        test, (best, incumbent) = self._tests[i], self._bar
        if test is not None and self._env.evaluated(test):
            test = None  # the same test earlier in this ask was simulated: now a free memo answer
        again = None if test is None else self._told.get(test.key())
        if again is not None:  # skipped before: told the same again, free, as the env's memo would
            self._results[i] = (action, again[0], {**again[1], "memo": True}, False)
            return again[0], self._results[i][2], self._inner_budget_spent
        told = info = None
        skip = self._screen(test, best, incumbent.get("test"))
        if skip is not None:
            told, info = self._skip(action, test, self.rule, skip, best, self._predictions.get(test.key()))
        elif test is not None:
            told, info = self._race(action, test, best, incumbent) or (None, None)
        if info is not None:
            self._results[i] = (action, told, info, False)
            self._told[test.key()] = (told, info)
            if self._env.budget_left <= 0:
                self._stop_reason = self._stop_reason or "budget spent"
            return told, info, self._env.budget_left <= 0 or self._inner_budget_spent
        reward, info, done = super()._step(env, action, callback)
        self._results[i] = (action, reward, info, True)
        if reward > best:
            self._bar = (reward, info)
        return reward, info, done or self._inner_budget_spent

    # --- Agent hooks ---------------------------------------------------------------------------------------------
    def _setup(self, info: dict) -> None:
        self._check_noise_mode()
        self.skipped = []
        self._told: dict[str, tuple[float, dict]] = {}  # what each skipped or dropped test was told, by key
        self.retrains = 0
        self.verified_at = None
        self._consecutive = 0
        self._reset_info = info
        self._featurizer = (self._initial.featurizer if self._initial is not None
                            else Featurizer.for_env(self._env, self.config.online.lowfi))
        if self.config.screen.rule == "lowfi" and self._featurizer.lowfi is None:
            raise SurrealistError("prescreen rule lowfi: the model has no low-fidelity features (train it with "
                                  "--lowfi)")
        self._X: list[np.ndarray] = []
        self._y: list[float] = []
        self._since_retrain = 0
        self.model = self._initial
        self._first: list[list[float]] = []
        self._calibrate()
        self._add_point(info)
        spends = self.config.skips is SkipAccounting.BUDGET
        self.inner.setup(_SpentBySkips(self._env, self) if spends else self._env, info)

    def _check_noise_mode(self) -> None:
        """Warn when the model learnt from evaluations flown in the other noise mode: its racing margins were
        calibrated on first runs whose noise the incumbent's did (common noise) or did not (each test's own) share."""
        trained = None if self._initial is None else self._initial.common_noise
        flies = self._env.evaluator.sim_config.common_noise
        if trained is not None and bool(trained) != flies:
            name = self._initial.path or "the surrogate model"
            warnings.warn(f"{name}: trained on evaluations flown with {describe_noise(trained)}, this search flies "
                          f"{describe_noise(flies)}; its racing margins were calibrated in the other mode (train it "
                          f"on stores flown the same way, or match --common-noise)", UserWarning, stacklevel=2)

    def _tell(self, actions, fitnesses, infos) -> None:
        for info in infos:
            if not info.get("memo") and not info.get("invalid"):
                self._add_point(info)
        if self.verified_at is None:  # the verify pass no longer consults the model
            self._maybe_retrain()

    # --- screening -----------------------------------------------------------------------------------------------
    def _test(self, action):
        """The candidate's test, or None when it is free (invalid or a memo hit)."""
        try:
            test = self._env.test_for(action)
        except InvalidTestCase:
            return None  # the env rejects it for free
        return None if self._env.evaluated(test) else test  # a memo hit costs nothing

    def _most_promising_first(self) -> list[int]:
        """Candidate indices, free ones first, then by predicted fitness (the order asked without a model)."""
        if self.model is None:
            return list(range(len(self._tests)))

        def priority(i):
            if self._tests[i] is None:
                return -np.inf
            mean = self._predict(self._tests[i])[0]
            return -mean if np.isfinite(mean) else np.inf
        return sorted(range(len(self._tests)), key=priority)

    def _predict(self, test) -> tuple[float, float]:
        """The model's (mean, std) for a test, on its scale (once per test in a batch)."""
        key = test.key()
        if key not in self._predictions:
            mean, std = self.model.predict(self._featurizer.transform([test]))
            self._predictions[key] = (float(mean[0]), max(float(std[0]), 1e-9))
        return self._predictions[key]

    def _screen(self, test, best_fitness: float, incumbent) -> Skip | None:
        """The screening rule's verdict on a candidate (None: simulate it); ``max_skips`` in a row force one."""
        if test is None or self._consecutive >= self.config.screen.max_skips:
            self._consecutive = 0
            return None
        skip = None if self._rule is None else self._rule.verdict(test, incumbent, best_fitness)
        self._consecutive = 0 if skip is None else self._consecutive + 1
        return skip

    def _screening_rule(self):
        """The rule in force as a :mod:`surrogates.screening` rule (None: nothing to skip on yet)."""
        cfg, rule = self.config.screen, self.rule
        if rule == "lowfi" and self.margin is not None:
            return LowFidelityShortfall(self._featurizer.lowfi, self.margin)
        if rule in ("ei", "pi") and self.model is not None:
            return ModelImprovement(self.model, self._predict, rule, cfg.threshold, cfg.pessimism)
        return None

    def _skip(self, action, test, rule: str, skip: Skip, best_fitness: float, prediction=None,
              flown=None) -> tuple[float, dict]:
        """Log a skipped candidate; returns the fitness and info the inner agent is told (a fitness below the best,
        and the trajectory and statuses of the runs flown, if any: the greedy's plateau test compares it with the
        incumbent's over the same first runs)."""
        told = min(skip.told, best_fitness - 1e-9 * max(1.0, abs(best_fitness)))
        env = self._env
        entry = dict(skip.why)
        entry.update({"action": np.asarray(action, dtype=np.float64).tolist(), "test_key": test.key(),
                      "obstacles": [o.to_list() for o in test.obstacles], "rule": rule, "told_fitness": told,
                      "after_evaluations": env.budget - env.budget_left, "simulations": env.simulations})
        info = {"fitness": told, "memo": self.config.skips is SkipAccounting.MEMO, "skipped": True, "invalid": None,
                "test": test,
                "evaluations": env.budget - env.budget_left, "budget_left": env.budget_left,
                "simulations": env.simulations, "best_fitness": None if env.best is None else env.best.fitness,
                "predicted": prediction}
        if flown is not None:
            info.update(trajectory=flown.trajectory, statuses=flown.statuses)
        log.info("skipped candidate %s (%s): %s", entry["action"], rule,
                 {k: round(v, 3) for k, v in entry.items() if isinstance(v, float)})
        self.skipped.append(entry)
        return told, info

    def _race(self, action, test, best_fitness: float, incumbent: dict) -> tuple[float, dict] | None:
        """Racing: fly the candidate's first runs, stage by stage; None to fly the rest (the candidate is stepped
        on), else what the inner agent is told of a candidate dropped at a stage because its runs so far fall short
        of the incumbent's same first runs by more than that stage's margin (the best minus that shortfall), or,
        with ``drop_ties``, score exactly as the incumbent's (just below the best)."""
        for k, margin in self.race_margins.items():
            if incumbent.get("test") is None or (margin is None and not self._drop_ties):
                return None
            theirs = self._env.evaluator.evaluate(incumbent["test"], runs=k).fitness
            flown = self._env.race(action, k)
            verdict = race_verdict(theirs, flown.fitness, margin, self._drop_ties)
            if verdict:
                shortfall = float(theirs - flown.fitness)
                entry = {"first_runs": k, "first_runs_fitness": float(flown.fitness), "race_shortfall": shortfall,
                         "race_margin": margin, "tie": verdict == "tie"}
                return self._skip(action, test, "race", Skip(best_fitness - shortfall, entry), best_fitness,
                                  flown=flown)
        return None

    def _calibrate(self) -> None:
        """Margins, the tie rule and the screening rule, for the model in force."""
        self.margin = self._calibrated_margin()
        self.race_margins = self._calibrated_race_margins()
        self._drop_ties = self._tie_rule()
        self._rule = self._screening_rule()

    def _calibrated_margin(self) -> float | None:
        """The ``lowfi`` margin: the configured one, else calibrated on the model's training data."""
        if self._featurizer.lowfi is None:
            return None  # no low-fidelity flights to compare
        if self.config.screen.margin is not None:
            return float(self.config.screen.margin)
        return None if self.model is None else model_margin(self.model, self.config.miss_rate)

    def _calibrated_race_margins(self) -> dict[int, float | None]:
        """Racing's margin per stage: the configured one, else calibrated on the model's training data at an equal
        share of the miss rate."""
        stages = self.config.race.stages
        if stages and stages[-1] >= self._env.evaluator.runs:
            raise SurrealistError(f"prescreen first_runs: {stages[-1]} must be below the env's runs "
                                  f"({self._env.evaluator.runs})")
        if self.config.race.margin is not None:
            return {k: float(self.config.race.margin) for k in stages}
        share = self.config.miss_rate / max(len(stages), 1)
        return {k: None if self.model is None else race_margin(self.model, k, share) for k in stages}

    def _tie_rule(self) -> bool:
        """Whether racing drops ties (``PrescreenConfig.drop_ties``; None: under common noise, unless a tie improved
        in the model's training stores)."""
        if self.config.race.drop_ties is not None:
            return self.config.race.drop_ties
        if not self._env.evaluator.sim_config.common_noise:
            return False
        model = self.model
        return model is None or not tie_improvements(model.train_first_runs, model.train_y, model.train_groups)

    # --- online training -----------------------------------------------------------------------------------------
    def _add_point(self, info: dict) -> None:
        test, fitness = info.get("test"), info.get("fitness")
        if test is None or fitness is None or not np.isfinite(fitness):
            return
        self._X.append(self._featurizer.features(test.obstacles))
        self._y.append(float(fitness))
        evaluator = self._env.evaluator
        self._first.append([evaluator.evaluate(test, runs=k).fitness for k in range(1, evaluator.runs)]
                           if self.config.race.stages else [])
        self._since_retrain += 1

    def _maybe_retrain(self) -> None:
        cfg = self.config.online
        online = self._initial is None
        if not online and cfg.retrain_every <= 0:
            return
        if online and len(self._y) < cfg.min_points:
            return
        if self.model is not None and self._since_retrain < max(cfg.retrain_every, 1):
            return
        X, y = np.asarray(self._X), np.asarray(self._y)
        first = stack_rows(self._first)
        groups = np.zeros(len(y), dtype=np.int64)  # the episode is one search
        if self._initial is not None:
            X = np.concatenate([self._initial.train_X, X])
            y = np.concatenate([self._initial.train_y, y])
            first = stack_rows([*self._initial.train_first_runs, *first])
            groups = np.concatenate([self._initial.train_groups, groups + int(self._initial.train_groups.max()) + 1])
            kind, config = self._initial.kind, asdict(self._initial.regressor.config)
        else:
            kind, config = cfg.kind, None
        model = SurrogateModel(self._featurizer, kind, "fitness", config, seed=(self.seed or 0) + self.retrains)
        self.model = model.fit(X, y, groups, first)
        model.common_noise = self._env.evaluator.sim_config.common_noise
        self._calibrate()
        self.retrains += 1
        self._since_retrain = 0
        log.info("surrogate retrained on %d evaluations", len(y))


class _SpentBySkips(SurrealistWrapper):
    """The env as the inner agent sees it with ``SkipAccounting.BUDGET``: its ``budget_left`` is
    :attr:`Prescreened.inner_budget_left`."""

    def __init__(self, env, prescreened: Prescreened):
        super().__init__(env)
        self._prescreened = prescreened

    @property
    def budget_left(self) -> int:
        return self._prescreened.inner_budget_left


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
