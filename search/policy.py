"""A trained policy, read safely and rolled out as a search agent (:class:`PPOAgent`).

The trained policy acts deterministically on the env; an action the env answers from its memo (already evaluated) or
rejects as invalid is followed by one sampled from the policy, so the rollout keeps spending the budget.
``sample=True`` samples every action from the policy, as training does: the policy is then a search distribution, not
one answer (on a case study, where failures are many and scattered, that is what finds them). A policy trained on
drawn case studies (``surrealist train --problem missions``) acts in the case study's mission frame
(:mod:`surrealist_gym.competition.mission_frame`), so it searches any case study with any number of boxes; the
package ships one, named ``pretrained`` (``ppo-sample:pretrained``). RL libraries are run-style, so the agent
overrides ``run`` and returns a SearchResult.

Example:
    >>> env = gym.make("Surrealist-CaseStudy-v1", case_study="mission1", obstacles=2, budget=20)   # doctest: +SKIP
    >>> PPOAgent("pretrained", seed=0, sample=True).run(env).best_fitness                        # doctest: +SKIP
"""
from __future__ import annotations

import os
import threading
from enum import Enum
from pathlib import Path

import gymnasium as gym
import numpy as np

from surrealist_gym.errors import DependencyNotInstalled, SurrealistError, regular_file

from .base import Agent, SearchResult


class Algorithm(str, Enum):
    """The stable-baselines3 algorithm (both fit the env's continuous action box)."""

    PPO = "ppo"
    SAC = "sac"


def load_policy(path, algorithm: Algorithm | str = "ppo"):
    """The policy network of a policy file written by :func:`train_policy`, read without running code from it:
    only its weights (``policy.pth``, ``torch.load(weights_only=True)``) go into a freshly built default
    ``MlpPolicy`` whose spaces follow from the weights (one action per mutator, the env's observation). SB3's own
    ``load`` would unpickle the file's other entries, which can carry code."""
    import io
    import pickle
    import zipfile

    try:
        import stable_baselines3  # noqa: F401 - the policy classes below are its
        import torch
    except ImportError as err:
        raise DependencyNotInstalled(f"{path}: a policy needs torch and stable-baselines3: pip install torch==2.13.0 "
                                     f"&& pip install 'surrealist-gym[rl]'") from err

    algorithm = Algorithm(algorithm)
    regular_file(path, "policy file")
    try:
        with zipfile.ZipFile(path) as archive:
            state = torch.load(io.BytesIO(archive.read("policy.pth")), weights_only=True, map_location="cpu")
    except pickle.UnpicklingError:  # torch refuses what is not plain tensors; it is never loaded unsafely
        raise SurrealistError(f"{path}: cannot be loaded safely: its policy.pth holds pickled objects besides "
                              f"tensors (a policy of `surrealist train` holds weights only)") from None
    except (OSError, KeyError, zipfile.BadZipFile, RuntimeError, ValueError, EOFError) as err:
        raise SurrealistError(f"{path}: not a policy file of `surrealist train` ({type(err).__name__})") from None
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise SurrealistError(f"{path}: not a policy file of `surrealist train` (policy.pth holds no weights)")
    first, action = (("mlp_extractor.policy_net.0.weight", "action_net.weight") if algorithm is Algorithm.PPO
                     else ("actor.latent_pi.0.weight", "actor.mu.weight"))
    if first not in state or action not in state:
        raise SurrealistError(f"{path}: not a default {algorithm.value.upper()} MlpPolicy (no {first!r} weights)")
    n_obs, n_act = int(state[first].shape[1]), int(state[action].shape[0])
    observations = gym.spaces.Box(-np.inf, np.inf, shape=(n_obs,), dtype=np.float32)
    actions = gym.spaces.Box(-1.0, 1.0, shape=(n_act,), dtype=np.float32)
    if algorithm is Algorithm.PPO:
        from stable_baselines3.common.policies import ActorCriticPolicy as policy_class
    else:
        from stable_baselines3.sac.policies import SACPolicy as policy_class
    policy = policy_class(observations, actions, lambda _: 0.0)
    try:
        policy.load_state_dict(state)
    except RuntimeError as err:
        raise SurrealistError(f"{path}: weights do not fit a default {algorithm.value.upper()} MlpPolicy "
                              f"({str(err).splitlines()[0]})") from None
    policy.set_training_mode(False)
    return policy


PRETRAINED = "pretrained"  # ppo:pretrained, ppo-sample:pretrained: the policy for every mission that ships


