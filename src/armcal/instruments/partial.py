"""Partial coordinates: an instrument that reads some of the tool's coordinates and turns.

A dial indicator, a laser displacement sensor, a constraint rig or a CMM with a
coordinate missing reads the tool point ``p`` (base frame) along some of the
axes of its own frame: ``y_k = e_k . R^T (p - t)`` for the axes ``k`` it reads
(``reads``, a subset of x, y, z), where ``R``, ``t`` are its orientation and
origin.  An instrument that reads the tool's orientation too (a 6-DoF tracker
with a component missing, an inclinometer beside a dial) reads components of the
rotation vector of the tool's orientation in its frame, ``phi = log(R^T R_tip
R_tool)`` (axis times angle, PRODUCT.md's ``rx_deg, ry_deg, rz_deg``), with
``R_tool`` the tool's axes in the tip frame.  A row of a measurement file gives
any of them (its ``x_mm ... rz_deg`` cells, empty where it did not read one);
each is a feature of the instrument (:attr:`Coordinates.labels`) and one number
of its own, with the sigma of its component.

**Parameters.**  Small moves from where the user says the instrument roughly
is, ``(R0, t0)``: ``R = R0 E_a E_b E_c``, three turns about the instrument's own
axes (``instrument.rx``, ``.ry``, ``.rz``, rad), and ``t = t0 + R d`` with ``d``
its shift along its own axes (``instrument.x``, ``.y``, ``.z``, mm), so that
``y_k = e_k . R^T (p - t0) - d_k``.  An instrument that reads turns adds the
tool's: ``R_tool = T0 E_a E_b E_c`` from where the user says the tool's axes are
(``tool_rpy_deg``), named after the tool point (``tool.rx``, ...: a target's
orientation, as a 6-DoF probe's).  The turns are taken in the order x, y, z,
except for an instrument of one axis, whose own turn is taken last (z: x, y, z;
x: y, z, x; y: z, x, y), so that ``R e_k`` does not depend on it at all.

**What partial coordinates cannot see.**  A shift of the whole arm along an
axis the instrument does not read changes no reading, nor any turn: ``d_j`` of
an unread axis is held (:attr:`Coordinates.held`).  An instrument whose readings
are all about one axis ``k`` (its coordinate, its turn, or both) cannot see a
turn about it: of the instrument where it reads no turn (``R e_k`` above), and
of the instrument and the tool together where it does (``Q^T phi`` has the same
``k`` component for ``Q`` a turn about ``e_k``, and ``R Q``, ``R_tool Q`` turn
``phi`` to ``Q^T phi``); the tool's turn about ``k`` is held.  With two axes or
more it sees the arm's whole pose, as a tracker does.

**Turns near a half turn.**  A rotation vector jumps at half a turn, where its
axis flips; a plan keeps the tool within :attr:`Coordinates.max_turn_deg` of the
instrument's axes (:meth:`Coordinates.slack`), away from the jump.

An instrument that reads turns reads the tool's *frame* (:attr:`Coordinates.frame`):
its "points" are the tool point and the tip's rotation ``(..., m, 12)``, and its
derivatives are by the point and by a small turn ``w`` of the tip (``R_tip ->
exp([w]) R_tip``, base frame), ``(..., m, 1, 6)``; a turn moves the rotation vector
by ``J_l(phi)^-1 R^T w`` (:func:`~armcal.models.spatial.chain.left_jacobian_inverse`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from ..models.spatial.chain import left_jacobian_inverse, rotation_vector, rpy_matrix
from ..noise import NoiseModel
from .base import (
    Defaults,
    Instrument,
    feature_index,
    same_features,
    turned_frame,
    turns_between,
)

__all__ = ["AXES", "COMPONENTS", "TURNS", "Coordinates"]

#: The axes a partial instrument may read, in its frame's order.
AXES = ("x", "y", "z")
#: The components of the tool's turn it may read: the rotation vector's, in its frame.
TURNS = ("rx", "ry", "rz")
#: Everything it may read, in order.
COMPONENTS = AXES + TURNS

#: A plan's largest turn of the tool from the instrument's axes, by default (deg): a
#: sixth of a turn from the rotation vector's jump at a half turn.
MAX_TURN_DEG = 150.0


@dataclass(frozen=True, eq=False)
class Coordinates(Defaults):
    """Partial coordinates (module notes).

    Attributes
    ----------
    reads : tuple of str
        The components the instrument reads, in the order x, y, z, rx, ry, rz (a subset).
    xyz_mm : ndarray, shape (3,)
        Where the user says the instrument's origin roughly is (base frame, mm).
    rpy_deg : ndarray, shape (3,)
        Its orientation, roll, pitch and yaw as in URDF (``Rz Ry Rx``), degrees.
    tool_rpy_deg : ndarray, shape (3,)
        Where the tool's axes roughly are in the tip frame (roll, pitch, yaw, degrees),
        for an instrument that reads turns.
    max_turn_deg : float
        The largest turn of the tool from the instrument's axes a plan keeps to (deg).
    tool : str
        The tool point's label (``[targets]``), which names the tool's turns.
    """

    reads: tuple[str, ...]
    xyz_mm: np.ndarray
    rpy_deg: np.ndarray
    tool_rpy_deg: np.ndarray = field(default_factory=lambda: np.zeros(3))
    max_turn_deg: float = MAX_TURN_DEG
    tool: str = "tool"

    def __post_init__(self) -> None:
        reads = tuple(self.reads)
        if not reads or len(set(reads)) != len(reads) or not set(reads) <= set(COMPONENTS):
            raise ValueError("reads must name some of x, y, z, rx, ry, rz, each once")
        object.__setattr__(self, "reads", tuple(a for a in COMPONENTS if a in reads))
        for name in ("xyz_mm", "rpy_deg", "tool_rpy_deg"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (3,) or not np.all(np.isfinite(value)):
                raise ValueError(f"{name} must be 3 finite numbers")
            object.__setattr__(self, name, value)
        if not 0.0 < float(self.max_turn_deg) < 180.0:
            raise ValueError("max_turn_deg must lie above 0 and below 180")

    @property
    def kind(self) -> str:
        return "partial"

    @property
    def labels(self) -> tuple[str, ...]:
        """The components it reads: every row's reading of one is a feature."""
        return self.reads

    @property
    def dim(self) -> int:
        return 1

    @cached_property
    def _components(self) -> np.ndarray:
        """Every feature's component: 0, 1, 2 for x, y, z, 3, 4, 5 for its turns."""
        return np.array([COMPONENTS.index(a) for a in self.reads])

    @property
    def turns(self) -> bool:
        """Whether it reads the tool's turns (then it reads the tool's frame)."""
        return bool(np.any(self._components >= 3))

    @property
    def frame(self) -> bool:
        return self.turns

    @property
    def turn_features(self) -> tuple[int, ...]:
        """The features whose readings are angles (rad): its turns'."""
        return tuple(int(k) for k in np.flatnonzero(self._components >= 3))

    @property
    def has_slack(self) -> bool:
        """Whether a plan keeps within its turn's range: where it reads turns."""
        return self.turns

    def for_tool(self, label: str) -> Coordinates:
        """The same instrument on the tool point ``label``, which names its tool's turns."""
        return replace(self, tool=label) if self.turns else self

    @property
    def param_names(self) -> tuple[str, ...]:
        mine = tuple(f"instrument.{c}" for c in COMPONENTS)
        return mine + (tuple(f"{self.tool}.{c}" for c in TURNS) if self.turns else ())

    @property
    def param_units(self) -> tuple[str, ...]:
        return ("mm",) * 3 + ("rad",) * (6 if self.turns else 3)

    @property
    def start(self) -> np.ndarray:
        return np.zeros(9 if self.turns else 6)

    @cached_property
    def _about(self) -> tuple[int, ...]:
        """The axes its readings are about (a coordinate's and a turn's alike)."""
        return tuple(sorted({int(c) % 3 for c in self._components}))

    @property
    def held(self) -> tuple[str, ...]:
        """The shifts along the axes whose coordinate it does not read; for readings all
        about one axis, the turn about it (the tool's where it reads turns)."""
        out = [f"instrument.{a}" for a in AXES if a not in self.reads]
        if len(self._about) == 1:
            axis = AXES[self._about[0]]
            out.append(f"{self.tool}.r{axis}" if self.turns else f"instrument.r{axis}")
        return tuple(out)

    @property
    def unseen(self) -> str:
        positions = [a for a in AXES if a in self.reads]
        turned = [a for a in TURNS if a in self.reads]
        if len(positions) == 3:
            words = (
                "reading x, y and z it sees the arm as a tracker does: the arm's pose in its "
                "frame is the instrument's own placement"
            )
        else:
            read = " and ".join(positions) if positions else "no coordinate"
            missing = " or ".join(a for a in AXES if a not in self.reads)
            plural = "es" if len(positions) < 2 else "is"
            words = (
                f"reading {'only ' if positions else ''}{read}, it cannot see the arm move "
                f"along the instrument's {missing} ax{plural}"
            )
        if len(self._about) == 1:
            axis = AXES[self._about[0]]
            who = "the instrument and the tool turned together" if self.turns else "turn"
            words += f", nor {who} about its {axis} axis"
        if turned:
            words += f"; it reads the tool's turn ({', '.join(turned)}) too"
        return words

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        return (("instrument", self.xyz_mm),)

    @property
    def label_column(self) -> str | None:
        return None

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return tuple(f"{a}_{'deg' if a in TURNS else 'mm'}" for a in self.reads)

    @property
    def constrained(self) -> bool:
        """False: it reads the tool wherever it is."""
        return False

    @property
    def reads_every_feature(self) -> bool:
        """True: a row reads every component, one column each (empty where it did not)."""
        return True

    def feature_sigma(self, noise: NoiseModel) -> np.ndarray | None:
        """Every component's std from the robot file's ``sigma_mm = [sx, sy, sz]`` where
        they differ, and the turns' from ``orientation_sigma_deg`` (rad); None for one
        sigma of coordinates alone.  ValueError for a laser tracker's model, a covariance
        with correlations (rows of one number each have none), or turns without a
        sigma."""
        if noise.tracker is not None:
            raise ValueError(
                "a laser tracker's noise model is for 3-D points; give sigma_mm per axis "
                "[sx, sy, sz]"
            )
        cov = np.asarray(noise.covariance_mm2, dtype=float)
        if cov.shape == (1, 1) or noise.isotropic_instrument:
            if not self.turns:
                return None
            each = np.full(3, float(np.sqrt(cov[0, 0])))
        elif cov.shape != (3, 3) or np.count_nonzero(cov - np.diag(np.diagonal(cov))):
            raise ValueError(
                "partial coordinates are read one at a time: give sigma_mm as one number or "
                "one per axis [sx, sy, sz], not a covariance"
            )
        else:
            each = np.sqrt(np.diagonal(cov))
        if not self.turns:
            return each[self._components]
        if noise.orientation_sigma is None:
            raise ValueError(
                f"it reads the tool's turn ({', '.join(a for a in self.reads if a in TURNS)}): "
                "give orientation_sigma_deg, the std of a turn's component"
            )
        every = np.concatenate([each, np.full(3, float(noise.orientation_sigma))])
        return every[self._components]

    @cached_property
    def _order(self) -> tuple[int, int, int]:
        """The axes of the three turns, in order (module notes)."""
        if len(self._about) == 1:
            k = self._about[0]
            return ((k + 1) % 3, (k + 2) % 3, k)
        return (0, 1, 2)

    @cached_property
    def _frame(self) -> np.ndarray:
        """``R0`` ``(3, 3)``."""
        return rpy_matrix(np.radians(self.rpy_deg))

    @cached_property
    def _tool_frame(self) -> np.ndarray:
        """``T0`` ``(3, 3)``: the tool's axes in the tip frame where the user put them."""
        return rpy_matrix(np.radians(self.tool_rpy_deg))

    def rotation(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``R`` ``(..., 3, 3)`` at ``params`` ``(..., 6 or 9)`` and its derivatives by the
        turns about x, y and z ``(..., 3, 3, 3)`` (the turn first)."""
        return turned_frame(self._frame, np.asarray(params, dtype=float)[..., 3:6], self._order)

    def tool_rotation(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``R_tool`` (the tool's axes in the tip frame) and its derivatives by its turns."""
        turns = np.asarray(params, dtype=float)[..., 6:9]
        return turned_frame(self._tool_frame, turns, self._order)

    def params_of(self, true: Instrument) -> np.ndarray:
        """The shift and the turns that put the instrument where ``true`` is
        (:func:`~armcal.instruments.base.turns_between`), ``d = R^T (t - t0)``, and the
        tool's turns to ``true``'s tool axes."""
        same_features(self, true)
        assert isinstance(true, Coordinates)
        r = true._frame
        found = [r.T @ (true.xyz_mm - self.xyz_mm), turns_between(self._frame, r, self._order)]
        if self.turns:
            found.append(turns_between(self._tool_frame, true._tool_frame, self._order))
        return np.concatenate(found)

    def out_of_reach(self, reach_mm: float) -> str | None:
        return None

    def _rows(self, feature: np.ndarray | None, m: int) -> np.ndarray:
        """Every row's component (0 to 5 for x, y, z, rx, ry, rz)."""
        return self._components[feature_index(feature, m, self.labels)]

    def _split(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The tool points ``(..., m, 3)`` and, for one that reads turns, the tip's rotations
        ``(..., m, 3, 3)``."""
        points = np.asarray(points, dtype=float)
        if not self.turns:
            return points, None
        return points[..., :3], points[..., 3:].reshape(*points.shape[:-1], 3, 3)

    def _turn(self, tip: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, ...]:
        """``phi = log(R^T R_tip R_tool)`` ``(..., m, 3)`` and what its derivatives need."""
        r, by = self.rotation(params)
        tool, by_tool = self.tool_rotation(params)
        r_t = np.swapaxes(r, -1, -2)[..., None, :, :]
        phi = rotation_vector(r_t @ tip @ tool[..., None, :, :])
        return phi, r, by, tool, by_tool

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``e_k . R^T (p - t0) - d_k`` (mm) or ``phi_k`` (rad) ``(..., m, 1)``."""
        p, tip = self._split(points)
        c = self._rows(feature, np.shape(p)[-2])
        params = np.asarray(params, dtype=float)
        r, _ = self.rotation(params)
        axes = np.swapaxes(r, -1, -2)[..., c % 3, :]  # R e_k of every row (..., m, 3)
        value = np.sum(axes * (p - self.xyz_mm), axis=-1) - params[..., c % 3]
        if tip is not None:
            phi = self._turn(tip, params)[0]
            angle = np.take_along_axis(phi, np.broadcast_to(c % 3, phi.shape[:-1])[..., None], -1)
            value = np.where(c >= 3, angle[..., 0], value)
        return value[..., None]

    def slack(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """How far (rad) every row's tool turn lies within :attr:`max_turn_deg` ``(..., m,
        1)``; None for an instrument that reads no turn."""
        _, tip = self._split(points)
        if tip is None:
            return None
        phi = self._turn(tip, np.asarray(params, dtype=float))[0]
        return (np.radians(self.max_turn_deg) - np.linalg.norm(phi, axis=-1))[..., None]

    def slack_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """By the tip's shift and turn ``(..., m, 1, 6)``: none by the shift, and ``-u^T R^T``
        by the turn, ``u`` the turn's axis (``phi^T J_l(phi)^-1 = phi^T``: a turn moves
        ``|phi|`` along its own axis alone); None for an instrument that reads no turn."""
        _, tip = self._split(points)
        if tip is None:
            return None
        params = np.asarray(params, dtype=float)
        phi, r, *_ = self._turn(tip, params)
        size = np.linalg.norm(phi, axis=-1, keepdims=True)
        axis = phi / np.where(size > 0.0, size, 1.0)  # at no turn, the slack's top: 0
        out = np.zeros((*phi.shape[:-1], 1, 6))
        out[..., 0, 3:] = -np.einsum("...mi,...ji->...mj", axis, r)  # -(R u)^T = -u^T R^T
        return out

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """0: it reads the tool wherever it is."""
        p, _ = self._split(points)
        return np.zeros((*np.shape(p)[:-1], 1))

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``R e_k`` ``(..., m, 1, 3)``; -1 at ``d_k`` and ``dR/da e_k . (p - t0)`` at the
        turns ``(..., m, 1, 6)``.  For one that reads turns, by the point and the tip's turn
        ``(..., m, 1, 6)``, a turn's row ``J_l(phi)^-1 R^T`` there, and ``J_l(phi)^-1``
        times the angular velocity of ``R^T R_tip R_tool`` at the instrument's and the
        tool's turns ``(..., m, 1, 9)`` (module notes)."""
        p, tip = self._split(points)
        params = np.asarray(params, dtype=float)
        m = np.shape(p)[-2]
        c = self._rows(feature, m)
        k = c % 3
        r, by = self.rotation(params)
        axes = np.swapaxes(r, -1, -2)[..., k, :]  # (..., m, 3)
        turned = np.moveaxis(np.swapaxes(by, -1, -2)[..., k, :], -3, -2)  # (..., m, 3, 3)
        offset = p - self.xyz_mm
        shape = np.broadcast_shapes(axes.shape[:-1], offset.shape[:-1])
        out = np.zeros((*shape, 1, len(self.start)))
        out[..., 0, 3:6] = np.einsum("...ta,...a->...t", turned, offset)
        out[..., np.arange(m), 0, k] = -1.0
        by_point = np.broadcast_to(axes, (*shape, 3))[..., None, :]
        if tip is None:
            return by_point, out
        phi, r, by, tool, by_tool = self._turn(tip, params)
        inverse = left_jacobian_inverse(phi)  # (..., m, 3, 3)
        pick = np.broadcast_to(k[:, None, None], (*inverse.shape[:-2], 1, 3))
        rows = np.take_along_axis(inverse, pick, axis=-2)[..., 0, :]  # e_k^T J_l^-1 (..., m, 3)
        r_t = np.swapaxes(r, -1, -2)
        # a turn w of the tip: R^T w; of the instrument: vee(dR^T R); of the tool: R^T
        # R_tip vee(dR_tool R_tool^T)
        spin = _vee(np.swapaxes(by, -1, -2) @ r[..., None, :, :])  # (..., 3 turns, 3)
        own = _vee(by_tool @ np.swapaxes(tool, -1, -2)[..., None, :, :])  # (..., 3, 3)
        carried = r_t[..., None, :, :] @ tip  # R^T R_tip (..., m, 3, 3)
        by_turn = np.einsum("...mi,...ij->...mj", rows, r_t)  # (..., m, 3)
        angular = np.einsum("...mi,...ti->...mt", rows, np.broadcast_to(spin, (*shape[:-1], 3, 3)))
        tooled = np.einsum("...mi,...mij,...tj->...mt", rows, carried, own)
        turn_row = np.zeros_like(out)
        turn_row[..., 0, 3:6] = angular
        turn_row[..., 0, 6:9] = tooled
        is_turn = (c >= 3)[:, None, None]
        frame_row = np.concatenate(
            [np.where(is_turn, 0.0, by_point), np.where(is_turn, by_turn[..., None, :], 0.0)],
            axis=-1,
        )
        return frame_row, np.where(is_turn, turn_row, out)

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """None (a reading is linear in the point) and ``dR/da e_k`` at the turns ``(...,
        m, 1, 6, 3)``; for one that reads turns, none: a design's gradient is then taken
        by central differences (:meth:`~armcal.models.instrumented.InstrumentedArm.linearize`)."""
        if self.turns:
            raise NotImplementedError("a turn's design gradient is taken by central differences")
        m = np.shape(points)[-2]
        k = self._rows(feature, m)
        _, by = self.rotation(params)
        turned = np.moveaxis(np.swapaxes(by, -1, -2)[..., k, :], -3, -2)  # (..., m, 3, 3)
        shape = np.broadcast_shapes(turned.shape[:-2], np.shape(points)[:-1])
        out = np.zeros((*shape, 1, 6, 3))
        out[..., 0, 3:, :] = turned
        return None, out


def _vee(skew: np.ndarray) -> np.ndarray:
    """The vectors ``(..., 3)`` of skew matrices ``(..., 3, 3)``."""
    return np.stack([skew[..., 2, 1], skew[..., 0, 2], skew[..., 1, 0]], axis=-1)
