"""An Aerialist test as Aerialist's ``to_dict()`` gives it, written as a YAML that surrealist-gym's ``load_test``
reads as it is (our loader reads Aerialist's YAML as both generations write it: docs/aerialist-yaml.md).

Aerialist resolves a relative path against the working folder of the process that reads it (COMPETITION.md
section 4), so a test sent from a tool's process names its paths against that tool's folder: they are made absolute
here. The ``assertion`` and ``agent`` sections are dropped: a competition test names no reference flight, and the
server decides the runs.

Example::

    >>> aerialist_doc({"robot": {"port": 14541, "mission_file": "case_studies/mission1.plan"}}, "/tool")
    {'robot': {'port': 14541, 'mission_file': '/tool/case_studies/mission1.plan'}}
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

from ...aerialist import FILE_FIELDS
from ...errors import InvalidTestCase


def aerialist_doc(test: Mapping, cwd) -> dict:
    """The Aerialist test dict with its relative file paths made absolute against ``cwd``, without ``assertion``
    and ``agent``."""
    if not isinstance(test, Mapping):
        raise InvalidTestCase(f"expected an Aerialist test (a mapping of sections), got {test!r}")
    doc = {key: value for key, value in test.items() if key not in ("assertion", "agent")}
    for section, keys in FILE_FIELDS.items():
        part = doc.get(section)
        if isinstance(part, Mapping):
            doc[section] = {**part, **{key: _absolute(part[key], cwd, key) for key in keys
                                       if part.get(key) is not None}}
    return doc


def outside(test: Mapping, cwd, roots) -> str | None:
    """The first file field of the test whose file (links resolved) lies in none of the folders ``roots``, else None
    (always None without roots)."""
    if not roots:
        return None
    doc = aerialist_doc(test, cwd)
    for section, keys in FILE_FIELDS.items():
        part = doc.get(section)
        for key in keys if isinstance(part, Mapping) else ():
            if part.get(key) is not None and not any(Path(os.path.realpath(part[key])).is_relative_to(root)
                                                     for root in roots):
                return key
    return None


def write_test(test: Mapping, cwd, path) -> Path:
    """Write the Aerialist test as a YAML at ``path`` (``load_test`` reads it); returns the path."""
    import yaml

    path = Path(path)
    with open(path, "w", encoding="utf-8") as f:
        yaml.safe_dump(aerialist_doc(test, cwd), f, sort_keys=False)
    return path


def _absolute(value, cwd, key: str) -> str:
    if not isinstance(value, str):
        raise InvalidTestCase(f"field {key!r}: expected a file path, got {value!r}")
    return value if os.path.isabs(value) else os.path.normpath(os.path.join(os.fspath(cwd), value))
