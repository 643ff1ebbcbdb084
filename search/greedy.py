"""The paper's adaptive greedy search (Algorithms 1 and 2), as an ask/tell agent.

Algorithm 1 loops over the env's mutators with a local budget of ``budget_left / (mutators x rounds_left)``;
Algorithm 2 is an adaptive line search on one mutator: try ``param +/- step`` around the best of the previous
local search, move on an improvement larger than epsilon, double the step after MAX_SEQ moves in one direction,
halve it when both sides are worse, stop on a plateau or after MAX_IT iterations without improvement. Evaluations
answered by the env's memo cost no budget (local or global).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import Agent


@dataclass(frozen=True, slots=True)
class GreedyConfig:
    """Hyper-parameters (paper Table 1 by default).

    Attributes:
        min_rounds: minimum ensured rounds of the global loop (Algorithm 1).
        max_seq: same-direction moves after which the step doubles (MAX_SEQ).
        max_it: iterations without improvement after which a local search stops (MAX_IT).
        epsilon: minimum fitness gain that counts as an improvement.
        use_min_step: stop a local search once its step falls below the mutator's ``min_step``.
        same_dtw: if set, two solutions whose averaged trajectories are closer than this DTW count as equal
            (the plateau test of the authors' run, which used 10); needs ``info["trajectory"]`` from the env.
    """

    min_rounds: int = 2
    max_seq: int = 5
    max_it: int = 5
    epsilon: float = 0.0
    use_min_step: bool = False
    same_dtw: float | None = None


PRESETS = {
    # Table 1 of the paper (RQ1 seed 1 used budget 200 with min_rounds 4; seed 2 and RQ2 min_rounds 2)
    "paper": GreedyConfig(),
    # the authors' own run: order y,x,r,sy,sx,sz (the env's mutator order), 2 rounds, budget 100, 5 runs
    "authors": GreedyConfig(min_rounds=2, max_seq=3, max_it=5, use_min_step=True, same_dtw=10.0),
}


class AdaptiveGreedy(Agent):
    """The reference agent: SURREALIST's adaptive greedy search."""

    name = "greedy"

    def __init__(self, config: GreedyConfig | str = "paper", seed: int | None = None):
        super().__init__(seed)
        if isinstance(config, str):
            if config not in PRESETS:
                raise ValueError(f"unknown greedy preset {config!r} (expected one of {sorted(PRESETS)})")
            config = PRESETS[config]
        self.config = config

    def _setup(self, info: dict) -> None:
        action, fitness, info = self.best
        self._current = (self._env.values_for(action), fitness, info)
        self._search = self._global_search()
        self._advance(None)

    def _ask(self) -> list[np.ndarray]:
        return self._proposal

    def _tell(self, actions, fitnesses, infos) -> None:
        self._advance(list(zip(fitnesses, infos)))

    def _advance(self, results) -> None:
        """Run the search generator to its next proposal (a pair of actions), or finish."""
        try:
            self._proposal = next(self._search) if results is None else self._search.send(results)
        except StopIteration:
            self._proposal = []
            if not self._stop_reason:
                self._finish("budget spent" if self._env.budget_left <= 0 else "no mutator improves the best")

    # --- Algorithms 1 and 2 as a generator: yields candidate pairs, receives [(fitness, info), ...] ------------
    def _global_search(self):
        mutators = self._env.mutators
        rounds = self.config.min_rounds
        improved = True
        while improved:
            improved = False
            local_budget = self._env.budget_left / (len(mutators) * max(rounds, 1))
            for index in range(len(mutators)):
                if self._env.budget_left <= 0:
                    return
                improved = (yield from self._local_search(index, local_budget)) or improved
            rounds -= 1

    def _local_search(self, index: int, local_budget: float):
        cfg = self.config
        mutator = self._env.mutators[index]
        base = self._current[0]
        step, param = mutator.default_step, mutator.default_value
        positive = negative = no_improvement = 0
        new_best = self._current
        while local_budget > 0 and no_improvement < cfg.max_it:
            if cfg.use_min_step and step < mutator.min_step:
                break
            up, down = base.copy(), base.copy()
            up[index] += param + step
            down[index] += param - step
            results = yield [self._env.action_for(up), self._env.action_for(down)]
            local_budget -= sum(0 if info.get("memo") else 1 for _, info in results)
            if len(results) < 2:
                break
            (f_up, i_up), (f_down, i_down) = results
            if f_up > new_best[1] + cfg.epsilon and f_up > f_down:  # best solutions kept as mutator values
                new_best, param = (up, f_up, i_up), param + step
                positive, negative, no_improvement = positive + 1, 0, 0
                if positive > cfg.max_seq:
                    step *= 2
            elif f_down > new_best[1] + cfg.epsilon:
                new_best, param = (down, f_down, i_down), param - step
                negative, positive, no_improvement = negative + 1, 0, 0
                if negative > cfg.max_seq:
                    step *= 2
            else:
                if self._same(new_best, f_up, i_up) and self._same(new_best, f_down, i_down):
                    break
                step /= 2
                positive = negative = 0
                no_improvement += 1
        if new_best is not self._current:
            self._current = new_best
            return True
        return False

    def _same(self, best, fitness: float, info: dict) -> bool:
        """The plateau test: equal fitness within epsilon, or (authors' run) averaged trajectories within same_dtw.
        A candidate judged on fewer runs than the best (``info["statuses"]``) is compared with the best's trajectory
        over the same first runs (scored by the env's evaluator)."""
        if (self.config.same_dtw is not None and info.get("trajectory") is not None
                and best[2].get("trajectory") is not None):
            from surrealist_gym.metrics import dtw
            ours, k = best[2]["trajectory"], len(info.get("statuses") or ())
            if 0 < k < len(best[2].get("statuses") or ()) and best[2].get("test") is not None:
                ours = self._env.evaluator.evaluate(best[2]["test"], runs=k).trajectory
            return dtw(ours, info["trajectory"]) < self.config.same_dtw
        return abs(best[1] - fitness) < self.config.epsilon
