"""The competition's published results on PX4 SITL + Gazebo: the ground truth a leaderboard on our simulator is held
against.

Source: the editions' reports (skhatiri/UAV-Testing-Competition, ``reports/``), as ``shared/COMPETITION.md`` section 5
transcribes them. 2024 (SBFT, Table 1): per tool and case study, the tests the tool reported failing and its suite
score; CS2 and CS3 were derived from the sample case studies ``mission2`` and ``mission3``. 2025 (ICST, SBFT): per tool
and case study, the tests reported, how many of the first 20 failed in the 3-run evaluation, the failure score and
the diversity; its case studies are not public, so only the share of re-run tests that failed again compares.

Example:
    >>> published_name("deephyperion"), published_name("snippets")
    ('DeepHyperion-UAV', None)
    >>> round(rerun_share(PUBLISHED["2025"]["PALM"]), 3)   # 1 + 20 + 19 of 20 + 20 + 20
    0.667
"""
from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["CASE_STUDIES", "PUBLISHED", "PublishedCell", "published_name", "rerun_share"]


@dataclass(frozen=True, slots=True)
class PublishedCell:
    """One (tool, case study) of a report: tests reported, tests of the evaluated ones that failed again (2025; None
    where the report gives none), the score (2024: the suite score; 2025: the failure score) and diversity (2025)."""

    reported: int
    score: float
    failing: int | None = None
    diversity: float | None = None

    @property
    def evaluated(self) -> int:
        """Tests the organisers re-ran: the first 20 of those reported (fewer when fewer were reported)."""
        return min(20, self.reported)


def _c(reported: int, score: float, failing: int | None = None, diversity: float | None = None) -> PublishedCell:
    return PublishedCell(reported, score, failing, diversity)


#: edition -> tool -> case study -> cell. The public case studies are the sample ones (mission2 -> CS2, mission3 -> CS3
#: in 2024); the others are named as the reports name them.
PUBLISHED: dict[str, dict[str, dict[str, PublishedCell]]] = {
    "2024": {
        "WOGAN-UAV": {"CS2": _c(61, 12.55), "CS3": _c(72, 14.00), "CS4": _c(81, 2.35), "CS5": _c(39, 8.40),
                      "CS6": _c(71, 4.81), "CS7": _c(90, 11.57)},
        "TUMB": {"CS2": _c(69, 0.12), "CS3": _c(113, 15.59), "CS4": _c(135, 7.12), "CS5": _c(114, 2.73),
                 "CS6": _c(151, 15.32), "CS7": _c(125, 11.12)},
        "CAMBA": {"CS2": _c(36, 11.84), "CS3": _c(30, 8.50), "CS4": _c(33, 0.0), "CS5": _c(11, 3.16),
                  "CS6": _c(102, 12.92), "CS7": _c(22, 4.69)},
        "DeepHyperion-UAV": {"CS2": _c(2, 1.22), "CS3": _c(28, 8.31), "CS4": _c(10, 7.74), "CS5": _c(22, 1.08),
                             "CS6": _c(7, 0.0), "CS7": _c(14, 2.96)},
        "AmbieGen": {"CS2": _c(30, 2.82), "CS3": _c(46, 2.00), "CS4": _c(36, 0.86), "CS5": _c(65, 1.22),
                     "CS6": _c(151, 10.07), "CS7": _c(30, 1.51)},
        "Surrealist": {"CS2": _c(10, 5.03), "CS3": _c(1, 0.0), "CS4": _c(10, 0.0), "CS5": _c(1, 0.75),
                       "CS6": _c(19, 3.88), "CS7": _c(2, 0.0)},
        "TAIiST": {"CS2": _c(7, 0.81), "CS3": _c(13, 0.0), "CS4": _c(6, 0.43), "CS5": _c(11, 1.57),
                   "CS6": _c(29, 1.67), "CS7": _c(22, 1.33)},
    },
    "2025": {
        "Pseudo-Random": {"CS2": _c(31, 5.25, 7, 0.86), "CS4": _c(66, 9.30, 12, 0.87), "CS5": _c(17, 2.71, 5, 0.82)},
        "Surrealist": {"CS2": _c(52, 4.16, 11, 0.21), "CS4": _c(9, 1.93, 3, 0.20), "CS5": _c(9, 0.11, 1, 0.18)},
        "OptObstacles": {"CS2": _c(3, 0.44, 1, 0.93), "CS4": _c(7, 0.0, 0, 0.92), "CS5": _c(2, 0.0, 0, 0.89)},
        "Evolv-1": {"CS2": _c(57, 9.02, 12, 0.88), "CS4": _c(22, 1.08, 2, 0.82), "CS5": _c(37, 2.93, 6, 0.85)},
        "PALM": {"CS2": _c(58, 0.14, 1, 0.58), "CS4": _c(82, 3.58, 20, 0.42), "CS5": _c(76, 0.80, 19, 0.46)},
        "TGen-UQ": {"CS2": _c(5, 0.50, 1, 1.00), "CS4": _c(6, 1.44, 1, 0.94), "CS5": _c(6, 0.0, 0, 0.89)},
    },
}

#: our public case study -> the report's case study derived from it (2024 only: the 2025 ones are not public)
CASE_STUDIES = {"2024": {"mission2": "CS2", "mission3": "CS3"}, "2025": {}}


def _key(name: str) -> str:
    return re.sub(r"[^a-z0-9]", "", name.lower())


def published_name(tool: str) -> str | None:
    """The reports' name of a tool named by its folder (``camba`` -> ``CAMBA``, ``deephyperion`` ->
    ``DeepHyperion-UAV``: a folder name that is the start of a published name, or holds one), or None."""
    key = _key(tool)
    if len(key) < 4:  # too short to name a tool
        return None
    names = {name for tools in PUBLISHED.values() for name in tools}
    return next((name for name in sorted(names) if _key(name).startswith(key) or key.startswith(_key(name))), None)


def rerun_share(cells: dict[str, PublishedCell]) -> float:
    """The share of a 2025 tool's re-run tests that failed again, pooled over its case studies (nan without any)."""
    evaluated = sum(c.evaluated for c in cells.values() if c.failing is not None)
    failing = sum(c.failing for c in cells.values() if c.failing is not None)
    return failing / evaluated if evaluated else float("nan")
