"""Joint compliance of a spatial arm under gravity and payload: :class:`CompliantSpatialArm`.

A revolute joint twists under the static torque of everything beyond it (the
links' weight and the payload): ``du_j = k_j tau_j`` (linear elastostatics, one
virtual spring per joint).  The twist adds to the joint's value, so the
measured point is the rigid arm's at ``u = M (q + dq) + du``: the deflection is
exact in the kinematics, and the Jacobian of a compliance parameter is the
joint's column of the joint Jacobian times the load it multiplies.

The loads (torques, lever arms) are computed on the *nominal* chain in the
robot's base frame, where gravity is given (``[elastostatic] gravity``; a
floor-mounted arm's is ``-z``).  The identified geometry changes them by its
relative size (1e-3 of a deflection of 1e-3 rad: 1e-6 rad, far below any
instrument), and in exchange the loads are constants of the rows: the model is
linear in the compliance and its Jacobian is exact.

Parameters, in display units
----------------------------
* **Masses known** (URDF ``<inertial>`` or the robot TOML): ``k{j}``
  [urad/(N*m)] for every revolute joint ``j``, the load its torque
  (:func:`~armcal.models.spatial.gravity.gravity_torques`).
* **Lumped mode** (masses unknown): the arm's weight is lumped at *stations*,
  the origins of the joints beyond ``j`` and the tip.  ``c{j}.{s}`` [mdeg/m] is
  joint ``j``'s deflection per metre of horizontal lever arm from joint ``j``
  to station ``s``, ``h = a_j . ((p_s - p_j) x g_hat)``: a weight at ``s``
  (``k_j`` times that weight).  A link whose centre of mass lies on the segment
  between two stations is a combination of the two, so J2 of an industrial arm
  sees its upper arm and forearm through the elbow's and the wrist's elevation;
  a centre off the stations' lines is approximated (the lever arm about a joint
  is two-dimensional, and the stations span what the chain's origins span).
  Revolute joints only: a prismatic joint is taken as rigid.  With
  payloads that vary, ``k{j}`` is identified as well, from the payload's own
  torque.

What the rows cannot identify is held at zero and named
(:meth:`CompliantSpatialArm.prepared`): a joint whose axis is parallel to
gravity (joint 1 of a floor-mounted arm) has no torque; a torque that never
changes is a zero offset, ``dq{j}``; two stations that coincide (a spherical
wrist) are one.  The user may hold more (a robot file's ``[identify]``, the fix
option: :meth:`CompliantSpatialArm.with_fixed`); a term the user lists as free
that the rows cannot identify is refused with the rule's reason rather than
held or fitted (its column lies within 1 % of the span of the others, so a fit
would trade it against them and report a number the data do not hold).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...errors import ArmcalError
from ...noise import NoiseModel
from ...numerics import ScaledSVD
from ..defaults import ArmEffect, TermChoice
from ..identifiability import Identifiability
from ..information import (
    BlockInformation,
    Linearization,
    column_identifiability,
    identifiable_or_raise,
    refit_free,
)
from ..interface import Conditions, DesignEffort, Effect, Held, Loads, UnpredictedLoads
from ..wording import held_sentence
from .arm import SpatialArm
from .gradient import Extra, jacobian_pose_pullback
from .gravity import STANDARD_GRAVITY, LinkMasses, chain_frames, gravity_torques
from .kinematics import ChainKinematics
from .selection import column_space, select_effect

__all__ = [
    "C_SCALE",
    "K_SCALE",
    "CompliantSpatialArm",
    "SpatialElastics",
]

#: Display scale of ``k`` (rad/(N m) -> urad/(N m)) and ``c`` (rad/m -> mdeg/m).
K_SCALE = 1e6
C_SCALE = 1e3 * 180.0 / np.pi
_UNITS = {"k": "urad/(N*m)", "c": "mdeg/m"}
_SCALES = {"k": K_SCALE, "c": C_SCALE}

#: Poses of the fixed probe that decides which compliance a design can identify.
_PROBE_POSES = 200


@dataclass(frozen=True, eq=False)
class SpatialElastics:
    """What loads a spatial arm's joints: gravity, the links' masses and the payload.

    Attributes
    ----------
    gravity : ndarray, shape (3,)
        Gravity's acceleration in the robot's base frame (m/s^2).
    links : LinkMasses or None
        Every link's mass and centre of mass; None selects the lumped mode.
    payload_kg : float
        The payload of rows that do not give their own.
    payload_com_mm : ndarray, shape (3,)
        Where the payload's centre of mass is in the tip (flange) frame.
    terms : TermChoice
        The compliance terms the user holds (the robot file's ``[identify]``).
    """

    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -STANDARD_GRAVITY]))
    links: LinkMasses | None = None
    payload_kg: float = 0.0
    payload_com_mm: np.ndarray = field(default_factory=lambda: np.zeros(3))
    terms: TermChoice = field(default_factory=TermChoice)

    @classmethod
    def create(
        cls,
        n: int,
        *,
        gravity: ArrayLike = (0.0, 0.0, -1.0),
        mass_kg: ArrayLike | None = None,
        com_mm: ArrayLike | None = None,
        payload_kg: float = 0.0,
        payload_com_mm: ArrayLike = (0.0, 0.0, 0.0),
    ) -> SpatialElastics:
        """Checked parameters; ``gravity`` is a direction scaled to standard gravity.

        Examples
        --------
        >>> e = SpatialElastics.create(2, mass_kg=[10, 5], com_mm=[[0, 0, 100], [200, 0, 0]])
        >>> e.gravity.tolist(), e.lumped
        ([0.0, 0.0, -9.80665], False)
        """
        g = np.asarray(gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)) or not np.any(g):
            raise ArmcalError(
                f"gravity must be a non-zero direction [gx, gy, gz], got {gravity!r}"
            )
        links = None
        if mass_kg is not None:
            mass = np.asarray(mass_kg, dtype=float)
            com = np.zeros((n, 3)) if com_mm is None else np.asarray(com_mm, dtype=float)
            if mass.shape != (n,) or not np.all(np.isfinite(mass)) or np.any(mass < 0):
                raise ArmcalError(f"link masses must be {n} numbers >= 0 (kg), got {mass_kg!r}")
            if com.shape != (n, 3) or not np.all(np.isfinite(com)):
                raise ArmcalError(f"centres of mass must be {n} points [x, y, z] (mm)")
            links = LinkMasses(mass, com)
        payload = float(payload_kg)
        if not np.isfinite(payload) or payload < 0:
            raise ArmcalError(f"payload_kg must be finite and not negative, got {payload_kg!r}")
        at = np.asarray(payload_com_mm, dtype=float)
        if at.shape != (3,) or not np.all(np.isfinite(at)):
            raise ArmcalError(f"payload_com_mm must be 3 numbers (mm), got {payload_com_mm!r}")
        return cls(g / np.linalg.norm(g) * STANDARD_GRAVITY, links, payload, at)

    @property
    def lumped(self) -> bool:
        """True when the masses are unknown (parameters ``c{j}.{s}``)."""
        return self.links is None

    def model_for(self, arm: Any, loads: Loads, *, virtual: bool = False) -> CompliantSpatialArm:
        """The compliant model of ``arm`` for rows with ``loads``
        (:meth:`CompliantSpatialArm.for_loads`)."""
        return CompliantSpatialArm.for_loads(arm, self, loads, virtual=virtual)

    def term_names(self, arm: SpatialArm) -> tuple[str, ...]:
        """Every compliance term a model of ``arm`` can have, whatever its rows' loads."""
        return CompliantSpatialArm(arm, self, known_loads=True).compliance_names

    def to_dict(self) -> dict[str, Any]:
        """The ``elastostatic`` section of a calibration file."""
        links = self.links
        return {
            "family": "spatial",
            "gravity_mps2": self.gravity.tolist(),
            "link_masses_kg": None if links is None else links.mass_kg.tolist(),
            "link_com_mm": None if links is None else links.com_mm.tolist(),
            "payload_kg": self.payload_kg,
            "payload_com_mm": self.payload_com_mm.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], n: int) -> SpatialElastics:
        masses = data["link_masses_kg"]
        links = None
        if masses is not None:
            links = LinkMasses(
                np.array(masses, dtype=float).reshape(n),
                np.array(data["link_com_mm"], dtype=float).reshape(n, 3),
            )
        return cls(
            np.array(data["gravity_mps2"], dtype=float).reshape(3),
            links,
            float(data["payload_kg"]),
            np.array(data["payload_com_mm"], dtype=float).reshape(3),
        )


