"""What `surrealist replicate` and `surrealist generate` share: options, progress bar, results folder, resume."""
from __future__ import annotations

import argparse
import json
import shutil
from collections import Counter
import sys
import time
from contextlib import contextmanager
from datetime import datetime
from pathlib import Path

from ..errors import SurrealistError

RUN_FILE = "run.json"


def add_search_arguments(parser, budget: int, runs: int) -> None:
    parser.add_argument("--budget", type=int, default=budget, help=f"evaluations allowed (default {budget})")
    parser.add_argument("--runs", type=int, default=runs, help=f"simulations per evaluation (default {runs})")
    parser.add_argument("--workers", type=int, default=None, help="local worker processes (default: all cores)")
    parser.add_argument("--dask-scheduler", default=None, metavar="ADDRESS",
                        help="run the simulations on a Dask cluster (tcp://host:port)")
    parser.add_argument("--preset", default="authors", choices=["paper", "authors"],
                        help="greedy hyper-parameters: paper Table 1, or the authors' own run (default)")
    parser.add_argument("--agent", default="greedy",
                        help="search agent: greedy (default), greedy-paper, random, cmaes, ppo:POLICY.zip, "
                             "module:Class")
    parser.add_argument("--random-seed", type=int, default=0, help="base seed of the simulation noise")
    parser.add_argument("--uav", default=None, metavar="NAME_OR_YAML",
                        help="UAV profile: px4-v1.12-sitl-iris (PX4 SITL + PX4-Avoidance, as Aerialist flies), "
                             "px4-vision-case0, or a profile YAML (default: px4-vision-case0 for a seed test with a "
                             "reference log, as the paper's, else px4-v1.12-sitl-iris)")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: run i of every test flies with the same noise, so tests "
                             "differ only by what they change (default: each test draws its own)")
    parser.add_argument("--surrogate", default=None, metavar="MODEL|online",
                        help="pre-screen mutations with a surrogate model folder (surrealist surrogate train) "
                             "or one trained online; skipped candidates cost no simulations")
    parser.add_argument("--first-runs", type=race_stages, default=[], metavar="K[,K2...]",
                        help="racing (with a surrogate; default online): fly K runs of a candidate first and the "
                             "rest only if they do not fall clearly short of the best test's first K runs; "
                             "K1,K2,... compares again after each (e.g. 1,2,3,4)")
    parser.add_argument("--screen", default="auto", choices=SCREEN_RULES,
                        help="pre-screening rule (with a surrogate): auto (default: lowfi with a --lowfi model, "
                             "else ei), lowfi, ei, pi, or none (skip nothing: race only, with --first-runs)")
    parser.add_argument("--skips-spend-budget", action="store_true",
                        help="pre-screening: the search's budget counts skipped and dropped candidates as "
                             "evaluations, so it walks and stops as without screening, having simulated less")
    parser.add_argument("--verify-stop", action="store_true",
                        help="pre-screening: when the search stops with budget left, restart it unscreened from "
                             "the best test")
    parser.add_argument("--out", default=None, help="results folder (default results/<command>-<time>)")
    parser.add_argument("--resume", default=None, metavar="DIR",
                        help="resume an interrupted search from its results folder (same options)")


SCREEN_RULES = ("auto", "lowfi", "ei", "pi", "none")  # surrogates.prescreen.RULES, without importing torch here


def race_stages(value) -> list[int]:
    """``--first-runs``: the run counts after which racing compares a candidate (``"1"``, ``"1,2,3,4"``; a number or
    a list from a run.json); empty when racing is off. Raises ArgumentTypeError for anything else."""
    try:
        stages = ([int(value)] if isinstance(value, int) else [int(k) for k in value] if isinstance(value, list)
                  else [int(k) for k in str(value).split(",")])
    except ValueError:
        stages = None
    if stages is None or any(k < 0 for k in stages) or any(b <= a for a, b in zip(stages, stages[1:])):
        raise argparse.ArgumentTypeError(f"expected increasing numbers of runs such as 1 or 1,2,3,4, got {value!r}")
    return [k for k in stages if k]


@contextmanager
def new_search_folder(args, command: str, keys: tuple[str, ...]):
    """Yield (folder, options) from :func:`prepare`; a folder made here is removed again if setting up fails
    (a bad log or test case leaves no empty results folder behind)."""
    fresh = not args.resume and not (args.out and Path(args.out).exists())
    out, options = prepare(args, command, keys)
    try:
        yield out, options
    except BaseException:
        if fresh:
            shutil.rmtree(out, ignore_errors=True)
        raise


