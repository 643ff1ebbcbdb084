"""``surrealist predict TESTS...``: fly each test on our simulator and predict PX4 SITL's verdict on it.

TESTS are Aerialist YAMLs or folders of them. Each test is flown ``--runs`` times (default: as many as the model was
trained with, 3) and the model of PX4's verdict (:mod:`surrealist_gym.fidelity.verdict`, the shipped parameters or
``--model FILE.json``) gives the probability that PX4 v1.12 SITL flies it under 1.5 m and under 1 m; our own median
distance and shares of failing and colliding runs stand beside. Prints one row per test and writes
``predictions.csv`` to ``--out``, a results folder (``evaluations.sqlite``: every run as it completes; the same
command with the same ``--out`` resumes).

``--fit LABELS`` refits the model instead: it flies the labelled set (a tests CSV or a folder of YAMLs with
``--labels``, as ``surrealist fidelity`` reads them) ``--runs`` times, writes the training table
(``training.csv``) to ``--out`` and the fitted parameters to ``--model FILE.json``. ``--fit TABLE.csv`` refits on a
training table that holds the flights' features already (``training.csv``; the shipped model's is
``benchmarks/data/px4-verdict-training.csv``), without flying.

Example::

    surrealist predict ../shared/data/competition/camba-collection --workers 2
    surrealist predict --fit ../shared/data/competition/rilast-mission1/tests.csv --model px4-verdict.json
    surrealist predict --fit benchmarks/data/px4-verdict-training.csv --model px4-verdict.json
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys

from ..errors import SurrealistError

COLUMNS = ("test", "file", "p_px4_under_1_5m", "p_px4_under_1m", "our_distance_m", "our_failure_share",
           "our_collision_share", "runs")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist predict``."""
    from .options import add_dask_argument, add_out_argument, add_random_seed_argument, add_workers_argument

    parser.add_argument("tests", nargs="*", metavar="TESTS", help="Aerialist test YAMLs or folders of them")
    parser.add_argument("--runs", type=int, default=None, metavar="N",
                        help="runs per test (default: the model's, 3); the features are computed over them")
    add_random_seed_argument(parser, "base seed of the simulation noise (default 0)")
    add_workers_argument(parser)
    add_dask_argument(parser)
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="UAV profile flown (default px4-v1.12-sitl-iris, the one the model was trained on)")
    parser.add_argument("--model", metavar="FILE.json", default=None,
                        help="the model's parameters: read (default: the shipped surrealist_gym/data/px4-verdict.json)"
                             "; with --fit, the one file written")
    parser.add_argument("--fit", metavar="LABELS", default=None,
                        help="refit the model instead of predicting: on a labelled set (a tests CSV, or a folder "
                             "of YAMLs with --labels), flown --runs times, or on a training table (training.csv) "
                             "without flying")
    parser.add_argument("--labels", metavar="FILE", help="with --fit: labels of a YAML folder "
                                                         "(default <folder>/labels.csv)")
    parser.add_argument("--l2", type=float, default=None, metavar="X",
                        help="with --fit: the ridge penalty (default the one chosen on rilast's development half)")
    add_out_argument(parser, "predict")
    parser.add_argument("--json", action="store_true", help="print the predictions as JSON")


def _check(args) -> None:
    from .options import check_at_least, check_writable, default_out, refuse_workers_with_dask

    check_at_least(args, runs=1, workers=1, random_seed=0)
    refuse_workers_with_dask(args)
    if args.fit is None:
        if not args.tests:
            raise SurrealistError("surrealist predict: give TESTS (Aerialist YAMLs or folders), or --fit LABELS")
        for flag, value in (("--labels", args.labels), ("--l2", args.l2)):
            if value is not None:
                raise SurrealistError(f"{flag}: applies only with --fit")
    else:
        if args.tests:
            raise SurrealistError(f"{args.tests[0]}: unexpected argument with --fit (it flies the labelled set)")
        if args.model is None:
            raise SurrealistError("--fit: name the model file it writes with --model FILE.json")
        check_writable(args.model, "--model", "file", (".json",))
        if args.l2 is not None and not (math.isfinite(args.l2) and args.l2 > 0):
            raise SurrealistError(f"--l2: expected a positive number, got {args.l2:g}")
    args.out = args.out or str(default_out("predict"))
    check_writable(args.out, "--out", "folder")


def run(args: argparse.Namespace) -> int:
    """Predict PX4's verdict on the tests (or refit the model with ``--fit``)."""
    from ..fidelity.verdict import load_verdict
    from ..results import ResultsFolder
    from ..sim.uav import DEFAULT_UAV, decide_uav

    _check(args)
    uav = decide_uav(uav=args.uav or DEFAULT_UAV)  # a bad profile fails before anything is read
    if args.fit is not None:
        from ..fidelity.labels import load_labelled_set
        from ..fidelity.verdict import is_table

        if is_table(args.fit):  # a training table: refit without flying
            return _fit_table(args, uav)
        lset = load_labelled_set(args.fit, args.labels)
        runs = args.runs or load_verdict().runs
        folder = ResultsFolder.claim(args.out, "predict", _settings(args, runs), free=("workers", "dask_scheduler"))
        with folder.keeping("the same command resumes it", "record(s) of runs"):
            return _fit(args, lset, runs, folder.path, uav)
    from ..competition.tool_output import load_tests

    verdict = load_verdict(args.model)
    tests = load_tests(args.tests, any_layout=True)  # bad input fails here, before any folder or flight
    runs = args.runs or verdict.runs
    folder = ResultsFolder.claim(args.out, "predict", _settings(args, runs), free=("workers", "dask_scheduler"))
    with folder.keeping("the same command resumes it", "record(s) of runs"):
        return _predict(args, verdict, tests, runs, folder.path, uav)


