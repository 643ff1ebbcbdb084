"""Run a competition tool's own ``cli.py``, unedited, with every Aerialist agent flying surrealist-gym's simulator.

:func:`prepare` checks everything before anything starts (the tool folder and its ``cli.py``, no link out of it:
``toolcopy``; the case study, the output folder, the UAV, an Aerialist that holds the API the tool imports and
imports here); :func:`run` copies the tool folder into the output folder, starts a
:class:`~surrealist_gym.competition.compete.server.SimulationServer`, and runs ``python cli.py generate CASE_STUDY
BUDGET`` in the copy, as the competition does, in a process group of its own under resource limits (``process``),
with the shim folder first on its ``PYTHONPATH`` (``shim/``: Aerialist's agents ask the server to fly). What the
tool wrote is read in streams, within :data:`MAX_READ_BYTES`. The output folder then holds::

    tool/            the copy the tool ran in, with what it wrote; each agent.run() hands it copies of its ULogs and
                     test in results/logs/<id>/, which it may move or delete (the shim's hand_over)
    flights/         compete's record, never handed to the tool: each test flown (sim-NNNN.yaml, sim-NNNN-runI.ulg)
    tool-stdout.txt, tool-stderr.txt   what the tool printed
    flights.csv      one row per agent.run(): agent, API, runs, statuses, competition distances, time
    summary.json     the tests the tool wrote, with their competition distance and points; the budget spent


``surrealist compete`` (``cli/competition/compete.py``) is this module's command: ``prepare`` then ``run``.
"""
from __future__ import annotations

import csv
import hashlib
import math
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Callable

from ...aerialist import FILE_FIELDS
from ...errors import DependencyNotInstalled, InvalidTestCase, SurrealistError, one_line
from ...sim.uav import DEFAULT_UAV, decide_uav
from ..scoring import writing_order
from .locate import AerialistSource, find_aerialist, tool_apis
from .process import ToolLimits, ending_with_us, start, stop, wait
from .server import Flight, SimulationServer
from .toolcopy import check_folder, copy_folder
from .toolenv import EnvChoice, ToolEnv, choose_env, own_env, top_level_imports

SHIM = Path(__file__).resolve().parent / "shim"
COMPAT_EXTRA = "pip install -e '.[compete]'"
#: Made in the tool's working folder before it runs, as the competition's Dockerfile does (``mkdir -p``).
PREPARED_FOLDERS = ("logs", "results", "generated_tests")
#: The largest file of the tool's that compete reads (a ULog it wrote, its stdout and stderr are read in part).
MAX_READ_BYTES = 512 * 2 ** 20
_LINE = 64 * 1024  # a line of the tool's stdout is read up to this many characters
#: Aerialist's modules that only its LocalAgent imports (PX4's and ROS's Python modules: mavsdk, rospy, ...).
LOCAL_AGENT_MODULES = ("local_agent", "drone", "simulator", "tools")


@dataclass(frozen=True, slots=True)
class CompetePlan:
    """A checked ``surrealist compete`` run: the tool, what its cli.py is given, where it writes, which Aerialist."""

    tool: Path
    case_study: str  # as the tool's cli.py gets it (relative to the tool's folder, or absolute)
    case_study_file: Path
    budget: int
    out: Path
    aerialist: AerialistSource
    apis: tuple[str, ...]
    runs_per_test: int = 1
    workers: int = 1
    seed: int = 0
    uav: str = DEFAULT_UAV
    env: EnvChoice = EnvChoice("ours", "every module its files import is installed here")
    limits: ToolLimits = ToolLimits()
    executor: str | None = None  # a Dask scheduler's address: the runs fly there instead of on ``workers``

    def settings(self) -> dict:
        """What the output folder records of the run (``run.json``): a resume must have the same; ``workers``, the
        tool's environment and its limits may change (they change where and how fast it runs, not its flights)."""
        return {"tool": str(self.tool), "case_study": self.case_study, "case_study_file": str(self.case_study_file),
                "budget": self.budget, "runs_per_test": self.runs_per_test, "seed": self.seed, "uav": self.uav,
                "workers": self.workers}


