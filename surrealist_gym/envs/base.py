"""The template env: an episode is one search from a seed test case.

Action: one value in [-1, 1] per mutator (``env.mutators``): the mutation of the SEED test, scaled to each mutator's
range (``values_for(action)`` gives metres and degrees, ``action_for(values)`` the inverse); the seed is
``env.seed_action`` (0 when every range is symmetric about the seed). The adaptive greedy's move "param +/- step on one
mutator around the best" is an action vector; CMA-ES and RL propose whole vectors. Reward: the fitness of the mutated
test (maximised). Observation (a bounded Box): the action last evaluated (scaled to [-1, 1]), the last and best fitness
(in units of the seed's, clipped to +-``FITNESS_BOUND``), and the share of the budget left (0 to 1). Info: the fitness
terms, the test, each run's status and distances, and the trajectory judged as a
:class:`~surrealist_gym.trajectory.Trajectory` (a value, not a bare array: Gymnasium's vector envs stack array-valued
info entries, which flights of different lengths cannot be). ``reset`` evaluates the seed (one evaluation). A test
evaluated before in the episode comes from the memo and costs no budget (``info["memo"]``); one evaluated in an earlier
episode, or by an interrupted search whose store is reused, is not simulated again but costs budget, so an episode does
not depend on what came before it (and a resumed search retraces the interrupted one); ``info["simulations"]`` counts
the runs the episode's evaluations stand for; an invalid test (overlap, non-positive size) is not simulated, costs no
budget and scores a penalty (``gym.make`` wraps the env so that every action flies instead:
:mod:`~surrealist_gym.envs.flyable`). The episode is truncated when the budget is spent. A wrapper that changes what is
charged (e.g. ``surrogates.racing.Racing``) is a :class:`~surrealist_gym.envs.wrapper.SurrealistWrapper`.

Subclasses override only the hooks ``_objective`` and, if needed, ``_terminated``, and hand the base class their
seed test, mutators, budget and one :class:`EnvSetup` (how evaluations fly: runs, UAV, noise seed, where, store).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import gymnasium as gym
import numpy as np

from ..errors import InvalidTestCase
from ..evaluation import Evaluation, Evaluator
from ..mutators import PropertyMutator, action_values, apply_action
from ..store import EvaluationStore
from ..testcase import TestCase
from ..trajectory import Trajectory

INVALID_STEPS_FACTOR = 4  # an episode also ends after this many steps per unit of budget (invalid actions)
FITNESS_BOUND = 10.0  # the observation's fitnesses, in units of the seed's, are clipped to +-this


@dataclass(frozen=True, slots=True, kw_only=True)
class EnvSetup:
    """What every env shares, whatever its problem: how an evaluation flies and where it is kept. Each field is the
    env keyword (``gym.make(id, runs=..., uav=...)``) of the same name.

    Attributes:
        runs: runs flown per evaluation.
        random_seed: base seed of the runs' noise.
        sim_config: a :class:`~surrealist_gym.sim.config.SimConfig` (or a mapping of its fields, e.g.
            ``{"common_noise": True}``); the UAV below is applied to it.
        uav: the UAV profile (preset name, YAML path or profile); None: the seed test's
            (:func:`~surrealist_gym.sim.uav.decide_uav`), with a mapping ``sim_config`` applied to it, unless
            ``sim_config`` is a full :class:`~surrealist_gym.sim.config.SimConfig`, which is then the UAV as given.
        executor: where the runs fly (:mod:`surrealist_gym.executors`); None: a pool of ``workers`` local
            processes (all cores, at most 8, when ``workers`` is None too), except in a daemonic process (a worker of
            Gymnasium's async vector env or SB3's ``SubprocVecEnv``), which may not start processes of its own: there
            the runs fly in that process (``"inline"``). ``"threads"``: threads of this process.
        workers: how many local processes (no executor given) or threads (``"threads"``).
        store: an :class:`~surrealist_gym.store.EvaluationStore` or its SQLite path, None for none.
    """

    runs: int
    random_seed: int = 0
    sim_config: Any = None
    uav: Any = None
    executor: Any = None
    workers: int | None = None
    store: Any = None


def in_daemon_process() -> bool:
    """Whether this process is daemonic (a vector env's worker): it may not start child processes."""
    import multiprocessing

    return bool(multiprocessing.current_process().daemon)


def _executor_for(setup: EnvSetup):
    """The executor of ``setup`` (see :class:`EnvSetup`): inline in a daemonic process unless one is named."""
    executor = setup.executor
    if in_daemon_process() and executor in (None, "process"):
        if setup.workers is not None or executor == "process":
            raise ValueError(f"workers={setup.workers}, executor={executor!r}: a daemonic process (a vector env's "
                             f"worker) cannot start worker processes; leave both unset to fly its runs inline")
        return "inline"
    if executor in (None, "threads") and setup.workers is not None:
        from ..executors import make_executor
        return make_executor(executor, setup.workers)
    return executor


class SurrealistEnv(gym.Env):
    """Base of Surrealist-Replicate-v0, Surrealist-Generate-v0 and Surrealist-CaseStudy-v1.

    ``render_mode="rgb_array"``: ``render()`` returns the top view of the last test evaluated (its obstacles and its
    runs' flights; a replication's real flight too) as an H x W x 3 uint8 array; ``"human"``: ``reset`` and ``step``
    show that view in a matplotlib window (none under a non-interactive backend, e.g. on a server); None (default):
    no rendering.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 4}
    steps_per_budget = INVALID_STEPS_FACTOR  # the episode also ends after this many steps per evaluation budgeted

    def __init__(self, seed_test: TestCase, mutators: Sequence[PropertyMutator], budget: int, *, setup: EnvSetup,
                 render_mode: str | None = None):
        if budget < 1:
            raise ValueError(f"budget must be >= 1, got {budget}")
        if not mutators:
            raise ValueError("at least one mutator is needed")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode: expected None or one of {self.metadata['render_modes']}, got "
                             f"{render_mode!r}")
        self.render_mode = render_mode
        self._seed_test = seed_test
        self._mutators = tuple(mutators)
        self._budget = int(budget)
        self.setup = setup
        store = setup.store
        executor = _executor_for(setup)
        store = EvaluationStore(store) if isinstance(store, (str, Path)) else store
        # a seed whose uav.* settings are invalid fails here in one line, not as error runs in the workers
        self.uav = self._decide_uav(seed_test, setup)
        self.evaluator = Evaluator(self._objective(), runs=setup.runs, seed=setup.random_seed,
                                   sim_config=self.uav.config, executor=executor, store=store)
        n = len(self._mutators)
        low = np.array([m.low for m in self._mutators], dtype=np.float64)
        high = np.array([m.high for m in self._mutators], dtype=np.float64)
        self._centre, self._half_range = (high + low) / 2, (high - low) / 2
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(n,), dtype=np.float32)
        low = np.concatenate([-np.ones(n), [-FITNESS_BOUND, -FITNESS_BOUND, 0.0]]).astype(np.float32)
        self.observation_space = gym.spaces.Box(low, np.concatenate([np.ones(n), [FITNESS_BOUND] * 2 + [1.0]])
                                                .astype(np.float32), dtype=np.float32)
        self._evaluations = 0
        self._simulations = 0
        self._steps = 0
        self._seed_fitness = 0.0
        self._episode_keys: set[str] = set()
        self._best: Evaluation | None = None
        self._seed_evaluation: Evaluation | None = None
        self._shown: Evaluation | None = None  # what render() draws: the last test evaluated
        self._refused: str | None = None  # why the last action was refused, if it was
        self._window = None  # render_mode="human": (figure, image) of the matplotlib window
        self._seed_action = self.action_for([m.default_value for m in self._mutators])
        self._seed_action.setflags(write=False)
        self._last_action = self._seed_action.copy()

    # --- hooks ----------------------------------------------------------------------------------------------------
    def _objective(self):
        raise NotImplementedError

    def _terminated(self, evaluation: Evaluation) -> bool:
        return False

    # --- properties -----------------------------------------------------------------------------------------------
    @property
    def mutators(self) -> tuple[PropertyMutator, ...]:
        """The mutators, in the order of the action vector."""
        return self._mutators

    def _decide_uav(self, seed_test, setup: EnvSetup):
        """The UAV that flies (:func:`~surrealist_gym.sim.uav.decide_uav`); an env that knows more (a log's vehicle)
        says so here."""
        from ..sim.uav import decide_uav

        return decide_uav(seed_test, setup.uav, config=setup.sim_config)

    @property
    def seed_test(self) -> TestCase:
        """The test the mutators start from."""
        return self._seed_test

    @property
    def budget(self) -> int:
        """Evaluations allowed per episode."""
        return self._budget

    @property
    def budget_left(self) -> int:
        """Evaluations left."""
        return self._budget - self._evaluations

    @property
    def evaluations(self) -> int:
        """Evaluations charged to the budget in this episode (memo answers and invalid actions are free)."""
        return self._evaluations

    @property
    def simulations(self) -> int:
        """Runs simulated in this episode."""
        return self._simulations

    def evaluated(self, test: TestCase) -> bool:
        """Whether ``test`` was evaluated in this episode (asking for it again is a free memo answer)."""
        return test.key() in self._episode_keys

    @property
    def seed_action(self) -> np.ndarray:
        """The action that stands for the seed test (read-only): 0 where a mutator's range is symmetric about the
        seed, as in the paper's envs; elsewhere, e.g. the case study's rules box, the seed's place in the range."""
        return self._seed_action

    @property
    def seed_evaluation(self) -> Evaluation | None:
        """The evaluation of the seed test (made by reset)."""
        return self._seed_evaluation

    @property
    def best(self) -> Evaluation | None:
        """The best evaluation of this episode."""
        return self._best

    def values_for(self, action) -> np.ndarray:
        """Mutator values (metres, degrees) of an action in [-1, 1]: those its test is made with (``action_values``)."""
        return np.array(action_values(self._mutators, np.asarray(action, dtype=np.float64).reshape(-1)))

    def action_for(self, values) -> np.ndarray:
        """The action in [-1, 1] of mutator values (metres, degrees); values beyond a mutator's range are clipped."""
        return np.clip((np.asarray(values, dtype=np.float64) - self._centre) / self._half_range, -1.0, 1.0)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-mutator action bounds within [-1, 1] that keep every obstacle of the seed a valid size."""
        low, high = zip(*(m.valid_range(self._seed_test) for m in self._mutators))
        return self.action_for(low), self.action_for(high)

    def test_for(self, action) -> TestCase:
        """The test case an action stands for (raises InvalidTestCase if it is invalid)."""
        return apply_action(self._seed_test, self._mutators, np.asarray(action, dtype=np.float64).reshape(-1))

    # --- gymnasium API ----------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode from the seed test (evaluated, or answered from the store).

        ``seed`` seeds the episode's noise (and Gymnasium's ``np_random``): run ``i`` of a test draws from (seed,
        the test's key, i), so the same seed reproduces an episode and different seeds fly different noise (a vector
        env's sub-envs, seeded ``s, s + 1, ...``, differ). None keeps the seed of the episode before, at first the
        constructor's ``random_seed``. An env with a store keeps the store's seed (ValueError for another)."""
        super().reset(seed=seed)
        if seed is not None and int(seed) != self.evaluator.seed:
            self.evaluator = self.evaluator.reseeded(int(seed))
        self._evaluations = 0
        self._simulations = 0
        self._steps = 0
        self._episode_keys: set[str] = set()
        self._last_action = self._seed_action.copy()
        evaluation, _ = self._evaluate(self._seed_test)
        if not np.isfinite(evaluation.fitness):
            from collections import Counter

            from ..errors import SimulationError
            statuses = ", ".join(f"{n} {s}" for s, n in Counter(evaluation.statuses).items()) or "no runs"
            raise SimulationError(f"seed test: none of its runs could be judged ({statuses}); check that its "
                                  f"mission can be flown (surrealist simulate shows each run's end)")
        self._seed_fitness = evaluation.fitness
        self._seed_evaluation = evaluation
        self._best = evaluation
        self._shown, self._refused = evaluation, None
        self._show()
        return self._observation(evaluation.fitness), self._info(evaluation, None, False)

    def step(self, action):
        """Evaluate the seed mutated by ``action`` (clipped to [-1, 1]); an invalid test or a memo hit costs no
        simulation."""
        action = np.clip(np.asarray(action, dtype=np.float64).reshape(-1), -1.0, 1.0)
        self._steps += 1
        self._last_action = action
        try:
            test = self.test_for(action)
        except InvalidTestCase as err:
            evaluation, invalid, memo = None, str(err), False
        else:
            (evaluation, memo), invalid = self._evaluate(test), None
            self._shown = evaluation
            if evaluation.fitness > self._best.fitness:
                self._best = evaluation
        self._refused = invalid
        fitness = self._penalty() if evaluation is None or not np.isfinite(evaluation.fitness) else evaluation.fitness
        truncated = self.budget_left <= 0 or self._steps >= self.steps_per_budget * self._budget
        terminated = evaluation is not None and self._terminated(evaluation)
        info = self._info(evaluation, invalid, memo)
        self._show()
        return self._observation(fitness), float(fitness), terminated, truncated, info

    def render(self):
        """``render_mode="rgb_array"``: the top view of the last test evaluated (an invalid action evaluates nothing,
        so the one before stays) as an H x W x 3 uint8 array; None in other modes or before ``reset``."""
        if self.render_mode != "rgb_array":
            return None
        return self._top_view()

    def _show(self) -> None:
        """``render_mode="human"``: draw the top view in this env's matplotlib window (made on first use)."""
        if self.render_mode != "human":
            return
        import matplotlib
        import matplotlib.pyplot as plt
        from matplotlib.backends import BackendFilter, backend_registry

        if matplotlib.get_backend().lower() in backend_registry.list_builtin(BackendFilter.NON_INTERACTIVE):
            return  # nowhere to show it (a server): nothing drawn

        image = self._top_view()
        if image is None:
            return
        if self._window is None or not plt.fignum_exists(self._window[0].number):
            figure = plt.figure("surrealist-gym")
            axes = figure.add_axes((0, 0, 1, 1))
            axes.set_axis_off()
            self._window = (figure, axes.imshow(image))
            plt.show(block=False)
        else:
            self._window[1].set_data(image)
        self._window[0].canvas.draw_idle()
        plt.pause(1.0 / self.metadata["render_fps"])

    def _top_view(self):
        """The top view of the last test evaluated, as an image array (None before ``reset``)."""
        if self._shown is None:
            return None
        from ..logs.plots import top_view_image

        shown = self._shown
        flights = [Trajectory.from_array(r.trajectory) for r in shown.runs
                   if r.trajectory is not None and len(r.trajectory) > 1]
        title = f"evaluation {self._evaluations}/{self._budget}: fitness {shown.fitness:.3g}"
        if self._refused is not None:
            reason = self._refused if len(self._refused) <= 60 else self._refused[:57] + "..."
            title += f"\nlast action refused: {reason}"
        return top_view_image(flights, obstacles=shown.test.obstacles, title=title, reference=self._reference())

    def _reference(self):
        """The trajectory render() draws as the reference (a replication's real flight); None here."""
        return None

    def close(self):
        """Close the evaluator (and its executor) and the window of ``render_mode="human"``."""
        if self._window is not None:
            import matplotlib.pyplot as plt

            plt.close(self._window[0])
            self._window = None
        self.evaluator.close()

    # --- internals ------------------------------------------------------------------------------------------------
    def _evaluate(self, test: TestCase) -> tuple[Evaluation, bool]:
        """Evaluate; a test already evaluated in this episode is a memo hit and costs no budget."""
        key = test.key()
        memo = key in self._episode_keys
        if not memo:
            self._episode_keys.add(key)
            self._evaluations += 1
        evaluation = self.evaluator.evaluate(test)
        if not memo:
            self._simulations += len(evaluation.runs)
        return evaluation, memo

    def _penalty(self) -> float:
        return self._seed_fitness - max(1.0, abs(self._seed_fitness))

    def _observation(self, fitness: float) -> np.ndarray:
        scale = max(1.0, abs(self._seed_fitness))
        fitness = fitness if np.isfinite(fitness) else self._penalty()
        best = self._best.fitness if self._best is not None and np.isfinite(self._best.fitness) else fitness
        scaled = np.clip([fitness / scale, best / scale], -FITNESS_BOUND, FITNESS_BOUND)
        obs = np.concatenate([self._last_action, scaled, [max(self.budget_left, 0) / self._budget]])
        return obs.astype(np.float32)

    def _info(self, evaluation: Evaluation | None, invalid: str | None, memo: bool) -> dict:
        info = {"invalid": invalid, "evaluations": self._evaluations, "budget_left": self.budget_left,
                "simulations": self._simulations,
                "best_fitness": None if self._best is None else self._best.fitness}
        if evaluation is None:
            info.update(fitness=self._penalty(), memo=False, statuses=(), min_distances=(), durations=(), terms={})
            return info
        runs = evaluation.runs
        info.update(fitness=evaluation.fitness, memo=memo,
                    test=evaluation.test, statuses=evaluation.statuses,
                    min_distances=tuple(r.min_distance for r in runs),
                    min_distances_2d=tuple(r.min_distance_2d for r in runs),
                    competition_distances=tuple(r.competition_distance for r in runs),
                    durations=tuple(r.duration for r in runs),
                    terms=copy.deepcopy(evaluation.terms),
                    trajectory=None if evaluation.trajectory is None else Trajectory.from_array(evaluation.trajectory))
        return info
