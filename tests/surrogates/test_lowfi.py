"""The low-fidelity simulator as a source of features: real (coarse, noise-free) flights of the bundled problems."""
import warnings
from dataclasses import replace

import numpy as np
import pytest

import surrealist_gym as sg
from surrogates.dataset import Featurizer
from surrogates.lowfi import NAMES, LowFidelity
from surrogates.models import SurrogateModel, evaluate_model, train_model


@pytest.fixture(scope="module")
def featurizer(replicate_lowfi_featurizer):
    return replicate_lowfi_featurizer


def test_outcomes_follow_the_obstacle_and_are_cached(featurizer):
    lowfi = featurizer.lowfi
    seed = lowfi.seed_test
    near = lowfi.outcomes(seed.obstacles)
    far_box = replace(seed.obstacles[0], x=seed.obstacles[0].x + 40.0)
    far = lowfi.outcomes((far_box,))
    runs = lowfi.runs
    assert np.array_equal(lowfi.outcomes(seed.obstacles), near) and lowfi.runs == runs  # cached by test key
    named = dict(zip(NAMES, near)), dict(zip(NAMES, far))
    assert named[0]["lowfi_dtw"] > 0 and named[0]["lowfi_log_dtw"] == pytest.approx(np.log1p(named[0]["lowfi_dtw"]))
    assert named[1]["lowfi_min_dist_2d"] > named[0]["lowfi_min_dist_2d"] + 10  # the box moved 40 m away
    assert seed.reference_log is None and "MPC_XY_CRUISE" in seed.params  # the log's parameters are frozen in


def test_featurizer_appends_the_outcomes_and_round_trips(featurizer, tmp_path):
    plain = Featurizer.for_problem("replicate")
    test = sg.load_test(sg.data_path("rq1-seed1.yaml"))
    x = featurizer.transform([test])
    assert x.shape == (1, len(plain.names) + len(NAMES)) and featurizer.names[-len(NAMES):] == list(NAMES)
    assert np.allclose(x[0, :len(plain.names)], plain.transform([test])[0])
    featurizer.save(tmp_path / "saved")
    text = (tmp_path / "saved" / "lowfi-seed.yaml").read_text()
    assert "commands_file" not in text and "params_file" not in text and "log_file" not in text  # self-contained
    (tmp_path / "saved").rename(tmp_path / "moved")
    again = Featurizer.from_dict(featurizer.to_dict(), tmp_path / "moved")
    assert np.allclose(again.transform([test]), x, atol=1e-3)  # the mission survives the .plan round trip


def test_multi_fidelity_model_saves_its_simulator(featurizer, rq1_lowfi_dataset, tmp_path):
    from scipy.stats import spearmanr

    data = rq1_lowfi_dataset
    X, y = data.target("fitness")
    lowfi_dtw = X[:, featurizer.names.index("lowfi_dtw")]
    assert spearmanr(-lowfi_dtw, y).statistic > 0.5  # the coarse flight alone already ranks the real fitness
    assert np.allclose(X[:, featurizer.names.index("lowfi_fitness")], -lowfi_dtw)  # replication: -DTW
    model = train_model(data, featurizer, "ensemble", config={"members": 3}, seed=0)
    assert evaluate_model(model, data)["spearman"] > 0.8
    folder = model.save(tmp_path / "m")
    assert {"lowfi-seed.yaml", "lowfi-mission.plan", "lowfi-reference.npy"} <= {p.name for p in folder.iterdir()}
    loaded = SurrogateModel.load(folder)
    assert isinstance(loaded.featurizer.lowfi, LowFidelity)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tests = [sg.load_test(sg.data_path("rq1-seed1.yaml"))]
    assert np.allclose(loaded.predict_tests(tests)[0], model.predict_tests(tests)[0], atol=1e-3)
