"""A model of PX4's verdict: from our simulator's runs of a test, the probability that PX4 v1.12 SITL flies it under
1.5 m (the competition's soft failure) and under 1 m (its two-point band), learned on labelled PX4 SITL flights.

Two kinds of model on standardised features (:mod:`~surrealist_gym.fidelity.verdict_features`), both deterministic
and numpy only: a ridge logistic regression per target (Newton's method), or a ridge regression of log(PX4's distance
+ 0.1) with a normal residual (:class:`LogDistance`), which gives both targets from one fit. The default, chosen on
rilast-mission1's development half, is the latter on what the runs say, trained on the tests our runs bring within
6 m. Its parameters are a JSON file (:meth:`PX4Verdict.save`); the shipped one, ``surrealist_gym/data/
px4-verdict.json``, is refitted by ``surrealist predict --fit LABELS`` (docs/predict.md). The labelled sets hold no PX4
crash (rilast-mission1's closest PX4 flight passes at 0.65 m), so no probability of a PX4 crash is learned: the
under-1-m target is the nearest band the labels hold.

Example::

    >>> verdict = load_verdict()                                      # doctest: +SKIP
    >>> verdict.predict([test_features(test, runs)])                   # doctest: +SKIP
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..errors import SurrealistError
from .verdict_features import FEATURES, RUN_FEATURES, test_features

#: target -> PX4's distance below which a test counts [m]
TARGETS = {"unsafe": 1.5, "hard": 1.0}
# Chosen by leave-one-search-run-out cross-validation on rilast-mission1's development half (docs/predict.md,
# benchmarks/bench_px4_verdict.py): the kind of model, its ridge penalty, its features, and the tests it is trained on
# (those whose closest run of ours came within DEFAULT_NEAR_M [m]; None: all).
DEFAULT_KIND = "log-distance"
DEFAULT_L2 = 100.0
DEFAULT_FEATURES = RUN_FEATURES
DEFAULT_NEAR_M: float | None = 6.0
DEFAULT_RUNS = 3   #: runs per test the shipped model's features were computed from
SHIPPED = Path(__file__).resolve().parents[1] / "data" / "px4-verdict.json"
TABLE_COLUMNS = ("test", "half", "px4_result", "px4_distance_m", *FEATURES)


def half_of(test_id: str) -> str:
    """rilast-mission1's split (docs/fidelity.md): ``development`` for an even run number (random_run0_...,
    ga_run2_...), ``held-out`` for an odd one, ``-`` for a test without one."""
    m = re.search(r"run(\d+)_", test_id)
    return "-" if m is None else ("development" if int(m.group(1)) % 2 == 0 else "held-out")


@dataclass(frozen=True)
class Logistic:
    """One logistic regression: P(target) = sigmoid(intercept + coef . (x - mean) / scale)."""

    features: tuple[str, ...]
    mean: tuple[float, ...]
    scale: tuple[float, ...]
    coef: tuple[float, ...]
    intercept: float
    l2: float

    @classmethod
    def fit(cls, table: np.ndarray, positive: np.ndarray, features: Sequence[str], l2: float = DEFAULT_L2,
            iterations: int = 50) -> "Logistic":
        """Fit by Newton's method (iteratively reweighted least squares), the intercept unpenalised."""
        x = np.asarray(table, dtype=np.float64)
        y = np.asarray(positive, dtype=np.float64)
        mean, scale = x.mean(axis=0), x.std(axis=0)
        scale[scale == 0] = 1.0
        z = np.c_[np.ones(len(x)), (x - mean) / scale]
        penalty = np.full(z.shape[1], float(l2))
        penalty[0] = 0.0
        w = np.zeros(z.shape[1])
        for _ in range(iterations):
            p = 1.0 / (1.0 + np.exp(-(z @ w)))
            gradient = z.T @ (p - y) + penalty * w
            hessian = (z * (p * (1 - p))[:, None]).T @ z + np.diag(penalty) + 1e-9 * np.eye(len(w))
            step = np.linalg.solve(hessian, gradient)
            w -= step
            if np.abs(step).max() < 1e-10:
                break
        return cls(tuple(features), tuple(map(float, mean)), tuple(map(float, scale)), tuple(map(float, w[1:])),
                   float(w[0]), float(l2))

    def probability(self, table: np.ndarray) -> np.ndarray:
        """P(target) of each row of ``table`` (columns in :attr:`features`' order)."""
        z = (np.asarray(table, dtype=np.float64) - np.asarray(self.mean)) / np.asarray(self.scale)
        return 1.0 / (1.0 + np.exp(-(self.intercept + z @ np.asarray(self.coef))))


