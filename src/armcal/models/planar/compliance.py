"""Joint compliance under gravity, payload and tip forces: the elastostatic model.

On an arm whose plane holds gravity (a vertical arm, a humanoid limb, the
shoulder-elbow-wrist plane of an industrial robot) the joints twist under the
static torque of the links' weight, the payload and any force applied at the
tip.  The deflection of joint ``j`` is ``dtheta_j = k_j tau_j`` (linear
elastostatics, one virtual spring per joint), and the tip moves, to first
order, by ``sum_j dtheta_j i (p - p_j)`` (complex notation: ``p_j`` is joint
``j``, ``p`` the tip).

The torques and lever arms are computed on the arm's undeflected geometry (the
current estimate of the link lengths and offsets, in the measurement frame),
the tip on the deflected one: ``p = FK(q + dq, theta + cumsum(dtheta))``.
The two differ from the exact equilibrium by terms of order ``dtheta^2``
(about 1e-7 of the deflection for 1e-3 rad), far below any instrument.

Parameters (:class:`CompliantArm`), in display units
----------------------------------------------------

* ``k1 .. kn`` [urad/(N*m)]: joint compliance, when the torque is known: the
  link masses are given (``link_masses_kg``), or the load is a known payload
  or tip force (``payload_kg``, ``fx_N``, ``fy_N``).
* ``c1 .. cn`` [mdeg/m] (lumped mode, masses unknown): the deflection of joint
  ``j`` per metre of horizontal lever arm from joint ``j`` to the tip, i.e. the
  arm's own weight taken as one weight at the tip: ``dtheta_j = c_j h_j``
  with ``h_j = (p - p_j) x g_hat``.  Only the product of compliance and
  weight is seen, so no mass and no ``k`` follow from gravity alone; ``k_j``
  is identified as well when the data carry known loads that vary (payload or
  tip force), which separate the compliance from the weight.

What gravity alone cannot identify: a constant torque is a joint offset
(``k_j`` is seen only through the *variation* of ``tau_j`` over the poses,
and a joint whose torque never changes is confounded with ``dq_j``); the
masses, which only multiply ``k``; and, without a payload that varies, the
split of ``c_j`` into compliance and weight.

Several targets on the end effector (a nest of tracker reflectors) share the
arm: the payload hangs at the end of the last link, whose direction is the one
the first target's last link gives it, and every row's measured point is its
own target's, turned by each joint's deflection about that joint.

:class:`CompliantArm` is a :class:`~armcal.models.interface.FitModel`: the planar
arm's deviations followed by the compliance, fitted, simulated, validated and
compensated like any model; its :attr:`~CompliantArm.nested` model is the rigid
arm, from whose fit a fit starts and against which it is judged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...errors import ArmcalError, NotIdentifiableError
from ...noise import NoiseModel
from ...numerics import ScaledSVD
from ..defaults import ArmEffect, MinimalPlanar, TermChoice
from ..identifiability import Identifiability, listing
from ..information import BlockInformation, column_identifiability
from ..interface import Conditions, Effect, Held, Loads, UnpredictedLoads
from .arm import PlanarArm
from .kinematics import (
    forward_kinematics,
    jacobian,
    joint_jacobian,
    link_vectors,
    tool_angles,
)

__all__ = [
    "C_SCALE",
    "C_UNIT",
    "K_SCALE",
    "K_UNIT",
    "STANDARD_GRAVITY",
    "CompliantArm",
    "Elastostatic",
    "check_compliance_identifiable",
    "compliance_identifiability",
    "payload_values",
]

#: Standard gravity (m/s^2), the magnitude of ``gravity_xy`` (a direction).
STANDARD_GRAVITY = 9.80665

#: Display scale of ``k`` (rad/(N m) -> urad/(N m)) and ``c`` (rad/m -> mdeg/m).
K_SCALE = 1e6
C_SCALE = 1e3 * 180.0 / np.pi
K_UNIT = "urad/(N*m)"
C_UNIT = "mdeg/m"


def _vector(values: ArrayLike, n: int, what: str) -> np.ndarray:
    a = np.asarray(values, dtype=float)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ArmcalError(f"{what} must be one finite number or {n} numbers, got {values!r}")
    return a


@dataclass(frozen=True, eq=False)
class Elastostatic:
    """What loads the joints: gravity, the links' masses and the default payload.

    Attributes
    ----------
    gravity : ndarray, shape (2,), or None
        Gravitational acceleration (m/s^2) in the frame of the measurements
        (the base frame for 2-D data): in-plane, so that a vertical arm has
        ``|g| = 9.80665``; None for a horizontal arm (no gravity torque).
    link_masses_kg : ndarray, shape (n,), or None
        Mass of every link; None selects the lumped mode (``c1..cn``).
    com_fraction : ndarray, shape (n,)
        Where each link's centre of mass lies between its joint (0) and the
        next (1).
    payload_kg : float
        Payload at the tip for rows that do not give their own.
    terms : TermChoice
        The compliance terms the user holds (the robot file's ``[identify]``).
    """

    gravity: np.ndarray | None
    link_masses_kg: np.ndarray | None
    com_fraction: np.ndarray
    payload_kg: float = 0.0
    terms: TermChoice = field(default_factory=TermChoice)

    @classmethod
    def create(
        cls,
        n: int,
        *,
        gravity_xy: ArrayLike | None = None,
        link_masses_kg: ArrayLike | None = None,
        com_fraction: ArrayLike = 0.5,
        payload_kg: float = 0.0,
    ) -> Elastostatic:
        """Checked parameters; ``gravity_xy`` is a direction scaled to standard gravity.

        Examples
        --------
        >>> e = Elastostatic.create(3, gravity_xy=[0, -2], link_masses_kg=[20, 12, 6])
        >>> e.gravity.tolist(), e.lumped, e.com_fraction.tolist()
        ([0.0, -9.80665], False, [0.5, 0.5, 0.5])
        """
        gravity = None
        if gravity_xy is not None:
            g = np.asarray(gravity_xy, dtype=float)
            norm = float(np.linalg.norm(g)) if g.shape == (2,) else 0.0
            if g.shape != (2,) or not np.all(np.isfinite(g)) or norm == 0.0:
                raise ArmcalError(
                    f"gravity_xy must be a non-zero direction [gx, gy], got {gravity_xy!r}"
                )
            gravity = g / norm * STANDARD_GRAVITY
        masses = None
        if link_masses_kg is not None:
            masses = _vector(link_masses_kg, n, "link_masses_kg")
            if np.any(masses < 0):
                raise ArmcalError(f"link_masses_kg must not be negative, got {masses.tolist()}")
        fraction = _vector(com_fraction, n, "com_fraction")
        if np.any((fraction < 0) | (fraction > 1)):
            raise ArmcalError(f"com_fraction must lie in [0, 1], got {fraction.tolist()}")
        payload = float(payload_kg)
        if not np.isfinite(payload) or payload < 0:
            raise ArmcalError(f"payload_kg must be finite and not negative, got {payload_kg!r}")
        return cls(gravity, masses, fraction, payload)

    @property
    def lumped(self) -> bool:
        """True when the masses are unknown (parameters ``c1..cn``)."""
        return self.link_masses_kg is None

    def model_for(self, arm: Any, loads: Loads, *, virtual: bool = False) -> CompliantArm:
        """The compliant model of ``arm`` for rows with ``loads``
        (:meth:`CompliantArm.for_loads`)."""
        return CompliantArm.for_loads(arm, self, loads, virtual=virtual)

    def term_names(self, arm: PlanarArm) -> tuple[str, ...]:
        """Every compliance term a model of ``arm`` can have, whatever its rows' loads."""
        return CompliantArm(arm, self, known_loads=True).compliance_names

    def with_gravity(self, gravity: np.ndarray | None) -> Elastostatic:
        """The same loads with gravity (m/s^2) given in another frame."""
        return replace(self, gravity=None if gravity is None else np.asarray(gravity, dtype=float))


@dataclass(frozen=True, eq=False)
class CompliantArm(ArmEffect, MinimalPlanar):
    """A planar arm whose joints twist under load: geometry plus joint compliance.

    The parameter vector is the arm's user deviations followed by the
    compliance parameters (:attr:`compliance_names`): ``k1..kn`` when the
    masses are known; ``c1..cn`` in the lumped mode, followed by ``k1..kn``
    when ``known_loads`` (a payload or tip force that the torque can be
    computed from).  Internal units: rad/(N m) for ``k``, rad/m for ``c``.
    The compliance parameters are free but for those the user holds at zero
    (``elastic.terms``, :meth:`with_fixed`).

    Attributes
    ----------
    arm : PlanarArm
        The rigid arm: its geometry, limits, noise model and fixed parameters.
    elastic : Elastostatic
        Gravity, the links' masses and the default payload.
    known_loads : bool
        Whether the data or design carry known loads (lumped mode only).

    Examples
    --------
    >>> arm = PlanarArm([500.0, 300.0])
    >>> elastic = Elastostatic.create(2, gravity_xy=[0, -1], link_masses_kg=[10.0, 4.0])
    >>> model = CompliantArm.for_loads(arm, elastic, Loads.create(3, [0.0, 5.0, 0.0]))
    >>> model.param_names
    ('dl1', 'dl2', 'dq1', 'dq2', 'k1', 'k2')
    >>> model.nested is arm, model.effect.name
    (True, 'joint compliance')
    """

    arm: PlanarArm
    elastic: Elastostatic
    known_loads: bool = False

    def __post_init__(self) -> None:
        if self.elastic.gravity is None and not self.known_loads:
            raise ArmcalError(
                "[elastostatic] has no gravity_xy and the data carry no payload or tip "
                "force that varies: nothing twists the joints; give gravity_xy for a vertical "
                "arm, or payload_kg/fx_N/fy_N"
            )

    def __repr__(self) -> str:
        mode = "lumped" if self.elastic.lumped else "masses known"
        return f"CompliantArm({self.arm!r}, {mode}, compliance {', '.join(self.compliance_names)})"

    @classmethod
    def for_loads(
        cls, arm: PlanarArm, elastic: Elastostatic, loads: Loads, *, virtual: bool = False
    ) -> CompliantArm:
        """The model for data with ``loads``: in lumped mode, loads that vary add ``k1..kn``.

        ``virtual``: the model of a virtual robot measured under ``loads``, which
        every known load bends (by ``k`` times its torque) whether or not a fit
        of such data could tell ``k`` from the weight.
        """
        gravity_lumped = elastic.lumped and elastic.gravity is not None
        if gravity_lumped and not virtual and not loads.varying and loads.n_rows:
            # A constant payload only adds to the lumped weight (k needs loads that
            # vary): c1..cn then hold the deflection under that payload, which the
            # model records as its payload (see unpredicted_loads).
            elastic = replace(elastic, payload_kg=float(loads.payload_kg[0]))
            return cls(arm, elastic, known_loads=False)
        return cls(arm, elastic, known_loads=loads.known)

    # -- the compliance parameters ------------------------------------------------------

    @cached_property
    def kinds(self) -> tuple[str, ...]:
        """``"k"`` or ``"c"`` for every compliance parameter."""
        n = self.arm.n_joints
        if not self.elastic.lumped:
            return ("k",) * n
        if self.elastic.gravity is None:
            return ("k",) * n
        return ("c",) * n + (("k",) * n if self.known_loads else ())

    @cached_property
    def joints(self) -> np.ndarray:
        """The joint (0-based) of every compliance parameter."""
        n = self.arm.n_joints
        return np.tile(np.arange(n), len(self.kinds) // n)

    @property
    def n_compliance(self) -> int:
        """Number of compliance parameters ``P``."""
        return len(self.kinds)

    @cached_property
    def compliance_names(self) -> tuple[str, ...]:
        """``k1..kn`` and/or ``c1..cn``."""
        return tuple(f"{k}{j + 1}" for k, j in zip(self.kinds, self.joints, strict=True))

    @cached_property
    def compliance_units(self) -> tuple[str, ...]:
        return tuple(K_UNIT if k == "k" else C_UNIT for k in self.kinds)

    @cached_property
    def compliance_scale(self) -> np.ndarray:
        """Internal to display units of the compliance parameters."""
        return np.array([K_SCALE if k == "k" else C_SCALE for k in self.kinds])

    # -- parameters (FitModel) ----------------------------------------------------------

    @property
    def fixed(self) -> tuple[str, ...]:
        """The arm's fixed parameters and the compliance terms the user holds."""
        return self.arm.fixed + self.user_held

    @property
    def free(self) -> np.ndarray:
        """Free mask over every parameter: the compliance's but for those the user holds."""
        held = set(self.user_held)
        mine = np.array([n not in held for n in self.compliance_names], dtype=bool)
        return np.concatenate([self.arm.free, mine])

    @property
    def free_names(self) -> tuple[str, ...]:
        held = set(self.user_held)
        return self.arm.free_names + tuple(n for n in self.compliance_names if n not in held)

    @property
    def n_free(self) -> int:
        return self.arm.n_free + self.n_compliance - len(self.user_held)

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        """Which compliance terms the user holds (the planar arm holds none by a rule)."""
        return self.user_reason

    def with_noise(self, noise: NoiseModel | None) -> CompliantArm:
        return CompliantArm(self.arm.with_noise(noise), self.elastic, self.known_loads)

    def with_fixed(self, fixed: Sequence[str]) -> CompliantArm:
        """``fixed`` held, replacing the held set: the arm's parameters among them and the
        compliance terms (every term any rows could give the model is one,
        :meth:`Elastostatic.term_names`)."""
        geometry, terms = self.split_fixed(fixed)
        elastic = replace(self.elastic, terms=terms)
        return CompliantArm(self.arm.with_fixed(geometry), elastic, self.known_loads)

    def unpredicted_loads(self, loads: Loads) -> UnpredictedLoads | None:
        """In lumped mode without ``k1..kn``, any payload but the one ``c1..cn`` hold.

        Such a model was identified from data with one payload, which it records
        (:meth:`for_loads`): its ``c`` are the deflection under the arm's weight
        *and* that payload, so under another payload the difference is not
        predicted.
        """
        if not self.elastic.lumped or self.known_loads or self.elastic.gravity is None:
            return None
        held = self.elastic.payload_kg
        other = np.unique(loads.payload_kg[loads.payload_kg != held])
        forced = bool(np.any(loads.force_n != 0))
        if not other.size and not forced:
            return None
        return UnpredictedLoads(self.compliance_names, held, tuple(other.tolist()), forced)

    @property
    def uses_gravity(self) -> bool:
        """The arm's weight twists the joints: gravity's direction matters."""
        return True

    def with_gravity(self, gravity: np.ndarray | None) -> CompliantArm:
        """The same model with gravity (m/s^2) given in another frame."""
        return CompliantArm(self.arm, self.elastic.with_gravity(gravity), self.known_loads)

    # -- the deflected arm --------------------------------------------------------------

    def load_terms(
        self, q: np.ndarray, geometry: np.ndarray | None, loads: Loads | None
    ) -> np.ndarray:
        """The load ``(..., m, P)`` every compliance parameter multiplies, per row.

        The torque (N m) at the parameter's joint for ``k``, the horizontal lever
        arm (m) to the tip for ``c``, on the undeflected geometry.
        """
        arm, elastic = self.arm, self.elastic
        q = np.asarray(q, dtype=float)
        terms = _link_chain(arm, q, geometry) / 1000.0  # (..., m, n) in metres
        m = q.shape[-2]
        loads = self.default_loads(m) if loads is None else loads
        before = np.cumsum(terms, axis=-1) - terms  # joint j relative to the base
        tip = np.sum(terms, axis=-1, keepdims=True)
        lever = tip - before  # (..., m, n): from joint j to the tip
        payload = loads.payload_kg[:, None]
        force = (loads.force_n[:, 0] + 1j * loads.force_n[:, 1])[:, None]
        gravity = 0j if elastic.gravity is None else complex(*elastic.gravity)
        known = _cross(lever, payload * gravity + force)  # torque of the known loads
        out = []
        if "c" in self.kinds:
            g_hat = gravity / abs(gravity)
            out.append(_cross(lever, np.broadcast_to(g_hat, lever.shape)))
        if "k" in self.kinds:
            torque = known
            if not elastic.lumped and elastic.gravity is not None:
                masses = elastic.link_masses_kg
                assert masses is not None
                centre = before + elastic.com_fraction * terms  # every link's centre of mass
                # sum over links i >= j of m_i (c_i - p_j): reverse cumulative sums
                first = np.cumsum((masses * centre)[..., ::-1], axis=-1)[..., ::-1]
                mass = np.cumsum(masses[::-1])[::-1]
                torque = torque + _cross(first - mass * before, np.full(lever.shape, gravity))
            out.append(torque)
        return np.concatenate(out, axis=-1)

    def deflection(self, row_loads: np.ndarray, compliance: np.ndarray) -> np.ndarray:
        """Joint deflections ``(..., m, n)`` in rad (relative angles) of the rows' load terms
        (:meth:`load_terms`) under ``compliance``."""
        per_param = row_loads * np.asarray(compliance, dtype=float)[..., None, :]
        n = self.arm.n_joints
        return per_param.reshape(*per_param.shape[:-1], -1, n).sum(axis=-2)

    def _bent(self, conditions: Conditions, params: np.ndarray | None):
        """Geometry, compliance, the rows' loads and the deflections at ``params``."""
        full = np.zeros(self.n_params) if params is None else np.asarray(params, dtype=float)
        geometry, compliance = self.split(full)
        loads = conditions.loads
        row_loads = self.load_terms(conditions.q, geometry, loads)
        bend = self.deflection(row_loads, compliance)
        return geometry, row_loads, bend

    # -- measurement (FitModel) ---------------------------------------------------------

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        """The arm's checked conditions, each row loaded (default: the robot file's payload)."""
        m = np.shape(q)[0] if np.ndim(q) == 2 else 0
        loads = self.default_loads(m) if loads is None else loads
        return self.arm.conditions(
            q, target=target, loads=loads, sigma_mm=sigma_mm, feature=feature
        )

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """Measured points ``(..., m, 2)`` (mm): the arm deflected under the rows' loads."""
        geometry, _, bend = self._bent(conditions, params)
        return forward_kinematics(
            self.arm, conditions.q, geometry, target=conditions.target, deflection=bend
        )

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """``d(x, y) / d(params)`` ``(..., m, 2, p + P)`` (mm per internal unit).

        The geometric columns at the deflected pose; the compliance columns
        ``load_p i (p - p_j)``, ``p`` the row's point.  The torques' own (tiny)
        dependence on the geometry is left out: Gauss-Newton still converges to
        the exact fit, and the covariance changes by the relative size of a
        deviation (1e-3).
        """
        q, target = conditions.q, conditions.target
        geometry, row_loads, bend = self._bent(conditions, params)
        geo = jacobian(self.arm, q, geometry, target=target, deflection=bend)
        terms = link_vectors(self.arm, q, geometry, target=target, deflection=bend)
        turn = 1j * np.cumsum(terms[..., ::-1], axis=-1)[..., ::-1]  # i (p - p_j)
        columns = turn[..., self.joints] * row_loads
        comp = np.stack([columns.real, columns.imag], axis=-2)
        return np.concatenate([geo, comp], axis=-1)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d(x, y) / dq`` at the deflected pose (the deflection's own change with ``q``,
        about 1e-3 of a step, left out)."""
        geometry, _, bend = self._bent(conditions, params)
        return joint_jacobian(
            self.arm, conditions.q, geometry, target=conditions.target, deflection=bend
        )

    # -- fitting ------------------------------------------------------------------------

    @property
    def effect(self) -> Effect:
        return Effect(
            "joint compliance",
            "compliance",
            "geometry",
            lumped=self.elastic.lumped,
            stations=False,
            advice="load-more",
            positive=True,
        )

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        return np.zeros((points.shape[0], self.n_params))

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """The arm's, then the RMS tip motion per unit of every compliance parameter."""
        row_loads = self.load_terms(conditions.q, None, conditions.loads)
        per_unit = np.sqrt(np.mean(row_loads**2, axis=-2)) * float(np.sum(self.arm.link_lengths))
        return np.concatenate([self.arm.step_scale(conditions), per_unit])

    # -- analysis -----------------------------------------------------------------------

    def identifiability(self, conditions: Conditions) -> tuple[Identifiability, ScaledSVD]:
        return compliance_identifiability(self, conditions)

    def check_identifiable(self, conditions: Conditions) -> Identifiability:
        return check_compliance_identifiable(self, conditions)[0]

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        """``max_deflection_rad`` ``(n,)``: every joint's largest fitted deflection."""
        _, _, bend = self._bent(conditions, params)
        return {"max_deflection_rad": np.max(np.abs(bend), axis=0)}

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """Every target measured at every pose, each row with its pose's load."""
        loads = self.default_loads(np.shape(q)[-2]) if loads is None else loads
        return self.arm.plan_conditions(q, loads)

    # -- design -------------------------------------------------------------------------

    @property
    def rotation_invariant(self) -> bool:
        """Gravity has a direction: turning joint 1 changes every deflection."""
        return self.elastic.gravity is None and self.arm.rotation_invariant

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> BlockInformation:
        """From the whitened Jacobian.  The criteria's singular values are those of unit-norm
        columns: no design coordinates are fixed in advance for the compliance parameters,
        so the D-criterion compares how orthogonal a plan's columns are."""
        return BlockInformation(self, q, loads, unit_columns=True, rows=rows)

    def design_loads(self, payloads: Sequence[float] | None) -> tuple[CompliantArm, np.ndarray]:
        """The model of a plan whose poses carry ``payloads`` (kg; default 0 and the robot
        file's payload): in lumped mode, loads that vary add ``k1..kn``."""
        values = np.array(payload_values(self.elastic, payloads))
        return CompliantArm.for_loads(
            self.arm, self.elastic, Loads.create(values.size, values)
        ), values

    # -- the tool -----------------------------------------------------------------------

    @property
    def orientation_dim(self) -> int:
        return 1

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The tool's direction ``(..., m, 1)``: it turns with every joint's deflection."""
        geometry, _, bend = self._bent(conditions, params)
        angle = tool_angles(self.arm, conditions.q, geometry, target=conditions.target)
        return (angle + np.sum(bend, axis=-1))[..., None]

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        return self.arm.orientation_joint_jacobian(conditions)

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """The arm's columns, then every compliance parameter's load (its deflection)."""
        geometry, row_loads, _ = self._bent(conditions, params)
        arm = self.arm.orientation_jacobian(conditions, geometry)
        return np.concatenate([arm, row_loads[..., None, :]], axis=-1)

    def in_robot_frame(self, params: np.ndarray) -> tuple[CompliantArm, np.ndarray]:
        """The base pose set to 0, and gravity turned into the robot's frame (by ``-phi0``)."""
        geometry, compliance = self.split(params)
        robot = np.concatenate([self.arm.in_robot_frame(geometry)[1], compliance])
        if not self.arm.base_rotation or self.elastic.gravity is None:
            return self, robot
        phi0 = float(params[self.arm.param_names.index("phi0")])
        g = complex(*self.elastic.gravity) * np.exp(-1j * phi0)
        return self.with_gravity(np.array([g.real, g.imag])), robot


def _link_chain(arm: PlanarArm, q: np.ndarray, geometry: np.ndarray | None) -> np.ndarray:
    """The arm's links ``(..., m, n)`` as complex numbers (mm), each row's up to the tool.

    One target: the link vectors themselves.  Several: links ``1..n-1`` and the
    last link of nominal length ``l_n`` in the direction the first target's last
    link gives it (the tool's own link, which the payload hangs on, is the same
    whichever target a row measures).
    """
    if arm.n_target_links == 1:
        return link_vectors(arm, q, geometry)
    n = arm.n_joints
    first = np.zeros(np.shape(q)[-2], dtype=int)
    vectors = link_vectors(arm, q, geometry, target=first)  # (..., m, K): target 0's rows
    direction = vectors[..., n - 1] / np.abs(vectors[..., n - 1])
    tool = arm.link_lengths[-1] * direction * np.exp(-1j * arm.targets[0].angle)
    return np.concatenate([vectors[..., : n - 1], tool[..., None]], axis=-1)


def _cross(r: np.ndarray, f: np.ndarray) -> np.ndarray:
    """``r x f`` of complex 2-vectors: ``Im(conj(r) f)``."""
    return (np.conj(r) * f).imag


def compliance_identifiability(
    model: CompliantArm, conditions: Conditions
) -> tuple[Identifiability, ScaledSVD]:
    """Rank analysis of geometry plus compliance at the nominal arm, on scaled columns.

    The free columns of :meth:`CompliantArm.jacobian` at zero deviations decide
    through the one rank policy of :mod:`armcal.numerics`.
    """
    return column_identifiability(model, conditions, np.zeros(model.n_params))


def check_compliance_identifiable(
    model: CompliantArm, conditions: Conditions
) -> tuple[Identifiability, ScaledSVD]:
    """Raise :class:`NotIdentifiableError` unless the poses and loads identify everything.

    The message names the parameters that cannot be identified and says what
    the compliance needs: torques that vary through the poses and the payloads.
    """
    info, svd = compliance_identifiability(model, conditions)
    if info.identifiable:
        return info, svd
    m = conditions.m
    p = model.n_free
    shown = "; ".join(info.combinations[:3])
    compliant = [n for n in info.unidentifiable if n in model.compliance_names]
    if 2 * m < p:
        why = f"{m} poses give {2 * m} equations for {p} parameters; measure more poses"
    elif compliant:
        needs = []
        if any(n.startswith("k") for n in compliant) and model.elastic.lumped:
            needs.append(
                "k is told from c only by known loads that vary: measure some poses with "
                "a different payload (or tip force)"
            )
        if model.elastic.gravity is None:  # a horizontal arm: neither pose nor payload twists it
            needs.append(
                "the torques must vary, and without gravity_xy in [elastostatic] (a horizontal "
                "arm) neither the poses nor a payload (its weight is across the plane) "
                "give any: add gravity_xy if the arm is vertical, or measure with in-plane "
                "tip forces that vary (the measurements' fx_N, fy_N columns)"
            )
        else:
            needs.append(
                "the torques must vary: measure poses in which the links point in different "
                "directions relative to gravity, and with different payloads"
            )
        why = "; ".join(needs)
    else:
        why = "add poses in which every joint takes several different angles (armcal design)"
    raise NotIdentifiableError(
        f"the {m} poses cannot identify all {p} parameters of {model.arm.name} with "
        f"compliance (rank {info.rank} of {p}): not identifiable: "
        f"{listing(info.unidentifiable) if info.unidentifiable else '(none)'}; "
        f"unseen combinations: {shown}; {why}",
        list(info.combinations),
    )


def payload_values(elastic: Elastostatic, given: Sequence[float] | None) -> tuple[float, ...]:
    """The payloads a design may use: ``given``, else 0 and the robot file's payload."""
    if given is not None:
        values = sorted({float(v) for v in given})
        if not values or any(not np.isfinite(v) or v < 0 for v in values):
            raise ArmcalError(f"payloads must be finite and not negative (kg), got {list(given)}")
        return tuple(values)
    return (0.0, elastic.payload_kg) if elastic.payload_kg > 0 else (0.0,)
