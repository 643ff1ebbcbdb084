"""`surrealist compare`: run several agents on the same problems and seeds; Table 2 metrics, p-values, A12."""
from __future__ import annotations

import sys
from pathlib import Path

from .options import PROBLEM_DEFAULTS, PROBLEM_ENVS

CASE_STUDY_ENV = PROBLEM_ENVS["case study"]


def add_arguments(parser) -> None:
    """Arguments of ``surrealist compare``."""
    from .options import WORKERS_HELP, add_dask_argument, add_random_seed_argument, out_help

    parser.add_argument("--env", default=None,
                        help=f"env id: {', '.join(PROBLEM_ENVS.values())} (default {PROBLEM_ENVS['replicate']}; "
                             f"with --case-study {CASE_STUDY_ENV})")
    parser.add_argument("--case-study", default=None, metavar="NAME|YAML",
                        help=f"the UAV Testing Competition case study the searches generate tests for (mission1, "
                             f"mission2, mission3 or its YAML), on {CASE_STUDY_ENV} (default mission1)")
    parser.add_argument("--obstacles", type=int, default=None, metavar="N",
                        help=f"boxes per test of the case study, 1 to 3 (default 3; only {CASE_STUDY_ENV}): as the "
                             f"policies compared were trained (surrealist train --obstacles)")
    parser.add_argument("--agents", default="greedy,random,cmaes",
                        help="comma-separated agents: greedy, greedy-paper, random, cmaes, ppo[-sample]:POLICY.zip, "
                             "sac:POLICY.zip, module:Class or file.py:Class (default greedy,random,cmaes)")
    parser.add_argument("--repetitions", type=int, default=10, help="searches per agent (default 10)")
    parser.add_argument("--budget", type=int, default=100, help="evaluations per search (default 100)")
    parser.add_argument("--runs", type=int, default=None, metavar="N",
                        help="simulations per evaluation (default: the env's: " + ", ".join(
                            f"{PROBLEM_ENVS[p]} {d['runs']}" for p, d in PROBLEM_DEFAULTS.items()) + ")")
    parser.add_argument("--seed", default=None, metavar="TEST.yaml",
                        help="seed test case (default: the env's; not with a case study, which brings its mission)")
    parser.add_argument("--log", default=None,
                        help=f"reference flight log (only {PROBLEM_ENVS['replicate']}; default: the seed test's, "
                             f"else case0)")
    add_random_seed_argument(parser, "base seed: repetition r of every agent flies with noise seed N + r and seeds "
                                     "the agent with N + r (default 0)", seed_test=True)
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help=WORKERS_HELP[:-1] + "; not with --inline or --dask-scheduler)")
    parser.add_argument("--parallel", type=int, default=1,
                        help="searches run at the same time on the workers (default 1; not with --inline)")
    add_dask_argument(parser)
    parser.add_argument("--inline", action="store_true",
                        help="simulate in this process (no worker processes; not with --dask-scheduler)")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: run i of every test flies with the same noise")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help=out_help("compare", "results folder") + "; run again with the same --out to resume")


