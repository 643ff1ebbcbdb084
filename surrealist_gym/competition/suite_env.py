"""A wrapper that keeps a suite of distinct failures from every test a search flies
(:mod:`surrealist_gym.competition.suite`).

Any agent searches through it unchanged: it forwards the search API and charges nothing, it only offers each newly
evaluated test (not memo answers) to its :class:`~surrealist_gym.competition.suite.Suite` and notes the answer in
``info["suite"]`` (``added``, ``replaced N``, ``alike N``, ``passed``).

Example::

    env = RecordSuite(gym.make("Surrealist-CaseStudy-v1", case_study="mission2"))
    AdaptiveGreedy().run(env)
    env.suite.members        # the distinct failures found
"""
from __future__ import annotations

from ..envs.wrapper import SurrealistWrapper
from .suite import Member, Suite


class RecordSuite(SurrealistWrapper):
    """Keep the distinct failures of every evaluation in ``self.suite``."""

    def __init__(self, env, suite: Suite | None = None):
        super().__init__(env)
        self.suite = suite if suite is not None else Suite()

    def reset(self, **kwargs):
        """Reset the env and offer the seed's evaluation to the suite."""
        obs, info = self.env.reset(**kwargs)
        self._offer(info)
        return obs, info

    def step(self, action):
        """Step the env and offer the evaluated test to the suite."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._offer(info)
        return obs, reward, terminated, truncated, info

    def _offer(self, info: dict) -> None:
        if info.get("test") is None or info.get("memo") or info.get("trajectory") is None:
            return
        k = int(info.get("terms", {}).get("riskiest", 0))
        distances, statuses = info.get("competition_distances", ()), info.get("statuses", ())
        if k >= len(distances):
            return
        member = Member(info["test"], float(distances[k]), info["trajectory"], int(info["evaluations"]),
                        str(statuses[k]))
        self.suite, info["suite"] = self.suite.offer(member)
