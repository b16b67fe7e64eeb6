"""The planar arm as a fit model: :class:`PlanarArm`, the paper's family.

:class:`PlanarArm` is what users construct.  Its description -- geometry, joint
limits, noise, fixed parameters, measuring region -- is
:class:`~armcal.models.planar.spec.PlanarArmSpec`'s; this module adds the methods
of :class:`~armcal.models.interface.FitModel`, each a thin call into the family's
modules: kinematics (:mod:`~armcal.models.planar.kinematics`), the scaled
Jacobian and identifiability (:mod:`~armcal.models.planar.information`) and the
closed form (:mod:`~armcal.models.planar.closed_form`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ...noise import NoiseModel
from ...numerics import ScaledSVD
from ..defaults import LARGE_ANGLE_DEG, MinimalPlanar, RigidLoads
from ..identifiability import Identifiability
from ..interface import (
    Conditions,
    DeviationBounds,
    LinearPositions,
    Loads,
    PaperCriteria,
    refuse_feature,
)
from . import design as planar_design
from .closed_form import (
    PlanarClosedForm,
    projected_start,
    shared_plan_factor,
    user_from_links,
)
from .criteria import dstar, optimality_sums
from .design import PlanarPlanInformation
from .geometry import split_params, wrap_angle
from .information import (
    check_identifiable,
    covariance_factor,
    identifiability,
    plan_rows,
    plan_svd,
    unit_trace,
)
from .kinematics import (
    check_target,
    forward_kinematics,
    jacobian,
    joint_jacobian,
    link_phasors,
    link_units,
    tool_angles,
)
from .plans import PaperPlans
from .spec import PlanarArmSpec

__all__ = [
    "INSTRUMENT_PARAMS",
    "LARGE_LENGTH_FRACTION",
    "PlanarArm",
]

#: A link-length deviation beyond this fraction of its nominal length is implausible for
#: a calibration: 10 % is several times a calibration's deviation even on a 100 mm link
#: (10 mm against a few), yet far from what a unit mistake gives (-99.9 % or -90 % of
#: every link); any bound between a few percent and 90 % separates the two.
LARGE_LENGTH_FRACTION = 0.10

#: The parameters that place the arm in the instrument frame, not part of the robot.
INSTRUMENT_PARAMS = ("x0", "y0", "phi0")


class PlanarArm(RigidLoads, MinimalPlanar, PlanarArmSpec):
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
    joint_map : ndarray, shape (n, n)
        ``M`` with link angles ``theta = M q`` and ``dtheta = M dq``: how the
        controller's joint readings give the absolute link angles.  Default
        :func:`standard_joint_map` (each joint relative to the previous link); a
        joint that counts the other way round has a ``-1``, a joint reported
        relative to the horizon (coupled axes) a row with a single 1.
    targets : tuple of Target
        Several targets on the end effector, each with its own last link
        (parameters ``dl{n}@{label}``, ``dq{n}@{label}``).  Empty: one target,
        the end of link ``n`` (parameters ``dl{n}``, ``dq{n}``).
    base_rotation : bool
        Whether the rotation ``phi0`` of the base in the instrument frame is
        identified (3-D instrument data, whose fitted in-plane axes are
        arbitrary).  It turns every link like one joint-offset direction
        ``dq = M^-1 (1, ..., 1)``, so one joint offset on that direction is
        held (:attr:`rotation_partner`, ``dq1`` for the default joint map)
        unless ``fixed`` already removes it (e.g. ``fixed = ("phi0",)``).
    joint_offsets : ndarray, shape (n,)
        Known joint zero offsets ``o`` (rad), part of the nominal model:
        ``theta = M (q + o)``.  Zero by default; a calibrated arm exported as a
        robot file (``armcal export``) carries its identified offsets here.

    Notes
    -----
    The arm has ``K = n - 1 + max(1, len(targets))`` *links* (link vectors):
    links ``1..n-1`` and one last link per target.  Its parameters are, in order,
    ``dl`` ``(K,)`` (mm), ``dq`` ``(K,)`` (rad, joint space), ``x0, y0`` (mm) with
    a base offset, and ``phi0`` (rad) with a base rotation.

    Examples
    --------
    >>> from armcal.models import Target
    >>> arm = PlanarArm([260.0, 180.0])
    >>> arm.n_joints, arm.n_params, arm.param_names
    (2, 4, ('dl1', 'dl2', 'dq1', 'dq2'))
    >>> nest = PlanarArm([260.0, 180.0], targets=[Target("A", 180.0), Target("B", 150.0, 0.3)])
    >>> nest.param_names
    ('dl1', 'dl2@A', 'dl2@B', 'dq1', 'dq2@A', 'dq2@B')
    >>> PlanarArm([260.0, 180.0], base_offset=True, base_rotation=True).fixed
    ('dq1',)
    """

    @property
    def family(self) -> str:
        """``"planar"``: the registry's key (:mod:`armcal.families`)."""
        return "planar"

    def __repr__(self) -> str:
        lengths = ", ".join(f"{v:g}" for v in self.link_lengths)
        extras = [f"fixed={list(self.fixed)}"] if self.fixed else []
        if self.targets:
            extras.append(f"targets={list(self.target_labels)}")
        if self.noise is not None:
            extras.append(f"sigma={self.noise.sigma_mm:g} mm")
        more = "".join(f", {e}" for e in extras)
        return f"PlanarArm({self.name!r}, links [{lengths}] mm, {self.n_params} parameters{more})"

    # -- parameters --------------------------------------------------------------------

    @property
    def instrument_params(self) -> np.ndarray:
        """Boolean ``(p,)``: ``x0, y0, phi0``, the base pose in the instrument frame."""
        return np.array([name in INSTRUMENT_PARAMS for name in self.param_names])

    @property
    def registration_params(self) -> np.ndarray:
        """Boolean ``(p,)``: the base pose and, on an arm with several targets, every
        target's last link (``dl{n}@{t}``, ``dq{n}@{t}``): where the targets sit on the tool."""
        return self.instrument_params | np.array(["@" in name for name in self.param_names])

    @property
    def point_dim(self) -> int:
        """Measured points are in the plane: 2 coordinates."""
        return 2

    @property
    def reach_mm(self) -> float:
        """The sum of the link lengths, mm."""
        return float(np.sum(self.link_lengths))

    @property
    def deviation_bounds(self) -> DeviationBounds:
        """Every link's length deviation beyond :data:`LARGE_LENGTH_FRACTION` of its link,
        every joint offset beyond :data:`~armcal.models.defaults.LARGE_ANGLE_DEG`; the base
        pose is the instrument's.  With a base offset, the offsets that turn every link
        alike (:attr:`turn_offsets`) also take up any turn of the instrument's axes."""
        k, p = self.n_links, self.n_params
        bounds = np.full(p, np.inf)
        bounds[:k] = LARGE_LENGTH_FRACTION * self.link_nominal
        bounds[k : 2 * k] = np.radians(LARGE_ANGLE_DEG)
        reference = np.full(p, np.nan)
        reference[:k] = self.link_nominal
        names = tuple(f"link {name}" for name in self.link_names) + ("",) * (p - k)
        turns = np.zeros(p)
        if self.base_offset:
            turns[k : 2 * k] = self.turn_offsets
        return DeviationBounds(
            bounds,
            reference,
            names,
            "link",
            LARGE_LENGTH_FRACTION,
            LARGE_ANGLE_DEG,
            "links",
            turns,
        )

    @property
    def angle_scale_mm(self) -> float:
        """The sum of the link vectors' lengths (every target's last link), mm."""
        return float(np.sum(self.link_nominal))

    @property
    def arm(self) -> PlanarArm:
        """The arm itself: a planar arm is a geometric model."""
        return self

    def with_noise(self, noise: NoiseModel | None) -> PlanarArm:
        """The same arm with another noise model."""
        return self.replace(noise=noise)

    def with_fixed(self, fixed: Sequence[str]) -> PlanarArm:
        """The same arm with other parameters held fixed."""
        return self.replace(fixed=tuple(fixed))

    # -- measurement --------------------------------------------------------------------

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        """Checked conditions: ``q`` ``(m, n)``, every row's target on an arm with several."""
        q = np.asarray(q, dtype=float)
        if q.ndim != 2 or q.shape[1] != self.n_joints:
            raise ValueError(f"q must have shape (m, {self.n_joints}) in rad, got {q.shape}")
        m = q.shape[0]
        if loads is not None and loads.n_rows != m:
            raise ValueError(f"loads must have {m} rows, got {loads.n_rows}")
        refuse_feature(self.name, feature)
        return Conditions(q, check_target(self, q, target), loads, sigma_mm)

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The tip (or the row's target) ``(..., m, 2)`` in mm: paper eq. (1)."""
        return forward_kinematics(self, conditions.q, params, target=conditions.target)

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """``d(x, y) / d(params)`` ``(..., m, 2, p)`` (paper eq. 7-8, user parametrization)."""
        return jacobian(self, conditions.q, params, target=conditions.target)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d(x, y) / dq`` ``(..., m, 2, n)`` in mm/rad."""
        return joint_jacobian(self, conditions.q, params, target=conditions.target)

    def pose_covariances(
        self,
        conditions: Conditions,
        params: np.ndarray | None = None,
        *,
        noise: NoiseModel | None = None,
    ) -> np.ndarray:
        """Covariance ``(..., m, 2, 2)`` (mm^2) of every measured point (:mod:`armcal.noise`)."""
        return self.covariances_at(
            conditions.q, params, conditions.sigma_mm, target=conditions.target, noise=noise
        )

    def whitening(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray | None:
        """Relative whitening ``(..., m, 2, 2)``, None for isotropic iid noise."""
        return self.relative_whitening(conditions, params)

    # -- fitting ------------------------------------------------------------------------

    @property
    def has_closed_form(self) -> bool:
        """Every parameter free (or only the base rotation's partner held): the model is
        linear in the link phasors over its free parameters."""
        return self.complete

    @property
    def closed_form_hold(self) -> tuple[str, ...]:
        """The fixed parameters: with every one free the family has its closed form."""
        return tuple(self.fixed)

    def closed_form(self, conditions: Conditions) -> PlanarClosedForm | None:
        """The link-phasor least squares (:mod:`~armcal.models.planar.closed_form`)."""
        return PlanarClosedForm(self, conditions) if self.complete else None

    @property
    def nested(self) -> None:
        """A planar arm adds nothing to a simpler model."""
        return None

    @property
    def effect(self) -> None:
        return None

    def lift(self, nested_params: np.ndarray) -> np.ndarray:
        return nested_params

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        """Zero deviations, or the projected closed form with fixed parameters."""
        return projected_start(self, conditions, points, weights)

    def canonical(self, params: np.ndarray) -> np.ndarray:
        """Angles wrapped into ``(-pi, pi]``; with every parameter free, a link whose length
        came out negative is flipped: ``(L, dtheta)`` and ``(-L, dtheta + pi)`` are one link.

        Gauss-Newton from zero deviations may reach either; the closed form and every
        report give the positive length.
        """
        params = np.array(params, dtype=float)
        angles = np.flatnonzero(self.angle_params)
        params[..., angles] = wrap_angle(params[..., angles])
        if not self.complete:
            return params
        dl, dtheta, base = split_params(self, params)
        length = self.link_nominal + dl
        flipped = length < 0
        rows = np.any(flipped, axis=-1)
        if not np.any(rows):
            return params
        turned = user_from_links(
            self,
            (np.abs(length) - self.link_nominal)[rows],
            (dtheta + np.pi * flipped)[rows],
            base[rows][:, : 2 if self.base_offset else 0],
        )
        params[rows] = turned
        return params

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """A length per unit of every parameter: 1 for lengths and the base position; for a
        joint offset the reach beyond the joint (what it turns), for ``phi0`` the whole arm."""
        n = self.n_links
        scale = np.ones(self.n_params)
        if self.standard_map:
            # dq_j moves every link from j outwards: the tip by up to the reach beyond joint j.
            scale[n : 2 * n] = np.cumsum(self.link_lengths[::-1])[::-1]
        else:  # dq_j turns link vector k by A_kj; phi0 turns them all
            scale[n : 2 * n] = self.link_nominal @ np.abs(self.angle_map)
            if self.base_rotation:
                scale[-1] = float(np.sum(self.link_nominal))
        return scale

    # -- analysis -----------------------------------------------------------------------

    def _plan_svd(self, conditions: Conditions) -> ScaledSVD:
        """The plan's scaled SVD: the plain model's shared factorization, else its own."""
        if self.standard and conditions.sigma_mm is None:
            return shared_plan_factor(self, conditions).svd
        return conditions.memo(
            (self, "plan-svd"), lambda: plan_svd(self, conditions.q, conditions.target)
        )

    def identifiability(self, conditions: Conditions) -> tuple[Identifiability, ScaledSVD]:
        """Rank of the plan's Hadamard-scaled Jacobian (``planar_information.identifiability``)."""
        svd = self._plan_svd(conditions)
        return identifiability(self, conditions.q, svd=svd, target=conditions.target), svd

    def check_identifiable(self, conditions: Conditions) -> Identifiability:
        return check_identifiable(
            self, conditions.q, svd=self._plan_svd(conditions), target=conditions.target
        )

    def covariance_factor(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``G`` with ``(J_w^T J_w)^-1 = G G^T`` (from the plan's SVD for the plain model)."""
        svd = None if np.ndim(conditions.q) > 2 else self._plan_svd(conditions)
        return covariance_factor(self, conditions.q, params, svd, target=conditions.target)

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        """Nothing beyond the parameters."""
        return {}

    def linear_positions(self, conditions: Conditions) -> LinearPositions:
        """The tip is ``base + sum_k z_k u_k``: linear in the link phasors ``z`` (base last)."""
        units = link_units(self, conditions.q, conditions.target)  # (k, K)
        basis = np.concatenate([units, np.ones((units.shape[0], 1))], axis=1)
        return LinearPositions(basis, lambda params: link_phasors(self, params))

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """Every target measured at every pose (pose-major rows), with each pose's load."""
        rows, target, every = plan_rows(self, q, None)
        if loads is not None and every:
            loads = loads.repeat(self.n_target_links)
        return Conditions(rows, target, loads)

    # -- design -------------------------------------------------------------------------

    def feasible(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Poses within the joint limits whose every target is in the measurement region."""
        return planar_design.feasible(self, q, tol=tol)

    @property
    def has_view(self) -> bool:
        """A measurement region constrains the poses."""
        return self.region is not None

    def view_constraints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The measurement region's constraints on every target's point, None without one."""
        return planar_design.region_constraints(self, q)

    @property
    def rotation_invariant(self) -> bool:
        """No base offset and no direction in the instrument noise (see
        :func:`~armcal.models.planar.design.rotation_invariant`)."""
        return planar_design.rotation_invariant(self)

    @property
    def information_bound(self) -> bool:
        """:func:`~armcal.models.planar.information.unit_trace`: the paper's bound holds."""
        return unit_trace(self)

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> PlanarPlanInformation:
        """The complex-column information of the paper (loads move nothing of a rigid arm;
        it needs no rows)."""
        return PlanarPlanInformation(self, q)

    def closed_form_plans(self, m: int) -> PaperPlans:
        """The paper's orthogonal plans, placed within the limits and region."""
        return PaperPlans(self, m)

    def paper_criteria(self, q: np.ndarray) -> PaperCriteria:
        """The paper's D* pair and Table I sums of plan ``q``."""
        pair = dstar(self, q)
        return PaperCriteria(float(pair.det_c), float(pair.abs_det_s), optimality_sums(self, q))

    def design_loads(self, payloads: Sequence[float] | None) -> None:
        """A rigid arm's points do not depend on its payload."""
        return None

    # -- the tool -----------------------------------------------------------------------

    @property
    def orientation_dim(self) -> int:
        """The tool's direction in the plane: one angle."""
        return 1

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The direction ``(..., m, 1)`` of every row's last link vector, rad."""
        return tool_angles(self, conditions.q, params, target=conditions.target)[..., None]

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """The tool turns with the last link angle: row ``M[n]`` of the joint map."""
        q = np.asarray(conditions.q)
        return np.broadcast_to(self.joint_map[-1], (*q.shape[:-1], 1, self.n_joints))

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d tool angle / d params`` ``(m, 1, p)``: the last link vector's angle deviation."""
        q = np.asarray(conditions.q)
        k = self.n_links
        target = conditions.target
        last = k - self.n_target_links + (0 if target is None else target)
        g = np.zeros((q.shape[-2], self.n_params))
        g[:, k : 2 * k] = self.angle_map[last]
        if self.base_rotation:
            g[:, -1] = 1.0
        return g[:, None, :]

    def in_robot_frame(self, params: np.ndarray) -> tuple[PlanarArm, np.ndarray]:
        """The base pose (``x0, y0, phi0``) set to 0: the calibrated arm in its own frame."""
        return self, np.where(self.instrument_params, 0.0, params)

    def arm_params(self, params: np.ndarray) -> np.ndarray:
        return params
