"""A leaderboard's report: ``leaderboard.csv`` (one row per cell), ``leaderboard.png`` and ``report.md``, with PX4's
published figures (:mod:`~surrealist_gym.competition.published`) beside ours where the tools and case studies are
the reports'.

- **Per case study** (and wind, 2026): each tool's mean score over the repetitions (2024: the suite score; later: the
  failure score, diversity and R), the tests that failed again of those evaluated, and its place by the mean.
- **Overall**: 2024 ranked tools by the sum of their suite scores over the case studies, 2025 by the sum of their R.
- **Against PX4, 2024**: our mission2 and mission3 against the report's CS2 and CS3 (derived from them): per cell the
  tests reported and the suite score, their Spearman correlation over the cells, and on each case study whether our
  order of the tools is the report's and whether the report's best ranks first.
- **Against PX4, 2025**: the case studies are not public, so only the re-runs compare: the share of each tool's
  evaluated tests that failed again, ours against the report's (pooled over case studies).
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Sequence

import numpy as np

from ..leaderboard import Board, BoardRow
from ..published import CASE_STUDIES, PUBLISHED, published_name, rerun_share
from .tables import fixed, write_csv

__all__ = ["Summary", "agreement_2024", "summarise", "write_report"]


class Summary:
    """One tool on one case study (and wind) over the repetitions: mean score, diversity and R, and its re-runs."""

    __slots__ = ("tool", "case_study", "wind", "rows", "score", "diversity", "r", "failing", "evaluated", "reported")

    def __init__(self, tool: str, case_study: str, wind: str, rows: Sequence[BoardRow], ranks_diversity: bool):
        self.tool, self.case_study, self.wind, self.rows = tool, case_study, wind, tuple(rows)
        self.score = float(np.mean([r.failure_score if ranks_diversity else r.suite_score for r in rows]))
        diversities = [r.diversity for r in rows if not math.isnan(r.diversity)]
        self.diversity = float(np.mean(diversities)) if diversities else math.nan
        self.r = float(np.mean([r.r for r in rows]))
        self.failing = sum(r.failing_tests for r in rows)
        self.evaluated = sum(r.evaluated_tests for r in rows)
        self.reported = float(np.mean([r.reported_tests for r in rows]))

    @property
    def rerun(self) -> float:
        """The share of evaluated tests that failed again (nan without any)."""
        return self.failing / self.evaluated if self.evaluated else math.nan


def summarise(board: Board, rows: Sequence[BoardRow]) -> list[Summary]:
    """Each (case study, wind, tool) over the repetitions, case studies in the board's order, tools by place."""
    from ..leaderboard import case_label

    by_r = board.edition.ranks_diversity
    out = []
    for label in (case_label(c) for c in board.case_studies):
        for wind in board.variants:
            here = [Summary(t.name, label, wind, [r for r in rows if (r.tool, r.case_study, r.wind) ==
                                                  (t.name, label, wind)], by_r) for t in board.tools]
            out += sorted(here, key=lambda s: (s.r, -s.score) if by_r else (-s.score,))
    return out


def _places(group: Sequence[Summary], ranks_diversity: bool) -> list[int]:
    from ..scoring import ranks

    return list(ranks([s.score for s in group]) if not ranks_diversity else ranks([s.r for s in group],
                                                                              higher_is_better=False))


def agreement_2024(summaries: Sequence[Summary]) -> dict:
    """Our 2024 board against the report's Table 1 on the case studies derived from ours: the cells compared, the
    Spearman correlation of the suite scores (and of the tests reported), and per case study whether the order of the
    tools and the best tool agree."""
    from scipy.stats import spearmanr

    cells = []
    for s in summaries:
        cell = _published_cell("2024", s.tool, s.case_study)
        if cell is not None:
            cells.append((s, published_name(s.tool), CASE_STUDIES["2024"][s.case_study], cell))
    out: dict = {"cells": cells, "spearman": math.nan, "p": math.nan, "spearman_reported": math.nan, "studies": {}}
    if len(cells) >= 3:
        rho = spearmanr([s.score for s, *_ in cells], [c.score for *_, c in cells])
        out.update(spearman=float(rho.statistic), p=float(rho.pvalue))
        out["spearman_reported"] = float(spearmanr([s.reported for s, *_ in cells],
                                                   [c.reported for *_, c in cells]).statistic)
    for cs in dict.fromkeys(cs for _, _, cs, _ in cells):
        here = [(s, name, c) for s, name, case, c in cells if case == cs]
        ours = [name for s, name, _ in sorted(here, key=lambda x: -x[0].score)]
        theirs = [name for s, name, c in sorted(here, key=lambda x: -x[2].score)]
        best = max(s.score for s, _, _ in here)
        firsts = [name for s, name, _ in here if s.score == best]
        out["studies"][cs] = {"ours": ours, "report": theirs, "same_order": ours == theirs,
                              "report_best_first": theirs[0] in firsts and len(firsts) == 1}
    return out


