"""The measurement noise model, one definition for identification, design and simulation.

An instrument measures the tip with a ``2 x 2`` covariance ``Sigma_meas`` (mm^2):
isotropic ``sigma^2 I``, per axis ``diag(sx^2, sy^2)``, or a full matrix.  The
joint encoders may add noise ``sigma_q`` (rad, per joint): the arm was really at
``q + dq`` when the controller reported ``q``, so the measured tip moves by
``J_q dq`` to first order (errors in variables), and pose ``i`` carries::

    Sigma_i = Sigma_meas + J_q(q_i) diag(sigma_q^2) J_q(q_i)^T

with ``J_q = d tip / d q`` at the current deviations (the user Jacobian's
``dq`` columns: a joint offset and an encoder error move the tip alike).
An instrument that reports each point's uncertainty replaces ``Sigma_meas`` by
``s_i^2 I`` row by row.  A 6-DoF instrument also measures the target's
orientation, with independent noise ``sigma_o`` (rad) about each axis; its rows
are ``(x, y, z, turn)`` with the covariance ``diag(Sigma_meas, sigma_o^2 I)`` plus
the encoder term of the six rows.  A laser tracker's noise depends on where the point is
(:class:`TrackerNoise`): along the line of sight from the tracker's origin its
range uncertainty, across it its angular uncertainty times the distance, each
of the data-sheet form "a constant plus a term per metre", so
``Sigma_meas(p) = s_r(d)^2 u u^T + s_t(d)^2 (I - u u^T)`` with ``d = |p|`` and
``u = p / d`` (``p`` in the instrument's frame).

The noise knows nothing of arms: the model gives ``J_q`` (its joint Jacobian)
where the encoder term is needed.  Everything downstream sees the noise
through one *relative whitening*
``W_i`` (:meth:`NoiseModel.whitening`) with ``W_i^T W_i = sigma_ref^2 Sigma_i^-1``:
weighted least squares is ordinary least squares on ``W_i`` times the rows, and
``cov = sigma_ref^2 (J_w^T J_w)^-1`` is the generalized-least-squares covariance.
The reference ``sigma_ref`` (:attr:`NoiseModel.sigma_mm`) is the isotropic
noise with the same information per pose averaged over orientations,
``sqrt(2 / tr(Sigma_meas^-1))``: ``W = I`` for isotropic noise, so every result
of the isotropic model is unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "TRACKER_REFERENCE_MM",
    "NoiseModel",
    "TrackerNoise",
    "instrument_override",
    "per_row_sigma",
    "relative_noise",
]


#: Per-row sigma as a caller holds it (an array, a list).
_Rows = TypeVar("_Rows")

#: The distance (mm) at which a laser tracker's reference noise (:attr:`NoiseModel.sigma_mm`)
#: is stated: 1 m, the unit of the data sheets' distance terms.
TRACKER_REFERENCE_MM = 1000.0


@dataclass(frozen=True)
class TrackerNoise:
    """A laser tracker's noise, seen from its origin (1 std, mm).

    Along the line of sight the range (ADM or interferometer) uncertainty
    ``s_r = range_mm + range_mm_per_m * d``, across it the angular
    encoders' ``s_t = transverse_mm + transverse_mm_per_m * d``, at distance
    ``d`` (m) from the tracker: the form data sheets give.  Data sheets often
    quote maximum permissible errors, about 2 std: halve them.

    Examples
    --------
    >>> tracker = TrackerNoise(0.008, 0.0004, 0.010, 0.0025)
    >>> cov = tracker.covariances(np.array([[0.0, 0.0, 4000.0]]))[0]
    >>> np.sqrt(np.diagonal(cov)).round(6).tolist()  # across, across, along the sight
    [0.02, 0.02, 0.0096]
    """

    range_mm: float
    range_mm_per_m: float
    transverse_mm: float
    transverse_mm_per_m: float

    def __post_init__(self) -> None:
        values = [self.range_mm, self.range_mm_per_m, self.transverse_mm, self.transverse_mm_per_m]
        if not all(np.isfinite(v) and v >= 0 for v in values) or min(values[0], values[2]) <= 0:
            raise ValueError(
                "a tracker's noise terms must be finite and >= 0, and its constant range and "
                f"transverse terms > 0 (mm), got {values}"
            )

    def sigmas(self, distance_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Range and transverse noise (1 std, mm) at ``distance_mm`` from the tracker."""
        metres = np.asarray(distance_mm, dtype=float) / 1000.0
        return (
            self.range_mm + self.range_mm_per_m * metres,
            self.transverse_mm + self.transverse_mm_per_m * metres,
        )

    def covariances(self, points: np.ndarray) -> np.ndarray:
        """``Sigma_meas`` ``(..., 3, 3)`` (mm^2) of points ``(..., 3)`` in the tracker's frame."""
        points = np.asarray(points, dtype=float)
        distance = np.linalg.norm(points, axis=-1)
        sight = points / np.maximum(distance, 1e-300)[..., None]  # 0 at the origin itself
        along, across = self.sigmas(distance)
        outer = sight[..., :, None] * sight[..., None, :]
        return (along**2 - across**2)[..., None, None] * outer + across[..., None, None] ** 2 * (
            np.eye(3)
        )

    def precision_pullback(
        self, points: np.ndarray, velocity: np.ndarray, weight: np.ndarray
    ) -> np.ndarray:
        """``sum_jk S_jk d (Sigma_meas^-1)_jk / d q`` ``(..., n)`` (mm^-2 per reading) for
        weights ``S`` ``(..., 3, 3)`` at points ``(..., 3)`` moving at ``velocity``
        ``(..., 3, n)`` (mm per reading).

        ``Sigma^-1 = b I + (a - b) u u^T`` with ``a = s_r^-2``, ``b = s_t^-2`` at distance
        ``d = |p|`` and ``u = p / d``: ``dd = u . dp``, ``du = (dp - u dd) / d``, and
        ``da = -2 a s_r' dd / s_r`` (``s_r'`` the term per metre, per mm), so the sum is
        ``db tr S + (da - db) u.S u + 2 (a - b) (S_sym u) . du``.
        """
        points = np.asarray(points, dtype=float)
        distance = np.linalg.norm(points, axis=-1)
        sight = points / distance[..., None]
        along, across = self.sigmas(distance)
        a, b = along**-2.0, across**-2.0
        d_distance = np.einsum("...i,...in->...n", sight, velocity)  # (..., n)
        da = -2.0 * (a / along)[..., None] * (self.range_mm_per_m / 1000.0) * d_distance
        db = -2.0 * (b / across)[..., None] * (self.transverse_mm_per_m / 1000.0) * d_distance
        sym = 0.5 * (weight + np.swapaxes(weight, -1, -2))
        pulled = np.einsum("...ij,...j->...i", sym, sight)  # S_sym u
        along_s = np.einsum("...i,...i->...", sight, pulled)  # u.S u
        d_sight = (
            np.einsum("...i,...in->...n", pulled, velocity) - along_s[..., None] * d_distance
        ) / distance[..., None]  # (S_sym u) . du
        trace = np.trace(weight, axis1=-2, axis2=-1)
        return (
            db * trace[..., None]
            + (da - db) * along_s[..., None]
            + 2.0 * (a - b)[..., None] * d_sight
        )

    def to_dict(self) -> dict[str, float]:
        return {
            "range_mm": self.range_mm,
            "range_mm_per_m": self.range_mm_per_m,
            "transverse_mm": self.transverse_mm,
            "transverse_mm_per_m": self.transverse_mm_per_m,
        }


