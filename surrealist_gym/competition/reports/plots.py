"""The figures of a re-evaluation report (:mod:`surrealist_gym.competition.reevaluation`): distances per test, a top
view per test, a map of the suite and, when folders are scored as the competition did, the leaderboard.

Top views follow the local frame (x north, y east): east (y) on the horizontal axis, north (x) up. matplotlib is
imported inside each function (the ``Figure`` API, no pyplot state).
"""
from __future__ import annotations

import inspect
import math
import os
from typing import Sequence

import numpy as np

from ...outcomes import UNSAFE_DISTANCE_M

__all__ = ["plot_distances", "plot_leaderboard", "plot_suite", "plot_suite_map", "plot_top_views"]

_PASS, _FAIL, _BOX = "tab:blue", "tab:red", "0.55"


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def _boxes(ax, obstacles, **style) -> None:
    """Draw the footprints of ``obstacles`` on a top view (y east horizontal, x north vertical)."""
    from matplotlib.patches import Polygon

    for o in obstacles:
        corners = np.array(o.footprint())
        ax.add_patch(Polygon(corners[:, ::-1], closed=True, **style))


def _top_axes(ax) -> None:
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, linewidth=0.3)


def plot_distances(ev, path) -> None:
    """Each run's competition distance, one row per test: a box of the quartiles, the runs as dots (red when they
    fail, a cross for a collision) and the 1.5 m line. Runs that ended in an error (not flown to an end) and
    infinite distances (no obstacles) are left out; a row's label counts the errors apart."""
    tests = ev.tests
    fig = _figure(9, 1.4 + 0.32 * len(tests))
    ax = fig.subplots()
    rng = np.random.default_rng(0)  # jitter only
    finite = [[r.distance for r in t.runs if r.flown and math.isfinite(r.distance)] for t in tests]
    rows = np.arange(len(tests))[::-1]  # the first test on top
    horizontal = {"orientation": "horizontal"} if "orientation" in inspect.signature(ax.boxplot).parameters else {
        "vert": False}  # matplotlib < 3.10 knows only vert, which 3.11 deprecates
    ax.boxplot([d if d else [math.nan] for d in finite], positions=rows, **horizontal, widths=0.6, showfliers=False,
               medianprops={"color": "0.2"}, boxprops={"color": "0.6"}, whiskerprops={"color": "0.6"},
               capprops={"color": "0.6"})
    dots = [(r.distance, row + rng.uniform(-0.18, 0.18), r.failed, r.status == "collision")
            for row, t in zip(rows, tests) for r in t.runs if r.flown and math.isfinite(r.distance)]
    for failed, crash in ((False, False), (True, False), (True, True), (False, True)):
        xy = np.array([(x, y) for x, y, f, c in dots if f == failed and c == crash]).reshape(-1, 2)
        ax.scatter(xy[:, 0], xy[:, 1], s=28 if crash else 14, zorder=3, marker="x" if crash else "o",
                   color=_FAIL if failed else _PASS)
    ax.axvline(UNSAFE_DISTANCE_M, color="darkred", linestyle="--", linewidth=1, label=f"{UNSAFE_DISTANCE_M:g} m")
    ax.set_yticks(rows, [f"{t.name}  ({t.failures}/{t.flown}" + (f", {t.errors} error)" if t.errors else ")")
                         for t in tests], fontsize="small")
    ax.set_ylim(-0.7, len(tests) - 0.3)
    ax.set_xlim(left=0)
    ax.set_xlabel("competition distance [m] (2-D, footprint to the flight polyline)")
    ax.set_title(f"closest approach per run ({ev.runs} runs per test; red: failing, x: collision)")
    ax.grid(True, axis="x", linewidth=0.3)
    ax.legend(loc="lower right", fontsize="small")
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=100)


def plot_top_views(ev, path, columns: int = 4) -> None:
    """One top view per test: the boxes' footprints and every run's x-y flight (red: failing runs; grey dashed:
    runs that ended in an error)."""
    tests = ev.tests
    cols = max(1, min(columns, len(tests)))
    rows = math.ceil(len(tests) / cols)
    fig = _figure(3.6 * cols, 3.4 * rows)
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, t in zip(axes, tests):
        _boxes(ax, t.test.obstacles, facecolor="0.8", edgecolor=_BOX)
        for r in sorted(t.runs, key=lambda r: r.failed):  # failing flights on top
            if len(r.trajectory):
                ax.plot(r.trajectory.y, r.trajectory.x, color=_FAIL if r.failed else _PASS if r.flown
                        else "0.5", linestyle="-" if r.flown else "--", linewidth=0.8, alpha=0.8)
        _top_axes(ax)
        closest = "-" if math.isnan(t.min_distance) else f"{t.min_distance:.2f} m"
        ax.set_title(f"{t.name}\np {t.p:.2f}, closest {closest}", fontsize="small")
        ax.tick_params(labelsize="x-small")
    for ax in axes[len(tests):]:
        ax.axis("off")
    fig.supxlabel("y east [m]")
    fig.supylabel("x north [m]")
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.6 / fig.get_figheight(), top=1 - 0.5 / fig.get_figheight(),
                        wspace=0.25, hspace=0.45)  # tight_layout costs a draw per axes
    fig.savefig(os.fspath(path), dpi=80)


