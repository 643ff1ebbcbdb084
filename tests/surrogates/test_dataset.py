"""Features of stored tests: order invariance, relative-to-mission values, targets from real stores."""
import numpy as np
import pytest

from surrealist_gym.testcase import Obstacle
from surrogates.dataset import PER_OBSTACLE, DatasetError, Featurizer, load_dataset


def test_features_do_not_depend_on_obstacle_order(generate_featurizer):
    a = Obstacle(4, 3, 20, 17.0, 17.5, 0, 10)
    b = Obstacle(7, 5, 20, -6.0, 17.5, 0, 0)
    f = generate_featurizer
    assert np.array_equal(f.features([a, b]), f.features([b, a]))
    assert len(f.names) == f.features([a, b]).size == 2 * len(PER_OBSTACLE) + 5


def test_relative_features_of_a_box_on_a_straight_path():
    f = Featurizer(np.array([[0.0, 0.0], [20.0, 0.0]]), slots=1)
    row = dict(zip(f.names, f.features([Obstacle(2, 2, 5, 10.0, 3.0)])))
    assert row["o0.along"] == pytest.approx(0.5)
    assert row["o0.lateral"] == pytest.approx(3.0)          # right of the path (east of a northward leg)
    assert row["o0.gap"] == pytest.approx(2.0)              # |3| - half width 1
    assert row["o0.dist_path"] == pytest.approx(2.0)
    assert row["n_obstacles"] == 1


def test_featurizer_round_trip(replicate_featurizer):
    f = Featurizer.from_dict(replicate_featurizer.to_dict())
    obstacles = [Obstacle(3, 3, 3, -8.6, 1.7, 0, 158.8)]
    assert np.allclose(f.features(obstacles), replicate_featurizer.features(obstacles), atol=1e-3)


def test_dataset_from_real_stores(rq1_stores, replicate_featurizer):
    data = load_dataset(rq1_stores, replicate_featurizer)
    assert len(data) > 150 and data.X.shape == (len(data), len(replicate_featurizer.names))
    assert set(np.unique(data.groups)) == {0, 1}
    X, y = data.target("fitness")
    assert np.all(y < 0) and len(X) == len(y)
    assert np.all(data.targets["min_distance"] >= 0) and np.all((0 <= data.targets["unsafe"]) &
                                                                (data.targets["unsafe"] <= 1))
    assert data.trajectories.shape == (len(data), 32, 3) and np.isfinite(data.trajectories[0]).all()
    first = data.subset(data.groups == 0)
    assert len(first) + len(data.subset(data.groups == 1)) == len(data)


def test_bad_store_is_one_line_error(tmp_path, replicate_featurizer):
    bad = tmp_path / "bad.sqlite"
    bad.write_text("not sqlite at all" * 100)
    with pytest.raises(DatasetError, match="bad.sqlite"):
        load_dataset([bad], replicate_featurizer)
    with pytest.raises(DatasetError, match="no such evaluation store"):
        load_dataset([tmp_path / "missing.sqlite"], replicate_featurizer)


def test_datasets_of_two_stores_join(rq1_stores, replicate_featurizer):
    a, b = (load_dataset([s], replicate_featurizer) for s in rq1_stores)
    both = a.concat(b)
    assert len(both) == len(a) + len(b) and set(both.groups) == {0, 1}
    assert np.array_equal(both.X[len(a):], b.X) and both.keys[len(a):] == b.keys


def test_a_dataset_knows_the_noise_mode_of_its_stores(rq2_store, generate_featurizer, tmp_path):
    # a store flown with common random numbers, one flown with each test's own noise, and both (mixed: None)
    import gymnasium as gym

    import surrealist_gym  # noqa: F401 - registers the envs

    crn = tmp_path / "crn.sqlite"
    env = gym.make("Surrealist-Generate-v0", budget=1, runs=1, executor="inline", store=crn,
                   sim_config={"common_noise": True})
    env.reset(seed=0)
    env.close()
    common, own = (load_dataset([s], generate_featurizer) for s in (crn, rq2_store))
    assert common.common_noise is True and own.common_noise is False
    assert load_dataset([rq2_store, crn], generate_featurizer).common_noise is None
    from surrealist_gym.evaluation import describe_noise
    assert describe_noise(None) == "a mix of both noise modes"  # as `surrogate train` prints a mixed dataset
    assert own.concat(common).common_noise is None and own.concat(own).common_noise is False


def test_first_runs_of_a_store_written_now_are_scored_from_its_run_trajectories(tmp_path):
    """A store written by today's evaluator keeps each run's trajectory instead of a first-runs term: the dataset
    scores the first k runs with the problem's objective, as the evaluator does on demand (replication: in 3-D)."""
    import gymnasium as gym

    from surrogates.dataset import Featurizer, load_dataset

    store = tmp_path / "r.sqlite"
    env = gym.make("Surrealist-Replicate-v0", budget=2, runs=3, executor="inline", store=store).unwrapped
    _, info = env.reset(seed=0)
    expected = [env.evaluator.evaluate(info["test"], runs=k).fitness for k in (1, 2)]
    featurizer = Featurizer.for_env(env)
    env.close()
    data = load_dataset([store], featurizer)
    assert data.first_runs.shape == (1, 2) and np.allclose(data.first_runs[0], expected)
    saved = Featurizer.from_dict(featurizer.to_dict())
    assert saved.reference.shape[1] == 3  # saved to 0.1 mm: the features agree to that
    assert np.allclose(saved.transform([info["test"]]), featurizer.transform([info["test"]]), atol=1e-3)
