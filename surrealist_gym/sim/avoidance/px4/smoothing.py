"""The conic smoothing of the obstacle costs (``smoothPolarMatrix``) as the sparse tree search computes it
(:func:`~surrealist_gym.sim.avoidance.px4.expansion.expand_node`): along one padded line (:func:`conic_line`), or along
four (:func:`conic_lines4`) or two (:func:`conic_lines2`) lines in lockstep.

The same additions in the same order as the dense reference's running box sums
(:func:`~surrealist_gym.sim.reference.px4_tree.smooth_columns`,
:func:`~surrealist_gym.sim.reference.px4_tree.smooth_row`), computed only where a sum can change: the
same bits.
"""
from __future__ import annotations

from numba import njit


@njit(cache=True)
def _means(out, oi, n, length):  # pragma: no cover - compiled
    """``out[oi, :n] /= length`` (a loop that vectorizes). For a power of two (the default radius of 7 cells gives 8)
    as the product with its reciprocal, which is exact: both are the one rounding of the same real quotient, and a
    product is far cheaper than a division."""
    if length & (length - 1) == 0:
        inv = 1.0 / length
        for i in range(n):
            out[oi, i] *= inv
    else:
        for i in range(n):
            out[oi, i] /= length


@njit(cache=True)
def conic_line(src, si, lo, hi, r, n, box, out, oi):  # pragma: no cover - compiled
    """The conic kernel of radius ``r`` along one padded line ``src[si]`` (n + 2r values, zero outside ``[lo, hi]``)
    into ``out[oi, :n]``: the two running box sums of :func:`smooth_columns` / :func:`smooth_row`, the same
    additions in the same order, computed only where they can change. Before the first nonzero value enters the
    window a running sum adds zeros and stays 0.0; after the last one leaves it adds ``c - c`` and keeps its value;
    those stretches are written, not summed. ``box`` (>= n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)  # box[j] sums src[si, j:j + length]: 0.0 while j + r < lo
    j1 = min(m - 1, hi + 1)  # and box[hi + 1] from then on
    for j in range(j0):
        box[j] = 0.0
    s = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            s += src[si, j]
        box[0] = s
        start = 1
    for j in range(start, j1 + 1):
        s += src[si, j + length - 1] - src[si, j - 1]
        box[j] = s
    for j in range(j1 + 1, m):
        box[j] = s
    i0 = max(0, j0 - r)  # the second pass over box: 0.0 before j0 and constant after j1, likewise
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[oi, i] = 0.0
    s = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            s += box[j]
        out[oi, 0] = s
        start = 1
    for i in range(start, i1 + 1):
        s += box[i + length - 1] - box[i - 1]
        out[oi, i] = s
    for i in range(i1 + 1, n):
        out[oi, i] = s
    _means(out, oi, n, length)  # the means


@njit(cache=True)
def conic_lines4(src, ca, cb, cc, cd, lo, hi, r, n, box, out):  # pragma: no cover - compiled
    """:func:`conic_line` on the four lines ``src[ca]``, ``src[cb]``, ``src[cc]``, ``src[cd]``, each zero outside
    ``[lo, hi]``, into the same rows of ``out``, in lockstep: four independent chains of additions at once. Each
    line's sums are the same bits as alone: a line's sum over its own zeros before its first nonzero value is
    0.0 + (0.0 - 0.0), and after its last one it adds 0.0 (the window's values are equal), so running it over the
    group's range changes nothing. ``box`` (4, >= n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)
    j1 = min(m - 1, hi + 1)
    for j in range(j0):
        box[0, j] = box[1, j] = box[2, j] = box[3, j] = 0.0
    sa = sb = sc = sd = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            sa += src[ca, j]
            sb += src[cb, j]
            sc += src[cc, j]
            sd += src[cd, j]
        box[0, 0], box[1, 0], box[2, 0], box[3, 0] = sa, sb, sc, sd
        start = 1
    for j in range(start, j1 + 1):
        sa += src[ca, j + length - 1] - src[ca, j - 1]
        sb += src[cb, j + length - 1] - src[cb, j - 1]
        sc += src[cc, j + length - 1] - src[cc, j - 1]
        sd += src[cd, j + length - 1] - src[cd, j - 1]
        box[0, j], box[1, j], box[2, j], box[3, j] = sa, sb, sc, sd
    for j in range(j1 + 1, m):
        box[0, j], box[1, j], box[2, j], box[3, j] = sa, sb, sc, sd
    i0 = max(0, j0 - r)
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[ca, i] = out[cb, i] = out[cc, i] = out[cd, i] = 0.0
    sa = sb = sc = sd = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            sa += box[0, j]
            sb += box[1, j]
            sc += box[2, j]
            sd += box[3, j]
        out[ca, 0], out[cb, 0], out[cc, 0], out[cd, 0] = sa, sb, sc, sd
        start = 1
    for i in range(start, i1 + 1):
        sa += box[0, i + length - 1] - box[0, i - 1]
        sb += box[1, i + length - 1] - box[1, i - 1]
        sc += box[2, i + length - 1] - box[2, i - 1]
        sd += box[3, i + length - 1] - box[3, i - 1]
        out[ca, i], out[cb, i], out[cc, i], out[cd, i] = sa, sb, sc, sd
    for i in range(i1 + 1, n):
        out[ca, i], out[cb, i], out[cc, i], out[cd, i] = sa, sb, sc, sd
    _means(out, ca, n, length)  # the means (a repeated line is divided once)
    if cb != ca:
        _means(out, cb, n, length)
    if cc != cb:
        _means(out, cc, n, length)
    if cd != cc:
        _means(out, cd, n, length)


@njit(cache=True)
def conic_lines2(src, lo, hi, r, n, box, out):  # pragma: no cover - compiled
    """:func:`conic_line` on the two lines ``src[0]`` and ``src[1]``, zero outside ``[lo, hi]``, into ``out[0]``
    and ``out[1]`` (``[:n]``), in lockstep: two independent chains of additions at once, each line's sums the same
    bits as alone (:func:`conic_lines4`). ``box`` (>= 2 rows of n + r) is a work buffer."""
    length = r + 1
    m = n + r
    j0 = max(0, lo - r)
    j1 = min(m - 1, hi + 1)
    for j in range(j0):
        box[0, j] = box[1, j] = 0.0
    sa = sb = 0.0
    start = j0
    if j0 == 0:
        for j in range(length):
            sa += src[0, j]
            sb += src[1, j]
        box[0, 0], box[1, 0] = sa, sb
        start = 1
    for j in range(start, j1 + 1):
        sa += src[0, j + length - 1] - src[0, j - 1]
        sb += src[1, j + length - 1] - src[1, j - 1]
        box[0, j], box[1, j] = sa, sb
    for j in range(j1 + 1, m):
        box[0, j], box[1, j] = sa, sb
    i0 = max(0, j0 - r)
    i1 = min(n - 1, j1 + 1)
    for i in range(i0):
        out[0, i] = out[1, i] = 0.0
    sa = sb = 0.0
    start = i0
    if i0 == 0:
        for j in range(length):
            sa += box[0, j]
            sb += box[1, j]
        out[0, 0], out[1, 0] = sa, sb
        start = 1
    for i in range(start, i1 + 1):
        sa += box[0, i + length - 1] - box[0, i - 1]
        sb += box[1, i + length - 1] - box[1, i - 1]
        out[0, i], out[1, i] = sa, sb
    for i in range(i1 + 1, n):
        out[0, i], out[1, i] = sa, sb
    _means(out, 0, n, length)  # the means
    _means(out, 1, n, length)