def run(args) -> int:
    """Run the agents' searches, write the tables and the plot; returns the exit code."""
    from tqdm import tqdm

    from .options import check_at_least, check_writable, default_out, refuse_inapplicable

    check_at_least(args, repetitions=1, budget=1, runs=1, workers=1, parallel=1, random_seed=0, obstacles=1)
    if args.env is None:
        args.env = CASE_STUDY_ENV if args.case_study is not None else PROBLEM_ENVS["replicate"]

    from gymnasium.envs.registration import registry

    from search.compare import compare
    from search.registry import make_agent

    from ..errors import InvalidTestCase, SurrealistError, one_line

    surrealist_envs = sorted(k for k in registry if k.startswith("Surrealist-"))
    if args.env not in surrealist_envs:  # checked before any folder or worker exists
        raise SurrealistError(f"--env {args.env!r}: not a Surrealist env (one of {', '.join(surrealist_envs)})")
    case_study = args.env == CASE_STUDY_ENV
    refuse_inapplicable(args, [
        ("--case-study", case_study, f"applies only to {CASE_STUDY_ENV}, not to {args.env}"),
        ("--obstacles", case_study, f"applies only to {CASE_STUDY_ENV} (a case study's boxes), not to {args.env}"),
        ("--seed", not case_study, "not with a case study: it brings its own mission (the searches lay out its boxes)"),
        ("--log", args.env == PROBLEM_ENVS["replicate"],
         f"applies only to {PROBLEM_ENVS['replicate']} (a reference flight to replicate), not to {args.env}"),
        ("--dask-scheduler", not args.inline, "not with --inline: give one of them"),
        (("--workers", "--parallel"), not args.inline, "not with --inline: every simulation runs in this process"),
        ("--workers", args.dask_scheduler is None, "not with --dask-scheduler: the cluster's workers fly the runs")])
    if args.obstacles is not None and args.obstacles > 3:
        raise SurrealistError(f"--obstacles: the competition allows 1 to 3 boxes, got {args.obstacles}")
    agents = [a.strip() for a in args.agents.split(",") if a.strip()]
    if not agents:
        raise SurrealistError(f"--agents {args.agents!r}: expected comma-separated agent names such as "
                              f"greedy,random,cmaes")
    for name in agents:  # an unknown agent or a bad policy file, before any folder exists
        make_agent(name, seed=0)
    out = check_writable(args.out or default_out("compare"), "--out", "folder")
    env_kwargs = {}
    if args.case_study is not None:  # as generate --case-study names it: a YAML by its absolute path
        from ..competition.rules import case_study_path

        path = case_study_path(args.case_study)  # a case study that does not exist fails here
        env_kwargs["case_study"] = (str(path.resolve()) if Path(args.case_study).suffix in (".yaml", ".yml")
                                    else args.case_study)
    if case_study:  # the UAV generate --case-study flies, with or without --common-noise
        from ..sim.uav import DEFAULT_UAV

        env_kwargs["uav"] = DEFAULT_UAV
        if args.obstacles is not None:
            env_kwargs["obstacles"] = args.obstacles
    if args.seed:
        env_kwargs["seed_test"] = str(Path(args.seed).resolve())
    if args.log:
        env_kwargs["reference_log"] = str(Path(args.log).resolve())
    if args.common_noise:
        env_kwargs["sim_config"] = {"common_noise": True}
    try:  # the env as each search makes it, once, before any folder exists: bad inputs of the problem fail here
        import gymnasium as gym

        gym.make(args.env, **env_kwargs, budget=args.budget, executor="inline",
                 **({} if args.runs is None else {"runs": args.runs})).close()
    except TypeError as err:  # an option this env does not take (--log of a generation env)
        raise SurrealistError(f"--env {args.env}: does not take the options given ({one_line(err, 100)})") from None
    except InvalidTestCase as err:  # a setting of the seed test (the env checks its uav.* params): name its file
        if args.seed and str(err).startswith("params."):
            raise InvalidTestCase(f"{args.seed}: {err}") from None
        raise
    executor = args.dask_scheduler or ("inline" if args.inline else "process")
    bar = tqdm(total=len(agents) * args.repetitions * args.budget, unit="eval", desc="compare", dynamic_ncols=True,
               file=sys.stderr, disable=None)
    done: dict[tuple[str, int], int] = {}

    def progress(event: dict) -> None:
        done[(event["agent"], event["repetition"])] = min(int(event["evaluations"]), event["budget"])
        bar.n = sum(done.values())
        bar.set_postfix(agent=event["agent"], rep=event["repetition"], refresh=False)
        bar.refresh()

    try:
        result = compare(args.env, agents, repetitions=args.repetitions, budget=args.budget, runs=args.runs,
                         out=out, env_kwargs=env_kwargs, executor=executor, workers=args.workers,
                         parallel=args.parallel, progress=progress, random_seed=args.random_seed)
    except KeyboardInterrupt:
        bar.close()
        print(f"interrupted: finished searches and every evaluation are stored; resume with --out {out}",
              file=sys.stderr)
        return 130
    bar.close()
    print((out / "compare.md").read_text(), end="")
    print(f"\n{len(result.searches)} searches ({result.new_simulations} new simulations); results in {out}/: "
          f"compare.md, compare.csv, pairwise.csv, searches.csv, convergence.png")
    return 0
