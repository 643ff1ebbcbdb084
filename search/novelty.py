"""Suite search: the default generator of suites of distinct failures (``surrealist generate --case-study``).

Random search finds failures; the suite needs many distinct ones that fail again when re-flown. So the agent mixes
uniform samples (exploration: ``explore`` of the asks, and every ask until something failed) with mutations of earlier
failures (exploitation). A parent is drawn with a weight that falls with the children it already had, so the search
spreads over many failures instead of polishing one. A child moves each mutator with probability ``rate`` by a Gaussian
step of ``sigma`` (in action units: 1 is half a mutator's range). A child alike to its parent that comes closer replaces
it in the suite (:class:`~surrealist_gym.competition.suite_env.RecordSuite`); one that differs enough becomes a new
member. The agent reads the competition distance and the status of each run from ``info`` and nothing else.

Only failures are parents (``near_m``): near misses made no better parents than uniform samples
(``benchmarks/lab/2026-11-24-suites/``).

Example:
    >>> import gymnasium as gym, surrealist_gym                                # doctest: +SKIP
    >>> env = gym.make("Surrealist-CaseStudy-v1", case_study="mission2")    # doctest: +SKIP
    >>> SuiteSearch(seed=0).run(env).best_fitness                            # doctest: +SKIP
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from surrealist_gym.outcomes import UNSAFE_DISTANCE_M

from .base import Agent


@dataclass(frozen=True, slots=True)
class SuiteSearchConfig:
    """Hyper-parameters of the suite search.

    Attributes:
        explore: share of asks answered with a uniform sample once parents exist.
        near_m: a test whose closest run came within this distance [m] (or collided) can be a parent; the
            competition's soft-failure distance by default.
        sigma: mutation step, in action units (1 = half a mutator's range; on the case study's rules box, 0.2 is a
            tenth of the rule's width, the step the suite search has always taken there: 7 m in x, 3 m in y).
        rate: probability that a mutator is moved in a child.
    """

    explore: float = 0.4
    near_m: float = UNSAFE_DISTANCE_M
    sigma: float = 0.2
    rate: float = 0.35

    def __post_init__(self):
        if not 0 <= self.explore <= 1:
            raise ValueError(f"explore: expected a share in [0, 1], got {self.explore}")
        if not (self.near_m > 0 and self.sigma > 0 and 0 < self.rate <= 1):
            raise ValueError("near_m and sigma must be > 0, rate in (0, 1]")


class SuiteSearch(Agent):
    """Uniform exploration plus mutation of near misses and failures, spread over many parents."""

    name = "suite"

    def __init__(self, config: SuiteSearchConfig | None = None, seed: int | None = None, **overrides):
        super().__init__(seed)
        self.config = SuiteSearchConfig(**overrides) if config is None else config

    def _setup(self, info: dict) -> None:
        self._low, self._high = self._env.action_bounds()
        self._parents: list[list] = []  # [action, closest distance, children]
        self._consider(np.array(self._env.seed_action, dtype=np.float64), info)

    def _ask(self) -> list[np.ndarray]:
        c = self.config
        if not self._parents or self.rng.random() < c.explore:
            return [self.rng.uniform(self._low, self._high)]
        weights = np.array([1.0 / (1.0 + n) ** 2 for _, _, n in self._parents])
        parent = self._parents[int(self.rng.choice(len(self._parents), p=weights / weights.sum()))]
        parent[2] += 1
        moved = self.rng.random(len(self._low)) < c.rate
        moved[self.rng.integers(len(moved))] = True
        child = parent[0] + moved * self.rng.normal(0.0, c.sigma, len(self._low))
        return [np.clip(child, self._low, self._high)]

    def _tell(self, actions, fitnesses, infos) -> None:
        for action, info in zip(actions, infos):
            self._consider(action, info)

    def _consider(self, action, info: dict) -> None:
        if info.get("invalid") or info.get("memo"):
            return
        distances = [d for d in info.get("competition_distances", ()) if math.isfinite(d)]
        crashed = "collision" in info.get("statuses", ())
        closest = 0.0 if crashed else min(distances, default=math.inf)
        if closest < self.config.near_m:
            self._parents.append([np.asarray(action, dtype=np.float64), closest, 0])