def plot_suite_map(ev, path) -> None:
    """All the tests' boxes on one top view (faint) and the closest failing flight of each failing test; the
    distinct failures the suite kept are drawn thick."""
    fig = _figure(10, 8)
    ax = fig.subplots()
    for t in ev.tests:
        _boxes(ax, t.test.obstacles, facecolor="0.5", edgecolor="none", alpha=0.08)
    kept = {m.evaluation for m in ev.suite.members}
    colours = _colours(len(ev.failing))
    for colour, (i, t) in zip(colours, [(i, t) for i, t in enumerate(ev.tests, start=1) if t.failures]):
        run = t.closest_failure
        if run is None or not len(run.trajectory):
            continue
        if i in kept:
            _boxes(ax, t.test.obstacles, facecolor="none", edgecolor=colour, linewidth=1)
        ax.plot(run.trajectory.y, run.trajectory.x, color=colour, linewidth=2.2 if i in kept else 0.9,
                alpha=0.9, label=f"{t.name} ({run.distance:.2f} m" + (", kept)" if i in kept else ")"))
    if not ev.failing:
        ax.text(0.5, 0.5, "no failing test", transform=ax.transAxes, ha="center", color="0.4")
    _top_axes(ax)
    ax.set_xlabel("y east [m]")
    ax.set_ylabel("x north [m]")
    ax.set_title(f"suite map: {len(ev.tests)} layouts, {len(ev.failing)} failing tests, {len(ev.suite)} distinct "
                 f"failures (thick, with their boxes outlined)")
    if ev.failing:
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="x-small", title="closest failing run")
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=100)


def _colours(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab20" if n > 10 else "tab10"]
    return [cmap(i % cmap.N) for i in range(n)]


def plot_leaderboard(board, path) -> None:
    """The folders scored as an edition did (:func:`~surrealist_gym.competition.scoring.standings`), one row per case
    study: a bar per folder of its score (2024: the suite score; 2025: the failure score, and its diversity beside),
    labelled with its rank."""
    studies = list(dict.fromkeys(row.suite.case_study for row in board))
    from ..scoring import EDITIONS

    year = board[0].suite.edition
    by_r = EDITIONS[year].ranks_diversity
    panels = [("failure", "failure score (sum of test scores)"), ("diversity", "diversity (1 - mean area IoU)")] \
        if by_r else [("score", "suite score ((sum test_score + rest) x sim_pen)" if EDITIONS[year].rest
                       else "suite score (sum test_score x sim_pen)")]
    most = max(sum(row.suite.case_study == study for row in board) for study in studies)
    fig = _figure(5.2 * len(panels), 0.9 + len(studies) * (0.9 + 0.35 * most))
    axes = np.atleast_2d(fig.subplots(len(studies), len(panels), squeeze=False))
    for ax_row, study in zip(axes, studies):
        rows = [row for row in board if row.suite.case_study == study]
        colours = _colours(len(rows))
        ys = np.arange(len(rows))[::-1]  # the best on top
        for ax, (field, label) in zip(ax_row, panels):
            values = [getattr(row.suite, field) for row in rows]
            ax.barh(ys, [0 if math.isnan(v) else v for v in values], color=colours, height=0.6)
            for y, v, row in zip(ys, values, rows):
                rank = f"R_D {row.r_d}" if field == "diversity" else (
                    f"R_F {row.r_f}, R {row.r:g}, rank {row.rank}" if by_r else f"rank {row.rank}")
                ax.text(0 if math.isnan(v) else v, y, f"  {'-' if math.isnan(v) else f'{v:.2f}'}  ({rank})",
                        va="center", fontsize="small")
            ax.set_yticks(ys, [row.suite.name for row in rows], fontsize="small")
            ax.set_xlim(0, max([1e-9, *(v for v in values if not math.isnan(v))]) * 1.6
                        if field != "diversity" else 1.45)
            ax.set_title(f"{study}: {label}", fontsize="small")
            ax.grid(True, axis="x", linewidth=0.3)
    fig.suptitle(f"scored as the {year} edition" + ("; R = 0.75 R_F + 0.25 R_D per case study" if by_r
                                                     else "; ranked by score per case study"), fontsize="medium")
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=100)


def plot_suite(suite, path, order: Sequence[int] | None = None, columns: int = 4) -> None:
    """A top view of each member of a :class:`~surrealist_gym.competition.suite.Suite`, in ``order`` (as
    :func:`~surrealist_gym.competition.suite_export.export_suite` names them): its boxes and the flight that came
    closest (x north up, y east right)."""
    from ..suite_export import member_name

    order = list(range(len(suite.members)) if order is None else order)
    n = max(1, len(order))
    cols = min(columns, n)
    fig = _figure(3.2 * cols, 3.4 * math.ceil(n / columns))
    for k, i in enumerate(order):
        member = suite.members[i]
        ax = fig.add_subplot(math.ceil(n / columns), cols, k + 1)
        _boxes(ax, member.test.obstacles, facecolor=_BOX, edgecolor="0.3")
        ax.plot(member.trajectory[:, 1], member.trajectory[:, 0], color=_FAIL, linewidth=1.2)
        ax.set_title(f"{member_name(k)}: {member.distance:.2f} m, {member.points} pt", fontsize=9)
        ax.set_xlabel("y east [m]", fontsize=8)
        ax.set_ylabel("x north [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        _top_axes(ax)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
