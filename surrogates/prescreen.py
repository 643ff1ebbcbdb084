"""Pre-screening: a wrapper around any agent that simulates only the candidates worth a simulation.

:class:`Prescreened` asks the inner agent for candidates and screens each against the incumbent (the test with the
best real fitness so far) with one of these rules:

* ``lowfi`` (multi-fidelity): fly the candidate once in the low-fidelity simulator (:mod:`surrogates.lowfi`) and
  skip it when its low-fidelity fitness falls short of the incumbent's by more than a ``margin``. The margin is
  calibrated on the model's training stores: each search is replayed in the order it was evaluated, and the margin
  is the shortfall that only ``miss_rate`` of its real improvements exceeded (:func:`lowfi_margin`).
* ``ei`` / ``pi``: the surrogate's mean and standard deviation of the fitness (model scale) give the expected
  improvement over the best (skip when EI < ``threshold`` x the spread of the training targets) or the probability
  of improvement (skip when P < ``threshold``).
* ``none``: skip nothing; candidates are only raced (``first_runs``), most promising first by the model.
* ``auto`` (default): ``lowfi`` when a margin is known (a model trained with low-fidelity features on stores with
  enough improvements, or a margin given), else ``ei``.

A skipped candidate is not simulated and costs no budget: the inner agent is told an estimate below the best
(``lowfi``: the best minus the low-fidelity shortfall; ``ei``/``pi``: the prediction minus ``pessimism``
standard deviations, never above the best) with ``info["skipped"] = True`` and ``info["memo"]`` False (the
agent plans its own budgets as if it had been evaluated; ``agent_counts_skips=False``: True, so budget-aware
agents do not count it), and it is logged in :attr:`Prescreened.skipped`; asked again, it is told the same as a
memo answer (free), as the env answers a test it simulated. A candidate dropped by racing also carries the
averaged trajectory of the runs it flew (the authors' greedy compares trajectories in its plateau test). Promising
candidates go
through ``env.step`` as usual, the most promising of one ``ask`` first (by predicted mean), each screened against
the best so far including the earlier results of the same ``ask`` (the inner agent is told the results in the
order it asked). In online mode (no model to start from) or with ``retrain_every`` set, the model is
retrained on its training data plus the real evaluations of the episode every ``retrain_every`` evaluations once
``min_points`` exist (and the margin recalibrated). ``max_skips`` consecutive skips force the next candidate to
be simulated, so an agent that never stops on its own (random search) still spends its budget. Racing
(``first_runs``) flies a candidate that passes the screen run by run: its first runs, then the rest only if they
keep up with the incumbent's first runs; with common random numbers a candidate whose first runs score exactly
as the incumbent's did not change those flights and is dropped as a tie (``drop_ties``). An agent that counts
skips may give up because of them (the greedy ends when a whole round of mutators finds nothing better): with
``verify_stop`` the inner agent is then started again from the best test, unscreened, so the budget left checks
that stop by simulation.

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
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from search.base import Agent, SearchResult
from surrealist_gym.errors import InvalidTestCase, SurrealistError
from surrealist_gym.evaluation import describe_noise

from .dataset import Featurizer, stack_rows
from .lowfi import FITNESS as LOWFI_FITNESS
from .models import SurrogateModel

log = logging.getLogger(__name__)
RULES = ("auto", "lowfi", "ei", "pi", "none")
MIN_IMPROVEMENTS = 10  # improvements needed in the training data to calibrate the low-fidelity margin
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


def improvement_shortfalls(proxy, fitness, groups) -> list[float]:
    """For every real improvement of past searches (:func:`replayed_improvements`), the incumbent's proxy minus its
    own. Rows whose proxy is unknown (NaN) are skipped."""
    proxy = np.asarray(proxy)
    return [float(theirs - ours) for theirs, ours in replayed_improvements(proxy, fitness, groups, np.isfinite(proxy))]


def tie_improvements(first_runs, fitness, groups) -> int:
    """How many real improvements of past searches (:func:`replayed_improvements`) scored exactly as their incumbent
    on their first k runs at some stage (``first_runs``: (rows, k) fitness of the first 1..k runs, NaN where
    unknown); racing with ``drop_ties`` would have dropped them."""
    first_runs = np.asarray(first_runs, dtype=np.float64).reshape(len(fitness), -1)
    return sum(any(np.isfinite(a) and np.isfinite(b) and is_tie(a, b) for a, b in zip(theirs, ours))
               for theirs, ours in replayed_improvements(first_runs, fitness, groups))


def replay_margin(proxy, fitness, groups, miss_rate: float = 0.02) -> float | None:
    """The shortfall in a cheap proxy of the fitness (the low-fidelity fitness, or the fitness of the first runs)
    that only ``miss_rate`` of the real improvements of past searches exceeded (:func:`improvement_shortfalls`).
    None with fewer than ``MIN_IMPROVEMENTS`` improvements.
    """
    shortfalls = improvement_shortfalls(proxy, fitness, groups)
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


def race_margin(model: SurrogateModel, first_runs: int, miss_rate: float = 0.02) -> float | None:
    """:func:`replay_margin` of the fitness of the first ``first_runs`` runs on a model's training data; None when
    its stores hold no such fitness."""
    first = model.train_first_runs
    if first is None or first.shape[1] < first_runs:
        return None
    return replay_margin(first[:, first_runs - 1], model.train_y, model.train_groups, miss_rate)


@dataclass(frozen=True, slots=True)
class PrescreenConfig:
    """How candidates are screened and the model retrained.

    Attributes:
        rule: ``auto``, ``lowfi`` (low-fidelity shortfall), ``ei`` (expected improvement), ``pi``
            (probability of improvement) or ``none`` (skip nothing: only race, with ``first_runs``); see the
            module docstring.
        margin: ``lowfi``: skip when the low-fidelity fitness is below the incumbent's by more than this (in
            fitness units); None calibrates it on the model's training data (see ``miss_rate``).
        miss_rate: share of the past real improvements whose low-fidelity shortfall may exceed the calibrated
            margin.
        threshold: EI below ``threshold`` x std of the training targets (``ei``), or P(improvement) below it
            (``pi``), skips a candidate.
        pessimism: a skipped candidate is told ``mean - pessimism x std`` (capped below the best).
        min_points: real evaluations needed before an online model is first trained.
        retrain_every: retrain after this many new real evaluations (0: never retrain a pre-trained model;
            an online model always retrains).
        max_skips: consecutive skips after which the next candidate is simulated anyway.
        kind: model kind of an online model (``ensemble`` or ``knn``).
        agent_counts_skips: tell the inner agent a skip as a (non-memo) evaluation, so it plans its own budgets
            (the greedy's local budgets) as without screening (default; False tells skips as memo answers, which
            the greedy does not charge); the env's budget counts real simulations either way.
        lowfi: an online model's features include a low-fidelity flight of each test (one ~0.1 s flight per
            candidate screened; see :mod:`surrogates.lowfi`).
        first_runs: racing: a candidate that passes the screen first flies only this many of its runs, and the
            rest only if the fitness of those runs falls short of the incumbent's first runs by no more than
            ``race_margin`` (0: off; must be below the env's runs). A tuple races in stages: after each of its
            run counts (increasing, e.g. ``(1, 2, 3, 4)``) the candidate is compared again and dropped at the
            first stage it falls behind; later stages fly only the runs not flown yet.
        race_margin: racing's margin (fitness units, every stage); None calibrates one per stage like the
            ``lowfi`` margin, on the model's training stores and the episode's evaluations, each stage at an equal
            share of ``miss_rate`` (so the stages together miss about ``miss_rate`` of the improvements).
        drop_ties: racing also drops a candidate whose first runs score exactly as the incumbent's (told just
            below the best). With common random numbers (``SimConfig.common_noise``) that means the mutation left
            those flights unchanged (an obstacle slid along the path): in the 10 RQ2 stores of greedy alone under
            common noise 113 of 440 candidates tied on their first run, none improved the best and 105 tied over
            all ten runs. It is not a proof: in 50 case0 seed-1 stores 7 candidates tied the incumbent at some
            stage and 2 of them (a lower box) improved over all five runs. None (default): on when the env flies
            common noise (without it no two tests fly the same runs, so nothing ties) and no real improvement in the
            model's training stores tied its incumbent (:func:`tie_improvements`; checked again at each retrain).
        skips_spend_budget: the inner agent sees a budget from which every skipped or dropped candidate was spent
            as a whole evaluation (``budget_left`` as without screening; needs ``agent_counts_skips``), so it also
            plans its round budgets and stops as without screening: with a screen that drops no improvement it
            walks the unscreened search's path and ends where that would, having simulated less (up to the
            authors' plateau test, which compares trajectories: a skipped candidate has none, a dropped one the
            average of the runs it flew, not of all). The real budget
            left is then unused, or goes to the verify pass (``verify_stop``). Off by default: the inner agent
            sees the env's own budget, spends what screening saved on longer line searches and may walk
            elsewhere.
        verify_stop: when the inner agent stops with budget left, start it again from the best test with
            screening and racing off, so that a stop the skips may have caused is checked by simulation (tests
            already simulated are memo hits and cost nothing); the search then ends as the agent alone would.
            Off by default: on case0 it spent 10-44 more evaluations per search and found nothing better.
    """

    rule: str = "auto"
    margin: float | None = None
    miss_rate: float = 0.02
    threshold: float = 0.01
    pessimism: float = 1.0
    min_points: int = 10
    retrain_every: int = 5
    max_skips: int = 20
    kind: str = "ensemble"
    agent_counts_skips: bool = True
    lowfi: bool = True
    first_runs: int | tuple[int, ...] = 0
    race_margin: float | None = None
    drop_ties: bool | None = None
    skips_spend_budget: bool = False
    verify_stop: bool = False

    def __post_init__(self):
        if isinstance(self.first_runs, (list, tuple)):
            object.__setattr__(self, "first_runs", tuple(int(k) for k in self.first_runs))  # hashable, frozen
        if self.rule not in RULES:
            raise ValueError(f"prescreen rule: expected one of {', '.join(RULES)}, got {self.rule!r}")
        if not 0.0 <= self.miss_rate < 1.0:
            raise ValueError(f"prescreen miss_rate: expected a share in [0, 1), got {self.miss_rate!r}")
        if self.skips_spend_budget and not self.agent_counts_skips:
            raise ValueError("prescreen skips_spend_budget: needs agent_counts_skips (a skip told as a memo answer "
                             "spends no budget)")
        stages = self.race_stages
        if any(k < 1 for k in stages) or any(b <= a for a, b in zip(stages, stages[1:])):
            raise ValueError(f"prescreen first_runs: expected 0 (off), a number of runs or increasing numbers of "
                             f"runs, got {self.first_runs!r}")

    @property
    def race_stages(self) -> tuple[int, ...]:
        """The run counts after which racing compares a candidate with the incumbent (empty: racing off)."""
        if isinstance(self.first_runs, tuple):  # __post_init__ turns any sequence into a tuple
            return self.first_runs
        return (int(self.first_runs),) if self.first_runs else ()


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
        agent sees with ``skips_spend_budget``): the env's budget less its real evaluations and the skips."""
        return self._env.budget - self._env._evaluations - len(self.skipped)

    @property
    def unspent(self) -> int:
        """Budget the skipped and dropped candidates did not spend (the env charges a dropped candidate's probed
        runs in whole evaluations)."""
        return self._env.budget_left - self.inner_budget_left

    @property
    def race_margin(self) -> float | None:
        """Racing's margin at its first stage (None: racing off or not calibrated yet)."""
        return next(iter(self.race_margins.values()), None)

    @property
    def rule(self) -> str:
        """The rule in force: ``auto`` resolves to ``lowfi`` once a margin is known, else ``ei``."""
        if self.config.rule != "auto":
            return self.config.rule
        return "lowfi" if self.margin is not None else "ei"

    # --- the run: some candidates are answered without env.step ---------------------------------------------
    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Search on ``env`` until the inner agent stops or the budget is spent; the result counts real
        evaluations only (``history`` holds the fitness of each simulated or memo step)."""
        seed = seed if seed is not None else self.seed
        _, info = env.reset(seed=seed)
        self.setup(env, info)
        self.inner.setup(_SkipsSpendBudget(env.unwrapped, self) if self.config.skips_spend_budget else env, info)
        done = False
        while not done and (not self.stop() or self._verify_stop(env, info)):
            self._candidates = candidates = self.inner.ask()
            self.ask()
            results: list[tuple | None] = [None] * len(candidates)
            real = []
            _, best, incumbent = self.best
            if self.verified_at is None:
                order, tests, predictions = self._most_promising_first(candidates)
            else:  # the verify pass simulates every candidate: no tests to screen, nothing to predict
                order, tests, predictions = range(len(candidates)), [None] * len(candidates), [None] * len(candidates)
            for i in order:  # a better first result raises the bar for the rest
                if done or self._inner_budget_spent:
                    break
                if tests[i] is not None and tests[i].key() in self._env._episode_keys:
                    tests[i] = None  # the same test earlier in this ask was simulated: now a free memo answer
                again = None if tests[i] is None else self._told.get(tests[i].key())
                if again is not None:  # skipped before: told the same again, free, as the env's memo would
                    results[i] = (candidates[i], again[0], {**again[1], "memo": True})
                    continue
                skip = self._screen(candidates[i], tests[i], predictions[i], best, incumbent.get("test"))
                if skip is None and tests[i] is not None:
                    skip = self._race(candidates[i], tests[i], best, incumbent)
                if skip is not None:
                    results[i] = (candidates[i], skip["told_fitness"], skip["info"])
                    self._told[tests[i].key()] = results[i][1:]
                    done = self._env.budget_left <= 0
                    continue
                reward, step_info, done = self._step(env, candidates[i], callback)
                results[i] = (candidates[i], reward, step_info)
                real.append(results[i])
                if reward > best:
                    best, incumbent = reward, step_info
            told = list(itertools.takewhile(lambda r: r is not None, results))  # in the order asked
            self.tell([a for a, _, _ in real], [f for _, f, _ in real], [i for _, _, i in real])
            self.inner.tell([a for a, _, _ in told], [f for _, f, _ in told], [i for _, _, i in told])
        if not self._stop_reason:
            self._stop_reason = self.stop().get("reason", "")
        return self.result

    def stop(self) -> dict:
        if self._inner_budget_spent:
            return {"reason": "budget spent (skipped and dropped candidates counted as evaluations)"}
        return super().stop() or self.inner.stop()

    @property
    def _inner_budget_spent(self) -> bool:
        """With ``skips_spend_budget``, before the verify pass: the inner agent's budget (skips counted) is spent,
        where the env would have ended the search without screening."""
        return self.config.skips_spend_budget and self.verified_at is None and self.inner_budget_left <= 0

    def _verify_stop(self, env, info: dict) -> bool:
        """Begin the verify pass (see ``PrescreenConfig.verify_stop``) if due; True when it began."""
        if (not self.config.verify_stop or self.verified_at is not None or super().stop()
                or self._env.budget_left <= 0):
            return False
        self.verified_at = self._evaluations
        self.inner.setup(env, info, start=self.best)  # the env's own budget: what screening saved
        return not self.inner.stop()

    # --- Agent hooks ---------------------------------------------------------------------------------------------
    def _setup(self, info: dict) -> None:
        self._check_noise_mode()
        self.skipped = []
        self._told: dict[str, tuple[float, dict]] = {}  # what each skipped or dropped test was told, by key
        self.retrains = 0
        self.verified_at = None
        self._consecutive = 0
        self._featurizer = (self._initial.featurizer if self._initial is not None
                            else Featurizer.for_env(self._env, self.config.lowfi))
        if self.config.rule == "lowfi" and self._featurizer.lowfi is None:
            raise SurrealistError("prescreen rule lowfi: the model has no low-fidelity features (train it with "
                                  "--lowfi)")
        self._X: list[np.ndarray] = []
        self._y: list[float] = []
        self._since_retrain = 0
        self.model = self._initial
        self._first: list[list[float]] = []
        self.margin = self._calibrated_margin()
        self.race_margins = self._calibrated_race_margins()
        self._drop_ties = self._tie_rule()
        self._add_point(info)

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

    def _ask(self) -> list[np.ndarray]:  # the inner agent's candidates (run() tells back the simulated ones)
        return self._candidates

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
        return None if test.key() in self._env._episode_keys else test  # a memo hit costs nothing

    def _most_promising_first(self, candidates) -> tuple[list[int], list, list]:
        """Candidate indices, free ones first, then by predicted fitness (the order asked without a model); the
        tests (None: free) and the model's predictions (mean, std on the model's scale; None without a model)."""
        tests = [self._test(a) for a in candidates]
        if self.model is None:
            return list(range(len(candidates))), tests, [None] * len(candidates)
        predictions = [None if t is None else self._predict(t) for t in tests]

        def priority(i):
            p = predictions[i]
            return -np.inf if p is None else (-p[0] if np.isfinite(p[0]) else np.inf)
        return sorted(range(len(candidates)), key=priority), tests, predictions

    def _predict(self, test) -> tuple[float, float]:
        mean, std = self.model.predict(self._featurizer.transform([test]))
        return float(mean[0]), max(float(std[0]), 1e-9)

    def _screen(self, action, test, prediction, best_fitness: float, incumbent) -> dict | None:
        """None to simulate the candidate, else the log entry of a skip (with what the inner agent is told)."""
        if test is None or self._consecutive >= self.config.max_skips:
            self._consecutive = 0
            return None
        rule = self.rule
        if rule == "none":
            verdict = None
        elif rule == "lowfi":
            verdict = self._lowfi_verdict(test, incumbent, best_fitness)
        else:
            verdict = None if prediction is None else self._model_verdict(prediction, best_fitness)
        if verdict is None:
            self._consecutive = 0
            return None
        self._consecutive += 1
        entry, told = verdict
        return self._skip(action, test, rule, entry, told, best_fitness, prediction)

    def _skip(self, action, test, rule: str, entry: dict, told: float, best_fitness: float, prediction=None,
              trajectory=None, first_runs: int | None = None) -> dict:
        """Log a skipped candidate; returns what the inner agent is told (a fitness below the best, and the
        averaged trajectory of the runs flown, if any, with how many: the greedy's plateau test compares it with the
        incumbent's over the same first runs)."""
        told = min(told, best_fitness - 1e-9 * max(1.0, abs(best_fitness)))
        env = self._env
        entry.update({"action": np.asarray(action, dtype=np.float64).tolist(), "test_key": test.key(),
                      "obstacles": [o.to_list() for o in test.obstacles], "rule": rule, "told_fitness": told,
                      "after_evaluations": env.budget - env.budget_left, "simulations": env._simulations})
        info = {"fitness": told, "memo": not self.config.agent_counts_skips, "skipped": True, "invalid": None,
                "test": test,
                "evaluations": env.budget - env.budget_left, "budget_left": env.budget_left,
                "simulations": env._simulations, "best_fitness": None if env.best is None else env.best.fitness,
                "predicted": prediction}
        if trajectory is not None:
            info.update(trajectory=trajectory, first_runs=first_runs)
        log.info("skipped candidate %s (%s): %s", entry["action"], rule,
                 {k: round(v, 3) for k, v in entry.items() if isinstance(v, float)})
        self.skipped.append(entry)
        return {"told_fitness": told, "info": info}

    def _race(self, action, test, best_fitness: float, incumbent: dict) -> dict | None:
        """Racing: fly the candidate's first runs, stage by stage; None to fly the rest (the candidate is stepped
        on), else the log entry of a candidate dropped at a stage because its runs so far fall short of the
        incumbent's same first runs by more than that stage's margin (the inner agent is told the best minus that
        shortfall), or, with ``drop_ties``, score exactly as the incumbent's (told just below the best)."""
        theirs = (incumbent.get("terms") or {}).get("first_runs_fitness") or []
        for k, margin in self.race_margins.items():
            if len(theirs) < k or (margin is None and not self._drop_ties):
                return None
            fitness, probed = self._env.probe(action, k)
            verdict = race_verdict(theirs[k - 1], fitness, margin, self._drop_ties)
            if verdict:
                shortfall = float(theirs[k - 1] - fitness)
                entry = {"first_runs": k, "first_runs_fitness": float(fitness), "race_shortfall": shortfall,
                         "race_margin": margin, "tie": verdict == "tie"}
                return self._skip(action, test, "race", entry, best_fitness - shortfall, best_fitness,
                                  trajectory=probed.get("trajectory"), first_runs=k)
        return None

    def _lowfi_verdict(self, test, incumbent, best_fitness: float) -> tuple[dict, float] | None:
        """Skip when the low-fidelity fitness falls short of the incumbent's by more than the margin; the inner
        agent is told the best real fitness minus that shortfall."""
        if self.margin is None or incumbent is None:
            return None
        lowfi = self._featurizer.lowfi
        shortfall = float(lowfi.fitness(incumbent.obstacles) - lowfi.fitness(test.obstacles))
        if not shortfall > self.margin:
            return None
        return {"lowfi_shortfall": shortfall, "margin": self.margin}, best_fitness - shortfall

    def _model_verdict(self, prediction, best_fitness: float) -> tuple[dict, float] | None:
        """The model's rule (``ei`` or ``pi``); a skip is told the prediction minus ``pessimism`` std."""
        mean, std = prediction
        best = float(self.model.to_scale(best_fitness))
        z = (mean - best) / std
        cdf = 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))
        if self.rule == "pi":
            score, limit = cdf, self.config.threshold
        else:
            pdf = math.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)
            score = std * (z * cdf + pdf)
            limit = self.config.threshold * self._target_scale()
        if score >= limit:
            return None
        told = float(self.model.from_scale(min(mean - self.config.pessimism * std, best)))
        return {"predicted_mean": mean, "predicted_std": std, "score": score, "limit": limit}, told

    def _target_scale(self) -> float:
        y = self.model.to_scale(self.model.train_y)
        return float(np.std(y)) or 1.0

    def _calibrated_margin(self) -> float | None:
        """The ``lowfi`` margin: the configured one, else calibrated on the model's training data."""
        if self._featurizer.lowfi is None:
            return None  # no low-fidelity flights to compare
        if self.config.margin is not None:
            return float(self.config.margin)
        return None if self.model is None else model_margin(self.model, self.config.miss_rate)

    def _calibrated_race_margins(self) -> dict[int, float | None]:
        """Racing's margin per stage: the configured one, else calibrated on the model's training data at an equal
        share of the miss rate."""
        stages = self.config.race_stages
        if stages and stages[-1] >= self._env.evaluator.runs:
            raise SurrealistError(f"prescreen first_runs: {stages[-1]} must be below the env's runs "
                                  f"({self._env.evaluator.runs})")
        if self.config.race_margin is not None:
            return {k: float(self.config.race_margin) for k in stages}
        share = self.config.miss_rate / max(len(stages), 1)
        return {k: None if self.model is None else race_margin(self.model, k, share) for k in stages}

    def _tie_rule(self) -> bool:
        """Whether racing drops ties (``PrescreenConfig.drop_ties``; None: under common noise, unless a tie improved
        in the model's training stores)."""
        if self.config.drop_ties is not None:
            return self.config.drop_ties
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
        self._first.append(list((info.get("terms") or {}).get("first_runs_fitness") or []))
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
        self.margin = self._calibrated_margin()
        self.race_margins = self._calibrated_race_margins()
        self._drop_ties = self._tie_rule()
        self.retrains += 1
        self._since_retrain = 0
        log.info("surrogate retrained on %d evaluations", len(y))


class _SkipsSpendBudget:
    """The env as the inner agent sees it with ``PrescreenConfig.skips_spend_budget``: the same env, whose
    ``budget_left`` is :attr:`Prescreened.inner_budget_left`."""

    def __init__(self, env, prescreened: Prescreened):
        self._real, self._prescreened = env, prescreened

    @property
    def unwrapped(self):
        return self

    @property
    def budget_left(self) -> int:
        return self._prescreened.inner_budget_left

    def __getattr__(self, name):
        return getattr(self._real, name)


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