@dataclass(frozen=True, eq=False)
class CompliantSpatialArm(ArmEffect):
    """A spatial serial arm whose revolute joints twist under gravity (module notes).

    The parameter vector is the arm's followed by the compliance parameters
    (:attr:`compliance_names`), in internal units (rad/(N m) for ``k``, rad/m
    for ``c``).

    Attributes
    ----------
    arm : SpatialArm
        The rigid arm: its geometry, limits, noise model and held parameters.
    elastic : SpatialElastics
    known_loads : bool
        Whether the rows carry payloads that vary (lumped mode: ``k`` as well).
    held : tuple of str
        Compliance parameters the rows cannot identify (:meth:`prepared`); those the
        user holds are ``elastic.terms`` (:attr:`user_held`).
    merges : tuple of Held
        Why, one record per group.
    """

    arm: SpatialArm
    elastic: SpatialElastics
    known_loads: bool = False
    held: tuple[str, ...] = ()
    merges: tuple[Held, ...] = ()

    def __repr__(self) -> str:
        mode = "lumped" if self.elastic.lumped else "masses known"
        return f"CompliantSpatialArm({self.arm.name}, {mode}, {len(self.compliance_names)} terms)"

    @classmethod
    def for_loads(
        cls, arm: SpatialArm, elastic: SpatialElastics, loads: Loads, *, virtual: bool = False
    ) -> CompliantSpatialArm:
        """The model for rows with ``loads``.  In lumped mode payloads that vary add
        ``k{j}``; one constant payload only adds to the lumped weight, and the model
        records it (:meth:`unpredicted_loads`).  ``virtual``: a virtual robot, which
        every known load bends whether or not a fit could tell ``k`` from the weight."""
        _payloads_only(loads)
        if not any(kind == "R" for kind in arm.chain.kinds):
            raise ArmcalError(
                f"[elastostatic]: {arm.name} has no revolute joint, and only revolute joints "
                "twist in armcal's model; remove the table"
            )
        if elastic.lumped and not virtual and not loads.varying and loads.n_rows:
            return cls(arm, replace(elastic, payload_kg=float(loads.payload_kg[0])), False)
        return cls(arm, elastic, loads.known)

    # -- the compliance parameters -------------------------------------------------------

    @cached_property
    def _terms(self) -> tuple[tuple[str, int, int], ...]:
        """``(kind, joint, station)`` of every compliance parameter (0-based; station
        ``n`` is the tip, -1 for ``k``)."""
        chain = self.arm.chain
        n = chain.n_joints
        revolute = [j for j in range(n) if chain.kinds[j] == "R"]
        out: list[tuple[str, int, int]] = []
        if self.elastic.lumped:
            out += [("c", j, s) for j in revolute for s in range(j + 1, n + 1)]
        if not self.elastic.lumped or self.known_loads:
            out += [("k", j, -1) for j in revolute]
        return tuple(out)

    @cached_property
    def compliance_names(self) -> tuple[str, ...]:
        """``c{j}.j{i}``, ``c{j}.tip`` (lumped) and ``k{j}``."""
        n = self.arm.n_joints
        return tuple(
            f"k{j + 1}" if kind == "k" else f"c{j + 1}." + ("tip" if s == n else f"j{s + 1}")
            for kind, j, s in self._terms
        )

    @property
    def compliance_units(self) -> tuple[str, ...]:
        return tuple(_UNITS[k] for k in self.kinds)

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(t[0] for t in self._terms)

    @cached_property
    def joints(self) -> np.ndarray:
        """The chain joint (0-based) every compliance parameter twists."""
        return np.array([t[1] for t in self._terms], dtype=int)

    @property
    def n_compliance(self) -> int:
        return len(self._terms)

    @cached_property
    def compliance_scale(self) -> np.ndarray:
        return np.array([_SCALES[k] for k in self.kinds])

    # -- parameters ------------------------------------------------------------------------

    @property
    def fixed(self) -> tuple[str, ...]:
        """The arm's held parameters and the compliance held by the user or because the
        rows cannot identify it (as :attr:`SpatialArm.fixed`)."""
        held = set(self.held) | set(self.user_held)
        return self.arm.fixed + tuple(n for n in self.compliance_names if n in held)

    @cached_property
    def free(self) -> np.ndarray:
        held = set(self.held) | set(self.user_held)
        mine = np.array([name not in held for name in self.compliance_names], dtype=bool)
        return np.concatenate([self.arm.free, mine])

    @property
    def held_values(self) -> np.ndarray:
        return np.concatenate([self.arm.held_values, np.zeros(self.n_compliance)])

    @property
    def held_reasons(self) -> tuple[Held, ...]:
        return self.arm.held_reasons + self.user_reason + self.merges

    @property
    def free_names(self) -> tuple[str, ...]:
        return tuple(n for n, f in zip(self.param_names, self.free, strict=True) if f)

    @property
    def n_free(self) -> int:
        return int(np.count_nonzero(self.free))

    @property
    def position_dim(self) -> int:
        return self.arm.position_dim

    @property
    def design_effort(self) -> DesignEffort:
        return self.arm.design_effort

    def anchor(self, conditions: Conditions, points: np.ndarray) -> tuple[Conditions, np.ndarray]:
        return self.arm.anchor(conditions, points)

    def unanchor(self, conditions: Conditions, points: np.ndarray) -> np.ndarray:
        return self.arm.unanchor(conditions, points)

    def _with_arm(self, arm: SpatialArm) -> CompliantSpatialArm:
        return CompliantSpatialArm(arm, self.elastic, self.known_loads)

    def with_noise(self, noise: NoiseModel | None) -> CompliantSpatialArm:
        return replace(self, arm=self.arm.with_noise(noise))

    def with_fixed(self, fixed: Sequence[str]) -> CompliantSpatialArm:
        """``fixed`` held, replacing the held set: the arm's parameters among them and the
        compliance terms (every term any rows could give the model is one,
        :meth:`SpatialElastics.term_names`); the rule's set is chosen again
        (:meth:`prepared`)."""
        geometry, terms = self.split_fixed(fixed)
        elastic = replace(self.elastic, terms=terms)
        return CompliantSpatialArm(self.arm.with_fixed(geometry), elastic, self.known_loads)

    def unpredicted_loads(self, loads: Loads) -> UnpredictedLoads | None:
        """In lumped mode without ``k``, any payload but the one the ``c`` hold."""
        if not self.elastic.lumped or self.known_loads:
            return None
        held = self.elastic.payload_kg
        other = np.unique(loads.payload_kg[loads.payload_kg != held])
        if not other.size:
            return None
        return UnpredictedLoads(self.compliance_names, held, tuple(other.tolist()))

    @property
    def uses_gravity(self) -> bool:
        """Gravity is given in the robot's base frame, not in a plane of the instrument's."""
        return False

    def with_gravity(self, gravity: np.ndarray | None) -> CompliantSpatialArm:
        return self

    # -- the deflected arm -----------------------------------------------------------------

    def load_terms(self, conditions: Conditions) -> np.ndarray:
        """The load ``(..., m, P)`` every compliance parameter multiplies: torque (N m) for
        ``k``, lever arm (m) for ``c``, on the nominal chain at the rows' readings (once
        for the rows: every step of a fit needs them, and they do not change)."""
        return conditions.memo(self._loads_key, lambda: self._load_terms(conditions))

    @cached_property
    def _loads_key(self) -> tuple:
        """What the loads depend on besides the rows: the terms, gravity, the masses, the
        payload's centre and the nominal chain (by value: a key outlives its model)."""
        elastic, chain, links = self.elastic, self.arm.chain, self.elastic.links
        return (
            "spatial compliance loads",
            self._terms,
            elastic.payload_kg,  # the rows' payload where they give none
            elastic.gravity.tobytes(),
            None if links is None else (links.mass_kg.tobytes(), links.com_mm.tobytes()),
            elastic.payload_com_mm.tobytes(),
            chain.origins.tobytes(),
            chain.tip.tobytes(),
            chain.kinds,
            self.arm.joint_map.tobytes(),
        )

    def _load_terms(self, conditions: Conditions) -> np.ndarray:
        arm, elastic = self.arm, self.elastic
        q = np.asarray(conditions.q, dtype=float)
        loads = self.default_loads(q.shape[-2]) if conditions.loads is None else conditions.loads
        u = q @ arm.joint_map.T
        frames = chain_frames(arm.chain, u)
        axes, origins, _, tip = frames
        g = elastic.gravity
        terms = self._terms
        joints = self.joints
        out = np.empty((*q.shape[:-1], len(terms)))
        c = np.array([kind == "c" for kind, _, _ in terms], dtype=bool)
        if np.any(c):
            stations = np.concatenate([origins, tip[..., None, :3, 3]], axis=-2)
            at = np.array([s for kind, _, s in terms if kind == "c"])
            lever = stations[..., at, :] - origins[..., joints[c], :]
            moment = np.cross(lever, g / np.linalg.norm(g))
            out[..., c] = np.einsum("...ki,...ki->...k", axes[..., joints[c], :], moment) / 1e3
        if not np.all(c):
            links = elastic.links or LinkMasses(
                np.zeros(arm.n_joints), np.zeros((arm.n_joints, 3))
            )
            torques = gravity_torques(
                arm.chain,
                u,
                links,
                g,
                payload_kg=loads.payload_kg,
                payload_com_mm=elastic.payload_com_mm,
                frames=frames,
            )
            out[..., ~c] = torques[..., joints[~c]]
        return out

    def deflection(self, conditions: Conditions, compliance: np.ndarray) -> np.ndarray:
        """The joints' twists ``(..., m, n)`` (rad) under ``compliance`` ``(..., P)``."""
        per_term = self.load_terms(conditions) * np.asarray(compliance)[..., None, :]
        out = np.zeros((*per_term.shape[:-1], self.arm.n_joints))
        np.add.at(np.moveaxis(out, -1, 0), self.joints, np.moveaxis(per_term, -1, 0))
        return out

    def _bent(self, conditions: Conditions, params: np.ndarray | None) -> tuple[Conditions, Any]:
        """The rows with the readings that put the rigid arm where the twisted one is
        (``q + M^-1 du``), and the geometric parameters."""
        full = self.nominal if params is None else np.asarray(params, dtype=float)
        geometry, compliance = self.split(full)
        q = np.asarray(conditions.q, dtype=float)
        if np.any(compliance):  # the nominal arm (design, rank analysis) does not twist
            q = q + self.deflection(conditions, compliance) @ self._inverse_map.T
        c = conditions
        return Conditions(q, c.target, c.loads, c.sigma_mm, c.frames), geometry

    @cached_property
    def _inverse_map(self) -> np.ndarray:
        return np.linalg.inv(self.arm.joint_map)

    @cached_property
    def nominal(self) -> np.ndarray:
        """The arm's nominal parameters and no compliance."""
        return self.lift(self.arm.nominal)

    # -- measurement -----------------------------------------------------------------------

    def conditions(
        self,
        q: ArrayLike,
        *,
        target: ArrayLike | None = None,
        loads: Loads | None = None,
        sigma_mm: np.ndarray | None = None,
        feature: ArrayLike | None = None,
    ) -> Conditions:
        """The arm's checked rows, each loaded (default: the robot file's payload)."""
        rows = self.arm.conditions(q, target=target, sigma_mm=sigma_mm, feature=feature)
        loads = self.default_loads(rows.m) if loads is None else _payloads_only(loads)
        if loads.n_rows != rows.m:
            raise ValueError(f"loads must have {rows.m} rows, got {loads.n_rows}")
        return replace(rows, loads=loads)

    def positions(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        bent, geometry = self._bent(conditions, params)
        return self.arm.positions(bent, geometry)

    def _columns(self, conditions: Conditions, per_joint: np.ndarray) -> np.ndarray:
        """The compliance columns ``(..., m, d, P)`` from ``d point / d reading``."""
        per_u = per_joint @ self._inverse_map  # d point / d u
        return per_u[..., self.joints] * self.load_terms(conditions)[..., None, :]

    def jacobian(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        """The rigid arm's columns at the twisted pose, then ``J_u[:, j] * load``: exact."""
        bent, geometry = self._bent(conditions, params)
        geo, joint = self.arm.jacobians(bent, geometry)
        return np.concatenate([geo, self._columns(conditions, joint)], axis=-1)

    def joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        """``d point / dq`` at the twisted pose (the torques' own change with ``q``, about
        1e-3 of a step, left out)."""
        bent, geometry = self._bent(conditions, params)
        return self.arm.joint_jacobian(bent, geometry)

    # -- fitting ---------------------------------------------------------------------------

    @property
    def effect(self) -> Effect:
        return Effect(
            "joint compliance",
            "compliance",
            "geometry",
            lumped=self.elastic.lumped,
            stations=True,
            advice="two-payloads",
            positive=True,
        )

    def start(
        self, conditions: Conditions, points: np.ndarray, weights: np.ndarray | None = None
    ) -> np.ndarray:
        return self.lift(self.arm.start(conditions, points, weights))

    def step_scale(self, conditions: Conditions) -> np.ndarray:
        """The arm's, then the reach times the RMS load of every compliance parameter."""
        rms = np.sqrt(np.mean(self.load_terms(conditions) ** 2, axis=-2))
        return np.concatenate([self.arm.step_scale(conditions), rms * self.reach_mm])

    # -- the identifiable set ----------------------------------------------------------------

    def prepared(
        self, conditions: Conditions, points: np.ndarray | None = None
    ) -> CompliantSpatialArm:
        """The arm prepared for these rows (:meth:`SpatialArm.prepared`), and the compliance
        they cannot identify held at zero, each named with what it merges into: the
        columns are taken after the arm's free ones, and one whose part outside the span
        of those before is at most ``SELECT_RTOL`` of its length is held.  The terms the
        user holds take no part.

        Raises ArmcalError for a term the user lists as free (``[identify] free``) that
        the rows cannot identify, with the rule's reason.
        """
        arm = self.arm.prepared(conditions, points)
        model = self._with_arm(arm)
        jac = model.jacobian(conditions, model.nominal)
        w = arm.whitening(conditions)
        rows = jac if w is None else w @ jac
        flat = rows.reshape(-1, model.n_params)
        geo = np.flatnonzero(arm.free)
        user = set(model.user_held)
        mine = np.array([i for i, n in enumerate(model.compliance_names) if n not in user], int)
        columns = column_space(flat[:, np.concatenate([geo, arm.n_params + mine])])
        geo_names = [arm.param_names[i] for i in geo]
        names = [model.compliance_names[i] for i in mine]
        held, merges = select_effect(columns, geo_names, names, model.joints[mine])
        asked = [n for n in self.elastic.terms.asked if n in held]
        if asked:
            why = "; ".join(held_sentence(m) for m in merges if set(asked) & set(m.members))
            raise ArmcalError(
                f"[identify] free lists {', '.join(asked)}, which these rows cannot identify "
                f"({why}); leave {'it' if len(asked) == 1 else 'them'} out of free: "
                "a term the rows cannot tell from the others is held at zero"
            )
        return replace(model, held=held, merges=merges)

    def expressed(self, conditions: Conditions, params: np.ndarray) -> np.ndarray:
        """The free parameters that reproduce ``params``' points at these rows."""
        return refit_free(self, conditions, params)

    def identifiability(self, conditions: Conditions) -> tuple[Identifiability, ScaledSVD]:
        return column_identifiability(self, conditions)

    def check_identifiable(self, conditions: Conditions) -> Identifiability:
        return identifiable_or_raise(
            self,
            conditions,
            f"{self.name} with compliance",
            "measure poses in which every joint takes several values and the torques vary "
            "(links pointing in different directions relative to gravity, different payloads)",
        )

    def fit_details(self, conditions: Conditions, params: np.ndarray) -> dict[str, np.ndarray]:
        """``max_deflection_rad`` ``(n,)``: every joint's largest fitted twist."""
        twist = self.deflection(conditions, self.split(np.asarray(params, dtype=float))[1])
        return {"max_deflection_rad": np.max(np.abs(twist), axis=0)}

    def plan_conditions(self, q: np.ndarray, loads: Loads | None = None) -> Conditions:
        """Every target measured at every pose, each row with its pose's load."""
        rows = self.arm.plan_conditions(q)
        loads = self.default_loads(np.shape(q)[-2]) if loads is None else _payloads_only(loads)
        loads = loads.repeat(len(self.arm.targets))
        return Conditions(rows.q, rows.target, loads, rows.sigma_mm, rows.frames)

    # -- design ----------------------------------------------------------------------------

    @property
    def rotation_invariant(self) -> bool:
        return False

    def plan_information(
        self, q: np.ndarray, loads: Loads | None = None, *, rows: Conditions | None = None
    ) -> BlockInformation:
        return BlockInformation(
            self, q, loads, unit_columns=True, linearize=self.linearize, rows=rows
        )

    def linearize(self, conditions: Conditions) -> Linearization:
        """The rows' whitened blocks at the nominal parameters and their pullback: the arm's
        (:meth:`SpatialArm.linearize`) and the compliance columns' ``J_u[:, j] L``, whose
        ``J_u`` is the zero errors' columns through ``M^-1`` (pulled back by the chain's
        rule) and whose loads ``L`` are differentiated by central differences (they cost
        a pass of the frames, not of the Jacobian)."""
        arm, minv = self.arm, self._inverse_map
        free = np.flatnonzero(self.free[arm.n_params :])
        joints = self.joints[free]
        loads = self.load_terms(conditions)[..., free]  # (..., m, P_f)
        zeros = np.arange(arm.layout.zero_start, arm.layout.target_start)

        gradient: list[np.ndarray] = []  # d L / d q, computed once, when a gradient is asked

        def extra(kin: ChainKinematics) -> Extra:
            assert kin.jacobian is not None
            along = (kin.jacobian[..., zeros] @ minv)[..., joints]  # J_u's columns (..., 3, P_f)

            def pullback(cotangent: np.ndarray) -> np.ndarray:
                mapped = (cotangent * loads[..., None, :]) @ minv[:, joints].T
                out = jacobian_pose_pullback(kin, arm.layout, arm.joint_map, zeros, mapped)
                weight = np.sum(cotangent * along, axis=-2)  # (..., m, P_f)
                if not gradient:
                    gradient.append(self._load_gradient(conditions, free))
                return out + np.einsum("...p,...pn->...n", weight, gradient[0])

            return along * loads[..., None, :], pullback

        return arm.linearize(conditions, extra, self)

    def _load_gradient(self, conditions: Conditions, free: np.ndarray) -> np.ndarray:
        """``d L / d q`` ``(..., m, P_f, n)`` of the free compliance's loads, by central
        differences of step 1e-6 rad (the loads are smooth trigonometric sums)."""
        q = np.asarray(conditions.q, dtype=float)
        out = np.empty((*q.shape[:-1], free.size, q.shape[-1]))
        for j in range(q.shape[-1]):
            step = np.zeros(q.shape[-1])
            step[j] = 1e-6
            ahead = self.load_terms(Conditions(q + step, loads=conditions.loads))[..., free]
            behind = self.load_terms(Conditions(q - step, loads=conditions.loads))[..., free]
            out[..., j] = (ahead - behind) / 2e-6
        return out

    def design_loads(
        self, payloads: Sequence[float] | None
    ) -> tuple[CompliantSpatialArm, np.ndarray]:
        """The model of a plan whose poses carry ``payloads`` (kg; default 0 and the robot
        file's payload), with the compliance that poses at those payloads identify (a
        fixed probe of random poses within the limits decides)."""
        values = np.array(payload_choices(self.elastic.payload_kg, payloads))
        model = CompliantSpatialArm.for_loads(
            self.arm, self.elastic, Loads.create(values.size, values)
        )
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        probe = lo + (hi - lo) * np.random.default_rng(0).random((_PROBE_POSES, self.n_joints))
        loads = Loads.create(_PROBE_POSES, np.resize(values, _PROBE_POSES))
        ready = model.prepared(model.plan_conditions(probe, loads))
        return replace(model, held=ready.held, merges=ready.merges), values

    # -- the tool --------------------------------------------------------------------------

    @property
    def orientation_dim(self) -> int:
        return self.arm.orientation_dim

    def orientation(self, conditions: Conditions, params: np.ndarray | None = None) -> np.ndarray:
        bent, geometry = self._bent(conditions, params)
        return self.arm.orientation(bent, geometry)

    def orientation_turn(
        self, conditions: Conditions, params: np.ndarray | None, reference: np.ndarray
    ) -> np.ndarray:
        bent, geometry = self._bent(conditions, params)
        return self.arm.orientation_turn(bent, geometry, reference)

    def orientation_joint_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        bent, geometry = self._bent(conditions, params)
        return self.arm.orientation_joint_jacobian(bent, geometry)

    def orientation_jacobian(
        self, conditions: Conditions, params: np.ndarray | None = None
    ) -> np.ndarray:
        bent, geometry = self._bent(conditions, params)
        geo = self.arm.orientation_jacobian(bent, geometry)
        joint = self.arm.orientation_joint_jacobian(bent, geometry)
        return np.concatenate([geo, self._columns(conditions, joint)], axis=-1)

    def in_robot_frame(self, params: np.ndarray) -> tuple[CompliantSpatialArm, np.ndarray]:
        """The base pose set to 0; gravity is in the base frame already."""
        geometry, compliance = self.split(np.asarray(params, dtype=float))
        arm, robot = self.arm.in_robot_frame(geometry)
        return replace(self, arm=arm), np.concatenate([robot, compliance], axis=-1)


def _payloads_only(loads: Loads) -> Loads:
    """``loads``, or ArmcalError for tip forces, which this model has no term for."""
    if np.any(loads.force_n != 0):
        raise ArmcalError(
            "a spatial arm takes payloads (payload_kg), not tip forces fx_N/fy_N; remove "
            "the force columns"
        )
    return loads


def payload_choices(default_kg: float, given: Sequence[float] | None) -> tuple[float, ...]:
    """The payloads a design may use: ``given``, else 0 and the robot file's payload."""
    if given is not None:
        values = sorted({float(v) for v in given})
        if not values or any(not np.isfinite(v) or v < 0 for v in values):
            raise ArmcalError(f"payloads must be finite and not negative (kg), got {list(given)}")
        return tuple(values)
    return (0.0, default_kg) if default_kg > 0 else (0.0,)
