"""Payloads the data give in another unit, beyond what a calibration saw, or not at all.

A model with joint compliance predicts a deflection proportional to the torques of
its rows' payloads, so a payload column in grams (1000 per kg) or pounds (2.205 per
kg) makes every twist 1000 or 2.2 times too large -- and the fit answers by
scaling the compliance down, silently.  Three checks, each through the model
interface (:attr:`~armcal.models.interface.FitModel.default_payload_kg`, the
calibration's training rows), for every family with compliance:

* ``payload-unit`` (identify): the largest payload of the file is more than
  :data:`PAYLOAD_UNIT_FACTOR` times the robot file's ``payload_kg``, the payload
  the arm carries when a row gives none;
* ``payload-missing`` (identify): a fit inconsistent with the noise, on data without
  a ``payload_kg`` column, whose every row was then taken to carry the robot file's
  payload: a forgotten column is the likely cause;
* ``payload-extrapolated`` (validate, compensate): payloads more than
  :data:`PAYLOAD_EXTRAPOLATION` times the largest the calibration was fitted under,
  where the deflection is the model extrapolated and no data checked it.

Each costs a few passes over the rows' payloads.
"""

from __future__ import annotations

import numpy as np

from ..errors import ArmcalWarning
from ..models import CalibratedArm, FitModel, Loads

__all__ = [
    "PAYLOAD_EXTRAPOLATION",
    "PAYLOAD_UNITS",
    "PAYLOAD_UNIT_FACTOR",
    "payload_extrapolated",
    "payload_missing",
    "payload_unit",
]

#: How many times the robot file's ``payload_kg`` a file's largest payload must be to be
#: warned of: an arm is not calibrated under twice the payload it is rated to carry,
#: while pounds read 2.2 times and grams 1000 times heavier than kilograms.
PAYLOAD_UNIT_FACTOR = 2.0

#: The units a payload column is mistaken in, with how many of them make a kg.
PAYLOAD_UNITS = (("grams", 1000.0), ("pounds", 2.20462))

#: How many times the largest payload a calibration was fitted under a payload of
#: validation or compensation may be before the deflection there is named an
#: extrapolation: the compliance model is linear in the torque, yet twice the largest
#: torque the data held doubles the deflection's error and checks nothing of the model.
PAYLOAD_EXTRAPOLATION = 2.0

#: How close (relative) a ratio of payloads must be to a unit's count per kg to name it.
_UNIT_MATCH = 0.1


def _unit_named(ratio: float) -> tuple[str, float] | None:
    """The unit of :data:`PAYLOAD_UNITS` whose count per kg a payload ``ratio`` times too
    heavy matches (within :data:`_UNIT_MATCH`), or None."""
    return next(
        ((u, per_kg) for u, per_kg in PAYLOAD_UNITS if abs(ratio / per_kg - 1.0) <= _UNIT_MATCH),
        None,
    )


def _unit_hint(ratio: float) -> str:
    """Which unit a payload ``ratio`` times too heavy looks like, in words."""
    named = _unit_named(ratio)
    if named is not None:
        return f"they look like {named[0]} ({named[1]:g} per kg)"
    return "grams (1000 per kg) or pounds (2.205 per kg) read that much heavier"


def payload_unit(
    model: FitModel, payload_kg: np.ndarray | None, source: str
) -> ArmcalWarning | None:
    """``payload-unit`` when a payload column is far heavier than the robot file's payload.

    Parameters
    ----------
    model : FitModel
        The model fitted: its default payload is the robot file's ``payload_kg``.
    payload_kg : ndarray, shape (m,), or None
        The file's ``payload_kg`` column, if it has one.
    source : str
        The file, for the message.

    Returns
    -------
    ArmcalWarning or None
        None for a rigid model, a robot file without a payload, a file without the
        column, or payloads up to :data:`PAYLOAD_UNIT_FACTOR` times the robot's.
    """
    rated = model.default_payload_kg
    if payload_kg is None or not rated or rated <= 0:
        return None
    heaviest = float(np.max(payload_kg))
    ratio = heaviest / rated
    if ratio <= PAYLOAD_UNIT_FACTOR:
        return None
    return ArmcalWarning(
        "payload-unit",
        f"{source}: column payload_kg: the rows carry up to {heaviest:g} kg, {ratio:.4g} "
        f"times the robot file's payload_kg ({rated:g} kg): {_unit_hint(ratio)}, and the "
        "fitted compliance shrinks by as much to match; give payload_kg in kg (or, if the "
        "arm truly carried that, the robot file's payload_kg)",
    )


def payload_missing(
    model: FitModel,
    payload_kg: np.ndarray | None,
    fit_warnings: tuple[ArmcalWarning, ...] | list[ArmcalWarning],
    source: str,
) -> ArmcalWarning | None:
    """``payload-missing`` when a fit with compliance is inconsistent on data without a
    payload column: every row was taken to carry the robot file's payload.

    Returns
    -------
    ArmcalWarning or None
        None for a rigid model, a file with the column, or a consistent fit.
    """
    default = model.default_payload_kg
    if default is None or payload_kg is not None:
        return None
    if all(w.code != "fit-inconsistent" for w in fit_warnings):
        return None
    return ArmcalWarning(
        "payload-missing",
        f"{source}: has no payload_kg column, so every row was taken to carry the robot "
        f"file's payload_kg ({default:g} kg), and the fit is inconsistent with the noise: "
        "the likely cause is a payload column left out of rows measured under other "
        "payloads; add the column payload_kg with every row's payload",
    )


def payload_extrapolated(
    cal: CalibratedArm, loads: Loads | None, source: str
) -> ArmcalWarning | None:
    """``payload-extrapolated`` when ``loads`` carry payloads far beyond those the
    calibration was fitted under (:data:`PAYLOAD_EXTRAPOLATION`).

    Returns
    -------
    ArmcalWarning or None
        None without loads, for a calibration whose training rows are not known or
        carried no payload, or within the bound.
    """
    training = cal.training_rows
    default = cal.model.default_payload_kg
    if loads is None or training is None or default is None:
        return None
    seen = np.array([default]) if training.loads is None else training.loads.payload_kg
    lightest, heaviest = float(np.min(seen)), float(np.max(seen))
    asked = float(np.max(loads.payload_kg))
    if heaviest <= 0.0 or asked <= PAYLOAD_EXTRAPOLATION * heaviest:
        return None
    ratio = asked / heaviest
    range_ = f"{heaviest:g} kg" if lightest == heaviest else f"{lightest:g} to {heaviest:g} kg"
    hint = ""
    if _unit_named(ratio) is not None:
        hint = f"; if the payloads are not in kg, {_unit_hint(ratio)}"
    return ArmcalWarning(
        "payload-extrapolated",
        f"{source}: payloads up to {asked:g} kg, {ratio:.4g} times the largest the "
        f"calibration was fitted under ({range_}): the deflection "
        "there is the compliance model extrapolated, which no measurement checked; "
        f"calibrate with poses under payloads up to the ones used{hint}",
    )
