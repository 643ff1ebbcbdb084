"""Surrogate models: an ensemble of small MLPs (torch) whose spread gives the uncertainty, and a k-nearest-neighbours
baseline; both predict a mean and a standard deviation, are trained from a :class:`~surrogates.dataset.Dataset`,
and are saved as a folder holding ``weights.pt`` (tensors only, read back with ``torch.load(weights_only=True)``)
and ``meta.json`` (kind, target, hyper-parameters, featurizer context, training metrics).

The fitness target is modelled on a log scale when every value is negative (``t = -log(1 - fitness)``, monotone,
so rankings and improvements are the same); predictions come back on that scale from :meth:`SurrogateModel.predict`
and on the fitness scale from :meth:`SurrogateModel.predict_fitness`.

Example:
    >>> import numpy as np
    >>> X = np.random.default_rng(0).normal(size=(40, 3)); y = X[:, 0] - X[:, 1]
    >>> reg = KNNRegressor().fit(X, y, seed=0)
    >>> mean, std = reg.predict(X[:2]); mean.shape, bool((std >= 0).all())
    ((2,), True)
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from surrealist_gym.errors import DependencyNotInstalled, SurrealistError, regular_file

from .dataset import Dataset, Featurizer

FORMAT = "surrealist-surrogate/1"
KINDS = ("ensemble", "knn")
TRAIN_ARRAYS = ("train_X", "train_y", "train_groups", "train_first_runs")  # saved with the weights


class SurrogateModelError(SurrealistError):
    """A model file that is missing or is not a surrogate model."""


def _torch():
    try:
        import torch
    except ImportError as err:
        raise DependencyNotInstalled("surrogate models need torch: pip install torch==2.13.0 (CPU build), "
                                     "or pip install -e '.[surrogates]'") from err
    return torch


# --- regressors ----------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class EnsembleConfig:
    """Hyper-parameters of the MLP ensemble.

    Attributes:
        members: networks in the ensemble, each trained on its own bootstrap sample and initialisation.
        hidden: width of each of the two hidden layers.
        epochs: full-batch Adam steps.
        lr: learning rate.
        weight_decay: L2 penalty (AdamW).
    """

    members: int = 5
    hidden: int = 16
    epochs: int = 300
    lr: float = 3e-3
    weight_decay: float = 0.1


class EnsembleRegressor:
    """M two-hidden-layer MLPs trained at once (batched matrices); mean and spread over members, plus the
    out-of-bag residual variance as the noise floor of the uncertainty."""

    kind = "ensemble"

    def __init__(self, config: EnsembleConfig | None = None):
        self.config = config or EnsembleConfig()
        self.state: dict | None = None

    def fit(self, X: np.ndarray, y: np.ndarray, seed: int = 0) -> "EnsembleRegressor":
        """Train the ensemble on ``X`` (features) and ``y`` (fitness), seeded; returns self."""
        torch = _torch()
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # tiny matrices: one thread is fastest, and leaves the cores to the simulations
        try:
            cfg = self.config
            X, y = np.asarray(X, dtype=np.float64), np.asarray(y, dtype=np.float64)
            x_mean, x_std = X.mean(axis=0), X.std(axis=0)
            x_std[x_std < 1e-9] = 1.0
            y_mean, y_std = float(y.mean()), float(y.std()) or 1.0
            gen = torch.Generator().manual_seed(int(seed))
            xt = torch.as_tensor((X - x_mean) / x_std, dtype=torch.float32)
            yt = torch.as_tensor((y - y_mean) / y_std, dtype=torch.float32)
            n, d, m, h = len(X), X.shape[1], cfg.members, cfg.hidden
            counts = torch.stack([torch.bincount(torch.randint(n, (n,), generator=gen), minlength=n)
                                  for _ in range(m)]).float()  # (m, n) bootstrap weights
            params = {
                "w1": torch.randn(m, d, h, generator=gen) * math.sqrt(2.0 / d), "b1": torch.zeros(m, 1, h),
                "w2": torch.randn(m, h, h, generator=gen) * math.sqrt(2.0 / h), "b2": torch.zeros(m, 1, h),
                "w3": torch.randn(m, h, 1, generator=gen) * math.sqrt(1.0 / h), "b3": torch.zeros(m, 1, 1)}
            for p in params.values():
                p.requires_grad_(True)
            opt = torch.optim.AdamW(params.values(), lr=cfg.lr, weight_decay=cfg.weight_decay)
            xb = xt.expand(m, n, d)
            for _ in range(cfg.epochs):
                opt.zero_grad()
                loss = ((_forward(params, xb) - yt) ** 2 * counts).sum() / counts.sum()
                loss.backward()
                opt.step()
            with torch.no_grad():
                squared = (_forward(params, xb) - yt) ** 2
                oob = squared[counts == 0]  # each member's residuals on the rows its bootstrap left out
                noise = float(oob.mean()) if oob.numel() else float(squared.mean())
        finally:
            torch.set_num_threads(threads)
        self.state = {k: v.detach().clone() for k, v in params.items()}
        self.state.update(x_mean=torch.as_tensor(x_mean), x_std=torch.as_tensor(x_std),
                          y_scale=torch.tensor([y_mean, y_std, noise], dtype=torch.float64))
        return self

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The ensemble's mean and std of the fitness for each row of ``X`` (RuntimeError before :meth:`fit`)."""
        torch = _torch()
        if self.state is None:
            raise RuntimeError("predict() before fit()")
        s = self.state
        X = np.asarray(X, dtype=np.float64).reshape(-1, s["x_mean"].shape[0])
        xt = torch.as_tensor((X - s["x_mean"].numpy()) / s["x_std"].numpy(), dtype=torch.float32)
        with torch.no_grad():
            pred = _forward(s, xt.expand(s["w1"].shape[0], *xt.shape)).numpy().astype(np.float64)
        y_mean, y_std, noise = s["y_scale"].tolist()
        return pred.mean(axis=0) * y_std + y_mean, np.sqrt(pred.var(axis=0) + noise) * y_std


