"""`surrealist replicate LOG`: find the obstacles that make the simulated flight match a real one (paper RQ1)."""
from __future__ import annotations

from ._search import add_search_arguments, executor_of, new_search_folder, run_search, sim_config_of

KEYS = ("log", "seed", "budget", "runs", "workers", "dask_scheduler", "preset", "random_seed", "common_noise",
        "uav", "surrogate", "first_runs", "screen", "skips_spend_budget", "verify_stop", "agent", "averaging")


def add_arguments(parser) -> None:
    parser.add_argument("log", nargs="?", default=None,
                        help="real flight log (.ulg); default: the bundled case0.ulg of the paper")
    parser.add_argument("--seed", default=None, metavar="TEST.yaml",
                        help="seed test case (default: the paper's seed 1 for case0, else a 3x3x3 m box "
                             "near the middle of the straight path, turned along it)")
    parser.add_argument("--averaging", default="dba", choices=["dba", "soft_dtw"],
                        help="how the runs of a test are averaged before the DTW (default dba)")
    add_search_arguments(parser, budget=100, runs=5)


def run(args) -> int:
    from ..envs.replicate import ReplicateEnv

    if args.uav is None and not getattr(args, "resume", None):  # a real flight: the real PX4 Vision (run.json)
        from ..sim.profiles import VISION_CASE0
        args.uav = VISION_CASE0.name
    with new_search_folder(args, "replicate", KEYS) as (out, options):
        env = ReplicateEnv(reference_log=options["log"], seed_test=options["seed"], runs=options["runs"],
                           budget=options["budget"], averaging=options["averaging"], executor=executor_of(options),
                           store=out / "evaluations.sqlite", random_seed=options["random_seed"],
                           workers=options["workers"], sim_config=sim_config_of(options))
    return run_search(env, options, out, "replicate")
