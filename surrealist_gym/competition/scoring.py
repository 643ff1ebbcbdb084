"""The UAV Testing Competition's scoring of a test suite, as its 2024 (SBFT), 2025 (ICST, SBFT) and 2026 editions
did.

Sources: the editions' reports (skhatiri/UAV-Testing-Competition, ``reports/``). The rules on obstacles and the points
of a run are :mod:`surrealist_gym.competition.rules`'s; this module draws the tests an edition evaluates and scores
them.

- **Drawn tests** (:func:`draw`): 2024 drew 20 tests of a suite at random (here seeded) and ran each 5 times; 2025
  took the first 20 in the order the tool wrote them (:func:`writing_order`) and ran each 3 times; 2026 checks every
  test for compliance first and runs the first valid ones in the tool's rank order (the order it wrote them) 5 times
  each. How many 2026 evaluates is not published: 20 here, as 2024 and 2025 did (``leaderboard --tests``).
- **Test score** (:func:`test_score`): ``avg_point x 10 / (n_obstacles^2 x avg_time)``, avg_time the mean flight
  time in minutes (the simulated time from arming to the end of the run, the span of the run's ULog).
- **2024**: a suite of more than 20 tests earns half the mean test score for each test beyond the 20
  (:func:`rest_score`); tests whose averaged flights are almost identical are penalised (:func:`similar_flights`:
  the mean x-y distance along DTW's path between the DBA averages of their runs below :data:`SIMILAR_FLIGHT_M`),
  ``sim_pen = 1 - n_similar / n_evaluated``; ``suite_score = (sum test_score + rest_score) x sim_pen``.
- **2026**: 2024's test scores and similarity penalty on the 5 runs' averaged flights, without a rest score:
  ``suite_score = sum test_score x sim_pen``; tools ranked by it, once with the case study's wind and once without.
- **2025**: tests whose boxes cover the same ground (:func:`area_similarity` 1) are duplicates and count once
  (:func:`duplicates`); ``failure = sum test_score``; ``diversity = 1 - mean pairwise area similarity``
  (:func:`area_diversity`).
- **Ranks** per case study (:func:`standings`): R_F by the failure score (2024 and 2026: the suite score), R_D by
  diversity (2025), ``R = 0.75 R_F + 0.25 R_D``; 1 is the best, equal values share the best of their ranks (1, 2, 2,
  4).

Example:
    >>> round(test_score([5, 2, 0], [120.0, 120.0, 120.0], obstacles=2), 4)   # avg 7/3 points, 2 boxes, 2 min
    2.9167
    >>> ranks([9.3, 1.08, 9.3, float("nan")])
    (1, 3, 1, 4)
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import SurrealistError

__all__ = ["EDITIONS", "SIMILAR_FLIGHT_M", "Draw", "Edition", "ScoredTest", "Standing", "SuiteScore",
           "area_diversity", "area_similarity", "case_study_of", "draw", "draw_folder", "duplicates", "edition",
           "ranks", "rest_score", "score_draws", "score_suite", "similar_flights", "standings", "test_score",
           "writing_order"]


#: [m] 2024: two tests are similar when the DBA averages of their runs are closer than this on average along DTW's
#: path (x-y). Measured on CAMBA's 21 tests x 10 runs: two 5-run averages of the same test are 0.07-0.35 m apart
#: for 19 of 21 tests (0.70 and 0.82 m for the other two), averages of two different tests of one mission 0.45 m and
#: more (156 pairs): below 0.4 m a pair is as alike as repeats of one test are (``benchmarks/bench_similarity.py``).
#: 2026 names the same measure ("almost zero") and no number either; this one is its default too.
SIMILAR_FLIGHT_M = 0.4


@dataclass(frozen=True, slots=True)
class Edition:
    """An edition's rules: the ``budget`` of simulations a tool had per case study, the most boxes a test may hold
    and whether their sizes were bounded (``size_bounds``: 2025 on), the ``tests`` it evaluated of a suite (``draw``:
    ``random`` or ``first`` in writing order; ``valid_only``: the first valid ones, 2026), ``runs`` each, and whether
    each suite was evaluated twice, with the case study's wind and without (``wind``: 2026). How alike tests were
    judged (``similarity``: ``flights``, the DTW of their averaged runs under ``similar_m`` metres, penalised by
    ``sim_pen``, 2024 and 2026; ``area``, the ground their boxes cover, duplicates counted once, 2025); whether tests
    beyond the evaluated earned a rest score (``rest``: 2024). The ranking follows the similarity
    (:attr:`ranks_diversity`)."""

    name: str
    tests: int
    runs: int
    draw: str
    budget: int = 100
    max_obstacles: int = 3
    wind: bool = False
    similarity: str = "area"
    rest: bool = False
    size_bounds: bool = True
    valid_only: bool = False
    similar_m: float = SIMILAR_FLIGHT_M

    @property
    def ranks_diversity(self) -> bool:
        """Whether tools were ranked on failures and the area diversity of their tests (R = 0.75 R_F + 0.25 R_D): the
        edition that judged tests alike by the ground their boxes cover (2025); the others ranked the suite score."""
        return self.similarity == "area"

    @property
    def rules(self):
        """The competition's rules on obstacles as this edition published them: its most boxes, and 2024 without
        bounds on a box's size or turn (its README bounded the count, the ground, overlaps and the area only)."""
        from .rules import RULES, UNBOUNDED_SIZES

        return replace(RULES if self.size_bounds else UNBOUNDED_SIZES, max_obstacles=self.max_obstacles)


