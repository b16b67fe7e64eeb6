"""The planar arm's own criteria: the paper's information matrix, D* and Table I, batched.

Functions of plans ``q`` ``(..., m, n)`` (rad) of a planar arm at the nominal
parameters, batched over plans: what the reproduction of the paper's tables and
figures and the random-plan studies evaluate for thousands of plans at once.
The criteria every family has (efficiencies, predicted std, predicted position
error) are :mod:`armcal.criteria`'s, on the family's
:class:`~armcal.models.interface.PlanInformation`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...numerics import ScaledSVD, gram_of_factor
from .information import (
    covariance_factor,
    model_columns,
    plan_svd,
    scaled_jacobian,
)
from .kinematics import jacobian
from .spec import PlanarArmSpec

__all__ = [
    "DStar",
    "dstar",
    "information_matrix",
    "inverse_information",
    "inverse_information_batch",
    "model_singular_values",
    "optimality_sums",
    "scaled_information",
    "weighted_information",
]


def information_matrix(arm: PlanarArmSpec, q: np.ndarray) -> np.ndarray:
    """Information matrix ``F = sum_i J_i^T J_i`` in the paper's parametrization.

    Parameters
    ----------
    arm : PlanarArmSpec
    q : ndarray, shape (..., m, n)
        Plans (joint angles in rad); leading axes batch over plans.

    Returns
    -------
    ndarray, shape (..., p, p)
        Per unit noise variance: ``cov = sigma^2 F^-1`` (paper eq. 16).
    """
    jac = jacobian(arm, q, parametrization="paper")
    return np.einsum("...mki,...mkj->...ij", jac, jac)


def weighted_information(columns: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``sum_i w_i J_i^T J_i`` ``(..., p, p)`` from complex columns and weights ``(..., m)``."""
    return np.einsum("...m,...ma,...mb->...ab", weights, columns.conj(), columns).real


def scaled_information(arm: PlanarArmSpec, q: np.ndarray) -> np.ndarray:
    """Hadamard-normalized information ``Fs = D F D`` ``(..., p, p)`` with unit diagonal."""
    columns = model_columns(arm, np.asarray(q, dtype=float))
    return weighted_information(columns, np.full(columns.shape[:-1], 1 / columns.shape[-2]))