@dataclass(frozen=True)
class LogDistance:
    """PX4's distance as a log-normal: log(d + 0.1) = intercept + coef . (x - mean) / scale + N(0, sigma^2), so
    P(d < limit) = Phi((log(limit + 0.1) - mu) / sigma) (the same regression for both targets, each its limit [m],
    so P(d < 1 m) <= P(d < 1.5 m) always)."""

    features: tuple[str, ...]
    mean: tuple[float, ...]
    scale: tuple[float, ...]
    coef: tuple[float, ...]
    intercept: float
    sigma: float
    l2: float
    limit: float = TARGETS["unsafe"]

    @classmethod
    def fit(cls, table: np.ndarray, distance: np.ndarray, features: Sequence[str], l2: float = DEFAULT_L2,
            limit: float = TARGETS["unsafe"]) -> "LogDistance":
        """Ridge least squares (the intercept unpenalised); sigma from the residuals."""
        x = np.asarray(table, dtype=np.float64)
        y = np.log(np.asarray(distance, dtype=np.float64) + 0.1)
        mean, scale = x.mean(axis=0), x.std(axis=0)
        scale[scale == 0] = 1.0
        z = (x - mean) / scale
        coef = np.linalg.solve(z.T @ z + l2 * np.eye(z.shape[1]), z.T @ (y - y.mean()))
        residual = y - y.mean() - z @ coef
        return cls(tuple(features), tuple(map(float, mean)), tuple(map(float, scale)), tuple(map(float, coef)),
                   float(y.mean()), float(max(residual.std(), 1e-6)), float(l2), float(limit))

    def probability(self, table: np.ndarray, limit: float | None = None) -> np.ndarray:
        """P(PX4's distance < ``limit`` [m], default :attr:`limit`) of each row of ``table``."""
        limit = self.limit if limit is None else limit
        from scipy.special import ndtr

        z = (np.asarray(table, dtype=np.float64) - np.asarray(self.mean)) / np.asarray(self.scale)
        mu = self.intercept + z @ np.asarray(self.coef)
        return ndtr((math.log(limit + 0.1) - mu) / self.sigma)


@dataclass(frozen=True)
class PX4Verdict:
    """The two models and what they were trained on (``trained_on``: source, tests, runs, seed, UAV, halves)."""

    unsafe: Logistic | LogDistance
    hard: Logistic | LogDistance
    trained_on: dict = field(default_factory=dict)

    @property
    def runs(self) -> int:
        """Runs per test the features were computed from; predictions fly as many."""
        return int(self.trained_on.get("runs", DEFAULT_RUNS))

    def predict(self, rows: Sequence[dict]) -> tuple[np.ndarray, np.ndarray]:
        """P(PX4 < 1.5 m) and P(PX4 < 1 m) of each row of features (:func:`test_features`)."""
        return (self.unsafe.probability(_matrix(rows, self.unsafe.features)),
                self.hard.probability(_matrix(rows, self.hard.features)))

    def to_dict(self) -> dict:
        """JSON-ready parameters."""
        def model(m) -> dict:
            return {"kind": KINDS_OF[type(m)], **{k: list(v) if isinstance(v, tuple) else v
                                                  for k, v in dataclasses.asdict(m).items()}}

        return {"model": "surrealist_gym.fidelity.verdict: a model per target on standardised features",
                "targets": {k: f"PX4 distance < {v:g} m" for k, v in TARGETS.items()},
                "unsafe": model(self.unsafe), "hard": model(self.hard), "trained_on": self.trained_on}

    def save(self, path) -> Path:
        """Write the parameters as JSON (floats as Python writes them: a refit gives the same file)."""
        path = Path(path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="utf-8")
        except OSError as err:
            raise SurrealistError(f"{path}: cannot write the model ({err.strerror or err})") from err
        return path

    @classmethod
    def load(cls, path=None) -> "PX4Verdict":
        """Read a model JSON (default: the shipped one); a bad file is a one-line error naming it."""
        path = Path(path) if path is not None else SHIPPED
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
            models = {}
            for target in TARGETS:
                m = raw[target]
                kind = KINDS[m.get("kind", "logistic")]
                values = {}
                for f in dataclasses.fields(kind):
                    if f.name in m:
                        values[f.name] = (tuple(m[f.name]) if f.name == "features" else tuple(map(float, m[f.name]))
                                          if f.name in ("mean", "scale", "coef") else float(m[f.name]))
                    elif f.default is dataclasses.MISSING:
                        raise KeyError(f.name)
                models[target] = kind(**values)
                unknown = set(m["features"]) - set(FEATURES)
                if unknown or not len(m["features"]) == len(m["mean"]) == len(m["scale"]) == len(m["coef"]):
                    raise ValueError(f"field {target!r}: " + (f"unknown feature {sorted(unknown)[0]!r}" if unknown
                                                              else "features, mean, scale, coef differ in length"))
            return cls(models["unsafe"], models["hard"], dict(raw.get("trained_on", {})))
        except OSError as err:
            raise SurrealistError(f"{path}: cannot read the model ({err.strerror or err})") from err
        except (ValueError, KeyError, TypeError) as err:
            raise SurrealistError(f"{path}: not a PX4 verdict model ({err})") from err


