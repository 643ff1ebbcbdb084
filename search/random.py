"""Random search: uniform mutator values within each mutator's valid range (``env.action_bounds()``).

The baseline that the UAV Testing Competition's 2025 winner was built on. Each ``ask`` proposes a batch of
independent uniform vectors drawn from the agent's seeded generator; ``tell`` learns nothing.

Example:
    >>> import gymnasium as gym, surrealist_gym                                # doctest: +SKIP
    >>> env = gym.make("Surrealist-Generate-v0", budget=10, runs=1)          # doctest: +SKIP
    >>> RandomSearch(seed=0).run(env).best_fitness                           # doctest: +SKIP
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Agent


@dataclass(frozen=True, slots=True)
class RandomConfig:
    """Hyper-parameters of random search.

    Attributes:
        batch: actions proposed per ``ask`` (the env evaluates them in order).
    """

    batch: int = 1

    def __post_init__(self):
        if self.batch < 1:
            raise ValueError(f"batch: expected >= 1, got {self.batch}")


class RandomSearch(Agent):
    """Uniform random search over the env's action box."""

    name = "random"

    def __init__(self, config: RandomConfig | None = None, seed: int | None = None, **overrides):
        super().__init__(seed)
        self.config = RandomConfig(**overrides) if config is None else config

    def _setup(self, info: dict) -> None:
        self._low, self._high = self._env.action_bounds()

    def _ask(self) -> list[np.ndarray]:
        return [self.rng.uniform(self._low, self._high) for _ in range(self.config.batch)]

    def _tell(self, actions, fitnesses, infos) -> None:
        pass
