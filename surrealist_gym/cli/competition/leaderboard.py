"""``surrealist leaderboard TOOL_DIR... --case-study NAME...``: the competition's leaderboard on our simulator.

Every (tool, case study, repetition) cell runs through ``surrealist compete`` (the tool's own ``cli.py``, unedited),
then each case study and repetition is scored as the ``--edition`` did: 2024 (budget 200, up to 4 boxes of any size,
20 tests drawn at random, 5 runs each, the rest score and the similarity penalty, ranked by suite score), 2025
(budget 100, up to 3 boxes within the size bounds, the first 20 tests, 3 runs each, duplicates, diversity, R = 0.75
R_F + 0.25 R_D) or 2026 (2025's bounds, the first 20 valid tests in the tool's rank order, 5 runs each, the
similarity penalty, ranked by suite score, scored with and without the case study's wind). Writes
``leaderboard.csv`` (one row per cell), ``leaderboard.png`` and ``report.md`` (with PX4's published figures beside
ours where the tools and case studies are the reports'); every cell and every run is kept as it completes, and the
same command resumes.

Example::

    surrealist leaderboard ../shared/third_party/peers/{ambiegen,camba}/snippets \\
        ../shared/third_party/peers/deephyperion-uav/DeepHyperion --case-study mission2 mission3 --edition 2024 \\
        --repetitions 3 --workers 2 --out results/board-2024
"""
from __future__ import annotations

