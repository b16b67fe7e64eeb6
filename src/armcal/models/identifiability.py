"""What the measurements can and cannot separate: identifiability, in words a user reads.

The rank policy of :mod:`armcal.numerics` decides from the singular values of a
model's scaled Jacobian whether its free parameters are identifiable.  This
module holds what every family shares to say the answer: the
:class:`Identifiability` record, the unseen directions as parameter
combinations in echelon form (:func:`combination`, :func:`row_echelon`), and
lists in prose (:func:`listing`).  Each family computes its own record from its
own scaled Jacobian (:meth:`armcal.models.interface.FitModel.identifiability`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..numerics import COND_WARN

__all__ = [
    "Identifiability",
    "combination",
    "listing",
    "row_echelon",
]


@dataclass(frozen=True)
class Identifiability:
    """Rank analysis of a plan's column-scaled Jacobian (:func:`scaled_jacobian`).

    Attributes
    ----------
    rank : int
        Numerical rank: singular values above ``RANK_RTOL`` times the largest
        (:mod:`armcal.numerics`).
    n_params : int
        Number of parameters ``p``.
    singular_values : ndarray, shape (p,)
        Singular values of the Jacobian with unit-norm columns divided by
        ``sqrt(m)``, descending (zeros when ``2m < p``); all 1 for an orthogonal plan.
    unidentifiable : tuple of str
        Parameters that have a component in the null space (cannot be identified).
    combinations : tuple of str
        A basis of the null space written as parameter combinations in display
        units (mm, deg), each with leading coefficient 1: moving the parameters
        along one of these changes no measured position to first order.
    poorly_determined : tuple of str
        The same for every direction whose relative singular value is at most
        ``1 / COND_WARN`` (the null space included): what an ``ill-conditioned``
        warning names.
    joints_to_vary : tuple of int
        Joints (1-based) whose angles the plan should vary more to see the
        unseen or poorly determined combinations: for a combination of the
        parameters of links ``a..b`` (the base counting as link 0), joints
        ``a+1..b`` set their relative angles.
    """

    rank: int
    n_params: int
    singular_values: np.ndarray
    unidentifiable: tuple[str, ...]
    combinations: tuple[str, ...]
    poorly_determined: tuple[str, ...] = ()
    joints_to_vary: tuple[int, ...] = ()

    @property
    def identifiable(self) -> bool:
        """True when the Jacobian has full column rank."""
        return self.rank == self.n_params

    @property
    def condition_number(self) -> float:
        """Ratio of largest to smallest singular value (inf when one is 0)."""
        s = self.singular_values
        if s.size < self.n_params or s[-1] == 0:
            return float("inf")
        return float(s[0] / s[-1])

    @property
    def ill_conditioned(self) -> bool:
        """Identifiable, but with a condition number above ``COND_WARN``."""
        return self.identifiable and self.condition_number > COND_WARN


def combination(vector: np.ndarray, names: Sequence[str], *, drop: float = 1e-6) -> str:
    """A direction ``(p,)`` written as a combination of ``names``, leading coefficient 1."""
    # Leading coefficient 1 (the echelon pivot), so combinations read "dl1 - dl2";
    # terms below `drop` times the leading one are left out.
    leading = np.flatnonzero(np.abs(vector) > drop * np.max(np.abs(vector)))[0]
    coeffs = vector / vector[leading]
    terms = []
    for c, name in zip(coeffs, names, strict=True):
        if abs(c) < drop:
            continue
        mag = "" if abs(abs(c) - 1) < 1e-9 else f"{abs(c):.3g}*"
        sign = "-" if c < 0 else "+"
        terms.append(f"{sign} {mag}{name}")
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else "-" + text[2:]


def row_echelon(basis: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Reduced row echelon form of a basis ``(k, p)``: the same span, sparse rows.

    The SVD returns an arbitrary rotation of the null space; the echelon form
    gives each unseen combination a parameter of its own (e.g. ``dl1 - dl2``
    and ``dq1 - 3*dq2`` rather than two mixtures of all four).  Entries below
    ``tol`` times the largest are not used as pivots.
    """
    rows = basis.copy()
    scale = np.max(np.abs(rows)) if rows.size else 0.0
    pivot_row = 0
    for col in range(rows.shape[1]):
        if pivot_row == rows.shape[0]:
            break
        best = pivot_row + int(np.argmax(np.abs(rows[pivot_row:, col])))
        if abs(rows[best, col]) <= tol * scale:
            continue
        rows[[pivot_row, best]] = rows[[best, pivot_row]]
        rows[pivot_row] /= rows[pivot_row, col]
        others = np.arange(rows.shape[0]) != pivot_row
        rows[others] -= np.outer(rows[others, col], rows[pivot_row])
        pivot_row += 1
    return rows


def listing(items: Sequence[object]) -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"``."""
    words = [str(item) for item in items]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]
