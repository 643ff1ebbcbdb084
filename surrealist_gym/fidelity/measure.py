"""Fidelity: how far the simulated UAV agrees with the system that produced a labelled set of Aerialist tests.

Each test of a labelled set (:mod:`surrealist_gym.fidelity.labels`) is flown in the simulator and compared with its
label on the 2-D competition distance (:func:`~surrealist_gym.geometry.competition_distance`), the outcome and the
airborne time (first to last moment above 0.3 m).

Outcome mapping: their ``flown`` (or ``success``) is our ``success``; their ``no_result`` (Aerialist's 500 s
timeout: no metric) or ``timeout`` is our ``timeout``; ``collision`` is ``collision``. Our ``stuck``, and any
status that no label of the set maps to, is a status the labels never show. Our ``timeout`` and ``stuck`` count as
blocked. A test "flew" when it has a distance: theirs is ``flown``; ours has at least one run that ended neither
in ``timeout`` nor ``error``.

Example::

    >>> report = measure_fidelity("rilast-mission1/tests.csv", limit=20, workers=2)   # doctest: +SKIP
    >>> report.close.spearman, report.close.auc                                         # doctest: +SKIP
"""
from __future__ import annotations

import csv
import json
import math
import os
import time
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..errors import FrozenDict, SurrealistError
from ..outcomes import BLOCKED as _BLOCKED, UNSAFE_DISTANCE_M, RunRecord, RunStatus, status_counts, statuses_text
from ..sim.uav import DEFAULT_UAV, decide_uav
from ..trajectory import airborne_time  # noqa: F401 - the airborne time of the report, named here too
from .labels import InvalidLabels, Label, LabelledSet, load_labelled_set

__all__ = ["DISTANCE_NAME", "FidelityReport", "InvalidLabels", "Label", "LabelledSet", "RegionStats", "TestRow",
           "airborne_time", "build_report", "fly_labelled_set", "fly_tests", "format_figure", "load_labelled_set",
           "measure_fidelity", "plot_report", "region_stats", "write_report"]

DISTANCE_NAME = "2-D competition distance"
TARGET_PRECISION = 0.6    # the best recall is sought at this precision or above
# their (normalised) result -> our status that means the same
SAME_STATUS = {"flown": "success", "timeout": "timeout", "collision": "collision"}
BLOCKED = tuple(s.value for s in _BLOCKED)
NO_DISTANCE = (RunStatus.TIMEOUT.value, RunStatus.ERROR.value)
STATUS_ORDER = tuple(s.value for s in (RunStatus.SUCCESS, RunStatus.TIMEOUT, RunStatus.STUCK, RunStatus.COLLISION,
                                       RunStatus.ERROR))


# --- flying ------------------------------------------------------------------------------------------------------
def fly_labelled_set(lset: LabelledSet, runs: int = 1, seed: int = 0, config=None, workers: int | None = None,
                     buffer: float = 0.0, progress: Callable[[int, int], None] | None = None, executor=None,
                     store=None) -> list[tuple[RunRecord, ...]]:
    """Fly every test of ``lset``: :func:`fly_tests` on its tests."""
    return fly_tests(list(lset.tests), runs, seed, config, workers, buffer, progress, executor, store)


