"""The planar n-link arm: geometry, parameters, forward kinematics and Jacobians.

The model is paper eq. (1) with an optional base offset::

    p = (x0, y0) + sum_i (l_i + dl_i) * exp(1j * (theta_i + dtheta_i))
    theta_i  = q_1 + ... + q_i          (commanded, cumulative)
    dtheta_i = dq_1 + ... + dq_i        (joint zero offsets, cumulative)

Two parametrizations of the deviations are used (internal units: mm and rad):

* **user** ``[dl_1..dl_n, dq_1..dq_n, (x0, y0)]`` -- what files and reports show
  (``dl*`` in mm, ``dq*`` in degrees once converted, ``x0, y0`` in mm);
* **paper** ``[dtheta_1..dtheta_n, dl_1..dl_n, (x0, y0)]`` -- the paper's
  ``DeltaPi`` (eq. 6-8), in which the information matrix has the block form
  (17)-(19).

They are related by a constant linear map, :func:`paper_from_user_matrix`.
A rotation of the base about joint 1 cannot be told apart from ``dq1`` (both add
the same angle to every link), so armcal never identifies a base rotation: it is
part of ``dq1``.

All functions are batched on leading axes: joint angles ``q`` of shape
``(m, n)`` give positions ``(m, 2)`` and Jacobians ``(m, 2, p)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from .noise import NoiseModel

__all__ = [
    "Annulus",
    "Box",
    "Parametrization",
    "PlanarArm",
    "Region",
    "forward_kinematics",
    "jacobian",
    "link_angles",
    "link_phasors",
    "paper_from_user_matrix",
    "wrap_angle",
]

Parametrization = Literal["user", "paper"]


@dataclass(frozen=True)
class Annulus:
    """Measurement region: points whose distance from ``center`` lies in ``[r_min, r_max]``.

    Attributes
    ----------
    center : tuple of float
        ``(x, y)`` in mm, in the robot's base frame.
    r_min, r_max : float
        Radii in mm; ``r_min = 0`` makes a disc.
    """

    center: tuple[float, float]
    r_min: float
    r_max: float

    def contains(self, xy: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(...)`` of points ``xy`` ``(..., 2)`` inside the annulus."""
        r = np.hypot(xy[..., 0] - self.center[0], xy[..., 1] - self.center[1])
        return (r >= self.r_min - tol) & (r <= self.r_max + tol)

    def constraints(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Smooth constraint values ``g (..., k)``, ``>= 0`` inside, and ``dg/dxy (..., k, 2)``.

        ``g = ((r_max^2 - r^2), (r^2 - r_min^2)) / r_max`` (mm), the second only
        when ``r_min > 0``.
        """
        d = xy - np.asarray(self.center)
        r2 = np.sum(d**2, axis=-1)
        g = [(self.r_max**2 - r2) / self.r_max]
        dg = [-2.0 * d / self.r_max]
        if self.r_min > 0:
            g.append((r2 - self.r_min**2) / self.r_max)
            dg.append(2.0 * d / self.r_max)
        return np.stack(g, axis=-1), np.stack(dg, axis=-2)


@dataclass(frozen=True)
class Box:
    """Measurement region: the axis-aligned rectangle ``x in [x_lo, x_hi], y in [y_lo, y_hi]``.

    Attributes
    ----------
    x, y : tuple of float
        ``(lo, hi)`` bounds in mm, in the robot's base frame.
    """

    x: tuple[float, float]
    y: tuple[float, float]

    def contains(self, xy: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(...)`` of points ``xy`` ``(..., 2)`` inside the box."""
        px, py = xy[..., 0], xy[..., 1]
        return (
            (px >= self.x[0] - tol)
            & (px <= self.x[1] + tol)
            & (py >= self.y[0] - tol)
            & (py <= self.y[1] + tol)
        )

    def constraints(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Constraint values ``g (..., 4)``, ``>= 0`` inside (mm), and ``dg/dxy (..., 4, 2)``."""
        px, py = xy[..., 0], xy[..., 1]
        g = np.stack([px - self.x[0], self.x[1] - px, py - self.y[0], self.y[1] - py], axis=-1)
        dg = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
        return g, np.broadcast_to(dg, (*xy.shape[:-1], 4, 2))


Region = Annulus | Box


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False, init=False)
class PlanarArm:
    """Nominal geometry of a planar serial arm and what is identified.

    Attributes
    ----------
    link_lengths : ndarray, shape (n,)
        Nominal link lengths ``l_i`` in mm, all positive.
    joint_limits : ndarray, shape (n, 2)
        ``[lo, hi]`` of every commanded joint angle in rad.  Default: every
        joint turns through ``[-pi, pi]``, as in the paper.
    base_offset : bool
        Whether the base position ``(x0, y0)`` in the instrument frame is
        identified (two more parameters).
    name : str
        A label for reports and files.
    noise : NoiseModel or None
        The measurement noise (:mod:`armcal.noise`) from the robot file's
        ``[measurement]`` table, or None when the file does not give it;
        ``sigma=s`` is short for ``noise=NoiseModel.isotropic(s)``.
    region : Annulus or Box or None
        Where the instrument can measure, in the base frame (nominal model).
    fixed : tuple of str
        User parameters held at their nominal value (not identified), e.g.
        ``("dl4",)`` for a link measured otherwise; every other one is free.

    Examples
    --------
    >>> arm = PlanarArm([260.0, 180.0])
    >>> arm.n_joints, arm.n_params, arm.param_names
    (2, 4, ('dl1', 'dl2', 'dq1', 'dq2'))
    """

    link_lengths: np.ndarray
    joint_limits: np.ndarray
    base_offset: bool
    name: str
    noise: NoiseModel | None
    region: Region | None
    fixed: tuple[str, ...]

    def __init__(
        self,
        link_lengths: ArrayLike,
        joint_limits: ArrayLike | None = None,
        *,
        base_offset: bool = False,
        name: str = "arm",
        sigma: float | None = None,
        region: Region | None = None,
        noise: NoiseModel | None = None,
        fixed: Sequence[str] = (),
    ) -> None:
        lengths = _readonly(np.atleast_1d(np.asarray(link_lengths, dtype=float)))
        if lengths.ndim != 1 or lengths.size == 0:
            raise ValueError(f"link_lengths must have shape (n,) with n >= 1, got {lengths.shape}")
        if not np.all(np.isfinite(lengths) & (lengths > 0)):
            raise ValueError(f"link_lengths must be positive and finite, got {lengths.tolist()}")
        n = lengths.size
        if joint_limits is None:
            limits = np.tile([-np.pi, np.pi], (n, 1))
        else:
            limits = np.array(joint_limits, dtype=float)
        if limits.shape != (n, 2):
            raise ValueError(f"joint_limits must have shape ({n}, 2), got {limits.shape}")
        if not (np.all(np.isfinite(limits)) and np.all(limits[:, 0] < limits[:, 1])):
            raise ValueError("joint_limits must be finite with lo < hi for every joint")
        if sigma is not None:
            if noise is not None:
                raise ValueError("give sigma or noise, not both")
            if not (np.isfinite(sigma) and sigma > 0):
                raise ValueError(f"sigma must be positive and finite, got {sigma}")
            noise = NoiseModel.isotropic(float(sigma))
        if noise is not None:
            noise.check_joints(n)
        object.__setattr__(self, "link_lengths", lengths)
        object.__setattr__(self, "joint_limits", _readonly(limits))
        object.__setattr__(self, "base_offset", bool(base_offset))
        object.__setattr__(self, "name", str(name))
        object.__setattr__(self, "noise", noise)
        object.__setattr__(self, "region", region)
        names = self.param_names
        unknown = [f for f in fixed if f not in names]
        if unknown:
            raise ValueError(
                f"unknown parameter {unknown[0]!r} to fix; the parameters of this arm are "
                f"{', '.join(names)}"
            )
        if len(set(fixed)) == len(names):
            raise ValueError("every parameter is fixed: leave at least one free to identify")
        object.__setattr__(self, "fixed", tuple(nm for nm in names if nm in set(fixed)))

    def replace(self, **changes: Any) -> PlanarArm:
        """A copy with some constructor arguments changed (``sigma=`` replaces ``noise``)."""
        kwargs: dict[str, Any] = {
            "link_lengths": self.link_lengths,
            "joint_limits": self.joint_limits,
            "base_offset": self.base_offset,
            "name": self.name,
            "noise": self.noise,
            "region": self.region,
            "fixed": self.fixed,
        }
        if "sigma" in changes:
            kwargs.pop("noise")
        if "base_offset" in changes and "fixed" not in changes:
            kwargs["fixed"] = tuple(f for f in self.fixed if f not in ("x0", "y0"))
        kwargs.update(changes)
        return PlanarArm(**kwargs)

    @property
    def sigma(self) -> float | None:
        """Reference instrument noise (1 std, mm) of :attr:`noise`, or None."""
        return None if self.noise is None else self.noise.sigma_mm

    @property
    def free(self) -> np.ndarray:
        """Boolean mask ``(p,)`` of the identified (free) user parameters."""
        return np.array([name not in self.fixed for name in self.param_names])

    @property
    def n_free(self) -> int:
        """Number of identified parameters ``p_f`` (``p`` minus the fixed ones)."""
        return self.n_params - len(self.fixed)

    @property
    def free_names(self) -> tuple[str, ...]:
        """Names of the free parameters, in the order of :attr:`param_names`."""
        return tuple(name for name in self.param_names if name not in self.fixed)

    @property
    def standard(self) -> bool:
        """Every parameter free and isotropic iid noise: the paper's model, no weights."""
        return not self.fixed and (self.noise is None or self.noise.isotropic_iid)

    @property
    def n_joints(self) -> int:
        """Number of joints (= links) ``n``."""
        return int(self.link_lengths.size)

    @property
    def n_params(self) -> int:
        """Number of identified parameters ``p = 2n`` (``2n + 2`` with base offset)."""
        return 2 * self.n_joints + (2 if self.base_offset else 0)

    @property
    def param_names(self) -> tuple[str, ...]:
        """User parameter names in order: ``dl1..dln, dq1..dqn[, x0, y0]``."""
        n = self.n_joints
        names = [f"dl{i}" for i in range(1, n + 1)] + [f"dq{i}" for i in range(1, n + 1)]
        return tuple(names + (["x0", "y0"] if self.base_offset else []))

    @property
    def param_units(self) -> tuple[str, ...]:
        """Units of the user parameters as shown to users: ``mm`` or ``deg``."""
        n = self.n_joints
        return ("mm",) * n + ("deg",) * n + (("mm", "mm") if self.base_offset else ())

    @property
    def paper_param_names(self) -> tuple[str, ...]:
        """Paper parameter names in order: ``dtheta1..dthetan, dl1..dln[, x0, y0]``."""
        n = self.n_joints
        names = [f"dtheta{i}" for i in range(1, n + 1)] + [f"dl{i}" for i in range(1, n + 1)]
        return tuple(names + (["x0", "y0"] if self.base_offset else []))

    @property
    def display_scale(self) -> np.ndarray:
        """Factors ``(p,)`` from internal units (mm, rad) to display units (mm, deg)."""
        n = self.n_joints
        scale = np.ones(self.n_params)
        scale[n : 2 * n] = np.degrees(1.0)
        return scale

    def params_from_display(
        self, dl_mm: ArrayLike, dq_deg: ArrayLike, base_mm: ArrayLike | None = None
    ) -> np.ndarray:
        """Pack user deviations given in mm and degrees into an internal vector ``(p,)``.

        Examples
        --------
        >>> arm = PlanarArm([1.0, 1.0])
        >>> arm.params_from_display([0.5, 0.0], [180.0, 0.0]).round(6).tolist()
        [0.5, 0.0, 3.141593, 0.0]
        """
        n = self.n_joints
        parts = [np.broadcast_to(dl_mm, (n,)), np.radians(np.broadcast_to(dq_deg, (n,)))]
        if self.base_offset:
            parts.append(np.zeros(2) if base_mm is None else np.broadcast_to(base_mm, (2,)))
        elif base_mm is not None and np.any(np.asarray(base_mm) != 0):
            raise ValueError("a base offset was given but the arm has base_offset = False")
        return np.concatenate(parts).astype(float)

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(m, n)`` of joint angles ``q`` (rad) inside the joint limits."""
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        return (q >= lo - tol) & (q <= hi + tol)


def wrap_angle(angle: np.ndarray) -> np.ndarray:
    """Wrap angles (rad) into ``(-pi, pi]``.

    Examples
    --------
    >>> wrap_angle(np.array([np.pi, -np.pi, 3 * np.pi / 2])).round(6).tolist()
    [3.141593, 3.141593, -1.570796]
    """
    wrapped = np.mod(angle + np.pi, 2 * np.pi) - np.pi
    return np.where(wrapped <= -np.pi, wrapped + 2 * np.pi, wrapped)


def link_angles(q: np.ndarray) -> np.ndarray:
    """Absolute link orientations ``theta_i = q_1 + ... + q_i`` for ``q`` ``(..., n)`` (rad)."""
    return np.cumsum(q, axis=-1)


def paper_from_user_matrix(n: int, *, base_offset: bool = False) -> np.ndarray:
    """Matrix ``M`` ``(p, p)`` with ``paper = M @ user`` for deviation vectors.

    ``dtheta = T dq`` with ``T`` the lower-triangular matrix of ones; ``dl`` and
    the base are copied.  Jacobians transform as ``J_user = J_paper @ M`` and
    covariances as ``cov_user = M^-1 cov_paper M^-T``.

    Examples
    --------
    >>> paper_from_user_matrix(2).astype(int).tolist()
    [[0, 0, 1, 0], [0, 0, 1, 1], [1, 0, 0, 0], [0, 1, 0, 0]]
    """
    p = 2 * n + (2 if base_offset else 0)
    m = np.zeros((p, p))
    m[:n, n : 2 * n] = np.tril(np.ones((n, n)))
    m[n : 2 * n, :n] = np.eye(n)
    if base_offset:
        m[2 * n :, 2 * n :] = np.eye(2)
    return m


def _split(arm: PlanarArm, params: np.ndarray | None):
    """Split user ``params (..., p)`` into ``dl``, ``dq`` ``(..., n)`` and ``base (..., 2)``."""
    n = arm.n_joints
    if params is None:
        return np.zeros(n), np.zeros(n), np.zeros(2)
    params = np.asarray(params, dtype=float)
    if params.shape[-1] != arm.n_params:
        raise ValueError(
            f"params must have shape (..., {arm.n_params}) for {arm.param_names}, "
            f"got {params.shape}"
        )
    base = params[..., 2 * n :] if arm.base_offset else np.zeros((*params.shape[:-1], 2))
    return params[..., :n], params[..., n : 2 * n], base


def _check_q(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim < 1 or q.shape[-1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    return q


def _phasors(arm: PlanarArm, q: np.ndarray, params: np.ndarray | None):
    """Actual link lengths ``(..., n)`` and unit phasors ``exp(i phi)`` ``(..., m, n)``."""
    dl, dq, base = _split(arm, params)
    phi = link_angles(q) + link_angles(dq)[..., None, :]
    return arm.link_lengths + dl, np.exp(1j * phi), base


def link_phasors(arm: PlanarArm, params: np.ndarray) -> np.ndarray:
    """The deviated links and base as complex numbers ``(..., n + 1)``.

    ``z_k = (l_k + dl_k) exp(i dtheta_k)`` for every link, then the base
    ``x0 + i y0`` (0 without a base offset): the tip at joint angles ``q`` is
    ``base + sum_k z_k exp(i theta_k(q))``, linear in these numbers.

    Examples
    --------
    >>> z = link_phasors(PlanarArm([2.0, 1.0]), np.array([0.5, 0.0, np.pi / 2, 0.0]))
    >>> z.round(12).tolist()
    [2.5j, 1j, 0j]
    """
    dl, dq, base = _split(arm, params)
    z = (arm.link_lengths + dl) * np.exp(1j * link_angles(dq))
    return np.concatenate([z, (base[..., 0] + 1j * base[..., 1])[..., None]], axis=-1)


def forward_kinematics(
    arm: PlanarArm, q: np.ndarray, params: np.ndarray | None = None
) -> np.ndarray:
    """End-effector positions for joint angles ``q``.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    params : ndarray, shape (p,) or (..., p), optional
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm)]``; nominal when omitted.
        Leading axes broadcast, giving positions of shape ``(..., m, 2)``.

    Returns
    -------
    ndarray, shape (m, 2) or (..., m, 2)
        ``(x, y)`` in mm (paper eq. 1).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> forward_kinematics(arm, np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[2.0, 1.0]]
    """
    q = _check_q(arm, q)
    lengths, unit, base = _phasors(arm, q, params)
    tip = np.sum(lengths[..., None, :] * unit, axis=-1)
    return np.stack([tip.real, tip.imag], axis=-1) + base[..., None, :]


def jacobian(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    parametrization: Parametrization = "user",
) -> np.ndarray:
    """Jacobian of the end-effector position with respect to the deviations.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    params : ndarray, shape (p,) or (..., p), optional
        User deviations (mm, rad) at which to linearize; nominal when omitted.
        Leading axes broadcast against those of ``q`` (one Jacobian per estimate).
    parametrization : {"user", "paper"}
        Columns ``[dl, dq, (x0, y0)]`` or the paper's ``[dtheta, dl, (x0, y0)]``.

    Returns
    -------
    ndarray, shape (m, 2, p) or (..., m, 2, p)
        ``d(x, y) / d(params)``: mm per mm for lengths and base, mm per rad for angles.

    Notes
    -----
    With ``L_k = l_k + dl_k`` and ``phi_k = theta_k + dtheta_k`` (paper eq. 7-8,
    evaluated at the current deviations)::

        dp/ddtheta_k = L_k (-sin phi_k, cos phi_k),  dp/ddl_k = (cos phi_k, sin phi_k)

    and ``dp/ddq_j = sum_{k >= j} dp/ddtheta_k``.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> (jacobian(arm, np.zeros((1, 2)), parametrization="paper")[0] + 0.0).tolist()
    [[0.0, 0.0, 1.0, 1.0], [2.0, 1.0, 0.0, 0.0]]
    """
    q = _check_q(arm, q)
    lengths, unit, _ = _phasors(arm, q, params)
    d_theta = 1j * lengths[..., None, :] * unit  # complex d(tip)/d(dtheta_k), shape (..., m, n)
    cols = [d_theta, unit]
    if parametrization == "user":
        # d/d dq_j = sum over k >= j of d/d dtheta_k: reverse cumulative sum.
        cols = [unit, np.cumsum(d_theta[..., ::-1], axis=-1)[..., ::-1]]
    elif parametrization != "paper":
        raise ValueError(f"parametrization must be 'user' or 'paper', got {parametrization!r}")
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (*unit.shape[:-1], 2)))
    jc = np.concatenate(cols, axis=-1)
    return np.stack([jc.real, jc.imag], axis=-2)
