"""The envs on the real simulator, with tiny budgets (one run per evaluation, in process)."""
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import surrealist_gym as sg
from surrealist_gym.store import EvaluationStore
from tests.conftest import SHARED_DATA

ENV_IDS = ["Surrealist-Replicate-v0", "Surrealist-Generate-v0"]


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


def make(env_id, **kwargs):
    kwargs = {"budget": 30, "runs": 1, "executor": "inline", **kwargs}
    return gym.make(env_id, **kwargs)


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("runs", [1, 2])
def test_gymnasium_check_env(env_id, runs):
    """The current Gymnasium's checker, through gym.make's wrappers; two runs give the first-run infos too."""
    env = make(env_id, runs=runs)
    check_env(env)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env(env_id):
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env = make(env_id)
    sb3_checker.check_env(env.unwrapped, warn=False)
    env.close()


def test_defaults_are_the_papers():
    rep = gym.make("Surrealist-Replicate-v0", executor="inline").unwrapped
    assert rep.budget == 100 and rep.evaluator.runs == 5 and len(rep.reference) == 86
    assert [m.name for m in rep.mutators] == [f"obstacle0.{k}" for k in ("y", "x", "r", "sy", "sx", "sz")]
    assert rep.seed_test.obstacles[0].x == -8.64
    gen = gym.make("Surrealist-Generate-v0", executor="inline").unwrapped
    assert gen.budget == 50 and gen.evaluator.runs == 10
    assert [m.name for m in gen.mutators] == ["obstacle0.y", "obstacle0.x"] and len(gen.seed_test.obstacles) == 2


def test_memo_budget_truncation_and_info():
    env = make("Surrealist-Replicate-v0", budget=3).unwrapped
    obs, info = env.reset(seed=0)
    assert info["evaluations"] == 1 and np.isfinite(info["fitness"]) and info["terms"]["dtw"] > 0
    assert obs.shape == env.observation_space.shape
    action = env.action_for([2.0, 0, 0, 0, 0, 0])
    _, r1, _, trunc, info1 = env.step(action)
    assert info1["evaluations"] == 2 and not info1["memo"] and not trunc
    assert info1["statuses"] and len(info1["min_distances"]) == 1 and info1["simulations"] == 2
    _, r2, _, trunc, info2 = env.step(action)  # the same test again: memo, no budget
    assert info2["memo"] and info2["evaluations"] == 2 and r2 == r1 and not trunc
    _, _, _, trunc, info3 = env.step(env.action_for([0, 0, 0, 0, 0, -4.0]))  # height 3 - 4 < 0: invalid
    assert info3["invalid"] and "'h' must be positive" in info3["invalid"] and info3["evaluations"] == 2
    _, _, _, trunc, info4 = env.step(env.action_for([-2.0, 0, 0, 0, 0, 0]))
    assert trunc and info4["budget_left"] == 0
    assert env.best.fitness == max(info["fitness"], r1, info4["fitness"])


def test_same_seed_same_episode():
    env = make("Surrealist-Generate-v0").unwrapped
    a = env.action_for([3.0, -2.0])
    first = [env.reset(seed=1)[1]["fitness"], env.step(a)[1]]
    second = [env.reset(seed=1)[1]["fitness"], env.step(a)[1]]
    assert first == second


def test_every_evaluation_is_stored(tmp_path):
    env = make("Surrealist-Generate-v0", store=tmp_path / "e.sqlite").unwrapped
    env.reset(seed=0)
    env.step(env.action_for([4.0, 0.0]))
    env.step(env.action_for([4.0, 0.0]))  # memo: not stored twice
    rows = list(EvaluationStore(tmp_path / "e.sqlite"))
    assert len(rows) == 2 and rows[1].runs[0]["status"] in {"success", "collision", "timeout", "stuck"}
    # a new env on the same store answers from it without simulating, and still counts the budget
    again = make("Surrealist-Generate-v0", store=tmp_path / "e.sqlite").unwrapped
    _, info = again.reset(seed=0)
    assert again.evaluator.simulations == 0 and info["evaluations"] == 1
    assert info["fitness"] == rows[0].fitness


def test_replicate_from_a_log_without_seed_places_the_papers_box():
    from surrealist_gym.envs.replicate import seed_from_flight

    seed = seed_from_flight(sg.read_flight(sg.data_path("case0.ulg")))
    box = seed.obstacles[0]
    assert (box.l, box.w, box.h) == (3.0, 3.0, 3.0)
    assert box.x == pytest.approx(-17.0 / 2, abs=0.6) and box.y == pytest.approx(6.8 / 2, abs=0.6)


def test_racing_flies_the_first_runs_and_step_only_the_rest(tmp_path):
    from surrogates.racing import Racing

    action = [4.0, -1.0]
    whole = make("Surrealist-Generate-v0", budget=5, runs=3).unwrapped
    whole.reset(seed=0)
    _, fitness, _, _, info = whole.step(whole.action_for(action))
    first = [whole.evaluator.evaluate(info["test"], runs=k).fitness for k in (1, 2)]  # scored on demand, no flight
    assert whole.evaluator.simulations == 6
    assert first[0] <= first[1] + 1e-12 and first[1] <= fitness + 1e-12  # the riskiest run so far

    env = Racing(make("Surrealist-Generate-v0", budget=5, runs=3, store=tmp_path / "e.sqlite"))
    env.reset(seed=0)
    raced = env.race(env.action_for(action), 2)
    assert raced.fitness == pytest.approx(first[1]) and len(raced.runs) == 2
    assert env.evaluator.simulations == 3 + 2 and env.simulations == 5
    assert env.budget_left == 5 - 1  # two runs of three do not make an evaluation yet
    assert len(list(EvaluationStore(tmp_path / "e.sqlite"))) == 1  # a partial evaluation is not stored
    _, stepped, _, _, sinfo = env.step(env.action_for(action))
    assert stepped == fitness and env.evaluator.simulations == 6 and sinfo["simulations"] == 6
    assert env.budget_left == 5 - 2 and sinfo["budget_left"] == 3
    again = env.race(env.action_for(action), 1)  # evaluated in full: scored from its kept runs
    assert again.fitness == pytest.approx(first[0]) and env.evaluator.simulations == 6 and env.simulations == 6


