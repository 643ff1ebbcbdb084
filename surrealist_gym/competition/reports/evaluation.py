"""The report of a re-evaluation (:mod:`surrealist_gym.competition.reevaluation`): ``evaluation.csv``, ``runs.csv``, the
figures (:mod:`surrealist_gym.competition.reports.plots`) and ``report.md``, with the competition's scoring
(``leaderboard.csv``, ``test-scores.csv``, ``leaderboard.png``) when given a board. Every name here is importable from
:mod:`surrealist_gym.competition.reevaluation` too.
"""
from __future__ import annotations

import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from ...errors import SurrealistError
from ...outcomes import UNSAFE_DISTANCE_M
from .tables import fixed, rounded, write_csv

if TYPE_CHECKING:
    from ..reevaluation import Evaluation, TestStats

__all__ = ["REPORT_FILES", "SCORING_FILES", "report_text", "scoring_lines", "suite_lines", "write_report"]

def _p_text(t: TestStats) -> str:
    """``0.40 [0.05, 0.85]``: p and its interval; ``- (no run flown)`` when every run ended in error."""
    return f"{t.p:.2f} [{t.ci_low:.2f}, {t.ci_high:.2f}]" if t.flown else "- (no run flown)"


def suite_lines(ev: Evaluation) -> list[str]:
    """The suite's figures, one per line (the CLI's summary and the report share them)."""
    d = ev.diversity
    failing_runs, errors = sum(t.failures for t in ev.tests), sum(t.errors for t in ev.tests)
    unflown = [t.name for t in ev.tests if not t.flown]
    lines = [f"tests failing at least once: {len(ev.failing)} of {len(ev.tests)}; failing runs: {failing_runs} of "
             f"{sum(t.flown for t in ev.tests)} flown",
             f"points: {sum(t.points_mean for t in ev.tests if t.flown):.1f} expected per round of the suite (sum of "
             f"the mean points per run), {sum(t.points_median_run for t in ev.tests if t.flown)} for the median runs"]
    if errors:
        lines.append(f"runs that ended in error (neither passing nor failing, left out of p and points): {errors} of "
                     f"{len(ev.tests) * ev.runs}" + (f"; tests with no run flown (p unknown): {', '.join(unflown)}"
                                                     if unflown else ""))
    return lines + [
        f"distinct failures: {len(ev.suite)} of {len(ev.failing)} failing tests (alike: flights < "
        f"{ev.suite.min_flight_m:g} m apart and the boxes they failed at < {ev.suite.min_layout_m:g} m apart)",
        f"diversity of the failing tests' closest runs: flight mean {fixed(d['flight_mean_m'])} m (min "
        f"{fixed(d['flight_min_m'])} m), layout mean {fixed(d['layout_mean_m'])} m (min {fixed(d['layout_min_m'])} m)"
        if d["members"] > 1 else "diversity: needs two failing tests"]


REPORT_FILES = {"evaluation": "evaluation.csv", "runs": "runs.csv", "distances": "distances.png",
                "top_views": "top-views.png", "suite_map": "suite-map.png", "report": "report.md"}
SCORING_FILES = {"leaderboard": "leaderboard.csv", "test_scores": "test-scores.csv",
                 "leaderboard_plot": "leaderboard.png"}  # with the competition's scoring (--competition)


