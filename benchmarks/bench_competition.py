"""A leaderboard on one bench: five test generators on the competition's case studies, each run through ``surrealist
compete`` and scored by ``surrealist evaluate --competition 2025``.

The tools:

- ``surrealist``: our generator (``surrealist export-tool``, agent ``suite``);
- ``surrealist-cmaes``, ``surrealist-random``: the same tool with CMA-ES and the random agent as its search;
- ``reference``: the competition's 2025 reference generator (``uav-testing-competition/snippets``, random boxes);
- ``ambiegen``: AmbieGen, a 2024 participant (``peers/ambiegen/snippets``).

Each cell (tool, case study, repetition) runs ``surrealist compete TOOL CASE_STUDY BUDGET --random-seed REP``: the
tool's own ``cli.py``, unedited, every simulation it asks for flown on our simulator (PX4 v1.12 SITL Iris), at most
BUDGET.
Our three tools search in our simulator first (``--sim-budget-factor`` x BUDGET single-run evaluations, seed REP),
then spend the budget; those searches are extra flights of the very simulator that judges them, which a real
submission does not get (there PX4 SITL judges), so this bench measures the tools' searches, not our simulator's
fidelity. The reference and AmbieGen draw from their own unseeded random generators.

Then, per case study and repetition, the five output folders are scored together as the 2025 edition did
(``evaluate --competition 2025 --random-seed REP``: the first 20 tests of each, 3 runs each, test scores, duplicates,
area-IoU diversity, R_F, R_D, R = 0.75 R_F + 0.25 R_D). A tool whose cell wrote no test scores 0 with no diversity
and shares the last ranks. The table gives, per case study and tool, the mean R and its values, the failure score and
diversity, and, for our generator against each other tool, the p-value (search.statistics.compare: ANOVA or
Mann-Whitney) and Vargha-Delaney A12 (probability that ours is better: a lower R, a higher failure score) over the
repetitions.

Every cell and every scoring is kept in ``--out`` as it completes; a rerun skips what is done and redoes what was
interrupted (an interrupted cell's folder is kept beside, renamed ``*.interrupted-K``).

Usage::

    python benchmarks/bench_competition.py                  # 5 tools x 3 case studies x 3 reps, budget 100
    python benchmarks/bench_competition.py --missions mission2 --repetitions 1 --budget 10 --out results/bench-smoke
    python benchmarks/bench_competition.py --summary-only   # the table of what --out holds
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from surrealist_gym.competition.leaderboard import set_aside

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
AERIALIST = f"{THIRD_PARTY / 'aerialist-master'}:{THIRD_PARTY / 'aerialist-0.2.1'}"
PEERS = {"reference": THIRD_PARTY / "uav-testing-competition" / "snippets",
         "ambiegen": THIRD_PARTY / "peers" / "ambiegen" / "snippets"}
OURS = {"surrealist": "suite", "surrealist-cmaes": "cmaes", "surrealist-random": "random"}
TOOLS = tuple(OURS) + tuple(PEERS)
OUR_GENERATOR = "surrealist"


@dataclass(frozen=True)
class Cell:
    tool: str
    mission: str
    rep: int

    @property
    def name(self) -> str:
        return f"{self.tool}/{self.mission}-rep{self.rep}"


def surrealist(*args: str, log: Path) -> int:
    """Run ``surrealist ARGS`` in this interpreter, its output to ``log``; the exit code."""
    env = {**os.environ, "SURREALIST_AERIALIST": os.environ.get("SURREALIST_AERIALIST", AERIALIST)}
    with open(log, "w", encoding="utf-8") as f:
        return subprocess.call([sys.executable, "-m", "surrealist_gym.cli", *args], stdout=f, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL, env=env)


def tool_folder(cell: Cell, out: Path, args) -> Path:
    """The tool's folder: a peer's own; ours written once per agent and repetition (its seed) by export-tool."""
    if cell.tool in PEERS:
        return PEERS[cell.tool]
    folder = out / "tools" / f"{cell.tool}-seed{cell.rep}"
    if not (folder / "surrealist-tool.json").is_file():
        if folder.exists():
            set_aside(folder)
        folder.parent.mkdir(parents=True, exist_ok=True)
        code = surrealist("export-tool", str(folder), "--agent", OURS[cell.tool], "--random-seed", str(cell.rep),
                          "--sim-budget-factor", str(args.sim_budget_factor), "--confirm", str(args.confirm),
                          log=out / "tools" / f"{cell.tool}-seed{cell.rep}.log")
        if code != 0:
            raise RuntimeError(f"export-tool for {cell.name} exited {code}: {out / 'tools'}")
    return folder


def run_cell(cell: Cell, out: Path, args) -> dict:
    """Run one cell through compete (unless done); its summary."""
    folder = out / "cells" / cell.name
    summary = folder / "summary.json"
    if not summary.is_file():
        if folder.exists():
            set_aside(folder)
        folder.parent.mkdir(parents=True, exist_ok=True)
        tool = tool_folder(cell, out, args)
        surrealist("compete", str(tool), cell.mission, str(args.budget), "--out", str(folder), "--random-seed",
                   str(cell.rep), log=folder.with_name(folder.name + ".log"))
        if not summary.is_file():
            raise RuntimeError(f"{cell.name}: compete wrote no summary ({folder.with_name(folder.name + '.log')})")
    return json.loads(summary.read_text(encoding="utf-8"))


def tests_folder(values: dict) -> Path | None:
    """The tool's output folder if it holds a test YAML."""
    folder = values.get("output_folder")
    return Path(folder) if folder and any(Path(folder).glob("*.yaml")) else None


