"""SearchMetrics of a real tiny search, their JSON round trip, and the cached repetition runner."""
import json
import warnings

import gymnasium as gym
import pytest

import surrealist_gym  # noqa: F401  (registers the envs)
from search import RandomSearch
from search.metrics import SearchMetrics, search_metrics
from search.repetitions import run_repetition
from surrealist_gym.outcomes import outcomes


def _env(store=None):
    return gym.make("Surrealist-Generate-v0", budget=3, runs=2, random_seed=0, store=store, executor="inline")


@pytest.fixture(scope="module")
def searched():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = _env()
        trace = []
        result = RandomSearch(seed=0).run(env, seed=0, callback=lambda info: trace.append(
            (info["evaluations"], info["simulations"], info["best_fitness"])))
        yield env, result, search_metrics(env, result, trace, wall_seconds=1.23456)
        env.close()


def test_metrics_of_a_generation_search(searched):
    env, result, m = searched
    base = env.unwrapped
    assert (m.seed_fitness, m.best_fitness) == (base.seed_evaluation.fitness, base.best.fitness)
    assert (m.evaluations, m.evaluations_to_best) == (result.evaluations, result.evaluations_to_best)
    assert m.evaluations == 3 and m.wall_seconds == 1.235
    assert m.simulations == base.simulations == m.trace[-1][1] and m.trace[0] == (1, 2, m.seed_fitness)
    assert m.simulations_to_best == next(s for _, s, best in m.trace if best >= m.best_fitness)
    assert m.seed_dtw is None and m.dtw_reduction is None  # replication figures stay empty


def test_rates_are_the_outcomes_of_the_best_runs(searched):
    env, _, m = searched
    base = env.unwrapped
    best, seed = outcomes(base.best.runs, base.distance_measure), outcomes(base.seed_evaluation.runs,
                                                                           base.distance_measure)
    assert (m.crash_rate, m.unsafe_rate, m.best_min_distance) == (best.crash_rate, best.unsafe_rate, best.closest)
    assert m.seed_min_distance == seed.closest
    assert m.min_distance_reduction == pytest.approx(1 - best.closest / seed.closest)


def test_json_round_trip(searched):
    _, _, m = searched
    data = json.loads(json.dumps(m.to_json()))
    assert SearchMetrics.from_json(data) == m
    assert {"best_fitness", "simulations_to_best", "min_distance_reduction", "crash_rate", "trace"} <= set(data)
    assert "seed_dtw" not in data  # absent figures are left out


def test_a_search_file_of_compare_before_search_metrics_still_reads(searched):
    _, _, m = searched
    figures = {k: v for k, v in m.to_json().items() if k != "trace"}
    old = {"agent": "random", "repetition": 0, "metrics": figures, "trace": [list(p) for p in m.trace]}
    assert SearchMetrics.from_json(old) == m
    with pytest.raises(TypeError):  # reproduce_paper's rows of before: not metrics
        SearchMetrics.from_json({"seed_dtw": 1.0, "best_dtw": 0.5, "budget": 3, "wall_s": 1.0})


def test_the_runner_caches_a_finished_repetition(tmp_path):
    envs = []

    def make_env(store):
        envs.append(_env(str(store)))
        return envs[-1]

    stem = tmp_path / "r" / "random-miss0.02-rep0"  # a dotted stem keeps its repetition number
    first = run_repetition(stem, make_env, lambda: RandomSearch(seed=0), seed=0)
    assert first.new_simulations == envs[0].unwrapped.evaluator.simulations > 0
    assert sorted(p.name for p in stem.parent.iterdir()) == [f"{stem.name}.json", f"{stem.name}.sqlite"]
    again = run_repetition(stem, make_env, lambda: RandomSearch(seed=0), seed=0)
    assert len(envs) == 1 and again.new_simulations == 0 and again.metrics == first.metrics  # no env, no flight


def test_the_runner_replays_an_interrupted_or_old_repetition_from_its_store(tmp_path):
    stem = tmp_path / "rep0"  # no dots: with_suffix names its files
    first = run_repetition(stem, _env, lambda: RandomSearch(seed=0), seed=0)
    stem.with_suffix(".json").write_text(json.dumps({"seed_dtw": 1.0, "budget": 3}))  # an older format
    steps = []
    again = run_repetition(stem, _env, lambda: RandomSearch(seed=0), seed=0, callback=steps.append)
    assert again.new_simulations == 0 and len(steps) == len(first.metrics.trace) - 1
    assert again.metrics.trace == first.metrics.trace and again.metrics.best_fitness == first.metrics.best_fitness
    assert SearchMetrics.from_json(json.loads(stem.with_suffix(".json").read_text())) == again.metrics
