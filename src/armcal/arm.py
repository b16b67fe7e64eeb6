"""The planar n-link arm: geometry, parameters, forward kinematics and Jacobians.

The model is paper eq. (1) with an optional base pose::

    p = (x0, y0) + sum_k (L_k + dl_k) * exp(1j * (theta_a(k) + alpha_k + dtheta_k))
    theta    = M q                      (link angles from the joint readings)
    dtheta   = A dq + phi0              (link-vector angle deviations)

For the paper's arm ``M`` is the lower-triangular matrix of ones
(``theta_i = q_1 + ... + q_i``), there is one link vector per joint
(``L_k = l_k``, ``alpha_k = 0``, ``A = M``) and no base rotation.  A
controller's joint convention gives another ``M`` (:attr:`PlanarArm.joint_map`:
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
identified; with :attr:`PlanarArm.base_rotation` one joint-offset direction is
held instead (:attr:`PlanarArm.rotation_partner`).

All functions are batched on leading axes: joint angles ``q`` of shape
``(m, n)`` give positions ``(m, 2)`` and Jacobians ``(m, 2, p)``.  An arm with
several targets needs the ``target`` of every row.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
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
    "Target",
    "check_target",
    "forward_kinematics",
    "jacobian",
    "joint_jacobian",
    "link_angles",
    "link_phasors",
    "link_units",
    "link_vectors",
    "paper_from_user",
    "paper_from_user_matrix",
    "split_params",
    "standard_joint_map",
    "tool_angles",
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


#: Constructor arguments that decide the parameter names.
_STRUCTURE = frozenset({"link_lengths", "base_offset", "targets", "base_rotation"})


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
    >>> arm = PlanarArm([260.0, 180.0])
    >>> arm.n_joints, arm.n_params, arm.param_names
    (2, 4, ('dl1', 'dl2', 'dq1', 'dq2'))
    >>> nest = PlanarArm([260.0, 180.0], targets=[Target("A", 180.0), Target("B", 150.0, 0.3)])
    >>> nest.param_names
    ('dl1', 'dl2@A', 'dl2@B', 'dq1', 'dq2@A', 'dq2@B')
    >>> PlanarArm([260.0, 180.0], base_offset=True, base_rotation=True).fixed
    ('dq1',)
    """

    link_lengths: np.ndarray
    joint_limits: np.ndarray
    base_offset: bool
    name: str
    noise: NoiseModel | None
    region: Region | None
    fixed: tuple[str, ...]
    joint_map: np.ndarray
    targets: tuple[Target, ...]
    base_rotation: bool
    joint_offsets: np.ndarray
    _default_joint_map: bool = field(repr=False)

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
        mapping = standard_joint_map(n) if joint_map is None else np.array(joint_map, dtype=float)
        _check_joint_map(mapping, n, several_targets=len(targets) > 1)
        targets = tuple(targets)
        _check_targets(targets)
        object.__setattr__(self, "link_lengths", lengths)
        object.__setattr__(self, "joint_limits", _readonly(limits))
        object.__setattr__(self, "base_offset", bool(base_offset))
        object.__setattr__(self, "name", str(name))
        object.__setattr__(self, "noise", noise)
        object.__setattr__(self, "region", region)
        object.__setattr__(self, "joint_map", _readonly(mapping))
        object.__setattr__(self, "targets", targets)
        object.__setattr__(self, "base_rotation", bool(base_rotation))
        default = bool(np.array_equal(mapping, standard_joint_map(n)))
        # Derived once: the fast paths test these on every kinematics call.
        object.__setattr__(self, "_default_joint_map", default)
        names = self.param_names
        unknown = [f for f in fixed if f not in names]
        if unknown:
            raise ValueError(
                f"unknown parameter {unknown[0]!r} to fix; the parameters of this arm are "
                f"{', '.join(names)}"
            )
        offsets = np.zeros(n) if joint_offsets is None else np.array(joint_offsets, dtype=float)
        if offsets.shape != (n,) or not np.all(np.isfinite(offsets)):
            raise ValueError(f"joint_offsets must be {n} finite angles in rad, got {offsets}")
        object.__setattr__(self, "joint_offsets", _readonly(offsets))
        held = set(fixed)
        if self.base_rotation and not any(
            abs(self.rotation_direction[names.index(f)]) > 1e-12 for f in held
        ):
            held.add(self.rotation_partner)
        if len(held) == len(names):
            raise ValueError("every parameter is fixed: leave at least one free to identify")
        object.__setattr__(self, "fixed", tuple(nm for nm in names if nm in held))

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
            names = PlanarArm(**{**kwargs, "fixed": ()}).param_names
            kwargs["fixed"] = tuple(f for f in carried if f in names)
        return PlanarArm(**kwargs)

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
    def standard_map(self) -> bool:
        """The paper's structure: the default joint map, one target, no base rotation."""
        return not self.targets and not self.base_rotation and self._default_joint_map

    @property
    def paper_structure(self) -> bool:
        """:attr:`standard_map` with no nominal joint offsets: link angles are ``cumsum(q)``."""
        return self.standard_map and self._default_map

    @property
    def complete(self) -> bool:
        """Whether the free parameters map one to one onto the link vectors and the base.

        Then the model is linear in the link phasors over exactly the free
        parameters (the closed form applies): every parameter free, or with a
        base rotation, exactly the one joint offset that it replaces held.
        """
        if self.base_rotation:
            return len(self.fixed) == 1 and self.fixed[0] in self._rotation_names()
        return not self.fixed

    @property
    def standard(self) -> bool:
        """Linear in the link phasors over the free parameters and isotropic iid noise.

        The paper's model up to a constant reparametrization (joint map, targets,
        base rotation): no weights, and the closed form is exact.
        """
        return self.complete and (self.noise is None or self.noise.isotropic_iid)

    @property
    def n_joints(self) -> int:
        """Number of joints ``n``."""
        return int(self.link_lengths.size)

    @property
    def n_target_links(self) -> int:
        """Number of last links: one per target, at least one."""
        return max(1, len(self.targets))

    @property
    def n_links(self) -> int:
        """Number of link vectors ``K = n - 1 + max(1, len(targets))``."""
        return self.n_joints - 1 + self.n_target_links

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

    def _rotation_names(self) -> tuple[str, ...]:
        d = self.rotation_direction
        return tuple(nm for nm, c in zip(self.param_names, d, strict=True) if abs(c) > 1e-12)

    @property
    def rotation_direction(self) -> np.ndarray:
        """The user direction ``(p,)`` a base rotation cannot be told from (zeros without one).

        ``phi0 = 1`` with ``dq = -A^-1 (1, ..., 1)``: every link vector keeps its
        angle.  Which joint offsets it involves follows from the joint map.
        """
        d = np.zeros(self.n_params)
        if self.base_rotation:
            k = self.n_links
            d[k : 2 * k] = -np.linalg.solve(self.angle_map, np.ones(k))
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
        >>> arm = PlanarArm([1.0, 1.0])
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

    def within_limits(self, q: np.ndarray, *, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask ``(m, n)`` of joint angles ``q`` (rad) inside the joint limits."""
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        return (q >= lo - tol) & (q <= hi + tol)

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


def _check_joint_map(mapping: np.ndarray, n: int, *, several_targets: bool) -> None:
    if mapping.shape != (n, n):
        raise ValueError(f"joint_map must have shape ({n}, {n}), got {mapping.shape}")
    if not np.all(np.isfinite(mapping)):
        raise ValueError("joint_map must be finite")
    s = np.linalg.svd(mapping, compute_uv=False)
    if s[-1] <= 1e-9 * s[0]:
        raise ValueError(
            "joint_map must be invertible: every link angle needs its own joint reading "
            "(the default has ones in row i, columns 1..i)"
        )
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
    """Absolute link orientations ``theta_i = q_1 + ... + q_i`` for ``q`` ``(..., n)`` (rad).

    The default joint map; :meth:`PlanarArm.link_angles` applies an arm's own.
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


def paper_from_user(arm: PlanarArm) -> np.ndarray:
    """``P`` ``(2K [+2], p)``: link-vector deviations ``(dtheta, dl, [x0, y0]) = P user``.

    ``dtheta = A dq + phi0`` (:attr:`PlanarArm.angle_map`; ``phi0`` turns every
    link vector), ``dl`` and the base are copied.  Square and invertible unless
    the arm has a base rotation (one more user parameter than link coordinates:
    :attr:`PlanarArm.rotation_direction` spans its null space).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0], joint_map=[[1, 0], [0, 1]])   # absolute link angles
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


def split_params(arm: PlanarArm, params: np.ndarray | None):
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


def _check_q(arm: PlanarArm, q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim < 1 or q.shape[-1] != arm.n_joints:
        raise ValueError(f"q must have shape (m, {arm.n_joints}) in rad, got {q.shape}")
    return q


def check_target(arm: PlanarArm, q: np.ndarray, target: ArrayLike | None) -> np.ndarray | None:
    """The rows' target indices ``(m,)`` (None: every row measures the only target).

    Raises ValueError for an arm with several targets and no ``target``, or
    indices out of range.
    """
    if target is None:
        if arm.n_target_links > 1:
            raise ValueError(
                f"{arm.name} has {arm.n_target_links} targets: give the target of every row"
            )
        return None
    index = np.asarray(target)
    m = np.shape(q)[-2] if np.ndim(q) >= 2 else 1
    if index.shape != (m,) or not np.issubdtype(index.dtype, np.integer):
        raise ValueError(f"target must be an integer array of shape ({m},), got {index.shape}")
    if index.size and (index.min() < 0 or index.max() >= arm.n_target_links):
        raise ValueError(f"target indices must lie in 0..{arm.n_target_links - 1}")
    return index if arm.n_target_links > 1 else None


def link_units(arm: PlanarArm, q: np.ndarray, target: ArrayLike | None = None) -> np.ndarray:
    """Unit phasors ``(..., m, K)`` of every link vector's nominal direction, 0 where unused.

    ``exp(i (theta_a(k) + alpha_k))`` for link vector ``k`` turning with link
    angle ``a(k)`` (:attr:`PlanarArm.link_joint`) at nominal direction
    ``alpha_k`` (:attr:`PlanarArm.link_angle0`); a target's last link is 0 in the
    rows of the other targets.  The tip is ``base + sum_k z_k u_k`` with the
    link phasors ``z_k`` of :func:`link_phasors`.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0], targets=[Target("A", 1.0), Target("B", 1.0, np.pi / 2)])
    >>> link_units(arm, np.zeros((2, 2)), target=np.array([0, 1])).round(12).tolist()
    [[(1+0j), (1+0j), 0j], [(1+0j), 0j, 1j]]
    """
    q = _check_q(arm, q)
    return _tip_terms(arm, q, None, target)[1]


def link_phasors(arm: PlanarArm, params: np.ndarray) -> np.ndarray:
    """The deviated link vectors and base as complex numbers ``(..., K + 1)``.

    ``z_k = (L_k + dl_k) exp(i dtheta_k)`` for every link vector (nominal length
    ``L_k``, :attr:`PlanarArm.link_nominal`), then the base ``x0 + i y0`` (0
    without a base offset): the tip is ``base + sum_k z_k u_k`` with the unit
    phasors ``u_k`` of :func:`link_units`, linear in these numbers.

    Examples
    --------
    >>> z = link_phasors(PlanarArm([2.0, 1.0]), np.array([0.5, 0.0, np.pi / 2, 0.0]))
    >>> z.round(12).tolist()
    [2.5j, 1j, 0j]
    """
    dl, dtheta, base = split_params(arm, params)
    z = (arm.link_nominal + dl) * np.exp(1j * dtheta)
    return np.concatenate([z, (base[..., 0] + 1j * base[..., 1])[..., None]], axis=-1)


def _tip_terms(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None,
    target,
    deflection: np.ndarray | None = None,
):
    """``z_k u_k`` ``(..., m, K)``, ``exp(i dtheta_k) u_k`` ``(..., m, K)`` and the base.

    ``deflection`` ``(..., m, n)``: joint deflections (rad, relative: joint ``j``
    turns every link from ``j`` on), e.g. under load (:mod:`armcal.elastostatic`).
    """
    index = check_target(arm, q, target)
    dl, dtheta, base = split_params(arm, params)
    theta = arm.link_angles(q)[..., arm.link_joint] + arm.link_angle0
    if deflection is not None:
        theta = theta + np.cumsum(deflection, axis=-1)[..., arm.link_joint]
    turn = np.exp(1j * (theta + dtheta[..., None, :]))
    if index is not None:
        turn[..., arm.n_joints - 1 :] *= index[:, None] == np.arange(arm.n_target_links)
    lengths = (arm.link_nominal + dl)[..., None, :]
    return lengths * turn, turn, base


def link_vectors(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """Every link vector of every row as a complex number ``(..., m, K)`` (mm).

    The tip is the base plus their sum (a target's last link is 0 in the rows
    of the other targets); joint ``j + 1`` sits at the base plus the sum of the
    first ``j``.  Arguments as for :func:`forward_kinematics`.

    Examples
    --------
    >>> link_vectors(PlanarArm([2.0, 1.0]), np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[(2+0j), 1j]]
    """
    q = _check_q(arm, q)
    return _tip_terms(arm, q, params, target, deflection)[0]


def forward_kinematics(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """End-effector positions for joint angles ``q``.

    Parameters
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        Commanded joint angles in rad.
    params : ndarray, shape (p,) or (..., p), optional
        User deviations ``[dl (mm), dq (rad), (x0, y0) (mm), (phi0) (rad)]``;
        nominal when omitted.  Leading axes broadcast, giving positions of
        shape ``(..., m, 2)``.
    target : ndarray of int, shape (m,), optional
        Index into ``arm.targets`` of the target measured in every row; needed
        when the arm has several targets.
    deflection : ndarray, shape (m, n) or (..., m, n), optional
        Joint deflections in rad (relative angles, e.g. under gravity:
        :mod:`armcal.elastostatic`), added to the real joint angles.

    Returns
    -------
    ndarray, shape (m, 2) or (..., m, 2)
        ``(x, y)`` in mm (paper eq. 1, with the arm's joint map).

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> forward_kinematics(arm, np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[2.0, 1.0]]
    >>> horizon = PlanarArm([2.0, 1.0], joint_map=[[1, 0], [0, 1]])  # q2 from the horizon
    >>> forward_kinematics(horizon, np.array([[0.0, np.pi / 2]])).round(12).tolist()
    [[2.0, 1.0]]
    """
    q = _check_q(arm, q)
    terms, _, base = _tip_terms(arm, q, params, target, deflection)
    tip = np.sum(terms, axis=-1)
    return np.stack([tip.real, tip.imag], axis=-1) + base[..., None, :]


def jacobian(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    parametrization: Parametrization = "user",
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
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
        Columns ``[dl, dq, (x0, y0), (phi0)]`` or the paper's ``[dtheta, dl, (x0, y0)]``.
    target : ndarray of int, shape (m,), optional
        Every row's target (see :func:`forward_kinematics`).
    deflection : ndarray, shape (m, n) or (..., m, n), optional
        Joint deflections in rad at which to linearize (see :func:`forward_kinematics`).

    Returns
    -------
    ndarray, shape (m, 2, p) or (..., m, 2, p)
        ``d(x, y) / d(params)``: mm per mm for lengths and base, mm per rad for angles.

    Notes
    -----
    With ``L_k = l_k + dl_k`` and ``phi_k = theta_k + dtheta_k`` (paper eq. 7-8,
    evaluated at the current deviations)::

        dp/ddtheta_k = L_k (-sin phi_k, cos phi_k),  dp/ddl_k = (cos phi_k, sin phi_k)

    and ``dp/ddq_j = sum_k A_kj dp/ddtheta_k`` (``A`` the angle map; for the
    default joint map the sum over ``k >= j``), ``dp/dphi0 = sum_k dp/ddtheta_k``.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> (jacobian(arm, np.zeros((1, 2)), parametrization="paper")[0] + 0.0).tolist()
    [[0.0, 0.0, 1.0, 1.0], [2.0, 1.0, 0.0, 0.0]]
    """
    q = _check_q(arm, q)
    terms, turn, _ = _tip_terms(arm, q, params, target, deflection)
    d_theta = 1j * terms  # complex d(tip)/d(dtheta_k), shape (..., m, K)
    if parametrization == "user":
        if arm.standard_map:
            # d/d dq_j = sum over k >= j of d/d dtheta_k: reverse cumulative sum.
            d_q = np.cumsum(d_theta[..., ::-1], axis=-1)[..., ::-1]
        else:
            d_q = d_theta @ arm.angle_map
        cols = [turn, d_q]
    elif parametrization == "paper":
        cols = [d_theta, turn]
    else:
        raise ValueError(f"parametrization must be 'user' or 'paper', got {parametrization!r}")
    if arm.base_offset:
        cols.append(np.broadcast_to(np.array([1.0, 1j]), (*turn.shape[:-1], 2)))
    if arm.base_rotation and parametrization == "user":
        cols.append(np.sum(d_theta, axis=-1, keepdims=True))
    jc = np.concatenate(cols, axis=-1)
    return np.stack([jc.real, jc.imag], axis=-2)


def joint_jacobian(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
    deflection: np.ndarray | None = None,
) -> np.ndarray:
    """``d(x, y) / dq`` ``(..., m, 2, n)``: how the tip moves with the joint readings (mm/rad).

    ``theta = M q`` turns link vector ``k`` by ``M[a(k), j]`` per unit of ``q_j``.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> (joint_jacobian(arm, np.zeros((1, 2)))[0] + 0.0).tolist()
    [[0.0, 0.0], [3.0, 1.0]]
    """
    q = _check_q(arm, q)
    terms, _, _ = _tip_terms(arm, q, params, target, deflection)
    jc = (1j * terms) @ arm.joint_map[arm.link_joint]
    return np.stack([jc.real, jc.imag], axis=-2)


def tool_angles(
    arm: PlanarArm,
    q: np.ndarray,
    params: np.ndarray | None = None,
    *,
    target: ArrayLike | None = None,
) -> np.ndarray:
    """Direction ``(..., m)`` of every row's last link vector (the tool's orientation), rad.

    ``theta_n + alpha_t + dtheta_(n, t)``: the angle of the last link vector of
    the row's target, with the deviations ``params`` (nominal when omitted).
    """
    q = _check_q(arm, q)
    index = check_target(arm, q, target)
    _, dtheta, _ = split_params(arm, params)
    k0 = arm.n_joints - 1
    last = k0 + (0 if index is None else index)
    theta_n = arm.link_angles(q)[..., -1]
    return theta_n + arm.link_angle0[last] + np.take(dtheta, last, axis=-1)
