"""The description of a planar arm to calibrate: geometry, joint limits, noise, fixed parameters.

:class:`PlanarArmSpec` is the paper's arm (eq. 1) with the extensions of
:mod:`armcal.models.planar.geometry` -- joint maps, several targets, a base pose --
and what a calibration needs besides the geometry: the joint limits, the
instrument's noise (:mod:`armcal.noise`), the parameters held fixed and the
region where the instrument measures (:mod:`armcal.models.regions`).  The
planar family's analysis (:mod:`~armcal.models.planar.information`,
:mod:`~armcal.models.planar.closed_form`) works on it;
:class:`armcal.models.planar.arm.PlanarArm` adds the methods of the fit-model
interface on top and is what users construct.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from ...noise import NoiseModel, relative_noise
from ..interface import Conditions
from ..regions import Region
from .geometry import PlanarGeometry, Target, checked_link_lengths
from .kinematics import joint_jacobian

__all__ = [
    "PlanarArmSpec",
]


_Spec = TypeVar("_Spec", bound="PlanarArmSpec")

#: Constructor arguments that decide the parameter names.
_STRUCTURE = frozenset({"link_lengths", "base_offset", "targets", "base_rotation"})


@dataclass(frozen=True, eq=False, init=False)
class PlanarArmSpec(PlanarGeometry):
    """A planar arm to calibrate, as the planar family's analysis reads it.

    The fields and derived properties of :class:`armcal.models.planar.arm.PlanarArm`
    (which see) without the fit-model methods: the family's modules below that
    class take this type.
    """

    joint_limits: np.ndarray
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
        joint_map: ArrayLike | None = None,
        targets: Sequence[Target] = (),
        base_rotation: bool = False,
        joint_offsets: ArrayLike | None = None,
    ) -> None:
        n = checked_link_lengths(link_lengths).size
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
        super().__init__(
            link_lengths,
            name=name,
            base_offset=base_offset,
            joint_map=joint_map,
            targets=targets,
            base_rotation=base_rotation,
            joint_offsets=joint_offsets,
        )
        limits.flags.writeable = False
        object.__setattr__(self, "joint_limits", limits)
        object.__setattr__(self, "noise", noise)
        object.__setattr__(self, "region", region)
        names = self.param_names
        unknown = [f for f in fixed if f not in names]
        if unknown:
            raise ValueError(
                f"unknown parameter {unknown[0]!r} to fix; the parameters of this arm are "
                f"{', '.join(names)}"
            )
        held = set(fixed)
        if self.base_rotation and not any(
            abs(self.rotation_direction[names.index(f)]) > 1e-12 for f in held
        ):
            held.add(self.rotation_partner)
        if len(held) == len(names):
            raise ValueError("every parameter is fixed: leave at least one free to identify")
        object.__setattr__(self, "fixed", tuple(nm for nm in names if nm in held))

    def replace(self: _Spec, **changes: Any) -> _Spec:
        """A copy with some constructor arguments changed (``sigma=`` replaces ``noise``)."""
        kwargs: dict[str, Any] = {
            "link_lengths": self.link_lengths,
            "joint_limits": self.joint_limits,
            "base_offset": self.base_offset,
            "name": self.name,
            "noise": self.noise,
            "region": self.region,
            "fixed": self.fixed,
            "joint_map": self.joint_map,
            "targets": self.targets,
            "base_rotation": self.base_rotation,
            "joint_offsets": self.joint_offsets,
        }
        if "sigma" in changes:
            kwargs.pop("noise")
        kwargs.update(changes)
        if "fixed" not in changes and _STRUCTURE & set(changes):
            # The parameter names may change: carry over the fixed parameters that still
            # exist; the joint offset held only because of the base rotation is decided
            # anew.  (Without such a change every fixed parameter stays as it is.)
            carried = [
                f for f in self.fixed if not (self.base_rotation and f == self.rotation_partner)
            ]
            names = type(self)(**{**kwargs, "fixed": ()}).param_names
            kwargs["fixed"] = tuple(f for f in carried if f in names)
        return type(self)(**kwargs)

    @property
    def joint_limits_deg(self) -> np.ndarray:
        """The joint limits in degrees, rounded to 1e-9 deg so that a limit written as
        120 in a file is written back as 120, not 119.99999999999999."""
        return np.round(np.degrees(self.joint_limits), 9)

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
    def complete(self) -> bool:
        """Whether the free parameters map one to one onto the link vectors and the base.

        Then the model is linear in the link phasors over exactly the free
        parameters (the closed form applies): every parameter free, or with a
        base rotation, exactly the one joint offset that it replaces held.
        """
        if self.base_rotation:
            return len(self.fixed) == 1 and self.fixed[0] in self.rotation_names()
        return not self.fixed

    @property
    def standard(self) -> bool:
        """Linear in the link phasors over the free parameters and isotropic iid noise.

        The paper's model up to a constant reparametrization (joint map, targets,
        base rotation): no weights, and the closed form is exact.
        """
        return self.complete and (self.noise is None or self.noise.isotropic_iid)

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(m, n)`` of joint angles ``q`` (rad) inside the joint limits."""
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        return (q >= lo - tol) & (q <= hi + tol)

    def covariances_at(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        row_sigma: np.ndarray | None = None,
        *,
        target: np.ndarray | None = None,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        """``Sigma_i`` ``(..., m, 2, 2)`` in mm^2 of measurements at ``q`` ``(..., m, n)``.

        The noise model ``noise`` (default: the arm's own) with its encoder term
        linearized at the deviations ``params`` (``(p,)`` or ``(..., p)``; nominal
        when omitted) through the joint Jacobian; ``row_sigma`` ``(m,)`` (mm)
        replaces the instrument covariance row by row; ``target`` ``(m,)`` is every
        row's target on an arm with several.
        """
        noise, q, joint = self._noise_at(q, params, target, noise)
        return noise.pose_covariances(q.shape[:-1], joint_jacobian=joint, row_sigma=row_sigma)

    def _noise_at(
        self,
        q: np.ndarray,
        params: np.ndarray | None,
        target: np.ndarray | None,
        noise: NoiseModel | None,
    ) -> tuple[NoiseModel, np.ndarray, np.ndarray | None]:
        """The noise model (``noise`` or the arm's), the rows, and the joint Jacobian its
        encoder term needs (None without encoder noise)."""
        noise = self.noise if noise is None else noise
        if noise is None:
            raise ValueError(f"{self.name} has no noise model: give one")
        q = np.asarray(q, dtype=float)
        joint = (
            None if noise.joint_sigma is None else joint_jacobian(self, q, params, target=target)
        )
        return noise, q, joint

    def relative_whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        """The relative whitening ``W_i`` ``(..., m, 2, 2)`` of rows, None where it is ``I``.

        The arm's noise model (unit isotropic noise when it has none: weights are
        relative), its encoder term linearized at ``params``, the rows' own sigma
        where the conditions give it; None for isotropic iid noise and no per-row
        sigma, where every row weighs the same.
        """
        noise = relative_noise(self.noise)
        if noise.isotropic_iid and conditions.sigma_mm is None:
            return None
        at = params if noise.joint_sigma is not None else None
        return self.whitening_at(
            conditions.q, at, conditions.sigma_mm, target=conditions.target, noise=noise
        )

    def whitening_at(
        self,
        q: np.ndarray,
        params: np.ndarray | None = None,
        row_sigma: np.ndarray | None = None,
        *,
        target: np.ndarray | None = None,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        """Relative whitening ``W_i`` ``(..., m, 2, 2)`` of :meth:`covariances_at`.

        ``W_i^T W_i = sigma_ref^2 Sigma_i^-1`` (:meth:`armcal.noise.NoiseModel.whitening`).
        """
        noise, q, joint = self._noise_at(q, params, target, noise)
        return noise.whitening(q.shape[:-1], joint_jacobian=joint, row_sigma=row_sigma)