def write_report(ev: Evaluation, out, board: Sequence | None = None) -> dict[str, Path]:
    """Write ``evaluation.csv`` (one row per test), ``runs.csv`` (one row per run), the figures
    (:mod:`surrealist_gym.competition.reports.plots`) and ``report.md`` to the folder ``out``; returns their paths. With
    ``board`` (:func:`~surrealist_gym.competition.scoring.standings` of the folders scored as an edition did) also
    ``leaderboard.csv``, ``test-scores.csv`` and ``leaderboard.png``, and the report has a section on them.

    Whole or not at all: the files are written to a temporary folder inside ``out`` and then moved into place
    (``report.md`` last); if that fails (a full disk), the temporary folder and any report file moved are removed and
    a one-line SurrealistError says why."""
    from .plots import plot_distances, plot_leaderboard, plot_suite_map, plot_top_views

    out = Path(out)
    files = {**(SCORING_FILES if board else {}), **REPORT_FILES}  # report.md last
    paths = {key: out / name for key, name in files.items()}
    tmp, moving = None, False
    try:
        out.mkdir(parents=True, exist_ok=True)
        for stale in out.glob(".report-*"):  # left by a process killed while writing
            shutil.rmtree(stale, ignore_errors=True)
        tmp = Path(tempfile.mkdtemp(prefix=".report-", dir=out))
        draft = {key: tmp / name for key, name in files.items()}
        write_csv(draft["evaluation"], [t.to_row() for t in ev.tests])
        write_csv(draft["runs"], [{"file": t.file, "run": r.index, "status": r.status, "distance": rounded(r.distance),
                                    "failed": int(r.failed) if r.flown else "", "points": r.points if r.flown else "",
                                    "duration_s": rounded(r.duration, 2), "message": r.message}
                                   for t in ev.tests for r in t.runs])
        plot_distances(ev, draft["distances"])
        plot_top_views(ev, draft["top_views"])
        plot_suite_map(ev, draft["suite_map"])
        if board:
            write_csv(draft["leaderboard"], [_leaderboard_row(row) for row in board])
            write_csv(draft["test_scores"], [_test_score_row(row.suite, i, t) for row in board
                                              for i, t in enumerate(row.suite.drawn)])
            plot_leaderboard(board, draft["leaderboard_plot"])
        draft["report"].write_text(report_text(ev, board), encoding="utf-8")
        moving = True
        for key in files:
            os.replace(draft[key], paths[key])
    except BaseException as err:
        if moving:  # some files of this report may have replaced those of an earlier one: no half report
            for path in paths.values():
                path.unlink(missing_ok=True)
        if isinstance(err, OSError):
            raise SurrealistError(f"{out}: cannot write the report ({err.strerror or err})") from None
        raise
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    return paths


def _leaderboard_row(row) -> dict:
    """The row of ``leaderboard.csv``."""
    s = row.suite
    return {"case_study": s.case_study, "folder": s.folder, "edition": s.edition, "tests": s.tests,
            "drawn": len(s.drawn), "failing": s.failing, "alike": s.alike, "failure": rounded(s.failure, 6),
            "rest": rounded(s.rest, 6), "sim_pen": rounded(s.sim_pen, 6), "score": rounded(s.score, 6),
            "diversity": rounded(s.diversity, 6), "r_f": row.r_f, "r_d": "" if row.r_d is None else row.r_d,
            "r": rounded(row.r), "rank": row.rank}


def _test_score_row(s, i: int, t) -> dict:
    """The row of ``test-scores.csv``: one drawn test of a folder."""
    return {"case_study": s.case_study, "folder": s.folder, "position": i, "file": t.file, "obstacles": t.obstacles,
            "runs_scored": len(t.points), "points_mean": rounded(float(np.mean(t.points)) if t.points else math.nan, 6),
            "minutes_mean": rounded(float(np.mean(t.durations_s)) / 60 if t.durations_s else math.nan, 6),
            "test_score": rounded(t.score, 6), "counted": int(t.counted),
            "same_as": "" if t.same_as is None else t.same_as, "invalid": t.invalid}


