"""The chi-square and F tails and the chi-square quantile of armcal.distributions, against
scipy.special (an independent implementation, Cephes) and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import special

from armcal.distributions import chi2_cdf, chi2_isf, chi2_sf, f_sf

#: Upper-tail probabilities from 1e-15 to 1 - 1e-15: both tails and the middle.
LEVELS = np.concatenate([np.logspace(-15, -1, 15), np.linspace(0.05, 0.95, 19)])
LEVELS = np.concatenate([LEVELS, 1 - np.logspace(-1, -15, 15)])


def _relative(found, expected):
    found, expected = np.asarray(found), np.asarray(expected)
    return float(np.max(np.abs(found - expected) / np.abs(expected)))


@pytest.mark.parametrize("dof", [1, 2, 3, 5, 6, 10, 33, 150, 1000, 30_000, 299_964])
def test_chi_square_tails_match_scipy(dof):
    """Up to 299 964 degrees of freedom (a 10^5-row tracker fit): 1e-12 relative, the
    agreement the judgement's tests ask of its p-values (test_guard_judgement)."""
    x = special.chdtri(dof, LEVELS)
    x = x[np.isfinite(x) & (x > 0)]
    assert _relative(chi2_sf(dof, x), special.chdtrc(dof, x)) < 1e-12
    assert _relative(chi2_cdf(dof, x), special.chdtr(dof, x)) < 1e-12


def test_two_degrees_of_freedom_are_exp_of_minus_half_x():
    x = np.array([1e-8, 0.1, 1.0, 5.99, 30.0, 700.0])
    # exp(-x/2) carries x/2 eps of its argument: 8e-14 at x = 700.
    np.testing.assert_allclose(chi2_sf(2, x), np.exp(-x / 2), rtol=1e-13)
    np.testing.assert_allclose(chi2_cdf(2, x), -np.expm1(-x / 2), rtol=1e-13)
    assert chi2_sf(3, 0.0) == 1.0 and chi2_cdf(3, 0.0) == 0.0


@pytest.mark.parametrize("dfn", [1, 2, 3, 6, 12, 30])
@pytest.mark.parametrize("dfd", [1, 3, 10, 57, 300, 1000, 29_997, 299_961])
def test_f_tail_matches_scipy(dfn, dfd):
    """1e-12 relative up to 10^3 denominator degrees of freedom; beyond, the continued
    fraction near its switch loses about eps per term of its ~sqrt(dfd) terms near 1,
    eps dfd in all (2e-16 x 3 10^5 = 7e-11)."""
    f = special.fdtri(dfn, dfd, 1 - LEVELS[:33])
    f = f[np.isfinite(f) & (f > 0)]
    tolerance = max(1e-12, 2.2e-16 * dfd)
    assert _relative(f_sf(dfn, dfd, f), special.fdtrc(dfn, dfd, f)) < tolerance
    assert f_sf(dfn, dfd, 0.0) == 1.0


@pytest.mark.parametrize("dfd", [4, 57, 29_997, 299_961])
def test_f_with_two_numerator_dof_is_its_closed_form(dfd):
    """``P(F(2, d) > f) = (1 + 2 f / d)^(-d / 2)``, as above."""
    f = np.array([1e-3, 0.1, 0.5, 1.0, 1.9, 2.1, 5.0, 10.0, 30.0])
    exact = np.exp(-(dfd / 2) * np.log1p(2 * f / dfd))
    np.testing.assert_allclose(f_sf(2, dfd, f), exact, rtol=max(1e-13, 2.2e-16 * dfd))


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 12])
@pytest.mark.parametrize("p", [1e-9, 0.05, 0.5, 0.999])
def test_chi_square_quantile_inverts_the_tail(dof, p):
    """Newton's steps on the tail, to the last digits: the tail at it within 1e-12 of p,
    and scipy's chdtri within what p's own round-off moves x (near p = 1 the tail is
    flat: 1 - p carries eps / (1 - p), and x as (1 - p)^2 twice that: 4.4e-13)."""
    x = chi2_isf(dof, p)
    assert abs(x - special.chdtri(dof, p)) <= max(1e-13, 4.4e-16 / (1 - p)) * x
    assert abs(float(chi2_sf(dof, x)) - p) <= 1e-12 * p
    with pytest.raises(ValueError):
        chi2_isf(dof, 1.0)


@pytest.mark.parametrize("dof", [1, 4, 300, 299_964])
def test_a_chi_square_far_below_its_dof_is_scipy_s(dof):
    """A noiseless fit's chi-square (1e-300 to 1) against thousands of degrees of freedom:
    the lower tail underflows to 0 where scipy's does, the upper is 1; both within 1e-12
    elsewhere, as above."""
    x = np.array([1e-300, 1e-20, 1e-5, 1.0])
    found, expected = chi2_cdf(dof, x), special.chdtr(dof, x)
    assert np.array_equal(found == 0, expected == 0)
    nonzero = expected > 0
    if nonzero.any():
        assert _relative(found[nonzero], expected[nonzero]) < 1e-12
    assert _relative(chi2_sf(dof, x), special.chdtrc(dof, x)) < 1e-12
