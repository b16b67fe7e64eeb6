"""The planar arm's geometry and parametrization: link vectors, joint map, targets, base pose.

The model is paper eq. (1) with an optional base pose::

    p = (x0, y0) + sum_k (L_k + dl_k) * exp(1j * (theta_a(k) + alpha_k + dtheta_k))
    theta    = M q                      (link angles from the joint readings)
    dtheta   = A dq + phi0              (link-vector angle deviations)

For the paper's arm ``M`` is the lower-triangular matrix of ones
(``theta_i = q_1 + ... + q_i``), there is one link vector per joint
(``L_k = l_k``, ``alpha_k = 0``, ``A = M``) and no base rotation.  A
controller's joint convention gives another ``M`` (:attr:`PlanarGeometry.joint_map`:
joints counted the other way round, angles from the horizon); several targets
on the end effector each have their own last link vector (:class:`Target`);
3-D instrument data identify the base's rotation ``phi0`` in the fitted plane.

Two parametrizations of the deviations are used (internal units: mm and rad):

* **user** ``[dl_1..dl_K, dq_1..dq_K, (x0, y0), (phi0)]`` -- what files and
  reports show (``dl*`` in mm, ``dq*`` and ``phi0`` in degrees once converted,
  ``x0, y0`` in mm);
* **paper** ``[dtheta_1..dtheta_K, dl_1..dl_K, (x0, y0)]`` -- the paper's
  ``DeltaPi`` (eq. 6-8), in which the information matrix has the block form
  (17)-(19).

They are related by a constant linear map, :func:`paper_from_user`.  A
rotation of the base turns every link vector alike, so in 2-D data (instrument
axes parallel to the base frame) it is part of the joint offsets and never
identified; with :attr:`PlanarGeometry.base_rotation` one joint-offset direction
is held instead (:attr:`PlanarGeometry.rotation_partner`).

This module holds the structure only; :mod:`armcal.models.planar.kinematics`
evaluates it and :class:`armcal.models.planar.arm.PlanarArm` adds what a fit needs
(joint limits, noise, fixed parameters, the measuring region).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...numerics import wrap_angle
from ..joint_maps import checked_joint_map

__all__ = [
    "PlanarGeometry",
    "Target",
    "checked_link_lengths",
    "link_angles",
    "paper_from_user",
    "paper_from_user_matrix",
    "split_params",
    "standard_joint_map",
    "wrap_angle",
]


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Target:
    """A point measured on the end effector: a tracker reflector, a marker on a tool.

    Every target has its own last link from joint ``n``: the arm up to the last
    joint is shared, and target ``t`` is at ``length`` from joint ``n`` in the
    direction ``angle`` from the last link's nominal axis.

    Attributes
    ----------
    label : str
        The name used in the measurements' ``target`` column and in the
        parameter names ``dl{n}@{label}``, ``dq{n}@{label}``.
    length : float
        Nominal distance from joint ``n`` to the target, mm (positive).
    angle : float
        Nominal direction of the target from the last link's axis, rad.
    """

    label: str
    length: float
    angle: float = 0.0


def standard_joint_map(n: int) -> np.ndarray:
    """The default joint map ``(n, n)``: ``theta_i = q_1 + ... + q_i`` (lower-triangular ones).

    Examples
    --------
    >>> standard_joint_map(3).astype(int).tolist()
    [[1, 0, 0], [1, 1, 0], [1, 1, 1]]
    """
    return np.tril(np.ones((n, n)))


def checked_link_lengths(link_lengths: ArrayLike) -> np.ndarray:
    """Link lengths ``(n,)`` in mm as a read-only array; ValueError unless positive and finite."""
    lengths = _readonly(np.atleast_1d(np.asarray(link_lengths, dtype=float)))
    if lengths.ndim != 1 or lengths.size == 0:
        raise ValueError(f"link_lengths must have shape (n,) with n >= 1, got {lengths.shape}")
    if not np.all(np.isfinite(lengths) & (lengths > 0)):
        raise ValueError(f"link_lengths must be positive and finite, got {lengths.tolist()}")
    return lengths


@dataclass(frozen=True, eq=False, init=False)
class PlanarGeometry:
    """The structure of a planar serial arm: links, joint map, targets and base pose.

    What the kinematics need (:mod:`armcal.models.planar.kinematics`); the
    arm that is fitted, :class:`armcal.models.planar.arm.PlanarArm`, adds its joint
    limits, noise, fixed parameters and measuring region.

    Attributes
    ----------
    link_lengths : ndarray, shape (n,)
        Nominal link lengths ``l_i`` in mm, all positive.
    name : str
        A label for reports and files.
    base_offset : bool
        Whether the base position ``(x0, y0)`` in the instrument frame is
        identified (two more parameters).
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
        identified (3-D instrument data: the fitted plane's axes are the
        instrument's, turned against the robot's).  It turns every link like one
        joint-offset direction ``dq = M^-1 (1, ..., 1)``, so one joint offset on
        that direction is held (:attr:`rotation_partner`, ``dq1`` for the default
        joint map) unless another parameter on it is fixed.
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
    """

    link_lengths: np.ndarray
    name: str
    base_offset: bool
    joint_map: np.ndarray
    targets: tuple[Target, ...]
    base_rotation: bool
    joint_offsets: np.ndarray
    _default_joint_map: bool = field(repr=False)

    def __init__(
        self,
        link_lengths: ArrayLike,
        *,
        name: str = "arm",
        base_offset: bool = False,
        joint_map: ArrayLike | None = None,
        targets: Sequence[Target] = (),
        base_rotation: bool = False,
        joint_offsets: ArrayLike | None = None,
    ) -> None:
        lengths = checked_link_lengths(link_lengths)
        n = lengths.size
        mapping = standard_joint_map(n) if joint_map is None else checked_joint_map(joint_map, n)
        _check_last_column(mapping, several_targets=len(targets) > 1)
        targets = tuple(targets)
        _check_targets(targets)
        offsets = np.zeros(n) if joint_offsets is None else np.array(joint_offsets, dtype=float)
        if offsets.shape != (n,) or not np.all(np.isfinite(offsets)):
            raise ValueError(f"joint_offsets must be {n} finite angles in rad, got {offsets}")
        object.__setattr__(self, "link_lengths", lengths)
        object.__setattr__(self, "name", str(name))
        object.__setattr__(self, "base_offset", bool(base_offset))
        object.__setattr__(self, "joint_map", _readonly(mapping))
        object.__setattr__(self, "targets", targets)
        object.__setattr__(self, "base_rotation", bool(base_rotation))
        object.__setattr__(self, "joint_offsets", _readonly(offsets))
        # Derived once: the fast paths test it on every kinematics call.
        default = bool(np.array_equal(mapping, standard_joint_map(n)))
        object.__setattr__(self, "_default_joint_map", default)

    @property
    def standard_map(self) -> bool:
        """The paper's structure: the default joint map, one target, no base rotation."""
        return not self.targets and not self.base_rotation and self._default_joint_map

    @property
    def paper_structure(self) -> bool:
        """:attr:`standard_map` with no nominal joint offsets: link angles are ``cumsum(q)``."""
        return self.standard_map and self._default_map

    @property
    def n_joints(self) -> int:
        """Number of joints ``n``."""
        return int(self.link_lengths.size)

    @property
    def joint_kinds(self) -> tuple[str, ...]:
        """Every joint reading's kind: ``"R"`` each (a planar arm's joints turn; rad)."""
        return ("R",) * self.n_joints

    @property
    def n_target_links(self) -> int:
        """Number of last links: one per target, at least one."""
        return max(1, len(self.targets))

    @property
    def n_links(self) -> int:
        """Number of link vectors ``K = n - 1 + max(1, len(targets))``."""
        return self.n_joints - 1 + self.n_target_links

    @property
    def tip_reach_mm(self) -> float:
        """How far from joint 1 a measured point can lie: the links to the farthest target."""
        last = float(np.max(self.link_nominal[self.n_joints - 1 :]))
        return float(np.sum(self.link_lengths[:-1])) + last

    @property
    def target_labels(self) -> tuple[str, ...]:
        """Labels of the targets (empty for the single end-of-arm target)."""
        return tuple(t.label for t in self.targets)

    @property
    def link_nominal(self) -> np.ndarray:
        """Nominal length ``(K,)`` of every link vector, mm."""
        if not self.targets:
            return self.link_lengths
        return np.concatenate([self.link_lengths[:-1], [t.length for t in self.targets]])

    @property
    def link_joint(self) -> np.ndarray:
        """The link angle ``theta_i`` (0-based ``i``) each link vector turns with, ``(K,)``."""
        n = self.n_joints
        return np.concatenate([np.arange(n - 1), np.full(self.n_target_links, n - 1)])

    @property
    def link_angle0(self) -> np.ndarray:
        """Nominal direction ``(K,)`` of every link vector from its link's axis, rad."""
        tail = [t.angle for t in self.targets] if self.targets else [0.0]
        return np.concatenate([np.zeros(self.n_joints - 1), tail])

    @property
    def link_names(self) -> tuple[str, ...]:
        """``"1" .. "n-1"`` then ``"n"`` or ``"n@label"`` for every target."""
        n = self.n_joints
        tail = [f"{n}@{t.label}" for t in self.targets] if self.targets else [str(n)]
        return tuple([str(k) for k in range(1, n)] + tail)

    @property
    def angle_map(self) -> np.ndarray:
        """``A`` ``(K, K)`` with link-vector angle deviations ``dtheta = A dq`` (no base rotation).

        Rows of the shared links are those of :attr:`joint_map`; every target's
        row is the last row of the joint map with its own ``dq{n}@{label}``.
        """
        n, k = self.n_joints, self.n_links
        mapping = self.joint_map
        a = np.zeros((k, k))
        a[: n - 1, : n - 1] = mapping[: n - 1, : n - 1]
        a[n - 1 :, : n - 1] = mapping[n - 1, : n - 1]
        a[n - 1 :, n - 1 :] = mapping[n - 1, n - 1] * np.eye(self.n_target_links)
        if self.n_target_links == 1:
            a[: n - 1, n - 1] = mapping[: n - 1, n - 1]
        return a

    @property
    def n_paper(self) -> int:
        """Number of link-vector coordinates ``2K`` (``2K + 2`` with base offset)."""
        return 2 * self.n_links + (2 if self.base_offset else 0)

    @property
    def n_params(self) -> int:
        """Number of user parameters ``p``: ``2K`` (+2 with base offset, +1 with rotation)."""
        return self.n_paper + (1 if self.base_rotation else 0)

    @property
    def param_names(self) -> tuple[str, ...]:
        """User parameter names in order: ``dl.., dq..[, x0, y0][, phi0]``."""
        links = self.link_names
        names = [f"dl{k}" for k in links] + [f"dq{k}" for k in links]
        names += ["x0", "y0"] if self.base_offset else []
        return tuple(names + (["phi0"] if self.base_rotation else []))

    @property
    def param_units(self) -> tuple[str, ...]:
        """Units of the user parameters as shown to users: ``mm`` or ``deg``."""
        k = self.n_links
        base = ("mm", "mm") if self.base_offset else ()
        return ("mm",) * k + ("deg",) * k + base + (("deg",) if self.base_rotation else ())

    @property
    def paper_param_names(self) -> tuple[str, ...]:
        """Paper parameter names in order: ``dtheta.., dl..[, x0, y0]``."""
        links = self.link_names
        names = [f"dtheta{k}" for k in links] + [f"dl{k}" for k in links]
        return tuple(names + (["x0", "y0"] if self.base_offset else []))

    @property
    def angle_params(self) -> np.ndarray:
        """Boolean mask ``(p,)`` of the angle parameters (``dq``, ``phi0``: rad inside)."""
        mask = np.zeros(self.n_params, dtype=bool)
        mask[self.n_links : 2 * self.n_links] = True
        if self.base_rotation:
            mask[-1] = True
        return mask

    @property
    def display_scale(self) -> np.ndarray:
        """Factors ``(p,)`` from internal units (mm, rad) to display units (mm, deg)."""
        return np.where(self.angle_params, np.degrees(1.0), 1.0)

    def rotation_names(self) -> tuple[str, ...]:
        """The parameters on :attr:`rotation_direction` (a base rotation's partners)."""
        d = self.rotation_direction
        return tuple(nm for nm, c in zip(self.param_names, d, strict=True) if abs(c) > 1e-12)

    @property
    def turn_offsets(self) -> np.ndarray:
        """The joint offsets ``(k,)`` that turn every link vector alike, by 1 rad:
        ``A^-1 (1, ..., 1)`` (``dq1`` alone for the default map; round-off set to 0).

        A turn of the instrument's axes, or of the base, is this direction.
        """
        turn = np.linalg.solve(self.angle_map, np.ones(self.n_links))
        return np.where(np.abs(turn) > 1e-9, turn, 0.0)

    @property
    def rotation_direction(self) -> np.ndarray:
        """The user direction ``(p,)`` a base rotation cannot be told from (zeros without one).

        ``phi0 = 1`` with ``dq = -A^-1 (1, ..., 1)``: every link vector keeps its
        angle.  Which joint offsets it involves follows from the joint map.
        """
        d = np.zeros(self.n_params)
        if self.base_rotation:
            k = self.n_links
            d[k : 2 * k] = -self.turn_offsets
            d[-1] = 1.0
        return d

    @property
    def rotation_partner(self) -> str:
        """The joint offset a base rotation replaces by default: the first on its direction."""
        if not self.base_rotation:
            return ""
        k = self.n_links
        d = self.rotation_direction[k : 2 * k]
        first = int(np.flatnonzero(np.abs(d) > 1e-12)[0])
        return self.param_names[k + first]

    def params_from_display(
        self,
        dl_mm: ArrayLike,
        dq_deg: ArrayLike,
        base_mm: ArrayLike | None = None,
        rotation_deg: float = 0.0,
    ) -> np.ndarray:
        """Pack user deviations given in mm and degrees into an internal vector ``(p,)``.

        ``dl_mm`` and ``dq_deg`` have one value per link vector (``K``) or per
        joint (``n``; the last one then serves every target).

        Examples
        --------
        >>> arm = PlanarGeometry([1.0, 1.0])
        >>> arm.params_from_display([0.5, 0.0], [180.0, 0.0]).round(6).tolist()
        [0.5, 0.0, 3.141593, 0.0]
        """
        k, n = self.n_links, self.n_joints

        def per_link(values: ArrayLike) -> np.ndarray:
            v = np.atleast_1d(np.asarray(values, dtype=float))
            if v.size == n and k != n:
                v = np.concatenate([v[:-1], np.full(self.n_target_links, v[-1])])
            return np.broadcast_to(v, (k,))

        parts = [per_link(dl_mm), np.radians(per_link(dq_deg))]
        if self.base_offset:
            parts.append(np.zeros(2) if base_mm is None else np.broadcast_to(base_mm, (2,)))
        elif base_mm is not None and np.any(np.asarray(base_mm) != 0):
            raise ValueError("a base offset was given but the arm has base_offset = False")
        if self.base_rotation:
            parts.append(np.array([np.radians(rotation_deg)]))
        elif rotation_deg:
            raise ValueError("a base rotation was given but the arm has base_rotation = False")
        return np.concatenate(parts).astype(float)

    def link_angles(self, q: np.ndarray) -> np.ndarray:
        """Absolute link angles ``theta = M q`` ``(..., n)`` of joint readings ``q`` (rad)."""
        if self._default_map:
            return np.cumsum(q, axis=-1)  # the same numbers as the paper's sums, bit for bit
        return (np.asarray(q, dtype=float) + self.joint_offsets) @ self.joint_map.T

    @property
    def _default_map(self) -> bool:
        return self._default_joint_map and not np.any(self.joint_offsets)

    def target_index(self, labels: Sequence[str]) -> np.ndarray:
        """Index ``(m,)`` into :attr:`targets` of every row's target label."""
        index = {t.label: i for i, t in enumerate(self.targets)}
        unknown = [lb for lb in labels if lb not in index]
        if unknown:
            raise ValueError(
                f"unknown target {unknown[0]!r}; the targets of {self.name} are "
                f"{', '.join(index) or '(none)'}"
            )
        return np.array([index[lb] for lb in labels], dtype=int)


