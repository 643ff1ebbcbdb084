"""The competition's scoring (surrealist_gym.competition.scoring) on hand-made values: area similarity and diversity of
boxes, duplicates, the seeded 2024 draw and 2025's writing order, test, rest and suite scores, 2024's similar flights,
and the ranks of the ICST 2025 report's Table I."""
import math
import os
from dataclasses import dataclass, replace

import numpy as np
import pytest

from surrealist_gym.competition.rules import violations
from surrealist_gym.competition.scoring import (
    EDITIONS,
    Draw,
    SuiteScore,
    area_diversity,
    area_similarity,
    draw,
    duplicates,
    edition,
    ranks,
    rest_score,
    score_suite,
    similar_flights,
    standings,
    test_score,
    writing_order,
)
from surrealist_gym.errors import SurrealistError
from surrealist_gym.testcase import Obstacle, TestCase

A = Obstacle(4, 4, 20, 0, 20)              # a 4 x 4 m box at (0, 20)
A_TURNED = Obstacle(4, 4, 20, 0, 20, 0, 180)  # the same ground
B = Obstacle(4, 4, 20, 2, 20)              # moved 2 m along x: overlaps A on 2 x 4 m
FAR = Obstacle(4, 4, 20, 20, 30)           # far from A


# --- area similarity, duplicates, diversity ------------------------------------------------------------------------
def test_area_similarity_of_hand_made_boxes():
    assert area_similarity([A], [A]) == pytest.approx(1.0)
    assert area_similarity([A], [A_TURNED]) == pytest.approx(1.0)
    assert area_similarity([A], [FAR]) == 0.0
    assert area_similarity([A], [B]) == pytest.approx(8 / 24)  # intersection 2 x 4, union 16 + 16 - 8
    assert area_similarity([A, FAR], [FAR, A]) == pytest.approx(1.0)  # the boxes' order does not matter
    assert area_similarity([A, FAR], [A]) == pytest.approx(16 / 32)
    assert area_similarity([], []) == 1.0 and area_similarity([A], []) == 0.0


def test_duplicates_count_once_and_diversity():
    layouts = [[A], [B], [A_TURNED], [FAR], [A]]
    assert duplicates(layouts) == (None, None, 0, None, 0)
    # three distinct layouts: pairs A-B 1/3, A-FAR 0, B-FAR 0
    assert area_diversity([[A], [B], [FAR]]) == pytest.approx(1 - (1 / 3) / 3)
    assert area_diversity([[A], [A]]) == pytest.approx(0.0)
    assert area_diversity([[A], [FAR]]) == pytest.approx(1.0)
    assert math.isnan(area_diversity([[A]]))


# --- drawing -------------------------------------------------------------------------------------------------------
def _files(tmp_path, names):
    for name in names:
        (tmp_path / name).write_text("")
    return [tmp_path / name for name in names]


def test_2024_draw_is_seeded_and_reproducible(tmp_path):
    files = _files(tmp_path, [f"test_{i}.yaml" for i in range(25)])
    ed = EDITIONS["2024"]
    first = draw(files, ed, seed=7)
    assert len(first) == 20 == len(set(first))
    assert draw(list(reversed(files)), ed, seed=7) == first  # the same suite, the same draw
    assert list(first) == writing_order(first)               # listed in writing order
    assert any(draw(files, ed, seed=s) != first for s in range(8, 12))
    assert draw(files[:20], ed, seed=7) == tuple(writing_order(files[:20]))  # 20 or fewer: the whole suite
    assert draw(files[:3], ed, seed=7) == tuple(writing_order(files[:3]))


def test_2025_draws_the_first_20_in_writing_order(tmp_path):
    files = _files(tmp_path, [f"test_{i}.yaml" for i in range(25)])
    drawn = draw(files, EDITIONS["2025"])
    assert [f.name for f in drawn] == [f"test_{i}.yaml" for i in range(20)]  # test_2 before test_10


def test_writing_order_by_modification_time_without_numbers(tmp_path):
    files = _files(tmp_path, ["beta.yaml", "alpha.yaml", "gamma.yaml"])
    for age, f in zip((3, 1, 2), files):
        os.utime(f, ns=(age * 10**9, age * 10**9))
    assert [f.name for f in writing_order(files)] == ["alpha.yaml", "gamma.yaml", "beta.yaml"]


def test_unknown_edition_is_one_line():
    with pytest.raises(SurrealistError, match=r"^--competition: expected one of 2024, 2025, 2026, got '2023'$"):
        edition("2023")


# --- scores --------------------------------------------------------------------------------------------------------
def test_test_and_rest_scores():
    # avg points (5 + 2 + 0) / 3, two boxes, 90 s = 1.5 min: 7/3 x 10 / (4 x 1.5)
    assert test_score([5, 2, 0], [80.0, 90.0, 100.0], 2) == pytest.approx(7 / 3 * 10 / 6)
    assert test_score([1], [60.0], 3) == pytest.approx(10 / 9)
    assert test_score([], [], 2) == 0.0 and test_score([5], [60.0], 0) == 0.0
    assert rest_score(30, [2.0, 4.0]) == pytest.approx(10 * 3.0 / 2)
    assert rest_score(20, [2.0, 4.0]) == 0.0


