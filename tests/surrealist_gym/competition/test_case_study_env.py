"""Surrealist-CaseStudy-v1 ready for reinforcement learning: its action space is the rules' box, it renders the last
flight's top view, and it runs in Gymnasium's async vector env and SB3's SubprocVecEnv (flying inline there)."""
import functools
import warnings

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401  (registers the envs)
from surrealist_gym.competition.rules import LAYOUT_FIELDS, RULES
from surrealist_gym.errors import InvalidTestCase
from surrealist_gym.testcase import Shape
from tests.conftest import CASE_STUDIES

MISSION2 = CASE_STUDIES / "mission2.yaml"
SAMPLES = 2000


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


def case_study(**kwargs):
    return gym.make("Surrealist-CaseStudy-v1", case_study=MISSION2, executor="inline", **kwargs).unwrapped


def within_rules(boxes) -> bool:
    """Every box a ground box whose fields lie in the rules' ranges (no tolerance), at most the rules' count."""
    return len(boxes) <= RULES.max_obstacles and all(
        box.shape == Shape.BOX and box.z == 0
        and all(RULES.bounds(f)[0] <= getattr(box, f) <= RULES.bounds(f)[1] for f in LAYOUT_FIELDS)
        for box in boxes)


def test_every_sampled_action_is_within_the_rules(capsys):
    """2,000 samples of the action space, decoded without flying: all within the rules' ranges; about half are also
    free of overlaps, clear of the take-off and landing points and feasible (the rest are refused, not flown)."""
    env = case_study()
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(SAMPLES)]
    within = sum(within_rules(env.boxes_for(a)) for a in actions)
    assert within == SAMPLES  # 2000/2000
    valid, reasons = 0, {}
    for a in actions:
        try:
            test = env.test_for(a)
        except InvalidTestCase as err:
            kind = "overlap" if "overlap" in str(err) else str(err).split(":")[0]
            reasons[kind] = reasons.get(kind, 0) + 1
        else:
            valid += 1
            assert test.obstacles == env.boxes_for(a)  # what is flown is what was checked
    print(f"within the rules {within}/{SAMPLES}, valid {valid}/{SAMPLES}, refused {reasons}")
    assert valid / SAMPLES > 0.3, reasons  # measured 0.51 (seed 0); before: 0 of 2,000 within the rules
    assert set(reasons) <= {"overlap", "degenerate", "infeasible"}
    # the corners of the box are the rules' bounds, exactly
    low, high = env.boxes_for(-np.ones(18))[0], env.boxes_for(np.ones(18))[0]
    assert [getattr(low, f) for f in LAYOUT_FIELDS] == [RULES.bounds(f)[0] for f in LAYOUT_FIELDS]
    assert [getattr(high, f) for f in LAYOUT_FIELDS] == [RULES.bounds(f)[1] for f in LAYOUT_FIELDS]
    env.close()


def test_the_former_version_is_refused_naming_the_current_one():
    """v0's action meant an offset from the seed; a search written for it must not run on v1's meaning unnoticed."""
    with pytest.raises(gym.error.DeprecatedEnv, match="Surrealist-CaseStudy-v1"):
        gym.make("Surrealist-CaseStudy-v0")


def test_the_seed_has_its_own_action_and_the_paper_envs_keep_zero():
    env = case_study()
    assert env.test_for(env.seed_action) == env.seed_test
    assert not np.allclose(env.seed_action, 0.0)  # three boxes at the middle of the rules would overlap
    low, high = env.action_bounds()
    assert np.all(low == -1.0) and np.all(high == 1.0)  # every action is within the rules
    env.close()
    generate = gym.make("Surrealist-Generate-v0", runs=1, executor="inline").unwrapped
    assert np.all(generate.seed_action == 0.0)
    generate.close()


def test_a_refused_action_says_why_and_costs_no_budget():
    env = case_study(budget=3)
    _, info = env.reset(seed=0)
    values = np.zeros(18)
    values[0] = env.seed_test.obstacles[1].x - env.seed_test.obstacles[0].x  # box 0 onto box 1
    _, reward, _, _, info = env.step(env.action_for(values))
    assert "overlap" in info["invalid"] and info["evaluations"] == 1 and reward == info["fitness"] < 0
    env.close()