KINDS = {"logistic": Logistic, "log-distance": LogDistance}  #: the models a target may have, by the name JSON gives
KINDS_OF = {kind: name for name, kind in KINDS.items()}


def load_verdict(path=None) -> PX4Verdict:
    """The model in ``path`` (default: the shipped ``surrealist_gym/data/px4-verdict.json``)."""
    return PX4Verdict.load(path)


def _matrix(rows: Sequence[dict], features: Sequence[str]) -> np.ndarray:
    return np.array([[float(row[f]) for f in features] for row in rows], dtype=np.float64).reshape(-1, len(features))


# --- the training table ----------------------------------------------------------------------------------------------
def training_table(lset, outcomes) -> list[dict]:
    """One row per labelled test: its name, half, PX4's result and distance, and the features of our runs."""
    return [{"test": label.test_id, "half": half_of(label.test_id), "px4_result": label.result,
             "px4_distance_m": label.distance, **test_features(test, runs)}
            for label, test, runs in zip(lset.labels, lset.tests, outcomes, strict=True)]


def write_table(rows: Sequence[dict], path) -> Path:
    """Write a training table as CSV (numbers rounded to 6 digits)."""
    path = Path(path)
    try:
        with open(path, "w", newline="", encoding="utf-8") as f:
            writer = csv.DictWriter(f, fieldnames=TABLE_COLUMNS)
            writer.writeheader()
            for row in rows:
                writer.writerow({k: (round(v, 6) if isinstance(v, float) else v) for k, v in row.items()})
    except OSError as err:
        raise SurrealistError(f"{path}: cannot write the training table ({err.strerror or err})") from err
    return path


def read_table(path) -> list[dict]:
    """Read a training table (:func:`write_table`); a missing column or a bad number is a one-line error."""
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            missing = [c for c in TABLE_COLUMNS if c not in (reader.fieldnames or [])]
            if missing:
                raise SurrealistError(f"{path}: row 1 (header): missing column {missing[0]!r}")
            rows = []
            for n, raw in enumerate(reader, start=2):
                row = {k: raw[k] for k in ("test", "half", "px4_result")}
                for k in ("px4_distance_m", *FEATURES):
                    try:
                        row[k] = float(raw[k]) if raw[k] != "" else math.nan
                    except ValueError:
                        raise SurrealistError(f"{path}: row {n}, field {k!r}: expected a number, got "
                                              f"{raw[k]!r}") from None
                rows.append(row)
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise SurrealistError(f"{path}: cannot read the training table ({err})") from err
    return rows


