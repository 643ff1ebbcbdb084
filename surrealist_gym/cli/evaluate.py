"""``surrealist evaluate TESTS...``: re-fly a suite of Aerialist tests N times each and report how they fail.

TESTS are Aerialist YAMLs or folders of them (any generator's). Each test is flown ``--runs`` times; the command
prints one row per test (failure probability with its 95% Clopper-Pearson interval, the competition's points,
closest approach) and the suite's distinct failures and diversity, and writes ``report.md``, ``evaluation.csv``,
``runs.csv`` and the figures to ``--out``. Tests must keep the competition's rules unless ``--any-layout``.

Example::

    surrealist evaluate ../shared/data/competition/camba-collection --runs 5 --workers 2 --out results/camba
"""
from __future__ import annotations

import argparse
import sys
import time


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist evaluate``."""
    parser.add_argument("tests", metavar="TESTS", nargs="+", help="Aerialist test YAMLs, or folders of them")
    parser.add_argument("--runs", type=int, default=5, help="runs per test (default 5)")
    parser.add_argument("--workers", type=int, default=None, help="local worker processes (default: all cores)")
    parser.add_argument("--random-seed", type=int, default=0, metavar="S",
                        help="base seed: run i of a test draws its noise from the test, S and i (default 0)")
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="UAV profile for every test: px4-v1.12-sitl-iris, px4-vision-case0 or a profile YAML "
                             "(default: each test's own, px4-v1.12-sitl-iris for competition tests)")
    parser.add_argument("--any-layout", action="store_true",
                        help="accept tests outside the competition's rules on obstacles (count, bounds, boxes only)")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="output folder (default results/evaluate-<timestamp>)")


def summary_text(ev) -> str:
    """The table ``surrealist evaluate`` prints: one row per test, then the suite's figures."""
    from ..reevaluation import suite_lines

    width = max([len("test"), *(len(t.name) for t in ev.tests)])
    head = (f"{'test':{width}}  {'fail':>5}  {'p':>5}  {'95% CI':>12}  {'pts/run':>7}  {'median':>6}  "
            f"{'min [m]':>7}  {'med [m]':>7}  statuses")
    lines = [f"{len(ev.tests)} tests x {ev.runs} runs, seed {ev.seed}, flown in {ev.wall_s:.1f} s on {ev.workers} "
             f"worker(s)", head, "-" * len(head)]
    for t in ev.tests:
        lines.append(f"{t.name:{width}}  {f'{t.failures}/{len(t.runs)}':>5}  {t.p:5.2f}  "
                     f"{f'[{t.ci_low:.2f}, {t.ci_high:.2f}]':>12}  {t.points_mean:7.1f}  {t.points_median_run:6d}  "
                     f"{_m(t.min_distance):>7}  {_m(t.median_distance):>7}  {t.statuses}")
    return "\n".join(lines + suite_lines(ev))


def _m(value: float) -> str:
    return "-" if value != value else f"{value:.2f}"  # nan -> "-"


def run(args: argparse.Namespace) -> int:
    """Load and check the tests, fly them, print the summary and write the report."""
    from tqdm import tqdm

    from ..reevaluation import evaluate, load_tests, write_report
    from ..sim.profiles import load_profile
    from .options import check_at_least

    check_at_least(args, runs=1, workers=1)
    uav = None if args.uav is None else load_profile(args.uav)
    tests = load_tests(args.tests, any_layout=args.any_layout)  # bad input fails before the progress bar
    out = args.out or f"results/evaluate-{time.strftime('%Y%m%d-%H%M%S')}"
    bar = tqdm(total=len(tests) * args.runs, unit="run", desc="evaluate", dynamic_ncols=True, file=sys.stderr,
               disable=None)

    def progress(done: int, total: int) -> None:
        bar.n = done
        bar.refresh()

    try:
        ev = evaluate(tests, runs=args.runs, seed=args.random_seed, uav=uav, workers=args.workers,
                      progress=progress)
    finally:
        bar.close()
    paths = write_report(ev, out)
    print(summary_text(ev))
    print(f"report: {paths['report']}; per test: {paths['evaluation']}; per run: {paths['runs']}")
    return 0
