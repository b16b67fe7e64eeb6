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

Parameters (:class:`Compliance`), in display units
--------------------------------------------------

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
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArmcalError, ArmcalWarning, NotIdentifiableError
from ..numerics import COND_WARN, RANK_RTOL, ScaledSVD, scaled_svd
from .planar import PlanarArm
from .planar_information import Identifiability, combination, listing, row_echelon
from .planar_kinematics import forward_kinematics, jacobian, link_vectors

__all__ = [
    "STANDARD_GRAVITY",
    "Compliance",
    "Elastostatic",
    "Loads",
    "check_compliance_identifiable",
    "compliance_identifiability",
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
    """

    gravity: np.ndarray | None
    link_masses_kg: np.ndarray | None
    com_fraction: np.ndarray
    payload_kg: float = 0.0

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

    def with_gravity(self, gravity: np.ndarray | None) -> Elastostatic:
        """The same loads with gravity (m/s^2) given in another frame."""
        return Elastostatic(
            None if gravity is None else np.asarray(gravity, dtype=float),
            self.link_masses_kg,
            self.com_fraction,
            self.payload_kg,
        )


@dataclass(frozen=True, eq=False)
class Loads:
    """The known static loads of every row: payload (kg) and tip force (N).

    Attributes
    ----------
    payload_kg : ndarray, shape (m,)
    force_n : ndarray, shape (m, 2)
        Force applied at the tip, in the measurement frame.
    """

    payload_kg: np.ndarray
    force_n: np.ndarray

    @classmethod
    def create(
        cls, m: int, payload_kg: ArrayLike = 0.0, force_n: ArrayLike | None = None
    ) -> Loads:
        """Loads of ``m`` rows (a scalar payload is every row's).

        Examples
        --------
        >>> Loads.create(3, [0, 10, 0]).known
        True
        >>> Loads.create(2).known
        False
        """
        payload = np.broadcast_to(np.asarray(payload_kg, dtype=float), (m,)).copy()
        force = np.zeros((m, 2)) if force_n is None else np.asarray(force_n, dtype=float)
        if force.shape != (m, 2):
            raise ArmcalError(f"tip forces must have shape ({m}, 2) in N, got {force.shape}")
        if not (np.all(np.isfinite(payload)) and np.all(np.isfinite(force))):
            raise ArmcalError("payloads and tip forces must be finite")
        if np.any(payload < 0):
            raise ArmcalError("payloads must not be negative")
        return cls(payload, force)

    @property
    def n_rows(self) -> int:
        return int(self.payload_kg.shape[0])

    @property
    def known(self) -> bool:
        """Whether any row carries a payload or a tip force."""
        return bool(np.any(self.payload_kg != 0) or np.any(self.force_n != 0))

    @property
    def varying(self) -> bool:
        """Whether the known loads differ between rows."""
        if self.n_rows == 0:
            return False
        return bool(np.ptp(self.payload_kg) > 0 or np.any(np.ptp(self.force_n, axis=0) > 0))

    def take(self, rows: np.ndarray) -> Loads:
        """The loads of the rows ``rows`` (index or mask)."""
        return Loads(self.payload_kg[rows], self.force_n[rows])


@dataclass(frozen=True, eq=False)
class Compliance:
    """The compliance parameters of an arm under given loads, and the deflected model.

    The parameter vector is the arm's user deviations followed by the
    compliance parameters (:attr:`names`): ``k1..kn`` when the masses are
    known; ``c1..cn`` in the lumped mode, followed by ``k1..kn`` when
    ``known_loads`` (a payload or tip force that the torque can be computed
    from).  Internal units: rad/(N m) for ``k``, rad/m for ``c``.

    Attributes
    ----------
    arm : PlanarArm
    elastic : Elastostatic
    known_loads : bool
        Whether the data or design carry known loads (lumped mode only).
    """

    arm: PlanarArm
    elastic: Elastostatic
    known_loads: bool = False

    def __post_init__(self) -> None:
        if self.arm.n_target_links > 1:
            raise ArmcalError(
                "joint compliance is modelled for one target on the end effector; "
                "measure one target per pose, or leave out [elastostatic]"
            )
        if self.elastic.gravity is None and not self.known_loads:
            raise ArmcalError(
                "[elastostatic] has no gravity_xy and the data carry no payload or tip "
                "force that varies: nothing twists the joints; give gravity_xy for a vertical "
                "arm, or payload_kg/fx_N/fy_N"
            )

    @classmethod
    def for_loads(cls, arm: PlanarArm, elastic: Elastostatic, loads: Loads) -> Compliance:
        """The model for data with ``loads``: in lumped mode, loads that vary add ``k1..kn``."""
        gravity_lumped = elastic.lumped and elastic.gravity is not None
        # A constant payload only adds to the lumped weight: k needs loads that vary.
        return cls(arm, elastic, known_loads=loads.varying if gravity_lumped else loads.known)

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
    def n_params(self) -> int:
        return len(self.kinds)

    @cached_property
    def names(self) -> tuple[str, ...]:
        return tuple(f"{k}{j + 1}" for k, j in zip(self.kinds, self.joints, strict=True))

    @cached_property
    def units(self) -> tuple[str, ...]:
        return tuple(K_UNIT if k == "k" else C_UNIT for k in self.kinds)

    @cached_property
    def display_scale(self) -> np.ndarray:
        return np.array([K_SCALE if k == "k" else C_SCALE for k in self.kinds])

    @property
    def all_names(self) -> tuple[str, ...]:
        """The arm's parameter names, then the compliance parameters'."""
        return self.arm.param_names + self.names

    @property
    def all_units(self) -> tuple[str, ...]:
        return self.arm.param_units + self.units

    @property
    def all_scale(self) -> np.ndarray:
        return np.concatenate([self.arm.display_scale, self.display_scale])

    @property
    def all_free(self) -> np.ndarray:
        """Free mask over every parameter (compliance parameters are always free)."""
        return np.concatenate([self.arm.free, np.ones(self.n_params, dtype=bool)])

    @property
    def n_free(self) -> int:
        return self.arm.n_free + self.n_params

    def split(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Geometry ``(..., p)`` and compliance ``(..., P)`` of a full parameter vector."""
        p = self.arm.n_params
        return params[..., :p], params[..., p:]

    def loads(self, q: np.ndarray, geometry: np.ndarray | None, loads: Loads | None) -> np.ndarray:
        """The load ``(..., m, P)`` every compliance parameter multiplies, per row.

        The torque (N m) at the parameter's joint for ``k``, the horizontal lever
        arm (m) to the tip for ``c``, on the undeflected geometry.
        """
        arm, elastic = self.arm, self.elastic
        q = np.asarray(q, dtype=float)
        terms = link_vectors(arm, q, geometry) / 1000.0  # (..., m, n) in metres
        m = q.shape[-2]
        loads = Loads.create(m, elastic.payload_kg) if loads is None else loads
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

    def deflection(
        self,
        q: np.ndarray,
        geometry: np.ndarray | None,
        compliance: np.ndarray,
        loads: Loads | None,
        *,
        row_loads: np.ndarray | None = None,
    ) -> np.ndarray:
        """Joint deflections ``(..., m, n)`` in rad (relative angles)."""
        if row_loads is None:
            row_loads = self.loads(q, geometry, loads)
        per_param = row_loads * np.asarray(compliance, dtype=float)[..., None, :]
        n = self.arm.n_joints
        return per_param.reshape(*per_param.shape[:-1], -1, n).sum(axis=-2)

    def tip(self, q: np.ndarray, params: np.ndarray, loads: Loads | None) -> np.ndarray:
        """Measured positions ``(..., m, 2)`` (mm) of the full parameters ``(..., p + P)``."""
        geometry, compliance = self.split(np.asarray(params, dtype=float))
        deflection = self.deflection(q, geometry, compliance, loads)
        return forward_kinematics(self.arm, q, geometry, deflection=deflection)

    def jacobian(self, q: np.ndarray, params: np.ndarray, loads: Loads | None) -> np.ndarray:
        """``d(x, y) / d(params)`` ``(..., m, 2, p + P)`` (mm per internal unit).

        The geometric columns at the deflected pose; the compliance columns
        ``load_p i (p - p_j)``.  The torques' own (tiny) dependence on the
        geometry is left out: Gauss-Newton still converges to the exact fit,
        and the covariance changes by the relative size of a deviation (1e-3).
        """
        geometry, compliance = self.split(np.asarray(params, dtype=float))
        row_loads = self.loads(q, geometry, loads)
        deflection = self.deflection(q, geometry, compliance, loads, row_loads=row_loads)
        geo = jacobian(self.arm, q, geometry, deflection=deflection)
        terms = link_vectors(self.arm, q, geometry, deflection=deflection)
        turn = 1j * np.cumsum(terms[..., ::-1], axis=-1)[..., ::-1]  # i (p - p_j)
        columns = turn[..., self.joints] * row_loads
        comp = np.stack([columns.real, columns.imag], axis=-2)
        return np.concatenate([geo, comp], axis=-1)

    def whitened_jacobian(
        self, q: np.ndarray, loads: Loads | None, params: np.ndarray | None = None
    ) -> np.ndarray:
        """Free columns ``(..., m, 2, p_f + P)`` whitened by the arm's noise model (if any)."""
        total = self.arm.n_params + self.n_params
        at = np.zeros(total) if params is None else np.asarray(params, dtype=float)
        jac = self.jacobian(q, at, loads)[..., self.all_free]
        noise = self.arm.noise
        if noise is None or noise.isotropic_iid:
            return jac
        geometry = at[..., : self.arm.n_params] if noise.joint_sigma is not None else None
        return self.arm.whitening(q, geometry) @ jac

    def covariance(
        self,
        q: np.ndarray,
        loads: Loads | None,
        sigma: float,
        params: np.ndarray | None = None,
    ) -> tuple[np.ndarray, bool]:
        """Predicted covariance ``(p + P, p + P)`` (internal units) and whether it exists.

        ``sigma_ref^2 (J_w^T J_w)^-1`` over the free parameters, zero rows and
        columns for fixed ones; ``inf`` where the poses cannot identify them.
        """
        jac = self.whitened_jacobian(q, loads, params)
        svd = scaled_svd(jac.reshape(-1, self.n_free))
        inverse, ok = svd.inverse_gram()
        total = self.arm.n_params + self.n_params
        full = np.zeros((total, total))
        free = self.all_free
        full[np.ix_(free, free)] = sigma**2 * inverse
        return full, bool(ok)

    def std(self, covariance: np.ndarray) -> np.ndarray:
        """Standard deviations ``(p + P,)`` in display units of a covariance."""
        return np.sqrt(np.diagonal(covariance)) * self.all_scale

    def typical_scale(self, q: np.ndarray, loads: Loads | None) -> np.ndarray:
        """The RMS deflection (rad) per unit of every compliance parameter over the rows."""
        row_loads = self.loads(q, None, loads)
        return np.sqrt(np.mean(row_loads**2, axis=-2))


def _cross(r: np.ndarray, f: np.ndarray) -> np.ndarray:
    """``r x f`` of complex 2-vectors: ``Im(conj(r) f)``."""
    return (np.conj(r) * f).imag


def compliance_identifiability(
    model: Compliance,
    q: np.ndarray,
    loads: Loads | None,
    *,
    whitening: np.ndarray | None = None,
) -> tuple[Identifiability, ScaledSVD]:
    """Rank analysis of geometry plus compliance at the nominal arm, on scaled columns.

    The free columns of :meth:`Compliance.jacobian` at zero deviations (whitened
    when given) decide through the one rank policy of :mod:`armcal.numerics`.
    """
    q = np.asarray(q, dtype=float)
    full = np.zeros(model.arm.n_params + model.n_params)
    jac = model.jacobian(q, full, loads)[..., model.all_free]
    if whitening is not None:
        jac = whitening @ jac
    svd = scaled_svd(jac.reshape(-1, model.n_free))
    names = tuple(n for n, f in zip(model.all_names, model.all_free, strict=True) if f)
    scale = model.all_scale[model.all_free]
    null = svd.directions(RANK_RTOL)
    weak = svd.directions(1.0 / COND_WARN)
    bad: tuple[str, ...] = ()
    if null.shape[0]:
        basis, _ = np.linalg.qr((null * svd.column_norms).T)
        bad = tuple(
            n for n, w in zip(names, np.linalg.norm(basis, axis=1), strict=True) if w > 1e-8
        )

    null_rows = row_echelon(null * scale)
    weak_rows = row_echelon(weak * scale, tol=1e-3)
    m = q.shape[0]
    info = Identifiability(
        rank=int(svd.rank),
        n_params=model.n_free,
        singular_values=svd.singular_values / np.sqrt(max(m, 1)),
        unidentifiable=bad,
        combinations=tuple(combination(v, names) for v in null_rows),
        poorly_determined=tuple(combination(v, names, drop=1e-3) for v in weak_rows),
    )
    return info, svd


def check_compliance_identifiable(
    model: Compliance,
    q: np.ndarray,
    loads: Loads | None,
    *,
    whitening: np.ndarray | None = None,
) -> tuple[Identifiability, ScaledSVD]:
    """Raise :class:`NotIdentifiableError` unless the poses and loads identify everything.

    The message names the parameters that cannot be identified and says what
    the compliance needs: torques that vary through the poses and the payloads.
    """
    info, svd = compliance_identifiability(model, q, loads, whitening=whitening)
    if info.identifiable:
        return info, svd
    m = np.asarray(q).shape[0]
    p = model.n_free
    shown = "; ".join(info.combinations[:3])
    compliant = [n for n in info.unidentifiable if n in model.names]
    if 2 * m < p:
        why = f"{m} poses give {2 * m} equations for {p} parameters; measure more poses"
    elif compliant:
        needs = []
        if any(n.startswith("k") for n in compliant) and model.elastic.lumped:
            needs.append(
                "k is told from c only by known loads that vary: measure some poses with "
                "a different payload (or tip force)"
            )
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


def barely_identifiable_warning(info: Identifiability) -> ArmcalWarning | None:
    """An ``ill-conditioned`` warning when geometry plus compliance is barely identifiable."""
    if not info.ill_conditioned:
        return None
    return ArmcalWarning(
        "ill-conditioned",
        f"geometry plus compliance is barely identifiable (condition number "
        f"{info.condition_number:.3g}); poorly determined: "
        f"{'; '.join(info.poorly_determined[:3])}; vary the torques more (poses, payloads)",
    )