def score(mission: str, rep: int, folders: dict[str, Path], out: Path, args) -> Path:
    """Score a case study's folders of one repetition together (unless done); the leaderboard's path."""
    folder = out / "scores" / f"{mission}-rep{rep}"
    board = folder / "leaderboard.csv"
    if not board.is_file():
        folder.parent.mkdir(parents=True, exist_ok=True)
        log = folder.with_name(folder.name + ".log")
        if (folder / "run.json").is_file():
            code = surrealist("evaluate", "--resume", str(folder), "--workers", "1", log=log)
        else:
            if folder.exists():
                set_aside(folder)
            code = surrealist("evaluate", *map(str, folders.values()), "--competition", "2025", "--random-seed",
                              str(rep), "--workers", "1", "--out", str(folder), log=log)
        if code != 0 or not board.is_file():
            raise RuntimeError(f"scoring {mission} rep {rep} exited {code} ({log})")
    return board


def standings(board: Path, folders: dict[str, Path], summaries: dict[str, dict]) -> list[dict]:
    """Every tool's row of one case study and repetition: the leaderboard's, and score 0 / no diversity for a tool
    that wrote no test; R re-ranked over all five (competition.scoring.ranks, as the leaderboard ranks)."""
    from surrealist_gym.competition.scoring import ranks

    with open(board, newline="", encoding="utf-8") as f:
        by_folder = {row["folder"]: row for row in csv.DictReader(f)}
    rows = []
    for tool, values in summaries.items():
        row = by_folder.get(str(folders[tool].absolute())) if tool in folders else None
        rows.append({"tool": tool, "tests": int(row["tests"]) if row else 0,
                     "failing": int(row["failing"]) if row else 0,
                     "failure": float(row["failure"]) if row else 0.0,
                     "diversity": float(row["diversity"]) if row and row["diversity"] not in ("", "nan") else math.nan,
                     "simulations": values.get("simulations"), "problem": values.get("problem") or ""})
    r_f = ranks([r["failure"] for r in rows])
    r_d = ranks([r["diversity"] for r in rows])
    for row, f, d in zip(rows, r_f, r_d):
        row.update(r_f=f, r_d=d, r=0.75 * f + 0.25 * d)
    return rows