@dataclass(frozen=True, slots=True)
class WrittenTest:
    """One test in the tool's output folder: its files, and the competition distance [m] of its ULog (None when it
    could not be judged: ``note`` says why)."""

    name: str
    yaml: Path
    ulg: Path | None
    png: Path | None
    distance: float | None
    points: int | None
    flight: int | None = None  # the Flight whose ULog the tool copied
    note: str = ""


@dataclass(frozen=True, slots=True)
class CompeteResult:
    """What a run of the tool gave: its output folder (``found_by``: how it was found) and tests, the simulations
    flown and refused, the environment it ran in, and ``problem`` (a one-line reason the run does not count: a crash,
    a tool stopped for asking on and on past its budget, no output folder; None when it counts); ``replayed``: the
    simulations a resumed run answered from what its folder had stored."""

    plan: CompetePlan
    returncode: int
    output_folder: Path | None
    tests: tuple[WrittenTest, ...]
    flights: tuple[Flight, ...]
    spent: int
    refused: int
    notes: tuple[str, ...]
    wall_s: float
    problem: str | None = None
    found_by: str = ""
    tool_env: ToolEnv | None = None
    replayed: int = 0  # simulations answered from the folder's record (a resumed run), not flown again

    @property
    def failures(self) -> tuple[WrittenTest, ...]:
        """The tests whose run is a soft failure (competition distance below 1.5 m: 1 point or more)."""
        return tuple(t for t in self.tests if t.points)

    def to_dict(self) -> dict:
        """The run as JSON values: the plan, the Aerialist used, the outcome and each test written."""
        plan = self.plan
        return {
            "tool": str(plan.tool), "case_study": str(plan.case_study_file), "budget": plan.budget,
            "runs_per_test": plan.runs_per_test, "seed": plan.seed, "uav": plan.uav,
            "aerialist": {"version": plan.aerialist.version, "apis": list(plan.aerialist.apis),
                          "path": str(plan.aerialist.path or plan.aerialist.package)},
            "returncode": self.returncode, "problem": self.problem, "wall_s": round(self.wall_s, 2),
            "output_folder": None if self.output_folder is None else str(self.output_folder),
            "output_folder_found_by": self.found_by or None,
            "tool_env": None if self.tool_env is None else self.tool_env.to_dict(),
            "simulations": self.spent, "refused": self.refused, "requests": len(self.flights),
            "compat": list(self.notes),
            "tests": [{"name": t.name, "yaml": str(t.yaml), "ulg": t.ulg and str(t.ulg), "png": t.png and str(t.png),
                       "competition_distance": _finite(t.distance), "points": t.points, "flight": t.flight,
                       "note": t.note}
                      for t in self.tests],
        }


