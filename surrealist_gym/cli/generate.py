"""`surrealist generate TEST.yaml`: find nearby tests that make the UAV unsafe or crash (paper RQ2)."""
from __future__ import annotations

from ._search import add_search_arguments, executor_of, new_search_folder, run_search, sim_config_of

KEYS = ("test", "budget", "runs", "workers", "dask_scheduler", "preset", "random_seed", "common_noise",
        "uav", "surrogate", "first_runs", "screen", "skips_spend_budget", "verify_stop", "agent", "aggregate",
        "all_mutators")


def add_arguments(parser) -> None:
    parser.add_argument("test", nargs="?", default=None,
                        help="seed test case (Aerialist YAML); default: the paper's RQ2 seed")
    parser.add_argument("--aggregate", default="riskiest", choices=["riskiest", "mean"],
                        help="how the runs of a test are scored: the riskiest run (paper) or the mean")
    parser.add_argument("--all-mutators", action="store_true",
                        help="move, resize and rotate every obstacle (default: move the first obstacle only)")
    add_search_arguments(parser, budget=50, runs=10)


def run(args) -> int:
    from ..envs.generate import GenerateEnv
    from ..mutators import AUTHORS_ORDER, default_mutators
    from ..testcase import load_test

    if args.uav is None and not getattr(args, "resume", None):  # the seed test's default UAV, recorded in run.json
        from .. import data_path
        from ..sim.profiles import default_profile
        args.uav = default_profile(load_test(args.test or data_path("rq2-seed.yaml"))).name
    with new_search_folder(args, "generate", KEYS) as (out, options):
        mutators = None
        if options["all_mutators"]:
            from .. import data_path
            seed = load_test(options["test"] or data_path("rq2-seed.yaml"))
            mutators = default_mutators(seed, AUTHORS_ORDER)
        env = GenerateEnv(seed_test=options["test"], runs=options["runs"], budget=options["budget"],
                          mutators=mutators, aggregate=options["aggregate"], executor=executor_of(options),
                          store=out / "evaluations.sqlite", random_seed=options["random_seed"],
                          workers=options["workers"], sim_config=sim_config_of(options))
    return run_search(env, options, out, "generate")
