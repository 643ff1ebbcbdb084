"""``surrealist evaluate TESTS...``: re-fly a suite of Aerialist tests N times each and report how they fail.

TESTS are Aerialist YAMLs or folders of them (any generator's). Each test is flown ``--runs`` times; the command
prints one row per test (failure probability with its 95% Clopper-Pearson interval, the competition's points,
closest approach) and the suite's distinct failures and diversity, and writes ``report.md``, ``evaluation.csv``,
``runs.csv`` and the figures to ``--out``. Tests must keep the competition's rules unless ``--any-layout``.

``--competition 2024|2025`` scores each folder (a tool's output, one case study) as that edition did: it draws the
edition's tests (:mod:`surrealist_gym.competition.scoring`), flies them the edition's runs, and ranks the folders per
case study (``leaderboard.csv``, ``test-scores.csv``, ``leaderboard.png`` and a section of the report).

``--out`` holds one evaluation (a :class:`~surrealist_gym.results.ResultsFolder`): its options (``run.json``, with the
tests drawn) and every run, stored as it completes (``evaluations.sqlite``). The same command with the same ``--out``,
or ``--resume DIR``, finishes an interrupted evaluation: it flies only the missing runs and writes the same report an
uninterrupted one would have.

Example::

    surrealist evaluate ../shared/data/competition/camba-collection --runs 5 --workers 2 --out results/camba
    surrealist evaluate tool-a/out tool-b/out --competition 2025 --out results/ranked
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from dataclasses import dataclass
from pathlib import Path

from ...competition.scoring import EDITIONS, Draw
from ...errors import SurrealistError
from ...results import RUN_FILE
from ...sim.uav import recorded_choice, write_record
from ..options import default_out

STORE_FILE = "evaluations.sqlite"
DEFAULT_RUNS = 5  # runs per test without --competition


@dataclass(frozen=True)
class EvaluateOptions:
    """What an evaluation is run with, as ``run.json`` keeps it: the tests (absolute paths as given), runs per test,
    base seed, UAV profile (a preset's name or a YAML's absolute path), whether the competition's rules are skipped,
    the workers (the one option ``--resume`` may change), with ``--competition``, the edition and each folder's
    draw (so that a resume flies the same tests), and the competition distance's ``--buffer``."""

    tests: tuple[str, ...]
    runs: int = 5
    random_seed: int = 0
    uav: str | None = None
    any_layout: bool = False
    workers: int | None = None
    competition: str | None = None
    draws: tuple[Draw, ...] = ()
    buffer: float = 0.0

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> "EvaluateOptions":
        """The options of a new evaluation; with ``--competition``, each folder's tests are loaded and drawn here
        (one-line errors before anything is flown)."""
        from ...competition.scoring import draw_folder, edition

        ed = None if args.competition is None else edition(args.competition)
        runs = args.runs if args.runs is not None else ed.runs if ed else DEFAULT_RUNS
        draws = () if ed is None else tuple(
            draw_folder(folder, ed, args.random_seed)
            for folder in dict.fromkeys(str(Path(t).absolute()) for t in args.tests))  # each folder once
        return cls(tuple(str(Path(t).absolute()) for t in args.tests), runs, args.random_seed,
                   recorded_choice(args.uav), args.any_layout, args.workers, ed and ed.name, draws, args.buffer)

    @property
    def files(self) -> tuple[str, ...]:
        """The tests to load: with ``--competition`` the tests drawn, else the tests given."""
        return tuple(f for d in self.draws for f in d.drawn) if self.competition else self.tests

    def to_json(self) -> dict:
        """The options as the folder's ``run.json`` records them (read back by :meth:`from_json`)."""
        return {"command": "evaluate", **dataclasses.asdict(self), "tests": list(self.tests),
                "draws": [d.to_json() for d in self.draws]}

    @classmethod
    def from_json(cls, path: Path) -> "EvaluateOptions":
        """The options a results folder's ``run.json`` records (one-line errors for another command's file)."""
        try:
            values = json.loads(path.read_text())
            if values.pop("command", None) != "evaluate":
                raise SurrealistError(f"{path.parent}: holds no evaluation to resume ({path.name} is another "
                                      f"command's)")
            return cls(**{**values, "tests": tuple(values["tests"]),
                          "draws": tuple(Draw.from_json(d) for d in values.get("draws", ()))})
        except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError, AttributeError) as err:
            raise SurrealistError(f"{path}: not a readable run file ({type(err).__name__})") from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist evaluate``."""
    from ..options import (
        add_buffer_argument,
        add_dask_argument,
        add_out_argument,
        add_random_seed_argument,
        add_workers_argument,
    )

    parser.add_argument("tests", metavar="TESTS", nargs="*", help="Aerialist test YAMLs, or folders of them")
    parser.add_argument("--runs", type=int, default=None, metavar="N",
                        help=f"runs per test (default {DEFAULT_RUNS}; with --competition the edition's: "
                             + ", ".join(f"{e.name} {e.runs}" for e in EDITIONS.values()) + ")")
    parser.add_argument("--competition", metavar="EDITION", default=None,
                        help="score each folder (a tool's output or a compete folder, one case study) as the 2024, "
                             "2025 or 2026 edition did: its tests drawn, test scores, 2024's rest score and "
                             "similarity penalty, 2025's duplicates and diversity, 2026's first valid tests in rank "
                             "order and similarity penalty, and the folders ranked per case study (2026 each test "
                             "with its own wind; surrealist leaderboard scores with and without it)")
    add_workers_argument(parser)
    add_dask_argument(parser)
    add_random_seed_argument(parser, "base seed: run i of a test draws its noise from the test, N and i (default 0)")
    parser.add_argument("--uav", metavar="NAME_OR_YAML", default=None,
                        help="UAV profile for every test: px4-v1.12-sitl-iris, px4-vision-case0 or a profile YAML "
                             "(default: each test's own, px4-v1.12-sitl-iris for competition tests)")
    add_buffer_argument(parser)
    parser.add_argument("--any-layout", action="store_true",
                        help="accept tests outside the competition's rules on obstacles (count, bounds, boxes only)")
    add_out_argument(parser, "evaluate", "output folder, new or empty")
    parser.add_argument("--resume", metavar="DIR", default=None,
                        help="finish an interrupted evaluation in DIR: fly its missing runs and write its report "
                             "(same options; only --workers changes)")


def summary_text(ev) -> str:
    """The table ``surrealist evaluate`` prints: one row per test, then the suite's figures."""
    from ...competition.reports.evaluation import suite_lines

    width = max([len("test"), *(len(t.name) for t in ev.tests)])
    head = (f"{'test':{width}}  {'fail':>5}  {'err':>3}  {'p':>5}  {'95% CI':>12}  {'pts/run':>7}  {'median':>6}  "
            f"{'min [m]':>7}  {'med [m]':>7}  statuses")
    lines = [f"{len(ev.tests)} tests x {ev.runs} runs, seed {ev.seed}, flown in {ev.wall_s:.1f} s on {ev.workers} "
             f"worker(s)" + (f" ({ev.stored} runs read back from the store)" if ev.stored else ""),
             head, "-" * len(head)]
    for t in ev.tests:
        ci = f"[{t.ci_low:.2f}, {t.ci_high:.2f}]" if t.flown else "no run flown"
        lines.append(f"{t.name:{width}}  {f'{t.failures}/{t.flown}':>5}  {t.errors:3d}  {_m(t.p):>5}  {ci:>12}  "
                     f"{_m(t.points_mean, 1):>7}  {_m(t.points_median_run, 0):>6}  {_m(t.min_distance):>7}  "
                     f"{_m(t.median_distance):>7}  {t.statuses}")
    return "\n".join(lines + suite_lines(ev))