def scoring_lines(board: Sequence) -> list[str]:
    """The folders' scores and ranks, one line per folder (the CLI's summary and the report share them), and a line
    for each folder with fewer tests than the edition draws."""
    from ..scoring import EDITIONS

    if not board:
        return []
    ed = EDITIONS[board[0].suite.edition]
    lines = []
    for row in board:
        s = row.suite
        head = (f"{s.case_study}: {s.name}: {len(s.drawn)} of {s.tests} tests drawn, {s.failing} failing; ")
        if not ed.ranks_diversity:
            summed = f"({s.failure:.2f} + rest {s.rest:.2f})" if ed.rest else f"{s.failure:.2f}"
            lines.append(head + f"score {s.score:.2f} = {summed} x sim_pen {s.sim_pen:.2f} ({s.alike} flying "
                                f"alike); rank {row.rank}")
        else:
            lines.append(head + f"failure {s.failure:.2f}, diversity {fixed(s.diversity)}"
                                + (f" ({s.alike} duplicates counted once)" if s.alike else "")
                                + f"; R_F {row.r_f}, R_D {row.r_d}, R {row.r:g}, rank {row.rank}")
    for row in board:
        if row.suite.tests < ed.tests:
            lines.append(f"{row.suite.name}: {row.suite.tests} tests, fewer than the {ed.tests} the {ed.name} edition "
                         f"evaluates: all {row.suite.tests} scored")
    invalid = sum(bool(t.invalid) for row in board for t in row.suite.drawn)
    if invalid:
        lines.append(f"{invalid} drawn tests break the competition's rules: not flown, they score 0 "
                     f"(test-scores.csv names the rule)")
    return lines


def report_text(ev: Evaluation, board: Sequence | None = None) -> str:
    """The Markdown report (the figures are read from beside it); with ``board``, the competition's scoring first."""
    uav = ev.uav or ", ".join(sorted({t.uav for t in ev.tests})) + " (each test's default)"
    stored = f" ({ev.stored} runs flown before, read back from the store)" if ev.stored else ""
    lines = [f"# Re-evaluation of {len(ev.tests)} tests", "",
             f"{ev.runs} runs per test, base seed {ev.seed}, UAV profile {uav}; flown on {ev.workers} worker(s) in "
             f"{ev.wall_s:.1f} s{stored}.", "",
             f"A run **fails** when it collides or its competition distance (box footprint to the 0.5 s flight "
             f"polyline, 2-D) is below {UNSAFE_DISTANCE_M:g} m. Points as the competition scores a run: 5 below "
             f"0.25 m (and for a collision), 2 below 1 m, 1 below 1.5 m.", ""]
    lines += _scoring_section(board, ev.runs) if board else []
    lines += ["## Suite", ""]
    lines += [f"- {line}" for line in suite_lines(ev)]
    lines += ["", "## Tests", "",
              "p is the failure probability (failing runs / runs flown) with its 95% Clopper-Pearson interval; "
              "a run that ended in error (errors) was not flown to an end and is neither a pass nor a failure; "
              "points per run is the mean over the runs flown, median run the points of the run in the middle when "
              "ordered by distance; suite says what the archive of distinct failures did with the test's closest "
              "failing run (added, alike N: the same failure as member N, replaced N).", "",
              "| test | failures | errors | p [95% CI] | points per run | median run | min distance [m] | "
              "median distance [m] | statuses | suite |", "|---|---|---|---|---|---|---|---|---|---|"]
    for t in ev.tests:
        lines.append(f"| {t.name} | {t.failures}/{t.flown} | {t.errors} | {_p_text(t)} | {fixed(t.points_mean, 1)} | "
                     f"{fixed(t.points_median_run, 0)} | {fixed(t.min_distance)} | {fixed(t.median_distance)} | "
                     f"{t.statuses} | {t.suite or '-'} |")
    lines += ["", "## Figures", "",
              "**Closest approach per run** (`distances.png`): one row per test, each dot a run's competition "
              "distance (red: failing, a cross: a collision), a box of the runs' quartiles behind; the dashed line "
              "is the 1.5 m threshold. A test whose dots straddle the line fails by chance.", "",
              "![distances](distances.png)", "",
              "**Top view per test** (`top-views.png`): the boxes' footprints (grey) and every run's flight, east "
              "to the right and north up (red: failing runs).", "", "![top views](top-views.png)", "",
              "**Map of the suite** (`suite-map.png`): all the tests' boxes on one top view (faint) and the closest "
              "failing flight of each failing test (thick: a distinct failure the suite kept). Flights that lie on "
              "each other near the same boxes are the same failure.", "", "![suite map](suite-map.png)", "",
              "Per test: `evaluation.csv`; per run: `runs.csv`.", ""]
    return "\n".join(lines)


