"""A suite of distinct failures as files: Aerialist YAMLs ready to re-run on PX4, a table, and a top view of each.

``export_suite(suite, folder, order)`` writes each member as ``failure-01.yaml``, ``failure-02.yaml``, ... in the
given order (the best first: the 2025 edition evaluates the first 20 a tool wrote), each loading in Aerialist master
and 0.2.x alike (:func:`~surrealist_gym.aerialist.save_test`). The mission, parameter and command files are copied
into ``folder/case_studies/`` (:func:`~surrealist_gym.results.export_test`), so each YAML names them by the relative
path the competition's own YAMLs use; the folder's README says to run Aerialist from it, and the folder moves as a
whole.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Sequence

from ..results import export_test
from .suite import Member, Suite, layout_distance, trajectory_distance


def member_name(index: int) -> str:
    """The file stem of the member at ``index`` (0-based): ``failure-01``, ``failure-02``, ..."""
    return f"failure-{index + 1:02d}"


def export_suite(suite: Suite, folder, order: Sequence[int] | None = None,
                 expected: Sequence[float] | None = None) -> list[Path]:
    """Write the members in ``order`` (indices into ``suite.members``; default: as they are) as ``failure-NN.yaml``
    with their files (:func:`~surrealist_gym.results.export_test`), plus ``suite.csv`` (with each member's
    ``expected`` test score, when given); returns the YAMLs in that order."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    order = list(range(len(suite.members)) if order is None else order)
    paths = []
    for k, i in enumerate(order):
        path = folder / (member_name(k) + ".yaml")
        export_test(suite.members[i].test, path)
        paths.append(path)
    with open(folder / "suite.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["test", "evaluation", "status", "distance_m", "points", "obstacles",
                         "nearest_flight_m", "nearest_layout_m", "expected_score"])
        for k, i in enumerate(order):
            member = suite.members[i]
            flight, layout = _nearest(member, suite.members)
            writer.writerow([member_name(k), member.evaluation, member.status, f"{member.distance:.3f}",
                             member.points, len(member.test.obstacles), _fmt(flight), _fmt(layout),
                             "" if expected is None else f"{expected[i]:.4f}"])
    return paths


def _nearest(member: Member, members) -> tuple[float, float]:
    """The member's smallest flight and layout distances to the other members [m] (inf when it is alone)."""
    others = [m for m in members if m is not member]
    if not others:
        return math.inf, math.inf
    return (min(trajectory_distance(member.trajectory, m.trajectory) for m in others),
            min(layout_distance(member.test.obstacles, m.test.obstacles) for m in others))


def _fmt(value: float) -> str:
    return "" if not math.isfinite(value) else f"{value:.2f}"
