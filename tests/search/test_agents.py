"""Every agent on one tiny-budget problem: spends the budget, never loses the seed, same seed -> same search."""
import warnings

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import CMAES, Agent, PPOAgent, RandomSearch, make_agent, register_agent
from search.policy import load_policy
from search.registry import agent_label
from surrealist_gym.errors import SurrealistError, UnknownAgent
from tests.search.conftest import tiny_policy

BUDGET = 5


def _env(budget=BUDGET):
    return gym.make("Surrealist-Generate-v0", budget=budget, runs=1, executor="inline")


@pytest.fixture(scope="module")
def policy(tmp_path_factory):
    return tiny_policy(tmp_path_factory.mktemp("rl"), "generate")


@pytest.fixture(params=["greedy", "greedy-paper", "random", "cmaes", "ppo", "ppo-sample"])
def agent_name(request, policy):
    return f"{request.param}:{policy}" if request.param.startswith("ppo") else request.param


def test_agent_spends_the_budget_and_keeps_the_seed(agent_name):
    steps = []
    result = make_agent(agent_name, seed=1).run(_env(), seed=1, callback=steps.append)
    assert result.evaluations == BUDGET and steps[-1]["budget_left"] == 0
    assert result.best_fitness >= result.history[0] and result.best_fitness == max(result.history)
    assert 1 <= result.evaluations_to_best <= BUDGET


def test_same_seed_same_search(agent_name):
    a = make_agent(agent_name, seed=2).run(_env(), seed=2)
    b = make_agent(agent_name, seed=2).run(_env(), seed=2)
    assert a.history == b.history and np.array_equal(a.best_action, b.best_action)


def test_random_and_cmaes_propose_actions_in_the_box():
    env = _env()
    _, info = env.reset(seed=0)
    for agent in (RandomSearch(seed=0, batch=3), CMAES(seed=0, popsize=4)):
        agent.setup(env, info)
        actions = agent.ask()
        assert len(actions) == (3 if isinstance(agent, RandomSearch) else 4)
        assert all(a.shape == (2,) and np.all(np.abs(a) <= 1) for a in actions)
        agent.tell(actions[:1], [info["fitness"]], [info])  # a prefix (budget spent) is accepted


def test_random_and_cmaes_sample_only_valid_sizes():
    env = gym.make("Surrealist-Replicate-v0", budget=3, runs=1, executor="inline")
    base = env.unwrapped
    low, high = base.action_bounds()
    assert np.all(low[3:] > -1) and np.array_equal(low[:3], [-1, -1, -1]) and np.all(high == 1)
    info = {"fitness": -100.0, "evaluations": 1}
    for agent in (RandomSearch(seed=0, batch=50), CMAES(  # one obstacle: every sample must be a valid test
                  seed=0, popsize=50, sigma0=2.0)):
        agent.setup(env, info)
        for action in agent.ask():
            assert np.all(action >= low) and np.all(action <= high)
            base.test_for(action)  # raises InvalidTestCase if not


def test_cmaes_without_restarts_stops_on_its_own_criteria():
    agent = CMAES(seed=0, sigma0=1e-9, restarts=False, popsize=2)
    result = agent.run(_env(20), seed=0)
    assert result.evaluations <= 20 and agent.stop()


def test_policy_for_other_mutators_is_rejected(policy):
    env = gym.make("Surrealist-Replicate-v0", budget=3, runs=1, executor="inline")
    with pytest.raises(SurrealistError, match="trained for 2 mutators, the env has 6"):
        PPOAgent(policy).run(env)


def test_registry_names_hints_and_custom_agents(tmp_path):
    assert agent_label("ppo:some/where.zip") == "ppo" and agent_label("pkg.mod:Mine") == "Mine"
    assert agent_label("ppo-sample:some/where.zip") == "ppo-sample"
    with pytest.raises(UnknownAgent, match="did you mean ppo-sample:x.zip"):
        make_agent("ppo-sampel:x.zip")
    with pytest.raises(UnknownAgent, match="did you mean 'cmaes'"):
        make_agent("cmaess")
    with pytest.raises(UnknownAgent, match="ppo:POLICY.zip"):
        make_agent("ppo")
    with pytest.raises(SurrealistError, match="no such policy"):
        make_agent("ppo:missing.zip")

    class Zero(Agent):
        def _ask(self):
            return [np.zeros(len(self._env.mutators))]

        def _tell(self, actions, fitnesses, infos):
            self._finish("nothing to try")

    register_agent("zero", Zero)
    assert make_agent("zero", seed=0).run(_env()).stop_reason == "nothing to try"
    source = tmp_path / "mine.py"
    source.write_text("from search import RandomSearch\nclass Mine(RandomSearch):\n    name = 'mine'\n")
    assert make_agent(f"{source}:Mine", seed=0).name == "mine"
    with pytest.raises(UnknownAgent, match="cannot import"):
        make_agent(f"{source}:Missing")


