"""CPython's float functions bit for bit, for numba kernels that must equal a Python reference class exactly.

Where numba's operation differs from CPython's:

- :func:`py_hypot`: CPython's ``math.hypot`` is its own compensated algorithm (``vector_norm`` in
  Modules/mathmodule.c); libm's ``hypot``, which numba calls, differs in the last bit for ~0.2 % of arguments.
- :func:`py_remainder`: numba has no ``math.remainder``; this is CPython's ``m_remainder``.

tests/surrealist_gym/sim/navigation/test_navigator_kernels.py checks both against CPython on random and special
arguments.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

NAN = math.nan


@njit(cache=True)
def _two_product(x, y):  # pragma: no cover - compiled
    """x * y as hi + lo exactly (Dekker's product with Veltkamp's split; CPython's ``dl_mul`` gets the same pair
    from an fma)."""
    z = x * y
    t = x * 134217729.0
    xh = t - (t - x)
    xl = x - xh
    t = y * 134217729.0
    yh = t - (t - y)
    yl = y - yh
    return z, ((xh * yh - z) + xh * yl + xl * yh) + xl * yl


@njit(cache=True)
def py_hypot(x, y):  # pragma: no cover - compiled
    """CPython's ``math.hypot(x, y)`` bit for bit (``vector_norm`` in Modules/mathmodule.c: power-of-two scaling,
    exact squares, compensated sum, square root with a differential correction)."""
    x, y = abs(x), abs(y)
    if math.isinf(x) or math.isinf(y):
        return math.inf
    if x != x or y != y:
        return NAN
    top = x if x > y else y
    if top == 0.0:
        return top
    exponent = math.frexp(top)[1]
    if exponent < -1023:  # subnormal: CPython rescales by DBL_MIN first
        tiny = 2.2250738585072014e-308
        return tiny * py_hypot(x / tiny, y / tiny)
    scale = math.ldexp(1.0, -exponent)
    csum, frac1, frac2 = 1.0, 0.0, 0.0
    for v in (x, y):
        hi, lo = _two_product(v * scale, v * scale)
        s = csum + hi
        frac2 += (csum - s) + hi
        csum = s
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    s = csum + hi
    frac2 += (csum - s) + hi
    csum = s
    frac1 += lo
    h += (csum - 1.0 + (frac1 + frac2)) / (2.0 * h)
    return h / scale


@njit(cache=True)
def py_remainder(x, y):  # pragma: no cover - compiled
    """CPython's ``math.remainder(x, y)`` (IEEE remainder, ``m_remainder``) for finite x and y != 0, NaN in,
    NaN out."""
    if x != x or y != y:
        return NAN
    absx, absy = abs(x), abs(y)
    m = np.fmod(absx, absy)
    c = absy - m
    if m < c:
        r = m
    elif m > c:
        r = -c
    else:  # halfway: the even multiple
        r = m - 2.0 * np.fmod(0.5 * (absx - m), absy)
    return math.copysign(1.0, x) * r