def _settings(args, runs: int) -> dict:
    from pathlib import Path

    from ..sim.uav import recorded_choice

    def absolute(path):
        return None if path is None else str(Path(path).absolute())

    return {"tests": [absolute(t) for t in args.tests], "fit": absolute(args.fit), "labels": absolute(args.labels),
            "model": absolute(args.model), "l2": args.l2, "uav": recorded_choice(args.uav), "runs": runs,
            "random_seed": args.random_seed}


def _bar(desc: str):
    from tqdm import tqdm

    bar = tqdm(total=None, unit="test", desc=desc, dynamic_ncols=True, file=sys.stderr, disable=None)

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    return bar, progress


def _predict(args, verdict, tests, runs: int, out, uav) -> int:
    from ..fidelity.verdict import predict_tests
    from ..results import EVALUATIONS

    bar, progress = _bar("predict")
    try:
        predictions = predict_tests([t for _, t in tests], [p.stem for p, _ in tests], verdict=verdict, runs=runs,
                                    seed=args.random_seed, uav=args.uav, workers=args.workers,
                                    executor=args.dask_scheduler, progress=progress, store=out / EVALUATIONS[0])
    finally:
        bar.close()
    rows = [{"test": p.test, "file": str(path), "p_px4_under_1_5m": round(p.p_unsafe, 4),
             "p_px4_under_1m": round(p.p_hard, 4),
             "our_distance_m": None if math.isnan(p.our_distance_m) else round(p.our_distance_m, 4),
             "our_failure_share": round(p.our_failure_share, 4), "our_collision_share": round(p.our_collision_share, 4),
             "runs": p.runs} for (path, _), p in zip(tests, predictions)]
    table = out / "predictions.csv"
    try:
        with open(table, "w", newline="", encoding="utf-8") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
    except OSError as err:
        raise SurrealistError(f"{table}: cannot write the predictions ({err.strerror or err})") from err
    uav.write(out)
    if args.json:
        print(json.dumps({"predictions": rows, "file": str(table)}, indent=2))
        return 0
    print(f"PX4 v1.12 SITL's verdict predicted from {runs} run(s) per test on {uav.name}")
    print(f"{'test':32}{'P(PX4 < 1.5 m)':>16}{'P(PX4 < 1 m)':>14}{'ours [m]':>10}{'ours < 1.5 m':>14}")
    for r in rows:
        ours = "-" if r["our_distance_m"] is None else f"{r['our_distance_m']:.2f}"
        print(f"{r['test'][:31]:32}{r['p_px4_under_1_5m']:>16.2f}{r['p_px4_under_1m']:>14.2f}{ours:>10}"
              f"{r['our_failure_share']:>14.2f}")
    if any(r["our_distance_m"] is None for r in rows):
        print("ours '-': every run of ours timed out, which the model reads as far from the boxes; the labelled "
              "flights hold few such tests, so take its P there as unknown (docs/predict.md)")
    print(f"predictions: {table}")
    return 0


def _fit_table(args, uav) -> int:
    from pathlib import Path

    from ..fidelity.verdict import DEFAULT_L2, DEFAULT_RUNS, fit_verdict, read_table

    if args.labels is not None:
        raise SurrealistError("--labels: not with a training table (it holds PX4's distances already)")
    verdict = fit_verdict(read_table(args.fit), l2=args.l2 or DEFAULT_L2, trained_on={
        "source": Path(args.fit).name, "runs": args.runs or DEFAULT_RUNS, "seed": args.random_seed, "uav": uav.name})
    model = verdict.save(args.model)
    info = verdict.trained_on
    print(f"fitted on {info['tests']} tests PX4 flew ({info['positives']['unsafe']} under 1.5 m, "
          f"{info['positives']['hard']} under 1 m) of the training table {args.fit} (its flights: {info['runs']} "
          f"run(s) each, seed {info['seed']}, {info['uav']}, as --runs and --random-seed say)")
    print(f"model: {model}")
    return 0


def _fit(args, lset, runs: int, out, uav) -> int:
    from ..fidelity.measure import fly_labelled_set
    from ..fidelity.verdict import DEFAULT_L2, fit_verdict, training_table, write_table
    from ..results import EVALUATIONS

    bar, progress = _bar("fit")
    try:
        outcomes = fly_labelled_set(lset, runs, args.random_seed, uav.config, args.workers, 0.0, progress,
                                    args.dask_scheduler, out / EVALUATIONS[0])
    finally:
        bar.close()
    rows = training_table(lset, outcomes)
    table = write_table(rows, out / "training.csv")
    verdict = fit_verdict(rows, l2=args.l2 or DEFAULT_L2, trained_on={
        "source": lset.source, "runs": runs, "seed": args.random_seed, "uav": uav.name})
    model = verdict.save(args.model)
    uav.write(out)
    info = verdict.trained_on
    print(f"fitted on {info['tests']} tests PX4 flew ({info['positives']['unsafe']} under 1.5 m, "
          f"{info['positives']['hard']} under 1 m), {runs} run(s) each on {uav.name}")
    print(f"model: {model}; training table: {table}")
    return 0
