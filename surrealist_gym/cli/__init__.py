"""The ``surrealist`` command line: one module per sub-command, each with ``add_arguments`` and ``run``.

This is the only place that prints. A :class:`~surrealist_gym.errors.SurrealistError`, and a command line that
argparse refuses, becomes one line on stderr and exit code 2; Ctrl-C exits with 130.
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from ..errors import SurrealistError

# sub-command -> (module, one-line help); modules are imported only when their command runs.
COMMANDS = {
    "inspect": ("surrealist_gym.cli.inspect", "describe a flight log (.ulg, .tlog, .bin) and plot it"),
    "simulate": ("surrealist_gym.cli.simulate", "fly a test case in the simulator and report each run"),
    "calibrate": ("surrealist_gym.cli.calibrate", "fit a UAV profile to real flight logs (what PX4 parameters do "
                                                  "not fix)"),
    "replicate": ("surrealist_gym.cli.replicate", "find obstacles that make the simulated flight match a real log"),
    "generate": ("surrealist_gym.cli.generate", "find nearby tests that make the UAV unsafe or crash"),
    "compare": ("surrealist_gym.cli.compare", "run several search agents on the same problems and compare them"),
    "train-ppo": ("surrealist_gym.cli.train_ppo", "train an RL policy (PPO/SAC) across generated problems"),
    "surrogate": ("surrealist_gym.cli.surrogate", "train or evaluate a surrogate model on evaluation stores"),
    "fidelity": ("surrealist_gym.cli.fidelity", "fly a labelled set of tests and report how far our UAV agrees"),
    "evaluate": ("surrealist_gym.cli.evaluate", "re-fly a suite of tests N times: failure odds, points, diversity"),
    "compete": ("surrealist_gym.cli.compete", "run a UAV Testing Competition tool, unedited, on our simulator"),
    "export-tool": ("surrealist_gym.cli.export_tool", "write a competition tool that picks its tests on our simulator"),
}


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
        cmd = sub.add_parser(name, help=help_text, description=help_text)
        cmd.set_defaults(_module=module)
        importlib.import_module(module).add_arguments(cmd)
    return parser


def _version() -> str:
    from .. import __version__
    return __version__


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = _parser().parse_args(argv)
    except SurrealistError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args._flags = frozenset(a.split("=", 1)[0] for a in argv if a.startswith("--"))  # the options given explicitly
    warnings.simplefilter("ignore", DeprecationWarning)
    warnings.formatwarning = lambda msg, category, *a, **k: f"warning: {msg}\n"
    try:
        return importlib.import_module(args._module).run(args) or 0
    except SurrealistError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
