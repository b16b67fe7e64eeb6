"""The result of an identification: :class:`Calibration`, and a parameter by name.

A calibration holds the model it was made for, the estimate and its
covariance, the residuals and the judgement of the fit (goodness of fit,
outliers, warnings).  Internal units (mm, rad) in the arrays; the properties
:attr:`~Calibration.values`, :attr:`~Calibration.std` and indexing by name
(``cal["dl1"]``) give display units (mm, deg) with the unit.

Two root-mean-squares of residuals are in use, and every name says which:
*per coordinate* (``sqrt(mean(e_x^2, e_y^2, ...))``, comparable with sigma)
and *per point* (``sqrt(mean |e_i|^2)``, the Euclidean error of a point,
``sqrt(d)`` times larger for noise alike on every axis).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..errors import ArmcalWarning
from ..models import CalibratedArm, Conditions, Effect, FitModel, Plane
from ..notebook import html_table, number
from ..numerics import point_norms, rms
from .judgement import GoodnessOfFit, Outlier, row_noun
from .problem import sigma_parts, sigma_words
from .registration import Baseline

__all__ = [
    "STRONG_CORRELATION",
    "Calibration",
    "Estimate",
    "NestedFit",
    "calibrated_arm",
]

#: The correlation of two estimates beyond which a report names the pair (|r|).
STRONG_CORRELATION = 0.9


@dataclass(frozen=True)
class Estimate:
    """One identified parameter in display units.

    Attributes
    ----------
    name : str
    value : float
    std : float
        Its standard error (0 for a fixed parameter).
    unit : str
    fixed : bool
        Held at its nominal value, not identified.

    Examples
    --------
    >>> Estimate("dl1", 0.8031, 0.0167, "mm", False)
    dl1 = 0.8031 ± 0.0167 mm
    """

    name: str
    value: float
    std: float
    unit: str
    fixed: bool = False

    def __repr__(self) -> str:
        spread = "fixed" if self.fixed else f"± {self.std:.3g}"
        return f"{self.name} = {self.value:.6g} {spread} {self.unit}"


@dataclass(frozen=True)
class NestedFit:
    """What a model's effect bought: the fit of the same data without it.

    Attributes
    ----------
    effect : Effect
        What the model adds to its nested model, in words.
    names : tuple of str
        The effect's parameters.
    rms_per_coordinate_mm : float
        Residual RMS per coordinate of the fit without the effect, on the same poses.
    p_value : float or None
        The nested-model F test (:func:`~armcal.identification.judgement.nested_test`):
        small when the data show the effect; None when there is nothing to test.
    """

    effect: Effect
    names: tuple[str, ...]
    rms_per_coordinate_mm: float
    p_value: float | None


@dataclass(frozen=True, eq=False)
class Calibration:
    """Identified parameters with their uncertainty, the fit's residuals and its judgement.

    Attributes
    ----------
    model : FitModel
        The model calibrated, with the noise model and fixed parameters used.
    method : str
        Solver used: ``"closed-form"`` or ``"gauss-newton"``.
    params : ndarray, shape (p,)
        Parameters in internal units (mm, rad, ...); 0 for fixed ones.
    covariance : ndarray, shape (p, p)
        ``sigma^2 (J_w^T J_w)^-1`` over the free parameters in internal units,
        zero rows and columns for fixed ones.
    sigma_mm : float
        Measurement noise (1 std, mm) used for ``covariance``: the noise model's
        reference (:attr:`armcal.noise.NoiseModel.sigma_mm`), or estimated.
    sigma_source : {"given", "estimated"}
        Whether the noise was given (robot file, ``sigma``, per-row sigma) or
        estimated as ``sqrt(RSS / (d m - p_f))``.
    residuals : ndarray, shape (m, d)
        Measured minus fitted points in mm, for every pose.
    iterations : int
        Linearized solves (1 for the closed form).
    converged : bool
        Whether the solver met its tolerance.
    pose_labels : tuple of str
        A label for every pose (the measurement file's ``pose`` column, or 1..m).
    warnings : tuple of ArmcalWarning
        What makes the result suspicious (codes ``fit-inconsistent``,
        ``few-dof``, ``outlier``, ``ill-conditioned``, ``not-converged``, ...).
    goodness_of_fit : GoodnessOfFit or None
        The chi-square test over the poses in the fit.
    standardized_residuals : ndarray, shape (m, d) or None
        ``W_i e_i / sigma`` of every pose: ``N(0, I)`` under the noise model.
    outliers : tuple of Outlier
        Poses the studentized test flags, removed from the fit or not.
    used : ndarray of bool, shape (m,) or None
        Poses in the final fit (all unless a robust fit left outliers out).
    rows : tuple of int
        1-based data row of every pose in its file.
    robust : bool
        Whether the fit was robust (Huber, then the outlier test and a refit).
    conditions : Conditions or None
        The rows' joint readings, targets, loads and per-row noise.
    plane : Plane or None
        The plane of motion fitted to 3-D instrument data, in whose coordinates
        ``residuals`` and the base pose are; None otherwise.
    nested : NestedFit or None
        For a model with an effect (joint compliance): the fit without it.
    details : dict
        What the model reports of the fit besides its parameters
        (:meth:`~armcal.models.interface.FitModel.fit_details`).
    baseline : Baseline or None
        The nominal arm registered on its own to the same rows
        (:func:`~armcal.identification.registration.register_nominal`): what a user
        has without calibrating, against which validation judges the calibration.
    """

    model: FitModel
    method: str
    params: np.ndarray
    covariance: np.ndarray
    sigma_mm: float
    sigma_source: Literal["given", "estimated"]
    residuals: np.ndarray
    iterations: int
    converged: bool
    pose_labels: tuple[str, ...]
    warnings: tuple[ArmcalWarning, ...] = ()
    goodness_of_fit: GoodnessOfFit | None = None
    standardized_residuals: np.ndarray | None = None
    outliers: tuple[Outlier, ...] = ()
    used: np.ndarray | None = None
    rows: tuple[int, ...] = ()
    robust: bool = False
    conditions: Conditions | None = None
    plane: Plane | None = None
    nested: NestedFit | None = None
    details: dict[str, np.ndarray] = field(default_factory=dict)
    baseline: Baseline | None = None

    def __repr__(self) -> str:
        used = f"{self.n_used} of {self.n_poses}" if self.n_used < self.n_poses else self.n_poses
        codes = f", warnings {[w.code for w in self.warnings]}" if self.warnings else ""
        return (
            f"Calibration({self.model.name}: {used} {row_noun(self.target)}, {self.n_free} "
            f"free parameters, {self.method}, sigma {self.sigma_text} ({self.sigma_source}), "
            f"residual RMS {self.residual_rms:.4g} mm per coordinate{codes})"
        )

    def _repr_html_(self) -> str:
        """The repr over a table of the parameters (value, std, unit in display units),
        and the warnings below it: what a notebook shows."""
        rows = [
            [e.name, number(e.value, 6), "fixed" if e.fixed else number(e.std, 3), e.unit]
            for e in self.parameters
        ]
        notes = [f"warning {w.code}: {w.message}" for w in self.warnings]
        return html_table(repr(self), ["parameter", "value", "std", "unit"], rows, notes=notes)

    def calibrated(self) -> CalibratedArm:
        """The model with these parameters, for validation, compensation and export."""
        rows = self.conditions
        if rows is not None and self.used is not None:
            rows = rows.take(np.asarray(self.used, dtype=bool))
        baseline = None if self.baseline is None else self.baseline.params
        return CalibratedArm(
            self.model, self.params, self.covariance, self.sigma_mm, self.plane, rows, baseline
        )

    def __getitem__(self, name: str) -> Estimate:
        """A parameter by name, in display units: ``cal["dl1"]``."""
        names = self.names
        if name not in names:
            raise KeyError(f"no parameter {name!r}; the parameters are {', '.join(names)}")
        i = names.index(name)
        return Estimate(
            name,
            float(self.values[i]),
            float(self.std[i]),
            self.units[i],
            name in self.model.fixed,
        )

    @property
    def parameters(self) -> tuple[Estimate, ...]:
        """Every parameter by name, value, std and unit (display units)."""
        return tuple(self[name] for name in self.names)

    @property
    def arm(self) -> Any:
        """The geometric arm of the model."""
        return self.model.arm

    @property
    def target(self) -> np.ndarray | None:
        """Every pose's target (index into the arm's targets), on an arm with several."""
        return None if self.conditions is None else self.conditions.target

    @property
    def n_free(self) -> int:
        """Free parameters of the fit."""
        return self.model.n_free

    @property
    def n_poses(self) -> int:
        """Number of measured poses ``m`` (including any left out of the fit)."""
        return int(self.residuals.shape[0])

    @property
    def n_used(self) -> int:
        """Number of poses in the final fit."""
        return self.n_poses if self.used is None else int(np.count_nonzero(self.used))

    @property
    def dof(self) -> int:
        """Residual degrees of freedom ``d m_used - p_f``."""
        return self.residuals.shape[1] * self.n_used - self.n_free

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names, e.g. ``dl1.., dq1.., (x0, y0)``, then any ``k1..``/``c1..``."""
        return self.model.param_names

    @property
    def units(self) -> tuple[str, ...]:
        """Display units of the parameters (``mm``, ``deg``, ``urad/(N*m)``, ``mdeg/m``)."""
        return self.model.param_units

    @property
    def display_scale(self) -> np.ndarray:
        """Internal to display units of every parameter in :attr:`names`."""
        return self.model.display_scale

    @property
    def values(self) -> np.ndarray:
        """Parameter values ``(p,)`` in display units (mm, deg)."""
        return self.params * self.display_scale

    @property
    def covariance_display(self) -> np.ndarray:
        """Covariance ``(p, p)`` in display units (mm, deg)."""
        s = self.display_scale
        return self.covariance * np.outer(s, s)

    @property
    def std(self) -> np.ndarray:
        """Standard errors ``(p,)`` in display units (mm, deg); 0 for fixed parameters."""
        return np.sqrt(np.diag(self.covariance_display))

    @property
    def correlation(self) -> np.ndarray:
        """Correlation matrix ``(p, p)`` of the estimates (identity rows for fixed ones)."""
        d = np.sqrt(np.diag(self.covariance))
        safe = np.where(d > 0, d, 1.0)
        corr = self.covariance / np.outer(safe, safe)
        fixed = d == 0
        corr[fixed, :] = 0.0
        corr[:, fixed] = 0.0
        corr[fixed, fixed] = 1.0
        return corr

    @property
    def pose_residuals(self) -> np.ndarray:
        """Euclidean residual of every pose's position ``(m,)`` in mm."""
        return point_norms(self.residuals[:, : self.model.position_dim])

    @property
    def sigma_text(self) -> str:
        """The noise in words: ``"0.01 mm"`` (the readings' unit); for rows of coordinates
        and turns each's, ``"0.01 mm a coordinate, 0.005 deg a turn"``."""
        parts = sigma_parts(self.model, self.conditions, self.sigma_mm)
        if parts is None:
            return f"{self.sigma_mm:.4g} {self.model.reading_unit}"
        return sigma_words(parts)

    @property
    def turn_rows(self) -> np.ndarray:
        """Which rows read an angle (rad) rather than a position (partial coordinates'
        turns, :meth:`~armcal.models.interface.FitModel.turn_rows`) ``(m,)``."""
        found = None if self.conditions is None else self.model.turn_rows(self.conditions)
        return np.zeros(self.n_poses, dtype=bool) if found is None else np.asarray(found)

    def _position_rows(self) -> np.ndarray:
        """The rows in the fit that read a position ``(m,)``."""
        used = np.ones(self.n_poses, dtype=bool) if self.used is None else self.used
        return used & ~self.turn_rows

    def _used_residuals(self) -> np.ndarray:
        return self.residuals[self._position_rows()]

    @property
    def residual_rms(self) -> float:
        """RMS of the residual position coordinates of the poses in the fit (per
        coordinate), mm."""
        return rms(self._used_residuals()[:, : self.model.position_dim])

    @property
    def orientation_residual_rms_deg(self) -> float | None:
        """For a 6-DoF instrument, RMS of the residual turns' coordinates (per coordinate),
        degrees (for partial coordinates, of the rows that read a turn); None for positions
        only."""
        turn = self.turn_rows
        if np.any(turn):
            used = turn if self.used is None else turn & self.used
            return float(np.degrees(rms(self.residuals[used])))
        turns = self._used_residuals()[:, self.model.position_dim :]
        return None if turns.shape[1] == 0 else float(np.degrees(rms(turns)))

    @property
    def residual_rms_per_point(self) -> float:
        """RMS of the Euclidean residuals of the positions of the poses in the fit (per
        point: ``sqrt(d)`` times :attr:`residual_rms` for noise alike on every axis), mm."""
        return rms(self.pose_residuals[self._position_rows()])

    @property
    def residual_max(self) -> float:
        """Largest Euclidean residual of a pose in the fit, mm."""
        return float(np.max(self.pose_residuals[self._position_rows()]))

    @property
    def worst_pose(self) -> int:
        """Index of the pose in the fit with the largest Euclidean residual."""
        kept = self.pose_residuals
        return int(np.argmax(np.where(self._position_rows(), kept, -1.0)))

    def strong_correlations(
        self, above: float = STRONG_CORRELATION
    ) -> list[tuple[str, str, float]]:
        """Pairs of parameters whose estimates correlate beyond ``above`` in magnitude."""
        corr = self.correlation
        off = np.abs(corr - np.eye(len(self.names)))
        pairs = zip(*np.nonzero(np.triu(off > above)), strict=True)
        return [(self.names[i], self.names[j], float(corr[i, j])) for i, j in pairs]


def calibrated_arm(cal: Calibration | CalibratedArm) -> CalibratedArm:
    """The calibrated arm of ``cal``: a :class:`Calibration`'s
    (:meth:`Calibration.calibrated`), or ``cal`` itself (one read from a calibration
    file), so that validation and compensation take what :func:`identify` returns."""
    return cal.calibrated() if isinstance(cal, Calibration) else cal
