"""A competition leaderboard on our simulator: every (tool, case study, repetition) cell run through ``surrealist
compete``, then each case study and repetition scored as an edition did.

A :class:`Board` is checked whole before anything runs (:func:`plan`: every tool and case study through
:func:`~surrealist_gym.competition.compete.prepare`). Then:

1. **Cells** (:func:`run_cell`): ``surrealist compete TOOL CASE_STUDY BUDGET --random-seed SEED`` in a process of its
   own, into ``OUT/cells/TOOL/CASE_STUDY-repK``; repetition k's seed is ``--random-seed + k`` (the tool's runs draw
   their noise from it, and the tool's own ``random`` and ``numpy.random`` are seeded from it). A cell is done when its
   ``summary.json`` is there; an interrupted cell is run again into its folder, and compete resumes it (the
   simulations it stored are answered from its ``flights.sqlite``); a cell ends with the leaderboard that runs it
   (``kill -9`` too: ``process.end_with_parent``).
   Cells run at once on local worker threads (each a process of its own) or as tasks of a Dask cluster.
2. **Scores** (:func:`score_cell`): each cell's output folder drawn and flown as the edition did (a drawn test that
   breaks the edition's rules on boxes is not flown and scores 0, as the organisers checked them;
   :func:`~surrealist_gym.competition.reevaluation.evaluate` into
   ``OUT/scores/TOOL/CASE_STUDY-repK/evaluations.sqlite``: each run stored as it completes, read back on a rerun) and
   scored; a cell that wrote no test scores 0, with no
   diversity. 2026 scores twice: with the case study's wind blowing on every test, and without wind.
3. **Ranks** (:func:`rank`): per case study, repetition (and wind), the cells ranked as the edition ranked tools.

A cell's figures depend on its tool, case study, repetition and the board's settings (edition, budget, runs, seed,
UAV), not on the other tools: a board grows (more tools, case studies or repetitions) into the same folder, and
what it holds is reused.

Rows (:class:`BoardRow`) go to ``leaderboard.csv``; :mod:`~surrealist_gym.competition.reports.leaderboard` writes the
report and the figure.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

from ..errors import SurrealistError
from ..sim.uav import DEFAULT_UAV
from .reports.tables import rounded
from .scoring import EDITIONS, Edition, SuiteScore, edition, standings

__all__ = ["BOARD_FILE", "Board", "BoardRow", "Cell", "Tool", "cell_folder", "name_tools", "plan", "run_cell",
           "rank", "score_cell", "set_aside", "start"]

BOARD_FILE = "leaderboard.json"  # the board's settings: a rerun into the same folder must have the same
_GENERIC = {"snippets", "src", "tool"}  # folder names that say nothing of the tool: its parent's name is taken


@dataclass(frozen=True, slots=True)
class Tool:
    """A tool on the board: its name (its folder's) and folder."""

    name: str
    folder: Path


def name_tools(folders: Sequence) -> tuple[Tool, ...]:
    """Name each tool by its folder, lower case (``peers/camba/snippets`` is ``camba``: a folder called
    ``snippets``, ``src`` or ``tool`` takes its parent's name); names that would repeat get ``-2``, ``-3``. A folder
    given twice is a one-line error."""
    tools: list[Tool] = []
    seen: dict[Path, str] = {}
    for given in folders:
        folder = Path(os.fspath(given)).absolute()
        if folder.resolve() in seen:
            raise SurrealistError(f"TOOL_DIR {os.fspath(given)}: given twice (as {seen[folder.resolve()]})")
        base = (folder.parent.name if folder.name.lower() in _GENERIC else folder.name).lower() or "tool"
        name, k = base, 1
        while any(t.name == name for t in tools):
            k += 1
            name = f"{base}-{k}"
        seen[folder.resolve()] = name
        tools.append(Tool(name, folder))
    return tuple(tools)


@dataclass(frozen=True, slots=True)
class Cell:
    """One tool on one case study in one repetition."""

    tool: Tool
    case_study: str  # as given: a name (mission2) or an Aerialist YAML
    repetition: int

    @property
    def label(self) -> str:
        """The case study's name in the board (a YAML's stem)."""
        return case_label(self.case_study)


def case_label(case_study: str) -> str:
    """A case study's name on the board: ``mission2`` as it is, a YAML by its stem."""
    path = Path(case_study)
    return path.stem if path.suffix in (".yaml", ".yml") else case_study


def cell_folder(out: Path, cell: Cell) -> Path:
    """Where a cell's ``compete`` writes on the board."""
    return out / "cells" / cell.tool.name / f"{cell.label}-rep{cell.repetition}"


@dataclass(frozen=True, slots=True)
class Board:
    """A checked leaderboard: the tools, case studies, the edition and its settings, the UAV and the folder."""

    tools: tuple[Tool, ...]
    case_studies: tuple[str, ...]
    edition: Edition
    budget: int
    repetitions: int
    runs: int
    seed: int
    uav: str
    out: Path
    winds: tuple = ()  # per case study, its wind (a Wind or None): 2026 blows it on every test
    given: tuple[tuple[Cell, Path], ...] = ()  # cells run before: compete output folders given as TOOL_DIR

    @property
    def cells(self) -> tuple[Cell, ...]:
        """Every cell: those to run, repetition by repetition, case study by case study, tool by tool; then those
        given."""
        ran = {cell.tool for cell, _ in self.given}
        return tuple(Cell(t, c, k) for k in range(self.repetitions) for c in self.case_studies for t in self.tools
                     if t not in ran) + tuple(cell for cell, _ in self.given)

    def folder(self, cell: Cell) -> Path:
        """The cell's compete output folder: the one given, or where the board runs it."""
        return next((folder for given, folder in self.given if given == cell), None) or cell_folder(self.out, cell)

    @property
    def variants(self) -> tuple[str, ...]:
        """How each case study is scored: ``""`` (the tests as written), or 2026's ``with`` and ``without`` wind."""
        return ("with", "without") if self.edition.wind else ("",)

    def settings(self) -> dict:
        """What makes a cell's figures (``leaderboard.json``): a board into the same folder must have the same; its
        tools, case studies and repetitions may grow."""
        chosen = {key: getattr(self.edition, key) for key in ("tests", "similar_m")
                  if getattr(self.edition, key) != getattr(EDITIONS[self.edition.name], key)}  # set by the user
        return {"command": "leaderboard", "edition": self.edition.name, "budget": self.budget, "runs": self.runs,
                "random_seed": self.seed, "uav": self.uav, **chosen,
                "tools": {t.name: str(t.folder) for t in self.tools}}


def plan(tools: Sequence, case_studies: Sequence[str], edition_name, *, budget: int | None = None,
         repetitions: int = 3, runs: int | None = None, seed: int = 0, uav: str = DEFAULT_UAV,
         tests: int | None = None, similar_m: float | None = None, out) -> Board:
    """Check every input before anything runs (one-line SurrealistError): the edition, the numbers, each tool on each
    case study (:func:`~surrealist_gym.competition.compete.prepare`), and the folder: new, or holding this very board
    (then the run resumes). ``tests`` and ``similar_m`` set what the edition leaves open (how many tests it
    evaluates; how close two averaged flights are alike [m]); None: the edition's."""
    from ..aerialist import load_test
    from .compete import prepare
    from .rules import case_study_path
    from .tool_output import compete_summary

    ed = edition(edition_name, "--edition")
    budget = ed.budget if budget is None else budget
    runs = ed.runs if runs is None else runs
    tests = ed.tests if tests is None else tests
    for flag, value, least in (("--budget", budget, 1), ("--repetitions", repetitions, 1), ("--runs", runs, 1),
                               ("--random-seed", seed, 0), ("--tests", tests, 1)):
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise SurrealistError(f"{flag}: expected a whole number >= {least}, got {value!r}")
    if similar_m is not None:
        if ed.similarity != "flights":
            raise SurrealistError(f"--similar-m: the {ed.name} edition judged tests alike by the ground their boxes "
                                  f"cover, not by their flights")
        if isinstance(similar_m, bool) or not isinstance(similar_m, (int, float)) or not 0 <= similar_m < math.inf:
            raise SurrealistError(f"--similar-m: expected metres >= 0, got {similar_m!r}")
    ed = replace(ed, tests=tests, similar_m=ed.similar_m if similar_m is None else float(similar_m))
    if not tools:
        raise SurrealistError("TOOL_DIR: give at least one competition tool's folder")
    out = Path(out).absolute()
    summaries = [(os.fspath(t), compete_summary(t)) for t in tools]  # a compete output folder's, read once here
    ran = _given_cells(summaries, budget, uav)
    folders = [Path(given) for given, summary in summaries if summary is None]
    named = name_tools(folders + list(dict.fromkeys(Path(tool) for tool, _, _ in ran)))  # a folder twice: refused
    case_studies = list(case_studies) + [file for _, file, _ in ran if case_label(file) not in
                                         {case_label(c) for c in case_studies}]
    case_studies = list(dict.fromkeys(case_studies))
    if not case_studies:
        raise SurrealistError("--case-study: give at least one case study (mission1, mission2, mission3 or a YAML)")
    labels = [case_label(c) for c in case_studies]
    if len(set(labels)) < len(labels):
        raise SurrealistError(f"--case-study: {next(x for x in labels if labels.count(x) > 1)} given twice")
    probe = out / ".probe-not-written"
    winds = []
    for case in case_studies:
        files = [prepare(tool.folder, case, budget, probe, seed=seed, uav=uav).case_study_file
                 for tool in named[:len(folders)]]  # the file each tool is given (its own case_studies/ first)
        files += [Path(file) for _, file, _ in ran if case_label(file) == case_label(case)]  # as its cell ran it
        winds.append(load_test(files[0] if files else case_study_path(case)).wind)
    by_folder = {t.folder: t for t in named}
    given, count = [], {}
    for tool, file, folder in ran:
        case = next(c for c in case_studies if case_label(c) == case_label(file))
        key = (tool, case)
        count[key] = count.get(key, -1) + 1
        given.append((Cell(by_folder[Path(tool).absolute()], case, count[key]), folder))
    board = Board(named, tuple(case_studies), ed, budget, repetitions, runs, seed, uav, out, tuple(winds),
                  tuple(given))
    _check_folder(board)
    return board


def _given_cells(summaries: Sequence[tuple[str, dict | None]], budget: int, uav: str) -> list[tuple[str, str, Path]]:
    """The compete output folders among TOOL_DIR (``summaries``: each TOOL_DIR with its compete summary, or None):
    (the tool's folder, the case study's file, the folder) each, checked to have run with the board's budget and
    UAV."""
    out = []
    for given, summary in summaries:
        if summary is None:
            continue
        folder = Path(os.fspath(given)).absolute()
        for key, board_value, flag in (("budget", budget, "--budget"), ("uav", uav, "--uav")):
            if summary.get(key) != board_value:
                raise SurrealistError(f"TOOL_DIR {os.fspath(given)}: a compete folder run with {key} "
                                      f"{summary.get(key)!r}, not the board's {board_value!r} ({flag})")
        out.append((str(Path(summary["tool"]).absolute()), str(summary["case_study"]), folder))
    return out


def _check_folder(board: Board) -> None:
    out = board.out
    if out.exists() and not out.is_dir():
        raise SurrealistError(f"--out {out}: exists and is not a folder")
    settings = out / BOARD_FILE
    if settings.is_file():
        try:
            before = json.loads(settings.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as err:
            raise SurrealistError(f"--out {out}: {BOARD_FILE} is not readable ({type(err).__name__})") from None
        now = board.settings()
        differ = [k for k in now if k != "tools" and before.get(k) != now[k]]
        if differ:
            raise SurrealistError(f"--out {out}: holds a leaderboard with other settings ({differ[0]}: "
                                  f"{before.get(differ[0])!r}); resume it with the same, or choose another folder")
        known = before.get("tools") or {}
        clash = next((name for name, folder in now["tools"].items() if known.get(name, folder) != folder), None)
        if clash:
            raise SurrealistError(f"--out {out}: its tool {clash!r} is the folder {known[clash]}, not "
                                  f"{now['tools'][clash]}; choose another folder")
    elif out.is_dir() and any(out.iterdir()):
        raise SurrealistError(f"--out {out}: not empty and holds no leaderboard; choose a new folder")


def start(board: Board) -> None:
    """Record the board's settings in its folder, with every tool it has held."""
    board.out.mkdir(parents=True, exist_ok=True)
    path = board.out / BOARD_FILE
    settings = board.settings()
    if path.is_file():
        settings["tools"] = {**json.loads(path.read_text(encoding="utf-8")).get("tools", {}), **settings["tools"]}
    path.write_text(json.dumps(settings, indent=2) + "\n", encoding="utf-8")


# --- cells ----------------------------------------------------------------------------------------------------------
def cell_command(board: Board, cell: Cell) -> list[str]:
    """The ``surrealist compete`` command of a cell."""
    return [sys.executable, "-m", "surrealist_gym.cli", "compete", str(cell.tool.folder), cell.case_study,
            str(board.budget), "--out", str(board.folder(cell)), "--random-seed",
            str(board.seed + cell.repetition), "--uav", board.uav]


def cell_environment() -> dict[str, str]:
    """What a cell's process takes from the leaderboard's environment wherever it runs (on a Dask worker too): the
    Aerialist folders (``SURREALIST_AERIALIST``) and the case-study look-up (``SURREALIST_CASE_STUDIES``)."""
    from .compete import AERIALIST_ENV
    from .rules import CASE_STUDY_ENV

    return {k: os.environ[k] for k in (AERIALIST_ENV, CASE_STUDY_ENV) if k in os.environ}


def run_cell(command: Sequence[str], folder: str, env: dict | None = None) -> dict:
    """Run a cell's ``compete`` (unless its ``summary.json`` is there), with ``env`` over the process's own
    environment, and return that summary. An interrupted cell is resumed: compete answers the simulations its folder
    stored from it. A folder that holds no compete run (an older version's attempt) is kept beside, renamed. The
    cell ends with this process. Picklable, so a Dask worker runs it as it is."""
    from ..results import RUN_FILE, read_summary
    from .compete.process import PARENT_ENV

    folder_path = Path(folder)
    summary = read_summary(folder_path)
    if summary is None:
        if folder_path.exists() and not (folder_path / RUN_FILE).is_file():
            set_aside(folder_path)
        folder_path.parent.mkdir(parents=True, exist_ok=True)
        log = folder_path.with_name(folder_path.name + ".log")
        with open(log, "a", encoding="utf-8") as f:
            subprocess.call(list(command), stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                            env={**os.environ, **(env or {}), PARENT_ENV: str(os.getpid())})
        summary = read_summary(folder_path)
        if summary is None:
            lines = [x for x in log.read_text(encoding="utf-8", errors="replace").splitlines() if x.strip()]
            raise SurrealistError(f"cell {folder}: compete wrote no summary ({lines[-1] if lines else 'no output'}; "
                                  f"see {log})")
    return summary


def set_aside(folder: Path) -> Path:
    """Keep a folder beside, under a new name (nothing is deleted)."""
    k = 1
    while folder.with_name(f"{folder.name}.interrupted-{k}").exists():
        k += 1
    target = folder.with_name(f"{folder.name}.interrupted-{k}")
    folder.rename(target)
    return target


def run_cells(board: Board, workers: int, client=None, done: Callable[[Cell, dict], None] | None = None
              ) -> dict[Cell, dict]:
    """Run every cell not done yet (``workers`` at once, or as tasks of the Dask ``client``); each cell's summary."""
    from concurrent.futures import ThreadPoolExecutor, as_completed

    from .tool_output import compete_summary

    summaries: dict[Cell, dict] = {}
    env = cell_environment()
    given = {cell for cell, _ in board.given}
    jobs = {cell: (cell_command(board, cell), str(board.folder(cell)), env) for cell in board.cells
            if cell not in given}
    for cell in given:  # run before: its summary
        summaries[cell] = compete_summary(board.folder(cell))
    if client is not None:
        from distributed import as_completed as dask_completed

        futures = {client.submit(run_cell, *job, pure=False): cell for cell, job in jobs.items()}
        finished = dask_completed(futures)
    else:
        pool = ThreadPoolExecutor(max(1, workers))
        futures = {pool.submit(run_cell, *job): cell for cell, job in jobs.items()}
        finished = as_completed(futures)
    try:
        for future in finished:
            cell = futures[future]
            summaries[cell] = future.result()
            if done is not None:
                done(cell, summaries[cell])
    finally:
        if client is None:
            pool.shutdown(wait=True, cancel_futures=True)
    return summaries


# --- scores ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class BoardRow:
    """One cell as scored: tests the tool reported (wrote), evaluated (drawn) and failing (at least one run under
    1.5 m), its scores and rank among the tools on the case study in this repetition (and wind: 2026)."""

    tool: str
    case_study: str
    repetition: int
    wind: str
    reported_tests: int
    evaluated_tests: int
    failing_tests: int
    suite_score: float
    failure_score: float
    diversity: float
    r: float
    rank: int
    simulations: int
    refused: int
    problem: str

    def to_row(self, ed: Edition) -> dict:
        """The row of ``leaderboard.csv`` for the edition (2024: the suite score; later: failure score, diversity,
        R; 2026: the wind column)."""
        row: dict = {"tool": self.tool, "case_study": self.case_study, "repetition": self.repetition}
        if ed.wind:
            row["wind"] = self.wind
        row.update(reported_tests=self.reported_tests, evaluated_tests=self.evaluated_tests,
                   failing_tests=self.failing_tests)
        if not ed.ranks_diversity:
            row["suite_score"] = rounded(self.suite_score, 6)
        else:
            row.update(failure_score=rounded(self.failure_score, 6), diversity=rounded(self.diversity, 6),
                       R=rounded(self.r, 6))
        row.update(rank=self.rank, simulations=self.simulations, refused=self.refused, problem=self.problem)
        return row


def score_folder(board: Board, cell: Cell, wind: str) -> Path:
    """Where a cell is scored (its runs' store)."""
    return board.out / "scores" / cell.tool.name / (f"{cell.label}-rep{cell.repetition}"
                                                    + (f"-{wind}-wind" if wind else ""))


@dataclass(frozen=True, slots=True)
class CellScore:
    """A cell scored as the edition did: its suite's score, the tests its tool reported, and why it scores 0 if so."""

    cell: Cell
    wind: str
    suite: SuiteScore
    reported: int
    simulations: int
    refused: int
    problem: str


def score_cell(board: Board, cell: Cell, summary: dict, wind: str = "", workers: int | None = None, executor=None,
               progress: Callable[[int, int], None] | None = None) -> CellScore:
    """Draw a cell's tests and fly them as the edition did (``summary``: its compete summary): a drawn test that
    breaks the edition's rules on boxes is not flown and scores 0, as the organisers checked each for compliance
    before running it. A cell with no test, or whose tests cannot be read, scores 0, with the reason in
    ``problem``."""
    from .reevaluation import evaluate
    from .scoring import draw_folder, score_suite
    from .tool_output import load_tests, rule_broken

    ed, seed, folder = board.edition, board.seed + cell.repetition, board.folder(cell)
    reported, problem = len(summary.get("tests") or []), summary.get("problem") or ""
    suite, tests = None, []
    if summary.get("output_folder") and reported:
        try:  # the tool's tests: what cannot be read scores 0
            drawn = draw_folder(folder, ed, seed)
            tests = [(path.absolute(), _blown(board, cell.case_study, test, wind))
                     for path, test in load_tests(drawn.drawn, any_layout=True)]
        except SurrealistError as err:
            problem = f"not scored: {err}"
    if tests:
        invalid = {path: broken for path, test in tests if (broken := rule_broken(test, ed.rules))}
        flying = [(path, test) for path, test in tests if path not in invalid]
        runs: dict = {}
        if flying:
            store = score_folder(board, cell, wind) / "evaluations.sqlite"
            store.parent.mkdir(parents=True, exist_ok=True)
            ev = evaluate(flying, runs=board.runs, seed=seed, uav=board.uav, workers=workers, progress=progress,
                          store=store, executor=executor, identity={"competition": ed.name, "wind": wind})
            runs = {t.file: t.runs for t in ev.tests}
        suite = replace(score_suite(ed, drawn, [(test, runs.get(str(path), ()), invalid.get(path, ""))
                                                for path, test in tests]), case_study=cell.label)
    suite = suite or SuiteScore(str(folder.absolute()), cell.label, ed.name, 0, (), 0.0, 0.0, 1.0, 0.0, math.nan)
    return CellScore(cell, wind, suite, reported, int(summary.get("simulations") or 0),
                     int(summary.get("refused") or 0), problem)


def rank(board: Board, scores: Sequence[CellScore]) -> list[BoardRow]:
    """The rows of the board: per case study, repetition and wind, the cells ranked as the edition ranked tools; in
    the board's order (repetition, case study, wind, tool)."""
    rows = []
    for k in sorted({s.cell.repetition for s in scores}):
        for case in board.case_studies:
            for wind in board.variants:
                group = [s for s in scores if (s.cell.case_study, s.cell.repetition, s.wind) == (case, k, wind)]
                by_folder = {s.suite.folder: s for s in group}
                placed = {by_folder[p.suite.folder].cell.tool.name: p for p in standings([s.suite for s in group])}
                for s in group:
                    p = placed[s.cell.tool.name]
                    rows.append(BoardRow(s.cell.tool.name, s.cell.label, k, wind, s.reported, len(s.suite.drawn),
                                         s.suite.failing, s.suite.score, s.suite.failure, s.suite.diversity, p.r,
                                         p.rank, s.simulations, s.refused, s.problem))
    return rows


def _blown(board: Board, case_study: str, test, wind: str):
    """The test as scored: as written, or (2026) with the case study's wind on it, or with no wind."""
    if wind == "with":
        return replace(test, wind=board.winds[board.case_studies.index(case_study)])
    if wind == "without":
        return replace(test, wind=None)
    return test
