"""Reinforcement learning on stable-baselines3: train a policy across procedurally generated problems, on a
competition case study, or on case studies drawn at random (one policy for every mission); :mod:`search.policy` rolls
it out as a search agent.

Training (:func:`train_policy`) on the paper's problems uses :class:`ProceduralEnv`, a Gymnasium env that draws a new
problem at every reset. A replication problem is the seed test (by default the paper's case0 seed 1) plus a HIDDEN
obstacle layout: the seed mutated by a random action, so the answer is reachable; our simulator flies the hidden layout
once and that flight plays the "real" one (``ReplicateEnv(reference_trajectory=...)``). A generation problem is the RQ2
seed with its first obstacle moved at random. A case-study problem is ``Surrealist-CaseStudy-v1`` itself: the action
box is the rules' box, so every action is a layout within the rules (overlapping or walled-off ones are refused with a
penalty). A missions problem draws a new case study, wind and number of boxes at every reset and acts in the
mission's frame (:class:`~surrealist_gym.competition.missions.MissionCaseStudies`). Episodes are short searches
(``budget`` evaluations of ``runs`` simulations); ``envs`` > 1 steps that many envs at once, each on a thread of this
process (:class:`~search.thread_vec_env.ThreadVecEnv`), flying its runs inline there.

Example:
    >>> train_policy(steps=256, out="ppo.zip", problem="replicate")            # doctest: +SKIP
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Callable

import gymnasium as gym
import numpy as np

from surrealist_gym.envs.drawn import DrawnProblems
from surrealist_gym.errors import DependencyNotInstalled, SurrealistError

from .policy import Algorithm, load_policy


class Problem(str, Enum):
    """The family of procedurally generated training problems."""

    REPLICATE = "replicate"
    GENERATE = "generate"
    CASE_STUDY = "case-study"
    MISSIONS = "missions"


def _sb3(algorithm: Algorithm | str):
    try:
        import stable_baselines3
    except ImportError as err:
        raise DependencyNotInstalled("RL agents need stable-baselines3: pip install 'surrealist-gym[rl]'") from err
    return getattr(stable_baselines3, Algorithm(algorithm).name)


@dataclass(frozen=True, slots=True)
class ProblemConfig:
    """How training problems are drawn.

    Attributes:
        problem: replicate (hidden obstacle layouts), generate (random seed placements), case-study (the
            competition's case study ``case_study``, searched within its rules) or missions (case studies drawn at
            random, in their mission's frame: :class:`~surrealist_gym.competition.missions.MissionCaseStudies`).
        budget: evaluations per episode (one problem).
        runs: simulations per evaluation.
        spread: hidden layouts are the seed mutated by an action uniform in ``[-spread, spread]`` per mutator
            (1 = each mutator's full range); a generation seed's obstacle moves by up to ``spread`` x 8 [m].
        seed_test: the seed test case (path or TestCase); None = case0 seed 1 (replicate) or the RQ2 seed.
        case_study: the case study's name (``mission2``) or YAML; case-study problems only (and needed there).
        obstacles: boxes of a case-study test (1 to 3).
    """

    problem: Problem = Problem.REPLICATE
    budget: int = 15
    runs: int = 1
    spread: float = 0.3
    seed_test: object = None
    case_study: object = None
    obstacles: int = 3

    def __post_init__(self):
        object.__setattr__(self, "problem", Problem(self.problem))
        if (self.problem is Problem.CASE_STUDY) != (self.case_study is not None):
            raise ValueError("ProblemConfig: a case study is named for, and only for, the case-study problem")
        if self.budget < 2 or self.runs < 1 or not 0 < self.spread <= 1:
            raise ValueError(f"ProblemConfig: expected budget >= 2, runs >= 1, 0 < spread <= 1; got {self.budget}, "
                             f"{self.runs}, {self.spread}")


class ProceduralEnv(DrawnProblems):
    """A Surrealist env whose problem is drawn anew at every reset (for training RL policies).

    Spaces are those of the envs it draws (one action value per mutator of the seed's first obstacle), so a policy
    trained here runs on ``Surrealist-Replicate-v0`` (6 mutators) or ``Surrealist-Generate-v0`` (2 mutators).
    """

    def __init__(self, config: ProblemConfig | None = None, sim_config=None, executor="inline", **overrides):
        from surrealist_gym import data_path
        from surrealist_gym.aerialist import load_test
        from surrealist_gym.mutators import AUTHORS_ORDER, MOVE_KINDS, default_mutators
        from surrealist_gym.sim import SimConfig
        from surrealist_gym.testcase import TestCase

        self.config = ProblemConfig(**overrides) if config is None else config
        seed_test = self.config.seed_test
        if seed_test is None:
            replicate = self.config.problem is Problem.REPLICATE
            seed_test = data_path("rq1-seed1.yaml" if replicate else "rq2-seed.yaml")
        self.seed_test = seed_test if isinstance(seed_test, TestCase) else load_test(seed_test)
        kinds = AUTHORS_ORDER if self.config.problem is Problem.REPLICATE else MOVE_KINDS
        self.mutators = default_mutators(self.seed_test, kinds, obstacles=[0])
        self.sim_config, self.executor = SimConfig.coerce(sim_config), executor
        n = len(self.mutators)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(n,), dtype=np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(n + 3,), dtype=np.float32)

    def _mutated(self, action: np.ndarray):
        """The seed mutated by an action in [-1, 1] (raises InvalidTestCase)."""
        from surrealist_gym.mutators import apply_action

        return apply_action(self.seed_test, self.mutators, action)

    def _problem(self, seed: int):
        """A new inner env: a problem drawn from ``self.np_random`` (a few tries until the draw is valid)."""
        from surrealist_gym.envs.generate import GenerateEnv
        from surrealist_gym.envs.replicate import ReplicateEnv
        from surrealist_gym.errors import InvalidTestCase
        from surrealist_gym.mutators import MOVE_KINDS, default_mutators
        from surrealist_gym.sim import simulate

        cfg = self.config
        common = dict(runs=cfg.runs, budget=cfg.budget, mutators=self.mutators, executor=self.executor,
                      random_seed=seed, sim_config=self.sim_config)
        for _ in range(20):
            action = self.np_random.uniform(-cfg.spread, cfg.spread, len(self.mutators))
            try:
                if cfg.problem is Problem.GENERATE:
                    moves = default_mutators(self.seed_test, MOVE_KINDS, obstacles=[0])
                    test = self.seed_test
                    for mutator, a in zip(moves, action[:2]):
                        test = mutator.apply(test, float(np.round(a * 8.0, 6)))
                    return GenerateEnv(seed_test=test, **common)
                hidden = self._mutated(action)
            except InvalidTestCase:
                continue
            real = simulate(hidden, runs=1, seed=seed + 10_000, config=self.sim_config)[0]
            if getattr(real.status, "value", real.status) == "success" and len(real.trajectory) > 1:
                return ReplicateEnv(seed_test=self.seed_test, reference_trajectory=real.trajectory, **common)
        raise SurrealistError(f"ProceduralEnv: no valid {cfg.problem.value} problem in 20 draws "
                              f"(spread {cfg.spread}); lower the spread")

    def _draw(self):
        """A new problem, and its noise seed, drawn from ``self.np_random``."""
        env = self._problem(int(self.np_random.integers(0, 2**31 - 1)))
        self.np_random.integers(0, 2**31 - 1)  # a draw kept so that a seed still draws the problems it drew
        return env


def training_env(config: ProblemConfig, sim_config=None, seed: int = 0, executor="inline") -> gym.Env:
    """The env a policy trains on: :class:`ProceduralEnv` for the paper's problems, ``Surrealist-CaseStudy-v1`` (made
    through Gymnasium's registry, whose noise seed is ``seed``) for a case study.
    ``functools.partial(training_env, ...)`` is what a vector env makes each of its envs with (picklable by reference,
    so SB3's ``SubprocVecEnv`` takes it too)."""
    if config.problem is Problem.MISSIONS:
        from surrealist_gym.competition.missions import MissionCaseStudies

        return MissionCaseStudies(budget=config.budget, runs=config.runs, random_seed=seed, sim_config=sim_config,
                                  executor=executor)
    if config.problem is Problem.CASE_STUDY:
        return gym.make("surrealist_gym:Surrealist-CaseStudy-v1", case_study=config.case_study,
                        obstacles=config.obstacles, budget=config.budget, runs=config.runs, random_seed=seed,
                        sim_config=sim_config, executor=executor)
    return ProceduralEnv(config, sim_config=sim_config, executor=executor)


class TrainingRecord:
    """What a training run met, step by step (every env of a vector env): episodes, evaluations flown, actions
    refused (``info["invalid"]``) or answered from the memo, and the soft failures among the runs flown (a collision,
    or a competition distance below 1.5 m; case-study problems, whose distance is the competition's), and the
    simulated time of those runs [s]."""

    def __init__(self):
        self.steps = self.episodes = self.flown = self.refused = self.memo = 0
        self.simulations = self.soft_failures = 0
        self.simulated_s = 0.0

    def add(self, info: dict, done: bool) -> None:
        """Count one env step from its info (and whether its episode ended)."""
        from surrealist_gym.outcomes import run_points

        self.steps += 1
        self.episodes += bool(done)
        if info.get("invalid") is not None:
            self.refused += 1
        elif info.get("memo"):
            self.memo += 1
        else:
            self.flown += 1
            statuses, distances = info.get("statuses", ()), info.get("competition_distances", ())
            self.simulations += len(statuses)
            self.soft_failures += sum(run_points(s, d) > 0 for s, d in zip(statuses, distances))
            self.simulated_s += float(sum(info.get("durations", ())))

    def to_json(self) -> dict:
        """The counts, and the soft failures per simulation (None before any flight)."""
        out = dict(vars(self))
        out["soft_failures_per_simulation"] = self.soft_failures / self.simulations if self.simulations else None
        out["simulated_s"] = round(self.simulated_s, 1)
        return out


def train_policy(steps: int, out, problem: Problem | str = Problem.REPLICATE, algorithm: Algorithm | str = "ppo",
                 budget: int = 15, runs: int = 1, spread: float = 0.3, seed: int = 0, seed_test=None,
                 sim_config=None, progress: Callable[[int], None] | None = None, case_study=None,
                 obstacles: int = 3, envs: int = 1, init=None, executor="inline", workers: int | None = None,
                 **hyper) -> Path:
    """Train a policy for ``steps`` env steps and save it (SB3 ``save``), with ``train.json`` beside it.

    Args:
        steps: environment steps (each is one evaluation of ``runs`` simulations, ~0.3 s per simulation, or a
            refused action, which flies nothing).
        out: where to write the policy (``.zip``); its settings and :class:`TrainingRecord` go to the same name
            with ``.json`` (``policy.zip`` -> ``policy.json``).
        problem: replicate, generate or case-study.
        algorithm: ppo or sac.
        budget, runs, spread, seed_test, case_study, obstacles: the :class:`ProblemConfig` of the training problems.
        seed: seeds the problems, the policy's initialisation and its sampling; env i of ``envs`` gets ``seed + i``.
        progress: called with the number of steps done, after each step.
        envs: envs stepped together; more than 1 steps each on a thread of this process
            (:class:`~search.thread_vec_env.ThreadVecEnv`): they fly in parallel, as in SB3's ``SubprocVecEnv``.
        init: a policy file of :func:`train_policy` whose weights the new policy starts from (its optimiser starts
            afresh): training in parts, each saved, resumes after the last part saved.
        executor, workers: where the runs of one env fly (:func:`~surrealist_gym.executors.make_executor`: "inline",
            the default, "process" with ``workers`` local processes, or a Dask scheduler's address), one executor for
            the whole training; with ``envs`` above 1 each env flies its runs inline, on its thread.
        **hyper: keyword arguments of the SB3 algorithm, over :func:`algorithm_settings`' defaults.

    Returns:
        The path of the saved policy.

    Raises:
        KeyboardInterrupt: after saving the policy trained so far (Ctrl-C during training); its ``.json`` gives
            ``interrupted_after_steps``, and ``init`` trains on from it.
    """
    import contextlib
    import functools
    import json
    import time

    cls = _sb3(algorithm)
    from stable_baselines3.common.callbacks import BaseCallback

    config = ProblemConfig(problem, budget, runs, spread, seed_test, case_study, obstacles)
    pool = None
    if envs > 1:
        from search.thread_vec_env import ThreadVecEnv

        if executor not in (None, "inline"):
            raise ValueError(f"executor={executor!r}: with envs={envs} each env flies its runs inline, on its thread")
        env = ThreadVecEnv([functools.partial(training_env, config, sim_config, seed + i, "inline")
                            for i in range(envs)])
        env.seed(seed)
    else:
        if executor not in (None, "inline"):  # one pool or client for every problem drawn (each env closes its own)
            from surrealist_gym.executors import SharedExecutor, make_executor

            pool = make_executor(executor, workers)
            executor = SharedExecutor(pool)
        env = training_env(config, sim_config, seed, executor or "inline")
        env.reset(seed=seed)
    hyper = algorithm_settings(algorithm, steps, envs, config.problem, **hyper)
    model = cls("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **hyper)
    if init is not None:
        try:
            model.policy.load_state_dict(load_policy(init, algorithm).state_dict())
        except RuntimeError as err:
            raise SurrealistError(f"{init}: its weights do not fit this problem's policy "
                                  f"({str(err).splitlines()[0]})") from None
    record = TrainingRecord()

    class _Progress(BaseCallback):
        def _on_step(self) -> bool:
            for info, done in zip(self.locals.get("infos", ()), self.locals.get("dones", ())):
                record.add(info, bool(done))
            if progress is not None:
                progress(self.num_timesteps)
            return True

    start = time.perf_counter()
    interrupted = False
    try:
        try:
            model.learn(total_timesteps=int(steps), callback=_Progress())
        except KeyboardInterrupt:  # the policy so far is saved, and --init trains on from it
            interrupted = True
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        model.save(out)
    finally:
        with contextlib.suppress(*(() if not interrupted else (EOFError, OSError))):  # workers Ctrl-C ended
            env.close()
        if pool is not None:
            pool.close()
    path = out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
    settings = {"problem": config.problem.value, "algorithm": Algorithm(algorithm).value, "steps": int(steps),
                "budget": budget, "runs": runs, "seed": seed, "envs": envs,
                "init": None if init is None else str(init),
                "hyper": recorded_settings(hyper)}
    if config.problem is Problem.CASE_STUDY:
        settings.update(case_study=str(case_study), obstacles=obstacles)
    elif config.problem is Problem.MISSIONS:
        settings.update(frame="mission")
    else:
        settings.update(spread=spread, seed_test=None if seed_test is None else str(seed_test))
    summary = {**settings, "policy": path.name, "wall_seconds": round(time.perf_counter() - start, 1),
               "record": record.to_json()}
    if interrupted:
        summary["interrupted_after_steps"] = int(model.num_timesteps)
    path.with_suffix(".json").write_text(json.dumps(summary, indent=2) + "\n")
    if interrupted:
        raise KeyboardInterrupt(f"{path}: trained {model.num_timesteps} of {steps} steps")
    return path


def algorithm_settings(algorithm: Algorithm | str, steps: int, envs: int = 1,
                       problem: Problem | str = Problem.REPLICATE, **overrides) -> dict:
    """The keyword arguments :func:`train_policy` gives the SB3 algorithm: its defaults for ``steps`` env steps on
    ``envs`` envs of ``problem``, then ``overrides``. PPO's suit short runs (``n_steps=64, batch_size=32,
    n_epochs=5``; fewer steps per rollout when ``steps`` is smaller, so a tiny run trains on what it collects).

    The discount follows the problem. A replicate or generate action mutates the current test, so it shapes the
    steps after it: ``gamma=0.95``. A case-study action is the whole layout and its reward depends on it alone, so
    a discount would only add the unrelated rewards of later layouts to each return: ``gamma=0`` (SAC too)."""
    bandit = Problem(problem) in (Problem.CASE_STUDY, Problem.MISSIONS)
    if Algorithm(algorithm) is Algorithm.PPO:
        rollout = max(2, min(64, -(-int(steps) // envs)))
        return {"n_steps": rollout, "batch_size": min(32, rollout * envs), "n_epochs": 5,
                "gamma": 0.0 if bandit else 0.95, **overrides}
    return {"learning_starts": min(100, steps // 4), "buffer_size": 50_000, **({"gamma": 0.0} if bandit else {}),
            **overrides}


def recorded_settings(settings: dict) -> dict:
    """The settings a policy's ``.json`` records (``hyper``): the plain values among them."""
    return {k: v for k, v in settings.items() if isinstance(v, (int, float, str, bool))}
