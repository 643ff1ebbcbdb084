"""An env whose problem is drawn anew at every reset: what a policy that transfers trains on.

A subclass draws the problem (:meth:`DrawnProblems._draw`, from ``self.np_random``) as an env of its own, which then
answers ``reset`` and every ``step`` until the next reset draws another; ``close`` closes it. ``random_seed`` seeds
the draws of the first reset that is given no seed. Subclasses: the paper's drawn problems
(:class:`search.rl.ProceduralEnv`) and the drawn case studies
(:class:`~surrealist_gym.competition.missions.MissionCaseStudies`).
"""
from __future__ import annotations

import gymnasium as gym


class DrawnProblems(gym.Env):
    """A Gymnasium env that draws its problem (an inner env) at every reset."""

    metadata = {"render_modes": []}
    inner: gym.Env | None = None
    random_seed: int | None = None  # the draws' seed of a first reset given none (None: fresh entropy)
    _seeded = False

    def _draw(self) -> gym.Env:
        """A new problem, drawn from ``self.np_random``."""
        raise NotImplementedError

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Close the current problem, draw a new one and reset it; its (observation, info)."""
        super().reset(seed=self.random_seed if seed is None and not self._seeded else seed)
        self._seeded = True
        self.close()
        self.inner = self._draw()
        return self.inner.reset()

    def step(self, action):
        """One step of the current problem."""
        return self.inner.step(action)

    def close(self):
        """Close the current problem's env, if any."""
        if self.inner is not None:
            self.inner.close()
            self.inner = None