@dataclass(frozen=True)
class _Run:
    points: int
    duration: float
    trajectory: np.ndarray
    flown: bool = True


def _line(dx: float = 0.0, dy: float = 0.0) -> np.ndarray:
    t = np.linspace(0, 40, 81)
    return np.column_stack([t + dx, np.full_like(t, 20.0 + dy), np.full_like(t, 10.0)])


def test_similar_flights_by_dtw_of_the_averages():
    near, far = [_line(), _line(dy=0.2)], [_line(dy=3.0)]
    assert similar_flights([[_line()], near, far, []]) == (None, 0, None, None)
    assert similar_flights([[_line()], [_line(dy=0.5)]]) == (None, None)  # 0.5 m apart: above 0.4 m


def _test(*boxes):
    return TestCase(obstacles=boxes)


def test_2024_suite_score_with_rest_and_similarity_penalty():
    ed = EDITIONS["2024"]
    runs = [[_Run(5, 60.0, _line()), _Run(2, 120.0, _line())],      # 3.5 points, 1.5 min, 1 box
            [_Run(5, 60.0, _line(dy=0.1))],                          # flies as the first: similar
            [_Run(0, 60.0, _line(dy=5.0))]]                          # scores 0
    tests = [(_test(A), runs[0], ""), (_test(B), runs[1], ""), (_test(FAR), runs[2], ""),
             (_test(A, FAR), (), "obstacles[0].x: 35 is outside")]  # breaks a rule: scores 0, not flown
    d = Draw("suite", "mission1", 40, tuple(f"t{i}.yaml" for i in range(4)))
    s = score_suite(ed, d, tests)
    scores = [3.5 * 10 / 1.5, 5 * 10 / 1.0, 0.0, 0.0]
    assert [t.score for t in s.drawn] == pytest.approx(scores)
    assert [t.same_as for t in s.drawn] == [None, 0, None, None] and s.drawn[3].invalid
    assert s.failure == pytest.approx(sum(scores))
    assert s.rest == pytest.approx((40 - 20) * np.mean(scores) / 2)
    assert s.sim_pen == pytest.approx(1 - 1 / 4)
    assert s.score == pytest.approx((sum(scores) + s.rest) * 0.75)
    assert (s.failing, s.alike) == (2, 1)


def test_2026_suite_score_is_the_test_scores_times_the_similarity_penalty_without_rest():
    ed = EDITIONS["2026"]
    assert (ed.runs, ed.tests, ed.draw, ed.valid_only, ed.wind, ed.rest, ed.ranks_diversity) == (
        5, 20, "first", True, True, False, False)
    runs = [[_Run(5, 60.0, _line()), _Run(0, 60.0, _line())],        # 2.5 points, 1 min, 1 box: 25
            [_Run(2, 120.0, _line(dy=0.1))],                         # flies as the first: similar; 2 / 2 min: 10
            [_Run(1, 60.0, _line(dy=5.0))]]                          # 2 boxes: 1 x 10 / 4 = 2.5
    tests = [(_test(A), runs[0], ""), (_test(B), runs[1], ""), (_test(A, FAR), runs[2], "")]
    s = score_suite(ed, Draw("suite", "mission1", 40, ("a.yaml", "b.yaml", "c.yaml")), tests)
    assert [t.score for t in s.drawn] == pytest.approx([25.0, 10.0, 2.5])
    assert [t.same_as for t in s.drawn] == [None, 0, None]
    assert (s.rest, s.sim_pen) == (0.0, pytest.approx(2 / 3))  # 40 tests written: no rest score in 2026
    assert s.score == pytest.approx(37.5 * 2 / 3) and (s.failing, s.alike) == (3, 1)
    wider = score_suite(replace(ed, similar_m=0.05), Draw("suite", "mission1", 3, ("a", "b", "c")), tests)
    assert wider.sim_pen == 1.0 and wider.score == pytest.approx(37.5)  # 0.1 m apart: alike only above 0.1 m


def test_2026_draws_the_first_valid_tests_in_rank_order(tmp_path):
    files = _files(tmp_path, [f"test_{i}.yaml" for i in range(25)])
    valid = [f for f in files if f.name not in ("test_0.yaml", "test_3.yaml")]
    drawn = draw(files, EDITIONS["2026"], valid=valid)
    assert [f.name for f in drawn] == [f"test_{i}.yaml" for i in (1, 2, *range(4, 22))]
    assert draw(files, EDITIONS["2025"], valid=valid) == draw(files, EDITIONS["2025"])  # 2025 draws them all


