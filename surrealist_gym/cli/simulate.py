"""``surrealist simulate TEST.yaml``: fly a test case's runs in the simulator, report and save them.

Prints one row per run (status, minimum distance, duration), writes each run as a ULog and a plot of all runs with
the obstacles (top view and altitude). With a reference log, the plot shows the real flight too and the table
gives each run's DTW and Frechet distance to it.

Example::

    surrealist simulate rq1-seed1.yaml --runs 5 --random-seed 0 --out runs/
    surrealist simulate rq1-seed1.yaml --reference case0.ulg --no-avoidance
"""
from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import replace
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist simulate``."""
    from .options import (
        WORKERS_ONE_HELP,
        add_dask_argument,
        add_out_argument,
        add_random_seed_argument,
        add_workers_argument,
        refuse_argument,
    )

    parser.add_argument("test", metavar="TEST.yaml", help="Aerialist test case")
    parser.add_argument("--runs", type=int, default=5, metavar="N", help="number of runs (default 5)")
    add_random_seed_argument(parser, "base seed of the simulation noise: run i draws its noise from the test, N and i "
                                     "(default 0)")
    add_workers_argument(parser, WORKERS_ONE_HELP, default=1)
    add_dask_argument(parser)
    reference = parser.add_mutually_exclusive_group()
    reference.add_argument("--reference", metavar="LOG",
                           help="real flight to compare against (default: the test's assertion log, if any)")
    reference.add_argument("--no-reference", action="store_true",
                           help="do not compare with the test's assertion log")
    add_out_argument(parser, "simulate")
    refuse_argument(parser, "--vehicle", "--uav names the UAV that flies: a preset, or a profile YAML whose "
                                          "'vehicle:' is px4_vision or iris")
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="UAV profile: px4-v1.12-sitl-iris (PX4 SITL + PX4-Avoidance, as Aerialist flies), "
                             "px4-vision-case0, or a profile YAML (default: px4-vision-case0 for a test with a "
                             "reference log, else px4-v1.12-sitl-iris)")
    avoid = parser.add_mutually_exclusive_group()
    avoid.add_argument("--avoidance", dest="avoidance", action="store_true", default=None,
                       help="fly with the avoidance planner (default: the parameter COM_OBS_AVOID)")
    avoid.add_argument("--no-avoidance", dest="avoidance", action="store_false", help="fly without avoidance")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a PX4 parameter (repeatable)")
    parser.add_argument("--no-ulog", action="store_true", help="do not write the ULogs")
    parser.add_argument("--no-plot", action="store_true", help="do not write the plot")
    parser.add_argument("--json", action="store_true", help="print the table as JSON")


def _params(items: list[str]) -> dict:
    """``--param NAME=VALUE`` overrides, each a finite number in its physical range (ranges.RANGES)."""
    from ..errors import SimulationError, param_problem

    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            number = float(value) if sep else math.nan
        except ValueError:
            number = math.nan
        if not math.isfinite(number) or not name.strip():
            raise SimulationError(f"--param {item!r}: expected NAME=number (a finite number)")
        bad = param_problem(name.strip(), number)
        if bad:
            raise SimulationError(f"--param {item!r}: {name.strip()}: {bad}")
        out[name.strip()] = number
    return out


def _fly_on_workers(args: argparse.Namespace, test, config) -> list:
    """The runs flown on ``--workers`` local processes or the ``--dask-scheduler``'s cluster, in run order; a run
    whose simulation failed twice is the error it raised, as in this process."""
    from ..errors import SimulationError
    from ..executors import make_executor

    executor = make_executor(args.dask_scheduler, args.workers)
    try:
        results = executor.run(test, range(args.runs), args.random_seed, config)
    finally:
        executor.close()
    for r in results:
        if not hasattr(r, "local_position"):  # executors.FailedRun
            raise SimulationError(r.message)
    return results


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit code."""
    from .. import load_test
    from ..logs.ulog_writer import write_run_ulog
    from ..sim import simulate
    from .options import check_at_least, check_writable, default_out, refuse_workers_with_dask

    check_at_least(args, runs=1, random_seed=0, workers=1)
    refuse_workers_with_dask(args)
    out = check_writable(args.out or default_out("simulate"), "--out", "folder")  # before anything is read or flown
    params = _params(args.param)
    test = load_test(args.test)
    ref_path = args.reference or (None if args.no_reference else test.reference_log)
    reference = None
    if ref_path:
        from .. import read_flight
        reference = read_flight(ref_path)
        if args.reference:
            test = replace(test, reference_log=str(Path(args.reference).resolve()))
    from ..errors import InvalidTestCase
    from ..sim.uav import decide_uav

    try:  # the UAV and the test's uav.* settings, checked before anything flies
        given = {"avoidance": args.avoidance} if args.avoidance is not None else {}
        uav = decide_uav(test, args.uav, config={**given, **({"params": params} if params else {})})
    except InvalidTestCase as err:
        raise InvalidTestCase(f"{args.test}: {err}") from None
    config = uav.config
    start = time.perf_counter()
    results = (simulate(test, runs=args.runs, seed=args.random_seed, config=config)
               if args.workers == 1 and args.dask_scheduler is None else _fly_on_workers(args, test, config))
    wall = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    uav.write(out)
    stem = Path(args.test).stem
    rows = []
    for r in results:
        row = {"run": r.index, "status": r.status.value, "min_distance_m": round(r.min_distance, 3),
               "min_distance_2d_m": round(r.min_distance_2d, 3),
               "competition_distance_m": round(r.competition_distance, 3),
               "duration_s": round(r.duration, 2), "message": r.message}
        if reference is not None:
            from ..metrics import dtw, frechet
            row["dtw"] = round(dtw(r.trajectory, reference.trajectory), 2)
            row["frechet_m"] = round(frechet(r.trajectory, reference.trajectory), 3)
        if not args.no_ulog:
            path = out / f"{stem}-run{r.index}.ulg"
            write_run_ulog(path, r, mission=test.mission)
            row["ulog"] = str(path)
        rows.append(row)
    plot = None
    if not args.no_plot:
        from ..logs.plots import plot_trajectories
        plot = out / f"{stem}.png"
        plot_trajectories(plot, [r.trajectory for r in results], obstacles=test.obstacles,
                          title=f"{stem}: {len(results)} simulated runs (random seed {args.random_seed})",
                          reference=None if reference is None else reference.trajectory,
                          reference_label="real flight")
    simulated = sum(r.duration for r in results)
    if args.json:
        print(json.dumps({"runs": rows, "plot": None if plot is None else str(plot), "wall_s": round(wall, 3),
                          "simulated_s": round(simulated, 2), "uav": config.profile}, indent=2))
        return 0
    print("distances: 3-D and 2-D clearance of the vehicle's centre (true position), and the competition's 2-D "
          "distance (box footprint to the 0.5 s trajectory polyline)" + (f"; UAV {config.profile}" if config.profile
                                                                          else ""))
    head = f"{'run':>3}  {'status':9}  {'3-D':>8}  {'2-D':>8}  {'compet.':>8}  {'duration':>8}"
    if reference is not None:
        head += f"  {'DTW':>8}  {'Frechet':>8}"
    print(head)
    for row in rows:
        line = (f"{row['run']:>3}  {row['status']:9}  {row['min_distance_m']:>7.2f}m  {row['min_distance_2d_m']:>7.2f}m"
                f"  {row['competition_distance_m']:>7.2f}m  {row['duration_s']:>7.1f}s")
        if reference is not None:
            line += f"  {row['dtw']:>8.1f}  {row['frechet_m']:>7.2f}m"
        print(line)
    print(f"{len(results)} runs, {simulated:.1f} s simulated in {wall:.2f} s wall ({simulated / wall:.0f}x real time)")
    if not args.no_ulog:
        print(f"ULogs: {out}/{stem}-run*.ulg")
    if plot is not None:
        print(f"plot: {plot}")
    return 0
