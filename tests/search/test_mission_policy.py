"""A policy trained on drawn case studies searches any case study, with any number of boxes, in its env's own action."""
import json

import gymnasium as gym
import numpy as np
import pytest

import surrealist_gym  # noqa: F401 - registers the envs
from search import make_agent
from search.policy import PRETRAINED, pretrained_policy
from surrealist_gym.competition.case_study_env import CaseStudyEnv
from surrealist_gym.errors import SurrealistError
from tests.search.conftest import tiny_policy


@pytest.fixture(scope="module")
def mission_policy(tmp_path_factory):
    return tiny_policy(tmp_path_factory.mktemp("missions"), "missions")


def test_a_missions_policy_records_its_frame(mission_policy):
    record = json.loads(mission_policy.with_suffix(".json").read_text())
    assert record["problem"] == "missions" and record["frame"] == "mission" and record["hyper"]["gamma"] == 0.0
    assert record["record"]["steps"] == 16


@pytest.mark.parametrize("case_study, boxes", [("mission1", 2), ("mission3", 3)])
def test_one_policy_searches_every_case_study_in_its_own_action(mission_policy, case_study, boxes):
    env = CaseStudyEnv(case_study, obstacles=boxes, budget=3, executor="inline")
    runs = []
    for _ in range(2):
        result = make_agent(f"ppo-sample:{mission_policy}", seed=4).run(env, seed=4)
        runs.append(result.history)
    assert result.best_action.shape == (6 * boxes,) and result.evaluations == 3
    assert runs[0] == runs[1]  # the same seed, the same search
    env.close()


def test_a_missions_policy_refuses_what_it_cannot_search(mission_policy):
    with pytest.raises(SurrealistError, match="trained on drawn case studies"):
        make_agent(f"ppo:{mission_policy}").run(gym.make("Surrealist-Generate-v0", budget=2, executor="inline"))
    with pytest.raises(SurrealistError, match="other properties"):
        make_agent(f"ppo:{mission_policy}").run(CaseStudyEnv("mission2", budget=2, wind=True, executor="inline"))


def test_the_pretrained_policy_ships_with_its_record_and_searches_a_case_study():
    pytest.importorskip("stable_baselines3")
    path = pretrained_policy(PRETRAINED)
    record = json.loads(open(path[:-len(".zip")] + ".json").read())
    assert record["problem"] == "missions" and record["frame"] == "mission"
    env = CaseStudyEnv("mission2", obstacles=3, budget=2, executor="inline")
    result = make_agent("ppo-sample:pretrained", seed=0).run(env, seed=0)
    assert result.evaluations == 2 and np.all(np.abs(result.best_action) <= 1.0)
    env.close()
