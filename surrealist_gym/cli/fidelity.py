"""``surrealist fidelity LABELS``: fly a labelled set of Aerialist tests and report how far our UAV agrees.

LABELS is a tests CSV (flown on ``--mission``, default ``<CSV folder>/../case_studies/mission1.yaml``) or a folder
of Aerialist YAMLs with a labels file (``--labels``, default ``<folder>/labels.csv``). Prints the summary and writes
``fidelity.csv`` (one row per test), ``fidelity.json`` (the summary) and ``fidelity.png`` to ``--out``, a results
folder (``run.json``: its settings; ``evaluations.sqlite``: every run, stored as it completes): the same command
with the same ``--out`` resumes an interrupted measurement and flies only the runs it lacks.

Example::

    surrealist fidelity ../shared/data/competition/rilast-mission1/tests.csv --workers 2
    surrealist fidelity ../shared/data/competition/camba-collection --labels benchmarks/data/camba-px4-flights.csv
"""
from __future__ import annotations

import argparse
import math
import sys

from ..errors import SurrealistError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist fidelity``."""
    from .options import (
        add_buffer_argument,
        add_dask_argument,
        add_out_argument,
        add_random_seed_argument,
        add_workers_argument,
    )

    parser.add_argument("labels_set", metavar="LABELS", help="tests CSV, or a folder of Aerialist YAMLs")
    parser.add_argument("--labels", metavar="FILE", help="labels of a YAML folder (default <folder>/labels.csv)")
    parser.add_argument("--mission", metavar="YAML",
                        help="base test (mission, parameters) of a tests CSV "
                             "(default <CSV folder>/../case_studies/mission1.yaml)")
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="UAV profile: a preset (px4-v1.12-sitl-iris, the default; px4-vision-case0) or a "
                             "profile YAML")
    parser.add_argument("--runs", type=int, default=1, metavar="N", help="runs per test (default 1)")
    add_random_seed_argument(parser, "base seed of the simulation noise (default 0)")
    add_workers_argument(parser)
    add_dask_argument(parser)
    parser.add_argument("--limit", type=int, default=None, metavar="N", help="fly at most N tests")
    parser.add_argument("--every", type=int, default=1, metavar="K", help="fly every K-th test (default 1)")
    parser.add_argument("--close", type=float, default=3.0, metavar="M",
                        help="the close region: their distance below M metres (default 3)")
    add_buffer_argument(parser)
    add_out_argument(parser, "fidelity")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def _check(args) -> None:
    from pathlib import Path

    from ..geometry import check_buffer
    from .options import check_at_least, check_writable, default_out

    check_at_least(args, runs=1, every=1, workers=1, limit=1, random_seed=0)
    if args.mission is not None and Path(args.labels_set).is_dir():
        raise SurrealistError("--mission: applies only to a tests CSV (a folder of YAMLs brings its missions)")
    args.out = args.out or str(default_out("fidelity"))
    check_writable(args.out, "--out", "folder")
    if not args.close > 0 or not math.isfinite(args.close):
        raise SurrealistError(f"--close: expected a positive number of metres, got {args.close:g}")
    check_buffer(args.buffer)


def summary_text(report) -> str:
    """The summary ``surrealist fidelity`` prints; every distance says which one it is."""
    from ..fidelity.measure import DISTANCE_NAME, format_figure as _f

    results = {}
    for row in report.rows:
        results[row.label.result] = results.get(row.label.result, 0) + 1
    o, c = report.overall, report.close

    def row(name: str, a: str, b: str) -> str:
        return f"{name:44}{a:>18}{b:>26}"

    lines = [f"fidelity on {report.source}: {len(report.rows)} labelled tests ("
             + ", ".join(f"{n} {'no result/timeout' if k == 'timeout' else k}" for k, n in results.items())
             + f"), {report.runs} run(s) each, seed {report.seed}",
             f"distance: {DISTANCE_NAME} (box footprint to the 0.5 s polyline, buffer {report.buffer_m:g} m), "
             f"theirs vs ours" + (" (median of the runs)" if report.runs > 1 else ""),
             f"UAV profile: {report.uav}",
             row("", "all tests", f"close (theirs < {report.close_m:g} m)"),
             row("tests both flew", str(o.tests), str(c.tests)),
             row("Spearman, 2-D competition distance", _f(o.spearman), _f(c.spearman)),
             row("AUC for theirs < 1.5 m, scored by ours", _f(o.auc), _f(c.auc)),
             row("precision / recall of ours < 1.5 m", f"{_f(o.precision)} / {_f(o.recall)}",
                 f"{_f(c.precision)} / {_f(c.recall)}"),
             row("best recall at precision >= 0.6 (ours <= t)", f"{_f(o.best_recall)} (t {_f(o.best_threshold_m)} m)",
                 f"{_f(c.best_recall)} (t {_f(c.best_threshold_m)} m)"),
             row("failure rate (< 1.5 m) theirs / ours", f"{_f(o.their_failure_rate)} / {_f(o.our_failure_rate)}",
                 f"{_f(c.their_failure_rate)} / {_f(c.our_failure_rate)}"),
             "outcomes (runs): their result \\ our status"]
    statuses = list(next(iter(report.confusion.values()), {}))
    lines.append(f"  {'':28}" + "".join(f"{s:>11}" for s in statuses))
    for result, counts in report.confusion.items():
        name = {"timeout": "no result / timeout"}.get(result, result)
        lines.append(f"  {name:28}" + "".join(f"{counts[s]:>11}" for s in statuses))
    b, u = report.blocked, report.unseen
    lines.append(f"blocked (our timeout or stuck) for their no result/timeout: recall {_f(b['recall'])} (runs on "
                 f"their {b['their_timeouts']} timed-out tests), precision {_f(b['precision'])} (of our "
                 f"{b['our_blocked_runs']} blocked runs)")
    lines.append(f"runs ending in a status the labels never show ({', '.join(u['labels_show'])} only): "
                 f"{100 * u['share']:.1f}%" + (" (" + ", ".join(f"{n} {s}" for s, n in u["statuses"].items()) + ")"
                                                if u["statuses"] else ""))
    d = report.durations
    if d is not None:
        lines.append(f"airborne time ours / theirs on {d['tests']} tests: median {_f(d['median_ratio'])} (quartiles "
                     f"{_f(d['q1_ratio'])}-{_f(d['q3_ratio'])}), Spearman {_f(d['spearman'])}")
    rate = len(report.rows) / report.wall_s if report.wall_s > 0 else math.nan
    lines.append(f"{len(report.rows)} tests flown in {report.wall_s:.1f} s wall ({_f(rate)} tests/s)")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Fly the labelled set, print the summary and write the report files."""
    from ..fidelity.measure import load_labelled_set
    from ..results import ResultsFolder
    from ..sim.uav import DEFAULT_UAV, decide_uav

    _check(args)
    uav = decide_uav(uav=args.uav or DEFAULT_UAV)  # a bad profile fails before anything is read
    lset = load_labelled_set(args.labels_set, args.labels, args.mission)  # bad input fails before the progress bar
    folder = ResultsFolder.claim(args.out, "fidelity", _settings(args), free=("workers", "dask_scheduler"))
    with folder.keeping("the same command resumes it", "record(s) of runs"):
        return _measure(args, lset, folder.path, uav)


