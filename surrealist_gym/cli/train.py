"""`surrealist train`: train an RL policy (PPO or SAC, ``--algorithm``) across procedurally generated problems (random
hidden layouts), or on a competition case study (``--problem case-study --case-study mission2``). ``train-ppo``, its
former name, still works."""
from __future__ import annotations

import sys
import time


def add_arguments(parser) -> None:
    """Arguments of ``surrealist train``."""
    from .options import OUT_PATTERN, add_dask_argument, add_workers_argument, refuse_argument

    parser.add_argument("--steps", type=int, default=2000, help="env steps (evaluations) to train for (default 2000)")
    parser.add_argument("--policy", metavar="FILE.zip", default=None,
                        help=f"the policy file to write, its record FILE.json beside it (default "
                             f"{OUT_PATTERN.format(command='train')}/policy.zip): a new file unless --overwrite")
    refuse_argument(parser, "--out", _out_refused)
    parser.add_argument("--overwrite", action="store_true", help="replace the policy an existing --policy holds")
    parser.add_argument("--problem", default="replicate", choices=["replicate", "generate", "case-study", "missions"],
                        help="training problems: hidden layouts of case0 (replicate), RQ2 seeds (generate), a "
                             "competition case study's layouts within its rules (case-study, with --case-study), or "
                             "case studies drawn at random, for one policy on every mission (missions)")
    parser.add_argument("--case-study", default=None, metavar="NAME|YAML",
                        help="the case study of --problem case-study: mission1-mission3 or an Aerialist YAML")
    parser.add_argument("--obstacles", type=int, default=3, metavar="N",
                        help="boxes per test of --problem case-study, 1 to 3 (default 3)")
    parser.add_argument("--envs", type=int, default=1,
                        help="envs stepped together, each on a thread of its own (they fly in parallel: the compiled "
                             "loop releases the GIL); default 1")
    add_workers_argument(parser, "local worker processes flying the runs of an evaluation (default 1: in the "
                                 "training process; not with --envs above 1)", default=1)
    add_dask_argument(parser, "fly the runs on a Dask cluster (tcp://host:port; not with --envs above 1)")
    parser.add_argument("--algorithm", default="ppo", choices=["ppo", "sac"], help="SB3 algorithm (default ppo)")
    parser.add_argument("--episode-budget", type=int, default=15, help="evaluations per episode (default 15)")
    parser.add_argument("--runs", type=int, default=1, metavar="N", help="simulations per evaluation (default 1)")
    parser.add_argument("--spread", type=float, default=0.3,
                        help="how far hidden layouts lie from the seed, in action units (default 0.3; replicate and "
                             "generate)")
    parser.add_argument("--seed", default=None, metavar="TEST.yaml",
                        help="seed test case (default: replicate: the paper's seed 1 of case0, rq1-seed1.yaml; "
                             "generate: the paper's RQ2 seed, rq2-seed.yaml)")
    parser.add_argument("--random-seed", type=int, default=0, metavar="N",
                        help="seed of the problems (their noise and hidden layouts), the policy and its sampling "
                             "(default 0)")
    parser.add_argument("--learning-rate", type=float, default=None, metavar="RATE",
                        help="the optimiser's learning rate (default the algorithm's: 3e-4)")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    parser.add_argument("--init", default=None, metavar="POLICY.zip",
                        help="start from this policy's weights (its optimiser afresh): train on after an "
                             "interrupted training, which saves the policy so far")


def _out_refused(value) -> str:
    """``--out``, train's name for its policy file before: the file is ``--policy``."""
    if value and str(value).endswith(".zip"):
        return f"--out is a folder; the policy file is --policy {value}"
    return ("--out is a folder; train writes one policy file: --policy " + (f"{value.rstrip('/')}/policy.zip" if value
                                                                           else "FILE.zip"))


