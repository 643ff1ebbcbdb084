"""The options of a search, typed once: ``surrealist replicate`` / ``generate`` build their arguments from them,
``run.json`` records them, and ``--resume`` reads them back.

Each field's ``metadata`` holds its command-line help (and flags where they are not ``--field-name``); a field
without help is not an option of the command line.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import ClassVar

from ..errors import SurrealistError
from ..geometry import check_buffer

SCREEN_RULES = ("auto", "lowfi", "ei", "pi", "none")  # surrogates.config.RULES, without importing torch here


def race_stages(value) -> tuple[int, ...]:
    """``--first-runs``: the run counts after which racing compares a candidate (``"1"``, ``"1,2,3,4"``; a number or
    a list from a run.json); empty when racing is off. Raises ArgumentTypeError for anything else."""
    try:
        stages = ([int(value)] if isinstance(value, int) else [int(k) for k in value]
                  if isinstance(value, (list, tuple)) else [int(k) for k in str(value).split(",")])
    except ValueError:
        stages = None
    if stages is None or any(k < 0 for k in stages) or any(b <= a for a, b in zip(stages, stages[1:])):
        raise argparse.ArgumentTypeError(f"expected increasing numbers of runs such as 1 or 1,2,3,4, got {value!r}")
    return tuple(k for k in stages if k)


def _opt(default, help: str, **argparse_kwargs):
    return field(default=default, metadata={"help": help, **argparse_kwargs})


#: The defaults that differ by problem, stated once: replicate's and generate's options take theirs from here,
#: ``generate --case-study`` the third row (where the command line leaves them), ``compare --runs`` its help; the envs
#: (Surrealist-Replicate-v0, -Generate-v0, -CaseStudy-v1) take the same (tests/surrealist_gym/cli/test_vocabulary.py).
PROBLEM_DEFAULTS = {
    "replicate": {"budget": 100, "runs": 5, "agent": "greedy"},
    "generate": {"budget": 50, "runs": 10, "agent": "greedy"},
    "case study": {"budget": 200, "runs": 1, "agent": "suite"},
}
#: what ``generate --case-study`` changes, unless typed
CASE_STUDY_DEFAULTS = PROBLEM_DEFAULTS["case study"]
#: the env of each problem (``compare --env``)
PROBLEM_ENVS = {"replicate": "Surrealist-Replicate-v0", "generate": "Surrealist-Generate-v0",
                "case study": "Surrealist-CaseStudy-v1"}

#: Where every command that writes a folder writes it unless ``--out`` says otherwise (:func:`default_out`).
OUT_PATTERN = "results/{command}-YYYYmmdd-HHMMSS"


def default_out(command: str) -> Path:
    """The folder ``command`` writes when ``--out`` is not given: ``results/<command>-<YYYYmmdd-HHMMSS>`` (local
    time), the one pattern of every command."""
    return Path("results") / f"{command}-{datetime.now():%Y%m%d-%H%M%S}"


def out_help(command: str, what: str = "output folder") -> str:
    """The help of ``--out`` for ``command``: what it is and its default (:data:`OUT_PATTERN`)."""
    return f"{what} (default {OUT_PATTERN.format(command=command)})"


def add_out_argument(parser: argparse.ArgumentParser, command: str, what: str = "output folder") -> None:
    """``--out DIR``, default None: the command writes to :func:`default_out` then."""
    parser.add_argument("--out", metavar="DIR", default=None, help=out_help(command, what))


class Refused(argparse.Action):
    """An option kept only to be refused in one line (argparse's error: exit code 2, before any work) with what to
    type instead. ``instead``: the words, or a function of the value typed (None when none was) that gives them."""

    def __init__(self, option_strings, dest, instead="", **kwargs):
        self.instead = instead
        super().__init__(option_strings, dest, nargs="?", help=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        said = self.instead(values) if callable(self.instead) else self.instead
        parser.error(said if said.startswith(option_string + " ") else f"{option_string}: {said}")


class _RefusedPositional(argparse.Action):
    """A positional argument a command no longer takes (``generate SEED.yaml``), refused in one line with the option
    that took its place: ``instead(value)`` gives the words. A value that is not a test YAML (the value of a mistyped
    option, say) is kept for :func:`refuse_leftover` to refuse once argparse has said what else is wrong."""

    def __init__(self, option_strings, dest, instead=None, **kwargs):
        self.instead = instead
        super().__init__(option_strings, dest, nargs="?", default=None, help=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        if values is not None and str(values).lower().endswith((".yaml", ".yml")):
            parser.error(self.instead(values))
        setattr(namespace, self.dest, values)


def refuse_argument(parser: argparse.ArgumentParser, flag: str, instead) -> None:
    """Keep ``flag`` (an old spelling) only to refuse it in one line before any work: ``instead`` says what to type
    (words, or a function of the value typed)."""
    parser.add_argument(flag, dest="_refused_" + flag.lstrip("-").replace("-", "_"), action=Refused, default=None,
                        instead=instead)


def refuse_positional(parser: argparse.ArgumentParser, name: str, instead) -> None:
    """Refuse a positional argument the command no longer takes; ``instead(value)`` says what to type. The command's
    run() calls :func:`refuse_leftover` first."""
    parser.add_argument("_refused_" + name, action=_RefusedPositional, instead=instead)


def refuse_leftover(args: argparse.Namespace, name: str) -> None:
    """One line for a positional argument :func:`refuse_positional` kept (not a test YAML), before any work."""
    value = getattr(args, "_refused_" + name, None)
    if value is not None:
        raise SurrealistError(f"{value}: unexpected argument; the command takes options only (a seed test is --seed "
                              f"TEST.yaml)")


def add_random_seed_argument(parser: argparse.ArgumentParser, help: str, default: int = 0,
                             seed_test: bool = False) -> None:
    """``--random-seed N``, the seed of the simulation noise in every command; ``--seed`` (which names a seed test
    elsewhere) is refused in one line, unless the command takes a seed test (``seed_test``)."""
    parser.add_argument("--random-seed", type=int, default=default, metavar="N", help=help)
    if not seed_test:
        refuse_argument(parser, "--seed", "use --random-seed (the noise seed); --seed names a seed test in "
                                          "other commands")


def refuse_inapplicable(args: argparse.Namespace, rules) -> None:
    """One line for an option typed on the command line that does not apply to the chosen problem, before any work.
    ``rules``: ``(flags, applies, why)``; a flag of ``flags`` given (``args._flags``) when ``applies`` is false is
    refused as ``--flag: why``."""
    given = getattr(args, "_flags", frozenset())
    for flags, applies, why in rules:
        if applies:
            continue
        for flag in (flags,) if isinstance(flags, str) else flags:
            if flag in given:
                raise SurrealistError(f"{flag}: {why}")


#: ``--buffer`` of generate, evaluate and fidelity: one meaning, one default (sim.SimConfig.competition_buffer_m).
BUFFER_HELP = ("half width added to the flight's polyline in the competition distance [m]: 0.125 is Aerialist's since "
               "Oct 2024, whose figures read that much lower; default 0, Aerialist's before then (and the labelled "
               "PX4 flights')")
#: ``--dask-scheduler`` of every command that flies (:data:`FLYING_COMMANDS`): the searches' (a SearchOptions field)
#: and the others' (:func:`add_dask_argument`).
DASK_HELP = "run the simulations on a Dask cluster (tcp://host:port)"
#: ``--workers`` with its default, local processes: all cores, at most ``executors.DEFAULT_MAX_WORKERS``
WORKERS_HELP = "local worker processes (default: all cores, at most 8)"
#: ``--workers`` of a command that flies in its own process unless told otherwise (simulate, train, compete)
WORKERS_ONE_HELP = "local worker processes flying the runs of a test (default 1: in this process)"
#: The commands that fly simulations: each takes ``--workers N`` and ``--dask-scheduler ADDRESS``, and
#: ``--random-seed N`` for the noise (docs/cli.md; tests/surrealist_gym/cli/test_vocabulary.py).
FLYING_COMMANDS = ("simulate", "calibrate", "replicate", "generate", "compare", "train", "fidelity", "predict",
                   "evaluate", "compete", "leaderboard")


_UAV_HELP = ("UAV profile: px4-v1.12-sitl-iris (PX4 SITL + PX4-Avoidance, as Aerialist flies), px4-vision-case0, "
             "px4-vision-sitl (the paper's case0 tests as Gazebo flies them), or a profile YAML (surrealist calibrate)")
_PRESET_HELP = "greedy hyper-parameters (--agent greedy): paper Table 1, or the authors' own run (default)"


@dataclass(frozen=True)
class SearchOptions:
    """What steers one search (the fields both commands share)."""

    command: ClassVar[str] = ""

    budget: int = _opt(PROBLEM_DEFAULTS["replicate"]["budget"], "evaluations allowed (default {default})", type=int)
    runs: int = _opt(PROBLEM_DEFAULTS["replicate"]["runs"], "simulations per evaluation (default {default})", type=int,
                     metavar="N")
    workers: int | None = _opt(None, WORKERS_HELP, type=int, metavar="N")
    dask_scheduler: str | None = _opt(None, DASK_HELP, metavar="ADDRESS")
    preset: str = _opt("authors", _PRESET_HELP, choices=["paper", "authors"])
    agent: str = _opt(PROBLEM_DEFAULTS["replicate"]["agent"], "search agent: greedy, greedy-paper, random, cmaes, "
                                                             "suite, ppo[-sample]:POLICY.zip, module:Class "
                                                             "(default {default})")
    random_seed: int = _opt(0, "base seed of the simulation noise (default {default})", type=int, metavar="N")
    uav: str | None = _opt(None, _UAV_HELP + "; default: the log's vehicle (a PX4 Vision: px4-vision-case0, else "
                                             "px4-v1.12-sitl-iris, on the ground as long as the log)",
                           metavar="NAME_OR_YAML")
    common_noise: bool = _opt(False, "common random numbers: run i of every test flies with the same noise, so "
                                     "tests differ only by what they change (default: each test draws its own)",
                              action="store_true")
    surrogate: str | None = _opt(None, "pre-screen mutations with a surrogate model folder (surrealist surrogate "
                                       "train) or one trained online; skipped candidates cost no simulations",
                                 metavar="MODEL|online")
    first_runs: tuple[int, ...] = _opt((), "racing (with a surrogate; default online): fly K runs of a candidate "
                                           "first and the rest only if they do not fall clearly short of the best "
                                           "test's fitness (with --common-noise: of its first K runs); K1,K2,... "
                                           "compares again after each (e.g. 1,2,3,4)", type=race_stages,
                                 metavar="K[,K2...]")
    screen: str = _opt("auto", "pre-screening rule (with a surrogate): auto (default: lowfi with a --lowfi model, "
                               "else ei), lowfi, ei, pi, or none (skip nothing: race only, with --first-runs)",
                       choices=SCREEN_RULES)
    skips_spend_budget: bool = _opt(False, "pre-screening: the search's budget counts skipped and dropped "
                                           "candidates as evaluations, so it walks and stops as without screening, "
                                           "having simulated less", action="store_true")
    verify_stop: bool = _opt(False, "pre-screening: when the search stops with budget left, restart it "
                                    "unscreened from the best test", action="store_true")

    def check(self, where=lambda name: "--" + name.replace("_", "-")) -> "SearchOptions":
        """The options if every value is in range, else a one-line SurrealistError naming the option (``where``
        turns a field name into what the message calls it: the flag, or run.json's key)."""
        minimum = {"budget": 1, "runs": 1, "workers": 1, "random_seed": 0}
        for name, low in minimum.items():
            value = getattr(self, name)
            if value is None and name == "workers":
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise SurrealistError(f"{where(name)}: expected a whole number >= {low}, got {value!r}")
        if max(self.first_runs or (0,)) >= self.runs:
            raise SurrealistError(f"{where('first_runs')}: expected numbers of runs below the runs per evaluation "
                                  f"({self.runs}), got {','.join(map(str, self.first_runs))}")
        return self

    @staticmethod
    def inapplicable(args: argparse.Namespace, default_agent: str | None = None) -> list:
        """The options of a new search that do not apply to it (:func:`refuse_inapplicable`): ``--preset`` steers
        the greedy only (``default_agent``: the problem's agent when ``--agent`` is not typed)."""
        given = getattr(args, "_flags", frozenset())
        agent = args.agent if "--agent" in given or default_agent is None else default_agent
        return [("--preset", agent == "greedy", f"applies only to --agent greedy (the adaptive greedy's "
                                                f"hyper-parameters), not to {agent}")]

    @property
    def prescreened(self) -> bool:
        """Whether the search runs behind pre-screening (any of its options given)."""
        return bool(self.surrogate or self.first_runs or self.skips_spend_budget or self.verify_stop
                    or self.screen != "auto")

    def to_json(self) -> dict:
        """The options as run.json holds them."""
        values = dataclasses.asdict(self)
        values["first_runs"] = list(self.first_runs)
        return {"command": self.command, **values}

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> "SearchOptions":
        """The options the command line gave, checked (one-line errors)."""
        return cls(**{f.name: getattr(args, f.name) for f in dataclasses.fields(cls)}).check()

    @classmethod
    def from_json(cls, path: Path) -> "SearchOptions":
        """The options of the search a results folder's run.json records (one-line errors for a file that is not
        this command's)."""
        try:
            values = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
            raise SurrealistError(f"{path}: not a readable run file ({type(err).__name__})") from None
        if not isinstance(values, dict):
            raise SurrealistError(f"{path}: not a run file (expected a mapping)")
        if values.pop("command", None) != cls.command:
            raise SurrealistError(f"{path}: not a '{cls.command}' search")
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - names)
        if unknown:
            raise SurrealistError(f"{path}: unknown option {unknown[0]!r}")
        try:
            values["first_runs"] = race_stages(values.get("first_runs") or 0)
        except argparse.ArgumentTypeError as err:
            raise SurrealistError(f"{path}: first_runs: {err}") from None
        return cls(**values).check(lambda name: f"{path}: {name}")

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """The command line's arguments: positional fields first, then ``--field-name`` options."""
        for f in dataclasses.fields(cls):
            meta = dict(f.metadata)
            help_text = meta.pop("help").format(default=f.default)
            if meta.pop("positional", False):
                parser.add_argument(f.name, nargs="?", default=f.default, help=help_text)
                continue
            flag = meta.pop("flag", "--" + f.name.replace("_", "-"))
            parser.add_argument(flag, dest=f.name, default=f.default, help=help_text, **meta)
        add_out_argument(parser, cls.command, "results folder")
        parser.add_argument("--resume", default=None, metavar="DIR",
                            help="resume an interrupted search from its results folder (same options)")


@dataclass(frozen=True)
class ReplicateOptions(SearchOptions):
    """``surrealist replicate``: the real flight, the seed test and how runs are averaged."""

    command: ClassVar[str] = "replicate"

    log: str | None = _opt(None, "real flight log (.ulg); default: the bundled case0.ulg of the paper",
                           positional=True)
    seed: str | None = _opt(None, "seed test case, or: tall (default for a log other than case0: a 3 x 3 m box in "
                                  "the middle of the mission line, 2 m taller than the flight), paper (the same "
                                  "box 3 m tall, as the paper), detours (a tall box where the real flight leaves its "
                                  "mission line, one per detour); default for case0: the paper's seed 1",
                           metavar="TEST.yaml|tall|paper|detours")
    averaging: str = _opt("dba", "how the runs of a test are averaged before the DTW (default dba)",
                          choices=["dba", "soft_dtw"])
    allow_partial: bool = _opt(False, "replicate a damaged (truncated) log as far as it is readable",
                               action="store_true")
    search_uav: bool = _opt(False, "search the UAV's settings as well as the obstacles (take-off delay and the "
                                   "planner's pace, altitude and detour settings; best-uav.yaml names what it "
                                   "found)", action="store_true")

    def check(self, where=lambda name: "--" + name.replace("_", "-")) -> "ReplicateOptions":
        """The common checks, then replicate's own (no --search-uav with pre-screening); returns self."""
        super().check(where)
        if self.search_uav and self.prescreened:
            raise SurrealistError(f"{where('search_uav')}: not with pre-screening (--surrogate, --first-runs, ...): "
                                  f"the surrogate's features describe obstacles, not the UAV's settings")
        return self


@dataclass(frozen=True)
class GenerateOptions(SearchOptions):
    """``surrealist generate``: the seed test, how runs are scored and which obstacles move."""

    command: ClassVar[str] = "generate"

    budget: int = _opt(PROBLEM_DEFAULTS["generate"]["budget"], "evaluations allowed (default {default}; with "
                       f"--case-study {CASE_STUDY_DEFAULTS['budget']})", type=int)
    runs: int = _opt(PROBLEM_DEFAULTS["generate"]["runs"], "simulations per evaluation (default {default}; with "
                     f"--case-study {CASE_STUDY_DEFAULTS['runs']})", type=int, metavar="N")
    agent: str = _opt(PROBLEM_DEFAULTS["generate"]["agent"],
                      "search agent: greedy, greedy-paper, random, cmaes, suite, ppo[-sample]:POLICY.zip, module:Class "
                      f"(default {{default}}; with --case-study {CASE_STUDY_DEFAULTS['agent']})")
    uav: str | None = _opt(None, _UAV_HELP + "; default: px4-vision-case0 for a seed test with a reference log, as "
                                             "the paper's, else px4-v1.12-sitl-iris (with --case-study too)",
                           metavar="NAME_OR_YAML")
    test: str | None = _opt(None, "seed test case (Aerialist YAML); default: the paper's RQ2 seed", flag="--seed",
                            metavar="TEST.yaml")
    aggregate: str = _opt("riskiest", "how the runs of a test are scored: the riskiest run (paper) or the mean",
                          choices=["riskiest", "mean"])
    all_mutators: bool = _opt(False, "move, resize and rotate every obstacle of the seed test (default: move the "
                                     "first obstacle only; not with --case-study, whose boxes all change)",
                              action="store_true")
    case_study: str | None = _opt(None, "generate a suite of distinct failures for a UAV Testing Competition case "
                                        "study (mission1, mission2, mission3 or its YAML) under the competition's "
                                        "rules; then the defaults are " + " ".join(
                                            f"--{k} {v}" for k, v in CASE_STUDY_DEFAULTS.items()),
                                  metavar="NAME|YAML")
    obstacles: int = _opt(3, "with --case-study: boxes per test (1-3; default {default})", type=int, metavar="N")
    wind: bool = _opt(False, "search the wind's speed (0-10 m/s) and direction as well as the obstacles (not with "
                             "pre-screening)", action="store_true")
    confirm: int = _opt(5, "with --case-study: re-fly each failure of the suite this many times with fresh noise and "
                           "report its failure probability (default {default}; 0: do not)", type=int)
    buffer: float = _opt(0.0, BUFFER_HELP, type=float, metavar="M")
    px4_verdict: bool = _opt(False, "with --case-study: rank the suite by the model of PX4 SITL's verdict: P(PX4 < "
                                    "1.5 m) x the expected test score, from the --confirm re-runs (docs/predict.md)",
                             action="store_true")

    def check(self, where=lambda name: "--" + name.replace("_", "-")) -> "GenerateOptions":
        """The common checks, then generate's own (--confirm, --case-study and what goes with it); returns self."""
        super().check(where)
        if self.confirm < 0 or isinstance(self.confirm, bool):
            raise SurrealistError(f"{where('confirm')}: expected a whole number >= 0, got {self.confirm!r}")
        if self.case_study is not None and not str(self.case_study).strip():
            raise SurrealistError(f"{where('case_study')}: expected mission1, mission2, mission3 or a case study "
                                  f"YAML, got an empty name")
        if self.case_study is not None and self.test is not None:
            raise SurrealistError(f"{where('case_study')}: a case study brings its own mission; give it or a seed "
                                  f"test, not both")
        check_buffer(self.buffer, where("buffer"))
        if self.case_study is not None and not 1 <= self.obstacles <= 3:
            raise SurrealistError(f"{where('obstacles')}: the competition allows 1 to 3 boxes, got {self.obstacles}")
        if self.wind and self.prescreened:
            raise SurrealistError(f"{where('wind')}: not with pre-screening (--surrogate, --first-runs, ...): the "
                                  f"surrogate's features describe obstacles, not the wind")
        return self

    @staticmethod
    def inapplicable(args: argparse.Namespace) -> list:
        """The options of a new ``generate`` that do not apply to its problem (:func:`refuse_inapplicable`)."""
        case_study = bool(getattr(args, "case_study", None))
        return [("--obstacles", case_study, "applies only with --case-study (the boxes of a competition test; a "
                                            "seed test brings its obstacles)"),
                ("--confirm", case_study, "applies only with --case-study (the re-runs of its suite's failures)"),
                ("--px4-verdict", case_study, "applies only with --case-study (it ranks the suite's failures)"),
                ("--all-mutators", not case_study,
                 "not with --case-study: the competition's layout mutators change every box already"),
                *SearchOptions.inapplicable(args, CASE_STUDY_DEFAULTS["agent"] if case_study else None)]


def add_buffer_argument(parser: argparse.ArgumentParser) -> None:
    """``--buffer M`` (:data:`BUFFER_HELP`)."""
    parser.add_argument("--buffer", type=float, default=0.0, metavar="M", help=BUFFER_HELP)


def add_dask_argument(parser: argparse.ArgumentParser, help: str = DASK_HELP) -> None:
    """``--dask-scheduler ADDRESS`` (:data:`DASK_HELP`; an address that cannot be reached is one line)."""
    parser.add_argument("--dask-scheduler", default=None, metavar="ADDRESS", help=help)


def add_workers_argument(parser: argparse.ArgumentParser, help: str = WORKERS_HELP, default: int | None = None
                         ) -> None:
    """``--workers N`` (:data:`WORKERS_HELP`, or the command's own default said in ``help``)."""
    parser.add_argument("--workers", type=int, default=default, metavar="N", help=help)


def refuse_workers_with_dask(args: argparse.Namespace) -> None:
    """``--workers`` typed with ``--dask-scheduler``: one line (the cluster's workers fly the runs)."""
    if args.dask_scheduler is not None and "--workers" in getattr(args, "_flags", frozenset()):
        raise SurrealistError("--workers: not with --dask-scheduler (the cluster's workers fly the runs)")


def check_at_least(args: argparse.Namespace, **lowest) -> None:
    """One line for a whole-number option below its lowest value (``--runs: expected a whole number >= 1, got 0``),
    worded as the search options' check; an option left unset (None) passes."""
    for name, low in lowest.items():
        value = getattr(args, name, None)
        if value is not None and not value >= low:
            raise SurrealistError(f"--{name.replace('_', '-')}: expected a whole number >= {low}, got {value!r}")


def check_writable(path, flag: str = "--out", kind: str = "folder", suffixes: tuple[str, ...] = ()) -> Path:
    """One line naming ``flag`` unless ``path`` can be written as a ``kind`` ("folder" or "file"), checked before any
    work: a folder is an existing folder or a path whose nearest existing ancestor is a folder; a file's folder is
    such a path and the file itself, if it exists, is a regular file. Writability is probed by creating (and
    removing) a file in the nearest existing folder, so a read-only mount is refused even to root. Nothing is left
    behind. ``suffixes``: the file's accepted endings (e.g. ``(".png",)``)."""
    import errno
    import os
    import tempfile

    path = Path(path)
    if path.is_symlink() and not path.exists():
        raise SurrealistError(f"{flag} {path}: a link to {os.readlink(path)}, which does not exist")
    if kind == "file":
        if suffixes and path.suffix.lower() not in suffixes:
            raise SurrealistError(f"{flag} {path}: expected a {' or '.join(suffixes)} file")
        if path.exists() and not path.is_file():
            raise SurrealistError(f"{flag} {path}: exists and is not a regular file")
        folder = path.parent
    else:
        if path.exists() and not path.is_dir():
            raise SurrealistError(f"{flag} {path}: exists and is not a folder")
        folder = path
    existing = folder
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise SurrealistError(f"{flag} {path}: {existing} is a file, not a folder")
    try:
        fd, probe = tempfile.mkstemp(prefix=".surrealist-probe-", dir=existing)
        os.close(fd)
        os.unlink(probe)
    except OSError as err:
        reason = {errno.EROFS: "a read-only file system", errno.EACCES: "permission denied",
                  errno.ENOSPC: "no space left on the device"}.get(err.errno, err.strerror or str(err))
        raise SurrealistError(f"{flag} {path}: cannot write in {existing} ({reason})") from None
    return path


__all__ = ["BUFFER_HELP", "CASE_STUDY_DEFAULTS", "DASK_HELP", "FLYING_COMMANDS", "GenerateOptions", "OUT_PATTERN",
           "PROBLEM_DEFAULTS", "PROBLEM_ENVS", "ReplicateOptions", "SCREEN_RULES", "SearchOptions",
           "WORKERS_HELP", "WORKERS_ONE_HELP", "add_buffer_argument", "add_dask_argument", "add_out_argument",
           "add_random_seed_argument", "add_workers_argument", "check_at_least", "check_writable", "default_out",
           "out_help", "race_stages", "refuse_argument", "refuse_inapplicable", "refuse_leftover", "refuse_positional",
           "refuse_workers_with_dask"]
