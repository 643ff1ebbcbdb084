"""The tests a tool wrote: found in files and folders (a ``surrealist compete`` output folder stands for its tool's
output folder), loaded and checked against the competition's rules, each bad one a one-line error naming its file."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

from ..errors import InvalidTestCase, SurrealistError
from ..testcase import TestCase

__all__ = ["COMPETE_SUMMARY", "compete_summary", "find_tests", "load_tests", "rule_broken", "tool_output"]

COMPETE_SUMMARY = "summary.json"  # what ``surrealist compete`` writes beside the tool's folder
_SUFFIXES = (".yaml", ".yml")


def compete_summary(folder) -> dict | None:
    """The ``summary.json`` of a ``surrealist compete`` output folder (the tool, case study, budget, output folder,
    ...), or None when the folder is not one."""
    from ..results import read_summary

    try:
        summary = read_summary(os.fspath(folder), COMPETE_SUMMARY)
    except SurrealistError:
        return None
    keys = {"tool", "case_study", "budget", "output_folder"}
    return summary if isinstance(summary, dict) and keys <= summary.keys() else None


def tool_output(folder) -> Path:
    """The folder of tests that ``folder`` stands for: a ``surrealist compete`` output folder (its ``summary.json``
    names the tool's output folder, inside its ``tool/``) stands for the tool's output folder; any other folder for
    itself. A compete folder whose tool named no output folder, or whose output folder is gone, is a one-line
    error."""
    path = Path(os.fspath(folder))
    summary = compete_summary(path)
    if summary is None:
        return path
    named = summary["output_folder"]
    if not named:
        raise SurrealistError(f"{path}: a compete output folder whose tool wrote no output folder "
                              f"({summary.get('problem') or 'no tests'})")
    named = Path(str(named))
    parts = named.parts
    candidates = [named] + [path.joinpath(*parts[i:]) for i, part in enumerate(parts) if part == "tool"]
    found = next((c for c in candidates if c.is_dir()), None)
    if found is None:
        raise SurrealistError(f"{path}: the tool's output folder its {COMPETE_SUMMARY} names ({named}) is gone")
    return found


def find_tests(paths: Sequence) -> list[Path]:
    """The YAML files named by ``paths``: files as given, folders' ``*.yaml``/``*.yml`` (not recursive), each once; a
    ``surrealist compete`` output folder's are those of the tool's output folder (:func:`tool_output`)."""
    out, seen = [], set()
    for given in paths:
        path = Path(os.fspath(given))
        if path.is_dir():
            path = tool_output(path)
            found = sorted(p for p in path.iterdir() if p.suffix.lower() in _SUFFIXES and p.is_file())
            if not found:
                raise SurrealistError(f"{os.fspath(given)}: no test YAML (*.yaml, *.yml) in this folder")
        elif path.is_file():
            found = [path]
        else:
            raise SurrealistError(f"{os.fspath(given)}: no such file or folder")
        for p in found:
            if p.resolve() not in seen:
                seen.add(p.resolve())
                out.append(p)
    return out


def load_tests(paths: Sequence, any_layout: bool = False) -> list[tuple[Path, TestCase]]:
    """Load the tests named by ``paths`` (see :func:`find_tests`) and check them; unless ``any_layout``, against
    the competition's rules (:func:`~surrealist_gym.competition.rules.violations`). Raises a one-line
    :class:`~surrealist_gym.errors.InvalidTestCase` naming the file and field of the first bad test."""
    from ..aerialist import load_test

    out = []
    for path in find_tests(paths):
        test = load_test(path)
        if test.mission is None or not any(item.has_position for item in test.mission.items):
            raise InvalidTestCase(f"{path}: mission_file: no mission item with a position to fly to")
        if not any_layout and (broken := rule_broken(test)):
            raise InvalidTestCase(f"{path}: {broken}; --any-layout skips the competition's rules")
        out.append((path, test))
    return out


def rule_broken(test: TestCase, rules=None) -> str:
    """The first of the competition's rules (``rules``, default :data:`~surrealist_gym.competition.rules.RULES`) the
    test breaks (and how many more), or "" when it keeps them all."""
    from .rules import RULES, violations

    broken = violations(test, rules or RULES)
    return broken[0] + (f" (and {len(broken) - 1} more)" if len(broken) > 1 else "") if broken else ""
