"""What every instrument is: a measurement equation on the tool point, with derivatives.

An instrument reports ``dim`` numbers per row from the tool point ``p`` (mm, the
robot's base frame) and its own parameters ``theta`` (internal units: mm, rad),
at the feature the row touches (a plane of several, a fixed point of several):
``reading(p, feature, theta)``.  Its analytic derivatives,
``d reading / d p`` and ``d reading / d theta``, give the model's Jacobian by the
chain rule (:class:`~armcal.models.instrumented.InstrumentedArm`).

Every method is batched over leading axes of ``theta`` ``(..., t)`` and of the
points ``(..., m, 3)``, as :class:`~armcal.models.interface.FitModel`'s.
"""

from __future__ import annotations

from typing import Protocol, cast

import numpy as np

from ..models.spatial.chain import elementary, skew
from ..noise import NoiseModel

__all__ = [
    "Contact",
    "Defaults",
    "Instrument",
    "MeetsAtZero",
    "feature_index",
    "same_features",
    "turned_frame",
    "turns_between",
    "unseen_words",
    "z_to",
]


class Instrument(Protocol):
    """An instrument's measurement equation (module notes)."""

    @property
    def kind(self) -> str:
        """The robot file's ``[instrument] kind``: ``"plane"``, ``"point"``, ..."""
        ...

    @property
    def labels(self) -> tuple[str, ...]:
        """The features' labels (a plane's, a fixed point's), in parameter order."""
        ...

    @property
    def dim(self) -> int:
        """Numbers a row reports (mm each)."""
        ...

    @property
    def param_names(self) -> tuple[str, ...]: ...

    @property
    def param_units(self) -> tuple[str, ...]:
        """``mm`` or ``rad`` (shown in degrees)."""
        ...

    @property
    def start(self) -> np.ndarray:
        """``(t,)``: the parameters where the user says the instrument roughly is."""
        ...

    @property
    def unseen(self) -> str:
        """What the instrument cannot see of the arm, in words (a report's sentence)."""
        ...

    @property
    def label_column(self) -> str | None:
        """The measurement file's column naming every row's feature (``"plane"``), or None
        for an instrument of one feature that has none."""
        ...

    @property
    def reading_columns(self) -> tuple[str, ...]:
        """The measurement file's columns of what a row reports (``"distance_mm"``), or none
        where a row reports nothing but that it meets the instrument (a touch reads 0)."""
        ...

    @property
    def constrained(self) -> bool:
        """Whether a pose is measured only where the tool meets the instrument (a plane, a
        fixed point, a distance within range); False for one that reads it anywhere."""
        ...

    @property
    def reads_every_feature(self) -> bool:
        """Whether a row reads every feature at once, one column each (a partial
        instrument's axes, empty cells where it did not); else a row meets one feature,
        named in :attr:`label_column`."""
        ...

    @property
    def unit(self) -> str:
        """The unit of its readings and of their noise: ``"mm"``, a camera's ``"px"``."""
        ...

    @property
    def reading_bounds(self) -> tuple[tuple[float, float], ...] | None:
        """Where each of :attr:`reading_columns` can lie (a camera's image), or None."""
        ...

    @property
    def view_box(self) -> tuple[tuple[float, float], ...] | None:
        """Where each reading must lie for a plan's pose to count it seen (a camera's image
        less its margin): the view a design keeps to, a region with an inside; None for
        an instrument met on a thin set (:meth:`miss`) or read anywhere."""
        ...

    @property
    def frame(self) -> bool:
        """Whether it reads the tool's frame, not only its point (a camera on the tool, a
        board on it): its "points" are then the tip's origin and rotation ``(..., m,
        12)``, and its derivatives by the point are by the tip's shift and turn ``(..., m,
        dim, 6)`` (:mod:`~armcal.instruments.camera`)."""
        ...

    @property
    def held(self) -> tuple[str, ...]:
        """The instrument's parameters no row can see, held where it starts (an unread
        axis's shift), named in :attr:`unseen`."""
        ...

    @property
    def has_slack(self) -> bool:
        """Whether a plan's pose keeps within limits besides :attr:`view_box`
        (:meth:`slack`: a camera's depth and tilt, a turn's range)."""
        ...

    @property
    def turn_features(self) -> tuple[int, ...]:
        """The features whose readings are angles (rad, shown in degrees), not
        :attr:`unit`'s: the turns partial coordinates read."""
        ...

    @property
    def tool_point(self) -> bool:
        """Whether it measures a tool point the robot file gives in ``[targets]`` (a camera
        on the tool is placed on the flange instead)."""
        ...

    def for_tool(self, label: str) -> Instrument:
        """The same instrument on the tool point ``label`` (which names a tool's turns)."""
        ...

    def feature_sigma(self, noise: NoiseModel) -> np.ndarray | None:
        """Every feature's reading std (mm) under the robot file's ``noise`` where they
        differ (a partial instrument's axes), else None: the noise's own sigma for every
        row (ValueError for a noise model the instrument cannot read)."""
        ...

    @property
    def marks(self) -> tuple[tuple[str, np.ndarray], ...]:
        """Where a picture marks the instrument, where the user says it is: a label and a
        point ``(3,)`` (base frame, mm) for each feature (a plane's point nearest the
        base's origin, a fixed point, a pivot, an instrument's origin)."""
        ...

    def params_of(self, true: Instrument) -> np.ndarray:
        """``(t,)``: this instrument's parameters that describe ``true``, an instrument of
        the same kind and features (where a virtual lab's instrument really is)."""
        ...

    def out_of_reach(self, reach_mm: float) -> str | None:
        """Why no pose of a tool point within ``reach_mm`` of the base's origin can meet
        the instrument where it roughly is (a plane or a point beyond the reach, a range
        of distances no such point has from the pivot), else None."""
        ...

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``(..., m, dim)``: what the instrument reports of tool points ``(..., m, 3)``."""
        ...

    def slack(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """``(..., m, s)``: how far within the limits a plan's pose keeps to besides its
        :attr:`view_box` each row lies (>= 0 within: a camera's corner beyond its nearest
        depth, the board within its largest tilt), or None where there are none."""
        ...

    def slack_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        """``d slack / d points`` ``(..., m, s, 3)`` (by the tip's shift and turn ``(..., m,
        s, 6)`` for one that reads the tool's frame), or None where the model takes them by
        central differences."""
        ...

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """``(..., m, dim)``: how far (mm) tool points lie from where the instrument can
        measure them, 0 there: a touch off its plane, a seating off its point (the reading
        itself), a distance outside the instrument's range."""
        ...

    def derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``d reading / d points`` ``(..., m, dim, 3)`` and ``d reading / d params``
        ``(..., m, dim, t)``."""
        ...

    def tool_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """:meth:`derivatives`' first, by the points alone (a pose's joint step needs no
        parameter's column)."""
        ...

    def curvatures(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """How :meth:`derivatives` change with the points: ``d^2 reading / d points^2``
        ``(..., m, dim, 3, 3)`` and ``d^2 reading / d params d points`` ``(..., m, dim, t,
        3)``, each None where it is 0 (a design's gradient in the poses needs them)."""
        ...


class Defaults:
    """What most instruments share: they read the tool point in mm, unbounded, every
    parameter can be seen, and their noise is the robot file's, one sigma."""

    @property
    def frame(self) -> bool:
        return False

    @property
    def unit(self) -> str:
        return "mm"

    @property
    def reading_bounds(self) -> tuple[tuple[float, float], ...] | None:
        return None

    @property
    def view_box(self) -> tuple[tuple[float, float], ...] | None:
        return None

    def slack(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        return None

    def slack_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray | None:
        return None

    def tool_derivatives(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """Where the instrument's own is no cheaper: :meth:`Instrument.derivatives`'."""
        return cast(Instrument, self).derivatives(points, feature, params)[0]

    @property
    def held(self) -> tuple[str, ...]:
        return ()

    @property
    def has_slack(self) -> bool:
        return False

    @property
    def turn_features(self) -> tuple[int, ...]:
        return ()

    @property
    def tool_point(self) -> bool:
        return True

    def for_tool(self, label: str) -> Instrument:
        return self  # type: ignore[return-value]

    def feature_sigma(self, noise: NoiseModel) -> np.ndarray | None:
        return None


class Contact(Defaults):
    """What a contact instrument (a plane, a fixed point, a distance) shares besides: a
    pose is measured where the tool meets one feature, named by the row."""

    @property
    def constrained(self) -> bool:
        return True

    @property
    def reads_every_feature(self) -> bool:
        return False


class MeetsAtZero(Contact):
    """An instrument that measures a pose where its reading is 0 (a touch of a plane, a
    seating in a point): its miss is its reading."""

    def reading(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        raise NotImplementedError  # the instrument's own

    def miss(
        self, points: np.ndarray, feature: np.ndarray | None, params: np.ndarray
    ) -> np.ndarray:
        """The reading: a row is measured where it is 0."""
        return self.reading(points, feature, params)


def feature_index(feature: np.ndarray | None, m: int, labels: tuple[str, ...]) -> np.ndarray:
    """Every row's feature index ``(m,)``: ``feature`` as given, or 0 for an instrument
    of one feature (ValueError where it has several and the rows do not say which)."""
    if feature is None:
        if len(labels) > 1:
            raise ValueError(
                f"the instrument has {len(labels)} features ({', '.join(labels)}): every row "
                "must say which it touches"
            )
        return np.zeros(m, dtype=int)
    index = np.asarray(feature)
    if index.shape != (m,) or index.dtype.kind not in "iu":
        raise ValueError(f"feature must be {m} integer indices")
    if m and (index.min() < 0 or index.max() >= len(labels)):
        raise ValueError(f"feature indices must lie in 0..{len(labels) - 1}")
    return index


def same_features(mine: Instrument, true: Instrument) -> None:
    """ValueError unless ``true`` is of ``mine``'s kind with the same features."""
    if true.kind != mine.kind or true.labels != mine.labels:
        raise ValueError(
            f"the true instrument must be a {mine.kind} with the features "
            f"{', '.join(mine.labels)}, in that order, as the robot file's"
        )


def z_to(normal: np.ndarray) -> np.ndarray:
    """The rotation ``(3, 3)`` that takes ``e_z`` to the unit vector ``normal`` along the
    great circle between them (a half turn about x for ``-e_z``).

    Examples
    --------
    >>> r = z_to(np.array([0.0, 0.6, 0.8]))
    >>> np.round(r @ [0.0, 0.0, 1.0], 12).tolist(), bool(np.allclose(r @ r.T, np.eye(3)))
    ([0.0, 0.6, 0.8], True)
    """
    a, b, c = (float(x) for x in normal)
    if c <= -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    # I + [v] + [v]^2 / (1 + c) with v = e_z x normal = (-b, a, 0).
    skew = np.array([[0.0, 0.0, a], [0.0, 0.0, b], [-a, -b, 0.0]])
    return np.eye(3) + skew + skew @ skew / (1.0 + c)


def unseen_words(instrument: Instrument) -> str:
    """The instrument's sentence on what it cannot see (for reports)."""
    return instrument.unseen


def turned_frame(
    frame: np.ndarray, angles: np.ndarray, order: tuple[int, int, int] = (0, 1, 2)
) -> tuple[np.ndarray, np.ndarray]:
    """``R = R0 E_i E_j E_k`` ``(..., 3, 3)``: ``frame`` ``R0`` turned about its own axes in
    ``order`` by ``angles`` ``(..., 3)`` (by axis x, y, z), and its derivatives by the turns
    about x, y and z ``(..., 3, 3, 3)`` (the turn first): an instrument's small moves from
    where the user placed it (:mod:`~armcal.instruments.partial`,
    :mod:`~armcal.instruments.camera`)."""
    angles = np.asarray(angles, dtype=float)
    turns = [elementary(axis, angles[..., axis]) for axis in order]
    spins = [skew(np.eye(3)[axis]) @ turn for axis, turn in zip(order, turns, strict=True)]
    by = [
        frame @ spins[0] @ turns[1] @ turns[2],
        frame @ turns[0] @ spins[1] @ turns[2],
        frame @ turns[0] @ turns[1] @ spins[2],
    ]
    ordered = [by[order.index(axis)] for axis in range(3)]
    return frame @ turns[0] @ turns[1] @ turns[2], np.stack(ordered, axis=-3)


def turns_between(
    frame: np.ndarray, rotation: np.ndarray, order: tuple[int, int, int] = (0, 1, 2)
) -> np.ndarray:
    """The angles ``(3,)`` (by axis) with :func:`turned_frame` ``(frame, angles, order)`` =
    ``rotation``: for the order's axes ``Q`` (a cyclic order), ``Q^T R0^T R Q = Rx(a)
    Ry(b) Rz(c)``."""
    q = np.eye(3)[:, list(order)]
    m = q.T @ frame.T @ rotation @ q
    found = (
        np.arctan2(-m[1, 2], m[2, 2]),
        np.arcsin(np.clip(m[0, 2], -1.0, 1.0)),
        np.arctan2(-m[0, 1], m[0, 0]),
    )
    out = np.zeros(3)
    for axis, angle in zip(order, found, strict=True):
        out[axis] = angle
    return out
