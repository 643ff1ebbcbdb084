"""``surrealist calibrate LOG... --profile uav.yaml``: fit a UAV profile to real flights (docs/calibration.md).

Every run flown is kept as it completes in a results folder named after the profile (``uav/`` beside ``uav.yaml``:
``run.json``, ``evaluations.sqlite``): the same command resumes an interrupted calibration and flies only the runs it
lacks.

Example::

    surrealist calibrate m0.ulg --profile m0-uav.yaml   # prints each fitted value and residual; m0-uav.png
    surrealist replicate m0.ulg --uav m0-uav.yaml
"""
from __future__ import annotations

import argparse
import time

from ..errors import SurrealistError
from .options import (
    add_dask_argument,
    add_random_seed_argument,
    add_workers_argument,
    check_at_least,
    check_writable,
    refuse_argument,
    refuse_workers_with_dask,
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist calibrate``."""
    parser.add_argument("logs", metavar="LOG", nargs="+", help="flight logs of one UAV (.ulg, .tlog, .bin)")
    parser.add_argument("--profile", metavar="FILE.yaml", required=True, help="the fitted UAV profile to write")
    refuse_argument(parser, "--out", _out_refused)
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="profile to start from (default: the first log's vehicle: px4-vision-case0 for a "
                             "PX4 Vision, else px4-v1.12-sitl-iris)")
    parser.add_argument("--seed", metavar="TEST.yaml", default=None,
                        help="fly the missions with this test's obstacles (default: none)")
    parser.add_argument("--runs", type=int, default=2, metavar="N", help="runs per simulated figure (default 2)")
    add_random_seed_argument(parser, "base seed of the simulation noise (default 0)", seed_test=True)
    add_workers_argument(parser)
    add_dask_argument(parser)
    parser.add_argument("--plot", metavar="PNG", default=None,
                        help="real vs simulated phases over time (default: the profile's path with .png)")


def _out_refused(value) -> str:
    """``--out``, calibrate's name for its profile file before: the file is ``--profile``."""
    if value and str(value).lower().endswith((".yaml", ".yml")):
        return f"--out is a folder; the profile file is --profile {value}"
    return ("--out is a folder; calibrate writes one profile file: --profile "
            + (f"{value.rstrip('/')}/uav.yaml" if value else "FILE.yaml"))


def run(args) -> int:
    """Fly the logs' missions, fit the UAV profile, write it (and its plot); returns the exit code."""
    from ..aerialist import load_test
    from ..executors import make_executor
    from ..fidelity.calibration import calibrate, format_calibration, plot_calibration
    from ..logs import read_flight
    from ..results import EVALUATIONS, ResultsFolder
    from ..sim.profiles import save_profile
    from ..sim.uav import decide_uav

    check_at_least(args, runs=1, workers=1, random_seed=0)
    refuse_workers_with_dask(args)
    out = check_writable(args.profile, "--profile", "file", (".yaml", ".yml"))  # before any log is read or flown
    plot = check_writable(args.plot or out.with_suffix(".png"), "--plot", "file", (".png",))
    flights = []
    for log in args.logs:
        flight = read_flight(log)
        if flight.damage:
            raise SurrealistError(f"{flight.path}: {flight.damage}; a flight cut short cannot be calibrated on")
        flights.append(flight)
    uav = decide_uav(uav=args.uav or None, flight=flights[0])  # --uav, else the first log's vehicle
    base = uav.profile
    seed = load_test(args.seed) if args.seed else None
    # the runs, kept as they fly in a results folder named after the profile: the same command resumes
    folder = ResultsFolder.claim(out.with_suffix(""), "calibrate", _settings(args), free=("workers",))
    uav.write(folder.path)  # the UAV the calibration starts from, and why
    start = time.perf_counter()
    with folder.keeping("the same command resumes it", "record(s) of runs"):
        executor = make_executor(args.dask_scheduler, args.workers)
        try:
            cal = calibrate(flights, base, seed, runs=args.runs, executor=executor, seed=args.random_seed,
                            store=folder.path / EVALUATIONS[0], progress=lambda line: print(f"  {line}", flush=True))
        finally:
            executor.close()
    print(format_calibration(cal))
    out.parent.mkdir(parents=True, exist_ok=True)
    save_profile(cal.profile, out)
    plot_calibration(cal, plot)
    print(f"profile {cal.profile.name} -> {out} ({cal.simulations} simulations, "
          f"{time.perf_counter() - start:.1f} s); phases plotted in {plot}; runs kept in {folder.path}/")
    return 0


def _settings(args) -> dict:
    """What the runs folder records of the calibration (``run.json``): the same command resumes only with the same."""
    from pathlib import Path

    from ..sim.uav import recorded_choice

    return {"logs": [str(Path(log).absolute()) for log in args.logs], "uav": recorded_choice(args.uav or None),
            "seed": None if args.seed is None else str(Path(args.seed).absolute()), "runs": args.runs,
            "random_seed": args.random_seed}