def report_lines(board: Board, rows: Sequence[BoardRow]) -> list[str]:
    """The tables of ``report.md`` (the command prints them too)."""
    summaries = summarise(board, rows)
    lines = [f"## Per case study (mean over {board.repetitions} repetitions)", ""]
    head = ("| case study | " + ("wind | " if board.edition.wind else "") + "tool | place | "
            + ("suite score | " if not board.edition.ranks_diversity else "failure score | diversity | R | ")
            + "tests reported | failing of evaluated (re-run) |")
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for label in dict.fromkeys(s.case_study for s in summaries):
        for wind in board.variants:
            group = [s for s in summaries if (s.case_study, s.wind) == (label, wind)]
            for s, place in zip(group, _places(group, board.edition.ranks_diversity)):
                lines.append(f"| {label} | " + (f"{wind} | " if board.edition.wind else "") + f"{s.tool} | {place} | "
                             + (f"{fixed(s.score)} | " if not board.edition.ranks_diversity else
                                f"{fixed(s.score)} | {fixed(s.diversity)} | {fixed(s.r)} | ")
                             + f"{s.reported:.1f} | {s.failing}/{s.evaluated}"
                             + (f" ({100 * s.rerun:.0f}%) |" if s.evaluated else " |"))
    lines += ["", "## Overall", ""]
    for wind in board.variants:
        totals = {t.name: sum(s.score if not board.edition.ranks_diversity else s.r for s in summaries
                              if s.tool == t.name and s.wind == wind) for t in board.tools}
        order = sorted(totals, key=lambda t: -totals[t] if not board.edition.ranks_diversity else totals[t])
        what = "sum of mean suite scores" if not board.edition.ranks_diversity else "sum of mean R (lower is better)"
        lines.append((f"{wind} wind: " if wind else "") + f"{what}: "
                     + ", ".join(f"{i + 1}. {t} {totals[t]:.2f}" for i, t in enumerate(order)))
    lines += ["", *_px4_lines(board, summaries)]
    return lines


def _px4_lines(board: Board, summaries: Sequence[Summary]) -> list[str]:
    """PX4's published figures beside ours: the 2024 report's Table 1 for a 2024 board; else the 2025 reports'
    re-runs (2026 published none)."""
    if board.edition.name == "2024":
        agree = agreement_2024(summaries)
        if not agree["cells"]:
            return ["## Against PX4", "", "No tool and case study of the 2024 report's Table 1 is on this board "
                    "(its public case studies: mission2 -> CS2, mission3 -> CS3)."]
        lines = ["## Against PX4 (2024 report, Table 1)", "",
                 "| case study | tool | tests reported: ours (mean) | PX4 | suite score: ours (mean) | PX4 |",
                 "|---|---|---|---|---|---|"]
        lines += [f"| {s.case_study} ({cs}) | {name} | {s.reported:.1f} | {c.reported} | {fixed(s.score)} | "
                  f"{fixed(c.score)} |" for s, name, cs, c in agree["cells"]]
        lines += ["", f"Spearman over the {len(agree['cells'])} cells: suite scores {fixed(agree['spearman'])} "
                      f"(p {fixed(agree['p'], 3)}), tests reported {fixed(agree['spearman_reported'])}."]
        for cs, v in agree["studies"].items():
            lines.append(f"- {cs}: ours {' > '.join(v['ours'])}; PX4 {' > '.join(v['report'])}: "
                         f"{'the same order' if v['same_order'] else 'another order'}; the report's best "
                         f"{'ranks first alone' if v['report_best_first'] else 'does not rank first alone'}.")
        return lines
    table = PUBLISHED["2025"]
    lines = ["## Against PX4 (2025 reports): tests that failed again in the evaluation", "",
             "| tool | ours: failing of evaluated | share | PX4 (2025, pooled over CS2, CS4, CS5) |",
             "|---|---|---|---|"]
    for tool in board.tools:
        mine = [s for s in summaries if s.tool == tool.name and s.wind in ("", "without")]
        failing, evaluated = sum(s.failing for s in mine), sum(s.evaluated for s in mine)
        name = published_name(tool.name)
        px4 = (f"{fixed(100 * rerun_share(table[name]), 0)}% ({name})" if name in table else "-")
        share = f"{100 * failing / evaluated:.0f}%" if evaluated else "-"
        lines.append(f"| {tool.name} | {failing}/{evaluated} | {share} | {px4} |")
    return lines


