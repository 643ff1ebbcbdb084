"""Labelled sets of Aerialist tests: what another system (PX4 SITL, a field campaign) measured on each test.

Two forms:

- a tests CSV: ``test_id`` (or ``test``), ``obstacles`` (a JSON list of ``{l, w, h, x, y, z, r}`` as in an
  Aerialist YAML), ``px4_min_distance_2d``, optionally ``px4_result`` and ``n_obstacles``, flown on a base test YAML
  that gives the mission and parameters (default ``<CSV folder>/../case_studies/mission1.yaml``);
- a folder of Aerialist YAMLs with a labels file (default ``<folder>/labels.csv``): ``test`` (the YAML's name),
  ``px4_min_distance_2d``, optionally ``mission`` (checked against the YAML's mission file, by file stem),
  ``n_obstacles``, ``px4_result`` or ``status``, ``airborne_s`` (or ``duration_s``: takeoff start to touchdown).

Results: ``flown``/``success``; ``no_result`` (Aerialist's timeout: no metric)/``timeout``; ``collision``. A
distance may be empty only for a timeout. Rows are numbered as in a spreadsheet: the header is row 1.

Example::

    >>> lset = load_labelled_set("camba-collection")            # doctest: +SKIP
    >>> lset.labels[0].distance, lset.tests[0].mission_file     # doctest: +SKIP
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

from ..aerialist import load_test
from ..errors import InvalidLabels, InvalidTestCase, regular_file
from ..testcase import Obstacle, TestCase

# their result (lower case) -> normalised result
RESULTS = {"flown": "flown", "success": "flown", "no_result": "timeout", "timeout": "timeout",
           "collision": "collision"}
# field -> accepted column names, first preferred
COLUMNS = {"id": ("test_id", "test"), "distance": ("px4_min_distance_2d", "min_distance_2d"),
           "result": ("px4_result", "status", "result"), "airborne": ("airborne_s", "duration_s")}


@dataclass(frozen=True, slots=True)
class Label:
    """What the labels say of one test: result, 2-D competition distance [m] (nan without a result), airborne [s]."""

    test_id: str
    result: str
    distance: float
    airborne_s: float = math.nan
    row: int = 0  # row in the labels file (the header is row 1)


@dataclass(frozen=True, slots=True)
class LabelledSet:
    """Labelled tests ready to fly: ``labels[i]`` belongs to ``tests[i]``."""

    source: str
    labels_file: str
    labels: tuple[Label, ...]
    tests: tuple[TestCase, ...]

    def __len__(self) -> int:
        return len(self.labels)

    def subset(self, limit: int | None = None, every: int = 1) -> "LabelledSet":
        """Every ``every``-th test, at most ``limit`` of them."""
        end = None if limit is None else limit * every
        return replace(self, labels=self.labels[:end:every], tests=self.tests[:end:every])


def load_labelled_set(path, labels=None, mission=None) -> LabelledSet:
    """Read a labelled set: a tests CSV (flown on the base test ``mission``) or a folder of YAMLs with ``labels``.

    Args:
        path: a CSV with an ``obstacles`` column, or a folder of Aerialist YAMLs.
        labels: the folder's labels file (default ``<folder>/labels.csv``).
        mission: the CSV's base test YAML (default ``<CSV folder>/../case_studies/mission1.yaml``).

    Raises:
        InvalidLabels: one line naming the file, row and field.
    """
    path = Path(path)
    if path.is_dir():
        return _load_folder(path, Path(labels) if labels is not None else path / "labels.csv")
    regular_file(path, "labels file or folder", InvalidLabels)
    if labels is not None:
        raise InvalidLabels(f"{path}: a separate labels file goes with a folder of YAMLs, not with a tests CSV")
    base = Path(mission) if mission is not None else path.resolve().parent.parent / "case_studies" / "mission1.yaml"
    if not base.is_file():
        raise InvalidLabels(f"{base}: base test YAML (mission and parameters) of {path} not found; "
                            f"give one with --mission YAML")
    return _load_csv(path, load_test(base))


def _read_rows(path: Path, needed: Sequence[str]) -> tuple[dict[str, str | None], list[tuple[int, dict]]]:
    """The column name used for each field (None if absent) and the rows with their row numbers."""
    regular_file(path, "labels file", InvalidLabels)
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []
            rows = [(reader.line_num, row) for row in reader]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InvalidLabels(f"{path}: cannot read the labels ({err})") from err
    columns = {field: next((c for c in names if c in header), None) for field, names in COLUMNS.items()}
    for field in needed:
        names = COLUMNS.get(field, (field,))
        if columns.get(field, field if field in header else None) is None:
            raise InvalidLabels(f"{path}: row 1 (header): missing column {names[0]!r}"
                                + (f" (or {', '.join(map(repr, names[1:]))})" if len(names) > 1 else ""))
    return columns, rows


def _number(path, n, column, value, allow_empty=False) -> float:
    text = (value or "").strip()
    if not text and allow_empty:
        return math.nan
    try:
        number = float(text)
    except ValueError:
        number = math.nan
    if not math.isfinite(number) or number < 0:
        raise InvalidLabels(f"{path}: row {n}, field {column!r}: expected a non-negative number, got {text!r}")
    return number


def _label(path: Path, n: int, row: dict, columns: dict, seen: dict) -> Label:
    test_id = (row.get(columns["id"]) or "").strip()
    if not test_id:
        raise InvalidLabels(f"{path}: row {n}, field {columns['id']!r}: empty test name")
    if test_id in seen:
        raise InvalidLabels(f"{path}: row {n}, field {columns['id']!r}: test {test_id!r} is labelled twice "
                            f"(first at row {seen[test_id]})")
    seen[test_id] = n
    result = "flown"
    if columns["result"] and (row.get(columns["result"]) or "").strip():
        raw = row[columns["result"]].strip()
        result = RESULTS.get(raw.lower())
        if result is None:
            raise InvalidLabels(f"{path}: row {n}, field {columns['result']!r}: unknown result {raw!r} "
                                f"(expected one of {', '.join(RESULTS)})")
    distance = _number(path, n, columns["distance"], row.get(columns["distance"]), allow_empty=result == "timeout")
    airborne = math.nan
    if columns["airborne"]:
        airborne = _number(path, n, columns["airborne"], row.get(columns["airborne"]), allow_empty=True)
    return Label(test_id, result, distance, airborne, n)


def _check_count(path, n, row, test: TestCase) -> None:
    if (row.get("n_obstacles") or "").strip():
        count = _number(path, n, "n_obstacles", row["n_obstacles"])
        if count != len(test.obstacles):
            raise InvalidLabels(f"{path}: row {n}, field 'n_obstacles': {row['n_obstacles'].strip()} but the test "
                                f"has {len(test.obstacles)} obstacles")


def _check_mission(path, n, row, test: TestCase, where: str) -> None:
    """A ``mission`` column names the mission file the test flies (compared by file stem, case-insensitive)."""
    value = (row.get("mission") or "").strip()
    flies = Path(test.mission_file).stem if test.mission_file else None
    if value and (flies is None or Path(value).stem.lower() != flies.lower()):
        raise InvalidLabels(f"{path}: row {n}, field 'mission': {value!r} but {where} flies "
                            f"{Path(test.mission_file).name if flies else 'no mission file'}")


def _load_csv(path: Path, base: TestCase) -> LabelledSet:
    columns, rows = _read_rows(path, ("id", "obstacles", "distance"))
    labels, tests, seen = [], [], {}
    for n, row in rows:
        label = _label(path, n, row, columns, seen)
        try:
            raw = json.loads(row.get("obstacles") or "")
            if not isinstance(raw, list) or not all(isinstance(o, dict) for o in raw):
                raise ValueError("not a list of {l, w, h, x, y, z, r}")
            test = base.with_obstacles(Obstacle(**o) for o in raw)
        except (ValueError, TypeError, InvalidTestCase) as err:
            raise InvalidLabels(f"{path}: row {n}, field 'obstacles': {err}") from err
        except RecursionError:
            raise InvalidLabels(f"{path}: row {n}, field 'obstacles': JSON nested too deeply") from None
        _check_count(path, n, row, test)
        _check_mission(path, n, row, test, "the base test")
        labels.append(label)
        tests.append(test)
    if not labels:
        raise InvalidLabels(f"{path}: no labelled tests")
    return LabelledSet(str(path), str(path), tuple(labels), tuple(tests))


def _load_folder(folder: Path, labels_file: Path) -> LabelledSet:
    if not labels_file.exists():  # anything else that is not a regular file: _read_rows says what it is
        raise InvalidLabels(f"{labels_file}: labels file not found (a folder of YAMLs needs labels.csv, "
                            f"or --labels FILE)")
    columns, rows = _read_rows(labels_file, ("id", "distance"))
    yamls = {p.stem: p for p in sorted(folder.glob("*.y*ml")) if p.suffix in (".yaml", ".yml")}
    labels, tests, seen = [], [], {}
    for n, row in rows:
        label = _label(labels_file, n, row, columns, seen)
        stem = label.test_id[:-5] if label.test_id.endswith(".yaml") else label.test_id
        if stem not in yamls:
            raise InvalidLabels(f"{labels_file}: row {n}, field {columns['id']!r}: no test YAML {stem}.yaml "
                                f"in {folder}")
        test = load_test(yamls[stem])
        _check_count(labels_file, n, row, test)
        _check_mission(labels_file, n, row, test, yamls[stem].name)
        labels.append(replace(label, test_id=stem))
        tests.append(test)
    unlabelled = sorted(set(yamls) - {label.test_id for label in labels})
    if unlabelled:
        raise InvalidLabels(f"{yamls[unlabelled[0]]}: no label row in {labels_file}"
                            + (f" ({len(unlabelled) - 1} more YAMLs unlabelled)" if len(unlabelled) > 1 else ""))
    if not labels:
        raise InvalidLabels(f"{labels_file}: no labelled tests")
    return LabelledSet(str(folder), str(labels_file), tuple(labels), tuple(tests))