def test_a_policy_records_the_settings_it_was_trained_with(policy):
    """A policy's .json records algorithm_settings (defaults, then the caller's), so a rerun can tell its parts."""
    import json

    from search.rl import algorithm_settings, recorded_settings

    saved = json.loads(policy.with_suffix(".json").read_text())["hyper"]
    assert saved == {"n_steps": 8, "batch_size": 8, "n_epochs": 1, "gamma": 0.95}
    assert saved == recorded_settings(algorithm_settings("ppo", 16, n_steps=8, batch_size=8, n_epochs=1))
    assert algorithm_settings("ppo", 16)["n_steps"] == 16 and algorithm_settings("ppo", 5000, envs=2)["n_steps"] == 64
    # a case-study action is a whole layout whose reward depends on it alone: no discount, for PPO and SAC alike
    assert algorithm_settings("ppo", 5000, 2, "case-study")["gamma"] == 0.0
    assert algorithm_settings("sac", 5000, 1, "case-study")["gamma"] == 0.0
    assert "gamma" not in algorithm_settings("sac", 5000, 1, "generate")
    assert algorithm_settings("ppo", 5000, 2, "case-study", gamma=0.5)["gamma"] == 0.5


def test_a_sampled_rollout_draws_every_action_from_the_policy(policy):
    """``ppo:`` acts on the policy's mean until a memo hit or a refusal; ``ppo-sample:`` samples every step."""
    from surrealist_gym.envs.wrapper import SurrealistWrapper

    class Recording(SurrealistWrapper):
        def __init__(self, env):
            super().__init__(env)
            self.actions = []

        def step(self, action):
            self.actions.append(tuple(np.round(np.asarray(action, dtype=np.float64), 9)))
            return self.env.step(action)

    def first_actions(name):
        env = Recording(_env(4))
        make_agent(f"{name}:{policy}", seed=3).run(env, seed=3)
        return env.actions

    deterministic, sampled = first_actions("ppo"), first_actions("ppo-sample")
    mean, _ = load_policy(policy).predict(_env(4).reset(seed=3)[0], deterministic=True)
    assert np.allclose(deterministic[0], np.clip(mean, -1, 1), atol=1e-6)
    assert not np.allclose(sampled[0], np.clip(mean, -1, 1), atol=1e-3)
    assert len(set(sampled)) == len(sampled)
    assert make_agent(f"ppo-sample:{policy}").name == "ppo-sample"


def test_ppo_searches_in_parallel_threads_are_reproducible(policy):
    from concurrent.futures import ThreadPoolExecutor

    def search(seed):
        return make_agent(f"ppo:{policy}", seed=seed).run(_env(8), seed=seed).history

    alone = [search(seed) for seed in (4, 5)]
    with ThreadPoolExecutor(2) as pool:
        together = list(pool.map(search, (4, 5)))
    assert together == alone


def test_a_policy_file_runs_no_code_from_its_data(policy, tmp_path):
    """SB3's own load unpickles the zip's ``data``; ours reads only the weights, so a crafted entry does nothing."""
    import base64
    import pickle
    import zipfile

    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    crafted = tmp_path / "crafted.zip"
    with zipfile.ZipFile(policy) as source, zipfile.ZipFile(crafted, "w") as target:
        target.writestr("policy.pth", source.read("policy.pth"))
        blob = base64.b64encode(pickle.dumps(Payload())).decode()
        target.writestr("data", '{"observation_space": {":serialized:": "%s"}}' % blob)
    agent = make_agent(f"ppo:{crafted}", seed=0)
    assert not marker.exists()
    result = agent.run(_env(3), seed=0)
    assert result.evaluations >= 1 and not marker.exists()


def test_interrupted_training_saves_the_policy_so_far_and_trains_on_from_it(tmp_path):
    """Ctrl-C during training (a KeyboardInterrupt from inside SB3's loop) keeps the policy trained so far, with the
    steps done in its record; ``init`` then trains on from those weights."""
    pytest.importorskip("stable_baselines3")
    import json

    from search.policy import load_policy
    from search.rl import train_policy

    def ctrl_c_at_6(steps: int) -> None:
        if steps >= 6:
            raise KeyboardInterrupt

    out = tmp_path / "ppo.zip"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(KeyboardInterrupt):
            train_policy(16, out, problem="generate", budget=3, n_steps=4, batch_size=4, n_epochs=1,
                         progress=ctrl_c_at_6)
        assert json.loads(out.with_suffix(".json").read_text())["interrupted_after_steps"] == 6
        saved = load_policy(out).state_dict()
        more = train_policy(4, tmp_path / "more.zip", problem="generate", budget=3, n_steps=4, batch_size=4,
                            n_epochs=1, init=out, learning_rate=0.0)
    after = load_policy(more).state_dict()  # no learning: the weights it started from
    assert all((saved[k] == after[k]).all() for k in saved)
    assert "interrupted_after_steps" not in json.loads(more.with_suffix(".json").read_text())


def test_training_on_envs_stepped_together_counts_every_env_and_repeats_with_its_seed(tmp_path):
    """``envs=2``: two case-study envs step on threads of this process; each step of each env is counted, and the
    same seed trains the same weights."""
    pytest.importorskip("stable_baselines3")
    import json

    from search.rl import train_policy

    weights = []
    for name in ("a.zip", "b.zip"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            path = train_policy(8, tmp_path / name, problem="case-study", case_study="mission2", obstacles=1,
                                budget=2, envs=2, seed=4, n_steps=4, batch_size=8, n_epochs=1)
        record = json.loads(path.with_suffix(".json").read_text())
        weights.append(load_policy(path).state_dict())
    assert record["envs"] == 2
    assert record["record"]["steps"] == 8 and record["record"]["simulations"] >= 2
    assert all(np.array_equal(weights[0][k].numpy(), weights[1][k].numpy()) for k in weights[0])
