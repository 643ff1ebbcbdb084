"""Action spaces in which every point flies: the decoding ``gym.make`` gives the registered envs.

The core envs keep the paper's semantics: an action whose test is invalid (a non-positive size, overlapping boxes,
a rule broken, a mission walled off) is not flown and scores a penalty, as the adaptive greedy expects. A learner or
``action_space.sample()`` meets such actions most of the time (a replication's resizes reach below zero, the case
study's three boxes overlap), so :class:`FlyableActions` projects each action onto the flyable tests instead:

1. each component is clipped to ``env.action_bounds()`` (the part of its range that keeps every box a valid size);
2. if the test is still invalid, the action is moved back toward the seed's (``env.seed_action``, always flyable)
   along the line between them, to the last flyable point that bisection finds (:data:`BISECTIONS` halvings).

A flyable action is flown unchanged, so the wrapper changes nothing for an agent that proposes valid tests, and the
search API (``values_for``, ``test_for``, ...) is the env's. ``info["action"]`` is the action flown and
``info["repaired"]`` whether it differs from the one given. ``gym.make(id, flyable=False)`` gives the bare env.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidTestCase
from .generate import GenerateEnv
from .replicate import ReplicateEnv
from .wrapper import SurrealistWrapper

BISECTIONS = 12  # halvings of the way back to the seed: the flown action is within 2^-12 of the last flyable one


class FlyableActions(SurrealistWrapper):
    """Fly the flyable test nearest each action (see the module); no step is refused."""

    def __init__(self, env):
        super().__init__(env)
        self._bounds = self.inner.action_bounds()  # of the seed test and the mutators, which an env never changes

    @property
    def spec(self):
        """The registered env's spec: this wrapper is part of its entry point, not a wrapper added to it (and the
        spec is not deep-copied, so an executor among its keyword arguments, e.g. a Dask client, stays as given)."""
        return self.env.spec

    def repair(self, action) -> np.ndarray:
        """The action flown for ``action``: itself when its test is flyable, else its projection (module doc)."""
        low, high = self._bounds
        wanted = np.clip(np.asarray(action, dtype=np.float64).reshape(-1), low, high)
        if self.flies(wanted):
            return wanted
        seed = np.asarray(self.inner.seed_action, dtype=np.float64)
        near, far = 0.0, 1.0
        for _ in range(BISECTIONS):
            middle = (near + far) / 2
            if self.flies(seed + middle * (wanted - seed)):
                near = middle
            else:
                far = middle
        return seed + near * (wanted - seed)

    def step(self, action):
        """Step the env with the repaired action."""
        given = np.clip(np.asarray(action, dtype=np.float64).reshape(-1), -1.0, 1.0)
        flown = self.repair(given)
        obs, reward, terminated, truncated, info = self.env.step(flown)
        info["action"], info["repaired"] = flown, not np.array_equal(flown, given)
        return obs, reward, terminated, truncated, info

    def flies(self, action) -> bool:
        """Whether the bare env flies ``action`` as it is (its test is valid), rather than refusing it."""
        try:
            self.inner.test_for(action)
        except InvalidTestCase:
            return False
        return True


def maker(env_class):
    """A ``gym.make`` entry point: ``env_class`` wrapped in :class:`FlyableActions` unless ``flyable=False``."""

    def make(flyable: bool = True, **kwargs):
        env = env_class(**kwargs)
        return FlyableActions(env) if flyable else env

    make.__name__ = make.__qualname__ = env_class.__name__
    make.metadata = env_class.metadata  # what gym.make reads the render modes from
    make.__doc__ = (f"A {env_class.__name__}, its actions made flyable (:class:`FlyableActions`) unless "
                    f"``flyable=False``.")
    return make


replicate = maker(ReplicateEnv)  # Surrealist-Replicate-v0's entry point
generate = maker(GenerateEnv)  # Surrealist-Generate-v0's
