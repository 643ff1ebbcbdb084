"""Train a PPO policy across procedurally generated replication problems, then use it as a search agent.

Each training episode draws a hidden obstacle layout near the case0 seed box; our simulator flies it once and that
flight plays the real one. The trained policy then searches the real log (case0.ulg, seed 1).

    python examples/train_ppo.py --steps 3000          # a few minutes on one core
    python examples/train_ppo.py --steps 16 --budget 3  # CI
"""
import argparse

import gymnasium as gym

import surrealist_gym  # noqa: F401 - registers the envs
from search import PPOAgent, train_policy

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--steps", type=int, default=3000, help="training steps (evaluations)")
parser.add_argument("--budget", type=int, default=20, help="evaluations of the final search on the real log")
parser.add_argument("--policy", default="results/ppo-example.zip", help="the policy file to write")
args = parser.parse_args()

small = {"n_steps": 8, "batch_size": 8} if args.steps < 64 else {}
path = train_policy(args.steps, args.policy, problem="replicate", budget=15, runs=1, seed=0, **small)
print(f"policy saved to {path}")
env = gym.make("Surrealist-Replicate-v0", budget=args.budget, runs=1, executor="inline")
result = PPOAgent(path, seed=0).run(env)
print(f"on case0: fitness {result.history[0]:.1f} -> {result.best_fitness:.1f} "
      f"after {result.evaluations_to_best} of {result.evaluations} evaluations")