def fly_tests(tests: Sequence, runs: int = 1, seed: int = 0, config=None, workers: int | None = None,
              buffer: float = 0.0, progress: Callable[[int, int], None] | None = None, executor=None,
              store=None, command: str = "fidelity") -> list[tuple[RunRecord, ...]]:
    """Fly every test (:func:`~surrealist_gym.executors.fly_many`) with ``config`` (default
    :class:`~surrealist_gym.sim.config.SimConfig`), the competition distance's polyline buffered by ``buffer`` [m].

    ``executor``: a Dask scheduler's address, a ``distributed.Client`` or an executor (default ``workers`` local
    processes, all cores and at most 8; 1: this process). Returns one tuple of run records per test, in their
    order; ``progress`` is called with (tests done, tests) as tests finish. A run whose simulation raises is retried
    once; if it raises again, it ends in ``error`` with the exception as message. ``store``: an SQLite file
    (:class:`~surrealist_gym.store.EvaluationStore`) that holds the runs of this measurement: those it holds are read
    back, not flown, and each chunk flown is written to it as it completes (a store of another measurement is a
    one-line error; ``command`` names the measurement in it).
    """
    from ..executors import default_workers, executor_for, fly_many
    from ..sim import SimConfig

    config = replace(config or SimConfig(), competition_buffer_m=buffer)
    db, have = None, [{} for _ in tests]
    if store is not None:
        db = open_store(store, tests, runs, seed, config, command)
        for row in db:
            have[row.info["test"]].update(
                (r["index"], RunRecord.from_dict(r, t)) for r, t in zip(row.runs, row.info["trajectories"]))
    held, finished = [len(h) for h in have], sum(len(h) == runs for h in have)

    def done(i: int, records: list) -> None:  # runs arrive chunk by chunk: a test is done when all its runs are
        nonlocal finished
        if db is not None:
            _store_runs(db, i, tests[i], records)
        held[i] += len(records)
        finished += held[i] == runs
        if progress and held[i] == runs:
            progress(finished, len(tests))

    try:
        with executor_for(executor, workers or default_workers()) as flying:
            return fly_many(list(tests), runs, seed, config, flying, have=have, done=done)
    finally:
        if db is not None:
            db.close()


def open_store(store, tests, runs: int, seed: int, config, command: str):
    """The measurement's store (``command``: ``fidelity``, ``calibrate``, ...), claimed for its identity (the tests,
    runs, seed and simulator settings)."""
    import hashlib

    from ..evaluation import named_tree_reuse
    from ..store import EvaluationStore

    def digest(value: str) -> str:
        return hashlib.sha1(value.encode()).hexdigest()[:16]

    db = EvaluationStore(store)
    try:
        db.claim({"command": command, "tests": [digest(t.key()) for t in tests], "runs": int(runs),
                  "seed": int(seed), "sim": digest(repr(config))} | named_tree_reuse([config]))
    except BaseException:
        db.close()
        raise
    return db


def _store_runs(db, i: int, test, records) -> None:
    """Write a chunk of runs of test ``i`` (with their trajectories) and commit it."""
    from ..store import StoredEvaluation

    db.add(StoredEvaluation(test.key(), {}, tuple(r.index for r in records), tuple(r.to_dict() for r in records),
                            None, {"test": i, "trajectories": [r.trajectory.xyz.tolist() for r in records]}))


# --- the report --------------------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class TestRow:
    """One labelled test with its simulated runs."""

    __test__ = False  # not a pytest class

    label: Label
    runs: tuple[RunRecord, ...]

    @property
    def distances(self) -> list[float]:
        """Competition distances [m] of the runs that flew (nan ones left out)."""
        return [r.distance for r in self.runs if r.status not in NO_DISTANCE and not math.isnan(r.distance)]

    @property
    def distance(self) -> float:
        """Median 2-D competition distance [m] over the runs that flew (nan if none did)."""
        d = self.distances
        return float(np.median(d)) if d else math.nan

    @property
    def both_flew(self) -> bool:
        """Whether theirs and ours both have a distance (theirs flown, ours finite)."""
        return self.label.result == "flown" and math.isfinite(self.distance)

    @property
    def failure_probability(self) -> float:
        """Share of the runs that flew with a distance below 1.5 m (nan if none flew)."""
        d = self.distances
        return float(np.mean(np.asarray(d) < UNSAFE_DISTANCE_M)) if d else math.nan

    @property
    def status(self) -> str:
        """The most common status of the runs (ties: the first in success, timeout, stuck, collision, error)."""
        counts = status_counts(self.runs)
        rank = {s: i for i, s in enumerate(STATUS_ORDER)}
        return min(counts, key=lambda s: (-counts[s], rank.get(s, len(rank)), s))

    @property
    def airborne_s(self) -> float:
        """Median airborne time [s] over the runs that did not end in error."""
        a = [r.airborne for r in self.runs if r.flown]
        return float(np.median(a)) if a else math.nan

    def to_dict(self) -> dict:
        """The row of ``fidelity.csv``: their figures and ours side by side, rounded."""
        lab = self.label
        ratio = self.airborne_s / lab.airborne_s if lab.airborne_s > 0 else math.nan
        return {"test": lab.test_id, "their_result": lab.result, "their_distance_m": _r(lab.distance),
                "our_distance_m": _r(self.distance), "our_failure_probability": _r(self.failure_probability),
                "our_status": self.status, "our_statuses": statuses_text(self.runs),
                "runs": len(self.runs), "their_airborne_s": _r(lab.airborne_s, 1),
                "our_airborne_s": _r(self.airborne_s, 1), "airborne_ratio": _r(ratio),
                "our_duration_s": _r(float(np.median([r.duration for r in self.runs])), 1)}


