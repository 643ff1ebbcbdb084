"""Pre-screening: a batch evaluator between an agent's ask and its tell that simulates only the candidates worth a
simulation (docs/surrogates.md).

The agent asks for candidate actions; :meth:`Prescreener.evaluate` evaluates them, most promising first (by the
model), against the incumbent (the test with the best real fitness so far), and answers in the order asked:

* a free candidate (invalid, or evaluated before in the episode) is stepped on the env, which answers it for free;
* a candidate the screening rule (:mod:`surrogates.screening`: ``lowfi``, ``ei``, ``pi``; ``none`` skips nothing;
  ``auto`` is ``lowfi`` once a margin is known, else ``ei``) finds without a real chance is skipped: it is not
  simulated and the agent is told an estimate below the best (``info["skipped"]``);
* one that passes may be raced (:mod:`surrogates.racing`): its first runs fly first, the rest only if they keep up
  with the incumbent's; one that falls behind is dropped and told like a skip;
* the rest are stepped on the env (simulated).

After each batch the model learns the real evaluations (:mod:`surrogates.online`). Pre-screening neither subclasses
nor wraps the agent, so any ask/tell loop can put it between ask and tell, as pycma's surrogate population sits
between its optimizer's ask and tell. :class:`surrogates.prescreened.Prescreened` is that loop for any agent, with
the restart policy that verifies an early stop.

Example:
    >>> import gymnasium as gym, surrealist_gym
    >>> from search import AdaptiveGreedy
    >>> env = gym.make("Surrealist-Generate-v0", budget=4, runs=1, executor="inline")
    >>> _, info = env.reset(seed=0)
    >>> prescreener, agent = Prescreener("online", seed=0), AdaptiveGreedy("paper", seed=0)
    >>> prescreener.start(env, info)
    >>> agent.setup(prescreener.agent_env, info)
    >>> while not (prescreener.stop() or agent.stop()):
    ...     actions = agent.ask()
    ...     batch = prescreener.evaluate(actions)
    ...     agent.tell(actions[:len(batch.fitnesses)], batch.fitnesses, batch.infos)
    >>> env.unwrapped.evaluations <= 4
    True
"""
from __future__ import annotations

import itertools
import logging
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from surrealist_gym.envs.wrapper import SurrealistWrapper, search_layer
from surrealist_gym.errors import InvalidTestCase, SurrealistError
from surrealist_gym.evaluation import describe_noise

from .config import PrescreenConfig, SkipAccounting
from .dataset import Featurizer
from .models import SurrogateModel
from .online import OnlineTraining
from .racing import Race, Racing
from .replay import model_margin
from .screening import Screen, Skip, rule_in_force, screening_rule

log = logging.getLogger(__name__)

SPENT_BY_SKIPS = "budget spent (skipped and dropped candidates counted as evaluations)"


@dataclass(frozen=True, slots=True)
class Batch:
    """A batch of candidates evaluated.

    Attributes:
        fitnesses, infos: what the agent is told, in the order it asked, up to the first candidate not reached (the
            batch ends early when the episode does, or with ``SkipAccounting.BUDGET`` when the agent's budget is
            spent): the env's answer for a candidate stepped on, an estimate below the best for one skipped or
            dropped (``info["skipped"]``).
        stepped: the candidates stepped on the env (simulated, or answered by its memo) as (action, fitness, info),
            in the order stepped; some may lie beyond what the agent is told.

    Whether the episode is over is :attr:`Prescreener.over` (and :meth:`Prescreener.stop`).
    """

    fitnesses: tuple[float, ...]
    infos: tuple[dict, ...]
    stepped: tuple[tuple[np.ndarray, float, dict], ...]


@dataclass(frozen=True, slots=True)
class Calibration:
    """What the model in force sets: the ``lowfi`` margin, racing's rule, and the screening rule in force."""

    margin: float | None = None  #: ``lowfi``: the shortfall that skips (None: not calibrated, or no coarse flight)
    race: Race = Race()
    screening: Any = None  #: a :mod:`surrogates.screening` rule (None: nothing to skip on yet)