def is_table(path) -> bool:
    """Whether ``path`` is a training table (a CSV whose header holds :data:`TABLE_COLUMNS`), not a labelled set."""
    path = Path(path)
    if not path.is_file() or path.suffix.lower() != ".csv":
        return False
    try:
        with open(path, newline="", encoding="utf-8") as f:
            header = next(csv.reader(f), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return False
    return "d_min" in header and "px4_distance_m" in header


def fit_verdict(rows: Sequence[dict], *, halves: Sequence[str] | None = None, kind: str = DEFAULT_KIND,
                l2: float = DEFAULT_L2, features: Sequence[str] = DEFAULT_FEATURES,
                near_m: float | None = DEFAULT_NEAR_M, trained_on: dict | None = None) -> PX4Verdict:
    """Fit both targets on the rows PX4 flew (a distance), of ``halves`` only when given, and only those whose
    closest run of ours came within ``near_m`` [m] when given (the model then learns where the verdict is in doubt;
    it is applied to every test)."""
    used = [r for r in rows if r["px4_result"] == "flown" and math.isfinite(r["px4_distance_m"])
            and (halves is None or r["half"] in halves) and (near_m is None or r["d_min"] < near_m)]
    if not used:
        raise SurrealistError("no labelled test PX4 flew to fit the model on")
    x = _matrix(used, features)
    distance = np.array([r["px4_distance_m"] for r in used])
    if kind == "log-distance":
        models = {t: LogDistance.fit(x, distance, features, l2, limit) for t, limit in TARGETS.items()}
    else:
        models = {t: KINDS[kind].fit(x, distance < limit, features, l2) for t, limit in TARGETS.items()}
    info = {**(trained_on or {}), "tests": len(used), "halves": sorted(halves) if halves else "all",
            "near_m": near_m,
            "positives": {t: int((distance < limit).sum()) for t, limit in TARGETS.items()}}
    return PX4Verdict(models["unsafe"], models["hard"], info)


# --- predicting -----------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Prediction:
    """One test's prediction: P(PX4 < 1.5 m), P(PX4 < 1 m), and what our simulator flew (median distance [m],
    share of runs under 1.5 m or in collision, share in collision)."""

    test: str
    p_unsafe: float
    p_hard: float
    our_distance_m: float
    our_failure_share: float
    our_collision_share: float
    runs: int


def predict_runs(verdict: PX4Verdict, names: Sequence[str], tests: Sequence, outcomes) -> list[Prediction]:
    """The predictions for tests already flown (``outcomes``: each test's run records)."""
    rows = [test_features(t, runs) for t, runs in zip(tests, outcomes, strict=True)]
    unsafe, hard = verdict.predict(rows) if rows else (np.zeros(0), np.zeros(0))
    out = []
    for name, runs, row, pu, ph in zip(names, outcomes, rows, unsafe, hard):
        flown = [r for r in runs if r.flown]
        distances = [r.distance for r in flown if r.status != "timeout" and math.isfinite(r.distance)]
        out.append(Prediction(name, float(pu), float(ph), float(np.median(distances)) if distances else math.nan,
                              row["share_unsafe"], row["share_collision"], len(runs)))
    return out


def predict_tests(tests: Sequence, names: Sequence[str] | None = None, *, verdict: PX4Verdict | None = None,
                  runs: int | None = None, seed: int = 0, uav: str | None = None, workers: int | None = None,
                  executor=None, progress: Callable[[int, int], None] | None = None, store=None) -> list[Prediction]:
    """Fly each test ``runs`` times (default: as many as the model was trained with) on ``uav`` (default
    ``px4-v1.12-sitl-iris``) and predict PX4's verdict. ``store``: an SQLite file keeping the runs (resumable)."""
    from ..sim.uav import DEFAULT_UAV, decide_uav
    from .measure import fly_tests

    verdict = verdict or load_verdict()
    runs = runs or verdict.runs
    config = decide_uav(uav=uav or DEFAULT_UAV).config
    names = list(names) if names is not None else [f"test-{i}" for i in range(len(tests))]
    outcomes = fly_tests(list(tests), runs, seed, config, workers, 0.0, progress, executor, store, command="predict")
    return predict_runs(verdict, names, tests, outcomes)


# --- a pre-screen: PX4's verdict first ---------------------------------------------------------------------------
def rank_by_verdict(tests: Sequence, outcomes, expected: Sequence[float], verdict: PX4Verdict | None = None
                    ) -> tuple[list[int], list[Prediction]]:
    """The order (best first) of tests already flown (``outcomes``) by P(PX4 < 1.5 m) x ``expected`` (each test's
    expected score on our simulator), ties by ``expected`` then as given; and each test's prediction."""
    predictions = predict_runs(verdict or load_verdict(), [f"test-{i}" for i in range(len(tests))], tests, outcomes)
    key = [p.p_unsafe * e for p, e in zip(predictions, expected, strict=True)]
    return sorted(range(len(tests)), key=lambda i: (-key[i], -expected[i], i)), predictions


def write_ranking(path, files: Sequence, predictions: Sequence[Prediction], expected: Sequence[float],
                  order: Sequence[int]) -> Path:
    """Write the ranking :func:`rank_by_verdict` made as CSV, best first: file, P(PX4 < 1.5 m), P(PX4 < 1 m), our
    expected score and failure share."""
    path = Path(path)
    try:
        with open(path, "w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f)
            writer.writerow(["rank", "test", "p_px4_under_1_5m", "p_px4_under_1m", "expected_score",
                             "our_failure_share"])
            for rank, i in enumerate(order, start=1):
                p = predictions[i]
                writer.writerow([rank, Path(files[i]).name, round(p.p_unsafe, 4), round(p.p_hard, 4),
                                 round(float(expected[i]), 4), round(p.our_failure_share, 4)])
    except OSError as err:
        raise SurrealistError(f"{path}: cannot write the ranking ({err.strerror or err})") from err
    return path


__all__ = ["DEFAULT_FEATURES", "DEFAULT_KIND", "DEFAULT_L2", "DEFAULT_NEAR_M", "DEFAULT_RUNS", "KINDS", "LogDistance",
           "Logistic", "PX4Verdict", "Prediction", "SHIPPED", "TARGETS", "fit_verdict", "half_of", "is_table",
           "load_verdict", "predict_runs", "predict_tests", "rank_by_verdict", "read_table", "training_table",
           "write_ranking", "write_table"]