def test_raced_runs_are_charged_to_the_budget_in_whole_evaluations():
    from surrogates.racing import Racing

    env = Racing(make("Surrealist-Generate-v0", budget=2, runs=2))
    env.reset(seed=0)
    env.race(env.action_for([4.0, -1.0]), 1)
    assert env.budget_left == 1 and env.unwrapped.budget_left == 1
    env.race(env.action_for([3.0, -2.0]), 1)
    assert env.budget_left == 0 and env.simulations == 4  # two half evaluations make one
    *_, truncated, info = env.step(env.action_for([2.0, 1.0]))
    assert truncated and info["budget_left"] < 0


def test_a_partial_evaluation_is_scored_from_the_runs_a_store_keeps(tmp_path):
    """Runs keep their trajectories, in memory and in the store: the score of a test's first k runs alone is
    computed on demand, like for like with a race, without flying again after a restart."""
    from surrogates.racing import Racing

    kwargs = dict(budget=3, runs=3, store=tmp_path / "r.sqlite", sim_config={"common_noise": True})
    env = Racing(make("Surrealist-Replicate-v0", **kwargs))
    _, info = env.reset(seed=0)
    first = env.evaluator.evaluate(info["test"], runs=1)
    assert len(first.runs) == 1 and first.trajectory.shape[1] == 3
    assert first.fitness != info["fitness"]  # one run is not the average of three
    values = env.values_for(np.zeros(env.action_space.shape))
    values[0] += 2.0
    action = env.action_for(values)
    raced = env.race(action, 2)
    _, stepped, _, _, sinfo = env.step(action)
    two = env.evaluator.evaluate(sinfo["test"], runs=2)
    assert np.array_equal(raced.trajectory, two.trajectory) and raced.fitness == pytest.approx(two.fitness)

    again = Racing(make("Surrealist-Replicate-v0", **kwargs))
    again.reset(seed=0)
    reread = again.evaluator.evaluate(sinfo["test"], runs=2)
    assert again.evaluator.simulations == 0
    assert reread.fitness == two.fitness and np.array_equal(reread.trajectory, two.trajectory)
    assert len(again.race(action, 1).runs) == 1 and again.evaluator.simulations == 0


def test_envs_take_a_uav_profile():
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.sim.config import AvoidanceModel, SimConfig

    env = GenerateEnv(runs=1, budget=2, uav="px4-v1.12-sitl-iris", sim_config={"common_noise": True})
    cfg = env.evaluator.sim_config
    assert cfg.profile == "px4-v1.12-sitl-iris" and cfg.avoidance_model == AvoidanceModel.PX4 and cfg.common_noise
    # without one: the paper's seed names a real flight (the PX4 Vision), a competition test flies the SITL Iris
    assert GenerateEnv(runs=1, budget=2).evaluator.sim_config.profile == "px4-vision-case0"
    # a mapping changes fields of that UAV; a full SimConfig is the UAV as given
    crn = GenerateEnv(runs=1, budget=2, sim_config={"common_noise": True}).evaluator.sim_config
    assert crn.profile == "px4-vision-case0" and crn.common_noise
    assert GenerateEnv(runs=1, budget=2, sim_config=SimConfig()).evaluator.sim_config.profile is None


def test_a_competition_seed_flies_the_sitl_iris_by_default(shared_data):
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.sim.config import AvoidanceModel

    mission1 = SHARED_DATA / "competition" / "case_studies" / "mission1.yaml"
    cfg = GenerateEnv(seed_test=str(mission1), runs=1, budget=2).evaluator.sim_config
    assert cfg.profile == "px4-v1.12-sitl-iris" and cfg.avoidance_model == AvoidanceModel.PX4


def test_a_seed_test_that_cannot_fly_is_a_one_line_error(tmp_path):
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.errors import SimulationError

    plan = tmp_path / "empty.plan"
    plan.write_text('{"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": [], '
                    '"plannedHomePosition": [47.39, 8.54, 488]}}')
    test = tmp_path / "empty.yaml"
    test.write_text("robot:\n  mission_file: empty.plan\nsimulation:\n  obstacles: [3,3,3, 0,9,0, 0]\n")
    env = GenerateEnv(seed_test=str(test), runs=1, budget=2, executor="inline")
    with pytest.raises(SimulationError, match="seed test: none of its runs could be judged"):
        env.reset()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_shared_keywords_become_one_frozen_setup(env_id, tmp_path):
    """What every env shares reaches the base class as one EnvSetup, each field the gym.make keyword of its name."""
    import dataclasses

    from surrealist_gym.envs import EnvSetup

    env = make(env_id, runs=2, random_seed=7, uav="px4-v1.12-sitl-iris", store=str(tmp_path / "s.db")).unwrapped
    assert env.setup == EnvSetup(runs=2, random_seed=7, uav="px4-v1.12-sitl-iris", executor="inline",
                                 store=str(tmp_path / "s.db"))
    assert env.evaluator.runs == 2 and env.evaluator.sim_config.profile == "px4-v1.12-sitl-iris"
    with pytest.raises(dataclasses.FrozenInstanceError):
        env.setup.runs = 3
    with pytest.raises(TypeError):
        EnvSetup(2)  # keywords only: no setting passed on by position
