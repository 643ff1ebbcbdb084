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