def _m(value, digits: int = 2) -> str:
    return "-" if value is None or value != value else f"{value:.{digits}f}"  # None, nan -> "-"


def run(args: argparse.Namespace) -> int:
    """Check the options, the output folder and the tests; fly the missing runs into the folder's store; print the
    summary and write the report. ``--resume DIR``, or ``--out DIR`` naming a folder that holds an evaluation,
    finishes that evaluation."""
    from ...competition.reevaluation import uav_decisions
    from ...competition.scoring import edition
    from ...competition.tool_output import load_tests, rule_broken
    from ...geometry import check_buffer
    from ...results import ResultsFolder
    from ...sim.uav import decide_uav
    from ..options import check_at_least, check_writable

    check_at_least(args, runs=1, workers=1)
    check_buffer(args.buffer)
    resume = args.resume or (args.out if args.out and _evaluation_folder(Path(args.out)) else None)
    flag = "--resume" if args.resume else "--out"
    if resume:
        out, options = _resumed(args, check_writable(resume, flag, "folder"), flag)
    else:
        if not args.tests:
            raise SurrealistError("TESTS: give the tests to evaluate (YAMLs or folders of them), or --resume DIR")
        if args.competition is not None:
            edition(args.competition)
        _distinct(args.tests, "TESTS")
        out = check_writable(Path(args.out or default_out("evaluate")), "--out", "folder")
        options = EvaluateOptions.from_args(args)
    uav = None if options.uav is None else decide_uav(uav=options.uav if resume else args.uav).profile
    scored = bool(options.competition)  # a drawn test that breaks the rules is not flown and scores 0
    tests = load_tests(args.tests if not (resume or scored) else options.files,
                       any_layout=options.any_layout or scored)
    tests = [(path.absolute(), test) for path, test in tests]  # as a resume loads them: the same report
    decisions = uav_decisions(tests, uav)  # uav.* settings the UAV takes, before anything flies
    rules = edition(options.competition).rules if scored else None
    invalid = {path: broken for path, test in tests if scored and not options.any_layout
               and (broken := rule_broken(test, rules))}
    if scored and len(invalid) == len(tests):
        raise SurrealistError(f"every drawn test breaks the competition's rules ({tests[0][0]}: "
                              f"{invalid[tests[0][0]]}): each would score 0; --any-layout flies them anyway")
    settings = None if resume else {k: v for k, v in options.to_json().items() if k != "command"}
    folder = ResultsFolder.claim(out, "evaluate", settings, free=("workers",), resume_only=bool(resume), flag=flag)
    with folder.keeping(f"surrealist evaluate --resume {out} flies the rest and writes the report", "evaluation(s)",
                        said=True):
        write_record(out, {str(path): decision for (path, _), decision in zip(tests, decisions)})
        return _evaluate(out, options, tests, uav, invalid, args.dask_scheduler)