def _settings(args) -> dict:
    """What the folder records of the measurement (``run.json``): the same command resumes only with the same."""
    from pathlib import Path

    from ..sim.uav import recorded_choice

    def absolute(path):
        return None if path is None else str(Path(path).absolute())

    return {"labels_set": absolute(args.labels_set), "labels": absolute(args.labels), "mission": absolute(args.mission),
            "uav": recorded_choice(args.uav), "runs": args.runs,
            "random_seed": args.random_seed, "limit": args.limit, "every": args.every, "close": args.close,
            "buffer": args.buffer}


def _measure(args, lset, out, uav) -> int:
    import json

    from tqdm import tqdm

    from ..fidelity.measure import measure_fidelity, write_report
    from ..results import EVALUATIONS

    bar = tqdm(total=None, unit="test", desc="fidelity", dynamic_ncols=True, file=sys.stderr, disable=None)

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    try:
        report = measure_fidelity(lset, runs=args.runs, seed=args.random_seed, uav=args.uav, workers=args.workers,
                                  limit=args.limit, every=args.every, close=args.close, buffer=args.buffer,
                                  progress=progress, executor=args.dask_scheduler, store=out / EVALUATIONS[0])
    finally:
        bar.close()
    paths = write_report(report, out)
    uav.write(out)
    if args.json:
        print(json.dumps({**report.to_dict(), "files": {k: str(v) for k, v in paths.items()}}, indent=2))
        return 0
    print(summary_text(report))
    print(f"per-test rows: {paths['csv']}; summary: {paths['json']}; plot: {paths['png']}")
    return 0
