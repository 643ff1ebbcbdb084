"""Profiles over time (altitude, horizontal speed, distance to goal) of a real flight."""
import numpy as np
import pytest

import surrealist_gym as sg
from surrealist_gym.trajectory import WINDOW_S, Trajectory, profile


@pytest.fixture(scope="module")
def case0():
    return sg.read_flight(sg.data_path("case0.ulg")).trajectory


def test_profile_of_a_real_flight(case0):
    p = profile(case0)
    assert len(p.t) == len(p.altitude) == len(p.horizontal_speed) == len(p.distance_to_goal) == len(case0)
    assert p.duration == pytest.approx(case0.duration) and 40 < p.duration < 45  # case0 flies ~42.6 s
    assert np.all(np.isfinite(p.horizontal_speed)) and np.all(p.horizontal_speed >= 0)
    assert 0.2 < p.horizontal_speed.mean() < p.horizontal_speed.max() < 10
    assert np.array_equal(p.altitude, case0.z) and p.altitude.max() > 3
    # the goal defaults to the last point: the distance starts at the flight's horizontal span and ends at 0
    assert p.distance_to_goal[-1] == pytest.approx(0.0)
    assert p.distance_to_goal[0] == pytest.approx(np.hypot(*(case0.xyz[-1, :2] - case0.xyz[0, :2])))
    summary = p.summary()
    assert summary["duration_s"] == pytest.approx(p.duration, abs=0.01) and summary["samples"] == len(case0)
    percentiles = summary["horizontal_speed_percentiles_mps"]
    assert percentiles["p10"] <= percentiles["p50"] <= percentiles["p90"] <= summary["max_horizontal_speed_mps"]


def test_points_without_times_are_taken_every_half_second(case0):
    # the pipeline's 0.5 s windows: the real flight's samples are ~0.5 s apart
    assert np.median(np.diff(case0.t)) == pytest.approx(WINDOW_S, abs=0.01)
    p = profile(case0.xyz)
    assert np.allclose(np.diff(p.t), WINDOW_S) and p.t[0] == 0
    assert p.horizontal_speed.mean() == pytest.approx(profile(case0).horizontal_speed.mean(), rel=0.1)


def test_straight_line_at_constant_speed_towards_a_goal():
    t = np.arange(11) * 0.5
    line = Trajectory(t, np.column_stack([2.0 * t, np.zeros_like(t), np.full_like(t, 5.0)]))  # 2 m/s north
    p = profile(line, goal=(20.0, 0.0, 0.0))
    assert np.allclose(p.horizontal_speed, 2.0)
    assert np.allclose(p.distance_to_goal, 20.0 - 2.0 * t)
    assert np.allclose(p.altitude, 5.0)
    assert profile(line.xyz[:1]).horizontal_speed.tolist() == [0.0]
    assert profile(np.zeros((0, 3))).summary() == {"duration_s": 0.0, "samples": 0}