def _check_last_column(mapping: np.ndarray, *, several_targets: bool) -> None:
    """Refuse a joint map that turns a target's own last link by a joint before the last
    (every target has its own last link vector, turned by the last joint alone)."""
    n = mapping.shape[0]
    if several_targets and n > 1 and np.any(mapping[: n - 1, n - 1] != 0):
        raise ValueError(
            "with several targets the last joint may turn only the last link: "
            "joint_map's last column must be 0 above its last row"
        )


def _check_targets(targets: tuple[Target, ...]) -> None:
    labels = [t.label for t in targets]
    if len(set(labels)) != len(labels):
        raise ValueError(f"target labels must be distinct, got {labels}")
    for t in targets:
        if not t.label or any(c in t.label for c in ", @\t\n\"'"):
            raise ValueError(
                f"target label {t.label!r} must be non-empty, without spaces, commas, quotes or @"
            )
        if not (np.isfinite(t.length) and t.length > 0 and np.isfinite(t.angle)):
            raise ValueError(f"target {t.label}: length must be positive and angle finite")


def link_angles(q: np.ndarray) -> np.ndarray:
    """Absolute link orientations ``theta_i = q_1 + ... + q_i`` for ``q`` ``(..., n)`` (rad).

    The default joint map; :meth:`PlanarGeometry.link_angles` applies an arm's own.
    """
    return np.cumsum(q, axis=-1)