class SkipLog:
    """The candidates skipped or dropped in an episode: why (one entry each, what ``skipped.json`` holds), and what
    each was told, told again when it is asked again.

    Args:
        memo: tell a skip as a free memo answer (``SkipAccounting.MEMO``), else as an evaluation.
    """

    def __init__(self, memo: bool = False):
        self.memo = memo
        self.entries: list[dict] = []
        self._told: dict[str, tuple[float, dict]] = {}  # what each skipped or dropped test was told, by key

    @property
    def dropped(self) -> int:
        """Candidates dropped by racing after their first runs (the other entries were never flown)."""
        return sum(e["rule"] == "race" for e in self.entries)

    def again(self, test) -> tuple[float, dict] | None:
        """What a test skipped before is told again (free, as the env's memo would answer); None if it was not."""
        told = self._told.get(test.key())
        return None if told is None else (told[0], {**told[1], "memo": True})

    def add(self, env, action, test, rule: str, skip: Skip, best_fitness: float,
            prediction: tuple[float, float] | None = None) -> tuple[float, dict]:
        """Log a skipped or dropped candidate (``env``: the Surrealist layer, for its counts); returns the fitness and
        info the agent is told: a fitness below the best, and the trajectory and statuses of the runs flown, if any
        (the greedy's plateau test compares it with the incumbent's over the same first runs)."""
        told = min(skip.told, best_fitness - 1e-9 * max(1.0, abs(best_fitness)))
        entry = dict(skip.why)
        entry.update({"action": np.asarray(action, dtype=np.float64).tolist(), "test_key": test.key(),
                      "obstacles": [o.to_list() for o in test.obstacles], "rule": rule, "told_fitness": told,
                      "after_evaluations": env.budget - env.budget_left, "simulations": env.simulations})
        info = {"fitness": told, "memo": self.memo, "skipped": True, "invalid": None, "test": test,
                "evaluations": env.budget - env.budget_left, "budget_left": env.budget_left,
                "simulations": env.simulations, "best_fitness": None if env.best is None else env.best.fitness,
                "predicted": prediction}
        if skip.flown is not None:
            info.update(trajectory=skip.flown.trajectory, statuses=skip.flown.statuses)
        log.info("skipped candidate %s (%s): %s", entry["action"], rule,
                 {k: round(v, 3) for k, v in entry.items() if isinstance(v, float)})
        self.entries.append(entry)
        self._told[test.key()] = (told, info)
        return told, info