#: 2024 (SBFT): budget 200, up to 4 boxes of any size, 20 tests drawn at random, 5 runs each, the rest score and the
#: similarity penalty; 2025 (ICST, SBFT): budget 100, up to 3 boxes within the size bounds, the first 20 tests, 3 runs
#: each, duplicates and diversity; 2026: 2025's rules on boxes, the first 20 valid tests in the tool's rank order, 5
#: runs each, 2024's similarity penalty, with and without wind (``shared/COMPETITION.md`` sections 2, 3, 5 and 6).
EDITIONS = {"2024": Edition("2024", 20, 5, "random", budget=200, max_obstacles=4, similarity="flights", rest=True,
                            size_bounds=False),
            "2025": Edition("2025", 20, 3, "first"),
            "2026": Edition("2026", 20, 5, "first", wind=True, similarity="flights", valid_only=True)}
_SAME_AREA = 1.0 - 1e-9  # area similarity counted as 1 (floating error of the footprints' union and intersection)


def edition(name, flag: str = "--competition") -> Edition:
    """The edition named (``2024``, ``2025`` or ``2026``), or a one-line error naming ``flag``."""
    try:
        return EDITIONS[str(name)]
    except KeyError:
        raise SurrealistError(f"{flag}: expected one of {', '.join(EDITIONS)}, got {name!r}") from None


# --- which tests ---------------------------------------------------------------------------------------------------
def _natural(path: Path) -> list:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def writing_order(files: Sequence) -> list[Path]:
    """The tests in the order a tool wrote them: the natural order of their names (digits compared as numbers:
    ``test_2`` before ``test_10``) when every name holds a number, as the competition's sample tool numbers them;
    else by modification time (then name)."""
    files = [Path(os.fspath(f)) for f in files]
    if all(re.search(r"\d", f.stem) for f in files):
        return sorted(files, key=_natural)
    return sorted(files, key=lambda f: (f.stat().st_mtime_ns, f.name))


def draw(files: Sequence, ed: Edition, seed: int = 0, valid: Sequence | None = None) -> tuple[Path, ...]:
    """The tests the edition evaluates, in writing order: ``random``: ``ed.tests`` of them drawn without replacement
    by ``numpy.random.default_rng(seed)``; ``first``: the first ``ed.tests``. A smaller suite is evaluated whole.
    ``valid``: the files that keep the edition's rules; with ``ed.valid_only`` the draw is made among them alone."""
    ordered = writing_order(files)
    if ed.valid_only and valid is not None:
        kept = {Path(os.fspath(f)) for f in valid}
        ordered = [f for f in ordered if f in kept]
    if len(ordered) <= ed.tests:
        return tuple(ordered)
    if ed.draw == "first":
        return tuple(ordered[:ed.tests])
    chosen = np.random.default_rng(seed).choice(len(ordered), size=ed.tests, replace=False)
    return tuple(ordered[i] for i in sorted(int(i) for i in chosen))


