"""`surrealist replicate LOG`: find the obstacles that make the simulated flight match a real one (paper RQ1)."""
from __future__ import annotations

import dataclasses
import json

from ..results import RUN_FILE
from ._search import run_search, search_folder
from .options import ReplicateOptions, refuse_inapplicable


def add_arguments(parser) -> None:
    """Arguments of ``surrealist replicate``."""
    ReplicateOptions.add_arguments(parser)


def run(args) -> int:
    """Search for the obstacles that make the simulated flight match the log; returns the exit code."""
    from ..envs.replicate import ReplicateEnv
    from ..errors import InvalidTestCase
    from ..sim.profiles import PRESETS, save_profile

    if not args.resume:
        refuse_inapplicable(args, ReplicateOptions.inapplicable(args))
    with search_folder(args, ReplicateOptions) as (out, options):
        try:
            env = ReplicateEnv(reference_log=options.log, seed_test=options.seed, runs=options.runs,
                               budget=options.budget, averaging=options.averaging, executor=options.dask_scheduler,
                               store=out / "evaluations.sqlite", random_seed=options.random_seed,
                               workers=options.workers, uav=options.uav,
                               sim_config={"common_noise": options.common_noise},
                               allow_partial=options.allow_partial, uav_mutators=options.search_uav)
        except InvalidTestCase as err:  # a field of the seed test: name its file
            if options.seed and str(err).startswith("params."):
                raise InvalidTestCase(f"{options.seed}: {err}") from None
            raise
        if options.uav is None and env.uav.profile is not None:  # the log's own vehicle, recorded for --resume
            profile = env.uav.profile
            uav = profile.name
            if PRESETS.get(profile.name) != profile:
                save_profile(profile, out / "uav.yaml")
                uav = str((out / "uav.yaml").resolve())
            options = dataclasses.replace(options, uav=uav)
            (out / RUN_FILE).write_text(json.dumps(options.to_json(), indent=2) + "\n")
        return run_search(env, options, out, "replicate")
