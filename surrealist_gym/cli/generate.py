"""`surrealist generate TEST.yaml`: find nearby tests that make the UAV unsafe or crash (paper RQ2)."""
from __future__ import annotations

from ._search import new_search_folder, run_search, sim_config_of
from .options import GenerateOptions


def add_arguments(parser) -> None:
    GenerateOptions.add_arguments(parser)


def run(args) -> int:
    from .. import data_path
    from ..envs.generate import GenerateEnv
    from ..mutators import AUTHORS_ORDER, default_mutators
    from ..testcase import load_test

    if args.uav is None and not args.resume:  # the seed test's default UAV, recorded in run.json
        from ..sim.profiles import default_profile
        args.uav = default_profile(load_test(args.test or data_path("rq2-seed.yaml"))).name
    with new_search_folder(args, GenerateOptions) as (out, options):
        mutators = None
        if options.all_mutators:
            seed = load_test(options.test or data_path("rq2-seed.yaml"))
            mutators = default_mutators(seed, AUTHORS_ORDER)
        env = GenerateEnv(seed_test=options.test, runs=options.runs, budget=options.budget, mutators=mutators,
                          aggregate=options.aggregate, executor=options.dask_scheduler,
                          store=out / "evaluations.sqlite", random_seed=options.random_seed,
                          workers=options.workers, sim_config=sim_config_of(options))
    return run_search(env, options, out, "generate")