def case_study_of(test) -> str:
    """The case study a test belongs to: its mission file's name (``mission1.plan`` -> ``mission1``)."""
    return Path(test.mission_file).stem if test.mission_file else "(no mission file)"


@dataclass(frozen=True, slots=True)
class Draw:
    """One folder's draw: its case study, how many tests it holds and the files drawn (absolute, in order)."""

    folder: str
    case_study: str
    tests: int
    drawn: tuple[str, ...]

    def to_json(self) -> dict:
        """The draw as JSON values (read back by :meth:`from_json`)."""
        return {"folder": self.folder, "case_study": self.case_study, "tests": self.tests, "drawn": list(self.drawn)}

    @classmethod
    def from_json(cls, values: dict) -> "Draw":
        """A draw from :meth:`to_json`'s values."""
        return cls(str(values["folder"]), str(values["case_study"]), int(values["tests"]),
                   tuple(str(f) for f in values["drawn"]))


def draw_folder(folder, ed: Edition, seed: int = 0) -> Draw:
    """Load every test of a tool's output folder (one-line errors: no YAML, a broken test), check that they belong
    to one case study, and draw the edition's tests."""
    from .tool_output import load_tests

    path = Path(os.fspath(folder))
    if not path.is_dir():
        raise SurrealistError(f"{os.fspath(folder)}: --competition scores folders (a tool's output), and this is "
                              + ("a file" if path.exists() else "no such folder"))
    from .tool_output import rule_broken

    tests = load_tests([path], any_layout=True)
    studies: dict[str, list[str]] = {}
    for file, test in tests:
        studies.setdefault(case_study_of(test), []).append(file.name)
    if len(studies) > 1:
        named = "; ".join(f"{name}: {len(names)} ({names[0]}, ...)" for name, names in sorted(studies.items()))
        raise SurrealistError(f"{os.fspath(folder)}: tests of {len(studies)} case studies ({named}); a folder holds "
                              f"one case study's tests: put each in a folder of its own")
    broken = {file: rule_broken(test, ed.rules) for file, test in tests} if ed.valid_only else {}
    valid = [file for file, rule in broken.items() if not rule] if ed.valid_only else None
    if valid == []:
        first = tests[0][0]
        raise SurrealistError(f"{os.fspath(folder)}: none of its {len(tests)} tests keeps the {ed.name} edition's "
                              f"rules ({first.name}: {broken[first]}): nothing to evaluate")
    drawn = draw([file for file, _ in tests], ed, seed, valid)
    return Draw(str(path.absolute()), next(iter(studies)), len(tests), tuple(str(f.absolute()) for f in drawn))


# --- scores --------------------------------------------------------------------------------------------------------
def test_score(points: Sequence[int], durations_s: Sequence[float], obstacles: int) -> float:
    """``avg_point x 10 / (obstacles^2 x avg_time)``, avg_time the mean duration in minutes (0 without runs or
    obstacles)."""
    if not len(points) or obstacles < 1:
        return 0.0
    minutes = float(np.mean(durations_s)) / 60.0
    return float(np.mean(points)) * 10.0 / (obstacles ** 2 * minutes) if minutes > 0 else 0.0


test_score.__test__ = False  # not a pytest test


def rest_score(n_tests: int, scores: Sequence[float], drawn: int = 20) -> float:
    """2024: each test beyond the ``drawn`` earns half the mean score of those evaluated."""
    return (n_tests - drawn) * float(np.mean(scores)) / 2.0 if n_tests > drawn and len(scores) else 0.0


def area_similarity(a, b) -> float:
    """``|area(a) & area(b)| / |area(a) | area(b)|`` of two layouts' footprints (the union of each test's boxes,
    shapely); 1 for two empty layouts."""
    from .suite import footprints

    if not a or not b:
        return 1.0 if not a and not b else 0.0
    fa, fb = footprints(a), footprints(b)
    union = fa.union(fb).area
    return float(fa.intersection(fb).area / union) if union > 0 else 1.0


