"""The adaptive greedy on the real envs (tiny budgets), and the agent interface's checks."""

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy, GreedyConfig


def _env(budget=10):
    return gym.make("Surrealist-Generate-v0", budget=budget, runs=1, executor="inline")


def test_greedy_spends_the_budget_and_never_loses_the_seed():
    env = _env()
    steps = []
    result = AdaptiveGreedy("paper").run(env, seed=0, callback=steps.append)
    assert result.evaluations == 10 and result.stop_reason == "budget spent"
    assert result.best_fitness >= result.history[0]
    assert result.best_fitness == max(result.history)
    assert 1 <= result.evaluations_to_best <= 10
    # the first moves are the paper's: +/- 4 m on the first mutator (y) around the seed
    assert [s["test"].obstacles[0].y for s in steps[:2]] == pytest.approx([17.53125 + 4, 17.53125 - 4])


def test_same_seed_same_search():
    a = AdaptiveGreedy("authors").run(_env(6), seed=3)
    b = AdaptiveGreedy("authors").run(_env(6), seed=3)
    assert a.history == b.history and np.array_equal(a.best_action, b.best_action)


def test_ask_tell_order_is_checked():
    agent = AdaptiveGreedy()
    with pytest.raises(RuntimeError, match="before ask"):
        agent.ask()
    env = _env(4)
    _, info = env.reset(seed=0)
    agent.setup(env, info)
    actions = agent.ask()
    assert len(actions) == 2
    with pytest.raises(RuntimeError, match="twice"):
        agent.ask()
    with pytest.raises(ValueError, match="3 actions"):
        agent.tell(actions + actions[:1], [0.0] * 3, [{}] * 3)


def test_presets():
    assert AdaptiveGreedy("paper").config == GreedyConfig()
    assert AdaptiveGreedy("authors").config.max_seq == 3
    with pytest.raises(ValueError, match="unknown greedy preset"):
        AdaptiveGreedy("fast")


def test_the_plateau_test_compares_a_candidate_judged_on_its_first_runs_with_the_best_over_the_same_runs():
    """The authors' plateau test (averaged trajectories within DTW 10) on a candidate a pre-screen judged on its first
    run alone: compared with the best's first run, not with the best's average of three runs."""
    env = gym.make("Surrealist-Replicate-v0", budget=3, runs=3, executor="inline",
                   sim_config={"common_noise": True})
    _, info = env.reset(seed=0)
    best = (None, info["fitness"], info)
    first_run = env.unwrapped.evaluator.evaluate(info["test"], runs=1)
    agent = AdaptiveGreedy("authors")
    agent.setup(env, info)
    assert agent._same(best, -1e9, {"trajectory": first_run.trajectory, "statuses": first_run.statuses})
    assert not agent._same(best, -1e9, {"trajectory": first_run.trajectory})  # against three runs' average: DTW > 10