def pretrained_policy(path):
    """The shipped policy's file for the name ``pretrained``; any other path as given."""
    if str(path) != PRETRAINED:
        return path
    from surrealist_gym import data_path

    return data_path("policies/ppo-missions.zip")


def policy_frame(path) -> str | None:
    """The frame a policy file acts in, from its record beside it (``frame``; None: the env's own action)."""
    import json

    record = Path(path).with_suffix(".json")
    try:
        return json.loads(record.read_text()).get("frame") if record.is_file() else None
    except (OSError, ValueError, AttributeError):
        return None


_TORCH_RNG = threading.Lock()  # searches run in threads (compare --parallel) share torch's global generator


class PPOAgent(Agent):
    """A trained stable-baselines3 policy (PPO by default, or SAC) rolled out as a search agent."""

    name = "ppo"

    def __init__(self, policy, seed: int | None = None, algorithm: Algorithm | str = "ppo", sample: bool = False,
                 frame: str | None = None):
        super().__init__(seed)
        self.algorithm = Algorithm(algorithm)
        self.sample = bool(sample)
        self.name = self.algorithm.value + ("-sample" if self.sample else "")
        if isinstance(policy, (str, os.PathLike)):
            policy = pretrained_policy(policy)
            if not Path(policy).is_file():
                raise SurrealistError(f"{policy}: no such policy file (train one with `surrealist train`)")
            self.policy_path = str(policy)
            frame = frame or policy_frame(policy)
            policy = load_policy(self.policy_path, self.algorithm)
        if frame not in (None, "mission"):
            raise SurrealistError(f"policy frame {frame!r}: expected none or 'mission'")
        self.frame_kind = frame  # "mission": the policy acts in the case study's mission frame (any mission)
        self.model = policy
        self._frame = None
        self._obs = None
        self._explore = False

    def _ask(self) -> list[np.ndarray]:
        obs = self._obs if self._frame is None else self._frame.observe(self._env)
        if not (self._explore or self.sample):
            action, _ = self.model.predict(obs, deterministic=True)
        else:  # sample with torch's global generator, seeded from this agent's: reproducible beside other threads
            import torch
            with _TORCH_RNG:
                torch.manual_seed(int(self.rng.integers(2**31 - 1)))
                action, _ = self.model.predict(obs, deterministic=False)
        action = np.asarray(action, dtype=np.float64).reshape(-1)
        return [action if self._frame is None else self._frame.env_action(action)]

    def _tell(self, actions, fitnesses, infos) -> None:
        self._explore = bool(infos) and (bool(infos[-1].get("memo")) or infos[-1].get("invalid") is not None)

    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Roll the policy out on ``env`` until its budget is spent."""
        self._frame = self._mission_frame(env) if self.frame_kind == "mission" else None
        expected = self.model.action_space.shape
        if self._frame is None and env.action_space.shape != expected:
            raise SurrealistError(f"policy {getattr(self, 'policy_path', '')}: trained for {expected[0]} mutators, "
                                  f"the env has {env.action_space.shape[0]}")
        self._obs, info = env.reset(seed=seed)  # the episode's noise: seed, else the env's own (random_seed)
        self._explore = False
        self.setup(env, info)
        done = False
        while not done:
            actions = self.ask()
            self._obs, reward, terminated, truncated, step_info = env.step(actions[0])
            if callback is not None:
                callback(step_info)
            done = terminated or truncated
            if done:
                self._stop_reason = "budget spent" if self._env.budget_left <= 0 else "episode ended"
            self.tell(actions, [reward], [step_info])
        return self.result

    def _mission_frame(self, env):
        """The mission frame of a case-study env, for a policy trained on drawn case studies."""
        from surrealist_gym.competition.mission_frame import FIELDS_PER_BOX, MissionFrame

        inner = env.unwrapped
        where = getattr(self, "policy_path", "")
        if not hasattr(inner, "case_study"):
            raise SurrealistError(f"policy {where}: trained on drawn case studies, it searches a competition case "
                                  f"study (generate --case-study, Surrealist-CaseStudy-v1), not {type(inner).__name__}")
        boxes = len(inner.seed_test.obstacles)
        if env.action_space.shape != (FIELDS_PER_BOX * boxes,):
            raise SurrealistError(f"policy {where}: it places boxes only (x, y, l, w, h, r of each); this env also "
                                  f"mutates {env.action_space.shape[0] - FIELDS_PER_BOX * boxes} other properties "
                                  f"(wind?)")
        return MissionFrame.of(env)
