"""Quality of a calibration plan: optimality criteria, predicted std and position error.

Every function here judges plans of any family of arm through its
:class:`~armcal.models.interface.PlanInformation`
(:meth:`~armcal.models.interface.FitModel.plan_information`): the normalized
information ``M`` of the model's *design coordinates* -- for the planar arm the
paper's Hadamard-normalized ``Fs`` (below) -- with unit measurement noise
unless ``sigma`` is given.  Plans are joint angles ``q`` (rad) of shape
``(m, n)``, or ``(..., m, n)`` where a family batches over plans.

**The paper's scaling.**  The information matrix ``F = sum_i J_i^T J_i`` (paper
eq. 16-19) in the paper's parametrization ``(dtheta, dl, [x0, y0])`` mixes mm^2
and mm^2/rad^2.  The planar arm's criteria are computed on the
*Hadamard-normalized* matrix

    Fs = D F D,   D = diag(1 / sqrt(F_opt)),   F_opt = diag(m l_i^2, m, [m, m])

where ``F_opt`` is the information matrix of an orthogonal plan (paper eq. 24,
Table II).  Since the diagonal of ``F`` is ``(m l_i^2, m, [m, m])`` for *every*
plan, ``Fs`` has a unit diagonal, and Hadamard's inequality gives
``det Fs <= 1`` with equality iff ``F`` is diagonal -- the paper's optimality
conditions (21).  So every efficiency below is 1 exactly for orthogonal plans
and smaller otherwise.

**One rank policy.**  ``M = H^T H`` with ``H`` the stacked whitened rows in
design coordinates divided by ``sqrt(R)``
(:meth:`~armcal.models.interface.PlanInformation.svd`): its singular values
alone decide, through :mod:`armcal.numerics`, whether a plan is identifiable,
its covariance, its efficiencies and observability indices, and whether results
carry an ``ill-conditioned`` warning.  They come from a thin QR of ``H``, never
from the eigenvalues of ``M``, which cannot resolve a relative singular value
below ``sqrt(eps) ~ 1e-8``.

**Models without the bound.**  Where some pose's information has a trace other
than ``p_f`` (:attr:`~armcal.models.interface.FitModel.information_bound` false:
encoder noise, fixed parameters that tie links together, joint compliance) the
criteria are the same functions of the weighted information, no longer 1 at the
optimum: they compare plans of one model, and the certificate of
:mod:`armcal.doe` says how far from the optimum a plan is.  The paper's
conditions (21), its D* and the orthogonal plans assume isotropic iid noise and
every parameter free (:meth:`~armcal.models.interface.FitModel.paper_criteria`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .errors import ArmcalWarning
from .models import (
    Conditions,
    FitModel,
    Identifiability,
    Loads,
    PaperCriteria,
    PlanInformation,
    position_jacobian,
)
from .models.information import (
    display_std,
    identified_or_prepared,
    mean_tip_variance,
    tip_variances,
)
from .models.wording import ill_conditioned_warning
from .notebook import html_table, number
from .numerics import COND_WARN, RANK_RTOL, gram_of_factor, log_det, spd_inverse

__all__ = [
    "COND_WARN",
    "CRITERIA",
    "RANK_RTOL",
    "Criterion",
    "PlanQuality",
    "PositionAccuracy",
    "attains_unit_bound",
    "d_efficiency",
    "efficiencies",
    "evaluate_plan",
    "observability_indices",
    "position_accuracy",
    "position_rms",
    "predicted_std",
]


def _eigvalsh(fs: np.ndarray) -> np.ndarray:
    return np.clip(np.linalg.eigvalsh(fs), 0.0, None)


@dataclass(frozen=True)
class Criterion:
    """A larger-is-better design criterion on the normalized information ``Fs``.

    Attributes
    ----------
    name : str
        Registry key (``"D"``, ``"A"``, ``"E"``).
    description : str
        Formula and source, for help texts and reports.
    efficiency : callable
        ``Fs (..., p, p) -> (...)``, 1 for orthogonal plans: the smooth objective
        of the optimizer.
    log_gradient : callable
        ``Fs (..., p, p) -> (..., p, p)``: the symmetric matrix gradient of
        ``log efficiency`` with respect to ``Fs`` (used by the optimizer).
    from_singular_values : callable
        ``s (..., p) -> (...)``: the same efficiency from the singular values of
        the plan's information
        (:meth:`~armcal.models.interface.PlanInformation.singular_values`; ``M`` has
        eigenvalues ``s^2``), with those the rank policy calls zero set to 0 --
        what every evaluation reports, so a plan that cannot identify every
        parameter has efficiency 0.
    """

    name: str
    description: str
    efficiency: Callable[[np.ndarray], np.ndarray]
    log_gradient: Callable[[np.ndarray], np.ndarray]
    from_singular_values: Callable[[np.ndarray], np.ndarray]


# The gradients invert Fs with spd_inverse, which cannot raise: the optimizer
# regularizes a singular Fs before asking, and other callers pass identifiable plans.


def _d_eff(fs: np.ndarray) -> np.ndarray:
    return np.exp(log_det(fs) / fs.shape[-1])


def _d_grad(fs: np.ndarray) -> np.ndarray:
    return spd_inverse(fs) / fs.shape[-1]


def _d_from_s(s: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return np.exp(2.0 * np.mean(np.log(s), axis=-1))  # 0 when a value is 0


def _a_eff(fs: np.ndarray) -> np.ndarray:
    values = _eigvalsh(fs)
    with np.errstate(divide="ignore"):
        return fs.shape[-1] / np.sum(1.0 / values, axis=-1)  # 0 when singular


def _a_grad(fs: np.ndarray) -> np.ndarray:
    inv = spd_inverse(fs)
    inv2 = inv @ inv
    return inv2 / np.trace(inv, axis1=-2, axis2=-1)[..., None, None]


def _a_from_s(s: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return s.shape[-1] / np.sum(1.0 / s**2, axis=-1)  # 0 when a value is 0


def _e_eff(fs: np.ndarray) -> np.ndarray:
    return _eigvalsh(fs)[..., 0]


def _e_grad(fs: np.ndarray) -> np.ndarray:
    values, vectors = np.linalg.eigh(fs)
    v = vectors[..., :, 0]
    # The smallest eigenvalue, floored like spd_inverse's: eigh knows it to p eps lambda_max.
    floor = fs.shape[-1] * np.finfo(float).eps * values[..., -1]
    smallest = np.maximum(values[..., 0], np.maximum(floor, np.finfo(float).tiny))
    return v[..., :, None] * v[..., None, :] / smallest[..., None, None]


def _e_from_s(s: np.ndarray) -> np.ndarray:
    return np.min(s, axis=-1) ** 2


#: The design criteria by name, on the normalized information ``M`` of the model's
#: design coordinates: 1 for the paper's orthogonal plans of its model.
CRITERIA: dict[str, Criterion] = {
    "D": Criterion(
        "D",
        "D-efficiency (det Fs)^(1/p): volume of the confidence ellipsoid (Kiefer 1959)",
        _d_eff,
        _d_grad,
        _d_from_s,
    ),
    "A": Criterion(
        "A",
        "A-efficiency p / tr(Fs^-1): mean variance of the scaled parameters",
        _a_eff,
        _a_grad,
        _a_from_s,
    ),
    "E": Criterion(
        "E",
        "E-efficiency lambda_min(Fs): worst-determined direction of the scaled parameters",
        _e_eff,
        _e_grad,
        _e_from_s,
    ),
}


def _information(
    model: FitModel, q: np.ndarray, loads: Loads | None, info: PlanInformation | None
) -> PlanInformation:
    return model.plan_information(np.asarray(q, dtype=float), loads) if info is None else info


def efficiencies(
    model: FitModel,
    q: np.ndarray,
    loads: Loads | None = None,
    *,
    info: PlanInformation | None = None,
) -> dict[str, np.ndarray]:
    """Every criterion of :data:`CRITERIA` for plans ``q`` ``(..., m, n)``, by name.

    From the singular values of the plan's information; 0 for a plan the rank
    policy calls singular.  ``info`` is the plan's information when the caller
    has it already.
    """
    s = _information(model, q, loads, info).singular_values()
    return {name: crit.from_singular_values(s) for name, crit in CRITERIA.items()}


def d_efficiency(
    model: FitModel,
    q: np.ndarray,
    loads: Loads | None = None,
    *,
    info: PlanInformation | None = None,
) -> np.ndarray:
    """D-efficiency ``(det M)^(1/p_f)`` of plans ``q`` ``(..., m, n)``.

    For the paper's model ``(det F / det F_opt)^(1/p)``: 1 exactly for plans
    meeting the paper's conditions (21); 0 for plans that cannot identify every
    parameter (the rank policy of :mod:`armcal.numerics`).

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> from armcal.doe import orthogonal_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> round(float(d_efficiency(arm, orthogonal_plan(arm, 20))), 12)
    1.0
    >>> float(d_efficiency(arm, np.zeros((6, 4))))   # six identical poses
    0.0
    """
    s = _information(model, q, loads, info).singular_values()
    return CRITERIA["D"].from_singular_values(s)


def attains_unit_bound(model: FitModel, q: np.ndarray, efficiency: float | None = None) -> bool:
    """Whether plan ``q`` ``(m, n)`` is provably D-optimal: the bound ``det M <= 1`` holds
    (:attr:`~armcal.models.interface.FitModel.information_bound`) and ``M = I``.

    ``M = I`` is judged on the D-efficiency (``efficiency`` when the caller has it),
    to the round-off of its ``m``-term sums (``m eps``).
    """
    if not model.information_bound:
        return False
    tol = 1e-12 + np.shape(q)[-2] * np.finfo(float).eps
    if efficiency is None:
        efficiency = float(d_efficiency(model, q))
    return efficiency >= 1.0 - tol


def observability_indices(
    model: FitModel,
    q: np.ndarray,
    loads: Loads | None = None,
    *,
    info: PlanInformation | None = None,
) -> dict[str, np.ndarray]:
    """Observability indices on the singular values of the plan's normalized rows.

    With ``s_1 >= ... >= s_p`` the singular values of ``H`` (for the paper's
    model ``J D / sqrt(m)``, ``D`` the Hadamard scaling, so ``s_i = sqrt(eig(Fs))``
    and all equal 1 at the optimum):

    * ``O1 = (s_1 ... s_p)^(1/p)`` (Borm & Menq 1991; equals ``sqrt(D-efficiency)``),
    * ``O2 = s_p / s_1``, the inverse condition number (Driels & Pathre 1990),
    * ``O3 = s_p``, the minimum singular value (Nahvi et al. 1994),
    * ``O4 = s_p^2 / s_1``, the noise amplification index (Nahvi & Hollerbach 1996).

    All are larger-is-better and 1 for orthogonal plans; all are 0 for a plan
    the rank policy calls singular.
    """
    s = _information(model, q, loads, info).singular_values()
    with np.errstate(divide="ignore"):
        return {
            "O1": np.exp(np.mean(np.log(s), axis=-1)),
            "O2": s[..., -1] / s[..., 0],
            "O3": s[..., -1],
            "O4": s[..., -1] ** 2 / s[..., 0],
        }


def _covariance(info: PlanInformation, sigma: float, params: np.ndarray | None = None):
    """``sigma^2 (J_w^T J_w)^-1`` ``(..., p, p)`` of the plans (internal units), ``inf``
    where singular, and the identifiable mask."""
    g, ok = info.covariance_factor(params)
    return sigma**2 * gram_of_factor(g, ok), ok


def predicted_std(
    model: FitModel,
    q: np.ndarray,
    sigma: float,
    params: np.ndarray | None = None,
    *,
    loads: Loads | None = None,
    info: PlanInformation | None = None,
) -> np.ndarray:
    """Predicted standard errors of the parameters in display units (mm, deg, ...).

    Parameters
    ----------
    model : FitModel
    q : ndarray, shape (..., m, n)
        Plans (rad); leading axes batch over plans where the family does.
    sigma : float
        Measurement noise (1 std, mm): the reference noise of a weighted model.
    params : ndarray, shape (p,), optional
        Deviations at which to linearize (nominal when omitted).
    loads : Loads, optional
        Every pose's loads, for a model whose points depend on them.
    info : PlanInformation, optional
        The plans' information when the caller has it already.

    Returns
    -------
    ndarray, shape (..., p)
        ``sqrt(diag(sigma^2 (J_w^T J_w)^-1))``; 0 for a fixed parameter, ``inf``
        where the plan cannot identify the parameters.
    """
    covariance, _ = _covariance(_information(model, q, loads, info), sigma, params)
    return display_std(model, covariance)


@dataclass(frozen=True)
class PositionAccuracy:
    """Predicted end-effector position error after calibration at test poses.

    Every figure is the RMS error *per point* (the root of the trace of a
    point's covariance, both coordinates together), not per coordinate.

    Attributes
    ----------
    rms_mm : float
        ``sqrt(mean_x sigma^2 tr(J0(x) F^-1 J0(x)^T))``: RMS over the test poses.
    max_mm : float
        The same at the worst test pose.
    per_pose_mm : ndarray, shape (k,)
        Predicted RMS error at each test point (every target of every test pose).
    """

    rms_mm: float
    max_mm: float
    per_pose_mm: np.ndarray


def position_accuracy(
    model: FitModel,
    q: np.ndarray,
    test_q: np.ndarray,
    sigma: float,
    *,
    loads: Loads | None = None,
    info: PlanInformation | None = None,
) -> PositionAccuracy:
    """Predicted positioning accuracy after calibration with plan ``q`` at poses ``test_q``.

    Parameters
    ----------
    model : FitModel
    q : ndarray, shape (m, n)
        The calibration plan (rad).
    test_q : ndarray, shape (k, n)
        Poses where the calibrated arm will work (rad), every target of each.
    sigma : float
        Measurement noise (1 std, mm).
    loads : Loads, optional
        The plan's loads, for a model whose points depend on them.
    info : PlanInformation, optional
        The plan's information when the caller has it already.

    Returns
    -------
    PositionAccuracy

    Notes
    -----
    The error of the predicted tip position at ``x`` has covariance
    ``sigma^2 J0(x) F^-1 J0(x)^T`` (:func:`armcal.models.information.tip_variances`);
    its trace is the mean squared position error.  For an arm measured by an
    instrument other than a tracker, ``J0`` is the arm's own tool point's in the frame
    the instrument is placed in, ``F^-1`` the arm's block of the covariance
    (:meth:`~armcal.models.interface.FitModel.alone`): what the instrument cannot see
    is held, and not in the figure.  For an orthogonal plan of the
    paper's model it equals ``2 n sigma^2 / m`` at every pose
    (``2 (n + 1) sigma^2 / m`` with a base offset).

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter.
    """
    info = _information(model, q, loads, info)
    info.check_identifiable()
    covariance, _ = _covariance(info, sigma)
    # The arm's own tool points: an instrument's readings are not where the arm is
    # (a touch's error along a normal is not the tool's error in 3-D).
    arm, _, covariance = model.alone(np.zeros(model.n_params), covariance)
    j0 = position_jacobian(arm, arm.plan_conditions(np.asarray(test_q, dtype=float)))
    per_pose = np.sqrt(tip_variances(j0, covariance))
    return PositionAccuracy(
        float(np.sqrt(np.mean(per_pose**2))), float(np.max(per_pose)), per_pose
    )


def position_rms(
    model: FitModel,
    q: np.ndarray,
    test_q: np.ndarray,
    sigma: float,
    *,
    loads: Loads | None = None,
    info: PlanInformation | None = None,
) -> float:
    """Predicted RMS position error per point after calibration with plan ``q`` over
    ``test_q`` (every target of every test pose); ``inf`` for a plan that cannot identify
    every parameter.

    ``sigma sqrt(mean_x tr(J(x) F^-1 J(x)^T))``
    (:func:`armcal.models.information.mean_tip_variance`).
    """
    g, ok = _information(model, q, loads, info).covariance_factor()
    if not bool(ok):
        return math.inf
    inverse = gram_of_factor(g, ok)
    j0 = position_jacobian(model, model.plan_conditions(np.asarray(test_q, dtype=float)))
    return float(sigma * np.sqrt(mean_tip_variance(j0, inverse)))


@dataclass(frozen=True, eq=False)
class PlanQuality:
    """Everything known about a plan before measuring, for a given noise level.

    Attributes
    ----------
    model : FitModel
        The model judged (its noise model, fixed parameters and loads).
    n_poses : int
    sigma_mm : float
        Measurement noise assumed (mm).
    efficiencies : dict of str to float
        D, A, E efficiencies (1 for orthogonal plans of the paper's model).
    observability : dict of str to float
        O1..O4 (see :func:`observability_indices`).
    predicted_std : ndarray, shape (p,)
        Standard errors of the parameters in display units (0 for a fixed one).
    position : PositionAccuracy or None
        Predicted positioning accuracy after calibration at the test poses
        (None without test poses).
    warnings : tuple of ArmcalWarning
        An ``ill-conditioned`` warning when the plan's condition number exceeds
        ``COND_WARN``; empty otherwise.
    paper : PaperCriteria or None
        The paper's D* and Table I sums, for the arms its theory covers.
    payload_counts : dict of float to int or None
        How many poses carry each payload (kg), for a model whose points
        depend on the load.
    """

    model: FitModel
    n_poses: int
    sigma_mm: float
    efficiencies: dict[str, float]
    observability: dict[str, float]
    predicted_std: np.ndarray
    position: PositionAccuracy | None
    warnings: tuple[ArmcalWarning, ...] = ()
    paper: PaperCriteria | None = None
    payload_counts: dict[float, int] | None = None

    @property
    def normalized(self) -> bool:
        """Whether the efficiencies are relative to an optimum of 1
        (:attr:`~armcal.models.interface.FitModel.information_bound`); otherwise they
        are criteria of the weighted information, comparing plans of one model."""
        return self.model.information_bound

    def __repr__(self) -> str:
        eff = self.efficiencies
        position = (
            ""
            if self.position is None
            else f"; predicted position RMS {self.position.rms_mm:.4g} mm per point"
        )
        return (
            f"PlanQuality({self.n_poses} poses, sigma {self.sigma_mm:g} mm: D {eff['D']:.4f}, "
            f"A {eff['A']:.4f}, E {eff['E']:.4f}{position})"
        )

    def _repr_html_(self) -> str:
        """The repr over a table of every parameter's predicted std (display units), and the
        warnings below it: what a notebook shows."""
        model = self.model
        rows = [
            [name, number(std, 3) if free else "fixed", unit]
            for name, std, unit, free in zip(
                model.param_names, self.predicted_std, model.param_units, model.free, strict=True
            )
        ]
        notes = [f"warning {w.code}: {w.message}" for w in self.warnings]
        return html_table(repr(self), ["parameter", "predicted std", "unit"], rows, notes=notes)

    def __getitem__(self, name: str) -> dict[str, float | str]:
        """A parameter by name: its predicted std and unit (display units; 0 when fixed).

        Examples
        --------
        >>> from armcal.models import PlanarArm
        >>> from armcal.doe import orthogonal_plan
        >>> arm = PlanarArm([260.0, 180.0])
        >>> plan = orthogonal_plan(arm, 16)
        >>> quality = evaluate_plan(arm, plan, sigma=0.1, test_q=np.zeros((0, 2)))
        >>> round(quality["dl2"]["predicted_std"], 12), quality["dl2"]["unit"]  # sigma/sqrt(m)
        (0.025, 'mm')
        """
        names = self.model.param_names
        if name not in names:
            raise KeyError(f"no parameter {name!r}; the parameters are {', '.join(names)}")
        i = names.index(name)
        return {
            "predicted_std": float(self.predicted_std[i]),
            "unit": self.model.param_units[i],
        }


def _identified_plan(
    model: FitModel, q: np.ndarray, loads: Loads | None, rows: Conditions | None = None
) -> tuple[FitModel, PlanInformation, Identifiability]:
    """The model the plan ``q`` (its ``rows``, when made) identifies, its information (one
    factorization serves every figure of :func:`evaluate_plan`) and identifiability.

    :func:`~armcal.models.information.identified_or_prepared`: at no cost where the plan
    identifies the model as given; a model it does not (a spatial arm as loaded,
    over-complete) is prepared for the plan's rows and checked there.
    NotIdentifiableError where the prepared model is not identified either.
    """
    rows = model.plan_conditions(q, loads) if rows is None else rows

    def check(it: FitModel) -> tuple[PlanInformation, Identifiability]:
        info = it.plan_information(q, loads, rows=rows)
        return info, info.check_identifiable()

    ready, (info, identified) = identified_or_prepared(model, rows, check)
    return ready, info, identified


def evaluate_plan(
    model: FitModel,
    q: np.ndarray,
    *,
    sigma: float,
    test_q: np.ndarray,
    loads: Loads | None = None,
    rows: Conditions | None = None,
) -> PlanQuality:
    """Criteria, predicted std and positioning accuracy of plan ``q`` ``(m, n)``.

    ``test_q`` ``(k, n)`` are the poses where positioning accuracy matters (none:
    no position figures); ``loads`` every pose's loads for a model whose points
    depend on them (default: the model's).  Every target of every pose is measured
    (:meth:`~armcal.models.interface.FitModel.plan_conditions`; ``rows``, made already,
    share what is memoized on them, as a model :meth:`prepared` for them left).  A model the plan
    does not identify as given is first prepared for it
    (:func:`~armcal.models.information.identifying`: a spatial arm as loaded holds
    what the plan cannot separate); :attr:`PlanQuality.model` is the model evaluated.

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every parameter: such a plan has no finite
        predicted accuracy to report.

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> from armcal.doe import orthogonal_plan, random_plan
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> quality = evaluate_plan(arm, orthogonal_plan(arm, 20), sigma=0.1,
    ...                         test_q=random_plan(arm, 50, rng=0))
    >>> bool(np.isclose(quality.position.rms_mm, 0.1 * np.sqrt(2 * 4 / 20), rtol=1e-12))
    True
    """
    q = np.asarray(q, dtype=float)
    model, info, identified = _identified_plan(model, q, loads, rows)
    warning = ill_conditioned_warning(model, identified)
    counts = None
    if model.default_payload_kg is not None:  # the points depend on the load
        payload = (
            np.full(q.shape[0], model.default_payload_kg) if loads is None else loads.payload_kg
        )
        values, numbers = np.unique(payload, return_counts=True)
        counts = {float(v): int(c) for v, c in zip(values, numbers, strict=True)}
    test_q = np.asarray(test_q, dtype=float)
    return PlanQuality(
        model=model,
        n_poses=int(q.shape[0]),
        sigma_mm=float(sigma),
        efficiencies={k: float(v) for k, v in efficiencies(model, q, info=info).items()},
        observability={k: float(v) for k, v in observability_indices(model, q, info=info).items()},
        predicted_std=predicted_std(model, q, sigma, info=info),
        position=(
            position_accuracy(model, q, test_q, sigma, info=info) if test_q.shape[0] else None
        ),
        warnings=() if warning is None else (warning,),
        paper=model.paper_criteria(q),
        payload_counts=counts,
    )