@dataclass(frozen=True, slots=True)
class RegionStats:
    """Agreement on the tests both flew in a region (all tests, or those with theirs < close)."""

    tests: int                  # tests both flew
    their_failures: int         # of them, theirs < 1.5 m
    spearman: float             # ours vs theirs, 2-D competition distance
    auc: float                  # their failures scored by our distance (smaller = riskier)
    precision: float            # of "ours < 1.5 m" for "theirs < 1.5 m"
    recall: float
    best_recall: float          # the largest recall at precision >= 0.6 over thresholds "ours <= t"
    best_threshold_m: float     # that t [m]
    their_failure_rate: float   # share of the tests with theirs < 1.5 m
    our_failure_rate: float     # mean share of our runs < 1.5 m


@dataclass(frozen=True, slots=True)
class FidelityReport:
    """Agreement of the simulated UAV with a labelled set (see the module docstring for the mapping)."""

    source: str
    labels_file: str
    runs: int
    seed: int
    close_m: float
    buffer_m: float
    uav: str | None
    rows: tuple[TestRow, ...]
    overall: RegionStats
    close: RegionStats
    confusion: FrozenDict            # their result -> our status -> runs
    blocked: FrozenDict              # agreement on timeouts / blocked flights
    unseen: FrozenDict               # runs ending in a status the labels never show
    durations: FrozenDict | None     # airborne ratios ours / theirs, when labelled
    wall_s: float

    def to_dict(self) -> dict:
        """The summary (no per-test rows), JSON-ready: nan and inf become None."""
        return {"distance": f"{DISTANCE_NAME} [m], buffer {self.buffer_m:g} m", "source": self.source,
               "labels_file": self.labels_file, "tests": len(self.rows), "runs_per_test": self.runs,
               "seed": self.seed, "close_m": self.close_m, "uav": self.uav,
               "their_results": dict(Counter(r.label.result for r in self.rows)),
               "our_statuses": dict(status_counts(run for r in self.rows for run in r.runs)),
               "overall": _clean(_asdict(self.overall)), "close": _clean(_asdict(self.close)),
               "confusion": {k: dict(v) for k, v in self.confusion.items()}, "blocked": _clean(dict(self.blocked)),
               "unseen_statuses": _clean(dict(self.unseen)),
               "durations": None if self.durations is None else _clean(dict(self.durations)),
               "wall_s": round(self.wall_s, 2),
               "tests_per_s": round(len(self.rows) / self.wall_s, 3) if self.wall_s > 0 else None}

    def to_json(self) -> str:
        """The report as indented JSON (:meth:`to_dict`)."""
        return json.dumps(self.to_dict(), indent=2)


def _asdict(obj) -> dict:
    return {name: getattr(obj, name) for name in obj.__slots__}


def _r(value: float, digits: int = 4):
    return None if value is None or not math.isfinite(value) else round(float(value), digits)


def _clean(d: dict) -> dict:
    return {k: (_r(v) if isinstance(v, float) else v) for k, v in d.items()}


def _spearman(a, b) -> float:
    from scipy.stats import spearmanr

    if len(a) < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return math.nan
    return float(spearmanr(a, b).statistic)


def _auc(positive: np.ndarray, scores: np.ndarray) -> float:
    """P(score of a positive < score of a negative), ties half: Vargha-Delaney A12 of the negatives over the
    positives, the Mann-Whitney U of the negatives over the pairs."""
    from scipy.stats import mannwhitneyu

    pos, neg = scores[positive], scores[~positive]
    if not pos.size or not neg.size:
        return math.nan
    return float(mannwhitneyu(neg, pos).statistic / (neg.size * pos.size))


