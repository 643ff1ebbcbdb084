"""`surrealist train`: train an RL policy (PPO or SAC, ``--algorithm``) across procedurally generated problems (random
hidden layouts). ``train-ppo``, its former name, still works."""
from __future__ import annotations

import sys
import time


def add_arguments(parser) -> None:
    """Arguments of ``surrealist train``."""
    from .options import OUT_PATTERN

    parser.add_argument("--steps", type=int, default=2000, help="env steps (evaluations) to train for (default 2000)")
    parser.add_argument("--out", metavar="POLICY.zip", default=None,
                        help=f"where to save the policy (default {OUT_PATTERN.format(command='train')}/policy.zip)")
    parser.add_argument("--problem", default="replicate", choices=["replicate", "generate"],
                        help="training problems: hidden layouts of case0 (replicate) or RQ2 seeds (generate)")
    parser.add_argument("--algorithm", default="ppo", choices=["ppo", "sac"], help="SB3 algorithm (default ppo)")
    parser.add_argument("--episode-budget", type=int, default=15, help="evaluations per episode (default 15)")
    parser.add_argument("--runs", type=int, default=1, help="simulations per evaluation (default 1)")
    parser.add_argument("--spread", type=float, default=0.3,
                        help="how far hidden layouts lie from the seed, in action units (default 0.3)")
    parser.add_argument("--seed", default=None, metavar="TEST.yaml",
                        help="seed test case (default: replicate: the paper's seed 1 of case0, rq1-seed1.yaml; "
                             "generate: the paper's RQ2 seed, rq2-seed.yaml)")
    parser.add_argument("--random-seed", type=int, default=0, metavar="N",
                        help="seed of the problems (their noise and hidden layouts), the policy and its sampling "
                             "(default 0)")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")


def run(args) -> int:
    """Train the policy across generated problems and save it; returns the exit code."""
    import math
    from pathlib import Path

    from tqdm import tqdm

    from ..errors import SurrealistError
    from .options import check_at_least, check_writable, default_out

    check_at_least(args, steps=1, episode_budget=2, runs=1, threads=1, random_seed=0)
    args.out = args.out or str(default_out("train") / "policy.zip")
    if not (math.isfinite(args.spread) and 0 < args.spread <= 1):
        raise SurrealistError(f"--spread: expected a number in (0, 1] (action units), got {args.spread:g}")
    out = Path(args.out)  # stable-baselines3 saves to the path with .zip added unless it ends in .zip
    check_writable(out if out.suffix == ".zip" else out.with_name(out.name + ".zip"), "--out", "file")
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
        path = train_policy(args.steps, args.out, problem=args.problem, algorithm=args.algorithm,
                            budget=args.episode_budget, runs=args.runs, spread=args.spread, seed=args.random_seed,
                            seed_test=args.seed, progress=progress)
    except KeyboardInterrupt:
        bar.close()
        print("interrupted: no policy saved", file=sys.stderr)
        return 130
    bar.close()
    print(f"trained {args.algorithm} for {args.steps} steps on {args.problem} problems in "
          f"{time.perf_counter() - start:.0f} s; policy in {path}")
    print(f"use it: surrealist compare --agents greedy,{args.algorithm}:{path} ...")
    return 0
