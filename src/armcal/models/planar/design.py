"""The planar arm's design view: a plan's information, its gradient, the poses it may hold.

:class:`PlanarPlanInformation` is the planar family's
:class:`~armcal.models.interface.PlanInformation`: every design function
(optimizer, exchange, certificate, criteria) sees a plan of a planar arm through
the columns of :func:`~armcal.models.planar.information.model_columns`: the paper's scaled
columns ``c`` (:func:`~armcal.models.planar.information.scaled_columns`) in the free
coordinates ``C`` of :func:`~armcal.models.planar.information.model_basis` and whitened
per pose.  Pose ``i`` contributes ``I_i = A_i^T P_i A_i`` to the information,
``A_i`` the real ``2 x p_f`` form of ``u_i = c_i C`` and
``P_i = W_i^T W_i = sigma_ref^2 Sigma_i^-1`` its relative precision
(:mod:`armcal.noise`); the identity for isotropic iid noise.

**Gradient.**  The optimizer and the certificate need
``d/dq <Phi, sum_i I_i>`` for a symmetric ``Phi`` ``(p_f, p_f)``.  With ``P``
held fixed the columns give ``2 <dA_i, P_i A_i Phi>``; ``d c_k / d theta_j = i c_k``
for ``k in {j, n + j}`` (link ``j`` turns) and 0 otherwise, so with
``h_i = (P_i (u_i Phi)) C^T`` (``P`` acting on complex numbers as
``a z + b conj(z)``) the derivative by ``theta_j`` is
``2 (t_j + t_(n+j))``, ``t_k = Re(i c_k conj(h_k))``; for ``P = I``, ``C = I``
this is the paper model's ``Re(conj(u Phi) i c)``.  Encoder noise makes ``P_i``
depend on the pose through ``Sigma_i = Sigma_meas + J_q S J_q^T``
(``S = diag(sigma_q^2)``), and that dependence is included, not neglected:
``dP = -P dSigma P / sigma_ref^2``, so the term adds
``<dJ_q, R_i>`` with ``R_i = -2 P_i G_i P_i J_q S / sigma_ref^2`` and
``G_i = A_i Phi A_i^T``; column ``j`` of ``J_q`` is
``sum_(k >= j) i l_k e^(i theta_k)``, whose derivative by ``theta_k`` (``k >= j``)
is ``-l_k e^(i theta_k)``.

**Where the paper's bound still holds.**  The paper's optimum rests on
Hadamard's inequality: every column has unit modulus at every pose, so the
normalized information has a unit diagonal and ``det <= 1``, with equality iff
it is ``I`` (an orthogonal plan).  AM-GM on its eigenvalues gives the same
bound whenever only the *trace* of every pose's information is ``p_f``
(:func:`~armcal.models.planar.information.unit_trace`): ``tr M = p_f`` for every
design, so ``det M <= 1``, and a plan with ``M = I`` is D-, A- and E-optimal.  That holds

* with isotropic iid noise when each free coordinate is one paper column (a
  fixed ``dl``, base coordinate or leading joint offset just drops columns);
* with every parameter free and any instrument covariance, no encoder noise:
  ``A_i A_i^T = (p / 2) I`` (each link's two columns, and the base's, are
  orthonormal in the plane) and ``tr P_i = 2``, so ``tr(A_i^T P_i A_i) = p``.

Encoder noise, or a fixed ``dq_j`` (``j >= 2``) after a free one (links
``j - 1`` and ``j`` then share one column, whose norm depends on ``q_j``),
or a fixed parameter under anisotropic noise, make the trace depend on the pose:
such models have no closed-form bound, and only the Kiefer-Wolfowitz
certificate (:func:`armcal.doe.certify`) says how far a plan is from their optimum.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ...errors import ArmcalError, action
from ...noise import complex_whitening
from ...numerics import ScaledSVD
from ..identifiability import Identifiability
from ..interface import Note
from .criteria import model_singular_values, weighted_information
from .information import (
    check_identifiable,
    covariance_factor,
    model_basis,
    model_columns,
    plan_rows,
    plan_svd,
    scaled_columns,
)
from .kinematics import forward_kinematics, link_jacobian
from .spec import PlanarArmSpec

__all__ = [
    "PlanarPlanInformation",
    "PoseModel",
    "feasible",
    "information_gradient",
    "model_differences",
    "pose_model",
    "q_from_theta_gradient",
    "region_constraints",
    "rotation_invariant",
]


def rotation_invariant(arm: PlanarArmSpec) -> bool:
    """Whether turning joint 1 leaves every pose's information unchanged.

    Without a base offset the columns turn together with joint 1 and only
    their relative angles matter -- unless the instrument's covariance has a
    direction (anisotropic or correlated noise), which the arm turns against.
    Encoder noise alone turns with the arm.
    """
    if arm.base_offset:
        return False
    return arm.noise is None or arm.noise.isotropic_instrument


def model_differences(arm: PlanarArmSpec) -> tuple[Note, ...]:
    """What makes the model differ from the paper's, for design notes (in words:
    :func:`~armcal.models.wording.note_words`).

    Examples
    --------
    >>> arm = PlanarArmSpec([260.0, 180.0], fixed=("dl1", "dl2"))
    >>> model_differences(arm)
    (Note(code='offsets-only', values={'fixed': ('dl1', 'dl2')}),)
    """
    parts = []
    n = arm.n_joints
    if arm.fixed:
        lengths = tuple(f"dl{k}" for k in range(1, n + 1))
        only = set(lengths) <= set(arm.fixed) and len(arm.fixed) == n
        parts.append(Note("offsets-only" if only else "fixed", {"fixed": tuple(arm.fixed)}))
    noise = arm.noise
    if noise is not None and not noise.isotropic_instrument:
        cov = noise.covariance_mm2
        if cov[0, 1] == 0:
            sigmas = {"sx": float(np.sqrt(cov[0, 0])), "sy": float(np.sqrt(cov[1, 1]))}
            parts.append(Note("anisotropic", sigmas))
        else:
            parts.append(Note("correlated"))
    if noise is not None and noise.joint_sigma is not None:
        degrees = tuple(float(v) for v in np.degrees(np.atleast_1d(noise.joint_sigma)))
        parts.append(Note("encoder", {"deg": degrees}))
    return tuple(parts)


@dataclass(frozen=True, eq=False)
class PoseModel:
    """The model's columns of a stack of poses, with what their gradient needs.

    Attributes
    ----------
    columns : ndarray, shape (..., m, p_f)
        :func:`~armcal.models.planar.information.model_columns`: ``sum_i Re(c_i^H c_i)`` is
        the information.
    full : ndarray, shape (..., m, p)
        The paper's scaled columns (before the basis and the whitening).
    basis : ndarray, shape (p, p_f), or None
        ``C`` of :func:`~armcal.models.planar.information.model_basis`; None when every
        parameter is free.
    precision : ndarray, shape (..., m, 2, 2), or None
        ``P_i = W_i^T W_i`` (dimensionless); None for isotropic iid noise.
    joint_jacobian : ndarray, shape (..., m, n), or None
        ``J_q`` as complex numbers (mm/rad) when there is encoder noise.
    targets : int
        Rows per pose: every target of the arm is measured at every pose, so
        the row axis of the arrays above has ``m T`` rows, pose-major
        (:func:`~armcal.models.planar.information.every_target`), the targets'
        columns weighted by :func:`~armcal.models.planar.information.target_weights`.
    """

    columns: np.ndarray
    full: np.ndarray
    basis: np.ndarray | None
    precision: np.ndarray | None
    joint_jacobian: np.ndarray | None
    targets: int = 1


def pose_model(arm: PlanarArmSpec, q: np.ndarray) -> PoseModel:
    """:class:`PoseModel` of poses ``q`` ``(..., m, n)`` (rad) at the nominal parameters."""
    q = np.asarray(q, dtype=float)
    _check_designable(arm)
    noise = arm.noise
    count = arm.n_target_links
    if arm.standard or noise is None or noise.isotropic_iid:
        columns = model_columns(arm, q)  # every target of every pose: count rows per pose
        if arm.standard:
            return PoseModel(columns, columns, None, None, None, count)
        full = scaled_columns(arm, q)
        return PoseModel(columns, full, model_basis(arm)[0], None, None, count)
    # model_columns' own steps, sharing the whitening with the precision (the
    # optimizer's hot loop); tests hold the columns equal to model_columns'.
    full = scaled_columns(arm, q)
    basis = None if arm.free.all() else model_basis(arm)[0]
    w = arm.whitening_at(q)
    alpha, beta = complex_whitening(w)
    unwhitened = full if basis is None else full @ basis
    columns = alpha[..., None] * unwhitened + beta[..., None] * unwhitened.conj()
    precision = np.swapaxes(w, -1, -2) @ w
    joint_jacobian = None
    if noise.joint_sigma is not None:
        turn = link_jacobian(arm, q)  # d tip / d theta_k
        joint_jacobian = q_from_theta_gradient(arm, turn)  # d tip / d q_j
    return PoseModel(columns, full, basis, precision, joint_jacobian)


def _check_designable(arm: PlanarArmSpec) -> None:
    """Several targets are designed for with isotropic iid instrument noise."""
    noise = arm.noise
    if arm.n_target_links > 1 and not (noise is None or noise.isotropic_iid):
        raise ArmcalError(
            f"{arm.name} has {arm.n_target_links} targets: plans for several targets are "
            "designed for isotropic instrument noise without encoder noise; give "
            f"[measurement] sigma_mm as one number, or {action('isotropic-noise')}"
        )


def _real_pair(z: np.ndarray) -> np.ndarray:
    """Complex ``(..., k)`` as real ``(..., 2, k)``: rows x and y."""
    return np.stack([z.real, z.imag], axis=-2)


def q_from_theta_gradient(arm: PlanarArmSpec, grad_theta: np.ndarray) -> np.ndarray:
    """``d/dq = M^T d/dtheta`` ``(..., n)`` for ``theta = M q`` (the arm's joint map).

    For the default map ``theta_j = q_1 + ... + q_j``: d/dq_a = sum over j >= a
    of d/dtheta_j.
    """
    if arm.standard_map:
        return np.cumsum(grad_theta[..., ::-1], axis=-1)[..., ::-1]
    return grad_theta @ arm.joint_map


def information_gradient(arm: PlanarArmSpec, model: PoseModel, phi: np.ndarray) -> np.ndarray:
    """``d/dq_i <Phi, I_i>`` ``(..., m, n)`` for every pose of ``model`` (see the module notes).

    ``phi`` ``(p_f, p_f)`` or one per plan ``(..., p_f, p_f)``, real symmetric
    (a matrix product with the plans' columns ``(..., m, p_f)``).
    """
    n = arm.n_joints
    c = model.full
    u = c if model.basis is None else c @ model.basis  # unwhitened model columns
    v = u @ phi  # (..., m, p_f), complex: phi is real
    if model.precision is None:
        weighted = v
    else:
        a, b = complex_whitening(model.precision)  # P z = a z + b conj(z)
        weighted = a[..., None] * v + b[..., None] * v.conj()
    h = weighted if model.basis is None else weighted @ model.basis.T
    # In this order the paper's model gets its plans bit for bit as before (a complex
    # product rounds differently with its operands swapped when numpy uses FMA).
    t = np.real(h.conj() * 1j * c)
    if model.targets == 1:
        grad_theta = 2.0 * (t[..., :n] + t[..., n : 2 * n])
        if model.joint_jacobian is not None:
            grad_theta = grad_theta + _encoder_gradient(arm, model, u, v)
        return q_from_theta_gradient(arm, grad_theta)
    # Several targets: every link vector turns with its link angle, and a pose's
    # gradient is the sum over the rows of its targets.
    k = arm.n_links
    per_link = 2.0 * (t[..., :k] + t[..., k : 2 * k])  # (..., m T, K)
    turns = np.zeros((k, n))
    turns[np.arange(k), arm.link_joint] = 1.0
    rows = q_from_theta_gradient(arm, per_link @ turns)  # (..., m T, n)
    return rows.reshape(*rows.shape[:-2], -1, model.targets, n).sum(axis=-2)


def _encoder_gradient(
    arm: PlanarArmSpec, model: PoseModel, u: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """The part of the theta gradient through ``P_i(q)``: encoder noise (module notes)."""
    assert arm.noise is not None and arm.noise.joint_sigma is not None
    assert model.precision is not None and model.joint_jacobian is not None
    n = arm.n_joints
    p = model.precision
    g = _real_pair(v) @ np.swapaxes(_real_pair(u), -1, -2)  # A Phi A^T, (..., m, 2, 2)
    k = p @ g @ p / arm.noise.sigma_mm**2
    variance = np.broadcast_to(arm.noise.joint_sigma, (n,)) ** 2
    r = -2.0 * (k @ _real_pair(model.joint_jacobian)) * variance  # (..., m, 2, n)
    if arm.standard_map:
        r = np.cumsum(r, axis=-1)  # column k: sum over j <= k of R[:, j]
    else:
        r = r @ arm.joint_map.T  # column k: sum over j of M_kj R[:, j]
    # d J_q[:, j] / d theta_k = -l_k e^(i theta_k) (k >= j); the dl columns are e^(i theta_k).
    turn = -arm.link_lengths * model.full[..., n : 2 * n]
    return r[..., 0, :] * turn.real + r[..., 1, :] * turn.imag


def feasible(arm: PlanarArmSpec, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
    """Mask ``(..., m)`` of poses inside the joint limits and (if any) the measurement region.

    With several targets every target's point must lie in the region.
    """
    ok = np.all(arm.within_limits(q, tol=tol), axis=-1)
    if arm.region is not None:
        rows, target, _ = plan_rows(arm, q, None)  # every target of every pose
        inside = arm.region.contains(forward_kinematics(arm, rows, target=target), tol=tol)
        ok &= np.all(inside.reshape(*np.shape(q)[:-1], arm.n_target_links), axis=-1)
    return ok


def region_constraints(arm: PlanarArmSpec, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Region constraint values ``g (..., m, k)`` (>= 0 inside) and ``dg/dq (..., m, k, n)``.

    None without a measurement region.  Every target's point gives its own
    constraints (``k`` is the region's count times the targets): the point from
    the forward kinematics, its derivative through the link angles
    (:func:`~armcal.models.planar.kinematics.link_jacobian`), then the joint map.
    """
    if arm.region is None:
        return None
    q = np.asarray(q, dtype=float)
    rows, target, _ = plan_rows(arm, q, None)  # every target of every pose
    g, dg = arm.region.constraints(forward_kinematics(arm, rows, target=target))
    d_tip = link_jacobian(arm, rows, target=target)  # (..., m T, K) complex
    grad_link = dg[..., :1] * d_tip.real[..., None, :] + dg[..., 1:] * d_tip.imag[..., None, :]
    if arm.n_target_links == 1:  # a link per joint
        grad = q_from_theta_gradient(arm, grad_link)
    else:  # every target's last link turns with joint n
        grad = grad_link @ arm.joint_map[arm.link_joint]
    shape = (*q.shape[:-1], arm.n_target_links * g.shape[-1])
    return g.reshape(shape), grad.reshape(*shape, arm.n_joints)


class PlanarPlanInformation:
    """What plans ``q`` ``(..., m, n)`` of a planar arm tell about its free parameters.

    The planar family's :class:`~armcal.models.interface.PlanInformation`, on the
    complex columns of :func:`~armcal.models.planar.information.model_columns`:
    the Hadamard-normalized information of the paper for its model, the weighted
    information over the free parameters otherwise (module notes).  Every target
    of every pose is measured.
    """

    def __init__(self, arm: PlanarArmSpec, q: np.ndarray) -> None:
        self.arm = arm
        self.q = np.asarray(q, dtype=float)

    @property
    def rows_per_pose(self) -> int:
        return self.arm.n_target_links

    @cached_property
    def _model(self) -> PoseModel:
        return pose_model(self.arm, self.q)

    @cached_property
    def _svd(self) -> ScaledSVD:
        return plan_svd(self.arm, self.q)

    def information(self) -> np.ndarray:
        columns = self._model.columns
        rows = columns.shape[-2]  # every target of every pose
        return weighted_information(columns, np.full(columns.shape[:-1], 1.0 / rows))

    def gradient(self, phi: np.ndarray) -> np.ndarray:
        return information_gradient(self.arm, self._model, phi)

    def pose_variance(self, m_inv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # Every pose as a plan of its own (its targets' rows); a pose's information is
        # the mean over its rows, as the plan's is over all its rows.
        model = pose_model(self.arm, self.q[:, None, :])  # q: (k, n) poses
        columns = model.columns
        value = np.einsum("kma,ab,kmb->k", columns.conj(), m_inv, columns).real
        grad = information_gradient(self.arm, model, m_inv)[:, 0, :]
        return value / model.targets, grad / model.targets

    def blocks(self) -> np.ndarray:
        columns = model_columns(self.arm, self.q)  # every target of every pose: T rows per pose
        blocks = np.stack([columns.real, columns.imag], axis=-2)
        return blocks.reshape(*self.q.shape[:-1], -1, columns.shape[-1])

    def svd(self) -> ScaledSVD:
        return self._svd

    @cached_property
    def _singular_values(self) -> np.ndarray:
        return model_singular_values(self.arm, self.q, self._svd)

    def singular_values(self) -> np.ndarray:
        return self._singular_values

    @cached_property
    def _identified(self) -> Identifiability:
        return check_identifiable(self.arm, self.q, svd=self._svd)  # raises: nothing cached

    def check_identifiable(self) -> Identifiability:
        return self._identified

    @cached_property
    def _nominal_factor(self) -> tuple[np.ndarray, np.ndarray]:
        return covariance_factor(self.arm, self.q, None, self._svd)

    def covariance_factor(self, params: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        if params is None:
            return self._nominal_factor
        return covariance_factor(self.arm, self.q, params, self._svd)