def _published_cell(year: str, tool: str, case_study: str):
    """PX4's published cell of a tool on the report's case study derived from ours, or None."""
    name, cs = published_name(tool), CASE_STUDIES.get(year, {}).get(case_study)
    return PUBLISHED.get(year, {}).get(name, {}).get(cs) if name and cs else None


def plot_board(board: Board, rows: Sequence[BoardRow], path) -> None:
    """One panel per case study (and wind): each tool's score per repetition (dots) and mean (bar), and PX4's
    published score where the report has the cell (a black diamond)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    year = board.edition.name
    summaries = summarise(board, rows)
    panels = list(dict.fromkeys((s.case_study, s.wind) for s in summaries))
    fig = Figure(figsize=(4.2 * len(panels), 1.2 + 0.45 * len(board.tools)))
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, len(panels), squeeze=False)[0])
    for ax, (label, wind) in zip(axes, panels):
        group = [s for s in summaries if (s.case_study, s.wind) == (label, wind)]
        ys = np.arange(len(group))[::-1]
        ax.barh(ys, [s.score for s in group], color="0.8", height=0.6)
        for y, s, place in zip(ys, group, _places(group, board.edition.ranks_diversity)):
            values = [r.suite_score if not board.edition.ranks_diversity else r.failure_score for r in s.rows]
            ax.plot(values, [y] * len(values), "o", color="tab:red", markersize=4,
                    label="each repetition" if y == ys[0] else None)
            px4 = _published_cell(year, s.tool, label)
            if px4 is not None:
                ax.plot([px4.score], [y], "D", color="black", markersize=5, label="PX4 (published)")
            ax.text(max([s.score, *values, *([px4.score] if px4 else [])]), y, f"  #{place}", va="center",
                    fontsize="small")
        ax.set_yticks(ys, [s.tool for s in group], fontsize="small")
        ax.set_xlabel("suite score" if not board.edition.ranks_diversity else "failure score", fontsize="small")
        ax.set_title(label + (f", {wind} wind" if wind else ""), fontsize="small")
        ax.grid(True, axis="x", linewidth=0.3)
        handles, names = ax.get_legend_handles_labels()
        if "PX4 (published)" in names:
            ax.legend(dict(zip(names, handles)).values(), dict(zip(names, handles)).keys(), fontsize="x-small",
                      loc="lower right")
    fig.suptitle(f"leaderboard, {year} edition: bars the mean of {board.repetitions} repetitions, dots each one",
                 fontsize="medium")
    fig.tight_layout()
    fig.savefig(os.fspath(path), dpi=100)


def write_report(board: Board, rows: Sequence[BoardRow]) -> dict:
    """Write ``leaderboard.csv``, ``leaderboard.png`` and ``report.md`` into the board's folder; their paths, and the
    text of the tables (``text``)."""
    out = Path(board.out)
    paths = {"csv": out / "leaderboard.csv", "png": out / "leaderboard.png", "report": out / "report.md"}
    draft = paths["csv"].with_name(paths["csv"].name + ".tmp")
    write_csv(draft, [row.to_row(board.edition) for row in rows])
    os.replace(draft, paths["csv"])  # whole or not at all
    plot_board(board, rows, paths["png"])
    lines = report_lines(board, rows)
    head = [f"# Leaderboard, {board.edition.name} edition, on our simulator ({board.uav})", "",
            f"Tools: {', '.join(f'{t.name} ({t.folder})' for t in board.tools)}. Case studies: "
            f"{', '.join(board.case_studies)}. Budget {board.budget} per tool and case study; {board.runs} runs of "
            f"up to {board.edition.tests} tests evaluated; {board.repetitions} repetitions (repetition k: seed "
            f"{board.seed} + k). One row per cell: leaderboard.csv.", ""]
    paths["report"].write_text("\n".join(head + lines) + "\n", encoding="utf-8")
    paths["text"] = "\n".join(lines)
    return paths