@pytest.mark.parametrize("make", [
    functools.partial(case_study, obstacles=1, budget=2),
    functools.partial(gym.make, "Surrealist-Generate-v0", runs=1, budget=2, executor="inline"),
], ids=["case-study", "generate"])
def test_render_rgb_array_draws_the_last_flight(make):
    env = make(render_mode="rgb_array")
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.unwrapped.seed_action + 0.05)
    assert info["invalid"] is None
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    assert frame.shape[:2] == (480, 480) and frame.std() > 0  # something is drawn
    env.close()
    quiet = make()
    assert quiet.render_mode is None and quiet.unwrapped.render() is None
    quiet.close()


def test_async_vector_env_flies_inline_in_its_workers():
    venv = gym.make_vec("Surrealist-CaseStudy-v1", num_envs=2, vectorization_mode="async", case_study=MISSION2,
                        obstacles=1, budget=3)
    try:
        obs, info = venv.reset(seed=0)
        assert obs.shape == (2, 9)
        venv.action_space.seed(0)
        for _ in range(2):
            obs, reward, terminated, truncated, info = venv.step(venv.action_space.sample())
            assert obs.shape == (2, 9) and np.all(np.isfinite(reward))
        assert all(n >= 1 for n in venv.get_attr("simulations"))  # each worker flew its seed at least, inline
    finally:
        venv.close()


def test_sb3_subproc_vec_env_flies_inline_in_its_workers():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.vec_env import SubprocVecEnv

    make = functools.partial(gym.make, "surrealist_gym:Surrealist-CaseStudy-v1", case_study=MISSION2, obstacles=1,
                             budget=3)
    venv = SubprocVecEnv([make, make])
    try:
        obs = venv.reset()
        assert obs.shape == (2, 9)
        for _ in range(2):
            obs, reward, done, infos = venv.step(np.stack([venv.action_space.sample() for _ in range(2)]))
            assert obs.shape == (2, 9) and np.all(np.isfinite(reward)) and len(infos) == 2
        assert all(n >= 1 for n in venv.get_attr("simulations"))
    finally:
        venv.close()


def test_the_thread_vec_env_steps_as_sb3s_dummy_vec_env():
    """Envs stepped on threads (their flights in parallel) give, step for step, what SB3's one-after-the-other
    DummyVecEnv gives for the same envs and actions: observations, rewards, ends, the resets' observations."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.vec_env import DummyVecEnv

    from search.thread_vec_env import ThreadVecEnv

    def make(seed):
        return functools.partial(gym.make, "surrealist_gym:Surrealist-CaseStudy-v1", case_study=MISSION2,
                                 obstacles=1, budget=2, random_seed=seed, executor="inline")

    stepped = []
    for cls in (ThreadVecEnv, DummyVecEnv):
        venv = cls([make(0), make(1)])
        actions = np.random.default_rng(3).uniform(-1, 1, (3, 2, *venv.action_space.shape)).astype(np.float32)
        try:
            venv.seed(7)
            got = [venv.reset()]
            for action in actions:
                obs, reward, done, infos = venv.step(action)
                got.append((obs, reward, done, [i.get("terminal_observation") for i in infos]))
            stepped.append(got)
        finally:
            venv.close()
    threads, dummy = stepped
    assert any(d.any() for _, _, d, _ in threads[1:])  # budget 2: an episode ends and its env is reset
    assert np.array_equal(threads[0], dummy[0])
    for (o1, r1, d1, t1), (o2, r2, d2, t2) in zip(threads[1:], dummy[1:]):
        assert np.array_equal(o1, o2) and np.array_equal(r1, r2) and np.array_equal(d1, d2)
        assert all((a is None and b is None) or np.array_equal(a, b) for a, b in zip(t1, t2))


def test_a_daemonic_process_refuses_worker_processes_in_one_line(monkeypatch):
    import multiprocessing

    monkeypatch.setattr(multiprocessing.current_process(), "_config",
                        {**multiprocessing.current_process()._config, "daemon": True})
    with pytest.raises(ValueError, match="a daemonic process .* cannot start worker processes"):
        gym.make("Surrealist-CaseStudy-v1", case_study=MISSION2, obstacles=1, workers=2)
    env = gym.make("Surrealist-CaseStudy-v1", case_study=MISSION2, obstacles=1).unwrapped
    assert type(env.evaluator.executor).__name__ == "InlineExecutor"
    env.close()
