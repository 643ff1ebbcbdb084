"""Add your own agent: subclass Agent, write _ask (propose actions) and _tell (learn from their fitness).

    python examples/custom_agent.py --budget 10
    surrealist compare --env Surrealist-Generate-v0 --agents greedy,examples/custom_agent.py:HillClimber
"""
import argparse

import numpy as np

from search import Agent


class HillClimber(Agent):
    """(1+1) hill climbing: a Gaussian step around the best action so far."""

    name = "hill-climber"

    def __init__(self, seed=None, sigma=0.2):
        super().__init__(seed)
        self.sigma = sigma

    def _ask(self):
        best_action = self.best[0]                       # the base class tracks the best (action, fitness, info)
        return [np.clip(best_action + self.rng.normal(0, self.sigma, best_action.shape), -1, 1)]

    def _tell(self, actions, fitnesses, infos):
        pass                                             # the base class already kept the best


if __name__ == "__main__":
    import gymnasium as gym

    import surrealist_gym  # noqa: F401 - registers the envs

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=int, default=10)
    args = parser.parse_args()
    env = gym.make("Surrealist-Generate-v0", budget=args.budget, runs=1, executor="inline")
    result = HillClimber(seed=0).run(env)
    print(f"fitness {result.history[0]:.2f} -> {result.best_fitness:.2f} in {result.evaluations} evaluations")