def paper_from_user_matrix(n: int, *, base_offset: bool = False) -> np.ndarray:
    """Matrix ``M`` ``(p, p)`` with ``paper = M @ user`` for deviation vectors.

    ``dtheta = T dq`` with ``T`` the lower-triangular matrix of ones; ``dl`` and
    the base are copied.  Jacobians transform as ``J_user = J_paper @ M`` and
    covariances as ``cov_user = M^-1 cov_paper M^-T``.  :func:`paper_from_user`
    is the same for any arm (joint map, targets, base rotation).

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


def paper_from_user(arm: PlanarGeometry) -> np.ndarray:
    """``P`` ``(2K [+2], p)``: link-vector deviations ``(dtheta, dl, [x0, y0]) = P user``.

    ``dtheta = A dq + phi0`` (:attr:`PlanarGeometry.angle_map`; ``phi0`` turns every
    link vector), ``dl`` and the base are copied.  Square and invertible unless
    the arm has a base rotation (one more user parameter than link coordinates:
    :attr:`PlanarGeometry.rotation_direction` spans its null space).

    Examples
    --------
    >>> arm = PlanarGeometry([2.0, 1.0], joint_map=[[1, 0], [0, 1]])   # absolute link angles
    >>> paper_from_user(arm).astype(int).tolist()
    [[0, 0, 1, 0], [0, 0, 0, 1], [1, 0, 0, 0], [0, 1, 0, 0]]
    """
    k = arm.n_links
    p = np.zeros((arm.n_paper, arm.n_params))
    p[:k, k : 2 * k] = arm.angle_map
    p[k : 2 * k, :k] = np.eye(k)
    if arm.base_offset:
        p[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = np.eye(2)
    if arm.base_rotation:
        p[:k, -1] = 1.0
    return p


def split_params(arm: PlanarGeometry, params: np.ndarray | None):
    """User ``params (..., p)`` as ``dl (..., K)``, ``dtheta (..., K)``, ``base (..., 2)``.

    ``dtheta`` are the link vectors' angle deviations (joint map, targets and base
    rotation applied); ``base`` is 0 without a base offset.
    """
    k = arm.n_links
    if params is None:
        return np.zeros(k), np.zeros(k), np.zeros(2)
    params = np.asarray(params, dtype=float)
    if params.shape[-1] != arm.n_params:
        raise ValueError(
            f"params must have shape (..., {arm.n_params}) for {arm.param_names}, "
            f"got {params.shape}"
        )
    if arm.standard_map:
        dtheta = np.cumsum(params[..., k : 2 * k], axis=-1)
    else:
        dtheta = params[..., k : 2 * k] @ arm.angle_map.T
    if arm.base_rotation:
        dtheta = dtheta + params[..., -1:]
    if arm.base_offset:
        base = params[..., 2 * k : 2 * k + 2]
    else:
        base = np.zeros((*params.shape[:-1], 2))
    return params[..., :k], dtheta, base
