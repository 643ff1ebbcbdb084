"""`surrealist replicate LOG`: find the obstacles that make the simulated flight match a real one (paper RQ1)."""
from __future__ import annotations

import dataclasses
import json

from ._search import new_search_folder, run_search
from .options import RUN_FILE, ReplicateOptions


def add_arguments(parser) -> None:
    ReplicateOptions.add_arguments(parser)


def run(args) -> int:
    from ..envs.replicate import ReplicateEnv
    from ..sim.profiles import PRESETS, save_profile

    flight_profile = None
    if args.uav is None and not args.resume:  # the log's own vehicle (recorded in run.json, or as uav.yaml)
        flight_profile = log_profile(args)
        if flight_profile.name in PRESETS:
            args.uav = flight_profile.name
    with new_search_folder(args, ReplicateOptions) as (out, options):
        if options.uav is None and flight_profile is not None:
            save_profile(flight_profile, out / "uav.yaml")
            options = dataclasses.replace(options, uav=str((out / "uav.yaml").resolve()))
            (out / RUN_FILE).write_text(json.dumps(options.to_json(), indent=2) + "\n")
        env = ReplicateEnv(reference_log=options.log, seed_test=options.seed, runs=options.runs,
                           budget=options.budget, averaging=options.averaging, executor=options.dask_scheduler,
                           store=out / "evaluations.sqlite", random_seed=options.random_seed,
                           workers=options.workers, uav=options.uav,
                           sim_config={"common_noise": options.common_noise},
                           allow_partial=options.allow_partial, uav_mutators=options.search_uav)
    return run_search(env, options, out, "replicate")


def log_profile(args):
    """The UAV profile of the log the search replicates (:func:`~surrealist_gym.calibration.profile_for_flight`)."""
    from .. import data_path
    from ..calibration import profile_for_flight
    from ..logs import read_flight
    from ..testcase import load_test

    log = args.log
    if log is None:
        seed = load_test(args.seed) if args.seed and args.seed not in ("tall", "paper", "detours") else None
        log = (seed.reference_log if seed is not None else None) or data_path("case0.ulg")
    return profile_for_flight(read_flight(log))