def duplicates(layouts: Sequence) -> tuple[int | None, ...]:
    """For each layout, the first earlier one with area similarity 1 (its duplicate: counted once), or None."""
    out: list[int | None] = []
    for i, layout in enumerate(layouts):
        out.append(next((j for j in range(i) if out[j] is None
                         and area_similarity(layouts[j], layout) >= _SAME_AREA), None))
    return tuple(out)


def area_diversity(layouts: Sequence) -> float:
    """``1 - mean pairwise area similarity`` of the layouts (nan below two)."""
    pairs = [area_similarity(a, b) for i, a in enumerate(layouts) for b in layouts[i + 1:]]
    return 1.0 - float(np.mean(pairs)) if pairs else math.nan


def similar_flights(flights: Sequence, threshold_m: float = SIMILAR_FLIGHT_M) -> tuple[int | None, ...]:
    """2024 and 2026: for each test's runs (a sequence of (N, 3) trajectories; empty: not flown), the first earlier
    test whose averaged flight is within ``threshold_m`` (mean x-y distance along DTW's path between the DBA averages,
    :func:`~surrealist_gym.fitness.average_runs`, :func:`~surrealist_gym.competition.suite.trajectory_distance`), or
    None."""
    from ..fitness import average_runs
    from .suite import trajectory_distance

    averages = [average_runs([r for r in runs if len(r)]) if any(len(r) for r in runs) else None for runs in flights]
    out: list[int | None] = []
    for i, avg in enumerate(averages):
        out.append(None if avg is None else next(
            (j for j in range(i) if out[j] is None and averages[j] is not None
             and trajectory_distance(averages[j], avg) < threshold_m), None))
    return tuple(out)


@dataclass(frozen=True, slots=True)
class ScoredTest:
    """One drawn test: its file, boxes, the points and durations [s] of its runs flown, its test score, the rule it
    breaks (not flown, scores 0), and the earlier drawn test (index) it duplicates (2025) or flies alike (2024)."""

    __test__ = False  # not a pytest class

    file: str
    obstacles: int
    points: tuple[int, ...]
    durations_s: tuple[float, ...]
    score: float
    invalid: str = ""
    same_as: int | None = None

    @property
    def counted(self) -> bool:
        """2025: whether the test counts (not the duplicate of an earlier one)."""
        return self.same_as is None


@dataclass(frozen=True, slots=True)
class SuiteScore:
    """A folder scored as an edition did.

    Attributes:
        folder, case_study, edition: what was scored. tests: tests in the folder. drawn: the tests evaluated.
        failure: 2025: the sum of the test scores, duplicates once; 2024 and 2026: the sum of the test scores.
        rest: 2024's rest score (0 in 2025 and 2026). sim_pen: 2024 and 2026's similarity penalty (1 in 2025).
        score: what R_F ranks: 2025 the failure score, 2024 ``(failure + rest) x sim_pen``, 2026
        ``failure x sim_pen``.
        diversity: ``1 - mean pairwise area similarity`` of the drawn tests, duplicates once (nan below two).
    """

    folder: str
    case_study: str
    edition: str
    tests: int
    drawn: tuple[ScoredTest, ...]
    failure: float
    rest: float
    sim_pen: float
    score: float
    diversity: float

    @property
    def name(self) -> str:
        """The tool's output folder name."""
        return Path(self.folder).name

    @property
    def failing(self) -> int:
        """Drawn tests (2025: duplicates once) with a score above 0: the reports' ``#tests (failing)``."""
        return sum(t.score > 0 and (not EDITIONS[self.edition].ranks_diversity or t.counted) for t in self.drawn)

    @property
    def alike(self) -> int:
        """Drawn tests that duplicate (2025) or fly alike (2024) an earlier one."""
        return sum(not t.counted for t in self.drawn)


