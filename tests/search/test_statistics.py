"""Table 2 statistics against scipy and hand-computed values."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from search.statistics import a12_magnitude, cohens_d, compare, reduction, shapiro_wilk, vargha_delaney_a12

RNG = np.random.default_rng(42)
NORMAL_A = RNG.normal(383.5, 20.0, 10)
NORMAL_B = RNG.normal(63.15, 5.0, 10)


def test_shapiro_wilk_matches_scipy():
    assert shapiro_wilk(NORMAL_A) == pytest.approx(stats.shapiro(NORMAL_A).pvalue)
    assert shapiro_wilk([1.0, 1.0, 1.0, 1.0]) == 0.0
    with pytest.raises(ValueError, match="at least 3"):
        shapiro_wilk([1.0, 2.0])


def test_compare_uses_anova_for_gaussian_samples():
    assert shapiro_wilk(NORMAL_A) > 0.05 and shapiro_wilk(NORMAL_B) > 0.05
    p, test = compare(NORMAL_A, NORMAL_B)
    assert test == "anova"
    assert p == pytest.approx(stats.f_oneway(NORMAL_A, NORMAL_B).pvalue)
    assert p < 0.01


def test_compare_falls_back_to_mann_whitney():
    skewed = np.array([0.0] * 8 + [10.0, 50.0])  # clearly not Gaussian
    assert shapiro_wilk(skewed) < 0.05
    p, test = compare(skewed, NORMAL_B)
    assert test == "mann-whitney"
    assert p == pytest.approx(stats.mannwhitneyu(skewed, NORMAL_B, alternative="two-sided").pvalue)


def test_vargha_delaney_a12_known_values():
    assert vargha_delaney_a12([1, 2, 3], [1, 2, 3]) == 0.5
    assert vargha_delaney_a12([4, 5, 6], [1, 2, 3]) == 1.0
    assert vargha_delaney_a12([1, 2, 3], [4, 5, 6]) == 0.0
    # pairs (a > b): 2>1; ties: 2=2 -> (1 + 0.5) / 4
    assert vargha_delaney_a12([1, 2], [1, 2]) == 0.5
    assert vargha_delaney_a12([2, 3], [1, 2]) == pytest.approx((3 + 0.5) / 4)


def test_a12_equals_the_mann_whitney_u_over_n1_n2():
    a, b = RNG.normal(size=7), RNG.normal(0.5, 1.0, size=9)
    u = stats.mannwhitneyu(a, b, alternative="two-sided").statistic
    assert vargha_delaney_a12(a, b) == pytest.approx(u / (len(a) * len(b)))


def test_a12_magnitude_labels():
    assert [a12_magnitude(v) for v in (0.5, 0.6, 0.3, 0.2, 1.0)] == [
        "negligible", "small", "medium", "large", "large"]


def test_cohens_d_pooled_standard_deviation():
    # means 2 and 4, both sample variances 1 -> pooled SD 1 -> d = -2
    assert cohens_d([1, 2, 3], [3, 4, 5]) == pytest.approx(-2.0)
    a, b = [1.0, 2.0, 4.0, 7.0], [0.0, 1.0]
    pooled = math.sqrt((3 * np.var(a, ddof=1) + 1 * np.var(b, ddof=1)) / 4)
    assert cohens_d(a, b) == pytest.approx((3.5 - 0.5) / pooled)
    assert cohens_d([1, 1], [1, 1]) == 0.0
    assert cohens_d([2, 2], [1, 1]) == math.inf


def test_reduction():
    assert reduction(63.15, 383.5) == pytest.approx(0.8353, abs=1e-4)  # the paper's 83 %
    assert reduction(0.0, 3.36) == 1.0
    with pytest.raises(ValueError, match="seed"):
        reduction(1.0, 0.0)
