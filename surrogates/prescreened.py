"""A search through a :class:`~surrogates.prescreen.Prescreener`: any agent's ask -> evaluate -> tell loop, its
restart policy (:class:`VerifyStop`) and what it found (a :class:`~search.base.SearchResult`).

:class:`Prescreened` runs like an agent (``run(env, seed, callback) -> SearchResult``) but is not one: it drives the
agent it is given, whose candidates go through the prescreener between its ask and its tell. The result counts real
evaluations only (``history`` holds the fitness of each step on the env). :func:`wrap` is what the command line runs.

Example:
    >>> import gymnasium as gym, surrealist_gym
    >>> from search import AdaptiveGreedy
    >>> env = gym.make("Surrealist-Generate-v0", budget=4, runs=1, executor="inline")
    >>> result = Prescreened(AdaptiveGreedy("paper", seed=0), "online", seed=0).run(env, seed=0)
    >>> result.evaluations <= 4
    True
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from search.base import Agent, SearchLog, SearchResult
from surrealist_gym.errors import SurrealistError

from .config import PrescreenConfig
from .dataset import Featurizer
from .models import SurrogateModel
from .prescreen import Prescreener


class VerifyStop:
    """The restart policy of ``PrescreenConfig.verify_stop``: the first time the agent stops with budget left, it
    starts again from the best evaluation with screening and racing off (tests simulated before are memo answers and
    cost nothing), so a stop the skips may have caused is checked by simulation.

    Args:
        enabled: the policy is on (else :meth:`restart` never restarts).
    """

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.verified_at: int | None = None  #: real evaluations when the unscreened restart began

    def restart(self, agent: Agent, prescreener: Prescreener, info: dict, record: SearchLog) -> bool:
        """Restart ``agent`` (``info``: the episode's reset info) from the best of ``record`` if due; True when it
        goes on."""
        if not self.enabled or self.verified_at is not None or prescreener.env.budget_left <= 0:
            return False
        self.verified_at = record.evaluations
        prescreener.stop_screening()
        agent.setup(prescreener.env, info, start=record.best)  # the env's own budget: what screening saved
        return not agent.stop()


class Prescreened:
    """Run ``agent`` with only the candidates worth a simulation simulated: ask, evaluate through a
    :class:`~surrogates.prescreen.Prescreener`, tell, until the env's budget is spent or the agent stops (and, with
    ``verify_stop``, stops again after its unscreened restart).

    Args:
        agent: the agent (any :class:`~search.base.Agent`).
        model: a trained :class:`~surrogates.models.SurrogateModel`, the path of a saved one, or ``"online"``.
        config: a :class:`~surrogates.config.PrescreenConfig`.
        seed: seed of the search (the env's reset) and of the model's training; None: the agent's.
    """

    def __init__(self, agent: Agent, model: SurrogateModel | str | Path = "online",
                 config: PrescreenConfig | None = None, seed: int | None = None):
        self.agent = agent  #: the agent whose candidates are pre-screened
        self.seed = seed if seed is not None else agent.seed
        self.name = f"{agent.name}+prescreen"
        self.prescreener = Prescreener(model, config, self.seed)
        self.verify = VerifyStop(self.prescreener.config.verify_stop)

    @property
    def verified_at(self) -> int | None:
        """Real evaluations when the unscreened restart began (None: no restart)."""
        return self.verify.verified_at

    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Search on ``env`` until the agent stops or the budget is spent; ``callback`` gets the info of every step
        on the env."""
        prescreener, agent = self.prescreener, self.agent
        _, info = env.reset(seed=seed)  # the episode's noise: seed, else the env's own (random_seed)
        prescreener.start(env, info)
        agent.setup(prescreener.agent_env, info)
        record = SearchLog(prescreener.env, agent.best, info)
        self.verify = VerifyStop(prescreener.config.verify_stop)
        while not (reason := self._stop(info, record)):
            actions = agent.ask()
            batch = prescreener.evaluate(actions, callback)
            record.add(batch.stepped)
            agent.tell(actions[:len(batch.fitnesses)], batch.fitnesses, batch.infos)
        return record.result(reason["reason"])

    def _stop(self, info: dict, record: SearchLog) -> dict:
        """The prescreener's stop, else the agent's; an agent's stop may restart it instead (:class:`VerifyStop`:
        a restart goes on only when the agent does, with screening off, so neither stop holds then)."""
        prescreener = self.prescreener
        reason = prescreener.stop() or self.agent.stop()
        if reason and not prescreener.over and self.verify.restart(self.agent, prescreener, info, record):
            return {}
        return reason


def wrap(agent: Agent, spec: str | Path | None, env=None, config: PrescreenConfig | None = None):
    """What the command line runs for ``--surrogate SPEC``: ``agent`` itself when SPEC is empty, else
    ``Prescreened(agent, SPEC)`` (SPEC ``online`` or a model folder from ``surrealist surrogate train``).

    A pre-trained model must have been trained for the env's problem: its featurizer's mission path must match
    the env's seed test (checked when ``env`` is given).
    """
    if not spec:
        return agent
    model = "online" if str(spec) == "online" else SurrogateModel.load(spec)
    if env is not None and isinstance(model, SurrogateModel):
        ours, theirs = Featurizer.for_env(env).path, model.featurizer.path
        if ours.shape != theirs.shape or not np.allclose(ours, theirs, atol=0.5):
            raise SurrealistError(f"{spec}: the model was trained on another mission (path {theirs.round(1).tolist()}"
                                  f", this problem's is {ours.round(1).tolist()})")
    return Prescreened(agent, model, config)


__all__ = ["Prescreened", "VerifyStop", "wrap"]