def prepare(args, command: str, keys: tuple[str, ...]) -> tuple[Path, dict]:
    """The results folder and the options of this search (read back from run.json when resuming)."""
    if args.resume:
        out = Path(args.resume)
        saved = out / RUN_FILE
        if not saved.is_file():
            raise SurrealistError(f"{out}: not a results folder to resume (no {RUN_FILE})")
        options = json.loads(saved.read_text())
        if options.get("command") != command:
            raise SurrealistError(f"{saved}: a '{options.get('command')}' search, not '{command}'")
        return out, options
    if getattr(args, "agent", "greedy") not in (None, "greedy"):
        from search.registry import make_agent

        make_agent(args.agent)  # an unknown agent fails here, before any folder or worker exists
    if max(getattr(args, "first_runs", None) or [0]) >= args.runs:
        raise SurrealistError(f"--first-runs: expected numbers of runs below --runs ({args.runs}), "
                              f"got {','.join(map(str, args.first_runs))}")
    if getattr(args, "uav", None) is not None:
        from ..sim.profiles import PRESETS, load_profile

        load_profile(args.uav)  # a bad profile fails here, before any folder exists
        if args.uav not in PRESETS:
            args.uav = str(Path(args.uav).resolve())
    out = Path(args.out or f"results/{command}-{datetime.now():%Y%m%d-%H%M%S}")
    options = {"command": command, **{k: getattr(args, k) for k in keys}}
    for key in ("log", "test", "seed"):
        if options.get(key):
            options[key] = str(Path(options[key]).resolve())
    out.mkdir(parents=True, exist_ok=True)
    (out / RUN_FILE).write_text(json.dumps(options, indent=2) + "\n")
    return out, options


def run_search(env, options: dict, out: Path, problem: str) -> int:
    """Run the greedy on env with a live progress bar, then write the results folder and print where."""
    from tqdm import tqdm

    from search import AdaptiveGreedy

    from ..outcomes import judged_distance
    from ..results import write_results

    name = options.get("agent") or "greedy"
    if name == "greedy":
        agent = AdaptiveGreedy(options["preset"])
    else:
        from search.registry import make_agent

        agent = make_agent(name, seed=options["random_seed"])
    try:
        stages = tuple(race_stages(options.get("first_runs") or 0))
    except argparse.ArgumentTypeError as error:
        raise SurrealistError(f"{out / RUN_FILE}: first_runs: {error}") from None
    if (options.get("surrogate") or stages or options.get("skips_spend_budget") or options.get("verify_stop")
            or options.get("screen", "auto") != "auto"):
        from surrogates.prescreen import PrescreenConfig, wrap

        config = PrescreenConfig(rule=options.get("screen") or "auto", first_runs=stages,
                                 skips_spend_budget=bool(options.get("skips_spend_budget")),
                                 verify_stop=bool(options.get("verify_stop")))
        agent = wrap(agent, options.get("surrogate") or "online", env, config)
    bar = tqdm(total=options["budget"], unit="eval", desc=problem, dynamic_ncols=True, file=sys.stderr,
               disable=None)
    start = time.perf_counter()

    def progress(info: dict) -> None:
        bar.n = min(info["evaluations"], bar.total)
        bar.set_postfix(best=f"{info['best_fitness']:.2f}", memo=info.get("memo", False), refresh=False)
        bar.refresh()

    try:
        result = agent.run(env, seed=options["random_seed"], callback=progress)
    except KeyboardInterrupt:
        bar.close()
        print(f"interrupted: every finished evaluation is stored; resume with --resume {out}", file=sys.stderr)
        env.close()
        return 130
    bar.n = min(result.evaluations, bar.total)
    bar.close()
    summary = write_results(out, env, result, time.perf_counter() - start, problem)
    if hasattr(agent, "skipped"):
        (out / "skipped.json").write_text(json.dumps(agent.skipped, indent=1, default=str) + "\n")
        raced = agent.dropped
        ties = sum(bool(s.get("tie")) for s in agent.skipped)
        margin = "/".join("not calibrated" if m is None else f"{m:.2f}" for m in agent.race_margins.values())
        print(f"pre-screening ({agent.rule}): {len(agent.skipped) - raced} candidates skipped without a simulation"
              + (f", {raced} dropped after their first {'/'.join(map(str, stages))} runs ({ties} of them tied the "
                 f"best; racing margin {margin})" if stages else "") + " (skipped.json)")
    env.close()
    print(f"{problem}: seed fitness {summary['seed_fitness']:.2f} -> best {summary['best_fitness']:.2f} "
          f"after {summary['evaluations_to_best']} of {summary['evaluations']} evaluations "
          f"({summary['simulations']} simulations, {summary['wall_seconds']:.1f} s)")
    for key, value in summary["best_terms"].items():
        if isinstance(value, float):
            print(f"  best {key}: {value:.2f} (seed {summary['seed_terms'].get(key, float('nan')):.2f})")
    for label in ("seed", "best"):
        runs = summary[f"{label}_runs"]
        statuses = Counter(r["status"] for r in runs)
        measure = summary.get("distance", "paper")
        closest = min((judged_distance(r, measure) for r in runs), default=float("nan"))
        print(f"  {label} runs: " + ", ".join(f"{n} {s}" for s, n in statuses.most_common())
              + f"; closest approach {closest:.2f} m ("
              + ("competition distance" if measure == "competition" else "2-D clearance") + ")")
    print(f"results in {out}/: best.yaml, evaluations.csv, summary.json, figure1.png, fitness.png, "
          f"min_distances.png")
    return 0


def executor_of(options: dict):
    return options.get("dask_scheduler") or None


def sim_config_of(options: dict):
    """The search's SimConfig: its noise mode, flown by its UAV profile when it names one."""
    from ..sim import SimConfig

    config = SimConfig(common_noise=bool(options.get("common_noise")))
    if options.get("uav") is not None:
        from ..sim.profiles import load_profile

        config = load_profile(options["uav"]).sim_config(config)
    return config
