"""``surrealist compete TOOL_DIR CASE_STUDY BUDGET``: run a UAV Testing Competition tool, unedited, on our simulator.

The tool's own ``cli.py generate CASE_STUDY BUDGET`` runs in a copy of its folder inside ``--out``; every Aerialist
agent it reaches (Local, Docker, K8s; DroneTest or AerialistTest) flies surrealist-gym's simulator instead of PX4
and returns Aerialist's own results from ULogs. Prints where the tool's output folder is and a summary: tests
written, simulations flown and refused past the budget, failures by the competition's distance. A tool that
crashes, is stopped for asking on and on past its budget, or leaves no output folder (neither printed as
``output folder: PATH`` nor a folder of test YAMLs under ``generated_tests/``) gets one line and exit code 2, with
what it wrote kept. The tool runs with this Python, or in an environment of its own (``--tool-env``). Every
simulation is stored in ``--out`` as it completes: the same command with the same ``--out`` resumes a run that was
killed, answering the simulations stored instead of flying them again (docs/compete.md).

Example::

    surrealist compete ../shared/third_party/uav-testing-competition/snippets mission1 10 --out results/ref-m1
    SURREALIST_AERIALIST=../shared/third_party/aerialist-0.2.1 \\
        surrealist compete ../shared/third_party/peers/ambiegen/snippets mission2 10
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist compete``."""
    parser.add_argument("tool", metavar="TOOL_DIR", help="the competition tool's folder (with its cli.py)")
    parser.add_argument("case_study", metavar="CASE_STUDY",
                        help="mission1, mission2, mission3 (the tool's case_studies/ first) or an Aerialist YAML")
    parser.add_argument("budget", metavar="BUDGET", type=int, help="simulations the tool may fly (given to its cli.py)")
    from ...competition.compete.process import ToolLimits
    from ...competition.compete.toolenv import TOOL_ENV_MODES
    from ..options import (
        WORKERS_ONE_HELP,
        add_dask_argument,
        add_out_argument,
        add_random_seed_argument,
        add_workers_argument,
        refuse_argument,
    )

    add_out_argument(parser, "compete", "output folder: new, or one holding this run (then it resumes)")
    parser.add_argument("--runs", type=int, default=1, metavar="N",
                        help="runs an agent flies per test (default 1; a test's own agent.count wins)")
    refuse_argument(parser, "--runs-per-test", "use --runs (runs an agent flies per test)")
    add_workers_argument(parser, WORKERS_ONE_HELP, default=1)
    add_dask_argument(parser)
    parser.add_argument("--aerialist", metavar="DIR", default=None,
                        help="Aerialist's folder (default: the folders in $SURREALIST_AERIALIST holding the API the "
                             "tool imports, then the installed aerialist)")
    add_random_seed_argument(parser, "base seed of the runs' noise (default 0)")
    from ...sim.uav import DEFAULT_UAV

    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=DEFAULT_UAV,
                        help=f"UAV profile flown (default {DEFAULT_UAV}, the competition's PX4 SITL)")
    parser.add_argument("--tool-env", choices=TOOL_ENV_MODES, default="auto",
                        help="which Python runs the tool: ours, or an environment of its own built from its "
                             "requirements.txt and cached (default auto: ours when every module the tool imports is "
                             "installed here, else its own)")
    parser.add_argument("--tool-timeout", metavar="SECONDS", type=float, default=ToolLimits().timeout_s,
                        help="wall time after which the tool and its processes are stopped (default 7200; its CPU "
                             "time is limited to 1.5 x this: the competition gives a tool 1.5 vCPU)")
    parser.add_argument("--tool-memory", metavar="GB", type=float, default=ToolLimits().memory_gb,
                        help="address space of each of the tool's processes (RLIMIT_AS, default 8)")
    parser.add_argument("--tool-env-cache", metavar="DIR", default=None,
                        help="where the tools' own environments are kept (default $SURREALIST_TOOL_ENVS, else "
                             "~/.cache/surrealist-gym/tool-envs)")


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit code."""
    import math

    from tqdm import tqdm

    from ...competition.compete import claim, prepare, run as run_tool
    from ...competition.compete.process import ToolLimits
    from ...competition.compete.toolenv import CACHE_ENV
    from ...errors import SurrealistError
    from ..options import check_at_least, check_writable, default_out, refuse_workers_with_dask

    if args.budget < 1:  # the positional BUDGET, named as the usage names it
        raise SurrealistError(f"BUDGET: expected a whole number >= 1, got {args.budget}")
    check_at_least(args, runs=1, workers=1, random_seed=0)
    refuse_workers_with_dask(args)
    for flag, value, top in (("--tool-timeout", args.tool_timeout, 10 ** 7), ("--tool-memory", args.tool_memory, 4096)):
        if not (math.isfinite(value) and 0 < value <= top):
            raise SurrealistError(f"{flag}: expected a number above 0 and at most {top}, got {value:g}")
    plan = prepare(args.tool, args.case_study, args.budget, args.out or default_out("compete"),
                   runs_per_test=args.runs, workers=args.workers, aerialist=args.aerialist,
                   executor=args.dask_scheduler,
                   seed=args.random_seed, uav=args.uav, tool_env=args.tool_env,
                   tool_env_cache=args.tool_env_cache,
                   limits=ToolLimits(timeout_s=args.tool_timeout, memory_gb=args.tool_memory))
    check_writable(plan.out, "--out")
    _allow_the_tools_files(plan)
    if plan.env.kind == "own":  # where its environment is kept (built there unless it is)
        check_writable(plan.env.cache, "--tool-env-cache" if args.tool_env_cache else f"${CACHE_ENV} or the cache")
    print(f"tool: {plan.tool} ({', '.join(plan.apis) or 'no Aerialist test API found'}), case study "
          f"{plan.case_study_file}, budget {plan.budget}; {plan.aerialist.describe()}; UAV {plan.uav}", flush=True)
    if plan.env.kind == "own":
        print(f"tool environment: its own ({plan.env.reason}), from the cache {plan.env.cache} or built there "
              f"(pip's output: {plan.out / 'tool-env.txt'})", flush=True)
    print(plan.limits.describe(), flush=True)
    folder = claim(plan)  # one writer: a second compete on this --out stops here, in one line
    bar = tqdm(total=plan.budget, unit="sim", desc="simulations", file=sys.stderr, dynamic_ncols=True)
    failing = []

    def on_flight(flight) -> None:
        if flight.refused:
            bar.set_postfix_str(f"refused: over budget ({flight.number})")
            return
        bar.update(len(flight.statuses))
        failing.extend(d for d in flight.distances if d < 1.5)
        bar.set_postfix_str(f"runs < 1.5 m: {len(failing)}")

    try:  # the folder claimed (one writer; a run of the same settings there is resumed), the tool run
        result = run_tool(plan, on_flight, folder)
    finally:
        bar.close()
    _print_summary(result)
    if result.problem:
        raise SurrealistError(result.problem)
    return 0


def _allow_the_tools_files(plan) -> None:
    """The tests a tool sends name its files by absolute path (its folder, the copy it runs in under ``--out``, the
    case study given): the tests may read there, for this command (cli.main restores the environment)."""
    import os

    from ...errors import ALLOW_OUTSIDE_ENV

    folders = [os.environ.get(ALLOW_OUTSIDE_ENV)] + [str(Path(p).resolve()) for p in
                                                      (plan.tool, plan.out, Path(plan.case_study_file).parent)]
    os.environ[ALLOW_OUTSIDE_ENV] = os.pathsep.join(filter(None, folders))


def _print_summary(result) -> None:
    plan = result.plan
    if result.tool_env is not None:
        print(result.tool_env.describe())
    if result.output_folder is not None:
        complete = sum(1 for t in result.tests if t.ulg is not None and t.png is not None)
        print(f"output folder: {result.output_folder} (the tool's: {len(result.tests)} tests, {complete} with yaml, "
              f"ulg and png; {result.found_by})")
    flown = [f for f in result.flights if f.statuses]
    mean = sum(f.wall_s for f in flown) / max(1, sum(len(f.statuses) for f in flown))
    print(f"simulations: {result.spent} of budget {plan.budget} flown ({mean:.2f} s each), {result.refused} refused; "
          f"{len(result.flights)} agent runs in {result.wall_s:.1f} s"
          + (f"; resumed: {result.replayed} of them read back from {plan.out / 'flights.sqlite'}"
             if result.replayed else ""))
    if result.refused and not result.problem:
        print(f"budget: the tool asked for {result.refused} simulations past its budget of {plan.budget}; they were "
              f"refused (it saw each as a failed execution) and its output is scored as usual")
    judged = [t for t in result.tests if t.distance is not None]
    if judged:
        counts = {p: sum(1 for t in judged if t.points == p) for p in (5, 2, 1)}
        least = min(t.distance for t in judged)
        print(f"failures by the competition's distance: {len(result.failures)} of {len(judged)} tests below 1.5 m "
              f"(5 points: {counts[5]}, 2 points: {counts[2]}, 1 point: {counts[1]}); least distance {least:.2f} m")
    unjudged = [t for t in result.tests if t.distance is None]
    for t in unjudged:
        print(f"  {t.name}: not judged ({t.note})")
    for note in result.notes:
        print(f"compat: {note}")
    for note in () if result.tool_env is None else result.tool_env.substitutions:
        print(f"compat: tool environment: {note}")
    print(f"records: {plan.out / 'summary.json'}, {plan.out / 'flights.csv'}, flights in {plan.out / 'flights'}/")
