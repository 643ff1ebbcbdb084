"""Racing under each test's own noise: a candidate's first runs against the incumbent's fitness over all its runs
(``against="fitness"``), on the RQ2 mission with real simulations, seeded."""

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import AdaptiveGreedy
from surrogates.config import PrescreenConfig, RaceConfig
from surrogates.dataset import load_dataset
from surrogates.models import train_model
from surrogates.prescreened import Prescreened
from surrogates.racing import Race, Racing, race_margin
from surrogates.replay import improvement_shortfalls

RUNS = 4


@pytest.fixture(scope="module")
def raced():
    """The RQ2 env (4 runs, each test its own noise) after reset, raced, with the seed test as the incumbent."""
    env = Racing(gym.make("Surrealist-Generate-v0", budget=10, runs=RUNS, executor="inline"))
    _, info = env.reset(seed=0)
    return env, info


def _moved(env, dx: float) -> np.ndarray:
    """The seed test's action with the box moved along its x mutator (``obstacle0.x``)."""
    inner = env.unwrapped
    names = [m.name for m in inner.mutators]
    action = np.array(inner.action_for([m.default_value for m in inner.mutators]), dtype=np.float64)
    action[names.index("obstacle0.x")] += dx
    return action


def test_a_clearly_worse_candidate_is_dropped_after_its_first_run(raced):
    env, info = raced
    race = Race(((1, 5.0), (2, 5.0)), against="fitness")
    before = env.unwrapped.evaluator.simulations
    skip = race.verdict(env, _moved(env, 1.0), info["test"], info["fitness"])  # the box off the path: ~20 worse
    assert skip is not None and skip.why["first_runs"] == 1 and skip.why["race_against"] == "fitness"
    assert skip.why["race_shortfall"] == pytest.approx(info["fitness"] - skip.why["first_runs_fitness"])
    assert skip.why["race_shortfall"] > 5.0 and skip.told < info["fitness"]
    assert env.unwrapped.evaluator.simulations - before == 1  # one run flown, not four


def test_a_clearly_better_candidate_is_flown_in_full(raced):
    env, info = raced
    race = Race(((1, 5.0), (2, 5.0)), against="fitness")
    action = _moved(env, -0.5)  # the box nearer the path: ~10 better
    assert race.verdict(env, action, info["test"], info["fitness"]) is None
    _, fitness, *_ = env.step(action)  # flies the runs not flown yet
    assert fitness > info["fitness"] + 5.0
    assert len(env.unwrapped.evaluator.evaluate(env.unwrapped.test_for(action)).runs) == RUNS


def test_the_incumbents_own_first_runs_are_not_what_it_races_against(raced):
    # a margin of 0 against the fitness drops what falls short of the incumbent's fitness, whatever its first runs
    env, info = raced
    action = _moved(env, 0.5)
    theirs = env.unwrapped.evaluator.evaluate(info["test"], runs=1).fitness
    flown = env.race(action, 1).fitness
    skip = Race(((1, 0.0),), against="fitness").verdict(env, action, info["test"], info["fitness"])
    assert (skip is not None) == (flown < info["fitness"])
    paired = Race(((1, 0.0),), against="paired").verdict(env, action, info["test"], info["fitness"])
    assert (paired is not None) == (flown < theirs)


def test_the_margin_against_the_fitness_is_calibrated_on_past_improvements(rq2_store, generate_featurizer):
    data = load_dataset([rq2_store], generate_featurizer)
    model = train_model(data, generate_featurizer, "knn")
    y, first = data.targets["fitness"], data.first_runs[:, 0]
    best, shortfalls = y[0], []
    for fitness, proxy in zip(y[1:], first[1:]):
        if fitness > best:
            shortfalls.append(best - proxy)  # the incumbent's fitness minus the improvement's first run
            best = fitness
    assert improvement_shortfalls(first, y, data.groups, against_fitness=True) == pytest.approx(shortfalls)
    assert race_margin(model, 1, 0.1, "fitness") == pytest.approx(np.quantile(shortfalls, 0.9))
    assert race_margin(model, 1, 0.1, "fitness") != pytest.approx(race_margin(model, 1, 0.1, "paired"))


def test_the_noise_mode_picks_what_racing_races_against(rq2_store, generate_featurizer):
    model = train_model(load_dataset([rq2_store], generate_featurizer), generate_featurizer, "knn")
    assert Race.calibrated(RaceConfig((1,)), model, 0.02, common_noise=False).against == "fitness"
    assert Race.calibrated(RaceConfig((1,)), model, 0.02, common_noise=True).against == "paired"
    assert Race.calibrated(RaceConfig((1,), against="paired"), model, 0.02, common_noise=False).against == "paired"
    with pytest.raises(ValueError, match="race_against"):
        PrescreenConfig.of(first_runs=1, race_against="mean")


def test_a_search_raced_against_the_fitness_drops_only_what_falls_short_of_the_best():
    env = gym.make("Surrealist-Generate-v0", budget=6, runs=3, executor="inline")
    config = PrescreenConfig.of(rule="none", first_runs=(1, 2), race_margin=0.0, lowfi=False)
    agent = Prescreened(AdaptiveGreedy("paper"), "online", config, seed=0)
    result = agent.run(env, seed=0)
    raced = [s for s in agent.prescreener.skipped if s["rule"] == "race"]
    assert raced and all(s["race_against"] == "fitness" and s["race_shortfall"] > 0 for s in raced)
    assert env.unwrapped.evaluator.simulations == 3 * result.evaluations + sum(s["first_runs"] for s in raced)


def test_surrogate_alone_races_a_replication_with_its_own_noise_against_the_fitness_in_stages():
    from surrogates.config import SkipAccounting, measured_prescreen

    config = PrescreenConfig.of(**measured_prescreen(False, "replicate", runs=5))
    assert (config.screen.rule, config.race.stages, config.skips, config.verify_stop, config.race.against) == (
        "none", (1, 2, 3, 4), SkipAccounting.BUDGET, True, None)  # None: against the fitness under own noise
