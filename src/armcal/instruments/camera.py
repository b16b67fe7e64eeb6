"""A camera: the pixels of a checkerboard's corners, the camera on the tool or the board.

A pinhole camera with OpenCV's ``plumb_bob`` distortion (ROS ``camera_info``: the
camera matrix ``K`` and ``k1 k2 p1 p2 k3``) sees the corners of a board of
``rows x cols`` corners, corner ``k = i cols + j`` at ``(j s, i s, 0)`` in the
board's frame (OpenCV's object points; ``s`` the square's side).  A point ``P``
in the camera's frame (x right, y down, z along the view) is seen at

    x = P_x / P_z,  y = P_y / P_z,  r^2 = x^2 + y^2,  c = 1 + k1 r^2 + k2 r^4 + k3 r^6,
    x'' = x c + 2 p1 x y + p2 (r^2 + 2 x^2),  y'' = y c + p1 (r^2 + 2 y^2) + 2 p2 x y,
    u = f_x x'' + K_01 y'' + c_x,  v = f_y y'' + c_y   (pixels).

**Mounts.**  *Eye-in-hand*: the camera rides on the tool (its pose in the tip
frame unknown) and the board is fixed in the cell (its pose in the base frame
unknown).  *Eye-to-hand*: the camera is fixed in the cell and the board rides on
the tool.  Either way a photo's corner is ``P = R_c^T (v - t_c0) - d_c`` with ``v``
the corner in the camera's parent frame: the tip's for eye-in-hand, ``v = R^T (X -
t)`` with ``X`` the corner in the base; the base's for eye-to-hand, ``v = R Y + t``
with ``Y`` the corner in the tip frame (``R``, ``t`` the tip frame in the base).

**Parameters.**  Each of the two poses moves from where the user says it roughly
is (the robot file's), as partial coordinates' frame does
(:mod:`~armcal.instruments.partial`): ``R = R0 Rx(a) Ry(b) Rz(c)`` and a shift
along its own axes; the camera's ``camera.x, .y, .z`` (mm) and ``camera.rx, .ry,
.rz`` (rad), the board's ``board.x ... board.rz``, its corners at ``R_b (c_k +
d_b) + t_b0``.  This is hand-eye calibration and the arm's in one fit.

**What a camera cannot see.**  With the board's square known, nothing a tracker
sees: where the arm stands is the board's pose (eye-in-hand) or the camera's
(eye-to-hand), and the tool's is the camera's (or the board's).

The instrument reads the tool's *frame* (:attr:`Camera.frame`): its
"points" are ``(..., m, 12)``, the tip's origin then its rotation row by row, and
its derivatives are by the tip's shift and a small turn ``w`` of it (``R -> exp([w])
R``, base frame): ``(..., m, 2, 6)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from ..models.spatial.chain import rpy_matrix, skew
from .base import (
    Defaults,
    Instrument,
    feature_index,
    same_features,
    turned_frame,
    turns_between,
)

__all__ = ["MOUNTS", "Board", "Camera", "Intrinsics"]

#: Where the camera is: on the tool, or fixed in the cell.
MOUNTS = ("eye-in-hand", "eye-to-hand")


@dataclass(frozen=True, eq=False)
class Intrinsics:
    """A camera's ``camera_info``: ``K`` ``(3, 3)``, ``plumb_bob``'s ``k1 k2 p1 p2 k3`` and
    the image's size (pixels)."""

    matrix: np.ndarray
    distortion: np.ndarray
    width: int
    height: int

    def __post_init__(self) -> None:
        k = np.asarray(self.matrix, dtype=float)
        d = np.zeros(5)
        given = np.asarray(self.distortion, dtype=float).ravel()
        if k.shape != (3, 3) or not np.all(np.isfinite(k)):
            raise ValueError("the camera matrix must be 3 x 3 finite numbers")
        if not (k[0, 0] > 0 and k[1, 1] > 0 and k[1, 0] == 0 and np.all(k[2] == [0, 0, 1])):
            raise ValueError(
                "the camera matrix must be [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0"
            )
        if given.size > 5 or not np.all(np.isfinite(given)):
            raise ValueError("plumb_bob distortion is at most 5 finite numbers: k1 k2 p1 p2 k3")
        d[: given.size] = given
        if not (int(self.width) > 0 and int(self.height) > 0):
            raise ValueError("the image's width and height must be positive (pixels)")
        object.__setattr__(self, "matrix", k)
        object.__setattr__(self, "distortion", d)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pixels ``(..., 2)`` of camera-frame points ``(..., 3)`` (module notes of
        :mod:`~armcal.instruments.camera`) and their derivative by the point ``(..., 2,
        3)``."""
        k1, k2, p1, p2, k3 = self.distortion
        px, py, pz = points[..., 0], points[..., 1], points[..., 2]
        x, y = px / pz, py / pz
        r2 = x * x + y * y
        c = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dc = 2 * (k1 + r2 * (2 * k2 + 3 * k3 * r2))  # dc / dx = dc x, dc / dy = dc y
        xd = x * c + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * c + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        a = self.matrix
        uv = np.stack([a[0, 0] * xd + a[0, 1] * yd + a[0, 2], a[1, 1] * yd + a[1, 2]], axis=-1)
        # d(x'', y'') / d(x, y)
        dxx = c + x * dc * x + 2 * p1 * y + 6 * p2 * x
        dxy = x * dc * y + 2 * p1 * x + 2 * p2 * y
        dyx = y * dc * x + 2 * p1 * x + 2 * p2 * y
        dyy = c + y * dc * y + 6 * p1 * y + 2 * p2 * x
        inv = 1.0 / pz
        zero = np.zeros_like(pz)
        by_p = np.stack(  # d(x, y) / dP
            [np.stack([inv, zero, -x * inv], -1), np.stack([zero, inv, -y * inv], -1)], -2
        )
        distort = np.stack([np.stack([dxx, dxy], -1), np.stack([dyx, dyy], -1)], -2)
        pixels = np.array([[a[0, 0], a[0, 1]], [0.0, a[1, 1]]])
        return uv, pixels @ distort @ by_p


class _Sight(NamedTuple):
    """What a photo's corners' derivatives need, row by row (:meth:`Camera._seen`)."""

    t: np.ndarray  # the tip's origin (..., m, 3)
    rot: np.ndarray  # the tip's rotation R (..., m, 3, 3)
    cam: np.ndarray  # the camera's R_c (..., 3, 3) and its derivatives (..., 3, 3, 3)
    by_cam: np.ndarray
    brd: np.ndarray  # the board's R_b and its derivatives
    by_brd: np.ndarray
    corner: np.ndarray  # c_k + d_b in the board's frame (..., m, 3)
    y: np.ndarray  # the corner in the board's parent frame (..., m, 3)
    local: np.ndarray  # the corner in the camera's parent frame, less t_c0 (..., m, 3)


@dataclass(frozen=True)
class Board:
    """A checkerboard of ``rows x cols`` inner corners ``square_mm`` apart."""

    rows: int
    cols: int
    square_mm: float

    def __post_init__(self) -> None:
        if not (int(self.rows) >= 2 and int(self.cols) >= 2):
            raise ValueError("a board needs at least 2 x 2 corners")
        if not (np.isfinite(self.square_mm) and self.square_mm > 0):
            raise ValueError("a board's square must be a positive number of mm")

    @cached_property
    def corners(self) -> np.ndarray:
        """``(rows cols, 3)``: corner ``k = i cols + j`` at ``(j s, i s, 0)`` (mm)."""
        i, j = np.divmod(np.arange(self.rows * self.cols), self.cols)
        return np.column_stack([j, i, np.zeros_like(i)]).astype(float) * self.square_mm


@dataclass(frozen=True, eq=False)
class Camera(Defaults):
    """A camera and a board (module notes).

    Attributes
    ----------
    intrinsics : Intrinsics
    board : Board
    mount : {"eye-in-hand", "eye-to-hand"}
    camera_pose : tuple of ndarray
        Where the user says the camera roughly is, ``xyz_mm`` and ``rpy_deg`` (URDF's
        ``Rz Ry Rx``): in the tip frame (eye-in-hand) or the base frame (eye-to-hand).
    board_pose : tuple of ndarray
        Where the board roughly is: in the base frame (eye-in-hand) or the tip frame.
    margin_px : float
        How far inside the image's edges a corner must be seen for a plan's pose.
    min_depth_mm : float
        How far in front of the lens a corner must be for a plan's pose (a lens focuses
        from some distance on).
    max_tilt_deg : float
        The largest angle between the board's normal and the line of sight to a corner
        for a plan's pose: a corner seen more obliquely is found poorly, and a design
        without the limit turns the board edge-on a few centimetres from the lens.
    """

    intrinsics: Intrinsics
    board: Board
    mount: str
    camera_pose: tuple[np.ndarray, np.ndarray]
    board_pose: tuple[np.ndarray, np.ndarray]
    margin_px: float = 10.0
    min_depth_mm: float = 150.0
    max_tilt_deg: float = 60.0

    def __post_init__(self) -> None:
        if self.mount not in MOUNTS:
            raise ValueError(f"the mount must be one of {', '.join(MOUNTS)}")
        for name in ("camera_pose", "board_pose"):
            xyz, rpy = (np.asarray(v, dtype=float) for v in getattr(self, name))
            if xyz.shape != (3,) or rpy.shape != (3,) or not np.all(np.isfinite([*xyz, *rpy])):
                raise ValueError(f"{name} must be xyz_mm and rpy_deg, 3 finite numbers each")
            object.__setattr__(self, name, (xyz, rpy))

    @property
    def kind(self) -> str:
        return "camera"

    @property
    def labels(self) -> tuple[str, ...]:
        """The board's corners, ``"0"`` to ``"rows cols - 1"``."""
        return tuple(str(k) for k in range(self.board.rows * self.board.cols))

    @property
    def dim(self) -> int:
        return 2

    @property
    def unit(self) -> str:
        return "px"

    @property
    def has_slack(self) -> bool:
        """True: a photo keeps its corners near enough and the board not too oblique."""
        return True

    @property
    def tool_point(self) -> bool:
        """False: it is placed on the flange (its pose, or the board's, in the tip frame)."""
        return False

    @property
    def frame(self) -> bool:
        """True: it reads the tool's frame, not only its point (module notes)."""
        return True

    @property
    def reading_bounds(self) -> tuple[tuple[float, float], ...] | None:
        """The image: ``0 <= u <= width``, ``0 <= v <= height``."""
        return ((0.0, float(self.intrinsics.width)), (0.0, float(self.intrinsics.height)))

    @property
    def view_box(self) -> tuple[tuple[float, float], ...] | None:
        """The image less :attr:`margin_px` on every side (where :meth:`miss` is 0, the
        board in front of the lens and within its fold)."""
        (_, width), (_, height) = self.reading_bounds or ((0.0, 0.0), (0.0, 0.0))
        margin = self.margin_px
        return ((margin, width - margin), (margin, height - margin))

    @property
    def param_names(self) -> tuple[str, ...]:
        axes = ("x", "y", "z", "rx", "ry", "rz")
        return tuple(f"camera.{a}" for a in axes) + tuple(f"board.{a}" for a in axes)

    @property
    def param_units(self) -> tuple[str, ...]:
        return (("mm",) * 3 + ("rad",) * 3) * 2

    @property
    def start(self) -> np.ndarray:
        return np.zeros(12)

    @property
    def unseen(self) -> str:
        return (
            "with the board's square known a camera sees what a tracker sees: where the arm "
            "stands is the "
            + ("board's pose" if self.mount == "eye-in-hand" else "camera's pose")
            + ", and the tool is the "
            + ("camera" if self.mount == "eye-in-hand" else "board")
        )

    @property
    def label_column(self) -> str | None:
        return "corner"

    @property
    def reading_columns(self) -> tuple[str, ...]:
        return ("u_px", "v_px")

    @property
    def constrained(self) -> bool:
        """True: a pose is measured where the camera sees every corner of the board."""
        return True

    @property
    def reads_every_feature(self) -> bool:
        """True: a photo reads every corner of the board."""
        return True

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        fixed = self.board_pose if self.mount == "eye-in-hand" else self.camera_pose
        return (("board" if self.mount == "eye-in-hand" else "camera", fixed[0]),)

    def params_of(self, true: Instrument) -> np.ndarray:
        """The moves that put the camera and the board where ``true``'s are."""
        same_features(self, true)
        assert isinstance(true, Camera) and true.mount == self.mount
        out = []
        mine, theirs = (self.camera_pose, self.board_pose), (true.camera_pose, true.board_pose)
        for a, b, r0, r in zip(mine, theirs, self._frames, true._frames, strict=True):
            out += [r.T @ (b[0] - a[0]), turns_between(r0, r)]
        return np.concatenate(out)

    def out_of_reach(self, reach_mm: float) -> str | None:
        return None

    # -- the measurement equation -------------------------------------------------------------

    def _rotations(self, params: np.ndarray) -> tuple[np.ndarray, ...]:
        """``R_c``, ``dR_c / d(a, b, c)``, ``R_b``, its derivatives: ``(..., 3, 3)`` and
        ``(..., 3, 3, 3)`` (the turn first)."""
        camera = turned_frame(self._frames[0], params[..., 3:6])
        board = turned_frame(self._frames[1], params[..., 9:12])
        return (*camera, *board)

    @cached_property
    def _frames(self) -> tuple[np.ndarray, np.ndarray]:
        """Where the user placed the camera and the board: their rotations."""
        return (
            rpy_matrix(np.radians(self.camera_pose[1])),
            rpy_matrix(np.radians(self.board_pose[1])),
        )

    def _seen(
        self, tool: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, _Sight]:
        """Every row's corner in the camera's frame ``P`` and what its derivatives need."""
        m = np.shape(tool)[-2]
        k = feature_index(feature, m, self.labels)
        params = np.asarray(params, dtype=float)
        t = tool[..., :3]
        rot = tool[..., 3:].reshape(*tool.shape[:-1], 3, 3)
        cam, by_cam, brd, by_brd = self._rotations(params)
        corner = self.board.corners[k] + params[..., None, 6:9]  # c_k + d_b (..., m, 3)
        y = np.einsum("...ij,...mj->...mi", brd, corner) + self.board_pose[0]  # parent frame
        if self.mount == "eye-in-hand":
            v = np.einsum("...mji,...mj->...mi", rot, y - t)  # R^T (X - t): the tip's frame
        else:
            v = np.einsum("...mij,...mj->...mi", rot, y) + t  # R Y + t: the base's
        local = v - self.camera_pose[0]
        p = np.einsum("...ji,...mj->...mi", cam, local) - params[..., None, :3]
        return p, _Sight(t, rot, cam, by_cam, brd, by_brd, corner, y, local)

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """The corners' pixels ``(..., m, 2)``."""
        p, _ = self._seen(np.asarray(points, dtype=float), feature, params)
        return self.intrinsics.project(p)[0]

    def _normal(self, sight: _Sight) -> np.ndarray:
        """The board's normal in the camera's frame, row by row ``(..., m, 3)``."""
        rot, cam = sight.rot, sight.cam
        normal = sight.brd[..., :, 2]  # the board's normal in its parent's frame (..., 3)
        if self.mount == "eye-in-hand":  # in the base frame: into the tip's
            normal = np.einsum("...mji,...j->...mi", rot, normal)
        else:  # on the tip: into the base's
            normal = np.einsum("...mij,...j->...mi", rot, normal)
        return np.einsum("...ji,...mj->...mi", cam, normal)

    def slack(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """Every corner's depth beyond :attr:`min_depth_mm` (mm) and how far the cosine of
        its line of sight's angle with the board's normal is above that of
        :attr:`max_tilt_deg` ``(..., m, 2)``."""
        p, sight = self._seen(np.asarray(points, dtype=float), feature, params)
        seen = self._normal(sight)
        cosine = np.abs(np.sum(seen * p, axis=-1)) / np.linalg.norm(p, axis=-1)
        return np.stack(
            [p[..., 2] - self.min_depth_mm, cosine - np.cos(np.radians(self.max_tilt_deg))],
            axis=-1,
        )

    def slack_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """By the tip's shift and turn ``(..., m, 2, 6)``: the depth's is ``dP_z``; the
        cosine ``|n . P| / |P|``'s is ``sign(n . P) (P^T dn + n^T dP) / |P| - |n . P| P^T dP
        / |P|^3``, with ``dP`` the corner's (:meth:`_by_tip`) and ``dn`` the normal's: by the
        turn alone, ``R_c^T R^T [n_b]`` for a board in the base (``R^T n_b`` turns by ``-R^T
        [w] n_b``), ``-R_c^T [R n_b]`` for one on the tip (``[w] R n_b``)."""
        p, sight = self._seen(np.asarray(points, dtype=float), feature, params)
        rot = sight.rot
        by_tip = self._by_tip(sight)  # dP (..., m, 3, 6)
        cam_t = np.swapaxes(sight.cam, -1, -2)[..., None, :, :]
        normal = sight.brd[..., None, :, 2]  # (..., 1, 3)
        if self.mount == "eye-in-hand":
            by_turn = cam_t @ np.swapaxes(rot, -1, -2) @ skew(normal)
        else:
            by_turn = -cam_t @ skew(np.einsum("...mij,...mj->...mi", rot, normal))
        seen = self._normal(sight)
        dot = np.sum(seen * p, axis=-1)
        size = np.linalg.norm(p, axis=-1)
        along = np.einsum("...mi,...mij->...mj", p, by_tip)  # P^T dP (..., m, 6)
        cosine = (np.sign(dot) / size)[..., None] * np.einsum("...mi,...mij->...mj", seen, by_tip)
        cosine[..., 3:] += (np.sign(dot) / size)[..., None] * np.einsum(
            "...mi,...mij->...mj", p, by_turn
        )
        cosine -= (np.abs(dot) / size**3)[..., None] * along
        return np.stack([by_tip[..., 2, :], cosine], axis=-2)

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """How far (px) each corner lies outside the image less :attr:`margin_px`, 0 within
        it, where the lens puts it (distorted: a pincushion moves corners outward); the
        distortion's polynomial folds points far outside the view back into the image, so
        a corner is in view only where its radius still grows, ``1 + 3 k1 r^2 + 5 k2 r^4
        + 7 k3 r^6 > 0``: a corner behind the camera, or beyond the fold, misses by the
        image's size."""
        p, _ = self._seen(np.asarray(points, dtype=float), feature, params)
        depth = p[..., 2]
        x, y = p[..., 0] / depth, p[..., 1] / depth
        k1, k2, _, _, k3 = self.intrinsics.distortion
        r2 = x * x + y * y
        growing = 1 + r2 * (3 * k1 + r2 * (5 * k2 + 7 * k3 * r2)) > 0
        uv = self.intrinsics.project(p)[0]  # where the lens puts it, before the fold
        margin = self.margin_px
        high = np.array([self.intrinsics.width, self.intrinsics.height], dtype=float) - margin
        off = uv - np.clip(uv, margin, high)
        lost = ((depth <= 0.0) | ~growing)[..., None]
        return np.where(lost, float(self.intrinsics.width + self.intrinsics.height), off)

    def _by_tip(self, sight: _Sight) -> np.ndarray:
        """``dP / d(shift, turn)`` of the tip ``(..., m, 3, 6)``: ``R_c^T R^T [-I, [X - t]]``
        for a camera on the tip, ``R_c^T [I, -[R Y]]`` for one in the cell."""
        t, rot, y = sight.t, sight.rot, sight.y
        cam_t = np.swapaxes(sight.cam, -1, -2)[..., None, :, :]  # R_c^T, over the rows
        if self.mount == "eye-in-hand":
            to_p = cam_t @ np.swapaxes(rot, -1, -2)  # dP / dX
            return np.concatenate([-to_p, to_p @ skew(y - t)], axis=-1)
        by_shift = np.broadcast_to(cam_t, (*rot.shape[:-2], 3, 3))
        by_turn = -cam_t @ skew(np.einsum("...mij,...mj->...mi", rot, y))
        return np.concatenate([by_shift, by_turn], axis=-1)

    def tool_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """By the tip's shift and turn alone ``(..., m, 2, 6)``: what a pose's joint step
        needs, without the twelve parameters' columns."""
        p, sight = self._seen(np.asarray(points, dtype=float), feature, params)
        return self.intrinsics.project(p)[1] @ self._by_tip(sight)

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """By the tip's shift and turn ``(..., m, 2, 6)`` and by the parameters ``(..., m,
        2, 12)`` (module notes)."""
        p, sight = self._seen(np.asarray(points, dtype=float), feature, params)
        rot, brd = sight.rot, sight.brd
        _, by_p = self.intrinsics.project(p)  # (..., m, 2, 3)
        by_tip = by_p @ self._by_tip(sight)  # (..., m, 2, 6)
        # dP/dY: R_c^T R^T (board in the base, seen from the tip) or R_c^T R (on the tip)
        cam_t = np.swapaxes(sight.cam, -1, -2)[..., None, :, :]
        to_board = (
            by_p @ cam_t @ (np.swapaxes(rot, -1, -2) if self.mount == "eye-in-hand" else rot)
        )
        # the camera's turn k: (dR_c/da_k)^T local; the board's: dP/dY (dR_b/da_k) (c + d_b)
        by_camera_turn = np.einsum("...mj,...kjl->...mkl", sight.local, sight.by_cam)
        by_board_turn = np.einsum("...klj,...mj->...mkl", sight.by_brd, sight.corner)
        own = np.concatenate(
            [
                -by_p,
                by_p @ np.swapaxes(by_camera_turn, -1, -2),
                to_board @ brd[..., None, :, :],
                to_board @ np.swapaxes(by_board_turn, -1, -2),
            ],
            axis=-1,
        )
        return by_tip, own

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        raise NotImplementedError("a camera's design gradient is taken by central differences")