def _best_recall(positive: np.ndarray, scores: np.ndarray) -> tuple[float, float]:
    """Largest recall with precision >= TARGET_PRECISION over "score <= t", and the smallest such t."""
    if not positive.any():
        return math.nan, math.nan
    order = np.argsort(scores, kind="stable")
    s, p = scores[order], positive[order]
    last = np.r_[s[1:] != s[:-1], True]  # the last index of each distinct score
    tp = np.cumsum(p)[last]
    k = np.flatnonzero(last) + 1
    precision, recall = tp / k, tp / positive.sum()
    ok = precision >= TARGET_PRECISION
    if not ok.any():
        return 0.0, math.nan
    best = np.flatnonzero(ok & (recall == recall[ok].max()))[0]
    return float(recall[best]), float(s[last][best])


def region_stats(theirs: np.ndarray, ours: np.ndarray, failure_prob: np.ndarray) -> RegionStats:
    """Agreement on paired distances [m] (tests both flew) and our per-test failure probabilities."""
    positive = theirs < UNSAFE_DISTANCE_M
    predicted = ours < UNSAFE_DISTANCE_M
    tp = int((positive & predicted).sum())
    best_recall, threshold = _best_recall(positive, ours)
    n = len(theirs)
    return RegionStats(
        tests=n, their_failures=int(positive.sum()), spearman=_spearman(theirs, ours), auc=_auc(positive, ours),
        precision=tp / predicted.sum() if predicted.any() else math.nan,
        recall=tp / positive.sum() if positive.any() else math.nan, best_recall=best_recall,
        best_threshold_m=threshold, their_failure_rate=float(positive.mean()) if n else math.nan,
        our_failure_rate=float(failure_prob.mean()) if n else math.nan)


def build_report(lset: LabelledSet, outcomes: Sequence[tuple[RunRecord, ...]], *, runs: int = 1, seed: int = 0,
                 close: float = 3.0, buffer: float = 0.0, uav: str | None = None, wall_s: float = 0.0
                 ) -> FidelityReport:
    """Compare flown ``outcomes`` (one tuple of runs per test of ``lset``) with the labels."""
    rows = tuple(TestRow(label, tuple(o)) for label, o in zip(lset.labels, outcomes, strict=True))
    both = [r for r in rows if r.both_flew]
    theirs = np.array([r.label.distance for r in both])
    ours = np.array([r.distance for r in both])
    prob = np.array([r.failure_probability for r in both])
    near = theirs < close
    confusion: dict[str, Counter] = {}
    for r in rows:
        confusion.setdefault(r.label.result, Counter()).update(status_counts(r.runs))
    statuses = [s for s in STATUS_ORDER if any(s in c for c in confusion.values())]
    statuses += sorted({s for c in confusion.values() for s in c} - set(statuses))
    confusion_table = FrozenDict({k: FrozenDict({s: c.get(s, 0) for s in statuses}) for k, c in confusion.items()})
    all_runs = [(r.label.result, run.status) for r in rows for run in r.runs]
    ours_blocked = [res for res, s in all_runs if s in BLOCKED]
    on_timeouts = [s for res, s in all_runs if res == "timeout"]
    blocked = FrozenDict({
        "their_timeouts": sum(r.label.result == "timeout" for r in rows),
        "our_blocked_runs": len(ours_blocked),
        "recall": sum(s in BLOCKED for s in on_timeouts) / len(on_timeouts) if on_timeouts else math.nan,
        "precision": ours_blocked.count("timeout") / len(ours_blocked) if ours_blocked else math.nan})
    seen = {SAME_STATUS[r.label.result] for r in rows}
    unseen_counts = Counter(s for _, s in all_runs if s not in seen)
    unseen = FrozenDict({"share": sum(unseen_counts.values()) / max(1, len(all_runs)),
                         "statuses": FrozenDict(unseen_counts), "labels_show": tuple(sorted(seen))})
    return FidelityReport(
        source=lset.source, labels_file=lset.labels_file, runs=runs, seed=seed, close_m=close, buffer_m=buffer,
        uav=uav, rows=rows, overall=region_stats(theirs, ours, prob),
        close=region_stats(theirs[near], ours[near], prob[near]), confusion=confusion_table, blocked=blocked,
        unseen=unseen, durations=_durations(rows), wall_s=wall_s)


