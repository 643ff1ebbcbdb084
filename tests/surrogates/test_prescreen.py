"""Pre-screening around the greedy on a tiny Generate env: real simulations only, skips logged, seeded."""
import warnings

import gymnasium as gym
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy
from surrealist_gym.errors import SurrealistError
from surrogates.dataset import load_dataset
from surrogates.models import train_model
from surrogates.prescreen import PrescreenConfig, Prescreened, wrap

BUDGET = 4


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _env():
    return gym.make("Surrealist-Generate-v0", budget=BUDGET, runs=1, executor="inline")


@pytest.fixture(scope="module")
def model(rq2_store, generate_featurizer):
    return train_model(load_dataset([rq2_store], generate_featurizer), generate_featurizer, "knn")


def _run(model, seed=0):
    env = _env()
    steps = []
    agent = Prescreened(AdaptiveGreedy("paper"), model, PrescreenConfig(threshold=0.5, max_skips=3), seed=seed)
    result = agent.run(env, seed=seed, callback=steps.append)
    return agent, result, steps, env


@pytest.fixture(scope="module")
def runs(model):
    return _run(model), _run(model)


def test_budget_counts_real_simulations_only(runs):
    agent, result, steps, env = runs[0]
    assert result.evaluations <= BUDGET
    assert env.unwrapped.evaluator.simulations == result.evaluations  # 1 run per evaluation; skips fly nothing
    assert agent.skipped, "a strict threshold must skip candidates"
    for entry in agent.skipped:
        assert entry["predicted_std"] > 0 and entry["told_fitness"] < result.best_fitness
    assert not any(s.get("skipped") for s in steps)  # the callback sees real steps only
    assert result.best_fitness == max(result.history)


def test_same_seed_same_search(runs):
    (a, ra, _, _), (b, rb, _, _) = runs
    assert ra.history == rb.history and a.skipped == b.skipped


def test_online_model_trains_as_evaluations_arrive():
    agent = Prescreened(AdaptiveGreedy("paper"), "online",
                        PrescreenConfig(min_points=2, retrain_every=1, kind="knn"), seed=1)
    result = agent.run(_env(), seed=1)
    assert result.evaluations <= BUDGET and agent.retrains >= 1 and agent.model is not None


def test_wrap(model, tmp_path):
    greedy = AdaptiveGreedy("paper")
    assert wrap(greedy, None) is greedy
    folder = model.save(tmp_path / "m")
    assert isinstance(wrap(greedy, str(folder), _env()), Prescreened)
    replicate = gym.make("Surrealist-Replicate-v0", budget=2, runs=1, executor="inline")
    with pytest.raises(SurrealistError, match="another mission"):
        wrap(greedy, str(folder), replicate)


def test_free_then_most_promising_candidates_first(model):
    import numpy as np

    env = _env()
    _, info = env.reset(seed=0)
    agent = Prescreened(AdaptiveGreedy("paper"), model, seed=0)
    agent.setup(env, info)
    candidates = [np.array([0.1, 0.0]), np.array([-0.1, 0.3]), np.array([0.0, -1.0])]  # the last one overlaps
    order, predictions = agent._most_promising_first(candidates)
    means = [p[1] for p in predictions[:2]]
    assert predictions[2] is None and order[0] == 2
    assert order[1:] == sorted([0, 1], key=lambda i: -means[i])
