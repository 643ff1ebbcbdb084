"""The mission frame and the drawn case studies: what one policy for every mission acts through."""
import math

import numpy as np
import pytest
from shapely.geometry import LineString, Point

from surrealist_gym.competition import mission_frame, missions
from surrealist_gym.competition.case_study_env import CaseStudyEnv
from surrealist_gym.competition.mission_frame import MissionFrame, MissionFrameEnv
from surrealist_gym.competition.missions import MissionCaseStudies, random_case_study, random_mission
from surrealist_gym.competition.rules import RULES, load_case_study, violations


def _path(test):
    return LineString([(0.0, 0.0)] + [(x, y) for x, y, _ in test.mission.waypoints])


@pytest.mark.parametrize("name", ["mission1", "mission2", "mission3"])
def test_a_box_with_no_offset_stands_on_the_path_and_an_offset_one_beside_it(name):
    test = load_case_study(name)
    frame = MissionFrame(test, boxes=1)
    for along in (-0.8, 0.0, 0.6):
        action = np.zeros(mission_frame.FRAME_ACTION_SIZE)
        action[0] = along
        (on,) = frame.layout(action)
        assert _path(test).distance(Point(on.x, on.y)) < 1e-6
        action[1] = 0.5
        (beside,) = frame.layout(action)
        # half the offset from the path, less what keeps it within the rules' bounds
        assert math.hypot(beside.x - on.x, beside.y - on.y) == pytest.approx(0.5 * mission_frame.OFFSET_M, abs=0.05)
        assert _path(test).distance(Point(beside.x, beside.y)) > 1.0


def test_every_frame_action_is_a_layout_within_the_rules_and_the_env_decodes_the_same_boxes():
    rng = np.random.default_rng(3)
    for k in range(40):
        test = random_case_study(rng) if k % 4 else load_case_study(f"mission{k // 4 % 3 + 1}")
        boxes = int(rng.integers(1, RULES.max_obstacles + 1))
        frame = MissionFrame(test, boxes)
        env = CaseStudyEnv(test, obstacles=boxes, budget=2, executor="inline")
        for _ in range(10):
            action = rng.uniform(-1, 1, mission_frame.FRAME_ACTION_SIZE)
            layout = frame.layout(action)
            assert len(layout) == boxes
            assert violations(test.with_obstacles(layout[:1])) == ()
            decoded = env.boxes_for(frame.env_action(action))
            for mine, theirs in zip(layout, decoded):
                assert np.allclose([mine.x, mine.y, mine.l, mine.w, mine.h, mine.r],
                                   [theirs.x, theirs.y, theirs.l, theirs.w, theirs.h, theirs.r], atol=1e-6)
        env.close()


def test_the_observation_tells_missions_box_counts_and_winds_apart():
    mission1, mission2 = load_case_study("mission1"), load_case_study("mission2")
    wind = load_case_study("mission2-wind")
    obs = {key: MissionFrame(test, boxes).observation() for key, (test, boxes) in
           {"m1-2": (mission1, 2), "m2-2": (mission2, 2), "m2-3": (mission2, 3), "w2-3": (wind, 3)}.items()}
    assert all(o.shape == (mission_frame.FRAME_OBSERVATION_SIZE,) and np.all(np.isfinite(o)) for o in obs.values())
    assert len({o.tobytes() for o in obs.values()}) == 4


def test_drawn_missions_have_the_case_studies_shapes_and_follow_their_seed():
    a = [random_mission(np.random.default_rng(7), (47.4, 8.5, 488.0)) for _ in range(2)]
    assert a[0] == a[1]
    rng = np.random.default_rng(11)
    counts = set()
    for _ in range(200):
        mission = random_mission(rng, (47.4, 8.5, 488.0))
        points = mission.waypoints
        counts.add(len(points))
        assert points[0] == (0.0, 0.0, 10.0) and points[-1][2] == 0.0
        assert points[1][1] >= 45.0  # the first leg crosses the obstacle area
        assert all(RULES.x[0] <= x <= RULES.x[1] for x, _, _ in points)
    assert counts == {2, 3, 4, 5}
    drawn = random_case_study(np.random.default_rng(1))
    assert drawn.timeout == missions.DRAWN_TIMEOUT_S and drawn.obstacles == ()


def test_drawn_case_studies_reset_alike_for_a_seed_and_fly_in_the_frame():
    env = MissionCaseStudies(budget=3, executor="inline")
    obs, _ = env.reset(seed=5)
    assert obs[-1] == pytest.approx(2 / 3)  # the seed layout's evaluation is the first of the budget
    again = MissionCaseStudies(budget=3, executor="inline")
    assert np.array_equal(obs, again.reset(seed=5)[0])
    assert obs.shape == env.observation_space.shape
    action = np.zeros(mission_frame.FRAME_ACTION_SIZE)
    action[1::6] = [-0.9, 0.0, 0.9]  # the boxes side by side across the path: none overlaps
    action[0::6] = [-0.6, 0.0, 0.6]
    obs, reward, _, _, info = env.step(action)
    assert info["invalid"] is None and len(info["statuses"]) == 1 and math.isfinite(reward)
    assert obs[-1] == pytest.approx(1 / 3)
    env.close()
    again.close()


def test_the_frame_wrapper_refuses_nothing_the_case_study_accepts():
    env = MissionFrameEnv(CaseStudyEnv("mission2", obstacles=1, budget=1, executor="inline"))
    obs, _ = env.reset(seed=0)
    assert obs.shape == (mission_frame.FRAME_OBSERVATION_SIZE,)
    assert env.action_space.shape == (mission_frame.FRAME_ACTION_SIZE,)
    env.close()


def test_drawn_case_studies_are_a_gymnasium_env_that_warns_nothing(tmp_path, monkeypatch):
    import warnings

    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env

    import surrealist_gym  # noqa: F401 - registers the envs

    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gym.make("Surrealist-Missions-v0", budget=3, executor="inline")
        check_env(env.unwrapped)
        env.close()
    assert [str(w.message) for w in caught] == []
    assert list(tmp_path.iterdir()) == []