def inverse_information_batch(
    arm: PlanarArmSpec,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    svd: ScaledSVD | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(J^T J)^-1`` in the user parametrization for a stack of plans, with an identifiable mask.

    Parameters
    ----------
    arm : PlanarArmSpec
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans.
    params : ndarray, shape (p,) or (..., p), optional
        Deviations at which to linearize (nominal when omitted).
    svd : ScaledSVD, optional
        ``plan_svd(arm, q)`` when the caller has it already (it does not depend
        on ``params``).

    Returns
    -------
    inverse : ndarray, shape (..., p, p)
        ``(J^T J)^-1`` (mm, rad); entries of singular plans are ``inf``.
    identifiable : ndarray of bool, shape (...)
        False where the rank policy (:data:`armcal.numerics.RANK_RTOL` on the
        singular values of :func:`scaled_jacobian`) calls the plan singular --
        the test of :func:`identifiability` -- or a link has length 0 at ``params``.

    Notes
    -----
    ``J = sqrt(m) H T^-1`` with ``T`` explicit (a rotation and a division by the
    link length per link), so ``(J^T J)^-1 = T V S^-2 V^T T^T / m`` from the SVD
    of ``H``: accurate to ``cond(H) eps``, with no Gram matrix inverted.
    """
    g, ok = covariance_factor(arm, q, params, svd)
    return gram_of_factor(g, ok), ok


def inverse_information(
    arm: PlanarArmSpec,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    svd: ScaledSVD | None = None,
) -> np.ndarray | None:
    """``(J^T J)^-1`` ``(p, p)`` in the user parametrization (mm, rad), or None if singular.

    See :func:`inverse_information_batch`; singular means what
    :func:`identifiability` calls not identifiable.
    """
    inverse, ok = inverse_information_batch(arm, q, params, svd=svd)
    return inverse if bool(ok) else None


def model_singular_values(
    arm: PlanarArmSpec, q: np.ndarray, svd: ScaledSVD | None = None
) -> np.ndarray:
    """Singular values ``(..., p_f)`` of :func:`scaled_jacobian`, those the policy drops set to 0.

    For the paper's model the columns have unit norm and these are the policy's
    own.  For a weighted or reduced model (:attr:`PlanarArmSpec.standard` false) they
    are the singular values of the unnormalized matrix, so that the criteria
    measure the weighted information, not only how orthogonal the columns are.
    """
    svd = plan_svd(arm, q) if svd is None else svd
    if arm.standard:
        return svd.truncated
    raw = np.linalg.svd(scaled_jacobian(arm, q), compute_uv=False)
    return np.where(svd.kept, raw, 0.0)


@dataclass(frozen=True)
class DStar:
    """The paper's D* pair (eq. 20) with ``C' = C / m`` and ``S' = S / m``.

    Attributes
    ----------
    det_c : float or ndarray
        ``det(C')``, at most 1 (Hadamard), 1 exactly at the optimum.
    abs_det_s : float or ndarray
        ``|det(S')|``, 0 at the optimum and identically 0 for odd ``n``.

    Notes
    -----
    ``c_jk = sum_i cos(theta_j - theta_k)`` and ``s_jk = sum_i sin(theta_j - theta_k)``
    (eq. 18).  The paper prints ``C' = [c_jk / n]``; but ``c_jj = m`` for every plan,
    so only division by the number of poses ``m`` gives ``det C' = 1`` at the
    optimum (``C = m I``) as the paper states -- ``/n`` is a typo.  ``S`` is
    skew-symmetric (``s_kj = -s_jk``), so ``det S = det S^T = (-1)^n det S``
    vanishes for odd ``n`` whatever the plan: ``|det S'|`` only carries information
    for even ``n``, and minimizing it is not the same as making ``S = 0``.
    """

    det_c: np.ndarray
    abs_det_s: np.ndarray


def _relative_sums(arm: PlanarArmSpec, q: np.ndarray) -> np.ndarray:
    """``sum_i exp(i (theta_j - theta_k))`` ``(..., n, n)``: ``C + i S`` of eq. (18)."""
    unit = np.exp(1j * arm.link_angles(q))
    return np.einsum("...mj,...mk->...jk", unit, unit.conj())


def dstar(arm: PlanarArmSpec, q: np.ndarray) -> DStar:
    """The paper's D* criterion pair ``det(C')``, ``|det(S')|`` (eq. 20), see :class:`DStar`."""
    m = np.shape(q)[-2]
    sums = _relative_sums(arm, q) / m
    # The paper's own numbers: plain determinants of n x n matrices with entries in
    # [-1, 1] (no overflow); numpy's LU determinant returns 0 for a singular matrix.
    return DStar(np.linalg.det(sums.real), np.abs(np.linalg.det(sums.imag)))


def optimality_sums(arm: PlanarArmSpec, q: np.ndarray) -> dict[str, float]:
    """Every sum of the paper's optimality conditions (21) / Table I, by name.

    For ``1 <= j < k <= n`` the keys ``"cos(q{j+1}+...+q{k})"`` and
    ``"sin(...)"`` hold ``sum_i cos(theta_k - theta_j)`` and the sine, i.e. the
    paper's ``c_jk, s_jk``; with a base offset ``"cos(q1+...+qj)"`` sums (from
    the base columns) are included.  All vanish for an optimal plan.

    Examples
    --------
    >>> from armcal.models.planar.plans import orthogonal_plan
    >>> arm = PlanarArmSpec([2.0, 1.0])
    >>> sums = optimality_sums(arm, orthogonal_plan(arm, 3))
    >>> sorted(sums), max(abs(v) for v in sums.values()) < 1e-12
    (['cos(q2)', 'sin(q2)'], True)
    """
    q = np.asarray(q, dtype=float)
    n = arm.n_joints
    # theta_0 = 0 stands for the base: its pairs appear only when the base is identified.
    theta = np.concatenate([np.zeros((q.shape[0], 1)), arm.link_angles(q)], axis=1)
    out: dict[str, float] = {}
    for j in range(0 if arm.base_offset else 1, n + 1):
        for k in range(j + 1, n + 1):
            label = "+".join(f"q{a}" for a in range(j + 1, k + 1))
            angle = theta[:, k] - theta[:, j]
            out[f"cos({label})"] = float(np.sum(np.cos(angle)))
            out[f"sin({label})"] = float(np.sum(np.sin(angle)))
    return out
