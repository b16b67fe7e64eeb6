"""What a rigid export of a calibration with an effect loses, on the calibration's own rows.

A robot TOML or URDF holds geometry only: exported from a calibration with joint
compliance, it is the calibrated geometry without the twist of the joints.  That
geometry was fitted *with* the compliance, so alone it may fit the calibration's
rows worse than the nominal arm does.  :func:`rigid_export` says by how much, in
mm per point, against the calibrated model's own predictions at the rows it was
fitted to (noise-free, so every figure is the model's and none the instrument's):

* the exported geometry where the calibration placed the instrument and the
  targets (the points of the two models at the same parameters);
* the exported geometry with the instrument's pose and the targets fitted anew
  to those predictions, as a user of the file does when measuring with it (the
  export carries no instrument pose: it is the instrument's, not the robot's);
* the nominal arm so fitted: what the rows would give without calibrating.

The fits are Gauss-Newton on the registration alone
(:func:`~armcal.identification.registration.fit_registration`: the instrument's pose and
the targets), the rest held, started from the calibration's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ArmcalWarning, action
from .identification.registration import fit_registration
from .models import CalibratedArm, Conditions, FitModel
from .numerics import point_norms, rms

__all__ = [
    "WORSE_FACTOR",
    "RigidExport",
    "rigid_export",
    "rigid_export_warnings",
]

#: The exported geometry is called worse than the nominal arm when, registered, it misses
#: the rows by more than this factor of the nominal arm's RMS: a calibration of an arm
#: whose geometry is nominal exports it within its estimate's scatter, which changes the
#: RMS by 0.02 % to 0.11 % on the virtual six-axis cell of the tests (geometry nominal,
#: three noise seeds, lumped or masses known): 5 % clears that forty-fold.
WORSE_FACTOR = 1.05


@dataclass(frozen=True)
class RigidExport:
    """How far a rigid export of a calibration is from the calibration, on its own rows.

    Every figure is a distance to the calibrated model's predicted points at the
    calibration's rows, in mm per point (Euclidean), RMS and max.

    Attributes
    ----------
    rows : int
        The rows the calibration was fitted to.
    rms_per_point_mm, max_mm : float
        The exported (rigid) geometry, with the calibration's instrument pose and targets.
    registered_rms_per_point_mm, registered_max_mm : float
        The exported geometry, with the instrument's pose and the targets fitted anew.
    nominal_rms_per_point_mm, nominal_max_mm : float
        The nominal arm, with the instrument's pose and the targets fitted anew.
    """

    rows: int
    rms_per_point_mm: float
    max_mm: float
    registered_rms_per_point_mm: float
    registered_max_mm: float
    nominal_rms_per_point_mm: float
    nominal_max_mm: float

    @property
    def worse_than_nominal(self) -> bool:
        """Whether the exported geometry, registered, misses the rows clearly more than the
        nominal arm registered the same way (RMS per point, by :data:`WORSE_FACTOR`)."""
        return self.registered_rms_per_point_mm > WORSE_FACTOR * self.nominal_rms_per_point_mm

    def to_dict(self) -> dict[str, float | int | bool]:
        """JSON form: the attributes and ``worse_than_nominal``."""
        return {
            "rows": self.rows,
            "rms_per_point_mm": self.rms_per_point_mm,
            "max_mm": self.max_mm,
            "registered_rms_per_point_mm": self.registered_rms_per_point_mm,
            "registered_max_mm": self.registered_max_mm,
            "nominal_rms_per_point_mm": self.nominal_rms_per_point_mm,
            "nominal_max_mm": self.nominal_max_mm,
            "worse_than_nominal": self.worse_than_nominal,
        }


def _registered(
    model: FitModel, rows: Conditions, start: np.ndarray, reference: np.ndarray
) -> np.ndarray:
    """Every row's distance (mm) from ``reference`` ``(m, d)`` of ``model`` with its
    registration (instrument pose and targets) fitted, the others held at ``start``."""
    d = model.position_dim
    free = np.asarray(model.registration_params, dtype=bool) & np.asarray(model.free)
    fitted = fit_registration(model, rows, reference, np.asarray(start, dtype=float), free)
    params = np.asarray(start, dtype=float) if fitted is None else fitted
    return point_norms(reference[..., :d] - model.positions(rows, params)[..., :d])


def rigid_export(cal: CalibratedArm) -> RigidExport | None:
    """What exporting ``cal`` without its effect loses on the rows it was fitted to
    (module notes); None for a model without an effect or a calibration whose rows are
    not known (a file written before they were stored).

    Examples
    --------
    >>> from armcal.models import CompliantArm, Elastostatic, Loads, PlanarArm
    >>> arm = PlanarArm([500.0, 300.0])
    >>> elastic = Elastostatic.create(2, gravity_xy=[0, -1], link_masses_kg=[10.0, 4.0])
    >>> model = CompliantArm.for_loads(arm, elastic, Loads.create(1))
    >>> rows = model.conditions(np.radians([[0.0, 0.0], [90.0, 0.0]]))
    >>> k = np.array([0.0, 0.0, 0.0, 0.0, 2e-6, 0.0])  # joint 1: 2 urad/(N m)
    >>> cal = CalibratedArm(model, k, np.zeros((6, 6)), 0.01, training_rows=rows)
    >>> lost = rigid_export(cal)
    >>> # stretched level: 800 mm times 2e-6 rad/(N m) times (10 * 0.25 + 4 * 0.65) kg m * g
    >>> round(lost.max_mm, 6), round(800 * 2e-6 * 5.1 * 9.80665, 6)
    (0.080022, 0.080022)
    """
    model, rows = cal.model, cal.training_rows
    inner: Any = model.nested
    if inner is None or model.effect is None or rows is None or rows.m == 0:
        return None
    d = model.position_dim
    reference = model.positions(rows, cal.params)
    geometry = model.arm_params(cal.params)
    at_pose = point_norms(reference[..., :d] - inner.positions(rows, geometry)[..., :d])
    registered = _registered(inner, rows, geometry, reference)
    nominal = np.where(inner.registration_params, geometry, inner.held_values)
    nominal_fit = _registered(inner, rows, nominal, reference)
    return RigidExport(
        rows.m,
        rms(at_pose),
        float(np.max(at_pose)),
        rms(registered),
        float(np.max(registered)),
        rms(nominal_fit),
        float(np.max(nominal_fit)),
    )


def rigid_export_warnings(
    cal: CalibratedArm, loss: RigidExport | None = None
) -> list[ArmcalWarning]:
    """What any exported file of ``cal`` leaves out: ``{short}-not-exported`` (the effect's
    values, and ``loss`` where known: :func:`rigid_export`), and ``rigid-export-worse``
    when the exported geometry fits the calibration's rows worse than the nominal arm;
    none for a model without an effect."""
    model, effect, inner = cal.model, cal.model.effect, cal.model.nested
    if effect is None or inner is None:
        return []
    extra = inner.n_params + np.flatnonzero(model.free[inner.n_params :])  # fitted terms
    values = ", ".join(
        f"{model.param_names[i]} = {cal.params[i] * model.display_scale[i]:.4g} "
        f"{model.param_units[i]}"
        for i in extra
    )
    lost = ""
    if loss is not None:
        lost = (
            f"; on the calibration's {loss.rows} rows the rigid {effect.nested} misses the "
            f"calibrated model's points by {loss.rms_per_point_mm:.3g} mm RMS per point (max "
            f"{loss.max_mm:.3g} mm), {loss.registered_rms_per_point_mm:.3g} mm (max "
            f"{loss.registered_max_mm:.3g} mm) with the instrument's pose and the targets "
            f"fitted anew, where the nominal arm so fitted misses them by "
            f"{loss.nominal_rms_per_point_mm:.3g} mm (max {loss.nominal_max_mm:.3g} mm)"
        )
    warnings = [
        ArmcalWarning(
            f"{effect.short}-not-exported",
            f"the exported {effect.nested} is rigid: the {effect.name} ({values}) is not "
            f"part of a robot file or URDF{lost}; compensate programs with armcal "
            "compensate, which uses it",
        )
    ]
    if loss is not None and loss.worse_than_nominal:
        warnings.append(
            ArmcalWarning(
                "rigid-export-worse",
                f"the exported rigid {effect.nested} fits the calibration's own rows WORSE "
                f"than the nominal arm: {loss.registered_rms_per_point_mm:.3g} mm against "
                f"{loss.nominal_rms_per_point_mm:.3g} mm RMS per point, each with the "
                f"instrument's pose and the targets fitted anew (the {effect.nested} was "
                f"fitted together with the {effect.name}, which the file leaves out); for a "
                f"rigid robot file, {action('geometry-alone')} and export that calibration",
            )
        )
    return warnings