def test_each_edition_checks_the_rules_it_published():
    narrow = _test(Obstacle(1.0, 30.0, 5.0, 0, 20, 0, 120))  # 1 m wide, 30 m long, 5 m tall, turned 120 degrees
    assert violations(narrow, EDITIONS["2024"].rules) == ()
    assert EDITIONS["2024"].rules.max_obstacles == 4
    broken = violations(narrow, EDITIONS["2025"].rules)
    assert [b.split(":")[0] for b in broken] == ["obstacles[0].l", "obstacles[0].w", "obstacles[0].h"]  # as l 30, w 1
    assert violations(narrow, EDITIONS["2026"].rules) == broken
    outside = _test(Obstacle(1.0, 1.0, 5.0, 35, 20))
    assert [b.split(":")[0] for b in violations(outside, EDITIONS["2024"].rules)] == ["obstacles[0].x"]


def test_2025_suite_score_counts_duplicates_once():
    ed = EDITIONS["2025"]
    run = [_Run(5, 60.0, _line())]
    tests = [(_test(A), run, ""), (_test(A_TURNED), run, ""), (_test(B), run, "")]
    s = score_suite(ed, Draw("suite", "mission1", 3, ("a.yaml", "b.yaml", "c.yaml")), tests)
    assert [t.same_as for t in s.drawn] == [None, 0, None]
    assert s.failure == s.score == pytest.approx(2 * 50.0)  # the duplicate's 50 counts once
    assert s.diversity == pytest.approx(1 - 1 / 3)          # over A and B only
    assert (s.rest, s.sim_pen, s.failing, s.alike) == (0.0, 1.0, 2, 1)


# --- ranks ---------------------------------------------------------------------------------------------------------
def test_ranks_share_the_best_rank_and_put_nan_last():
    assert ranks([2.71, 2.93, 0.0, 0.80, 0.11, 0.0]) == (2, 1, 5, 3, 4, 5)  # SBFT/ICST 2025, CS5's failure ranks
    assert ranks([6, 7.5, 8.25, 8.25], higher_is_better=False) == (1, 2, 3, 3)
    assert ranks([0.5, math.nan, 0.9]) == (2, 3, 1)


def _suite(study: str, tool: str, failure: float, diversity: float) -> SuiteScore:
    return SuiteScore(tool, study, "2025", 20, (), failure, 0.0, 1.0, failure, diversity)


def test_standings_reproduce_the_icst_2025_table():
    """ICST 2025, Table I: failure and diversity per case study; the sum of R over the case studies is the report's
    final column (6, 7.5, 8.25, 8.25) and ranks 1, 2, 3, 3."""
    tools = ("Evolv-1", "PALM", "TGen-UQ", "Surrealist")
    table = {"CS2": dict(zip(tools, [(9.02, 0.88), (0.14, 0.58), (0.50, 1.00), (4.16, 0.21)])),
             "CS4": dict(zip(tools, [(1.08, 0.82), (3.58, 0.42), (1.44, 0.94), (1.93, 0.20)])),
             "CS5": dict(zip(tools, [(2.93, 0.85), (0.80, 0.46), (0.00, 0.89), (0.11, 0.18)]))}
    board = standings([_suite(cs, tool, f, d) for cs, tools in table.items() for tool, (f, d) in tools.items()])
    by = {(row.suite.case_study, row.suite.folder): row for row in board}
    assert [(by["CS2", t].r_f, by["CS2", t].r_d) for t in table["CS2"]] == [(1, 2), (4, 3), (3, 1), (2, 4)]
    assert by["CS4", "Evolv-1"].r == pytest.approx(0.75 * 4 + 0.25 * 2)
    totals = {tool: sum(by[cs, tool].r for cs in table) for tool in table["CS2"]}
    assert totals == pytest.approx({"Evolv-1": 6.0, "PALM": 7.5, "TGen-UQ": 8.25, "Surrealist": 8.25})
    assert ranks(list(totals.values()), higher_is_better=False) == (1, 2, 3, 3)
    assert [row.suite.case_study for row in board] == ["CS2"] * 4 + ["CS4"] * 4 + ["CS5"] * 4
    assert [row.rank for row in board[:4]] == [1, 2, 2, 4]  # CS2: R 1.25, 2.5, 2.5 (TGen-UQ, Surrealist), 3.75


def test_2024_standings_rank_by_score_alone():
    scores = [SuiteScore(name, "CS2", "2024", 30, (), f, 0.0, 1.0, f, math.nan)
              for name, f in (("WOGAN-UAV", 12.55), ("TUMB", 0.12), ("CAMBA", 11.84))]
    board = standings(scores)
    assert [(row.suite.folder, row.r_f, row.r_d, row.rank) for row in board] == [
        ("WOGAN-UAV", 1, None, 1), ("CAMBA", 2, None, 2), ("TUMB", 3, None, 3)]