class Prescreener:
    """Evaluates an agent's candidates, simulating only those with a real chance of improving on the incumbent.

    Args:
        model: a trained :class:`~surrogates.models.SurrogateModel`, the path of a saved one, or ``"online"``.
        config: a :class:`~surrogates.config.PrescreenConfig`.
        seed: seed of the model's (re)training.

    Bind it to an episode with :meth:`start`, set the agent up on :attr:`agent_env`, then :meth:`evaluate` each of
    its batches until :meth:`stop` or the agent's own stop.
    """

    def __init__(self, model: SurrogateModel | str | Path = "online", config: PrescreenConfig | None = None,
                 seed: int | None = None):
        if str(model) == "online":
            model = None
        elif not isinstance(model, SurrogateModel):
            model = SurrogateModel.load(model)
        self.initial: SurrogateModel | None = model  #: the pre-trained model (None: online)
        self.config = config or PrescreenConfig()
        self.seed = seed
        self.env = None  #: the episode's Surrealist layer (:class:`~surrogates.racing.Racing` when racing)
        self.agent_env = None  #: the env the agent searches on (with ``SkipAccounting.BUDGET``, skips spend budget)
        self.screening = True  #: False once every candidate is simulated (:meth:`stop_screening`)
        self.over = False  #: the episode is over
        self.calibration = Calibration()
        self.training: OnlineTraining | None = None
        self._stepper = None  # what evaluate() steps: the env given to start(), raced when racing
        self._screen = Screen(self.config.screen.max_skips)
        self._skips = SkipLog(self.config.skips is SkipAccounting.MEMO)
        self._incumbent: tuple[float, dict] = (-np.inf, {})  # the best real (fitness, info) so far
        self._predictions: dict[str, tuple[float, float]] = {}  # the model's (mean, std) per test, for one batch

    # --- what it did -----------------------------------------------------------------------------------------------
    @property
    def model(self) -> SurrogateModel | None:
        """The model in force (retrained during a search, or trained online)."""
        return self.initial if self.training is None else self.training.model

    @property
    def retrains(self) -> int:
        """Models trained in this episode."""
        return 0 if self.training is None else self.training.retrains

    @property
    def margin(self) -> float | None:
        """The ``lowfi`` margin in force (None: not calibrated yet, or a model without low-fidelity features)."""
        return self.calibration.margin

    @property
    def race_margins(self) -> dict[int, float | None]:
        """Racing's margin per stage (run count); None where not calibrated yet."""
        return dict(self.calibration.race.margins)

    @property
    def rule(self) -> str:
        """The rule in force: ``auto`` resolves to ``lowfi`` once a margin is known, else ``ei``."""
        return rule_in_force(self.config.screen.rule, self.margin)

    @property
    def skipped(self) -> tuple[dict, ...]:
        """One entry per candidate skipped or dropped (what ``skipped.json`` holds), in order."""
        return tuple(self._skips.entries)

    @property
    def dropped(self) -> int:
        """Candidates dropped by racing after their first runs (the rest of :attr:`skipped` were never flown)."""
        return self._skips.dropped

    @property
    def agent_budget_left(self) -> int:
        """The budget left with every skipped or dropped candidate spent as a whole evaluation (what the agent sees
        with ``SkipAccounting.BUDGET``): the env's budget less its real evaluations and the skips."""
        return self.env.budget - self.env.evaluations - len(self._skips.entries)

    @property
    def unspent(self) -> int:
        """Budget the skipped and dropped candidates did not spend (raced runs are charged in whole evaluations)."""
        return self.env.budget_left - self.agent_budget_left

    @property
    def spent_by_skips(self) -> bool:
        """With ``SkipAccounting.BUDGET``, while screening: the agent's budget (skips counted) is spent, where the env
        would have ended the search without screening."""
        return self.config.skips is SkipAccounting.BUDGET and self.screening and self.agent_budget_left <= 0

    # --- the verbs ---------------------------------------------------------------------------------------------------
    def start(self, env, info: dict) -> None:
        """Bind to an episode of ``env`` just reset (``info``: its reset info, the seed test's evaluation): the
        screening rule and margins for the model, the seed as the incumbent. Raises SurrealistError when the rule
        or the racing stages do not fit the model or the env."""
        self._stepper = Racing(env) if self.config.race.stages else env
        self.env = search_layer(self._stepper)
        self._check_noise_mode()
        featurizer = (self.initial.featurizer if self.initial is not None
                      else Featurizer.for_env(self.env, self.config.online.lowfi))
        if self.config.screen.rule == "lowfi" and featurizer.lowfi is None:
            raise SurrealistError("prescreen rule lowfi: the model has no low-fidelity features (train it with "
                                  "--lowfi)")
        stages = self.config.race.stages
        if stages and stages[-1] >= self.env.evaluator.runs:
            raise SurrealistError(f"prescreen first_runs: {stages[-1]} must be below the env's runs "
                                  f"({self.env.evaluator.runs})")
        self.training = OnlineTraining(self.initial, featurizer, self.config.online, self.env.evaluator,
                                       bool(stages), self.seed)
        self.screening, self.over = True, False
        self._screen = Screen(self.config.screen.max_skips)
        self._skips = SkipLog(self.config.skips is SkipAccounting.MEMO)
        self._incumbent = (float(info["fitness"]), info)
        self._calibrate()
        self.training.add(info)
        spends = self.config.skips is SkipAccounting.BUDGET
        self.agent_env = _SpentBySkips(self.env, self) if spends else self.env

    def evaluate(self, candidates: Sequence[np.ndarray], callback: Callable[[dict], None] | None = None) -> Batch:
        """Evaluate a batch of candidate actions (free ones first, then the most promising): each is told again
        what it was told before, skipped, dropped by racing, or stepped on the env (``callback`` gets the info of
        each step). Then the model learns the real evaluations."""
        candidates = list(candidates)
        self._predictions = {}
        if self.screening:
            tests = [self._test(a) for a in candidates]
            order = self._most_promising_first(tests)
        else:  # every candidate is simulated: no tests to screen, nothing to predict
            tests, order = [None] * len(candidates), list(range(len(candidates)))
        results: list[tuple[float, dict] | None] = [None] * len(candidates)
        stepped = []
        for i in order:
            fitness, info, real, done = self._evaluate_one(candidates[i], tests[i], callback)
            results[i] = (fitness, info)
            if real:
                stepped.append((candidates[i], fitness, info))
            if done:
                break
        self._learn([info for _, _, info in stepped])
        told = list(itertools.takewhile(lambda r: r is not None, results))
        return Batch(tuple(f for f, _ in told), tuple(i for _, i in told), tuple(stepped))

    def stop(self) -> dict:
        """A non-empty dict (with the reason) once the episode is over, or (``SkipAccounting.BUDGET``, while
        screening) once the agent's budget with the skips counted is spent."""
        if self.over:
            return {"reason": "budget spent"}
        return {"reason": SPENT_BY_SKIPS} if self.spent_by_skips else {}

    def stop_screening(self) -> None:
        """Simulate every candidate from now on: no screening, racing or retraining (the verify pass)."""
        self.screening = False

    # --- one candidate -----------------------------------------------------------------------------------------------
    def _evaluate_one(self, action, test, callback) -> tuple[float, dict, bool, bool]:
        """(fitness, info, stepped on the env, the batch is over) for one candidate (``test`` None: free)."""
        env, (best, incumbent) = self.env, self._incumbent
        if test is not None and env.evaluated(test):
            test = None  # the same test earlier in this batch was simulated: now a free memo answer
        again = None if test is None else self._skips.again(test)
        if again is not None:  # skipped before: told the same again, free
            return *again, False, self.spent_by_skips
        skip, rule = self._screen.verdict(self.calibration.screening, test, incumbent.get("test"), best), self.rule
        prediction = None if skip is None else self._predictions.get(test.key())
        if skip is None and test is not None:
            skip, rule = self.calibration.race.verdict(env, action, incumbent.get("test"), best), "race"
        if skip is None:
            return self._step(action, best, callback)
        told, info = self._skips.add(env, action, test, rule, skip, best, prediction)
        self.over = self.over or env.budget_left <= 0  # the runs raced spent it
        return told, info, False, self.over or self.spent_by_skips

    def _step(self, action, best: float, callback) -> tuple[float, dict, bool, bool]:
        """Step the candidate on the env: a real evaluation (or the env's free answer)."""
        _, reward, terminated, truncated, info = self._stepper.step(action)
        if callback is not None:
            callback(info)
        reward = float(reward)
        self.over = self.over or bool(terminated or truncated)
        if reward > best:
            self._incumbent = (reward, info)
        return reward, info, True, self.over or self.spent_by_skips

    def _test(self, action):
        """The candidate's test, or None when it is free (invalid or a memo hit)."""
        try:
            test = self.env.test_for(action)
        except InvalidTestCase:
            return None  # the env rejects it for free
        return None if self.env.evaluated(test) else test  # a memo hit costs nothing

    def _most_promising_first(self, tests) -> list[int]:
        """Candidate indices, free ones first, then by predicted fitness (the order asked without a model)."""
        if self.model is None:
            return list(range(len(tests)))

        def priority(i):
            if tests[i] is None:
                return -np.inf
            mean = self._predict(tests[i])[0]
            return -mean if np.isfinite(mean) else np.inf
        return sorted(range(len(tests)), key=priority)

    def _predict(self, test) -> tuple[float, float]:
        """The model's (mean, std) for a test, on its scale (once per test in a batch)."""
        key = test.key()
        if key not in self._predictions:
            mean, std = self.model.predict(self.training.featurizer.transform([test]))
            self._predictions[key] = (float(mean[0]), max(float(std[0]), 1e-9))
        return self._predictions[key]

    # --- the model in force ----------------------------------------------------------------------------------------
    def _learn(self, infos: list[dict]) -> None:
        """Learn the real evaluations of a batch; while screening, retrain when due and calibrate again."""
        for info in infos:
            if not info.get("memo") and not info.get("invalid"):
                self.training.add(info)
        if self.screening and self.training.due:
            model = self.training.retrain()
            self._calibrate()
            log.info("surrogate retrained on %d evaluations", len(model.train_y))

    def _calibrate(self) -> None:
        """Margins, the tie rule and the screening rule, for the model in force."""
        cfg, model, lowfi = self.config, self.model, self.training.featurizer.lowfi
        margin = None
        if lowfi is not None:  # else no low-fidelity flights to compare
            margin = (float(cfg.screen.margin) if cfg.screen.margin is not None
                      else None if model is None else model_margin(model, cfg.miss_rate))
        race = Race.calibrated(cfg.race, model, cfg.miss_rate, self.env.evaluator.sim_config.common_noise)
        self.calibration = Calibration(margin, race, screening_rule(cfg.screen, margin, lowfi, model, self._predict))

    def _check_noise_mode(self) -> None:
        """Warn when the model learnt from evaluations flown in the other noise mode: its racing margins were
        calibrated on first runs whose noise the incumbent's did (common noise) or did not (each test's own) share."""
        trained = None if self.initial is None else self.initial.common_noise
        flies = self.env.evaluator.sim_config.common_noise
        if trained is not None and bool(trained) != flies:
            name = self.initial.path or "the surrogate model"
            warnings.warn(f"{name}: trained on evaluations flown with {describe_noise(trained)}, this search flies "
                          f"{describe_noise(flies)}; its racing margins were calibrated in the other mode (train it "
                          f"on stores flown the same way, or match --common-noise)", UserWarning, stacklevel=2)


class _SpentBySkips(SurrealistWrapper):
    """The env as the agent sees it with ``SkipAccounting.BUDGET``: its ``budget_left`` is
    :attr:`Prescreener.agent_budget_left`."""

    def __init__(self, env, prescreener: Prescreener):
        super().__init__(env)
        self._prescreener = prescreener

    @property
    def budget_left(self) -> int:
        """The budget left with the skips counted as evaluations."""
        return self._prescreener.agent_budget_left


__all__ = ["Batch", "Calibration", "PrescreenConfig", "Prescreener", "SkipAccounting", "SkipLog"]
