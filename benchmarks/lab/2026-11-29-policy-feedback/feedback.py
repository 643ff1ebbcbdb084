"""Does the missions policy learn more when it sees what its search has found? (README beside this file.)

    python benchmarks/lab/2026-11-29-policy-feedback/feedback.py train STEPS OUT.zip
    python benchmarks/lab/2026-11-29-policy-feedback/feedback.py eval POLICY.zip fb|plain [MISSION BOXES BUDGET]

``train``: PPO (the shipped recipe: gamma 0, 2 envs, n_steps 64, batch 32, 5 epochs, learning rate 1e-3) on drawn
case studies whose observation also holds the search's feedback (:class:`Feedback`), warm-started from the shipped
policy (its weights, zero weights for the new inputs: it starts acting as the shipped policy does).
``eval``: 5 searches (seeds 300-304) of MISSION (a case study, or bench_rl's ``drawn`` / ``drawn-calm``) with BOXES
boxes and BUDGET single-run evaluations; soft failures per simulation and distinct failures.
"""
import functools
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[3]
SHIPPED = ROOT / "surrealist_gym" / "data" / "policies" / "ppo-missions.zip"
ACTION_SIZE = 18
FEEDBACK_SIZE = ACTION_SIZE + 3  # the best frame action so far, its fitness / 5, the last fitness / 5, any yet


class Feedback(gym.Wrapper):
    """A frame env (MissionFrameEnv, or MissionCaseStudies) whose observation also holds the search's feedback."""

    def __init__(self, env):
        super().__init__(env)
        size = env.observation_space.shape[0] + FEEDBACK_SIZE
        self.observation_space = gym.spaces.Box(-5.0, 5.0, shape=(size,), dtype=np.float32)
        self.best_action, self.best_fitness, self.last_fitness = None, 0.0, 0.0

    def _observation(self, obs):
        found = self.best_action is not None
        best = self.best_action if found else np.zeros(ACTION_SIZE)
        feedback = [self.best_fitness / 5 if found else 0.0, self.last_fitness / 5, float(found)]
        return np.clip(np.concatenate([obs, best, feedback]), -5, 5).astype(np.float32)

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.best_action, self.best_fitness, self.last_fitness = None, 0.0, 0.0
        return self._observation(obs), info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        if not info.get("invalid"):
            self.last_fitness = float(reward)
            if self.best_action is None or reward > self.best_fitness:
                self.best_action = np.clip(np.asarray(action, dtype=np.float64), -1, 1)
                self.best_fitness = float(reward)
        return self._observation(obs), reward, terminated, truncated, info


def drawn_with_feedback(seed: int):
    """A training env: drawn case studies (15 evaluations an episode) with the feedback."""
    from surrealist_gym.competition.missions import MissionCaseStudies

    return Feedback(MissionCaseStudies(budget=15, runs=1, random_seed=seed, executor="inline"))


def train(steps: int, out: str) -> None:
    """Warm-start from the shipped policy and train ``steps`` steps; saved to ``out``."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import SubprocVecEnv

    env = SubprocVecEnv([functools.partial(drawn_with_feedback, 500 + i) for i in range(2)])
    shipped = PPO.load(SHIPPED, device="cpu").policy.state_dict()
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=5, gamma=0.0, learning_rate=1e-3, seed=0,
                device="cpu")
    weights = model.policy.state_dict()
    for key, value in weights.items():
        if value.shape == shipped[key].shape:
            weights[key] = shipped[key].clone()
        else:  # a first layer: the shipped columns, zeros for the feedback's
            padded = torch.zeros_like(value)
            padded[:, :shipped[key].shape[1]] = shipped[key]
            weights[key] = padded
    model.policy.load_state_dict(weights)
    start = time.time()
    model.learn(total_timesteps=steps)
    model.save(out)
    env.close()
    print(f"trained {steps} steps in {time.time() - start:.0f} s: {out}", flush=True)


def evaluate(policy: str, feedback: bool, mission: str, boxes: int, budget: int) -> tuple[list, list]:
    """Soft failures per simulation and distinct failures of 5 searches (seeds 300-304)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_rl import case_study
    from stable_baselines3 import PPO

    from search.rl import TrainingRecord
    from surrealist_gym.competition.case_study_env import CaseStudyEnv
    from surrealist_gym.competition.mission_frame import MissionFrameEnv
    from surrealist_gym.competition.suite_env import RecordSuite

    model = PPO.load(policy, device="cpu")
    rates, distinct = [], []
    for seed in range(300, 305):
        suite = RecordSuite(CaseStudyEnv(case_study(mission, seed), obstacles=boxes, budget=budget, runs=1,
                                         random_seed=seed, executor="inline"))
        env = Feedback(MissionFrameEnv(suite)) if feedback else MissionFrameEnv(suite)
        torch.manual_seed(seed)
        obs, _ = env.reset(seed=seed)
        record, done = TrainingRecord(), False
        while not done:
            action, _ = model.predict(obs, deterministic=False)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
            record.add(info, done)
        rates.append(record.soft_failures / max(1, record.simulations))
        distinct.append(sum(m.evaluation > 1 for m in suite.suite.members))
        env.close()
    return rates, distinct


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    if argv[0] == "train":
        train(int(argv[1]), argv[2])
        return 0
    policy, kind = argv[1], argv[2]
    mission, boxes, budget = (argv[3], int(argv[4]), int(argv[5])) if len(argv) > 5 else ("drawn-calm", 2, 30)
    rates, distinct = evaluate(policy, kind == "fb", mission, boxes, budget)
    print(f"{mission}, {boxes} boxes, budget {budget}: {Path(policy).name} ({kind}): soft failures per simulation "
          f"{np.mean(rates):.3f} ± {np.std(rates, ddof=1):.3f} {np.round(rates, 3).tolist()}; distinct failures "
          f"{np.mean(distinct):.1f} {distinct}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