import argparse
import sys
import time


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist leaderboard``."""
    from ...competition.scoring import EDITIONS
    from ..options import add_dask_argument, add_out_argument, add_random_seed_argument

    parser.add_argument("tools", metavar="TOOL_DIR", nargs="+",
                        help="competition tools' folders (each with its cli.py), named on the board by their folder "
                             "(a folder called snippets by its parent's); or surrealist compete output folders, "
                             "each a cell run before (its tool's repetitions 0, 1, ... in the order given)")
    parser.add_argument("--case-study", dest="case_studies", metavar="NAME", nargs="+", default=(),
                        help="case studies: mission1, mission2, mission3 or Aerialist YAMLs (default: those of the "
                             "compete output folders given)")
    parser.add_argument("--edition", required=True, choices=list(EDITIONS),
                        help="score as this edition did; its defaults: " + "; ".join(
                            f"{e.name}: budget {e.budget}, up to {e.max_obstacles} boxes"
                            + (" within the size bounds" if e.size_bounds else " of any size") + f", {e.runs} runs of "
                            + (f"{e.tests} tests drawn at random" if e.draw == "random" else f"the first {e.tests}"
                               + (" valid tests in the tool's rank order" if e.valid_only else " tests written"))
                            + (", the rest score" if e.rest else "")
                            + (", the similarity penalty" if e.similarity == "flights" else ", duplicates and "
                               "diversity") + (", with and without wind" if e.wind else "") for e in EDITIONS.values()))
    parser.add_argument("--tests", type=int, default=None, metavar="N",
                        help="tests evaluated of each suite (default: the edition's, 20; 2026 did not publish how "
                             "many it evaluates, and 2024 and 2025 evaluated 20)")
    parser.add_argument("--similar-m", type=float, default=None, metavar="M",
                        help="2024 and 2026: two tests are alike (sim_pen) when their runs' averaged flights are "
                             "closer than M metres on average along DTW's path (default 0.4: as alike as repeats "
                             "of one test are here; neither edition published a number)")
    parser.add_argument("--budget", type=int, default=None,
                        help="simulations per tool and case study (default: the edition's)")
    parser.add_argument("--repetitions", type=int, default=3, help="runs of each tool on each case study (default 3)")
    parser.add_argument("--runs", type=int, default=None, metavar="N",
                        help="runs per evaluated test in the scoring (default: the edition's)")
    add_random_seed_argument(parser, "base seed: repetition k runs the tools and scores with seed S + k (default 0)")
    parser.add_argument("--workers", type=int, default=None, metavar="N",
                        help="cells run at once, and processes flying the scoring's runs (default: all cores, at "
                             "most 8)")
    add_dask_argument(parser)
    from ...sim.uav import DEFAULT_UAV

    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=DEFAULT_UAV,
                        help=f"UAV profile flown (default {DEFAULT_UAV}, the competition's PX4 SITL)")
    add_out_argument(parser, "leaderboard", "output folder: new, or one holding this board (then it resumes)")


def run(args: argparse.Namespace) -> int:
    """Check everything, run the missing cells, score, write the board; returns the exit code."""
    from ...competition import leaderboard as lb
    from ...competition.reports.leaderboard import write_report
    from ...errors import SurrealistError
    from ...executors import default_workers
    from ...results import ResultsFolder
    from ...sim.uav import decide_uav
    from ..options import check_at_least, check_writable, default_out, refuse_workers_with_dask

    check_at_least(args, workers=1)
    refuse_workers_with_dask(args)
    out = args.out or default_out("leaderboard")
    check_writable(out, "--out")
    board = lb.plan(args.tools, args.case_studies, args.edition, budget=args.budget, repetitions=args.repetitions,
                    runs=args.runs, seed=args.random_seed, uav=args.uav, tests=args.tests,
                    similar_m=args.similar_m, out=out)
    workers = args.workers or default_workers()
    executor = None
    if args.dask_scheduler:
        from ...executors import DaskExecutor

        executor = DaskExecutor(args.dask_scheduler)
    print(f"leaderboard: {len(board.tools)} tools ({', '.join(t.name for t in board.tools)}) x "
          f"{len(board.case_studies)} case studies x {board.repetitions} repetitions, edition {board.edition.name}: "
          f"budget {board.budget}, {board.runs} runs of up to {board.edition.tests} tests; UAV {board.uav}; "
          f"{'Dask ' + args.dask_scheduler if executor else f'{workers} workers'}; {board.out}", flush=True)
    folder = ResultsFolder.claim(board.out, "leaderboard", None, settings_file=lb.BOARD_FILE, stores=())
    lb.start(board)  # its settings, written by the one writer (a board grows: lb.plan compared them)
    decide_uav(uav=board.uav).write(board.out)  # each cell's compete folder records it too
    started = time.perf_counter()
    try:
        summaries = lb.run_cells(board, workers, executor and executor.client,
                                 done=lambda cell, values: _cell_line(cell, values, board, started))
        scores = []
        for cell in board.cells:
            for wind in board.variants:
                scores.append(lb.score_cell(board, cell, summaries[cell], wind, workers=workers, executor=executor))
                s = scores[-1]
                print(f"scored {cell.tool.name} on {cell.label} rep {cell.repetition}"
                      + (f", {wind} wind" if wind else "") + f": {s.suite.failing} of {len(s.suite.drawn)} evaluated "
                      f"tests failing, score {s.suite.score:.2f}" + (f"; {s.problem}" if s.problem else ""),
                      flush=True)
        rows = lb.rank(board, scores)
    except KeyboardInterrupt:
        print(f"interrupted: every finished cell and scored run is kept in {board.out}; the same command resumes",
              file=sys.stderr)
        return 130
    except SurrealistError as err:
        raise SurrealistError(f"{err}; what is done is kept in {board.out}: the same command resumes") from None
    finally:
        folder.release()  # kept: every finished cell and scored run is in it
        if executor is not None:
            executor.close()
    paths = write_report(board, rows)
    print(paths["text"])
    print(f"leaderboard: {paths['csv']}; figure: {paths['png']}; report: {paths['report']} "
          f"({time.perf_counter() - started:.0f} s)")
    return 0


def _cell_line(cell, values: dict, board, started: float) -> None:
    tests = values.get("tests") or []
    failing = sum(1 for t in tests if t.get("points"))
    print(f"[{time.perf_counter() - started:5.0f} s] {cell.tool.name} on {cell.label} rep {cell.repetition}: "
          f"{len(tests)} tests written ({failing} under 1.5 m in their run), {values.get('simulations')} of "
          f"{board.budget} simulations" + (f", {values['refused']} refused" if values.get("refused") else "")
          + (f"; {values['problem']}" if values.get("problem") else ""), flush=True)
