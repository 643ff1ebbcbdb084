"""Replication and generation fitness on hand-made trajectories and obstacles with known answers."""
from __future__ import annotations

import math

import numpy as np
import pytest

from surrealist_gym.fitness import (
    Aggregate,
    Averaging,
    GenerationFitness,
    average_runs,
    generation_fitness,
    replication_fitness,
    run_distances,
)
from surrealist_gym.metrics import dtw, soft_dtw_barycenter
from surrealist_gym.outcomes import Measure, RunStatus, judged_distance, measure_for, outcomes
from surrealist_gym.testcase import Obstacle, Shape
from surrealist_gym.trajectory import Trajectory
from tests.conftest import REFERENCE_CSV

# Two 2 m x 2 m boxes, 5 m high, centred at y = +10 and y = -10: on the line x = 0 between them,
# the footprint distances are 9 - y and 9 + y, so their sum is 18 m everywhere.
NORTH_SOUTH = [Obstacle(l=2, w=2, h=5, x=0, y=10), Obstacle(l=2, w=2, h=5, x=0, y=-10)]


def _line(*ys: float, x: float = 0.0, z: float = 2.0) -> np.ndarray:
    return np.array([[x, y, z] for y in ys])


RUN_CLOSE = _line(0, 3, 6)     # min_dist 3 (at y = 6), sum_dist 18 -> score 24
RUN_FAR = _line(0, -1)         # min_dist 8 (at y = -1), sum_dist 18 -> score 34
RUN_ASIDE = _line(0, x=5)      # both distances hypot(4, 9) -> score 4 * sqrt(97)


def test_run_distances_on_known_geometry():
    assert run_distances(RUN_CLOSE, NORTH_SOUTH) == pytest.approx((18.0, 3.0))
    assert run_distances(RUN_FAR, NORTH_SOUTH) == pytest.approx((18.0, 8.0))
    assert run_distances(RUN_ASIDE, NORTH_SOUTH) == pytest.approx((2 * math.sqrt(97), math.sqrt(97)))


def test_sum_dist_and_min_dist_may_come_from_different_points():
    # One obstacle close to the second point only; the first point is close to the sum's minimiser.
    obstacles = [Obstacle(l=2, w=2, h=5, x=0, y=10), Obstacle(l=2, w=2, h=5, x=10, y=0)]
    run = _line(0, 8.5)  # (0,0): 9 + 9 = 18; (0, 8.5): 0.5 + hypot(9, 7.5) = 12.21...
    sum_dist, min_dist = run_distances(run, obstacles)
    assert min_dist == pytest.approx(0.5)
    assert sum_dist == pytest.approx(0.5 + math.hypot(9, 7.5))


def test_generation_fitness_scores_the_riskiest_run_by_default():
    result = generation_fitness([RUN_FAR, RUN_CLOSE, RUN_ASIDE], NORTH_SOUTH)
    assert isinstance(result, GenerationFitness)
    assert result.riskiest == 1
    assert result.fitness == pytest.approx(-24.0)
    assert result.aggregate is Aggregate.RISKIEST
    assert result.sum_dist == pytest.approx((18.0, 18.0, 2 * math.sqrt(97)))
    assert result.min_dist == pytest.approx((8.0, 3.0, math.sqrt(97)))
    assert result.scores == pytest.approx((34.0, 24.0, 4 * math.sqrt(97)))
    assert result.min_distance == pytest.approx(3.0)


def test_generation_fitness_mean_option():
    result = generation_fitness([RUN_FAR, RUN_CLOSE, RUN_ASIDE], NORTH_SOUTH, aggregate="mean")
    assert result.fitness == pytest.approx(-(34.0 + 24.0 + 4 * math.sqrt(97)) / 3)
    assert result.riskiest == 1
    assert result.aggregate is Aggregate.MEAN


def test_generation_fitness_single_run_and_trajectory_input():
    traj = Trajectory.from_array(RUN_CLOSE)
    assert generation_fitness([traj], NORTH_SOUTH).fitness == pytest.approx(-24.0)
    # Closer to an obstacle is riskier: a higher fitness.
    assert generation_fitness([RUN_CLOSE], NORTH_SOUTH).fitness > generation_fitness([RUN_FAR], NORTH_SOUTH).fitness


def test_generation_fitness_inside_an_obstacle_footprint_is_zero_distance():
    result = generation_fitness([_line(0, 10)], NORTH_SOUTH)
    assert result.min_dist == (0.0,)
    assert result.fitness == pytest.approx(-18.0)  # sum_dist 18 at y = 0 (19 at y = 10), min_dist 0


def test_generation_fitness_3d_counts_height():
    above = _line(10, z=8.0)  # over the 5 m high north box: 0 m in 2-D, 3 m in 3-D
    assert generation_fitness([above], NORTH_SOUTH).min_dist == (0.0,)
    result = generation_fitness([above], NORTH_SOUTH, dims=3)
    assert result.min_dist == pytest.approx((3.0,))
    assert result.sum_dist == pytest.approx((3.0 + math.hypot(19.0, 3.0),))


