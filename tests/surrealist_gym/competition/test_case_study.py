"""The competition's rules and points, suites of distinct failures, and Surrealist-CaseStudy-v1 on real PyBullet."""
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import surrealist_gym  # noqa: F401  (registers the envs)
from surrealist_gym.competition.rules import (
    RULES,
    case_study_path,
    layout_mutators,
    load_case_study,
    points,
    seed_layout,
    violations,
)
from surrealist_gym.competition.suite import Member, Suite, diversity, layout_distance, trajectory_distance
from surrealist_gym.competition.suite_env import RecordSuite
from surrealist_gym.errors import InvalidTestCase
from surrealist_gym.testcase import Obstacle
from tests.conftest import CASE_STUDIES


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        yield


def mission(name="mission1"):
    return load_case_study(CASE_STUDIES / f"{name}.yaml")


def test_points_follow_the_competition():
    assert [points(d) for d in (0.0, 0.24, 0.25, 0.99, 1.0, 1.49, 1.5, 7.0, math.inf)] == [5, 5, 2, 2, 1, 1, 0, 0, 0]


def test_rules_name_the_field_and_bound():
    test = mission().with_obstacles([Obstacle(25, 5, 20, -10, 20), Obstacle(5, 5, 8, 20, 35, 0, 60)])
    broken = violations(test)
    assert "obstacles[0].l: 25 is outside the competition's [2, 20]" in broken
    assert "obstacles[1].h: 8 is outside the competition's [10, 25]" in broken
    assert len(broken) == 2  # r = 60 is within the rules
    turned = mission().with_obstacles([Obstacle(20, 4, 20, -10, 20, 0, 300)])  # = a 4 x 20 box turned by 30
    assert violations(turned) == ()
    assert violations(mission().with_obstacles([Obstacle(30, 4, 20, -10, 20, 0, 120)]))[0] == \
        "obstacles[0].w: 30 is outside the competition's [2, 20] (checked as the same box turned by r = 30, l and w " \
        "swapped)"
    four = mission().with_obstacles([Obstacle(2, 2, 20, -35 + 15 * i, 20) for i in range(4)])
    assert violations(four)[0].startswith("obstacles: 4 boxes")
    assert violations(mission().with_obstacles(seed_layout(3))) == ()


def test_unknown_case_study_is_one_line(monkeypatch):
    monkeypatch.setenv("SURREALIST_CASE_STUDIES", str(CASE_STUDIES))
    with pytest.raises(InvalidTestCase, match=r"case study 'mission9': not found in .*known: mission1, mission1-wind, "
                                              r"mission2, mission2-wind, mission3, mission3-wind\)$"):
        case_study_path("mission9")


def test_layout_mutators_span_exactly_the_rules():
    seed = mission().with_obstacles(seed_layout(3))
    env_like = layout_mutators(seed)
    assert len(env_like) == 18
    for m in env_like:
        low, high = m.valid_range(seed)
        field = {"x": "x", "y": "y", "r": "r", "sx": "l", "sy": "w", "sz": "h"}[m.kind.value]
        now = getattr(seed.obstacles[m.obstacle], field)
        assert (now + low, now + high) == pytest.approx(RULES.bounds(field))
    with pytest.raises(InvalidTestCase, match=r"obstacles\[0\].y 45 is outside \[10, 40\]"):
        env_like[1].apply(seed, 20.0)


def test_distances_between_failures():
    line = np.column_stack([np.zeros(50), np.linspace(0, 50, 50), np.full(50, 10.0)])
    shifted = line + [1.5, 0, 0]
    assert trajectory_distance(line, line) == 0.0
    assert trajectory_distance(line, shifted) == pytest.approx(1.5)
    a, b = [Obstacle(2, 2, 20, 0, 20)], [Obstacle(2, 2, 20, 0, 20), Obstacle(2, 2, 20, 10, 30)]
    assert layout_distance(a, a) == 0.0
    assert layout_distance(a, b) == pytest.approx(math.hypot(11, 11) - 0, abs=1.5)


