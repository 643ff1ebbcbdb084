"""Statistics for the paper's Table 2: normality, the significance test, effect sizes and reductions.

The paper compares seed and best solutions over the algorithm repetitions: Shapiro-Wilk on both samples, then
one-way ANOVA when both look Gaussian, else Mann-Whitney U (two-sided); effect size by Vargha-Delaney A12 (and
Cohen's d, which the paper's reported values of 7.9 and 119.9 suggest). Tests come from ``scipy.stats``.

Example:
    >>> p, test = compare([1.0, 1.1, 0.9, 1.05, 0.95], [2.0, 2.1, 1.9, 2.05, 1.95])
    >>> test, p < 0.05, vargha_delaney_a12([2, 3], [0, 1])
    ('anova', True, 1.0)
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

ALPHA = 0.05


def _sample(x: Sequence[float], name: str, min_size: int = 1) -> np.ndarray:
    arr = np.asarray(x, dtype=np.float64).ravel()
    if arr.size < min_size:
        raise ValueError(f"{name}: expected at least {min_size} values, got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite values, got {arr.tolist()}")
    return arr


def shapiro_wilk(x: Sequence[float]) -> float:
    """p-value of the Shapiro-Wilk normality test (``scipy.stats.shapiro``); needs at least 3 values.

    A constant sample (zero variance) returns 0.0: it is not treated as Gaussian.
    """
    from scipy import stats

    arr = _sample(x, "x", 3)
    if np.ptp(arr) == 0:
        return 0.0
    return float(stats.shapiro(arr).pvalue)


def compare(a: Sequence[float], b: Sequence[float], alpha: float = ALPHA) -> tuple[float, str]:
    """The paper's significance test between two samples.

    Shapiro-Wilk on both; if neither rejects normality at ``alpha``, one-way ANOVA (``scipy.stats.f_oneway``),
    otherwise the two-sided Mann-Whitney U test (``scipy.stats.mannwhitneyu``).

    Returns:
        ``(p_value, test_name)`` with ``test_name`` ``"anova"`` or ``"mann-whitney"``.
    """
    from scipy import stats

    xa, xb = _sample(a, "a", 3), _sample(b, "b", 3)
    if shapiro_wilk(xa) > alpha and shapiro_wilk(xb) > alpha:
        return float(stats.f_oneway(xa, xb).pvalue), "anova"
    return float(stats.mannwhitneyu(xa, xb, alternative="two-sided").pvalue), "mann-whitney"


def vargha_delaney_a12(a: Sequence[float], b: Sequence[float]) -> float:
    """Vargha-Delaney A12: probability that a value from ``a`` exceeds one from ``b`` (ties count half).

    0.5 means no difference; 1.0 means every value of ``a`` is larger, 0.0 every value smaller.
    """
    xa, xb = _sample(a, "a"), _sample(b, "b")
    greater = (xa[:, None] > xb[None, :]).sum()
    ties = (xa[:, None] == xb[None, :]).sum()
    return float((greater + 0.5 * ties) / (xa.size * xb.size))


def a12_magnitude(a12: float) -> str:
    """Vargha and Delaney's (2000) label for an A12 value: negligible, small, medium or large.

    Thresholds on ``|A12 - 0.5|``: < 0.06 negligible, < 0.14 small, < 0.21 medium, else large.
    """
    delta = abs(a12 - 0.5)
    return "negligible" if delta < 0.06 else "small" if delta < 0.14 else "medium" if delta < 0.21 else "large"


def cohens_d(a: Sequence[float], b: Sequence[float]) -> float:
    """Cohen's d: ``(mean(a) - mean(b)) / s`` with the pooled standard deviation ``s`` (n-1 denominators).

    Returns 0.0 for equal means with zero spread, and +/-inf for different means with zero spread.
    """
    xa, xb = _sample(a, "a", 2), _sample(b, "b", 2)
    na, nb = xa.size, xb.size
    pooled = math.sqrt(((na - 1) * xa.var(ddof=1) + (nb - 1) * xb.var(ddof=1)) / (na + nb - 2))
    diff = float(xa.mean() - xb.mean())
    if pooled == 0.0:
        return 0.0 if diff == 0.0 else math.copysign(math.inf, diff)
    return diff / pooled


def reduction(best: float, seed: float) -> float:
    """Table 2's reduction ``1 - best / seed`` (a fraction; 0.83 = 83 %) for DTW, Fréchet or min_dist.

    Raises:
        ValueError: when ``seed`` is zero.
    """
    if seed == 0:
        raise ValueError(f"seed: the reduction 1 - best/seed needs a non-zero seed value, got {seed!r}")
    return 1.0 - float(best) / float(seed)


__all__ = ["ALPHA", "a12_magnitude", "cohens_d", "compare", "reduction", "shapiro_wilk", "vargha_delaney_a12"]