def score_suite(ed: Edition, d: Draw, tests: Sequence[tuple[object, Sequence, str]]) -> SuiteScore:
    """Score a folder's draw. ``tests``: per drawn file, in order, (its TestCase, its runs (objects with ``points``,
    ``duration``, ``trajectory`` and ``flown``; empty when not flown), the rule it breaks or "")."""
    scored = []
    for file, (test, runs, invalid) in zip(d.drawn, tests):
        flown = [r for r in runs if r.flown] if not invalid else []
        points, durations = tuple(int(r.points) for r in flown), tuple(float(r.duration) for r in flown)
        scored.append(ScoredTest(file, len(test.obstacles), points, durations,
                                 test_score(points, durations, len(test.obstacles)), invalid))
    layouts = [test.obstacles for test, _, _ in tests]
    if ed.similarity == "flights":
        same = similar_flights([[r.trajectory for r in runs if r.flown] if not invalid else []
                                for _, runs, invalid in tests], ed.similar_m)
        scored = [_with_same(t, s) for t, s in zip(scored, same)]
        failure = sum(t.score for t in scored)
        rest = rest_score(d.tests, [t.score for t in scored], ed.tests) if ed.rest else 0.0
        sim_pen = 1.0 - sum(s is not None for s in same) / len(scored) if scored else 1.0
        return SuiteScore(d.folder, d.case_study, ed.name, d.tests, tuple(scored), failure, rest, sim_pen,
                          (failure + rest) * sim_pen, area_diversity(layouts))
    same = duplicates(layouts)
    scored = [_with_same(t, s) for t, s in zip(scored, same)]
    failure = sum(t.score for t in scored if t.counted)
    return SuiteScore(d.folder, d.case_study, ed.name, d.tests, tuple(scored), failure, 0.0, 1.0, failure,
                      area_diversity([layout for layout, s in zip(layouts, same) if s is None]))


def score_draws(ed: Edition, draws: Sequence[Draw], tests, runs, invalid) -> tuple["Standing", ...]:
    """Each folder's draw scored as the edition did (:func:`score_suite`), ranked per case study (:func:`standings`).
    ``tests``: each drawn file's TestCase by its Path; ``runs``: its runs flown by its file name as drawn (str);
    ``invalid``: the rule a drawn test breaks by its Path (not flown, scores 0)."""
    return standings([score_suite(ed, d, [(tests[Path(f)], runs.get(f, ()), invalid.get(Path(f), ""))
                                          for f in d.drawn]) for d in draws])


def _with_same(t: ScoredTest, same: int | None) -> ScoredTest:
    return replace(t, same_as=same)


# --- ranks ---------------------------------------------------------------------------------------------------------
def ranks(values: Sequence[float], higher_is_better: bool = True) -> tuple[int, ...]:
    """1 for the best; equal values share the best of their ranks (1, 2, 2, 4); nan ranks after every number."""
    def key(v: float) -> float:
        return math.inf if v is None or math.isnan(v) else (-v if higher_is_better else v)

    keys = [key(v) for v in values]
    return tuple(1 + sum(other < k for other in keys) for k in keys)


@dataclass(frozen=True, slots=True)
class Standing:
    """A folder's place among the folders on its case study: R_F, R_D (2025; None in 2024, which ranked by the
    suite score alone), R (``0.75 R_F + 0.25 R_D``; 2024: R_F) and its rank by R."""

    suite: SuiteScore
    r_f: int
    r_d: int | None
    r: float
    rank: int


def standings(scores: Sequence[SuiteScore]) -> tuple[Standing, ...]:
    """Rank the folders per case study (case studies by name, folders by rank, then as given)."""
    out = []
    for study in sorted({s.case_study for s in scores}):
        group = [s for s in scores if s.case_study == study]
        r_f = ranks([s.score for s in group])
        if not EDITIONS[group[0].edition].ranks_diversity:
            r_d: Sequence[int | None] = [None] * len(group)
            r = [float(f) for f in r_f]
        else:
            r_d = ranks([s.diversity for s in group])
            r = [0.75 * f + 0.25 * d for f, d in zip(r_f, r_d)]
        final = ranks(r, higher_is_better=False)
        rows = [Standing(s, f, d, x, k) for s, f, d, x, k in zip(group, r_f, r_d, r, final)]
        out += sorted(rows, key=lambda row: row.rank)
    return tuple(out)
