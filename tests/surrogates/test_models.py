"""The MLP ensemble and the knn baseline on a real store: training, prediction, save/load, the CLI."""
import numpy as np
import pytest

from surrealist_gym.cli import main
from surrogates.dataset import load_dataset
from surrogates.models import SurrogateModel, SurrogateModelError, evaluate_model, train_model

SMALL = {"members": 3, "epochs": 150}


@pytest.fixture(scope="module")
def data(rq1_stores, replicate_featurizer):
    return load_dataset(rq1_stores, replicate_featurizer)


@pytest.fixture(scope="module")
def ensemble(data, replicate_featurizer):
    return train_model(data.subset(np.arange(len(data)) % 4 != 0), replicate_featurizer, "ensemble", config=SMALL,
                       seed=0)


def test_ensemble_learns_the_fitness(ensemble, data):
    train = evaluate_model(ensemble, data.subset(np.arange(len(data)) % 4 != 0))
    held_out = evaluate_model(ensemble, data.subset(np.arange(len(data)) % 4 == 0))  # every 4th evaluation
    assert train["spearman"] > 0.7 and held_out["spearman"] > 0.5
    assert train["r2_modelled"] > 0.5  # on the log scale the model works on, the long tail does not dominate
    mean, std = ensemble.predict(data.X[:5])
    assert np.all(np.isfinite(mean)) and np.all(std > 0)
    assert ensemble.log_scale and np.all(ensemble.predict_fitness(data.X[:5]) < 0)


def test_training_is_seeded(data, replicate_featurizer):
    part = data.subset(data.groups == 1)
    a = train_model(part, replicate_featurizer, config={"members": 2, "epochs": 30}, seed=3).predict(data.X[:4])
    b = train_model(part, replicate_featurizer, config={"members": 2, "epochs": 30}, seed=3).predict(data.X[:4])
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


@pytest.mark.parametrize("kind", ["ensemble", "knn"])
def test_save_load_round_trip(kind, ensemble, data, replicate_featurizer, tmp_path):
    import torch

    model = ensemble if kind == "ensemble" else train_model(data, replicate_featurizer, "knn")
    folder = model.save(tmp_path / kind)
    assert sorted(p.name for p in folder.iterdir()) == ["meta.json", "weights.pt"]
    assert "train_X" in torch.load(folder / "weights.pt", weights_only=True)
    loaded = SurrogateModel.load(folder)
    for a, b in zip(model.predict(data.X[:7]), loaded.predict(data.X[:7])):
        assert np.allclose(a, b)


def test_knn_baseline_predicts_its_training_points(data, replicate_featurizer):
    model = train_model(data, replicate_featurizer, "knn", config={"k": 1})
    X, y = data.target()
    assert evaluate_model(model, data)["spearman"] > 0.95 and model.predict(X[:3])[1].min() > 0


def test_corrupt_model_is_one_line_error(tmp_path):
    (tmp_path / "meta.json").write_text("{not json")
    with pytest.raises(SurrogateModelError, match="not a surrogate model"):
        SurrogateModel.load(tmp_path)


def test_cli_train_and_eval(rq1_stores, tmp_path, capsys):
    out = tmp_path / "model"
    assert main(["surrogate", "train", *map(str, rq1_stores), "--out", str(out), "--kind", "knn",
                 "--holdout", "1"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("held-out (1 of 2 stores): ") and "Spearman" in text and "weights.pt, meta.json" in text
    assert "flown with each test's own noise" in text
    png = tmp_path / "plots" / "eval.png"
    assert main(["surrogate", "eval", str(out), str(rq1_stores[1]), "--plot", str(png)]) == 0
    assert "within 1 sd (68% ideal)" in capsys.readouterr().out
    assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size > 10_000
    assert main(["surrogate", "eval", str(tmp_path / "nope"), str(rq1_stores[1])]) == 2
    assert "not a surrogate model" in capsys.readouterr().err
    assert main(["surrogate", "eval", str(out), str(rq1_stores[1]), "--plot", "/proc/no/eval.png"]) == 2
    assert "--plot /proc/no/eval.png: cannot write in /proc" in capsys.readouterr().err
    assert main(["surrogate", "train", str(rq1_stores[0]), "--out", str(out), "--holdout", "1"]) == 2
    assert "needs at least 2 stores" in capsys.readouterr().err


def test_cli_train_lowfi_reports_the_screening_margin(rq1_stores, tmp_path, capsys):
    out = tmp_path / "lowfi-model"
    assert main(["surrogate", "train", *map(str, rq1_stores), "--out", str(out), "--kind", "knn", "--lowfi"]) == 0
    text = capsys.readouterr().out
    assert "falls short of the incumbent's by more than" in text
    assert set(SurrogateModel.load(out).train_groups.tolist()) == {0, 1}  # one group per store, saved