def run(args) -> int:
    """Train the policy across generated problems and save it; returns the exit code."""
    import json
    import math
    from pathlib import Path

    from tqdm import tqdm

    from ..errors import SurrealistError
    from .options import check_at_least, check_writable, default_out, refuse_inapplicable, refuse_workers_with_dask

    case_study = args.problem == "case-study"
    competition = args.problem in ("case-study", "missions")
    refuse_inapplicable(args, [
        ("--case-study", case_study, "applies only to --problem case-study (missions draws its case studies)"),
        ("--obstacles", case_study, "applies only to --problem case-study (missions draws 1 to 3 boxes)"),
        (("--spread", "--seed"), not competition, f"not with --problem {args.problem} (its boxes are searched within "
                                                  f"the competition's rules, not drawn around a seed test)"),
    ])
    if case_study and args.case_study is None:
        raise SurrealistError("--problem case-study: name the case study with --case-study NAME|YAML (e.g. mission2)")
    check_at_least(args, steps=1, episode_budget=2, runs=1, threads=1, random_seed=0, envs=1, obstacles=1, workers=1)
    refuse_workers_with_dask(args)
    refuse_inapplicable(args, [(("--workers", "--dask-scheduler"), args.envs == 1,
                                "not with --envs above 1: each env flies its runs inline, on its thread")])
    if args.obstacles > 3:
        raise SurrealistError(f"--obstacles: the competition allows 1 to 3 boxes, got {args.obstacles}")
    if case_study:  # the case study is read before anything is trained or flown
        from ..competition.rules import case_study_path
        args.case_study = str(case_study_path(args.case_study).resolve())
    args.policy = args.policy or str(default_out("train") / "policy.zip")
    if args.learning_rate is not None and not (math.isfinite(args.learning_rate) and 0 < args.learning_rate < 1):
        raise SurrealistError(f"--learning-rate: expected a number in (0, 1), got {args.learning_rate:g}")
    if not (math.isfinite(args.spread) and 0 < args.spread <= 1):
        raise SurrealistError(f"--spread: expected a number in (0, 1] (action units), got {args.spread:g}")
    out = Path(args.policy)  # stable-baselines3 saves to the path with .zip added unless it ends in .zip
    out = out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
    check_writable(out, "--policy", "file")
    if out.exists() and not args.overwrite:
        raise SurrealistError(f"--policy {out}: holds a policy already; --overwrite replaces it, or choose another "
                              f"file")
    if args.init:
        from ..errors import regular_file
        regular_file(args.init, "--init policy file")
    if args.seed:  # the problems' seed test, read before anything is trained or flown
        from ..aerialist import load_test
        load_test(args.seed)

    from ..errors import DependencyNotInstalled
    try:
        import torch
    except ImportError as err:
        raise DependencyNotInstalled("train needs torch and stable-baselines3: pip install 'surrealist-gym[rl]'") \
            from err

    from search.rl import train_policy

    torch.set_num_threads(max(1, args.threads))
    bar = tqdm(total=args.steps, unit="step", desc=f"train {args.algorithm}", dynamic_ncols=True, file=sys.stderr,
               disable=None)

    def progress(steps: int) -> None:
        bar.n = min(steps, bar.total)
        bar.refresh()

    start = time.perf_counter()
    try:
        extra = (dict(case_study=args.case_study, obstacles=args.obstacles) if case_study else {} if competition
                 else dict(spread=args.spread, seed_test=args.seed))
        executor = args.dask_scheduler or ("process" if args.workers > 1 else "inline")
        path = train_policy(args.steps, args.policy, problem=args.problem, algorithm=args.algorithm,
                            budget=args.episode_budget, runs=args.runs, seed=args.random_seed, progress=progress,
                            envs=args.envs, init=args.init, executor=executor, workers=args.workers, **extra,
                            **({} if args.learning_rate is None else {"learning_rate": args.learning_rate}))
    except KeyboardInterrupt:
        bar.close()
        saved = out
        record = saved.with_suffix(".json")
        done = json.loads(record.read_text()).get("interrupted_after_steps") if record.is_file() else None
        if done is None:
            print("interrupted: no policy saved", file=sys.stderr)
        else:
            print(f"interrupted after {done} of {args.steps} steps: the policy so far is in {saved} (record in "
                  f"{record}); train on with the same options and --init {saved} --steps {args.steps - done} "
                  f"--policy NEW.zip", file=sys.stderr)
        return 130
    bar.close()
    record = json.loads(path.with_suffix(".json").read_text())["record"]
    what = (f"case study {Path(args.case_study).stem}" if case_study else "drawn case studies"
            if competition else f"{args.problem} problems")
    print(f"trained {args.algorithm} for {args.steps} steps on {what} in {time.perf_counter() - start:.0f} s; "
          f"policy in {path}")
    print(f"{record['episodes']} episodes: {record['flown']} evaluations flown ({record['simulations']} simulations), "
          f"{record['refused']} actions refused, {record['memo']} answered from the memo"
          + (f", {record['soft_failures']} soft failures" if competition else "")
          + f"; record in {path.with_suffix('.json')}")
    print(f"use it: {compare_command(args, path)}")
    return 0


def compare_command(args, policy) -> str:
    """The ``surrealist compare`` that compares the policy a training saved with the other agents, on the problem it
    was trained for (its env, its case study and boxes, or its seed test), as a shell runs it."""
    import shlex

    from .options import PROBLEM_ENVS

    agent = f"{args.algorithm}:{policy}"
    if args.problem == "missions":  # a policy for every mission: on a case study it never trained on
        words = ["--case-study", "mission2", "--obstacles", "3", "--agents", f"suite,random,{args.algorithm}-sample:"
                                                                              f"{policy}"]
    elif args.problem == "case-study":
        words = ["--case-study", args.case_study, "--obstacles", str(args.obstacles), "--agents",
                 f"suite,random,{agent}"]
    else:
        words = ["--env", PROBLEM_ENVS[args.problem], *(["--seed", args.seed] if args.seed else []),
                 "--agents", f"greedy,random,{agent}"]
    return shlex.join(["surrealist", "compare", *map(str, words)])