def _durations(rows) -> FrozenDict | None:
    pairs = [(r.airborne_s, r.label.airborne_s) for r in rows
             if r.label.airborne_s > 0 and math.isfinite(r.airborne_s) and r.airborne_s > 0]
    if not pairs:
        return None
    ours, theirs = np.array(pairs).T
    q1, median, q3 = np.percentile(ours / theirs, [25, 50, 75])
    return FrozenDict({"tests": len(pairs), "median_ratio": float(median), "q1_ratio": float(q1),
                       "q3_ratio": float(q3), "spearman": _spearman(ours, theirs)})


def measure_fidelity(path, *, labels=None, mission=None, runs: int = 1, seed: int = 0, uav: str | None = None,
                     config=None, workers: int | None = None, limit: int | None = None, every: int = 1,
                     close: float = 3.0, buffer: float = 0.0,
                     progress: Callable[[int, int], None] | None = None, executor=None,
                     store=None) -> FidelityReport:
    """Fly a labelled set (see :func:`load_labelled_set`) and report how far our UAV agrees with the labels.

    Args:
        path, labels, mission: the labelled set (see :func:`load_labelled_set`), or a :class:`LabelledSet`.
        runs: runs per test; seed: base seed of the noise.
        uav: UAV profile, a preset name or YAML (default ``px4-v1.12-sitl-iris``); config: the SimConfig the
            profile applies to (default :class:`~surrealist_gym.sim.config.SimConfig`).
        workers: processes (default: all cores, at most 8); executor: a Dask scheduler's address, a
            ``distributed.Client`` or an executor instead (:func:`fly_labelled_set`); limit, every: fly every
            ``every``-th test, at most ``limit``.
        close: the close region is theirs < ``close`` [m]; buffer: polyline buffer of the distance [m].
        progress: called with (tests done, tests) as tests finish.
        store: an SQLite file holding the runs (:func:`fly_labelled_set`): a measurement interrupted and run again
            on it flies only the runs it lacks, and reports as an uninterrupted one.
    """
    if runs < 1 or every < 1 or (limit is not None and limit < 1) or close <= 0 or buffer < 0:
        raise ValueError(f"invalid options: runs={runs}, every={every}, limit={limit}, close={close}, "
                         f"buffer={buffer}")
    config = decide_uav(uav=uav or DEFAULT_UAV, config=config).config
    lset = path if isinstance(path, LabelledSet) else load_labelled_set(path, labels, mission)
    lset = lset.subset(limit, every)
    start = time.perf_counter()
    outcomes = fly_labelled_set(lset, runs, seed, config, workers, buffer, progress, executor, store)
    return build_report(lset, outcomes, runs=runs, seed=seed, close=close, buffer=buffer, uav=config.profile,
                        wall_s=time.perf_counter() - start)