def test_suite_keeps_distinct_failures_and_the_closest_of_alike_ones():
    base = mission()
    line = np.column_stack([np.zeros(50), np.linspace(0, 50, 50), np.full(50, 10.0)])
    near = Member(base.with_obstacles([Obstacle(4, 4, 20, 3, 20)]), 1.2, line, 1)
    suite, said = Suite().offer(near)
    assert said == "added" and len(suite) == 1
    closer = Member(base.with_obstacles([Obstacle(4, 4, 20, 3.5, 20)]), 0.4, line, 2)
    suite, said = suite.offer(closer)
    assert said == "replaced 0" and suite.members[0].distance == 0.4
    farther = Member(base.with_obstacles([Obstacle(4, 4, 20, 3.2, 20)]), 1.0, line, 3)
    assert suite.offer(farther)[1] == "alike 0"
    elsewhere = Member(base.with_obstacles([Obstacle(4, 4, 20, -3, 40)]), 1.0, line + [-2, 0, 0], 4)
    suite, said = suite.offer(elsewhere)
    assert said == "added" and len(suite) == 2
    assert suite.offer(Member(base.with_obstacles([Obstacle(4, 4, 20, 9, 20)]), 2.0, line, 5))[1] == "passed"
    spread = diversity(suite.members)
    assert spread["members"] == 2 and spread["flight_mean_m"] == pytest.approx(2.0)


def test_case_study_env_passes_gymnasiums_checker():
    env = gym.make("Surrealist-CaseStudy-v1", case_study=CASE_STUDIES / "mission2.yaml", budget=4,
                   executor="inline", obstacles=1)
    check_env(env.unwrapped)
    env.close()


def test_invalid_and_infeasible_tests_are_not_flown():
    env = gym.make("Surrealist-CaseStudy-v1", case_study=CASE_STUDIES / "mission1.yaml", budget=5,
                   executor="inline").unwrapped
    env.reset()
    assert (env.test_for(env.seed_action).obstacles == env.seed_test.obstacles)  # the seed's action: not 0
    on_top = env.action_for([28.0] + [0.0] * 17)  # box 0 moved onto box 1, the others where the seed has them
    _, reward, _, _, info = env.step(on_top)
    assert "overlap" in info["invalid"] and info["evaluations"] == 1
    # three large boxes turned 45 degrees, corner to corner across the track, wall the mission off
    values = np.zeros(18)
    for i, x in enumerate((-28.5, 0.0, 28.5)):
        seed_box = env.seed_test.obstacles[i]
        values[6 * i:6 * i + 6] = [x - seed_box.x, 26 - seed_box.y, 20 - seed_box.l, 20 - seed_box.w, 0,
                                   45 - seed_box.r]
    _, _, _, _, info = env.step(env.action_for(values))
    assert info["invalid"] is not None and info["invalid"].startswith("infeasible")
    assert info["evaluations"] == 1  # neither cost budget
    # a box beside the take-off point: every run would fail before the planner has anything to do
    values = np.zeros(18)
    seed_box = env.seed_test.obstacles[1]
    values[:6] = 0.0
    values[6:12] = [-seed_box.x, 11.0 - seed_box.y, 4 - seed_box.l, 20 - seed_box.w, 0, -seed_box.r]
    _, _, _, _, info = env.step(env.action_for(values))
    assert info["invalid"] == ("degenerate: the take-off point is 1.00 m from obstacles[1], within the 1.5 m "
                               "safety distance: every run would fail before flying")
    assert info["evaluations"] == 1
    env.close()


def test_a_search_keeps_a_suite_of_real_failures():
    """Random search on mission1 for 12 evaluations: every member of the suite failed by the competition's
    distance, members are pairwise distinct, and the suite only grows from tests the env flew."""
    from search.random import RandomSearch

    env = RecordSuite(gym.make("Surrealist-CaseStudy-v1", case_study=CASE_STUDIES / "mission1.yaml", budget=12,
                               executor="inline", obstacles=2))
    said = []
    RandomSearch(seed=3).run(env, callback=lambda info: said.append(info.get("suite")))
    suite = env.suite
    assert all(m.distance < 1.5 or m.status == "collision" for m in suite.members)
    assert sum(s == "added" for s in said) >= len(suite)
    for i, a in enumerate(suite.members):
        for b in suite.members[i + 1:]:
            assert not suite.alike(a, b)
    env.close()


def test_wind_mutators_join_the_layout():
    env = gym.make("Surrealist-CaseStudy-v1", case_study=CASE_STUDIES / "mission1.yaml", budget=3, wind=True,
                   obstacles=1, executor="inline").unwrapped
    assert [m.name for m in env.mutators][-2:] == ["wind.speed", "wind.direction"]
    values = np.zeros(len(env.mutators))
    values[-2:] = [6.0, 90.0]  # 6 m/s, turned from north to east
    test = env.test_for(env.action_for(values))
    assert test.wind.velocity_mean == pytest.approx(6.0)
    assert test.wind.direction[:2] == pytest.approx((0.0, 1.0), abs=1e-9)
    assert test.obstacles == env.seed_test.obstacles
