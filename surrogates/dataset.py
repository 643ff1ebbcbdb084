"""Datasets for surrogate models: features of each stored test, and the outcomes it had.

A store holds a test's obstacles only; the mission (and, for replication, the reference trajectory) comes from
the problem the store was searched on, so a dataset is built from ``(stores, context)`` where the
:class:`Featurizer` carries that context. Its features are invariant to the order of the obstacles: the
obstacles are sorted by their position along the mission (then across it) and laid out in fixed slots, and
pooled features (the minimum clearances over all obstacles) follow them.

Per obstacle [m, or unitless]: size ``l, w, h``, position ``x, y, z``, ``sin r, cos r, sin 2r, cos 2r``,
footprint area, the along-track position of its centre (fraction of the mission path), its signed lateral
offset from the nearest mission segment, its half extent across that segment, the gap between its footprint and
the segment (negative when it blocks the straight path), the footprint distance to the mission path and to the
reference trajectory (if known), how many reference points pass within 3 m of it, the extent of its footprint
along and across the path (corners projected on the nearest segment), and the mean lateral offset of the
reference where it passes beside the obstacle.

With ``lowfi`` (a :class:`~surrogates.lowfi.LowFidelity`), the outcomes of one low-fidelity flight of the test
follow (DTW and Fréchet to the reference, clearances, collision, duration, extent): a multi-fidelity surrogate.

Example:
    >>> import surrealist_gym as sg
    >>> featurizer = Featurizer.for_problem("generate")
    >>> featurizer.transform([sg.load_test(sg.data_path("rq2-seed.yaml"))]).shape
    (1, 53)
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from surrealist_gym.aerialist import parse_obstacles
from surrealist_gym.errors import SurrealistError
from surrealist_gym.evaluation import flown_with_common_noise
from surrealist_gym.geometry import obstacle_distances
from surrealist_gym.outcomes import outcomes
from surrealist_gym.store import EvaluationStore
from surrealist_gym.testcase import Obstacle, TestCase

from .lowfi import NAMES as LOWFI_NAMES, LowFidelity

PER_OBSTACLE = ("present", "l", "w", "h", "x", "y", "z", "sin_r", "cos_r", "sin_2r", "cos_2r", "area",
                "along", "lateral", "half_across", "gap", "dist_path", "dist_reference", "near_reference",
                "along_min", "along_max", "lateral_min", "lateral_max", "ref_lateral")
POOLED = ("n_obstacles", "min_gap", "min_dist_path", "min_dist_reference", "sum_near_reference")
TARGETS = ("fitness", "min_distance", "unsafe", "crash")
NEAR = 3.0             # [m], radius of the "reference points near the obstacle" count
TRAJECTORY_POINTS = 32  # resampled length of the trajectory target


class DatasetError(SurrealistError):
    """A store or model context cannot be turned into a dataset."""


@dataclass(frozen=True)
class Featurizer:
    """Turns test cases into fixed-length feature vectors, given the mission path and (optionally) a reference.

    Args:
        path: (K, 2) mission path in the local frame [m] (the positions of the mission items, in order).
        reference: (N, 2 or 3) reference trajectory [m], or None (generation has no reference).
        slots: obstacle slots; tests with more obstacles keep the first ``slots`` in canonical order.
        lowfi: a low-fidelity simulator of the problem whose outcomes are appended to the features, or None.
    """

    path: np.ndarray
    reference: np.ndarray | None = None
    slots: int = 2
    lowfi: LowFidelity | None = None

    def __post_init__(self):
        path = np.asarray(self.path, dtype=np.float64).reshape(-1, 2)
        if len(path) < 2:
            raise DatasetError(f"featurizer: the mission path needs at least 2 positions, got {len(path)}")
        object.__setattr__(self, "path", path)
        if self.reference is not None:
            ref = np.asarray(self.reference, dtype=np.float64)  # kept whole: the objective judges in 3-D
            object.__setattr__(self, "reference", ref.copy() if len(ref) else None)
        # the features measure the reference in the x-y plane
        object.__setattr__(self, "_reference_xy", None if self.reference is None else self.reference[:, :2])
        dense = [np.linspace(a, b, max(2, int(np.ceil(np.linalg.norm(b - a) / 0.5)) + 1))
                 for a, b in zip(path[:-1], path[1:])]
        object.__setattr__(self, "_dense", np.concatenate(dense))
        lengths = np.linalg.norm(np.diff(path, axis=0), axis=1)
        object.__setattr__(self, "_cumulative", np.concatenate([[0.0], np.cumsum(lengths)]))

    # --- construction -----------------------------------------------------------------------------------------
    @classmethod
    def for_test(cls, test: TestCase, reference=None, slots: int | None = None, lowfi: bool = False) -> "Featurizer":
        """The featurizer of a problem's seed test (its mission) and reference trajectory; ``lowfi`` adds the
        outcomes of a low-fidelity flight of each test."""
        if test.mission is None or len(test.mission.waypoints) < 2:
            raise DatasetError("featurizer: the seed test has no mission with 2 positions to measure obstacles "
                               "against")
        path = [(x, y) for x, y, _ in test.mission.waypoints]
        ref = None if reference is None else np.asarray(reference, dtype=np.float64)
        return cls(np.asarray(path), ref, slots if slots is not None else max(1, len(test.obstacles)),
                   LowFidelity(test, ref) if lowfi else None)

    @classmethod
    def for_env(cls, env, lowfi: bool = False) -> "Featurizer":
        """The featurizer of a Surrealist env (its seed test, and its reference trajectory if it replicates)."""
        env = env.unwrapped
        reference = getattr(env, "reference", None)
        return cls.for_test(env.seed_test, None if reference is None else np.asarray(reference), lowfi=lowfi)

    @classmethod
    def for_problem(cls, problem: str = "replicate", seed_test=None, log=None, lowfi: bool = False) -> "Featurizer":
        """The featurizer of the bundled problems: ``replicate`` (case0, its reference) or ``generate`` (RQ2)."""
        import surrealist_gym as sg
        from surrealist_gym.aerialist import load_test

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            if problem == "replicate":
                test = load_test(seed_test or sg.data_path("rq1-seed1.yaml"))
                from surrealist_gym.logs import read_flight
                flight = read_flight(log or test.reference_log or sg.data_path("case0.ulg"))
                test = replace(test, reference_log=str(flight.path))  # its parameters, as the env flies them
                return cls.for_test(test, np.asarray(flight.trajectory), lowfi=lowfi)
            if problem == "generate":
                return cls.for_test(load_test(seed_test or sg.data_path("rq2-seed.yaml")), lowfi=lowfi)
        raise DatasetError(f"problem {problem!r}: expected 'replicate' or 'generate'")

    def to_dict(self) -> dict:
        """A JSON-able form (saved in a model's metadata; a low-fidelity simulator is saved by ``save``)."""
        return {"path": self.path.tolist(), "reference": None if self.reference is None else
                np.round(self.reference, 4).tolist(), "slots": self.slots, "lowfi": self.lowfi is not None}

    @classmethod
    def from_dict(cls, data: dict, folder=None) -> "Featurizer":
        """The featurizer of ``to_dict``; a low-fidelity one reads its simulator from ``folder`` (see ``save``)."""
        lowfi = None
        if data.get("lowfi"):
            if folder is None:
                raise DatasetError("featurizer: a low-fidelity featurizer needs the folder it was saved to")
            lowfi = LowFidelity.load(folder)
        return cls(np.asarray(data["path"]), None if data.get("reference") is None else
                   np.asarray(data["reference"]), int(data["slots"]), lowfi)

    def save(self, folder) -> None:
        """Write what ``to_dict`` leaves out (the low-fidelity simulator's problem) to ``folder``."""
        if self.lowfi is not None:
            self.lowfi.save(folder)

    # --- features ---------------------------------------------------------------------------------------------
    @property
    def names(self) -> list[str]:
        """Feature names, in column order."""
        names = [f"o{i}.{n}" for i in range(self.slots) for n in PER_OBSTACLE] + list(POOLED)
        return names + list(LOWFI_NAMES) if self.lowfi is not None else names

    def transform(self, tests: Iterable) -> np.ndarray:
        """(n, features) for test cases, or obstacle tuples, or stored ``{"obstacles": [...]}`` dicts."""
        rows = [self.features(_obstacles_of(t)) for t in tests]
        return np.asarray(rows, dtype=np.float64).reshape(len(rows), len(self.names))

    def features(self, obstacles: Sequence[Obstacle]) -> np.ndarray:
        """The feature vector of one layout of obstacles."""
        rows = sorted((self._obstacle_features(o) for o in obstacles),
                      key=lambda r: (round(r[12], 6), round(r[13], 6), r[4], r[5]))  # along, lateral, x, y
        out, pooled = np.zeros((self.slots, len(PER_OBSTACLE))), [0.0, 50.0, 50.0, 50.0, 0.0]
        if rows:
            arr = np.asarray(rows)
            out[:min(len(rows), self.slots)] = arr[:self.slots]
            pooled = [len(rows), arr[:, 15].min(), arr[:, 16].min(), arr[:, 17].min(), arr[:, 18].sum()]
        parts = [out.ravel(), pooled]
        if self.lowfi is not None:
            parts.append(self.lowfi.outcomes(obstacles))
        return np.concatenate(parts)

    def _obstacle_features(self, o: Obstacle) -> list[float]:
        rad = math.radians(o.r)
        centre = np.array([o.x, o.y])
        a, seg = self.path[:-1], np.diff(self.path, axis=0)
        length2 = np.maximum((seg ** 2).sum(axis=1), 1e-12)
        t = np.clip(((centre - a) * seg).sum(axis=1) / length2, 0.0, 1.0)
        k = int(np.argmin(np.linalg.norm(centre - (a + t[:, None] * seg), axis=1)))  # the nearest segment
        length = math.sqrt(length2[k])
        direction = seg[k] / length

        def frame(points):  # along and across that segment from its start (across: + to the right, NED)
            rel = points - a[k]
            return rel @ direction, direction[0] * rel[..., 1] - direction[1] * rel[..., 0]

        lateral = float(frame(centre)[1])
        along = (self._cumulative[k] + t[k] * length) / max(self._cumulative[-1], 1e-9)
        theta = rad - math.atan2(direction[1], direction[0])
        if o.shape.value == "cylinder":
            half_across, area = o.l / 2, math.pi * o.l * o.l / 4
        else:
            half_across, area = abs(o.l / 2 * math.sin(theta)) + abs(o.w / 2 * math.cos(theta)), o.l * o.w
        dist_path = float(obstacle_distances(self._dense, [o]).min())
        c_along, c_lat = frame(np.asarray(o.footprint()))
        if self.reference is None:
            dist_ref, near, ref_lateral = dist_path, 0.0, 0.0
        else:
            d_ref = obstacle_distances(self._reference_xy, [o])[:, 0]
            dist_ref, near = float(d_ref.min()), float((d_ref < NEAR).sum())
            # where the reference passed, across the path, beside the obstacle
            r_along, r_lat = frame(self._reference_xy)
            beside = (r_along >= c_along.min() - 1.0) & (r_along <= c_along.max() + 1.0)
            ref_lateral = float(r_lat[beside].mean()) if beside.any() else 0.0
        return [1.0, o.l, o.w, o.h, o.x, o.y, o.z, math.sin(rad), math.cos(rad), math.sin(2 * rad),
                math.cos(2 * rad), area, along, lateral, half_across, abs(lateral) - half_across, dist_path, dist_ref,
                near, float(c_along.min()), float(c_along.max()), float(c_lat.min()), float(c_lat.max()), ref_lateral]


def _obstacles_of(item) -> tuple[Obstacle, ...]:
    if isinstance(item, TestCase):
        return item.obstacles
    if isinstance(item, dict):
        return parse_obstacles(item.get("obstacles"), "stored test")
    return tuple(item)


# --- datasets ------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Dataset:
    """Features and targets of stored evaluations.

    Attributes:
        X: (n, features) feature matrix.
        targets: ``fitness`` (maximised), ``min_distance`` (smallest 2-D footprint distance over the runs [m]),
            ``unsafe`` and ``crash`` (share of runs closer than 1.5 m / that collided), each (n,).
        trajectories: (n, 32, 3) judged trajectory resampled to 32 points [m] (NaN when not stored).
        groups: (n,) index of the store each row comes from (for held-out splits by store).
        keys: test key of each row.
        names: feature names.
        first_runs: (n, runs - 1) fitness of each test's first k runs alone (column k-1; NaN when not stored), to
            calibrate racing (:mod:`surrogates.prescreen`).
        common_noise: whether the evaluations were flown with common random numbers (``SimConfig.common_noise``),
            None when the stores mix both noise modes.
    """

    X: np.ndarray
    targets: dict[str, np.ndarray]
    trajectories: np.ndarray
    groups: np.ndarray
    keys: tuple[str, ...]
    names: tuple[str, ...] = field(default=())
    first_runs: np.ndarray | None = None
    common_noise: bool | None = False

    def __post_init__(self):
        if self.first_runs is None:
            object.__setattr__(self, "first_runs", np.full((len(self.X), 0), np.nan))

    def __len__(self) -> int:
        return len(self.X)

    def subset(self, mask) -> "Dataset":
        """The rows selected by a boolean mask or index array."""
        idx = np.arange(len(self))[mask]
        return Dataset(self.X[idx], {k: v[idx] for k, v in self.targets.items()}, self.trajectories[idx],
                       self.groups[idx], tuple(self.keys[i] for i in idx), self.names, self.first_runs[idx],
                       self.common_noise)

    def concat(self, other: "Dataset") -> "Dataset":
        """The rows of both datasets (same features); the other's store indices follow this one's."""
        if self.names != other.names:
            raise DatasetError("datasets with different features cannot be joined")
        offset = int(self.groups.max()) + 1 if len(self) else 0
        return Dataset(np.concatenate([self.X, other.X]),
                       {k: np.concatenate([v, other.targets[k]]) for k, v in self.targets.items()},
                       np.concatenate([self.trajectories, other.trajectories]),
                       np.concatenate([self.groups, other.groups + offset]), self.keys + other.keys, self.names,
                       stack_rows([*self.first_runs, *other.first_runs]),
                       self.common_noise if self.common_noise == other.common_noise else None)

    def target(self, name: str = "fitness") -> tuple[np.ndarray, np.ndarray]:
        """``(X, y)`` for one target, without the rows whose value is unknown (fitness of an unflown test)."""
        if name not in self.targets:
            raise DatasetError(f"target {name!r}: expected one of {', '.join(TARGETS)}")
        y = self.targets[name]
        ok = np.isfinite(y)
        return self.X[ok], y[ok]


def load_dataset(stores: Sequence, featurizer: Featurizer) -> Dataset:
    """A dataset from one or more evaluation stores (paths or EvaluationStore) searched on one problem."""
    rows, modes = [], set()  # modes: the noise modes the evaluations were flown with
    for g, source in enumerate(stores):
        store = source if isinstance(source, EvaluationStore) else _open(source)
        try:
            objective = _objective(store, featurizer)
            for ev in store:
                modes.add(flown_with_common_noise(ev))
                try:
                    x = featurizer.features(_obstacles_of(ev.test))
                except SurrealistError as err:
                    raise DatasetError(f"{store.path}: evaluation {ev.id}: {err}") from err
                runs = ev.runs or ()
                judged, n = outcomes(runs), max(len(runs), 1)
                rows.append((x, np.nan if ev.fitness is None else float(ev.fitness),
                             judged.closest if runs else np.nan, judged.unsafe / n, judged.crashes / n,
                             _resample((ev.info or {}).get("trajectory")), _first_runs_fitness(ev, objective), g,
                             ev.test_key))
        finally:
            if store is not source:
                store.close()
    if not rows:
        raise DatasetError(f"{', '.join(map(str, stores))}: no evaluations stored")
    X, fit, mind, unsafe, crash, trajs, first, groups, keys = zip(*rows)
    return Dataset(np.asarray(X), dict(zip(TARGETS, map(np.asarray, (fit, mind, unsafe, crash)))), np.asarray(trajs),
                   np.asarray(groups), keys, tuple(featurizer.names), stack_rows(first),
                   modes.pop() if len(modes) == 1 else None)


def _objective(store: EvaluationStore, featurizer: Featurizer):
    """The objective a store's search judged its tests by (its recorded settings, the featurizer's reference)."""
    from surrealist_gym.evaluation import GenerationObjective, ReplicationObjective

    problem = (store.identity or {}).get("problem") or {}
    if featurizer.reference is not None:  # a model saved before the reference was kept in 3-D cannot judge
        return (ReplicationObjective(featurizer.reference, problem.get("averaging", "dba"))
                if featurizer.reference.shape[1] == 3 else None)
    return GenerationObjective(problem.get("aggregate", "riskiest"), problem.get("measure", "paper"))


def _first_runs_fitness(ev, objective) -> list[float]:
    """The fitness of a stored evaluation's first k runs alone (k = 1 .. n-1), to calibrate racing: scored from its
    runs' trajectories, or the term stores kept before runs kept their trajectories."""
    info = ev.info or {}
    kept = (info.get("terms") or {}).get("first_runs_fitness")
    if kept is not None or not info.get("run_trajectories") or objective is None:
        return kept or []
    from surrealist_gym.evaluation import stored_runs

    test, runs = TestCase(obstacles=tuple(_obstacles_of(ev.test))), stored_runs(ev)
    return [objective(test, runs[:k]).fitness for k in range(1, len(runs))]


def stack_rows(rows) -> np.ndarray:
    """Rows of different lengths as one float matrix padded with NaN."""
    width = max((len(r) for r in rows), default=0)
    out = np.full((len(rows), width), np.nan)
    for i, r in enumerate(rows):
        out[i, :len(r)] = np.asarray(r, dtype=np.float64)
    return out


def _open(path) -> EvaluationStore:
    """An input store, opened read-only (an empty file or a FIFO is refused, and nothing is written to it)."""
    if not Path(path).exists():
        raise DatasetError(f"{path}: no such evaluation store")
    try:
        store = EvaluationStore(path, readonly=True)
    except SurrealistError as err:
        raise DatasetError(str(err)) from err
    try:
        len(store)
    except Exception as err:  # sqlite3.DatabaseError on a file that is not an evaluation store
        store.close()
        raise DatasetError(f"{path}: not an evaluation store ({err})") from err
    return store


def _resample(trajectory) -> np.ndarray:
    if not trajectory:
        return np.full((TRAJECTORY_POINTS, 3), np.nan)
    arr = np.asarray(trajectory, dtype=np.float64).reshape(-1, 3)
    s = np.linspace(0, len(arr) - 1, TRAJECTORY_POINTS)
    return np.stack([np.interp(s, np.arange(len(arr)), arr[:, i]) for i in range(3)], axis=1)