def _spd(matrix: np.ndarray) -> bool:
    """Whether a square matrix is symmetric positive definite and finite."""
    if not np.all(np.isfinite(matrix)):
        return False
    scale = np.max(np.abs(np.diagonal(matrix)))
    if np.max(np.abs(matrix - matrix.T)) > 1e-12 * scale:
        return False
    return bool(np.all(np.linalg.eigvalsh((matrix + matrix.T) / 2) > 0))


@dataclass(frozen=True, eq=False, init=False)
class NoiseModel:
    """Instrument and encoder noise of the measurements.

    Parameters
    ----------
    covariance_mm2 : array_like, shape (2, 2)
        Covariance of a measured position in mm^2 (symmetric positive definite).
    joint_sigma : float or array_like of shape (n,), optional
        Encoder noise (1 std) in rad, one value for every joint or one per joint.
    tracker : TrackerNoise, optional
        A laser tracker's noise, which depends on where each point is; then
        ``covariance_mm2`` is the isotropic noise with the same information at
        :data:`TRACKER_REFERENCE_MM` (:meth:`laser_tracker` builds it).
    orientation_sigma : float, optional
        A 6-DoF instrument's orientation noise (1 std about each axis, rad).

    Examples
    --------
    >>> noise = NoiseModel.per_axis(0.08, 0.02)
    >>> round(noise.sigma_mm, 6), noise.isotropic_iid
    (0.02744, False)
    >>> (NoiseModel.isotropic(0.1).whitening((1,)) + 0.0).tolist()  # no -0.0
    [[[1.0, 0.0], [0.0, 1.0]]]
    """

    covariance_mm2: np.ndarray
    joint_sigma: np.ndarray | None
    tracker: TrackerNoise | None
    orientation_sigma: float | None

    def __init__(
        self,
        covariance_mm2: ArrayLike,
        joint_sigma: ArrayLike | None = None,
        *,
        tracker: TrackerNoise | None = None,
        orientation_sigma: float | None = None,
    ) -> None:
        cov = np.array(covariance_mm2, dtype=float)
        if cov.shape not in ((1, 1), (2, 2), (3, 3)) or not _spd(cov):
            raise ValueError(
                "covariance_mm2 must be a symmetric positive definite 1 x 1 (an instrument "
                "reading one distance), 2 x 2 (in the plane) or 3 x 3 matrix, got "
                f"{cov.tolist()}"
            )
        cov = (cov + cov.T) / 2
        cov.flags.writeable = False
        js = None
        if joint_sigma is not None:
            js = np.atleast_1d(np.array(joint_sigma, dtype=float))
            if js.ndim != 1 or not np.all(np.isfinite(js) & (js >= 0)):
                raise ValueError(f"joint_sigma must be finite and >= 0, got {js.tolist()}")
            if not np.any(js > 0):
                js = None
            else:
                js.flags.writeable = False
        if tracker is not None and cov.shape != (3, 3):
            raise ValueError("a laser tracker measures 3-D points: covariance_mm2 must be 3 x 3")
        object.__setattr__(self, "covariance_mm2", cov)
        object.__setattr__(self, "joint_sigma", js)
        object.__setattr__(self, "tracker", tracker)
        if orientation_sigma is not None:
            orientation_sigma = float(orientation_sigma)
            if not (np.isfinite(orientation_sigma) and orientation_sigma > 0):
                raise ValueError(f"orientation_sigma must be > 0 rad, got {orientation_sigma}")
        object.__setattr__(self, "orientation_sigma", orientation_sigma)

    def with_orientation(self, sigma_rad: float | None) -> NoiseModel:
        """The same noise with a 6-DoF instrument's orientation noise ``sigma_rad`` (rad)."""
        return NoiseModel(
            self.covariance_mm2,
            self.joint_sigma,
            tracker=self.tracker,
            orientation_sigma=sigma_rad,
        )

    @classmethod
    def laser_tracker(
        cls, tracker: TrackerNoise, joint_sigma: ArrayLike | None = None
    ) -> NoiseModel:
        """A laser tracker's noise (:class:`TrackerNoise`); the reference ``sigma_mm`` is
        ``sqrt(3 / (1/s_r^2 + 2/s_t^2))`` at :data:`TRACKER_REFERENCE_MM` from it.

        Examples
        --------
        >>> noise = NoiseModel.laser_tracker(TrackerNoise(0.01, 0.0, 0.01, 0.0))
        >>> round(noise.sigma_mm, 12), noise.isotropic_instrument
        (0.01, False)
        """
        along, across = tracker.sigmas(np.array(TRACKER_REFERENCE_MM))
        reference = np.sqrt(3.0 / (1.0 / along**2 + 2.0 / across**2))
        return cls(np.eye(3) * reference**2, joint_sigma, tracker=tracker)

    @classmethod
    def isotropic(
        cls, sigma_mm: float, joint_sigma: ArrayLike | None = None, *, dim: int = 2
    ) -> NoiseModel:
        """``sigma^2 I``: the same noise along every direction (the paper's model), in
        ``dim`` coordinates (2 in the plane, 3 in space)."""
        return cls(np.eye(dim) * float(sigma_mm) ** 2, joint_sigma)

    @property
    def dim(self) -> int:
        """Coordinates of a measured point: 2 or 3."""
        return int(self.covariance_mm2.shape[0])

    def for_dim(self, dim: int) -> NoiseModel:
        """The same noise for points of ``dim`` coordinates: an isotropic instrument's
        sigma carries over; ValueError for an anisotropic one of another dimension.

        Examples
        --------
        >>> NoiseModel.isotropic(0.05).for_dim(3).covariance_mm2.shape
        (3, 3)
        """
        if dim == self.dim:
            return self
        if self.tracker is not None:
            raise ValueError(
                f"a laser tracker's noise model is for 3-D points, the measurements are {dim}-D"
            )
        if not self.isotropic_instrument:
            raise ValueError(
                f"the instrument's noise is given for {self.dim}-D points, the measurements "
                f"are {dim}-D; give sigma_mm as one number or {dim} values"
            )
        same = NoiseModel.isotropic(self.sigma_mm, self.joint_sigma, dim=dim)
        return same.with_orientation(self.orientation_sigma)

    @classmethod
    def per_axis(
        cls, sx_mm: float, sy_mm: float, joint_sigma: ArrayLike | None = None
    ) -> NoiseModel:
        """``diag(sx^2, sy^2)``: independent noise per instrument axis."""
        return cls(np.diag([float(sx_mm) ** 2, float(sy_mm) ** 2]), joint_sigma)

    @property
    def sigma_mm(self) -> float:
        """The reference noise ``sqrt(d / tr(Sigma_meas^-1))`` (mm): ``sigma`` when isotropic."""
        return float(np.sqrt(self.dim / np.trace(np.linalg.inv(self.covariance_mm2))))

    @property
    def isotropic_instrument(self) -> bool:
        """Whether ``Sigma_meas`` is a multiple of the identity (never for a tracker)."""
        if self.tracker is not None:
            return False
        c = self.covariance_mm2
        return bool(np.array_equal(c, c[0, 0] * np.eye(self.dim)))

    @property
    def isotropic_iid(self) -> bool:
        """Isotropic instrument noise and no encoder noise: the paper's assumption."""
        return self.isotropic_instrument and self.joint_sigma is None

    def with_instrument_sigma(self, sigma_mm: float) -> NoiseModel:
        """The same encoder (and orientation) noise with isotropic instrument noise
        ``sigma_mm``."""
        same = NoiseModel.isotropic(sigma_mm, self.joint_sigma, dim=self.dim)
        return same.with_orientation(self.orientation_sigma)

    def check_joints(self, n: int) -> None:
        """Raise ValueError unless ``joint_sigma`` fits an arm of ``n`` joints."""
        if self.joint_sigma is not None and self.joint_sigma.size not in (1, n):
            raise ValueError(
                f"joint_sigma must have 1 or {n} values for {n} joints, "
                f"got {self.joint_sigma.size}"
            )

    def instrument_covariances(
        self,
        shape: tuple[int, ...],
        *,
        row_sigma: np.ndarray | None = None,
        points: np.ndarray | None = None,
        oriented: bool = False,
    ) -> np.ndarray:
        """The instrument's ``Sigma_meas`` ``(..., m, d, d)`` (mm^2) of measurements of shape
        ``(..., m)``: ``row_sigma`` ``(m,)`` (mm) replaces it row by row; a tracker's
        depends on the ``points`` ``(..., m, 3)`` (mm, instrument frame).  ``oriented``
        rows measure the orientation too: ``(..., m, d + 3, d + 3)``, block diagonal.
        """
        d = self.dim
        if row_sigma is not None:
            cov = np.asarray(row_sigma, dtype=float)[..., None, None] ** 2 * np.eye(d)
        elif self.tracker is not None:
            if points is None:
                raise ValueError("a laser tracker's noise depends on where the points are")
            cov = self.tracker.covariances(points)
        else:
            cov = np.broadcast_to(self.covariance_mm2, (*shape, d, d))
        if not oriented:
            return cov
        if self.orientation_sigma is None:
            raise ValueError(
                "the instrument measures orientations: its orientation noise is needed "
                "(orientation_sigma_deg in the robot file's [measurement])"
            )
        lead = np.broadcast_shapes(shape, cov.shape[:-2])
        out = np.zeros((*lead, d + 3, d + 3))
        out[..., :d, :d] = cov
        out[..., d:, d:] = self.orientation_sigma**2 * np.eye(3)
        return out

    def pose_covariances(
        self,
        shape: tuple[int, ...],
        *,
        joint_jacobian: np.ndarray | None = None,
        row_sigma: np.ndarray | None = None,
        points: np.ndarray | None = None,
        oriented: bool = False,
    ) -> np.ndarray:
        """``Sigma_i`` ``(..., m, d, d)`` in mm^2 of measurements of shape ``(..., m)``.

        ``joint_jacobian`` ``(..., m, d, n)`` (mm/rad) is ``d tip / d q`` where the
        encoder term is linearized: the model's (:meth:`armcal.models.planar.arm.PlanarArm.
        pose_covariances` gives it); without it, or without encoder noise, only the
        instrument's covariance counts.  ``row_sigma``, ``points`` and ``oriented`` as
        for :meth:`instrument_covariances` (``d`` is then ``dim + 3``).
        """
        base = self.instrument_covariances(
            shape, row_sigma=row_sigma, points=points, oriented=oriented
        )
        d = base.shape[-1]
        if self.joint_sigma is None or joint_jacobian is None:
            return np.broadcast_to(base, (*np.broadcast_shapes(shape, base.shape[:-2]), d, d))
        n = joint_jacobian.shape[-1]
        scaled = joint_jacobian * np.broadcast_to(self.joint_sigma, (n,))
        return base + scaled @ np.swapaxes(scaled, -1, -2)

    def whitening(
        self,
        shape: tuple[int, ...],
        *,
        joint_jacobian: np.ndarray | None = None,
        row_sigma: np.ndarray | None = None,
        points: np.ndarray | None = None,
        oriented: bool = False,
    ) -> np.ndarray:
        """Relative whitening ``W_i`` ``(..., m, d, d)``: ``W_i^T W_i = sigma_ref^2 Sigma_i^-1``.

        ``W_i = sigma_ref L_i^-1`` for the Cholesky factor ``Sigma_i = L_i L_i^T``,
        in closed form (lower triangular).  The identity for isotropic noise.
        Arguments as for :meth:`pose_covariances`.
        """
        cov = self.pose_covariances(
            shape,
            joint_jacobian=joint_jacobian,
            row_sigma=row_sigma,
            points=points,
            oriented=oriented,
        )
        return whitening_from_covariance(cov, self.sigma_mm)

    def metric_pullback(
        self,
        whitening: np.ndarray,
        points: np.ndarray,
        velocity: np.ndarray,
        jacobian: np.ndarray,
        cotangent: np.ndarray,
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """What a pose-dependent metric ``W^T W = sigma_ref^2 Sigma^-1`` adds to the derivative
        ``<G, d(W J)/dq>`` of a weighted sum of whitened blocks, ``G`` ``(..., d, k)`` =
        ``cotangent``: ``<S, d(W^T W)/dq> / 2`` with ``S = W^-1 G J^T``, exact for every
        quadratic form ``tr(A (W J)^T W J)`` (``G = 2 W J A``).

        With ``P = Sigma^-1``, ``d(W^T W) = -sigma_ref^2 P dSigma P``.  Returns two parts,
        None where the metric does not move that way:

        * a tracker's ``(..., n)``: ``Sigma_meas`` moves with the ``points`` at their
          ``velocity`` ``(..., 3, n)`` (``d Sigma = -Sigma dSigma^-1 Sigma``, so it is
          :meth:`TrackerNoise.precision_pullback` of ``Sigma_meas P S P Sigma_meas``);
        * the encoder term's, as a cotangent ``(..., d, n)`` of the joint Jacobian
          ``J_q`` = ``velocity``: ``Sigma = Sigma_meas + J_q D J_q^T`` (``D`` the
          encoders' variances) gives ``-sigma_ref^2 P S_sym P J_q D``, which the
          kinematics pulls back.
        """
        if self.tracker is None and self.joint_sigma is None:
            return None, None
        weight = np.linalg.solve(whitening, cotangent) @ np.swapaxes(jacobian, -1, -2)
        weight = 0.5 * (weight + np.swapaxes(weight, -1, -2))
        reference = self.sigma_mm**2
        precision = np.swapaxes(whitening, -1, -2) @ whitening / reference  # P
        spread = precision @ weight @ precision
        position = joint = None
        if self.tracker is not None:
            measured = self.tracker.covariances(points)
            pulled = self.tracker.precision_pullback(
                points, velocity, measured @ spread @ measured
            )
            position = 0.5 * reference * pulled
        if self.joint_sigma is not None:
            variances = np.broadcast_to(self.joint_sigma, (velocity.shape[-1],)) ** 2
            joint = -reference * (spread @ velocity) * variances
        return position, joint

    def to_dict(self) -> dict[str, object]:
        """JSON form: ``covariance_mm2``, ``joint_sigma_deg`` (null without encoder noise) and,
        for a laser tracker, ``tracker`` (its four terms)."""
        out: dict[str, object] = {
            "covariance_mm2": self.covariance_mm2.tolist(),
            "joint_sigma_deg": None
            if self.joint_sigma is None
            else np.degrees(self.joint_sigma).tolist(),
        }
        if self.tracker is not None:
            out["tracker"] = self.tracker.to_dict()
        if self.orientation_sigma is not None:
            out["orientation_sigma_deg"] = float(np.degrees(self.orientation_sigma))
        return out


def whitening_from_covariance(cov: np.ndarray, reference: float) -> np.ndarray:
    """``reference * L^-1`` ``(..., d, d)`` for ``cov = L L^T`` (closed-form Cholesky in 2-D)."""
    if cov.shape[-1] != 2:
        return reference * np.linalg.inv(np.linalg.cholesky(cov))
    a = cov[..., 0, 0]
    b = cov[..., 1, 0]
    c = cov[..., 1, 1]
    l11 = np.sqrt(a)
    l21 = b / l11
    l22 = np.sqrt(c - l21**2)
    w = np.zeros(cov.shape)
    w[..., 0, 0] = reference / l11
    w[..., 1, 1] = reference / l22
    w[..., 1, 0] = -reference * l21 / (l11 * l22)
    return w


def complex_whitening(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(alpha, beta)`` ``(...)`` with ``W (x, y) = alpha z + beta conj(z)`` for ``z = x + i y``.

    Every real-linear map of the plane acts on complex numbers this way, which
    keeps the complex-column form of the Jacobian (:mod:`armcal.models.planar.information`)
    for weighted models.

    Examples
    --------
    >>> alpha, beta = complex_whitening(np.array([[2.0, 0.0], [0.0, 1.0]]))
    >>> z = 1 + 2j
    >>> complex(alpha * z + beta * np.conj(z))
    (2+2j)
    """
    w11, w12, w21, w22 = w[..., 0, 0], w[..., 0, 1], w[..., 1, 0], w[..., 1, 1]
    alpha = ((w11 + w22) + 1j * (w21 - w12)) / 2
    beta = ((w11 - w22) + 1j * (w21 + w12)) / 2
    return alpha, beta


def instrument_override(noise: NoiseModel | None, sigma_mm: float) -> NoiseModel:
    """The noise model with ``sigma_mm`` as the instrument's isotropic noise: what ``--sigma``
    means, in one place.

    The instrument covariance becomes ``sigma_mm^2 I`` and any encoder noise of
    ``noise`` stays; without a noise model, isotropic noise of ``sigma_mm``.

    Examples
    --------
    >>> noise = instrument_override(NoiseModel.per_axis(0.08, 0.02, joint_sigma=1e-4), 0.05)
    >>> noise.covariance_mm2.round(6).tolist(), noise.joint_sigma.tolist()
    ([[0.0025, 0.0], [0.0, 0.0025]], [0.0001])
    >>> instrument_override(None, 0.1).isotropic_iid
    True
    """
    if noise is None:
        return NoiseModel.isotropic(sigma_mm)
    return noise.with_instrument_sigma(sigma_mm)


def per_row_sigma(sigma_mm: float | None, row_sigma: _Rows | None) -> _Rows | None:
    """The per-row instrument noise a fit or a draw uses, given both: the one rule of
    precedence between ``sigma`` and per-row sigma, in one place.

    An explicit ``sigma_mm`` is the instrument's noise: it replaces the noise
    model's instrument part (:func:`instrument_override`) *and* any per-row sigma
    (an instrument's reported uncertainties, a measurement file's ``sigma_mm``
    column), which is then not used; the encoder noise stays.  Without it the
    per-row values replace the instrument covariance row by row.  The command
    line's ``--sigma`` means the same.

    Examples
    --------
    >>> per_row_sigma(0.05, [0.01, 0.02]) is None
    True
    >>> per_row_sigma(None, [0.01, 0.02])
    [0.01, 0.02]
    """
    return None if sigma_mm is not None else row_sigma


def relative_noise(noise: NoiseModel | None) -> NoiseModel:
    """The noise that relative weights are taken from: ``noise``, or unit isotropic noise
    where there is none (every row then weighs the same)."""
    return noise if noise is not None else NoiseModel.isotropic(1.0)