def _forward(p, x):
    torch = _torch()
    h = torch.nn.functional.silu(torch.bmm(x, p["w1"]) + p["b1"])
    h = torch.nn.functional.silu(torch.bmm(h, p["w2"]) + p["b2"])
    return (torch.bmm(h, p["w3"]) + p["b3"]).squeeze(-1)


@dataclass(frozen=True)
class KNNConfig:
    """Hyper-parameters of the k-nearest-neighbours baseline.

    Attributes:
        k: neighbours (in standardised feature space) averaged, weighted by inverse distance.
    """

    k: int = 7


class KNNRegressor:
    """The baseline: inverse-distance-weighted mean of the k nearest training points; their spread is the std."""

    kind = "knn"

    def __init__(self, config: KNNConfig | None = None):
        self.config = config or KNNConfig()
        self.state: dict | None = None

    def fit(self, X: np.ndarray, y: np.ndarray, seed: int = 0) -> "KNNRegressor":
        """Keep the standardised training rows (nothing to fit); returns self."""
        X, y = np.asarray(X, dtype=np.float64), np.asarray(y, dtype=np.float64)
        x_mean, x_std = X.mean(axis=0), X.std(axis=0)
        x_std[x_std < 1e-9] = 1.0
        self.state = {"x_mean": x_mean, "x_std": x_std, "X": (X - x_mean) / x_std, "y": y}
        return self

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The distance-weighted mean and std of the fitness of each row's k nearest training rows (RuntimeError
        before :meth:`fit`)."""
        if self.state is None:
            raise RuntimeError("predict() before fit()")
        s = self.state
        Z = (np.asarray(X, dtype=np.float64).reshape(-1, len(s["x_mean"])) - s["x_mean"]) / s["x_std"]
        d = np.linalg.norm(Z[:, None, :] - s["X"][None, :, :], axis=2)
        idx = np.argsort(d, axis=1, kind="stable")[:, :min(self.config.k, len(s["y"]))]
        w = 1.0 / (np.take_along_axis(d, idx, axis=1) + 1e-6)
        w /= w.sum(axis=1, keepdims=True)
        yk = s["y"][idx]
        mean = (w * yk).sum(axis=1)
        spread = np.sqrt((w * (yk - mean[:, None]) ** 2).sum(axis=1))
        floor = 0.05 * (float(s["y"].std()) or 1.0)
        return mean, np.sqrt(spread ** 2 + floor ** 2)


def _regressor(kind: str, config: dict | None = None):
    config = dict(config or {})
    try:
        if kind == "ensemble":
            return EnsembleRegressor(EnsembleConfig(**config))
        if kind == "knn":
            return KNNRegressor(KNNConfig(**config))
    except TypeError as err:
        raise SurrealistError(f"{kind} model: bad option ({err})") from err
    raise SurrealistError(f"model kind {kind!r}: expected one of {', '.join(KINDS)}")


# --- the model ------------------------------------------------------------------------------------------------------
class SurrogateModel:
    """A regressor, the featurizer its inputs come from, and the target scale; trains, predicts, saves, loads.

    Args:
        featurizer: how test cases become features (mission path, reference).
        kind: ``ensemble`` (MLP ensemble, torch) or ``knn`` (baseline).
        target: one of ``fitness``, ``min_distance``, ``unsafe``, ``crash``.
        config: hyper-parameters of the regressor (:class:`EnsembleConfig` / :class:`KNNConfig` fields).
        seed: seed of every random choice in training.
    """

    def __init__(self, featurizer: Featurizer, kind: str = "ensemble", target: str = "fitness",
                 config: dict | None = None, seed: int = 0):
        self.featurizer = featurizer
        self.kind = kind
        self.target = target
        self.seed = int(seed)
        self.regressor = _regressor(kind, config)
        self.log_scale = False
        self.train_X: np.ndarray | None = None
        self.train_y: np.ndarray | None = None
        self.train_groups: np.ndarray | None = None  # the store (search) each training row comes from
        self.train_first_runs: np.ndarray | None = None  # fitness of each row's first k runs (racing calibration)
        self.common_noise: bool | None = None  # the training evaluations' noise mode (None: not recorded)
        self.metrics: dict = {}
        self.path: Path | None = None  # the folder it was loaded from

    def to_scale(self, y) -> np.ndarray:
        """Target values -> the modelled scale (higher is better for fitness)."""
        y = np.asarray(y, dtype=np.float64)
        return -np.log1p(-np.minimum(y, 0.0)) if self.log_scale else y

    def from_scale(self, t) -> np.ndarray:
        """The modelled scale -> target values (the inverse of :meth:`to_scale`)."""
        t = np.asarray(t, dtype=np.float64)
        return -np.expm1(-t) if self.log_scale else t

    def fit(self, X: np.ndarray, y: np.ndarray, groups=None, first_runs=None) -> "SurrogateModel":
        """Train on features X and raw target values y (fitness etc.); ``groups`` names the search each row comes
        from (rows of one search in the order evaluated; default: all one search); ``first_runs`` (rows, k) the
        fitness of each row's first 1..k runs alone, kept to calibrate racing (not a feature)."""
        X, y = np.asarray(X, dtype=np.float64), np.asarray(y, dtype=np.float64)
        groups = np.zeros(len(y), dtype=np.int64) if groups is None else np.asarray(groups, dtype=np.int64)
        first_runs = np.full((len(y), 0), np.nan) if first_runs is None else np.asarray(first_runs, dtype=np.float64)
        ok = np.isfinite(y)
        X, y, groups = X[ok], y[ok], groups[ok]
        self.train_first_runs = first_runs.reshape(len(ok), -1)[ok]
        if len(y) < 2:
            raise SurrealistError(f"surrogate: need at least 2 evaluations with a known {self.target}, got {len(y)}")
        self.log_scale = self.target == "fitness" and bool((y <= 0).all())
        self.train_X, self.train_y, self.train_groups = X, y, groups
        self.regressor.fit(X, self.to_scale(y), seed=self.seed)
        return self

    def fit_dataset(self, dataset: Dataset) -> "SurrogateModel":
        """Train on a dataset's rows with a known target (and keep its noise mode)."""
        dataset.target(self.target)  # checks the name
        self.common_noise = dataset.common_noise
        return self.fit(dataset.X, dataset.targets[self.target], dataset.groups, dataset.first_runs)

    def predict(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation on the modelled scale (see :meth:`to_scale`)."""
        return self.regressor.predict(np.asarray(X, dtype=np.float64))

    def predict_fitness(self, X: np.ndarray) -> np.ndarray:
        """Predicted mean on the target's own scale."""
        return self.from_scale(self.predict(X)[0])

    def predict_tests(self, tests: Sequence) -> tuple[np.ndarray, np.ndarray]:
        """Mean and std (modelled scale) for test cases or stored test dicts."""
        return self.predict(self.featurizer.transform(tests))

    def save(self, path) -> Path:
        """Write ``path/weights.pt`` and ``path/meta.json``; returns the folder."""
        torch = _torch()
        if self.train_X is None:
            raise SurrealistError("surrogate: save() before fit()")
        out = Path(path)
        out.mkdir(parents=True, exist_ok=True)
        tensors = {f"regressor.{k}": torch.as_tensor(v) for k, v in self.regressor.state.items()}
        tensors.update({name: torch.as_tensor(getattr(self, name)) for name in TRAIN_ARRAYS})
        torch.save(tensors, out / "weights.pt")
        meta = {"format": FORMAT, "kind": self.kind, "target": self.target, "seed": self.seed,
                "log_scale": self.log_scale, "common_noise": self.common_noise,
                "config": asdict(self.regressor.config),
                "features": self.featurizer.names, "n_train": int(len(self.train_y)), "metrics": self.metrics,
                "featurizer": self.featurizer.to_dict()}
        self.featurizer.save(out)
        (out / "meta.json").write_text(json.dumps(meta, indent=1) + "\n")
        return out

    @classmethod
    def load(cls, path) -> "SurrogateModel":
        """Read a model folder written by :meth:`save` (weights with ``torch.load(weights_only=True)``)."""
        torch = _torch()
        folder = Path(path)
        try:
            meta = json.loads((folder / "meta.json").read_text())
            if not isinstance(meta, dict) or meta.get("format") != FORMAT:
                raise ValueError(f"meta.json format is {meta.get('format') if isinstance(meta, dict) else meta!r}, "
                                 f"expected {FORMAT}")
            tensors = torch.load(folder / "weights.pt", weights_only=True, map_location="cpu")
            model = cls(Featurizer.from_dict(meta["featurizer"], folder), meta["kind"], meta["target"], meta["config"],
                        meta["seed"])
            state = {k.split(".", 1)[1]: v for k, v in tensors.items() if k.startswith("regressor.")}
            model.regressor.state = {k: v.numpy() for k, v in state.items()} if model.kind == "knn" else state
            for name in TRAIN_ARRAYS[:3]:
                setattr(model, name, tensors[name].numpy())
            first_runs = tensors.get("train_first_runs")  # absent from models saved before it was kept
            model.train_first_runs = (np.full((len(model.train_y), 0), np.nan) if first_runs is None
                                      else first_runs.numpy())
            model.log_scale = bool(meta["log_scale"])
            model.common_noise = meta.get("common_noise")  # models saved before it was recorded: unknown
            model.metrics = meta.get("metrics", {})
            model.path = folder
        except SurrealistError:
            raise
        except Exception as err:  # missing file, bad JSON, bad pickle, missing key: all mean "not a model"
            raise SurrogateModelError(f"{path}: not a surrogate model ({type(err).__name__}: {err})") from err
        return model


def saved_noise_mode(path) -> bool | None:
    """The noise mode of a saved model's training stores (``meta.json``'s ``common_noise``), read without loading
    the model (nor torch); None when unknown, or when the folder is not a readable model (loading it says why)."""
    try:
        meta = json.loads(Path(regular_file(Path(path) / "meta.json", "surrogate model file")).read_text())
        return meta.get("common_noise")
    except (SurrealistError, OSError, ValueError, AttributeError):
        return None


def train_model(dataset: Dataset, featurizer: Featurizer, kind: str = "ensemble", target: str = "fitness",
                config: dict | None = None, seed: int = 0) -> SurrogateModel:
    """Train a new model on a dataset (every row with a known target)."""
    return SurrogateModel(featurizer, kind, target, config, seed).fit_dataset(dataset)


@dataclass(frozen=True)
class Predictions:
    """A model's predictions on a dataset: on the target scale (``true``, ``mean``, and ``low``/``high`` = the
    modelled mean -/+ one sd mapped back) and on the modelled scale (``modelled_true``, ``modelled_mean``,
    ``modelled_std``: the log scale of a log-scale model, the target scale otherwise)."""

    true: np.ndarray
    mean: np.ndarray
    low: np.ndarray
    high: np.ndarray
    modelled_true: np.ndarray
    modelled_mean: np.ndarray
    modelled_std: np.ndarray

    @property
    def z(self) -> np.ndarray:
        """Errors in predicted standard deviations (modelled scale)."""
        return np.abs(self.modelled_true - self.modelled_mean) / np.maximum(self.modelled_std, 1e-12)

    def metrics(self) -> dict:
        """``n``; ``r2``, ``spearman`` and ``mae`` of predicted vs true values (target scale); ``r2_modelled`` (R2 on
        the modelled scale); calibration of the uncertainty on the modelled scale: ``within_1sd``/``within_2sd``
        (share of true values within 1 and 2 predicted sd: 0.68 and 0.95 when calibrated) and ``nll`` (mean
        Gaussian negative log-likelihood)."""
        from scipy import stats

        y, pred, z, std = self.true, self.mean, self.z, self.modelled_std
        nll = 0.5 * np.log(2 * np.pi * std ** 2) + 0.5 * z ** 2
        rho = stats.spearmanr(pred, y)[0] if np.ptp(pred) > 0 and np.ptp(y) > 0 else float("nan")
        return {"n": int(len(y)), "r2": _r2(y, pred), "r2_modelled": _r2(self.modelled_true, self.modelled_mean),
                "spearman": float(rho), "mae": float(np.abs(y - pred).mean()),
                "within_1sd": float((z <= 1).mean()), "within_2sd": float((z <= 2).mean()), "nll": float(nll.mean())}


def predict_dataset(model: SurrogateModel, dataset: Dataset) -> Predictions:
    """The model's :class:`Predictions` for every row of ``dataset`` with a known target (at least 3)."""
    X, y = dataset.target(model.target)
    if len(y) < 3:
        raise SurrealistError(f"evaluation: need at least 3 evaluations with a known {model.target}, got {len(y)}")
    mean_t, std_t = model.predict(X)
    return Predictions(y, model.from_scale(mean_t), model.from_scale(mean_t - std_t),
                       model.from_scale(mean_t + std_t), model.to_scale(y), mean_t, std_t)


def evaluate_model(model: SurrogateModel, dataset: Dataset) -> dict:
    """Prediction quality on a dataset (see :meth:`Predictions.metrics`)."""
    return predict_dataset(model, dataset).metrics()


def _r2(true: np.ndarray, predicted: np.ndarray) -> float:
    ss_tot = float(((true - true.mean()) ** 2).sum())
    return 1.0 - float(((true - predicted) ** 2).sum()) / ss_tot if ss_tot > 0 else float("nan")
