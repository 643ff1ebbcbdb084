"""Gymnasium's contract, as a new user meets it: ``gym.make`` from any folder, no checker warnings, flyable action
spaces, ``reset(seed=)`` seeding the noise, bounded observations, ``render_mode="human"`` (real simulator, one run per
evaluation, in process)."""
import filecmp
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import surrealist_gym  # noqa: F401  (registers the envs)
from tests.conftest import SHARED_DATA

ENV_IDS = ["Surrealist-Replicate-v0", "Surrealist-Generate-v0", "Surrealist-CaseStudy-v1"]


@pytest.fixture
def elsewhere(tmp_path, monkeypatch):
    """A folder with nothing of the project's in it, and no case-study look-up set."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("SURREALIST_CASE_STUDIES", raising=False)
    return tmp_path


def make(env_id, **kwargs):
    return gym.make(env_id, **{"budget": 4, "runs": 1, "executor": "inline", **kwargs})


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_make_works_from_any_folder_and_check_env_warns_nothing(env_id, elsewhere):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = make(env_id)
        check_env(env.unwrapped)
        env.close()
    assert [str(w.message) for w in caught] == []
    assert list(elsewhere.iterdir()) == []  # nothing written where the user stands


def test_the_case_studies_ship_with_the_package(elsewhere):
    from surrealist_gym.competition.rules import bundled_case_studies, case_study_path, load_case_study

    bundled = bundled_case_studies()
    shared = SHARED_DATA / "competition" / "case_studies"
    names = sorted(p.name for p in shared.iterdir())
    _, different, missing = filecmp.cmpfiles(shared, bundled, names, shallow=False)
    assert different == [] and missing == []  # byte for byte
    for n in (1, 2, 3):
        assert case_study_path(f"mission{n}").parent == bundled
        calm, windy = load_case_study(f"mission{n}"), load_case_study(f"mission{n}-wind")
        assert calm.mission == windy.mission and calm.params == windy.params
        assert calm.wind is None or calm.wind.velocity_mean == 0
        assert (windy.wind.velocity_mean, windy.wind.velocity_max, windy.wind.direction) == (3.0, 5.0, (1.0, 0.0, 0.0))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_sampled_action_is_a_flyable_test(env_id):
    env = make(env_id)
    flyable, bare = env.env.env, env.unwrapped  # gym.make: OrderEnforcing(PassiveEnvChecker(FlyableActions(env)))
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(300)]
    refused_bare = 0
    for action in actions:
        bare.test_for(flyable.repair(action))  # raises InvalidTestCase if the repair failed
        refused_bare += not flyable.flies(action)
    assert refused_bare > 0  # the bare env refuses some (so the repair did something)
    valid = next(a for a in actions if flyable.flies(a))
    assert np.array_equal(flyable.repair(valid), np.asarray(valid, dtype=np.float64))  # a flyable action flies as is
    env.reset(seed=0)
    for action in actions[:3]:
        *_, info = env.step(action)
        assert info["invalid"] is None and info["action"].shape == np.shape(action)
    env.close()
    bare_made = gym.make(env_id, flyable=False, executor="inline")
    assert bare_made.unwrapped is bare_made.env.env  # flyable=False: the bare env under gym.make's checkers


def test_reset_seed_seeds_the_noise():
    env = make("Surrealist-Generate-v0")
    action = np.full(env.action_space.shape, 0.3, dtype=np.float32)

    def episode(seed=None):
        _, info = env.reset(seed=seed)
        *_, step = env.step(action)
        return info["min_distances"] + step["min_distances"]

    first = episode(5)
    assert episode(5) == first  # the same seed reproduces
    other = episode(6)
    assert other != first  # another seed draws other noise
    assert episode() == other  # no seed: the noise of the episode before
    env.close()


def test_vector_envs_get_distinct_noise():
    envs = gym.make_vec("Surrealist-Generate-v0", num_envs=2, vectorization_mode="sync", budget=3, runs=1,
                        executor="inline")
    _, infos = envs.reset(seed=3)
    assert infos["fitness"][0] != infos["fitness"][1]  # sub-envs seeded 3 and 4 fly different noise
    _, again = envs.reset(seed=3)
    assert list(again["fitness"]) == list(infos["fitness"])
    envs.close()


def test_a_stored_search_keeps_its_seed(tmp_path):
    env = make("Surrealist-Generate-v0", store=str(tmp_path / "s.sqlite"), random_seed=2)
    env.reset(seed=2)  # the store's own seed: fine
    with pytest.raises(ValueError, match="random seed 2"):
        env.reset(seed=3)
    env.close()


def test_observations_stay_in_their_bounded_box():
    env = make("Surrealist-Replicate-v0", budget=3)
    space = env.observation_space
    assert np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))
    obs, _ = env.reset(seed=0)
    env.action_space.seed(1)
    for _ in range(3):
        assert space.contains(obs)
        obs, *_ = env.step(env.action_space.sample())
    env.close()


def test_human_render_mode_needs_no_pygame():
    env = make("Surrealist-Generate-v0", render_mode="human")
    assert env.unwrapped.render_mode == "human"  # native, not Gymnasium's pygame HumanRendering wrapper
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert env.render() is None  # human mode draws in reset and step (nowhere under the test's Agg backend)
    env.close()


def test_ppo_on_the_case_study_refuses_nothing():
    from stable_baselines3 import PPO

    env = make("Surrealist-CaseStudy-v1", budget=200)
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
    refused = []

    from stable_baselines3.common.callbacks import BaseCallback

    class Count(BaseCallback):
        def _on_step(self) -> bool:
            refused.extend(info.get("invalid") is not None for info in self.locals["infos"])
            return True

    model.learn(128, callback=Count())
    assert len(refused) >= 128 and sum(refused) == 0
    env.close()