def _distinct(tests, where: str, hint: str = "give it once") -> None:
    """Each test or folder once: two names for one (a link, ``./``) would be flown once but scored twice."""
    seen: dict = {}
    for given in tests:
        first = seen.setdefault(Path(given).resolve(), given)
        if first != given:
            raise SurrealistError(f"{where}: {given} and {first} are the same "
                                  f"{'folder' if Path(given).is_dir() else 'file'}; {hint}")


def _evaluation_folder(out: Path) -> bool:
    try:
        return json.loads((out / RUN_FILE).read_text()).get("command") == "evaluate"
    except (OSError, ValueError, AttributeError):
        return False


def _resumed(args: argparse.Namespace, out: Path, flag: str) -> tuple[Path, EvaluateOptions]:
    """The folder and options of the evaluation to finish; options given again must be those it was started with."""
    if not (out / RUN_FILE).is_file():
        raise SurrealistError(f"{flag} {out}: not an evaluation to resume (no {RUN_FILE})")
    options = EvaluateOptions.from_json(out / RUN_FILE)
    _distinct(options.tests, f"{flag} {out}: {RUN_FILE}'s tests",  # started twice by an earlier version
              "it cannot be resumed: start a new evaluation with each once")
    flags = getattr(args, "_flags", frozenset())
    given = {"tests": (tuple(str(Path(t).absolute()) for t in args.tests) if args.tests else None, None),
             "runs": (args.runs, None), "random_seed": (args.random_seed, 0), "uav": (recorded_choice(args.uav), None),
             "any_layout": (args.any_layout, False), "competition": (args.competition, None),
             "buffer": (args.buffer, 0.0)}
    for name, (value, default) in given.items():
        typed = "TESTS" if name == "tests" else "--" + name.replace("_", "-")
        if (typed in flags or value != default) and value != getattr(options, name):
            shown = f"other tests ({out / RUN_FILE} lists them)" if name == "tests" else repr(getattr(options, name))
            raise SurrealistError(f"{typed}: the evaluation in {out} was started with {shown}; resuming keeps its "
                                  f"options (only --workers changes)")
    if args.resume and args.out and Path(args.out).absolute() != out.absolute():
        raise SurrealistError(f"--out {args.out}: --resume writes to the folder it resumes ({out})")
    return out, dataclasses.replace(options, workers=args.workers or options.workers)


def _evaluate(out: Path, options: EvaluateOptions, tests, uav, invalid: dict, dask: str | None = None) -> int:
    """Fly the runs the store lacks (a progress bar from those stored), then the summary and the report; with
    ``--competition`` the folders' scores and ranks (``invalid``: the drawn tests not flown, with the rule each
    breaks)."""
    from tqdm import tqdm

    from ...competition.reevaluation import evaluate
    from ...competition.reports.evaluation import scoring_lines, write_report

    store = out / STORE_FILE
    resume = f"surrealist evaluate --resume {out}"
    flying = [(path, test) for path, test in tests if path not in invalid]
    bar = tqdm(total=len(flying) * options.runs, unit="run", desc="evaluate", dynamic_ncols=True, file=sys.stderr,
               disable=None)

    def progress(done: int, total: int) -> None:
        bar.n = done
        bar.refresh()

    try:
        try:
            ev = evaluate(flying, runs=options.runs, seed=options.random_seed, uav=uav, workers=options.workers,
                          progress=progress, store=store, executor=dask,
                          identity={"any_layout": options.any_layout, "competition": options.competition},
                          buffer=options.buffer)
        finally:
            bar.close()
        board = _board(options, ev, dict(tests), invalid) if options.competition else None
        try:
            paths = write_report(ev, out, board)
        except SurrealistError as err:
            raise SurrealistError(f"{err}; every run is stored in {store}: {resume} writes the report") from None
    except KeyboardInterrupt:
        print(f"interrupted: the runs flown are stored in {store}; {resume} flies the rest and writes the report",
              file=sys.stderr)
        return 130
    print(summary_text(ev))
    if board:
        print(f"scored as the {options.competition} edition:")
        print("\n".join(scoring_lines(board)))
    print(f"report: {paths['report']}; per test: {paths['evaluation']}; per run: {paths['runs']}"
          + (f"; leaderboard: {paths['leaderboard']}" if board else ""))
    return 0


def _board(options: EvaluateOptions, ev, tests: dict, invalid: dict):
    """The folders' draws scored as the edition did and ranked per case study."""
    from ...competition.scoring import edition, score_draws

    return score_draws(edition(options.competition), options.draws, tests, {t.file: t.runs for t in ev.tests},
                       invalid)