# --- checks ----------------------------------------------------------------------------------------------------------
def prepare(tool, case_study, budget: int, out=None, *, runs_per_test: int = 1, workers: int = 1, aerialist=None,
            seed: int = 0, uav: str = DEFAULT_UAV, tool_env: str = "auto", tool_env_cache=None,
            limits: ToolLimits = ToolLimits(), executor: str | None = None) -> CompetePlan:
    """Check every input and find the Aerialist to use; nothing is written. One-line SurrealistError otherwise.

    Args:
        tool: the tool's folder (holding its ``cli.py``).
        case_study: a case-study name (``mission1``: the tool's ``case_studies/``, then the project's look-up,
            ``competition.case_study_path``) or an Aerialist YAML.
        budget: the simulations the tool may fly, as its cli.py is told.
        out: the output folder: new or empty, or one holding a compete run of the same settings, which the run
            resumes (default ``results/compete-YYYYmmdd-HHMMSS``).
        runs_per_test: runs an agent flies per ``run()`` (a test's own ``agent.count`` wins).
        workers: processes flying the runs of one ``run()``.
        aerialist: an Aerialist folder (default: ``$SURREALIST_AERIALIST``, then the installed one).
        seed: base seed of the runs' noise.
        uav: the UAV profile flown (default the competition's PX4 v1.12 SITL Iris).
        tool_env: which Python runs the tool: ``auto``, ``ours`` or ``own`` (``toolenv.choose_env``).
        tool_env_cache: where the tools' own environments are kept (default ``toolenv.default_cache()``).
        limits: what the tool's process may use (time, memory, file size, CPU time; ``process.ToolLimits``).
        executor: a Dask scheduler's address (``tcp://host:port``): the runs fly on its cluster, not on ``workers``.
    """
    from ...results import ResultsFolder

    for name, value in (("budget", budget), ("--runs", runs_per_test), ("--workers", workers)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise SurrealistError(f"{name}: expected a whole number >= 1, got {value!r}")
    tool = Path(tool)
    if not tool.is_dir():
        raise SurrealistError(f"tool {tool}: {'not a folder' if tool.exists() else 'no such folder'}")
    if not (tool / "cli.py").is_file():
        raise SurrealistError(f"tool {tool}: no cli.py in it (a competition tool is a folder with cli.py)")
    check_folder(tool)  # no link out of it, no loop, no FIFO: before anything in it is read
    out = (Path(out) if out is not None else Path("results") / f"compete-{datetime.now():%Y%m%d-%H%M%S}").absolute()
    ResultsFolder.check(out, "compete")  # new, empty, or a compete run to resume (its settings compared later)
    decide_uav(uav=uav)  # a bad profile fails here, before any folder exists
    argument, file = _case_study(tool.resolve(), case_study)
    apis = tool_apis(tool)
    if len(apis) > 1:
        raise SurrealistError(f"tool {tool}: imports both {' and '.join(apis)}; no Aerialist holds both")
    source = find_aerialist(apis, aerialist)
    env = choose_env(tool, tool_env, tool_env_cache)
    if env.kind == "ours":  # an own environment gets Aerialist's imports installed
        _check_imports(source)
    return CompetePlan(tool.resolve(), argument, file, budget, out, source, apis, runs_per_test, workers, seed, uav,
                       env, limits, executor)


def _case_study(tool: Path, name) -> tuple[str, Path]:
    """What the tool's cli.py is given for the case study, and its file; checked as our loader and Aerialist (paths
    relative to the tool's folder) would read it."""
    from ...aerialist import load_test
    from ..rules import case_study_path

    given = Path(os.fspath(name))
    if given.suffix in (".yaml", ".yml"):
        if not given.is_absolute() and (tool / given).is_file():
            argument, file = given.as_posix(), tool / given
        elif given.is_file():
            argument, file = str(given.resolve()), given.resolve()
        else:
            raise InvalidTestCase(f"case study {os.fspath(name)!r}: no such file (nor in the tool's folder)")
    elif (tool / "case_studies" / f"{given.name}.yaml").is_file():
        argument, file = f"case_studies/{given.name}.yaml", tool / "case_studies" / f"{given.name}.yaml"
    else:
        file = case_study_path(name).resolve()
        argument = str(file)
    load_test(file)
    _check_relative_files(file, tool)
    return argument, file


def _check_relative_files(file: Path, tool: Path) -> None:
    """Aerialist opens a case study's relative paths from the tool's working folder: they must be there."""
    for key, value in _named_files(file):
        if not os.path.isabs(value) and not (tool / value).is_file():
            raise InvalidTestCase(f"case study {file}: field {key!r}: {value!r} is not in the tool's folder {tool} "
                                  f"(Aerialist opens relative paths from the tool's working folder)")


def _named_files(file: Path) -> tuple[tuple[str, str], ...]:
    """(field, path as written) of each file the case study names."""
    import yaml

    doc = yaml.safe_load(Path(file).read_text(encoding="utf-8")) or {}
    named = {}
    for section, keys in FILE_FIELDS.items():
        part = doc.get(section)
        for key in keys if isinstance(part, dict) else ():
            if isinstance(part.get(key), str):
                named.setdefault(key, part[key])  # a section's current name before its legacy one
    return tuple(named.items())


def _check_imports(source: AerialistSource) -> None:
    """Every module that Aerialist's test-case, obstacle, trajectory, plot and agent modules import at their top is
    found in this environment (the tool runs with this interpreter): a one-line error naming the first missing one
    otherwise. Aerialist's local agent needs PX4's and ROS's modules and is left out (the shim stands in for it), as
    is bagpy (the shim's stand-in)."""
    import ast
    import importlib.util

    own = {"aerialist", "bagpy"}
    for path in sorted((source.package / "px4").glob("*.py")):
        if path.stem in LOCAL_AGENT_MODULES:
            continue
        try:
            tree = ast.parse(path.read_text(encoding="utf-8", errors="replace"))
        except SyntaxError as err:
            raise SurrealistError(f"{source.describe()}: {path.name} is not valid Python ({err.msg})") from None
        for top in top_level_imports(tree.body):
            if top not in own and top not in sys.stdlib_module_names and importlib.util.find_spec(top) is None:
                raise DependencyNotInstalled(
                    f"{source.describe()}: its {path.name} imports {top}, which is not installed; install what "
                    f"Aerialist's modules import with: {COMPAT_EXTRA}")
            own.add(top)


def tool_environment(source: AerialistSource, address: str, authkey: bytes, runs: int,
                     seed: int = 0) -> dict[str, str]:
    """The environment of the tool's process: the shim, then Aerialist's folder first on its PYTHONPATH, the
    server's address and key, and the seed of the tool's global random generators (and of its hashes)."""
    env = dict(os.environ)
    paths = [str(SHIM)] + ([str(source.path)] if source.path is not None else [])
    if env.get("PYTHONPATH"):
        paths.append(env["PYTHONPATH"])
    env.update({"PYTHONPATH": os.pathsep.join(paths), "PYTHONUNBUFFERED": "1",
                "SURREALIST_COMPETE_ADDRESS": address, "SURREALIST_COMPETE_AUTHKEY": authkey.hex(),
                "SURREALIST_COMPETE_RUNS": str(runs), "SURREALIST_COMPETE_SEED": str(seed),
                "PYTHONHASHSEED": str(seed % 4294967296)})
    env.setdefault("MPLBACKEND", "Agg")
    return env


# --- the run ---------------------------------------------------------------------------------------------------------
def claim(plan: CompetePlan):
    """The run's output folder claimed (:class:`~surrealist_gym.results.ResultsFolder`: made or resumed, locked)."""
    from ...results import ResultsFolder
    from .record import FLIGHTS

    return ResultsFolder.claim(plan.out, "compete", plan.settings(), free=("workers",), stores=(FLIGHTS,))


def run(plan: CompetePlan, on_flight: Callable[[Flight], None] | None = None, folder=None) -> CompeteResult:
    """Run the tool (see the module docstring); ``on_flight`` is called with each Flight as the server records it.

    ``plan.out`` is claimed as a :class:`~surrealist_gym.results.ResultsFolder` (made, locked, its settings
    recorded): a folder holding a compete run of the same settings is resumed. The tool is started again in a fresh
    copy, and each simulation it asks for that the folder's ``flights.sqlite`` holds (the same test, run index and
    seed) is answered from it unflown, so the run ends as an uninterrupted one would. ``folder``: the folder
    :func:`claim` gave (claimed here when None); released when the run ends."""
    folder = claim(plan) if folder is None else folder
    with folder.keeping("the same command resumes it", "flight(s)"):
        return _run(plan, folder.resumed, on_flight)


def _run(plan: CompetePlan, resumed: bool, on_flight) -> CompeteResult:
    import shutil

    from .process import end_with_parent
    from .record import FLIGHTS, FlightRecord

    start_s = time.perf_counter()
    end_with_parent()  # a leaderboard's cell ends with the leaderboard
    work = plan.out / "tool"
    if resumed:  # the tool starts again from its own folder; what was flown stays in flights/ and flights.sqlite
        for name in ("summary.json", "flights.csv"):
            (plan.out / name).unlink(missing_ok=True)
        if work.exists():
            shutil.rmtree(work)
    tool_env = own_env(plan.env, plan.out / "tool-env.txt") if plan.env.kind == "own" else \
        ToolEnv("ours", Path(sys.executable), plan.env.reason)
    copy_folder(plan.tool, work)
    for name in PREPARED_FOLDERS:  # as the competition's Dockerfile prepares the tool's working folder
        (work / name).mkdir(exist_ok=True)
    stdout, stderr = plan.out / "tool-stdout.txt", plan.out / "tool-stderr.txt"
    uav = decide_uav(uav=plan.uav)
    uav.write(plan.out)
    config = uav.config
    command = [str(tool_env.python), "cli.py", "generate", plan.case_study, str(plan.budget)]
    roots = (work, plan.case_study_file.parent,  # where the files a test names may be: and those the case study names
             *(Path(v) for _, v in _named_files(plan.case_study_file) if os.path.isabs(v)))
    record = FlightRecord(plan.out / FLIGHTS[0])
    try:
        with SimulationServer(plan.out / "flights", plan.budget, config, plan.seed, plan.workers, on_flight,
                              roots=roots, executor=plan.executor, record=record) as server, \
                open(stdout, "wb") as out_file, open(stderr, "wb") as err_file:
            env = tool_environment(plan.aerialist, server.address, server.authkey, plan.runs_per_test, plan.seed)
            started = time.time()
            with ending_with_us():
                process = start(command, plan.limits, cwd=work, env=env, stdout=out_file, stderr=err_file,
                                stdin=subprocess.DEVNULL)
                try:
                    returncode, stopped = wait(process, plan.limits, server.runaway)
                finally:  # an exception, Ctrl-C, SIGTERM, or the tool's end: none of its processes outlives this
                    stop(process)
            flights, spent, refused, notes = server.flights, server.spent, server.refused, server.notes
            replayed = server.replayed
    finally:
        record.close()
    output, found_by = find_output_folder(stdout, work, started)
    tests = _written_tests(output, flights, work) if output is not None else ()
    problem = _problem(plan, returncode, stopped, output, found_by, stdout, stderr)
    result = CompeteResult(plan, returncode, output, tests, flights, spent, refused, notes,
                           time.perf_counter() - start_s, problem, found_by, tool_env, replayed)
    _write_records(result)
    return result


def find_output_folder(stdout: Path, work: Path, since: float = 0.0) -> tuple[Path | None, str]:
    """The tool's output folder and how it was found: the folder it named last in an ``output folder: PATH`` line
    (relative to its working folder), when it exists; else, as the organisers collect a tool's tests, the folder whose
    test YAMLs were written last (after ``since``, a time stamp: not a folder the tool shipped) under its
    ``generated_tests*/`` folders (``generated_tests/``; AmbieGen's ``generated_tests-01/``) or ``$TESTS_FOLDER``,
    which the tools read. (None, why) when neither is there. Only a folder inside ``work`` (links resolved) counts.
    stdout is read line by line, each line up to 64 K characters."""
    printed = None
    with open(stdout, encoding="utf-8", errors="replace") as lines:
        for line in iter(lambda: lines.readline(_LINE), ""):
            if line.strip().startswith("output folder:"):
                printed = line.strip()[len("output folder:"):].strip() or None
    named = None if printed is None else Path(os.path.normpath(Path(printed) if Path(printed).is_absolute()
                                                               else work / printed))
    inside = named is not None and Path(os.path.realpath(named)).is_relative_to(os.path.realpath(work))
    if named is not None and inside and named.is_dir():
        return named, "printed by the tool ('output folder: PATH')"
    said = ("it printed no 'output folder: PATH'" if named is None else
            f"the folder it printed, {named}, is outside its working folder" if not inside else
            f"the folder it printed, {named}, does not exist")
    roots = sorted(work.glob("generated_tests*")) + ([work / os.environ["TESTS_FOLDER"]]
                                                     if os.environ.get("TESTS_FOLDER") else [])
    latest: dict[Path, tuple[float, str]] = {}  # folder -> (when its last test YAML was written, its root's name)
    for root in (r for r in roots if r.is_dir() and not r.is_symlink()):
        for yaml_file in root.rglob("*.yaml"):
            if yaml_file.is_symlink():
                continue
            written = yaml_file.stat().st_mtime
            if written >= since and written > latest.get(yaml_file.parent, (0.0, ""))[0]:
                latest[yaml_file.parent] = (written, root.name)
    if not latest:
        return None, f"{said}, and wrote no test YAML under {work / 'generated_tests'}*/"
    newest = max(latest, key=lambda folder: (latest[folder][0], str(folder)))
    return newest, f"the newest folder of test YAMLs under {latest[newest][1]}/ ({said})"


def _problem(plan, returncode, stopped, output, found_by, stdout, stderr) -> str | None:
    """Why the run does not count (None when it does). Simulations refused over the budget are not a problem: the
    tool saw them fail, as PX4 runs past a budget would not have been given, and its output is scored as usual."""
    where = f"what it wrote is kept in {plan.out}"
    if stopped == "runaway":
        return (f"the tool kept asking for simulations past its budget of {plan.budget} and was stopped; {where}")
    if stopped == "timeout":
        return f"the tool ran past its time limit of {plan.limits.timeout_s:g} s and was stopped; {where}"
    if returncode != 0:
        lines = [line for line in _tail(stderr).splitlines() if line.strip()]
        last = f": {one_line(lines[-1], 120)}" if lines else ""
        return f"the tool crashed (exit code {returncode}){last} (see {stderr}); {where}"
    if output is None:
        return f"no output folder: {found_by} (see {stdout}); {where}"
    return None


def _tail(path: Path, size: int = 64 * 1024) -> str:
    """The last ``size`` bytes of a file, as text."""
    with open(path, "rb") as f:
        f.seek(max(0, f.seek(0, os.SEEK_END) - size))
        return f.read().decode("utf-8", errors="replace")


def _digest(path) -> str:
    """The SHA-1 of a file, read in blocks of 1 MB."""
    digest = hashlib.sha1()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(2 ** 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _own_file(path: Path, work: Path) -> Path | None:
    """``path`` when it is a regular file of the tool's (no link), else None."""
    return path if not path.is_symlink() and path.is_file() and path.resolve().is_relative_to(work.resolve()) \
        else None


def _written_tests(folder: Path, flights, work: Path) -> tuple[WrittenTest, ...]:
    """The tests in the tool's output folder, each judged by the competition's distance on its own ULog with the
    obstacles of the flight it came from (the tool copies our ULog as it is). A ULog is read only when its size is
    that of a ULog flown (then it is at most that large), never one over :data:`MAX_READ_BYTES`; links are not
    followed."""
    sizes, by_log = set(), {}
    for flight in flights:
        for log in flight.logs:
            if Path(log).is_file():
                sizes.add(Path(log).stat().st_size)
                by_log[_digest(log)] = flight
    tests = []
    for yaml_file in writing_order(y for y in folder.glob("*.yaml") if _own_file(y, work)):
        ulg, png = _own_file(yaml_file.with_suffix(".ulg"), work), _own_file(yaml_file.with_suffix(".png"), work)
        size = ulg.stat().st_size if ulg is not None else 0
        flight = by_log.get(_digest(ulg)) if ulg is not None and size in sizes and size <= MAX_READ_BYTES \
            else None
        distance, points, note = None, None, ""
        if ulg is None:
            note = "no ULog beside it"
        elif size > MAX_READ_BYTES:
            note = f"its ULog is {size} bytes, over the {MAX_READ_BYTES} compete reads; not read"
        elif flight is None:
            note = "its ULog is none that was flown"
        else:
            try:
                distance = ulog_distance(ulg, flight.test_file)
                from ..rules import points as competition_points

                points = competition_points(distance)
            except SurrealistError as err:
                note = str(err)
        tests.append(WrittenTest(yaml_file.stem, yaml_file, ulg, png, distance, points,
                                 None if flight is None else flight.number, note))
    return tuple(tests)


def ulog_distance(ulg, test_file) -> float:
    """The competition distance [m] of a ULog's flight to the obstacles of a test (our YAML): the least over the
    boxes of the distance from the footprint to the polyline of Aerialist's 0.5 s trajectory of the log
    (:meth:`~surrealist_gym.trajectory.Trajectory.aerialist`; unbuffered)."""
    from ...aerialist import load_test
    from ...geometry import competition_distance
    from ...logs import read_flight
    from ...trajectory import Trajectory

    test = load_test(test_file)
    p = read_flight(ulg).positions
    return float(competition_distance(Trajectory.aerialist(p.timestamp_us, p.x, p.y, p.z, p.heading), test.obstacles))


def _write_records(result: CompeteResult) -> None:
    """flights.csv, then summary.json (written last, whole: a folder with a summary is a finished run)."""
    from ...results import ResultsFolder

    out = result.plan.out
    with open(out / "flights.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["number", "agent", "api", "test_file", "runs", "statuses", "competition_distances",
                         "wall_s", "refused", "error"])
        for flight in result.flights:
            writer.writerow([flight.number, flight.agent, flight.api, flight.test_file, len(flight.statuses),
                             " ".join(flight.statuses), " ".join(f"{d:.3f}" for d in flight.distances),
                             f"{flight.wall_s:.3f}", int(flight.refused), flight.error])
    ResultsFolder(out, "compete").write_json("summary.json", result.to_dict())


def _finite(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None
