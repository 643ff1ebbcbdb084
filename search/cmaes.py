"""CMA-ES (pycma) over the action vector within ``env.action_bounds()``, started at the seed test (``env.seed_action``).

``ask`` is pycma's ``ask`` (a population of candidate actions within the bounds), ``tell`` is pycma's ``tell``
on the negated fitness (pycma minimises). An invalid test comes back from the env with its penalty fitness. When
pycma's own stopping criteria fire, the search restarts from a random point (drawn from the agent's seed) until the
env's budget is spent; with ``restarts=False`` the agent stops instead.

Example:
    >>> import gymnasium as gym, surrealist_gym                                # doctest: +SKIP
    >>> env = gym.make("Surrealist-Generate-v0", budget=20, runs=1)          # doctest: +SKIP
    >>> CMAES(seed=0).run(env).best_fitness                                  # doctest: +SKIP
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrealist_gym.errors import DependencyNotInstalled

from .base import Agent


@dataclass(frozen=True, slots=True)
class CMAESConfig:
    """Hyper-parameters of CMA-ES.

    Attributes:
        sigma0: initial step size, in action units (1 = half a mutator's range).
        popsize: population per generation; None = pycma's default ``4 + 3 ln(n)``.
        restarts: restart from a random point when pycma stops (else the agent stops).
    """

    sigma0: float = 0.3
    popsize: int | None = None
    restarts: bool = True

    def __post_init__(self):
        if not self.sigma0 > 0:
            raise ValueError(f"sigma0: expected > 0, got {self.sigma0}")
        if self.popsize is not None and self.popsize < 2:
            raise ValueError(f"popsize: expected >= 2 or None, got {self.popsize}")


class CMAES(Agent):
    """Covariance Matrix Adaptation Evolution Strategy (pycma) as an ask/tell agent."""

    name = "cmaes"

    def __init__(self, config: CMAESConfig | None = None, seed: int | None = None, **overrides):
        super().__init__(seed)
        self.config = CMAESConfig(**overrides) if config is None else config
        self.restarts = 0

    def _setup(self, info: dict) -> None:
        self.restarts = 0
        self._low, self._high = self._env.action_bounds()
        self._es = self._new_es(np.array(self._env.seed_action, dtype=np.float64))

    def _new_es(self, x0: np.ndarray):
        try:
            import cma
        except ImportError as err:
            raise DependencyNotInstalled("the CMA-ES agent needs pycma: pip install cma") from err
        options = {"bounds": [list(self._low), list(self._high)], "seed": int(self.rng.integers(1, 2**31 - 1)),
                   "verbose": -9, "verb_log": 0, "verb_disp": 0}
        if self.config.popsize is not None:
            options["popsize"] = self.config.popsize
        if len(x0) < 2:
            raise ValueError(f"CMA-ES needs at least two mutators, the env has {len(x0)}")
        return cma.CMAEvolutionStrategy(x0, self.config.sigma0, options)

    def _ask(self) -> list[np.ndarray]:
        if self._es.stop():
            if not self.config.restarts:
                self._finish("cma: " + ", ".join(sorted(self._es.stop())))
                return []
            self.restarts += 1
            self._es = self._new_es(self.rng.uniform(self._low, self._high))
        return [np.clip(np.asarray(x, dtype=np.float64), self._low, self._high) for x in self._es.ask()]

    def _tell(self, actions, fitnesses, infos) -> None:
        if len(actions) == self._es.popsize:  # a prefix: the budget ran out
            self._es.tell([np.asarray(a) for a in actions], [-float(f) for f in fitnesses])
