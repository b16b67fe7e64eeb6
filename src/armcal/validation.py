"""What a calibration predicts, checked: validation on held-out poses, cross-validation.

**Validation** (:func:`validate`) compares measured positions with the nominal
arm and with the calibrated one.  "Before" is what a user has without
calibrating: the nominal arm with its *own* instrument pose and targets, fitted
on the calibration's training rows (the calibration's baseline,
:func:`armcal.identification.registration.register_nominal`).  It is never the
nominal arm placed at the *calibrated* instrument pose, which has taken up the
geometry that merges into it and misses by several times as much.  A calibration
without a recorded baseline registers the nominal arm on the held-out rows
themselves (a baseline that flatters the nominal arm, and says so).  Next to the
measured errors it gives the error the calibration predicts for a measurement:
``sqrt(tr(J C J^T) + tr(Sigma))``, the model's uncertainty at the pose (``J``
the Jacobian in the parameters, ``C`` their covariance) plus the instrument's
noise.  A calibrated error far above it means the model misses something
(:func:`validation_warnings`).

**Cross-validation** (:func:`cross_validate`) predicts every pose with a
calibration made without it.

Both work through :class:`~armcal.models.interface.FitModel`, for every family
of arm.  Errors are of points: every RMS here is *per point* (the Euclidean
error of a point), ``sqrt(d)`` times the per-coordinate RMS of noise alike on
every axis.  A 6-DoF instrument's orientations are checked apart, in degrees
(the angle of the turn between measured and predicted), never mixed with mm.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArmcalError, ArmcalWarning, NotIdentifiableError, action
from .identification import identify
from .identification.registration import register_nominal
from .identification.result import Calibration, calibrated_arm
from .models import CalibratedArm, Conditions, FitModel, Loads
from .models.information import tip_variances
from .noise import NoiseModel, per_row_sigma
from .notebook import html_table, number
from .numerics import point_norms, rms
from .progress import ProgressCallback

__all__ = [
    "CrossValidation",
    "Turns",
    "Validation",
    "clearly_better",
    "cross_validate",
    "cross_validation_warning",
    "cross_validation_warnings",
    "predicted_errors",
    "training_rows_among",
    "validate",
    "validation_warnings",
    "worse_warning",
]


@dataclass(frozen=True, eq=False)
class Validation:
    """Positioning errors of the nominal and the calibrated model on held-out poses.

    Attributes
    ----------
    before : ndarray, shape (m, d)
        Measured minus nominal position (at the calibrated base pose), mm.
    after : ndarray, shape (m, d)
        Measured minus calibrated position, mm.
    predicted_mm : ndarray, shape (m,)
        The calibrated error a measurement is expected to show (RMS over the
        noise and the calibration's uncertainty), mm.
    model_mm : ndarray, shape (m,)
        The calibrated model's own uncertainty at the pose (RMS), mm.
    positions : ndarray, shape (m, d)
        The measured positions (in the plane for 3-D data), mm.
    out_of_plane_mm : ndarray, shape (m,), or None
        For 3-D data of a planar arm: each point's distance from its target's plane, mm.
    turns : Turns or None
        For a 6-DoF instrument: the orientation errors before and after, and predicted.
    baseline_rows : {"calibration", "held-out"}
        Where the nominal arm of ``before`` was registered: on the calibration's
        training rows (its recorded baseline), or on these held-out rows (for a
        calibration that recorded none).
    reused : ndarray of bool, shape (m,), or None
        Which rows are rows the calibration was fitted to (the same joint readings and
        target, to the last bit); None where the calibration does not record its rows.
        Of every row validated, a turn's too, where :attr:`kept` is given.
    kept : ndarray of int, shape (m,), or None
        Which of the rows validated the arrays above are, where some rows read a turn
        instead (partial coordinates': their errors are :attr:`turns`'); None for all.
    unit : str
        The readings' unit: the errors' and predictions' ``_mm`` are a camera's pixels
        under the same names (``"px"``).
    """

    before: np.ndarray
    after: np.ndarray
    predicted_mm: np.ndarray
    model_mm: np.ndarray
    positions: np.ndarray
    out_of_plane_mm: np.ndarray | None = None
    turns: Turns | None = None
    baseline_rows: Literal["calibration", "held-out"] = "calibration"
    reused: np.ndarray | None = None
    kept: np.ndarray | None = None
    unit: str = "mm"

    def __repr__(self) -> str:
        s, u = self.summary(), self.unit
        return (
            f"Validation({self.after.shape[0]} poses: RMS per point "
            f"{s['rms_before_per_point_mm']:.4g} {u} before, {s['rms_after_per_point_mm']:.4g} "
            f"{u} after, {s['predicted_rms_after_per_point_mm']:.4g} {u} predicted)"
        )

    def _repr_html_(self) -> str:
        """The repr over a table of the errors before and after calibration (per point,
        mm; a 6-DoF instrument's orientations in deg): what a notebook shows."""
        s, u = self.summary(), self.unit
        rows = [
            [f"RMS per point ({u})", number(s["rms_before_mm"]), number(s["rms_after_mm"])],
            [f"max ({u})", number(s["max_before_mm"]), number(s["max_after_mm"])],
            [f"95 % quantile ({u})", number(s["p95_before_mm"]), number(s["p95_after_mm"])],
            [f"predicted RMS per point ({u})", "", number(s["predicted_rms_after_per_point_mm"])],
        ]
        if self.turns is not None:
            rows.append(
                [
                    "orientation RMS (deg)",
                    number(s["orientation_rms_before_deg"]),
                    number(s["orientation_rms_after_deg"]),
                ]
            )
        return html_table(repr(self), ["", "before", "after"], rows)

    @property
    def before_mm(self) -> np.ndarray:
        """Euclidean error ``(m,)`` of the nominal model, mm."""
        return point_norms(self.before)

    @property
    def after_mm(self) -> np.ndarray:
        """Euclidean error ``(m,)`` of the calibrated model, mm."""
        return point_norms(self.after)

    def summary(self) -> dict[str, float]:
        """RMS, max and 95 % quantile before and after, and the predicted RMS (mm).

        Every figure is of the points' Euclidean errors (per point, both
        coordinates together; a coordinate's RMS is ``1 / sqrt(d)`` of it for
        isotropic errors); ``rms_before_mm`` and ``rms_after_mm`` are the
        per-point RMS under their PRODUCT.md names.  For 3-D data of a planar
        arm also the RMS and max distance of the points from their plane.
        """
        before, after = self.before_mm, self.after_mm
        out = {
            "rms_before_mm": rms(before),
            "rms_after_mm": rms(after),
            "rms_before_per_point_mm": rms(before),
            "rms_after_per_point_mm": rms(after),
            "max_before_mm": float(np.max(before)),
            "max_after_mm": float(np.max(after)),
            "p95_before_mm": float(np.percentile(before, 95)),
            "p95_after_mm": float(np.percentile(after, 95)),
            "predicted_rms_after_per_point_mm": rms(self.predicted_mm),
            "model_rms_per_point_mm": rms(self.model_mm),
        }
        if self.out_of_plane_mm is not None:
            out["out_of_plane_rms_per_point_mm"] = rms(self.out_of_plane_mm)
            out["out_of_plane_max_mm"] = float(np.max(np.abs(self.out_of_plane_mm)))
        if self.turns is not None:
            out.update(self.turns.summary())
        return out


@dataclass(frozen=True, eq=False)
class Turns:
    """A 6-DoF instrument's orientation errors on held-out rows (rad, instrument frame).

    Attributes
    ----------
    before, after : ndarray, shape (m, 3) or (m, 1)
        The turn from the nominal (calibrated) model's orientation to the measured one,
        as rotation vectors; for partial coordinates, a turn's component's error.
    predicted : ndarray, shape (m,)
        The calibrated turn's expected size (its uncertainty and the noise), rad.
    """

    before: np.ndarray
    after: np.ndarray
    predicted: np.ndarray

    def summary(self) -> dict[str, float]:
        """RMS and max of the turns' angles before and after, and the predicted RMS (deg)."""
        before = np.degrees(point_norms(self.before))
        after = np.degrees(point_norms(self.after))
        return {
            "orientation_rms_before_deg": rms(before),
            "orientation_rms_after_deg": rms(after),
            "orientation_max_after_deg": float(np.max(after)),
            "predicted_orientation_rms_after_deg": float(np.degrees(rms(self.predicted))),
        }


def _noise(cal: CalibratedArm) -> NoiseModel:
    """The noise of one measurement: the model's, else isotropic at the calibration's sigma."""
    noise = cal.model.noise
    return noise if noise is not None else NoiseModel.isotropic(cal.sigma_mm)


def predicted_errors(
    cal: CalibratedArm,
    q: ArrayLike,
    *,
    target: ArrayLike | None = None,
    row_sigma: np.ndarray | None = None,
    loads: Loads | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The calibrated model's uncertainty and a measurement's expected error ``(m,)`` each, mm.

    ``sqrt(tr(J C J^T))`` in the instrument frame (base pose included) and
    ``sqrt(tr(J C J^T) + tr(Sigma_i))`` with the noise of the measurement
    (:func:`armcal.models.information.tip_variances`).

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([2.0, 1.0])
    >>> cal = CalibratedArm(arm, np.zeros(4), np.zeros((4, 4)), 0.01)
    >>> [v.round(6).tolist() for v in predicted_errors(cal, np.zeros((1, 2)))]
    [[0.0], [0.014142]]
    """
    conditions = cal.model.conditions(q, target=target, loads=loads, sigma_mm=row_sigma)
    uncertainty, expected, *_ = _predicted(cal, conditions)
    return uncertainty, expected


#: Rows whose Jacobians :func:`_predicted` holds at once (about 10 MB for a six-axis arm):
#: memory stays flat in the number of held-out rows.
PREDICTED_CHUNK = 4096


def _predicted(
    cal: CalibratedArm, conditions: Conditions
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """The model's uncertainty and a measurement's expected error of the positions (mm),
    of a 6-DoF instrument's turns (rad; None without), and the calibrated arm's points
    (from the Jacobian's pass, where the model keeps them), :data:`PREDICTED_CHUNK` rows
    at a time."""
    parts = [_predicted_rows(cal, block) for block, _ in conditions.blocks(PREDICTED_CHUNK)]
    turns = [part[2] for part in parts if part[2] is not None]
    return (
        np.concatenate([part[0] for part in parts]),
        np.concatenate([part[1] for part in parts]),
        np.concatenate(turns) if len(turns) == len(parts) else None,
        np.concatenate([part[3] for part in parts]),
    )


def _predicted_rows(
    cal: CalibratedArm, conditions: Conditions
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    model, d = cal.model, cal.model.position_dim
    jac = model.jacobian(conditions, cal.params)
    positions = cal.positions(conditions)
    noise = model.pose_covariances(conditions, cal.params, noise=_noise(cal))
    variance = tip_variances(jac[..., :d, :], cal.covariance)
    total = variance + np.trace(noise[..., :d, :d], axis1=-2, axis2=-1)
    turn = None
    if jac.shape[-2] > d:
        turn_variance = tip_variances(jac[..., d:, :], cal.covariance)
        turn = np.sqrt(turn_variance + np.trace(noise[..., d:, d:], axis1=-2, axis2=-1))
    return np.sqrt(variance), np.sqrt(np.clip(total, 0.0, None)), turn, positions


def _turns(
    model: FitModel, before: np.ndarray, after: np.ndarray, predicted: np.ndarray | None
) -> Turns | None:
    """The orientation part of the errors, for a 6-DoF instrument's rows."""
    d = model.position_dim
    if predicted is None:
        return None
    return Turns(before[:, d:], after[:, d:], predicted)


def validate(
    cal: Calibration | CalibratedArm,
    q: ArrayLike,
    points: ArrayLike,
    *,
    target: ArrayLike | None = None,
    row_sigma: np.ndarray | None = None,
    loads: Loads | None = None,
    feature: ArrayLike | None = None,
) -> Validation:
    """Positioning error before and after calibration on held-out measurements.

    Parameters
    ----------
    cal : Calibration or CalibratedArm
        What :func:`~armcal.identification.identify` returns, or a calibrated arm
        (:func:`~armcal.files.read_calibration`).
    q : ndarray, shape (m, n)
        Joint angles of the held-out poses, rad.
    points : ndarray, shape (m, d) or (m, 3)
        Measured positions in the instrument frame, mm: as the calibration's
        data were (3-D points of a planar arm calibrated from 3-D data are
        projected into its plane).
    target : ndarray of int or sequence of str, shape (m,), optional
        Every row's target, for an arm with several: its index or its label.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm) for the predicted error.
    loads : Loads, optional
        Every row's payload and tip force, for a calibration with compliance
        (default: the robot file's payload).  The nominal model has none.
    feature : ndarray of int or sequence of str, shape (m,), optional
        For an instrument of several features (a plane, a fixed point): the one every
        row touches, its index or label.

    Returns
    -------
    Validation

    Raises
    ------
    ArmcalError
        For 2-D points with a 3-D calibration or the other way round.

    Examples
    --------
    >>> from armcal.models import PlanarArm, forward_kinematics
    >>> arm = PlanarArm([2.0, 1.0])
    >>> truth = arm.params_from_display([0.01, 0.0], [0.5, 0.0])
    >>> cal = CalibratedArm(arm, truth, np.zeros((4, 4)), 0.001)
    >>> q = np.radians([[0.0, 30.0], [45.0, -60.0]])
    >>> v = validate(cal, q, forward_kinematics(arm, q, truth))
    >>> bool(v.summary()["rms_before_mm"] > 0.02), float(v.summary()["rms_after_mm"])
    (True, 0.0)
    """
    cal = calibrated_arm(cal)
    model = cal.model
    conditions = model.conditions(
        q, target=target, loads=loads, sigma_mm=row_sigma, feature=feature
    )
    points = np.asarray(points, dtype=float)
    out_of_plane = None
    if cal.plane is not None:
        if points.shape[-1] != 3:
            raise ArmcalError(
                "the calibration was made from 3-D data: validate with x_mm, y_mm and z_mm"
            )
        out_of_plane = cal.plane.distance(points, conditions.target)
        measured = cal.plane.to_plane(points)
    else:
        if points.shape[-1] != model.point_dim:
            raise ArmcalError(_other_data(model.point_dim))
        conditions, measured = model.anchor(conditions, points)
    baseline_rows: Literal["calibration", "held-out"] = "calibration"
    if cal.baseline is not None:
        nominal = cal.baseline_positions(conditions)
    else:  # an older calibration file: the nominal arm registered on these rows
        found = register_nominal(model, conditions, measured, cal.params)
        if found is None:
            raise ArmcalError(
                "the nominal arm cannot be registered on these rows, and the calibration "
                "records no baseline; identify again to record one"
            )
        nominal, baseline_rows = model.arm.positions(conditions, found.params), "held-out"
    uncertainty, predicted, turn, calibrated = _predicted(cal, conditions)
    before = measured - nominal
    after = measured - calibrated
    d = model.position_dim
    reused = (
        None if cal.training_rows is None else training_rows_among(cal.training_rows, conditions)
    )
    kept, turns = _turn_split(model, conditions, before, after, predicted, turn)
    rows = slice(None) if kept is None else kept
    return Validation(
        before[rows, :d],
        after[rows, :d],
        predicted[rows],
        uncertainty[rows],
        measured[rows, :d],
        out_of_plane,
        turns,
        baseline_rows,
        reused,
        kept,
        model.reading_unit,
    )


def _turn_split(
    model: FitModel,
    conditions: Conditions,
    before: np.ndarray,
    after: np.ndarray,
    predicted: np.ndarray,
    turn_predicted: np.ndarray | None,
) -> tuple[np.ndarray | None, Turns | None]:
    """The rows that read a position (their indices; None: every row) and the turns'
    errors: the rows that read a turn (partial coordinates'), apart, else a 6-DoF
    instrument's orientations (:func:`_turns`, ``turn_predicted``)."""
    turning = model.turn_rows(conditions)
    if turning is None or not np.any(turning):
        return None, _turns(model, before, after, turn_predicted)
    turns = Turns(before[turning], after[turning], predicted[turning])
    return np.flatnonzero(~turning), turns


def _row_keys(rows: Conditions) -> np.ndarray:
    """Every row's joint readings and target as one opaque key ``(m,)``, bit for bit."""
    target = np.zeros(rows.m) if rows.target is None else rows.target.astype(float)
    table = np.ascontiguousarray(np.column_stack([np.asarray(rows.q, dtype=float), target]))
    return table.view(np.dtype((np.void, table.dtype.itemsize * table.shape[1]))).ravel()


def training_rows_among(training: Conditions, rows: Conditions) -> np.ndarray:
    """Boolean ``(m,)``: which of ``rows`` are rows of ``training`` (the same joint readings,
    to the last bit, and the same target): a calibration's own rows given to validation as
    held out.  One sort of both, ``O(m log m)``.

    Examples
    --------
    >>> train = Conditions(np.array([[0.1, 0.2], [0.3, 0.4]]))
    >>> training_rows_among(train, Conditions(np.array([[0.3, 0.4], [0.3, 0.41]]))).tolist()
    [True, False]
    """
    return np.isin(_row_keys(rows), _row_keys(training))


def _other_data(dim: int) -> str:
    """What the held-out data lack (or have too much of) for a calibration of ``dim``."""
    if dim == 6:
        return (
            "the calibration was made from 6-DoF data: validate with the orientation "
            "columns rx_deg, ry_deg, rz_deg too"
        )
    if dim == 3:
        return (
            "the calibration was made from 3-D positions: validate with x_mm, y_mm and z_mm "
            "(no orientation columns)"
        )
    return "the calibration was made from 2-D data: validate with x_mm and y_mm (no z_mm)"


def _too_large(measured: float, predicted: float, count: int) -> bool:
    """Whether an RMS over ``count`` points is above its prediction beyond chance.

    The mean square of ``2 count`` coordinates has relative std ``1/sqrt(count)``
    (chi-square), so the RMS about ``1/(2 sqrt(count))``: 6 of them, and at least 20 %.
    """
    return measured > predicted * (1.0 + max(0.2, 3.0 / np.sqrt(max(count, 1))))


def clearly_better(
    before_mm: np.ndarray, after_mm: np.ndarray, groups: np.ndarray | None = None
) -> bool:
    """Whether errors ``after_mm`` ``(m,)`` are clearly below ``before_mm`` ``(m,)``, mm.

    Clearly: the RMS after is below the RMS before beyond chance, by the margin of
    :func:`_too_large` over the ``n`` poses (``groups`` ``(m,)`` gathers a pose's
    points, which share its errors; every point its own pose by default): at most
    ``1 / (1 + max(0.2, 3 / sqrt(n)))`` of it, 0.83 from 225 poses on, 0.63 at 20,
    0.5 at 9.  A gain of a few percent, or one that a few poses may give by chance,
    is no reason to calibrate; a calibration that removes most of the error passes
    at any number of poses.

    Examples
    --------
    >>> before = np.array([1.0, 1.2, 0.9, 1.1, 1.0])
    >>> clearly_better(before, before / 10), clearly_better(before, before * 0.8)
    (True, False)
    """
    before_mm, after_mm = np.asarray(before_mm, float), np.asarray(after_mm, float)
    poses = before_mm.size if groups is None else np.unique(np.asarray(groups)).size
    return bool(_too_large(rms(before_mm), rms(after_mm), poses))


def worse_warning(
    before: float, after: float, predicted: float, count: int, where: str, unit: str = "mm"
) -> ArmcalWarning:
    """``calibration-worse``: RMS per point ``after`` calibration is not clearly below the
    nominal arm's ``before`` on ``count`` points, ``where`` (a phrase); ``predicted`` is
    the calibrated error expected, against which the nominal arm is judged; all in
    ``unit`` (a camera's px)."""
    numbers = (
        f"{after:.3g} {unit} RMS per point after calibration against {before:.3g} {unit} for "
        "the nominal arm registered on its own"
    )
    causes = (
        "the arm or the instrument changed during the campaign (a tracker or a base that "
        "moved, a joint that slipped, temperature), the model misses an effect, or the "
        "calibration and the measurements are of different setups"
    )
    nominal_fits = not _too_large(before, predicted, count)
    if after >= before and not (nominal_fits and not _too_large(after, predicted, count)):
        return ArmcalWarning(
            "calibration-worse",
            f"the calibrated model is worse than the nominal arm on {where} ({numbers}): {causes}",
        )
    if nominal_fits:  # both within the noise: nothing to buy
        return ArmcalWarning(
            "calibration-worse",
            f"calibration buys nothing measurable on {where} ({numbers}): the nominal arm "
            f"already predicts them within the noise and the calibration's uncertainty "
            f"({predicted:.3g} {unit}); keep the nominal model, or measure with a better "
            "instrument",
        )
    return ArmcalWarning(
        "calibration-worse",
        f"calibration does not make {where} clearly better ({numbers}), and both miss them "
        f"by more than the {predicted:.3g} mm predicted: {causes}",
    )


def validation_warnings(
    result: Validation, groups: np.ndarray | None = None
) -> list[ArmcalWarning]:
    """``validation-error`` when the calibrated error exceeds its prediction beyond chance,
    ``calibration-worse`` when the calibrated model is not clearly better than the nominal
    arm registered on its own (:func:`clearly_better`; ``groups`` ``(m,)`` gathers a pose's
    points)."""
    s = result.summary()
    warnings = []
    count = result.after.shape[0]
    reused = 0 if result.reused is None else int(np.count_nonzero(result.reused))
    poses = "these poses" if reused else "these held-out poses"  # own rows are not held out
    if _too_large(s["rms_after_per_point_mm"], s["predicted_rms_after_per_point_mm"], count):
        warnings.append(
            ArmcalWarning(
                "validation-error",
                f"the calibrated model misses {'these' if reused else 'the held-out'} poses "
                "by RMS "
                f"{s['rms_after_per_point_mm']:.3g} {result.unit} per point, more than the "
                f"{s['predicted_rms_after_per_point_mm']:.3g} {result.unit} it predicts (noise "
                "and "
                "its uncertainty): the model misses an effect, the poses lie outside the "
                "calibrated range, the arm changed, or the measurements belong to another setup",
            )
        )
    if result.turns is not None:
        warnings += _turn_warnings(s, result.turns.after.shape[0])
    if reused:
        warnings.append(
            ArmcalWarning(
                "not-held-out",
                f"{reused} of {0 if result.reused is None else result.reused.size} rows are "
                "rows the calibration was fitted to (the same joint readings and target): they "
                "are not held out, and their errors after calibration flatter it; validate on "
                "poses the calibration has not seen",
            )
        )
    if not clearly_better(result.before_mm, result.after_mm, groups):
        warnings.append(
            worse_warning(
                s["rms_before_per_point_mm"],
                s["rms_after_per_point_mm"],
                s["predicted_rms_after_per_point_mm"],
                count,
                poses,
                result.unit,
            )
        )
    return warnings


def _turn_warnings(s: dict[str, float], count: int) -> list[ArmcalWarning]:
    """The orientation's ``validation-error`` and ``calibration-worse``, in degrees."""
    after, before = s["orientation_rms_after_deg"], s["orientation_rms_before_deg"]
    predicted = s["predicted_orientation_rms_after_deg"]
    out = []
    if _too_large(after, predicted, count):
        out.append(
            ArmcalWarning(
                "validation-error",
                f"the calibrated model misses the held-out orientations by RMS {after:.3g} "
                f"deg, more than the {predicted:.3g} deg it predicts (noise and its "
                "uncertainty): the probe moved on the flange, or the orientation noise "
                "(orientation_sigma_deg) is too small",
            )
        )
    if after > before:
        out.append(
            ArmcalWarning(
                "calibration-worse",
                f"the calibrated model's orientations are worse than the nominal one's on "
                f"these poses ({after:.3g} against {before:.3g} deg RMS): check that the "
                "calibration and the measurements are of the same robot and instrument setup",
            )
        )
    return out


@dataclass(frozen=True, eq=False)
class CrossValidation:
    """K-fold prediction errors: every pose predicted by a calibration made without it.

    Attributes
    ----------
    folds : int
        Number of folds ``K``.
    fold : ndarray of int, shape (m,)
        The fold (0..K-1) every row was held out in.
    errors : ndarray, shape (m, d)
        Measured minus predicted position of every row, by the calibration of
        the other folds, mm.
    predicted_mm : ndarray, shape (m,)
        The error that calibration predicts for the row (its uncertainty and
        the instrument noise), mm.
    turns : Turns or None
        For a 6-DoF instrument: the predicted orientations' errors (``before``
        unused: the same as ``after``).
    nominal_errors : ndarray, shape (m, d), or None
        Measured minus the nominal arm's position, the nominal arm registered on its
        own to the same training rows as the fold's calibration (its baseline), mm.
    groups : ndarray, shape (m,), or None
        The pose every row belongs to (rows of one pose share its errors).
    unit : str
        The readings' unit (:attr:`Validation.unit`).
    """

    folds: int
    fold: np.ndarray
    errors: np.ndarray
    predicted_mm: np.ndarray
    turns: Turns | None = None
    nominal_errors: np.ndarray | None = None
    groups: np.ndarray | None = None
    unit: str = "mm"

    def __repr__(self) -> str:
        s, u = self.summary(), self.unit
        return (
            f"CrossValidation({self.folds} folds: prediction error RMS per point "
            f"{s['rms_per_point_mm']:.4g} {u}, "
            f"predicted {s['predicted_rms_per_point_mm']:.4g} {u})"
        )

    @property
    def errors_mm(self) -> np.ndarray:
        """Euclidean prediction error ``(m,)`` of every row, mm."""
        return point_norms(self.errors)

    @property
    def nominal_mm(self) -> np.ndarray | None:
        """Euclidean error ``(m,)`` of the registered nominal arm at every row, mm."""
        return None if self.nominal_errors is None else point_norms(self.nominal_errors)

    def per_fold(self) -> list[dict[str, float | int | None]]:
        """Every fold's held-out points, their RMS per point after calibration, predicted,
        and the nominal arm's (registered on the same training rows), mm."""
        nominal = self.nominal_mm
        out: list[dict[str, float | int | None]] = []
        for k in range(self.folds):
            held = self.fold == k
            out.append(
                {
                    "fold": k + 1,
                    "points": int(np.count_nonzero(held)),
                    "rms_per_point_mm": rms(self.errors_mm[held]),
                    "predicted_rms_per_point_mm": rms(self.predicted_mm[held]),
                    "nominal_rms_per_point_mm": None if nominal is None else rms(nominal[held]),
                }
            )
        return out

    def summary(self) -> dict[str, float | int]:
        """``folds``, RMS and max prediction error and the predicted RMS (mm), per point, and
        the nominal arm's RMS (registered on every fold's training rows); for a 6-DoF
        instrument the orientations' RMS and predicted RMS (deg)."""
        out: dict[str, float | int] = {
            "folds": self.folds,
            "rms_per_point_mm": rms(self.errors_mm),
            "max_mm": float(np.max(self.errors_mm)),
            "predicted_rms_per_point_mm": rms(self.predicted_mm),
        }
        nominal = self.nominal_mm
        if nominal is not None:
            out["nominal_rms_per_point_mm"] = rms(nominal)
        if self.turns is not None:
            turns = self.turns.summary()
            out["orientation_rms_deg"] = turns["orientation_rms_after_deg"]
            out["predicted_orientation_rms_deg"] = turns["predicted_orientation_rms_after_deg"]
        return out


def cross_validation_warnings(result: CrossValidation) -> list[ArmcalWarning]:
    """:func:`cross_validation_warning`, and ``calibration-worse`` when the held-out poses
    are not clearly better predicted than by the nominal arm registered on the same
    training rows (:func:`clearly_better`)."""
    found = [w for w in (cross_validation_warning(result),) if w is not None]
    nominal = result.nominal_mm
    if nominal is not None and not clearly_better(nominal, result.errors_mm, result.groups):
        s = result.summary()
        found.append(
            worse_warning(
                s["nominal_rms_per_point_mm"],
                s["rms_per_point_mm"],
                s["predicted_rms_per_point_mm"],
                result.errors.shape[0],
                "the held-out poses of the cross-validation",
                result.unit,
            )
        )
    return found


def cross_validation_warning(result: CrossValidation) -> ArmcalWarning | None:
    """``cross-validation`` when poses are predicted worse than the calibrations say."""
    summary = result.summary()
    count = result.errors.shape[0]
    rms, predicted = summary["rms_per_point_mm"], summary["predicted_rms_per_point_mm"]
    found = []
    if _too_large(rms, predicted, count):
        u = result.unit
        found.append(f"RMS {rms:.3g} {u} per point, more than the {predicted:.3g} {u}")
    if "orientation_rms_deg" in summary:  # a 6-DoF instrument's orientations
        turn, turn_predicted = (
            summary["orientation_rms_deg"],
            summary["predicted_orientation_rms_deg"],
        )
        if _too_large(turn, turn_predicted, count):
            found.append(f"orientation RMS {turn:.3g} deg, more than the {turn_predicted:.3g} deg")
    if not found:
        return None
    return ArmcalWarning(
        "cross-validation",
        f"held-out poses are predicted with {' and '.join(found)} the calibrations "
        f"predict: the model misses an effect (compliance, a wrong joint map, a probe "
        f"that moved on the flange) or some poses are outliers ({action('try-robust')})",
    )


def cross_validate(
    model: FitModel,
    q: ArrayLike,
    points: ArrayLike,
    folds: int,
    *,
    groups: np.ndarray | None = None,
    target: ArrayLike | None = None,
    sigma: float | None = None,
    row_sigma: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    loads: Loads | None = None,
    progress: ProgressCallback | None = None,
    feature: ArrayLike | None = None,
) -> CrossValidation:
    """K-fold cross-validation of the calibration of ``model``.

    Parameters
    ----------
    model : FitModel
        The model identified (noise model and fixed parameters included).
    q : ndarray, shape (m, n)
        Joint angles, rad.
    points : ndarray, shape (m, d)
        Measured positions in the frame identified in (the plane for 3-D data
        of a planar arm), mm.
    folds : int
        ``K >= 2``: every fold is left out once and predicted by the others.
    groups : ndarray, shape (m,), optional
        Rows that belong together (the targets measured at one pose) stay in
        one fold; every row its own group by default.
    target, sigma, row_sigma, loads
        As for :func:`armcal.identification.identify`: a given ``sigma`` replaces
        ``row_sigma`` (:func:`armcal.noise.per_row_sigma`) in every fold's fit and
        in the error each fold predicts.
    rng : numpy.random.Generator or int or None
        Shuffles the groups into folds.
    progress : callable, optional
        ``progress(done, folds)`` after every fold (:mod:`armcal.progress`).
    feature : ndarray of int or sequence of str, shape (m,), optional
        For an instrument of several features (planes, partial coordinates' axes and
        turns, a board's corners): every row's (as :func:`validate`'s).

    Returns
    -------
    CrossValidation

    Raises
    ------
    ArmcalError
        If ``K`` is out of range or some fold's complement cannot identify the
        parameters (too few poses for ``K`` folds).
    """
    rng = np.random.default_rng(rng)
    row_sigma = per_row_sigma(sigma, row_sigma)  # a given sigma replaces them, fold by fold
    conditions = model.conditions(
        q, target=target, loads=loads, sigma_mm=row_sigma, feature=feature
    )
    conditions, points = model.anchor(conditions, np.asarray(points, dtype=float))
    m = conditions.m
    keys = np.arange(m) if groups is None else np.unique(groups, return_inverse=True)[1]
    count = int(keys.max()) + 1
    if not 2 <= folds <= count:
        raise ArmcalError(
            f"{action('cross-validate')} needs 2 to {count} folds (the poses), got {folds}"
        )
    of_group = np.empty(count, dtype=int)
    of_group[rng.permutation(count)] = np.arange(count) % folds
    fold = of_group[keys]
    errors = np.empty(points.shape)
    nominal: np.ndarray | None = np.empty(points.shape)
    predicted = np.empty(m)
    turn_predicted = np.empty(m)
    for k in range(folds):
        held = fold == k
        train = conditions.take(~held)
        try:
            cal = identify(
                model,
                train.q,
                points[~held],
                sigma=sigma,
                row_sigma=train.sigma_mm,
                target=train.target,
                loads=train.loads,
                conditions=train,
            )
        except NotIdentifiableError:
            raise ArmcalError(
                f"with {folds} folds, the poses left after holding out fold {k + 1} cannot "
                "identify every parameter; use fewer folds or measure more poses"
            ) from None
        test = conditions.take(held)
        fitted = cal.calibrated()
        _, predicted[held], turn, calibrated = _predicted(fitted, test)
        errors[held] = points[held] - calibrated
        if nominal is not None and fitted.baseline is not None:
            nominal[held] = points[held] - fitted.baseline_positions(test)
        else:  # a fold whose rows cannot place the nominal arm: no baseline to compare
            nominal = None
        if turn is not None:
            turn_predicted[held] = turn
        if progress is not None:
            progress(k + 1, folds)
    turn = turn_predicted if points.shape[1] > model.position_dim else None
    found = (fold, errors, predicted, turn, nominal, groups)
    return _cross_validation(model, conditions, folds, *found)


def _cross_validation(
    model: FitModel,
    conditions: Conditions,
    folds: int,
    fold: np.ndarray,
    errors: np.ndarray,
    predicted: np.ndarray,
    turn_predicted: np.ndarray | None,
    nominal: np.ndarray | None,
    groups: np.ndarray | None,
) -> CrossValidation:
    """The folds' errors of every row as a :class:`CrossValidation`: the positions', and a
    6-DoF instrument's turns (``turn_predicted``) or partial coordinates' rows of turns
    apart, in :class:`Turns`."""
    d = model.position_dim
    kept, turns = _turn_split(model, conditions, errors, errors, predicted, turn_predicted)
    rows = slice(None) if kept is None else kept
    return CrossValidation(
        folds,
        fold[rows],
        errors[rows, :d],
        predicted[rows],
        turns,
        None if nominal is None else nominal[rows, :d],
        None if groups is None else np.asarray(groups)[rows],
        model.reading_unit,
    )
