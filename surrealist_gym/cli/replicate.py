"""`surrealist replicate LOG`: find the obstacles that make the simulated flight match a real one (paper RQ1)."""
from __future__ import annotations

from ._search import new_search_folder, run_search, sim_config_of
from .options import ReplicateOptions


def add_arguments(parser) -> None:
    ReplicateOptions.add_arguments(parser)


def run(args) -> int:
    from ..envs.replicate import ReplicateEnv

    if args.uav is None and not args.resume:  # a real flight: the real PX4 Vision (recorded in run.json)
        from ..sim.profiles import VISION_CASE0
        args.uav = VISION_CASE0.name
    with new_search_folder(args, ReplicateOptions) as (out, options):
        env = ReplicateEnv(reference_log=options.log, seed_test=options.seed, runs=options.runs,
                           budget=options.budget, averaging=options.averaging, executor=options.dask_scheduler,
                           store=out / "evaluations.sqlite", random_seed=options.random_seed,
                           workers=options.workers, sim_config=sim_config_of(options),
                           allow_partial=options.allow_partial)
    return run_search(env, options, out, "replicate")