def _scoring_section(board: Sequence, runs: int) -> list[str]:
    """The report's section on the competition's scoring: what the edition draws and computes, and the table."""
    from ..scoring import EDITIONS

    ed = EDITIONS[board[0].suite.edition]
    flown = f"each flown {runs} time{'s' if runs != 1 else ''} (the edition: {ed.runs})"
    score = ("test_score = avg_point x 10 / (n_obstacles^2 x avg_time), avg_time the mean flight time in minutes "
             "(simulated, from arming to the end of the run).")
    if not ed.ranks_diversity:
        drawn = (f"{ed.tests} tests drawn at random from each folder (seeded by the base seed)" if ed.draw == "random"
                 else f"the first {ed.tests} tests of each folder that keep the rules, in the tool's rank order (the "
                      f"order it wrote them)")
        rest = (f" A folder of more than {ed.tests} tests earns half the mean test score for each test beyond them "
                f"(rest)." if ed.rest else "")
        how = [f"Scored as the {ed.name} edition did: {drawn}, {flown}. {score}{rest} Two drawn tests are similar "
               f"when the DBA averages of their runs are less than {ed.similar_m:g} m apart on average along DTW's "
               f"path (x-y); sim_pen = 1 - similar / evaluated, each test similar to an earlier one counted once. "
               f"score = {'(sum test_score + rest)' if ed.rest else 'sum test_score'} x sim_pen; rank by score per "
               f"case study (1 the best, equal scores share a rank)."]
        table = _board_table(board, ["sum test_score", *(["rest"] if ed.rest else []), "alike", "sim_pen", "score",
                                     "rank"],
                             lambda r: [f"{r.suite.failure:.2f}", *([f"{r.suite.rest:.2f}"] if ed.rest else []),
                                        f"{r.suite.alike}", f"{r.suite.sim_pen:.2f}", f"{r.suite.score:.2f}",
                                        f"{r.rank}"])
    else:
        how = [f"Scored as the 2025 editions (ICST, SBFT) did: the first {ed.tests} tests of each folder in the "
               f"order the tool wrote them (the natural order of their names, digits as numbers; by modification "
               f"time when a name holds no number), {flown}. {score} Tests "
               f"whose boxes cover the same ground (area similarity 1) are duplicates, counted once. failure = sum "
               f"test_score; diversity = 1 - mean pairwise area similarity (intersection over union of the boxes' "
               f"footprints). Per case study R_F ranks the failure score, R_D the diversity (1 the best, equal "
               f"values share a rank), R = 0.75 R_F + 0.25 R_D, and rank orders R."]
        table = _board_table(board, ["duplicates", "failure", "diversity", "R_F", "R_D", "R", "rank"],
                             lambda r: [f"{r.suite.alike}", f"{r.suite.failure:.2f}", fixed(r.suite.diversity),
                                        f"{r.r_f}", f"{r.r_d}", f"{r.r:g}", f"{r.rank}"])
    return (["## Competition scoring", ""] + how + [""] + table + [""]
            + [f"- {line}" for line in scoring_lines(board)[len(board):]]
            + ["", "Per folder: `leaderboard.csv`; per drawn test (points, minutes, test score, duplicate or alike "
               "of which earlier test, the rule it breaks): `test-scores.csv`.", "",
               "![leaderboard](leaderboard.png)", ""])


def _board_table(board: Sequence, columns: list[str], cells: Callable) -> list[str]:
    """The leaderboard as a Markdown table: case study, folder, tests, drawn, failing, then ``columns``, whose cells
    ``cells(row)`` gives."""
    head = ["case study", "folder", "tests", "drawn", "failing", *columns]
    return (["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
            + ["| " + " | ".join([f"{r.suite.case_study}", f"{r.suite.name}", f"{r.suite.tests}",
                                  f"{len(r.suite.drawn)}", f"{r.suite.failing}", *cells(r)]) + " |" for r in board])
