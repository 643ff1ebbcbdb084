"""`surrealist train`: train an RL policy (PPO or SAC, ``--algorithm``) across procedurally generated problems (random
hidden layouts), or on a competition case study (``--problem case-study --case-study mission2``). ``train-ppo``, its
former name, still works."""
from __future__ import annotations

import sys
import time


def add_arguments(parser) -> None:
    """Arguments of ``surrealist train``."""
    from .options import OUT_PATTERN

    parser.add_argument("--steps", type=int, default=2000, help="env steps (evaluations) to train for (default 2000)")
    parser.add_argument("--out", metavar="POLICY.zip", default=None,
                        help=f"where to save the policy (default {OUT_PATTERN.format(command='train')}/policy.zip): "
                             "a new file unless --overwrite")
    parser.add_argument("--overwrite", action="store_true", help="replace the policy an existing --out holds")
    parser.add_argument("--problem", default="replicate", choices=["replicate", "generate", "case-study"],
                        help="training problems: hidden layouts of case0 (replicate), RQ2 seeds (generate), or a "
                             "competition case study's layouts within its rules (case-study, with --case-study)")
    parser.add_argument("--case-study", default=None, metavar="NAME|YAML",
                        help="the case study of --problem case-study: mission1-mission3 or an Aerialist YAML")
    parser.add_argument("--obstacles", type=int, default=3,
                        help="boxes per test of --problem case-study, 1 to 3 (default 3)")
    parser.add_argument("--envs", type=int, default=1,
                        help="envs stepped together, each in a process of its own (SB3's SubprocVecEnv; its runs fly "
                             "inline there); default 1")
    parser.add_argument("--algorithm", default="ppo", choices=["ppo", "sac"], help="SB3 algorithm (default ppo)")
    parser.add_argument("--episode-budget", type=int, default=15, help="evaluations per episode (default 15)")
    parser.add_argument("--runs", type=int, default=1, help="simulations per evaluation (default 1)")
    parser.add_argument("--spread", type=float, default=0.3,
                        help="how far hidden layouts lie from the seed, in action units (default 0.3; replicate and "
                             "generate)")
    parser.add_argument("--seed", default=None, metavar="TEST.yaml",
                        help="seed test case (default: replicate: the paper's seed 1 of case0, rq1-seed1.yaml; "
                             "generate: the paper's RQ2 seed, rq2-seed.yaml)")
    parser.add_argument("--random-seed", type=int, default=0, metavar="N",
                        help="seed of the problems (their noise and hidden layouts), the policy and its sampling "
                             "(default 0)")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    parser.add_argument("--init", default=None, metavar="POLICY.zip",
                        help="start from this policy's weights (its optimiser afresh): train on after an "
                             "interrupted training, which saves the policy so far")


def run(args) -> int:
    """Train the policy across generated problems and save it; returns the exit code."""
    import json
    import math
    from pathlib import Path

    from tqdm import tqdm

    from ..errors import SurrealistError
    from .options import check_at_least, check_writable, default_out, refuse_inapplicable

    case_study = args.problem == "case-study"
    refuse_inapplicable(args, [
        ("--case-study", case_study, "applies only to --problem case-study"),
        ("--obstacles", case_study, "applies only to --problem case-study"),
        (("--spread", "--seed"), not case_study, "not with --problem case-study (its boxes are searched within the "
                                                 "competition's rules, not drawn around a seed test)"),
    ])
    if case_study and args.case_study is None:
        raise SurrealistError("--problem case-study: name the case study with --case-study NAME|YAML (e.g. mission2)")
    check_at_least(args, steps=1, episode_budget=2, runs=1, threads=1, random_seed=0, envs=1, obstacles=1)
    if args.obstacles > 3:
        raise SurrealistError(f"--obstacles: the competition allows 1 to 3 boxes, got {args.obstacles}")
    if case_study:  # the case study is read before anything is trained or flown
        from ..competition.rules import case_study_path
        args.case_study = str(case_study_path(args.case_study).resolve())
    args.out = args.out or str(default_out("train") / "policy.zip")
    if not (math.isfinite(args.spread) and 0 < args.spread <= 1):
        raise SurrealistError(f"--spread: expected a number in (0, 1] (action units), got {args.spread:g}")
    out = Path(args.out)  # stable-baselines3 saves to the path with .zip added unless it ends in .zip
    out = out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
    check_writable(out, "--out", "file")
    if out.exists() and not args.overwrite:
        raise SurrealistError(f"--out {out}: holds a policy already; --overwrite replaces it, or choose another file")
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
        extra = dict(case_study=args.case_study, obstacles=args.obstacles) if case_study else dict(
            spread=args.spread, seed_test=args.seed)
        path = train_policy(args.steps, args.out, problem=args.problem, algorithm=args.algorithm,
                            budget=args.episode_budget, runs=args.runs, seed=args.random_seed, progress=progress,
                            envs=args.envs, init=args.init, **extra)
    except KeyboardInterrupt:
        bar.close()
        saved = Path(args.out) if Path(args.out).suffix == ".zip" else Path(args.out + ".zip")
        record = saved.with_suffix(".json")
        done = json.loads(record.read_text()).get("interrupted_after_steps") if record.is_file() else None
        if done is None:
            print("interrupted: no policy saved", file=sys.stderr)
        else:
            print(f"interrupted after {done} of {args.steps} steps: the policy so far is in {saved} (record in "
                  f"{record}); train on with the same options and --init {saved} --steps {args.steps - done} "
                  f"--out NEW.zip", file=sys.stderr)
        return 130
    bar.close()
    record = json.loads(path.with_suffix(".json").read_text())["record"]
    what = f"case study {Path(args.case_study).stem}" if case_study else f"{args.problem} problems"
    print(f"trained {args.algorithm} for {args.steps} steps on {what} in {time.perf_counter() - start:.0f} s; "
          f"policy in {path}")
    print(f"{record['episodes']} episodes: {record['flown']} evaluations flown ({record['simulations']} simulations), "
          f"{record['refused']} actions refused, {record['memo']} answered from the memo"
          + (f", {record['soft_failures']} soft failures" if case_study else "")
          + f"; record in {path.with_suffix('.json')}")
    if case_study:
        print(f"use it: surrealist compare --case-study {args.case_study} --agents suite,random,"
              f"{args.algorithm}:{path} ...")
    else:
        print(f"use it: surrealist compare --agents greedy,{args.algorithm}:{path} ...")
    return 0