def write_report(report: FidelityReport, out) -> dict[str, Path]:
    """Write ``fidelity.csv`` (one row per test), ``fidelity.json`` (the summary) and ``fidelity.png``."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        paths = {"csv": out / "fidelity.csv", "json": out / "fidelity.json", "png": out / "fidelity.png"}
        rows = [r.to_dict() for r in report.rows]
        with open(paths["csv"], "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        paths["json"].write_text(report.to_json() + "\n")
        plot_report(report, paths["png"])
    except OSError as err:
        raise SurrealistError(f"{out}: cannot write the fidelity report ({err.strerror or err})") from err
    return paths


_STATUS_COLOURS = {"success": "tab:blue", "timeout": "tab:orange", "stuck": "tab:purple", "collision": "tab:red",
                   "error": "black"}


def plot_report(report: FidelityReport, path, floor: float = 0.05) -> None:
    """Write the fidelity PNG: theirs vs ours beside the outcome table and the key figures.

    The scatter shows the 2-D competition distance on log axes (values below ``floor`` [m] drawn at it), the 1.5 m
    lines and the close region shaded, one colour per our status.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

    fig = Figure(figsize=(12, 5.5))
    FigureCanvasAgg(fig)
    ax, side = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1]})
    both = [r for r in report.rows if r.both_flew]
    values = [v for r in both for v in (r.label.distance, r.distance)]
    top = max([2 * report.close_m, *values]) * 1.3
    low = min(1.0, max(floor, min(values, default=floor) / 1.5)) * 0.8
    ax.axvspan(low, report.close_m, color="0.85", alpha=0.5, linewidth=0,
               label=f"close region (theirs < {report.close_m:g} m)")
    rank = {s: i for i, s in enumerate(STATUS_ORDER)}
    for status in sorted({r.status for r in both}, key=lambda s: (rank.get(s, len(rank)), s)):
        pts = np.array([(r.label.distance, r.distance) for r in both if r.status == status])
        ax.scatter(np.maximum(pts[:, 0], floor), np.maximum(pts[:, 1], floor), s=12, alpha=0.7,
                   color=_STATUS_COLOURS.get(status, "tab:gray"), label=f"ours: {status}", zorder=3)
    ax.plot([low, top], [low, top], color="0.4", linewidth=0.8, label="ours = theirs")
    ax.axvline(UNSAFE_DISTANCE_M, color="darkred", linestyle="--", linewidth=0.8)
    ax.axhline(UNSAFE_DISTANCE_M, color="darkred", linestyle="--", linewidth=0.8, label="soft failure, 1.5 m")
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlim(low, top)
    ax.set_ylim(low, top)
    ax.set_xlabel(f"theirs: {DISTANCE_NAME} [m]")
    ax.set_ylabel(f"ours: {DISTANCE_NAME} [m]" + (f", median of {report.runs} runs" if report.runs > 1 else ""))
    ax.set_title(f"{len(both)} tests both flew" + (f" (values < {floor:g} m drawn at {floor:g} m)"
                                                   if min(values, default=1.0) < floor else ""))
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(loc="upper left", fontsize="small")
    side.axis("off")
    statuses = list(next(iter(report.confusion.values()), {}))
    names = {"flown": "theirs: flown", "timeout": "theirs: no result / timeout", "collision": "theirs: collision"}
    table = side.table(cellText=[[str(v) for v in row.values()] for row in report.confusion.values()],
                       rowLabels=[names.get(k, k) for k in report.confusion], colLabels=statuses,
                       loc="upper right", bbox=[0.38, 0.62, 0.62, 0.3])
    table.set_fontsize(9)
    side.set_title("runs: their result vs our status")
    o, c = report.overall, report.close
    lines = [f"{DISTANCE_NAME}, buffer {report.buffer_m:g} m", "",
             f"{'':26}{'all':>8}{'close':>8}",
             f"{'tests both flew':26}{o.tests:>8}{c.tests:>8}",
             f"{'Spearman':26}{format_figure(o.spearman):>8}{format_figure(c.spearman):>8}",
             f"{'AUC, theirs < 1.5 m':26}{format_figure(o.auc):>8}{format_figure(c.auc):>8}",
             f"{'precision, ours < 1.5 m':26}{format_figure(o.precision):>8}{format_figure(c.precision):>8}",
             f"{'recall, ours < 1.5 m':26}{format_figure(o.recall):>8}{format_figure(c.recall):>8}",
             f"{'failure rate theirs':26}{format_figure(o.their_failure_rate):>8}"
             f"{format_figure(c.their_failure_rate):>8}",
             f"{'failure rate ours':26}{format_figure(o.our_failure_rate):>8}{format_figure(c.our_failure_rate):>8}"]
    if report.durations is not None:
        d = report.durations
        lines += ["", f"airborne time ours / theirs: median {format_figure(d['median_ratio'])}",
                  f"  (quartiles {format_figure(d['q1_ratio'])}-{format_figure(d['q3_ratio'])}, "
                  f"Spearman {format_figure(d['spearman'])}, {d['tests']} tests)"]
    side.text(0.0, 0.55, "\n".join(lines), family="monospace", fontsize=9, va="top", transform=side.transAxes)
    source = Path(report.source)
    fig.suptitle(f"fidelity: {source.parent.name}/{source.name}, {len(report.rows)} tests, {report.runs} run(s) each")
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=110)


def format_figure(value, digits: int = 2) -> str:
    """A figure for the report's text: rounded, or "-" when missing or not finite."""
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"
