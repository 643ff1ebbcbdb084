"""A tool's request to the simulation server, checked field by field before anything is done with it.

The tool is untrusted: a request is a JSON object (``shim/surrealist_compete_wire.py``) and each field is checked
for its type and bounds here; :class:`BadRequest` carries a short line naming the field, which the tool gets back and
``flights.csv`` keeps. It never quotes what the tool sent beyond a type name, so no file content travels back.

Example::

    >>> check({"op": "fly", "agent": "DockerAgent", "api": "AerialistTest", "cwd": "/t", "test": {}, "runs": 2},
    ...       budget=10).runs
    2
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

AGENTS = ("LocalAgent", "DockerAgent", "K8sAgent")
APIS = ("DroneTest", "AerialistTest")
MAX_PATH = 4096  # characters of the tool's working folder
MAX_NOTES = 32  # compat notes per request
MAX_NOTE = 500  # characters of a note
_FIELDS = frozenset(("op", "agent", "api", "cwd", "test", "runs", "compat"))


class BadRequest(Exception):
    """A request the server does not act on; ``str()`` is one short line naming the field."""


@dataclass(frozen=True, slots=True)
class FlyRequest:
    """A checked ``fly`` request: who asks, the tool's working folder, the Aerialist test, the runs wanted (1 to the
    budget) and the shim's compat notes."""

    agent: str
    api: str
    cwd: str
    test: Mapping
    runs: int
    compat: tuple[str, ...]


def check(message, budget: int) -> FlyRequest:
    """The request as a :class:`FlyRequest`, or BadRequest naming the first field that is wrong."""
    if not isinstance(message, dict):
        raise BadRequest("bad request: not a JSON object")
    if message.get("op") != "fly":
        raise BadRequest("bad request: field 'op': expected 'fly'")
    unknown = sorted(set(message) - _FIELDS)
    if unknown:
        raise BadRequest(f"bad request: unknown field {unknown[0][:40]!r}")
    agent, api = _choice(message, "agent", AGENTS), _choice(message, "api", APIS)
    cwd = message.get("cwd")
    if not isinstance(cwd, str) or not cwd or len(cwd) > MAX_PATH or "\0" in cwd:
        raise BadRequest(f"bad request: field 'cwd': expected a path of 1 to {MAX_PATH} characters")
    test = message.get("test")
    if not isinstance(test, dict):
        raise BadRequest(f"bad request: field 'test': expected an Aerialist test (an object), got a "
                         f"{type(test).__name__}")
    runs = message.get("runs")
    if isinstance(runs, bool) or not isinstance(runs, int) or not 1 <= runs <= budget:
        raise BadRequest(f"bad request: field 'runs': expected a whole number from 1 to the budget ({budget}), "
                         f"got {runs if isinstance(runs, int) else type(runs).__name__}"[:160])
    compat = message.get("compat", [])
    if not isinstance(compat, list) or len(compat) > MAX_NOTES or \
            not all(isinstance(n, str) and len(n) <= MAX_NOTE for n in compat):
        raise BadRequest(f"bad request: field 'compat': expected at most {MAX_NOTES} strings of at most {MAX_NOTE} "
                         f"characters")
    return FlyRequest(agent, api, cwd, MappingProxyType(test), runs, tuple(compat))


def _choice(message: dict, field: str, allowed: tuple[str, ...]) -> str:
    value = message.get(field)
    if value not in allowed:
        raise BadRequest(f"bad request: field {field!r}: expected one of {', '.join(allowed)}")
    return value
