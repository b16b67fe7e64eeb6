"""The chi-square and F distributions' tails and the chi-square's quantile.

What the judgement of a fit needs (:mod:`armcal.identification.judgement`,
:mod:`armcal.identification.robust`, the moved-instrument test): the upper and lower
tail of chi-square, the upper tail of F, and the chi-square quantile of a small
number of degrees of freedom.  ``scipy.special`` has them, but importing it costs
about 0.4 s of CPU, more than the statistics of a 10^5-row calibration; these are
computed here from the regularized incomplete gamma and beta functions:

* ``P(a, x)`` by its power series where ``x < a + 1``, ``Q(a, x)`` by its continued
  fraction elsewhere, each tail from its own expansion and the other as ``1 - it``
  only where that is at least about a half (no cancellation);
* ``I_x(a, b)`` by its continued fraction on the side of ``(a + 1) / (a + b + 2)``
  where it converges fast, the other side from the symmetry
  ``I_x(a, b) = 1 - I_{1-x}(b, a)`` (Abramowitz and Stegun 26.5.8; the continued
  fractions are the classical ones, 6.5.29-31 and 26.5.8, evaluated by the modified
  Lentz method);
* the prefactors ``x^a e^-x / Gamma(a)`` and ``x^a (1 - x)^b / B(a, b)`` through
  Stirling's series where a parameter is large (``ln Gamma(a) = (a - 1/2) ln a - a +
  ln(2 pi) / 2 + 1/(12 a) - 1/(360 a^3) + ...``), so that a chi-square of 3 10^5
  degrees of freedom keeps the accuracy of a small one.

Against scipy (tests/test_distributions.py): the chi-square tails within ``1e-13``
relative at any degrees of freedom; F's tail within ``1e-13`` up to 10^3 denominator
degrees of freedom, and about ``eps dfd`` beyond (``1.6e-11`` at 3 10^5, where its
continued fraction near the switch runs long with terms near 1): far below what a
p-value decides.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["chi2_cdf", "chi2_isf", "chi2_sf", "f_sf"]

#: Relative size of the last term (or continued-fraction factor) that ends an expansion.
_EPS = 1e-16
#: Terms at most of an expansion: sqrt(a) grows them; 3 10^5 degrees of freedom take ~4000.
_MOST_TERMS = 200_000
#: Parameters from which the prefactors use Stirling's series (below: math.lgamma).
_STIRLING_FROM = 10.0
#: Lentz's guard against a zero denominator.
_TINY = 1e-300


def chi2_sf(dof: ArrayLike, x: ArrayLike) -> np.ndarray:
    """``P(X > x)`` for ``X`` chi-square with ``dof`` degrees of freedom (scipy's ``chdtrc``).

    Examples
    --------
    >>> round(float(chi2_sf(2, 2 * np.log(20))), 15)  # exp(-x / 2) for 2 dof
    0.05
    """
    return _gamma_tails(np.asarray(dof, dtype=float) / 2, np.asarray(x, dtype=float) / 2)[1]


def chi2_cdf(dof: ArrayLike, x: ArrayLike) -> np.ndarray:
    """``P(X <= x)`` for ``X`` chi-square with ``dof`` degrees of freedom (``chdtr``)."""
    return _gamma_tails(np.asarray(dof, dtype=float) / 2, np.asarray(x, dtype=float) / 2)[0]


def f_sf(dfn: ArrayLike, dfd: ArrayLike, f: ArrayLike) -> np.ndarray:
    """``P(F > f)`` for ``F`` of ``(dfn, dfd)`` degrees of freedom (scipy's ``fdtrc``):
    ``I_x(dfd / 2, dfn / 2)`` at ``x = dfd / (dfd + dfn f)``.

    Examples
    --------
    >>> round(float(f_sf(2, 2, 1.0)), 15)  # 1 / (1 + f) for (2, 2)
    0.5
    """
    dfn, dfd, f = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (dfn, dfd, f)))
    f = np.maximum(f, 0.0)
    y = dfn * f / (dfd + dfn * f)  # 1 - x, without cancellation
    x = dfd / (dfd + dfn * f)
    return _beta_tail(dfd / 2, dfn / 2, x, y)


def chi2_isf(dof: float, p: float) -> float:
    """``x`` with ``chi2_sf(dof, x) = p`` (``chdtri``), for ``0 < p < 1``: Newton's steps
    on the tail from the Wilson-Hilferty start, kept within a bracket that halves.

    Examples
    --------
    >>> round(chi2_isf(2, 0.05), 12) == round(2 * math.log(20), 12)
    True
    """
    if not 0.0 < p < 1.0 or not dof > 0:
        raise ValueError("chi2_isf needs dof > 0 and 0 < p < 1")
    z = _normal_isf(p)
    h = 2.0 / (9.0 * dof)
    x = max(dof * (1.0 - h + z * math.sqrt(h)) ** 3, 1e-300)
    low, high = 0.0, math.inf
    for _ in range(200):
        miss = float(chi2_sf(dof, x)) - p
        if miss > 0:
            low = x  # the tail is still above p: x lies further out
        else:
            high = x
        density = math.exp(_log_chi2_density(dof, x))
        step = miss / density if density > 0 else math.inf
        new = x + step
        if not low < new < high:  # Newton left the bracket: halve it
            new = 2 * low + 1.0 if math.isinf(high) else (low + high) / 2
        if abs(new - x) <= 4e-16 * x:
            return new
        x = new
    return x


# --------------------------------------------------------------------------- gamma


def _gamma_tails(a: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``P(a, x)`` and ``Q(a, x)`` (regularized lower and upper incomplete gamma)."""
    a, x = np.broadcast_arrays(a, x)
    lower, upper = np.zeros(a.shape), np.ones(a.shape)
    inside = x > 0
    series = inside & (x < a + 1)
    fraction = inside & ~series
    if series.any():
        found = _gamma_series(a[series], x[series])
        lower[series], upper[series] = found, 1.0 - found
    if fraction.any():
        found = _gamma_fraction(a[fraction], x[fraction])
        lower[fraction], upper[fraction] = 1.0 - found, found
    return lower, upper


def _log_gamma_prefactor(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``ln(x^a e^-x / Gamma(a))``: for large ``a`` as ``-a (t - ln(1 + t)) + ln(a / 2 pi) / 2
    - c(a)`` with ``t = (x - a) / a`` and ``c`` Stirling's correction, whose terms are each
    of the size of the result (the direct form cancels terms of ``a ln a``)."""
    out = np.empty(a.shape)
    large = a >= _STIRLING_FROM
    if large.any():
        al, xl = a[large], x[large]
        t = (xl - al) / al
        gap = _t_minus_log1p(t)
        far = t < -0.5  # x far below a: ln(x / a) directly (1 + t may round to 0)
        gap[far] = t[far] - (np.log(xl[far]) - np.log(al[far]))
        out[large] = -al * gap + 0.5 * np.log(al / (2 * math.pi)) - _stirling(al)
    small = ~large
    if small.any():
        as_, xs = a[small], x[small]
        out[small] = as_ * np.log(xs) - xs - _lgamma(as_)
    return out


def _gamma_series(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``P(a, x) = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1) ... (a + n))``."""
    term = np.ones(a.shape)
    total = np.ones(a.shape)
    active = np.arange(a.size)
    for n in range(1, _MOST_TERMS):
        term[active] *= x[active] / (a[active] + n)
        total[active] += term[active]
        active = active[term[active] > _EPS * total[active]]
        if active.size == 0:
            break
    return np.exp(_log_gamma_prefactor(a, x)) * total / a


def _gamma_fraction(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``Q(a, x) = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - ...))``."""
    b = x + 1.0 - a
    c = np.full(a.shape, 1.0 / _TINY)
    d = 1.0 / np.where(np.abs(b) < _TINY, _TINY, b)
    h = d.copy()
    active = np.arange(a.size)
    for i in range(1, _MOST_TERMS):
        an = -i * (i - a[active])
        b[active] += 2.0
        dd = an * d[active] + b[active]
        dd = np.where(np.abs(dd) < _TINY, _TINY, dd)
        cc = b[active] + an / c[active]
        cc = np.where(np.abs(cc) < _TINY, _TINY, cc)
        d[active] = 1.0 / dd
        c[active] = cc
        delta = d[active] * cc
        h[active] *= delta
        active = active[np.abs(delta - 1.0) > _EPS]
        if active.size == 0:
            break
    return np.exp(_log_gamma_prefactor(a, x)) * h


# --------------------------------------------------------------------------- beta


def _beta_tail(a: np.ndarray, b: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``I_x(a, b)`` with ``y = 1 - x`` given exactly: the continued fraction where ``x``
    lies below ``(a + 1) / (a + b + 2)``, else ``1 - I_y(b, a)``."""
    out = np.where(x <= 0, 0.0, 1.0)
    inside = (x > 0) & (y > 0)
    direct = inside & (x < (a + 1) / (a + b + 2))
    mirrored = inside & ~direct
    if direct.any():
        out[direct] = _beta_fraction(a[direct], b[direct], x[direct], y[direct])
    if mirrored.any():
        out[mirrored] = 1.0 - _beta_fraction(b[mirrored], a[mirrored], y[mirrored], x[mirrored])
    return out


def _beta_fraction(a: np.ndarray, b: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``I_x(a, b) = x^a y^b / (a B(a, b)) / (1 + d1 / (1 + d2 / (1 + ...)))``, ``y = 1 - x``."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = np.ones(a.shape)
    d = 1.0 - qab * x / qap
    d = 1.0 / np.where(np.abs(d) < _TINY, _TINY, d)
    h = d.copy()
    active = np.arange(a.size)
    for m in range(1, _MOST_TERMS):
        at, bt, xt = a[active], b[active], x[active]
        m2 = 2 * m
        for coefficient in (
            m * (bt - m) * xt / ((qam[active] + m2) * (at + m2)),
            -(at + m) * (qab[active] + m) * xt / ((at + m2) * (qap[active] + m2)),
        ):
            dd = 1.0 + coefficient * d[active]
            d[active] = 1.0 / np.where(np.abs(dd) < _TINY, _TINY, dd)
            cc = 1.0 + coefficient / c[active]
            c[active] = np.where(np.abs(cc) < _TINY, _TINY, cc)
            delta = d[active] * c[active]
            h[active] *= delta
        active = active[np.abs(delta - 1.0) > _EPS]
        if active.size == 0:
            break
    # ln x and ln y each from the smaller of the two: a large a times ln x near 1 would
    # carry x's own round-off.
    log_x = np.where(y < 0.5, np.log1p(-np.minimum(y, 0.5)), np.log(np.maximum(x, _TINY)))
    log_y = np.where(x < 0.5, np.log1p(-np.minimum(x, 0.5)), np.log(np.maximum(y, _TINY)))
    return np.exp(a * log_x + b * log_y - _log_beta(a, b)) * h / a


def _log_beta(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``ln B(a, b)``: for a large parameter through Stirling's series of
    ``ln Gamma(big + small) - ln Gamma(big)``, which the direct form would cancel."""
    big, small = np.maximum(a, b), np.minimum(a, b)
    out = np.empty(a.shape)
    large = big >= _STIRLING_FROM
    if large.any():
        g, s = big[large], small[large]
        ratio = (g - 0.5) * np.log1p(s / g) + s * np.log(g + s) - s
        ratio += _stirling(g + s) - _stirling(g)
        out[large] = _lgamma(s) - ratio
    rest = ~large
    if rest.any():
        out[rest] = _lgamma(a[rest]) + _lgamma(b[rest]) - _lgamma(a[rest] + b[rest])
    return out


# --------------------------------------------------------------------------- pieces


def _stirling(a: np.ndarray) -> np.ndarray:
    """``ln Gamma(a) - ((a - 1/2) ln a - a + ln(2 pi) / 2)`` for ``a >= 10``: Stirling's
    series to ``a^-9`` (its next term is below ``1e-17`` there)."""
    inv = 1.0 / a
    inv2 = inv * inv
    return inv * (1 / 12 - inv2 * (1 / 360 - inv2 * (1 / 1260 - inv2 * (1 / 1680 - inv2 / 1188))))


def _t_minus_log1p(t: np.ndarray) -> np.ndarray:
    """``t - ln(1 + t)`` for ``t > -1``, by its series where ``|t|`` is small (the difference
    cancels); ``inf`` where ``1 + t`` rounds to 0 (the caller's)."""
    with np.errstate(divide="ignore"):
        out = t - np.log1p(t)
    small = np.abs(t) < 0.1
    if small.any():
        ts = t[small]
        total = np.zeros(ts.shape)
        power = ts * ts
        for k in range(2, 40):  # sum (-1)^k t^k / k, to 0.1^40
            total += (1.0 if k % 2 == 0 else -1.0) * power / k
            power = power * ts
        out[small] = total
    return out


def _lgamma(values: np.ndarray) -> np.ndarray:
    """``ln Gamma`` of each value (the standard library's, value by value)."""
    flat = np.asarray(values, dtype=float).ravel()
    unique, where = np.unique(flat, return_inverse=True)
    found = np.array([math.lgamma(v) for v in unique.tolist()])
    return found[where].reshape(np.shape(values))


def _log_chi2_density(dof: float, x: float) -> float:
    """``ln`` of chi-square's density at ``x`` (``x^(k/2-1) e^(-x/2) / (2^(k/2) Gamma(k/2))``)."""
    half = dof / 2
    return (half - 1) * math.log(x) - x / 2 - half * math.log(2.0) - math.lgamma(half)


def _normal_isf(p: float) -> float:
    """The standard normal's upper quantile, to a few digits (a start for Newton):
    Abramowitz and Stegun 26.2.23."""
    q = min(p, 1.0 - p)
    t = math.sqrt(-2.0 * math.log(q))
    z = t - (2.515517 + 0.802853 * t + 0.010328 * t * t) / (
        1 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t**3
    )
    return z if p < 0.5 else -z