def test_generation_fitness_with_a_cylinder():
    tree = [Obstacle(l=2, w=2, h=5, x=3, y=4, shape=Shape.CYLINDER)]  # 5 m from the origin, radius 1
    assert generation_fitness([_line(0)], tree).fitness == pytest.approx(-(4.0 + 2 * 4.0))


def test_generation_fitness_bad_input():
    with pytest.raises(ValueError, match="aggregate"):
        generation_fitness([RUN_CLOSE], NORTH_SOUTH, aggregate="median")
    with pytest.raises(ValueError, match="runs"):
        generation_fitness([], NORTH_SOUTH)
    with pytest.raises(ValueError, match="obstacles"):
        generation_fitness([RUN_CLOSE], [])


def test_competition_measure_uses_the_polyline_between_points():
    """Two samples either side of a box: the paper's point distance sees 3 m, the competition's polyline crosses
    the footprint (0 m); sum_dist stays the paper's."""
    box = Obstacle(l=2, w=2, h=20, x=0, y=5)
    run = np.array([[-4.0, 5.0, 10.0], [4.0, 5.0, 10.0]])
    paper = generation_fitness([run], [box])
    competition = generation_fitness([run], [box], measure="competition")
    assert paper.min_dist == (3.0,) and competition.min_dist == (0.0,)
    assert competition.sum_dist == paper.sum_dist
    assert competition.fitness == pytest.approx(-3.0)


def test_measure_follows_the_test(shared_data):
    from surrealist_gym import load_test
    from tests.conftest import EXPERIMENTS, SHARED_DATA

    assert measure_for(load_test(EXPERIMENTS / "rq2-seed.yaml")) is Measure.PAPER
    assert measure_for(load_test(SHARED_DATA / "competition" / "case_studies" / "mission1.yaml")) is Measure.COMPETITION
    run = {"min_distance_2d": 2.0, "competition_distance": 1.2}
    assert judged_distance(run, "paper") == 2.0 and judged_distance(run, Measure.COMPETITION) == 1.2


def test_outcomes_judge_runs_once_by_status_and_measure():
    runs = [{"status": "collision", "min_distance_2d": 0.0, "competition_distance": 0.0},
            {"status": RunStatus.TIMEOUT, "min_distance_2d": 1.49, "competition_distance": 1.6},
            {"status": "success", "min_distance_2d": 1.5, "competition_distance": 1.2}]
    paper, competition = outcomes(runs), outcomes(runs, Measure.COMPETITION)
    assert (paper.runs, paper.crashes, paper.unsafe, paper.blocked, paper.closest) == (3, 1, 2, 1, 0.0)
    assert competition.unsafe == 2 and competition.unsafe_rate == pytest.approx(2 / 3)
    assert outcomes([]).runs == 0 and math.isnan(outcomes([]).crash_rate)
    with pytest.raises(ValueError):
        outcomes([{"status": "exploded", "min_distance_2d": 1.0}])


# --- replication -----------------------------------------------------------------------------------------------
def _helix(n: int = 40) -> np.ndarray:
    s = np.linspace(0, 4 * np.pi, n)
    return np.column_stack([10 * np.cos(s), 10 * np.sin(s), 2 * s])


def test_replication_fitness_of_one_run_is_minus_its_dtw(shared_data):
    ref = Trajectory.read_csv(REFERENCE_CSV)
    run = ref.shifted(dx=0.5)
    fitness, averaged = replication_fitness(ref, [run])
    assert averaged is run
    assert round(fitness, 2) == -33.01
    assert replication_fitness(ref, [ref])[0] == 0.0


def test_replication_fitness_with_dba_of_symmetric_runs_is_perfect():
    reference = _helix()
    runs = [reference + [d, -d, 0.5 * d] for d in (-0.4, -0.2, 0.0, 0.2, 0.4)]
    fitness, averaged = replication_fitness(reference, runs, averaging="dba")
    assert fitness == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(averaged, reference, atol=1e-9)


def test_replication_fitness_with_soft_dtw_uses_the_soft_barycenter():
    reference = _helix()
    runs = [reference + [d, 0.0, 0.0] for d in (-0.5, 0.0, 1.0)]
    fitness, averaged = replication_fitness(reference, runs, averaging=Averaging.SOFT_DTW, gamma=20.0)
    np.testing.assert_allclose(averaged, soft_dtw_barycenter(runs, gamma=20.0))
    assert fitness == pytest.approx(-dtw(reference, averaged))
    assert fitness < 0.0


def test_average_runs_bad_input():
    with pytest.raises(ValueError, match="averaging"):
        average_runs([_helix(), _helix()], averaging="mean")
    with pytest.raises(ValueError, match="runs"):
        replication_fitness(_helix(), [])
