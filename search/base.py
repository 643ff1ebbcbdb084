"""The agent interface: ask/tell, and the one ``run`` built on them.

An agent proposes actions for a Surrealist env: an action is a vector with one value per mutator of the env
(``env.unwrapped.mutators``), the mutation of the env's seed test; the seed itself is ``env.seed_action`` (0 in the
paper's envs, the seed's place in the rules' box in the case study's). The env owns the budget, the memo and the
fitness, so every agent is measured the same way; an agent binds to the env's outermost Surrealist layer
(:func:`~surrealist_gym.envs.wrapper.search_layer`), so a wrapper that changes what is charged applies to it.
Subclasses implement ``_setup``, ``_ask`` and ``_tell``; RL agents, whose libraries are run-style, override ``run``
and return the same :class:`SearchResult`. What sits between ask and tell without being an agent (pre-screening:
:class:`surrogates.prescreen.Prescreener`) drives the public verbs and leaves them as they are.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np


@dataclass(frozen=True, slots=True)
class SearchResult:
    """What a search found: the best action (mutation vector), its fitness and test, and the cost to find it."""

    best_action: np.ndarray
    best_fitness: float
    best_info: dict
    evaluations: int             # evaluations that cost budget (simulated), in total
    evaluations_to_best: int     # evaluations spent until the best was found (the paper's "needed budget")
    history: tuple[float, ...] = field(default=())  # fitness of every step, in order
    stop_reason: str = ""
    simulations: int = 0         # runs the search simulated, as the env layer it searched through counts them


class SearchLog:
    """The bookkeeping of one search as the env saw it: the best evaluation, the evaluations spent (in all and until
    the best), and the fitness of every step in the order stepped. What an agent and a loop that drives one
    (:class:`surrogates.prescreened.Prescreened`) keep alike.

    Args:
        env: the Surrealist layer searched through (it counts the simulations).
        start: where the search starts, as (action, fitness, info): the seed test, or the test a restart begins at.
        info: the episode's reset info.
    """

    def __init__(self, env, start: tuple[np.ndarray, float, dict], info: dict):
        self.env = env
        action, fitness, start_info = start
        self.best = (np.array(action, dtype=np.float64), float(fitness), start_info)
        self.evaluations = int(info.get("evaluations", 1))
        self.evaluations_to_best = self.evaluations
        self.history = [self.best[1]]

    def add(self, stepped) -> None:
        """Record steps, as (action, fitness, info), in the order stepped."""
        for action, fitness, info in stepped:
            self.history.append(float(fitness))
            count = int(info.get("evaluations", self.evaluations))
            self.evaluations = max(self.evaluations, count)  # never decreases, whatever order results are told in
            if fitness > self.best[1]:
                self.best = (np.asarray(action, dtype=np.float64), float(fitness), info)
                self.evaluations_to_best = count

    def result(self, stop_reason: str) -> SearchResult:
        """The :class:`SearchResult` of the search so far."""
        action, fitness, info = self.best
        return SearchResult(action, fitness, info, self.evaluations, self.evaluations_to_best, tuple(self.history),
                            stop_reason, int(self.env.simulations))


class Agent(ABC):
    """Base class of every search agent (ask/tell; ``run`` drives an env with them)."""

    name = "agent"

    def __init__(self, seed: int | None = None):
        self.seed = seed
        self._pending: list[np.ndarray] | None = None
        self._env = None
        self._log: SearchLog | None = None
        self._stop_reason = ""

    # --- public verbs: bookkeeping, then the subclass hook ------------------------------------------------------
    def setup(self, env, info: dict, start: tuple | None = None) -> None:
        """Bind to an env just reset; ``info`` is the reset info (it carries the seed test's fitness). ``start``
        (action, fitness, info) begins the search from an evaluated test instead of the seed test (a restart)."""
        from surrealist_gym.envs.wrapper import search_layer

        self._env = search_layer(env)
        self.rng = np.random.default_rng(self.seed)
        seed = np.array(self._env.seed_action, dtype=np.float64)
        self._log = SearchLog(self._env, (seed, info["fitness"], info) if start is None else start, info)
        self._stop_reason = ""
        self._pending = None
        self._setup(info)

    def ask(self) -> list[np.ndarray]:
        """The next actions to evaluate (one or more)."""
        if self._env is None:
            raise RuntimeError("call setup(env, info) (or run) before ask()")
        if self._pending is not None:
            raise RuntimeError("ask() called twice without tell()")
        actions = [np.asarray(a, dtype=np.float64) for a in self._ask()]
        self._pending = actions
        return actions

    def tell(self, actions: Sequence[np.ndarray], fitnesses: Sequence[float], infos: Sequence[dict]) -> None:
        """Report the fitness (and env info) of actions from the last ask(); a prefix if the budget ran out."""
        if self._pending is None:
            raise RuntimeError("tell() called without a pending ask()")
        if not (len(actions) == len(fitnesses) == len(infos)) or len(actions) > len(self._pending):
            raise ValueError(f"tell() got {len(actions)} actions, {len(fitnesses)} fitnesses and {len(infos)} infos "
                             f"for {len(self._pending)} asked")
        self._pending = None
        self._log.add(zip(actions, fitnesses, infos))
        self._tell(list(actions), [float(f) for f in fitnesses], list(infos))

    def stop(self) -> dict:
        """A non-empty dict (with the reason) once the agent has nothing more to propose."""
        return {"reason": self._stop_reason} if self._stop_reason else {}

    @property
    def result(self) -> SearchResult:
        """The search's outcome: best action, fitness and info, evaluation counts, history and stop reason
        (RuntimeError before a run)."""
        if self._log is None:
            raise RuntimeError("no result before a run")
        return self._log.result(self._stop_reason)

    def run(self, env, seed: int | None = None, callback=None) -> SearchResult:
        """Search on ``env`` until the agent stops or the env's budget is spent. ``seed`` is the episode's
        (``env.reset(seed=...)``: the noise its runs draw), None the env's own; the agent draws from its own seed."""
        _, info = env.reset(seed=seed)  # the episode's noise: seed, else the env's own (random_seed)
        self.setup(env, info)
        while not self.stop():
            actions = self.ask()
            fitnesses, infos = [], []
            for action in actions:
                reward, step_info, done = self._step(env, action, callback)
                fitnesses.append(reward)
                infos.append(step_info)
                if done:  # the episode is over (the stop reason is noted), or the rest of this ask is not wanted
                    break
            self.tell(actions[:len(fitnesses)], fitnesses, infos)
        return self.result

    def _step(self, env, action, callback=None) -> tuple[float, dict, bool]:
        """One real evaluation through the env: (fitness, info, episode over); notes why the search stops."""
        _, reward, terminated, truncated, info = env.step(action)
        if callback is not None:
            callback(info)
        done = terminated or truncated
        if done:
            self._stop_reason = self._stop_reason or "budget spent"
        return float(reward), info, done

    # --- hooks --------------------------------------------------------------------------------------------------
    def _setup(self, info: dict) -> None:
        """Prepare a new search (the env is ``self._env``)."""

    @abstractmethod
    def _ask(self) -> list[np.ndarray]:
        ...

    @abstractmethod
    def _tell(self, actions: list[np.ndarray], fitnesses: list[float], infos: list[dict]) -> None:
        ...

    def _finish(self, reason: str) -> None:
        self._stop_reason = reason

    @property
    def best(self) -> tuple[np.ndarray, float, dict[str, Any]]:
        """The best evaluation so far as (action, fitness, info); None before the first."""
        return None if self._log is None else self._log.best