def summarise(records: list[dict], missions, tools) -> str:
    """The leaderboard table (markdown) over the repetitions."""
    import numpy as np

    from search.statistics import compare, vargha_delaney_a12

    def stat(ours, theirs, sign):
        if len(ours) < 3 or len(theirs) < 3:
            return "-", "-"
        if np.ptp(ours) == 0 and np.ptp(theirs) == 0:
            p = "1" if ours[0] == theirs[0] else "-"
        else:
            p = f"{compare(ours, theirs)[0]:.3f}"
        return p, f"{vargha_delaney_a12([sign * x for x in ours], [sign * x for x in theirs]):.2f}"

    lines = ["| case study | tool | reps | R (mean) | R per rep | failure score (mean) | diversity (mean) | "
             "failing tests of 20 | place | p (R) vs ours | A12 ours better (R) | p (failure) | A12 (failure) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for mission in missions:
        here = [r for r in records if r["mission"] == mission]
        mean_r = {t: np.mean([r["r"] for r in here if r["tool"] == t]) for t in tools
                  if any(r["tool"] == t for r in here)}
        place = {t: 1 + sum(other < m for other in mean_r.values()) for t, m in mean_r.items()}
        ours = [r for r in here if r["tool"] == OUR_GENERATOR]
        for tool in sorted(mean_r, key=lambda t: (mean_r[t], tools.index(t))):
            rows = sorted((r for r in here if r["tool"] == tool), key=lambda r: r["rep"])
            p_r, a_r = stat([r["r"] for r in ours], [r["r"] for r in rows], -1) if tool != OUR_GENERATOR else ("", "")
            p_f, a_f = (stat([r["failure"] for r in ours], [r["failure"] for r in rows], 1)
                        if tool != OUR_GENERATOR else ("", ""))
            div = [r["diversity"] for r in rows if not math.isnan(r["diversity"])]
            lines.append(f"| {mission} | {tool} | {len(rows)} | {mean_r[tool]:.2f} | "
                         f"{', '.join(format(r['r'], 'g') for r in rows)} | "
                         f"{np.mean([r['failure'] for r in rows]):.2f} | "
                         f"{np.mean(div) if div else math.nan:.2f} | "
                         f"{', '.join(str(r['failing']) for r in rows)} | {place[tool]} | {p_r} | {a_r} | {p_f} | "
                         f"{a_f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--missions", nargs="+", default=["mission1", "mission2", "mission3"])
    parser.add_argument("--tools", nargs="+", default=list(TOOLS), choices=TOOLS)
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--budget", type=int, default=100, help="simulations per tool and case study (default 100)")
    parser.add_argument("--sim-budget-factor", type=int, default=2,
                        help="our tools' search in the simulator: this x BUDGET evaluations (default 2)")
    parser.add_argument("--confirm", type=int, default=3, help="our tools' re-runs of each failure (default 3)")
    parser.add_argument("--jobs", type=int, default=2, help="cells run at once, one core each (default 2)")
    parser.add_argument("--out", default="results/bench-competition")
    parser.add_argument("--summary-only", action="store_true", help="the table of the scorings finished in --out")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    records_file = out / "records.json"
    cells = [Cell(t, m, r) for r in range(args.repetitions) for m in args.missions for t in args.tools]
    if not args.summary_only:
        start = time.perf_counter()
        summaries: dict[Cell, dict] = {}
        with ThreadPoolExecutor(args.jobs) as pool:
            futures = {pool.submit(run_cell, c, out, args): c for c in cells}
            for future in as_completed(futures):
                cell = futures[future]
                values = summaries[cell] = future.result()
                written = len(values.get("tests") or [])
                failing = sum(1 for t in values.get("tests") or [] if t.get("points"))
                print(f"[{len(summaries)}/{len(cells)} {time.perf_counter() - start:.0f} s] {cell.name}: "
                      f"{written} tests, {failing} failing, {values.get('simulations')} simulations, "
                      f"{values.get('wall_s', 0):.0f} s{'; ' + values['problem'] if values.get('problem') else ''}",
                      flush=True)
        groups = [(m, r) for r in range(args.repetitions) for m in args.missions]
        folders = {(m, r): {c.tool: f for c in cells if (c.mission, c.rep) == (m, r)
                            for f in [tests_folder(summaries[c])] if f} for m, r in groups}
        records = []
        with ThreadPoolExecutor(args.jobs) as pool:
            futures = {pool.submit(score, m, r, folders[m, r], out, args): (m, r) for m, r in groups}
            for future in as_completed(futures):
                m, r = futures[future]
                tools = {c.tool: summaries[c] for c in cells if (c.mission, c.rep) == (m, r)}
                rows = standings(future.result(), folders[m, r], tools)
                records += [{"mission": m, "rep": r, **row} for row in rows]
                print(f"scored {m} rep {r}: " + ", ".join(f"{row['tool']} R {row['r']:g}" for row in rows), flush=True)
        records_file.write_text(json.dumps(records, indent=1), encoding="utf-8")
        print(f"{len(cells)} cells and {len(groups)} scorings in {time.perf_counter() - start:.0f} s")
    records = json.loads(records_file.read_text(encoding="utf-8"))
    table = summarise(records, args.missions, args.tools)
    print(table)
    (out / "summary.md").write_text(
        f"budget {args.budget} per tool and case study; our tools: {args.sim_budget_factor} x budget simulator "
        f"evaluations, {args.confirm} re-runs per failure; {args.repetitions} repetitions; scored as 2025\n\n"
        + table + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
