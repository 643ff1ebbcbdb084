"""The ``surrealist`` command line: one module per sub-command, each with ``add_arguments`` and ``run``.

This is the only place that prints. A :class:`~surrealist_gym.errors.SurrealistError`, and a command line that
argparse refuses, becomes one line on stderr and exit code 2; Ctrl-C exits with 130.
"""
from __future__ import annotations

import _thread
import argparse
import importlib
import os
import signal
import sys
import threading
import warnings
from contextlib import contextmanager
from pathlib import Path

from ..errors import ALLOW_OUTSIDE_ENV, SurrealistError

# sub-command -> (module, one-line help); modules are imported only when their command runs.
COMMANDS = {
    "inspect": ("surrealist_gym.cli.inspect", "describe a flight log (.ulg, .tlog, .bin) and plot it"),
    "simulate": ("surrealist_gym.cli.simulate", "fly a test case in the simulator and report each run"),
    "calibrate": ("surrealist_gym.cli.calibrate", "fit a UAV profile to real flight logs (what PX4 parameters do "
                                                  "not fix)"),
    "replicate": ("surrealist_gym.cli.replicate", "find obstacles that make the simulated flight match a real log"),
    "generate": ("surrealist_gym.cli.generate", "find nearby tests that make the UAV unsafe or crash"),
    "compare": ("surrealist_gym.cli.compare", "run several search agents on the same problems and compare them"),
    "train": ("surrealist_gym.cli.train", "train an RL policy (--algorithm ppo or sac) across generated problems"),
    "surrogate": ("surrealist_gym.cli.surrogate", "train or evaluate a surrogate model on evaluation stores"),
    "fidelity": ("surrealist_gym.cli.fidelity", "fly a labelled set of tests and report how far our UAV agrees"),
    "predict": ("surrealist_gym.cli.predict", "predict PX4 SITL's verdict on tests from our simulator's flights of "
                                              "them"),
    "evaluate": ("surrealist_gym.cli.competition.evaluate",
                 "re-fly a suite of tests N times: failure odds, points, diversity"),
    "compete": ("surrealist_gym.cli.competition.compete",
                "run a UAV Testing Competition tool, unedited, on our simulator"),
    "leaderboard": ("surrealist_gym.cli.competition.leaderboard",
                    "run competition tools on case studies and rank them as an edition did, with PX4's published "
                    "results beside"),
    "export-tool": ("surrealist_gym.cli.competition.export_tool",
                    "write a competition tool that picks its tests on our simulator"),
}


# other names a sub-command answers to (the names it had before)
ALIASES = {"train": ["train-ppo"]}


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose errors are one line like any other bad input (argparse prints the usage block
    before its message); its sub-command parsers are of this class too. ``--help`` still prints the usage."""

    def error(self, message: str):
        raise SurrealistError(f"{self.prog}: {' '.join(message.split())}")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="surrealist", description="Test drones in the neighbourhood of real flights.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module, help_text) in COMMANDS.items():
        cmd = sub.add_parser(name, help=help_text, description=help_text, aliases=ALIASES.get(name, []))
        cmd.set_defaults(_module=module)
        importlib.import_module(module).add_arguments(cmd)
        cmd.add_argument("--allow-outside", action="append", default=[], metavar="FOLDER",
                         help="let tests read files under FOLDER (default: only under the YAML's folder and the "
                              "working folder; docs/aerialist-yaml.md); may be given more than once")
    return parser


def _given(parser: argparse.ArgumentParser, command: str, argv: list[str]) -> frozenset[str]:
    """The options typed on the command line, even at their defaults, each by its full name (``--obst`` is
    ``--obstacles``, as argparse reads an unambiguous prefix)."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    known = sub.choices[command]._option_string_actions
    given = set()
    for arg in argv:
        if not arg.startswith("--") or arg == "--":
            continue
        flag = arg.split("=", 1)[0]
        if flag not in known:
            matches = [o for o in known if o.startswith(flag)]
            flag = matches[0] if len(matches) == 1 else flag
        given.add(flag)
    return frozenset(given)


def _version() -> str:
    from .. import __version__
    return __version__


def main(argv: list[str] | None = None) -> int:
    """Run ``surrealist`` on ``argv`` (default: the command line); returns the exit code, 2 for refused input."""
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        parser = _parser()
        args = parser.parse_args(argv)
    except SurrealistError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args._flags = _given(parser, args.command, argv)
    warnings.simplefilter("ignore", DeprecationWarning)
    warnings.formatwarning = lambda msg, category, *a, **k: f"warning: {msg}\n"
    allowed = os.environ.get(ALLOW_OUTSIDE_ENV)
    try:
        from ..sim.config import default_physics

        default_physics()  # a bad $SURREALIST_PHYSICS is refused before any work
        _allow_outside(args.allow_outside)
        with _ctrl_c_answered_once():
            return importlib.import_module(args._module).run(args) or 0
    except SurrealistError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    finally:
        if allowed is None:
            os.environ.pop(ALLOW_OUTSIDE_ENV, None)
        else:
            os.environ[ALLOW_OUTSIDE_ENV] = allowed


@contextmanager
def _ctrl_c_answered_once():
    """While a command runs in the main thread, Ctrl-C raises KeyboardInterrupt once. A second Ctrl-C while the command
    stores what it has and stops its workers is ignored, and so is one during the interpreter's exit (either would end
    the process by the signal, exit code -2, mid clean-up). A Ctrl-C that lands in a C library's callback into Python
    (llvmlite's, while numba loads its cache), where no exception can propagate, is raised again once that returns."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield  # not ours to answer (Ctrl-C ignored by the parent, or a caller's own handler)
        return
    state = {"answered": False, "retry": None}

    def on_ctrl_c(signum, frame):
        if not state["answered"]:
            state["answered"] = True
            raise KeyboardInterrupt

    def lost(unraisable):
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            state["answered"] = False
            state["retry"] = threading.Timer(0.05, _thread.interrupt_main)
            state["retry"].start()
        else:
            sys.__unraisablehook__(unraisable)

    signal.signal(signal.SIGINT, on_ctrl_c)
    sys.unraisablehook = lost
    try:
        yield
    finally:
        if state["retry"] is not None:
            state["retry"].cancel()
        sys.unraisablehook = sys.__unraisablehook__
        signal.signal(signal.SIGINT, signal.SIG_IGN if state["answered"] else signal.default_int_handler)
        if state["answered"]:
            # A KeyboardInterrupt that ended code run from a string (a dataclass's or numba's generated source) leaves
            # CPython's "unhandled Ctrl-C" flag set although the command caught it, and `python -m` then ends by
            # SIGINT (exit code -2) instead of 130; every string evaluation starts by clearing that flag.
            exec("pass", {})  # noqa: S102 - a constant


def _allow_outside(folders: list[str]) -> None:
    """``--allow-outside``: each an existing folder, added to ``$SURREALIST_ALLOW_OUTSIDE`` for this command (its
    worker processes inherit it)."""
    resolved = []
    for folder in folders:
        path = Path(folder).expanduser()
        if not path.is_dir():
            raise SurrealistError(f"--allow-outside {folder}: " + ("not a folder" if path.exists() else "not found"))
        resolved.append(str(path.resolve()))
    if resolved:
        os.environ[ALLOW_OUTSIDE_ENV] = os.pathsep.join(filter(None, [os.environ.get(ALLOW_OUTSIDE_ENV), *resolved]))


if __name__ == "__main__":
    sys.exit(main())
