"""Errors for bad input: each message is one line naming the file or field, the bad value and what was expected.

The command line turns any :class:`SurrealistError` into exit code 2 with its message on stderr.
"""
from __future__ import annotations


class SurrealistError(Exception):
    """Base class of every error caused by bad input or a missing optional dependency."""


class LogFormatError(SurrealistError):
    """A flight log cannot be read, or lacks the data asked for (e.g. no valid local position)."""


class MissionError(SurrealistError):
    """A mission file (.plan, QGC WPL) is invalid or holds items that cannot be flown."""


class InvalidTestCase(SurrealistError):
    """A test case (or its YAML) is invalid: wrong field, non-positive size, overlapping obstacles, missing file."""


class InvalidProfile(SurrealistError):
    """A UAV profile (preset name or YAML) is unknown or holds an unknown key or an out-of-range value."""


class InvalidLabels(SurrealistError):
    """A labelled set for ``surrealist fidelity`` is invalid: missing column, unknown test, non-numeric value."""


class SimulationError(SurrealistError):
    """A simulation could not be set up from the given test case."""


class UnknownAgent(SurrealistError):
    """An agent name that is not registered."""


class DependencyNotInstalled(SurrealistError):
    """An optional dependency is missing; the message names the pip command that installs it."""


def one_line(err: Exception, limit: int = 80) -> str:
    """A foreign exception's text for a SurrealistError message: on one line (SQLite and pymavlink quote text with
    its line breaks), at most ``limit`` characters."""
    return " ".join(str(err).split())[:limit]


class InfrastructureError(SurrealistError):
    """The machinery that runs simulations failed (a worker or pool died, a scheduler was lost), not the simulation:
    never stored as a result; the search stops and ``--resume`` re-flies what is missing."""


def regular_file(path, what: str, error: type[SurrealistError] = SurrealistError, empty_ok: bool = True) -> str:
    """``path`` (as a string) if it names an existing regular file, else a one-line ``error``: missing, or what it is
    instead (a folder, a FIFO, a device, a socket), or empty when ``empty_ok`` is False. Checked with ``stat``, which
    does not open the file, so an input that is a FIFO or a device is refused instead of blocking its reader. Every
    reader of an input file calls it before opening it. ``what`` names the input ("log file", "test case")."""
    import os
    import stat

    name = os.fspath(path)
    try:
        info = os.stat(name)
    except OSError as err:
        raise error(f"{name}: cannot read {what} ({err.strerror or err})") from None
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode)
                else "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else "a special file")
        raise error(f"{name}: {kind}, not a regular file ({what} expected)")
    if not empty_ok and info.st_size == 0:
        raise error(f"{name}: an empty file, no {what} in it")
    return name


def text_lines(path, error: type[SurrealistError] = SurrealistError) -> list[str]:
    """The lines of a UTF-8 text file (:func:`regular_file` first), else a one-line ``error`` naming the file."""
    from pathlib import Path

    regular_file(path, "file", error)
    try:
        return Path(path).read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as err:
        raise error(f"{path}: not UTF-8 text (byte {err.start})") from None
    except OSError as err:
        raise error(f"{path}: cannot read ({err.strerror})") from None
