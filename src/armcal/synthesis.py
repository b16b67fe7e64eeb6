"""Measurements of a virtual robot: the one place armcal draws measurement noise.

``armcal synthesize``, ``armcal demo`` and the Monte Carlo of
:mod:`armcal.simulate` all call :func:`synthesize_measurements`: instrument noise
``N(0, Sigma_meas)`` and encoder noise through the exact points at the joints'
true readings (the noise model of :mod:`armcal.noise`), for any model
(:class:`~armcal.models.interface.FitModel`).

One rule for ``sigma`` everywhere here (as ``--sigma`` on the command line):
given, it is the instrument's isotropic noise and replaces the model's
instrument covariance, the encoder noise kept; omitted, the model's noise is
used as it is (:func:`simulated_noise`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArmcalError
from .models import FitModel, Loads
from .noise import NoiseModel, instrument_override, per_row_sigma

__all__ = [
    "checked_truth",
    "simulated_noise",
    "synthesize_measurements",
]


def simulated_noise(model: FitModel, sigma: float | None) -> NoiseModel:
    """The noise model a simulation of ``model`` draws from, with ``sigma`` as the instrument.

    ``sigma`` (mm) overrides the instrument, as ``--sigma`` does: the
    instrument covariance becomes ``sigma^2 I`` and the arm's encoder noise
    stays (:meth:`armcal.noise.NoiseModel.with_instrument_sigma`).  Without
    ``sigma`` the arm's own noise model is used as it is: its instrument
    covariance (isotropic, per axis or full) and its encoder noise.

    Parameters
    ----------
    model : FitModel
    sigma : float or None
        Isotropic instrument noise (1 std, mm), positive and finite, or None.

    Returns
    -------
    NoiseModel

    Raises
    ------
    ArmcalError
        If ``sigma`` is not positive and finite, or is None and the arm has no
        noise model.

    Examples
    --------
    >>> from armcal.noise import NoiseModel
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([2.0, 1.0], noise=NoiseModel.per_axis(0.08, 0.02, joint_sigma=1e-4))
    >>> simulated_noise(arm, None) is arm.noise
    True
    >>> noise = simulated_noise(arm, 0.05)
    >>> noise.covariance_mm2.round(6).tolist(), noise.joint_sigma.tolist()
    ([[0.0025, 0.0], [0.0, 0.0025]], [0.0001])
    """
    if sigma is None:
        if model.noise is None:
            raise ArmcalError(
                f"no measurement noise to simulate for {model.name}: give the instrument "
                "sigma (mm), or a [measurement] table in the robot file"
            )
        return model.noise
    if not (math.isfinite(sigma) and sigma > 0):
        raise ArmcalError(
            f"the instrument noise sigma must be positive and finite (mm), got {sigma}"
        )
    return instrument_override(model.noise, sigma)


def checked_truth(model: FitModel, truth: ArrayLike) -> np.ndarray:
    """``truth`` as floats ``(p,)``; ArmcalError unless it is that shape and finite."""
    values = np.asarray(truth, dtype=float)
    names = model.param_names
    what = "deviations" if model.nested is None else "values"  # an effect's are not deviations
    if values.shape != (len(names),) or not np.all(np.isfinite(values)):
        raise ArmcalError(
            f"the truth must hold {len(names)} finite {what} ({', '.join(names)}), "
            f"got {values.tolist()}"
        )
    return values


def _instrument_factor(
    model: FitModel,
    sigma: float | None,
    row_sigma: np.ndarray | None,
    m: int,
    clean: Callable[[], np.ndarray],
) -> float | np.ndarray:
    """What multiplies standard normal draws ``z`` ``(..., m, d)`` into instrument noise.

    A number ``s`` (isotropic: ``s z``), a lower-triangular ``L`` ``(d, d)`` with
    ``L L^T = Sigma_meas`` (``L z`` per pose), per-row ``s_i`` ``(m, 1)``, or
    per-row ``L_i`` ``(m, d, d)`` for a laser tracker, whose noise depends on
    where the noiseless points ``clean()`` are, and for a 6-DoF instrument, whose
    orientation noise comes with the position's.
    """
    oriented = model.point_dim > model.position_dim
    rows = None
    if row_sigma is not None:
        rows = np.asarray(row_sigma, dtype=float)
        if rows.shape != (m,) or not np.all(np.isfinite(rows) & (rows > 0)):
            raise ArmcalError(
                f"row_sigma must hold one positive, finite sigma (mm) per pose, shape ({m},), "
                f"got shape {rows.shape}"
            )
    rows = per_row_sigma(sigma, rows)  # a given sigma replaces them, as in a fit
    if rows is not None:
        if not oriented:
            return rows[:, None]
    elif sigma is not None:
        if not (math.isfinite(sigma) and sigma >= 0):
            raise ArmcalError(f"the noise sigma must be finite and >= 0 (mm), got {sigma}")
        if not oriented or sigma == 0:
            return float(sigma)  # exactly as given: the same draws give the same data as ever
    noise = simulated_noise(model, sigma if rows is None else None)
    if oriented:
        where = clean()[..., : model.position_dim] if noise.tracker is not None else None
        cov = noise.instrument_covariances((m,), row_sigma=rows, points=where, oriented=True)
        return np.linalg.cholesky(cov)
    if noise.tracker is not None:
        return np.linalg.cholesky(noise.instrument_covariances((m,), points=clean()))
    if noise.isotropic_instrument:
        return float(np.sqrt(noise.covariance_mm2[0, 0]))
    return np.linalg.cholesky(noise.covariance_mm2)


def _scale_instrument(z: np.ndarray, factor: float | np.ndarray) -> None:
    """Turn standard normal draws ``z`` ``(..., m, d)`` into instrument noise, in place."""
    if np.ndim(factor) == 2 and np.shape(factor) == (2, 2):
        lower = np.asarray(factor)
        # (x, y) = L (z0, z1) with L lower triangular: y first, while z0 is still z0.
        z[..., 1] *= lower[1, 1]
        z[..., 1] += lower[1, 0] * z[..., 0]
        z[..., 0] *= lower[0, 0]
    elif np.ndim(factor) == 2 and np.shape(factor)[0] == np.shape(factor)[1]:
        z[...] = z @ np.asarray(factor).T
    elif np.ndim(factor) == 3:  # one factor per row
        z[...] = np.einsum("mij,...mj->...mi", factor, z)
    else:
        z *= factor


def synthesize_measurements(
    model: FitModel,
    plan: ArrayLike,
    truth: ArrayLike,
    sigma: float | None = None,
    *,
    rng: np.random.Generator | int | None = None,
    trials: int | None = None,
    row_sigma: np.ndarray | None = None,
    target: ArrayLike | None = None,
    loads: Loads | None = None,
    exact: np.ndarray | None = None,
    frames: np.ndarray | None = None,
    feature: np.ndarray | None = None,
) -> np.ndarray:
    """Measurements of a virtual robot: points at ``truth`` drawn from the noise model.

    The one place where armcal draws measurement noise (``armcal synthesize``,
    ``armcal demo`` and :func:`armcal.simulate.monte_carlo` all call it).

    Parameters
    ----------
    model : FitModel
        The nominal model (a :class:`~armcal.models.planar.arm.PlanarArm`, a
        :class:`~armcal.models.planar.compliance.CompliantArm`); its noise model gives the
        shape of the instrument noise and the encoder noise.
    plan : ndarray, shape (m, n)
        Joint angles in rad, as the controller reports them.
    truth : ndarray, shape (p,)
        Parameters of the virtual robot (internal units: mm, rad, ...).
    sigma : float, optional
        Isotropic instrument noise (1 std, mm) that overrides the model's
        instrument covariance and any ``row_sigma``, as ``--sigma`` does; the
        encoder noise stays, and so does the orientations' (a 6-DoF instrument's,
        the rows of partial coordinates that read a turn).  0 gives no instrument
        noise at all.  Without it the model's noise is used as it is (see
        :func:`simulated_noise`).
    rng : numpy.random.Generator or int or None
        Noise source.
    trials : int, optional
        Draw this many independent measurement sets at once.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), for instruments that report each point's
        uncertainty: pose ``i`` gets ``s_i^2 I`` in place of the instrument
        covariance; a given ``sigma`` replaces them (the one rule of
        :func:`armcal.noise.per_row_sigma`, as in :func:`armcal.identify`).
    target : ndarray of int or sequence of str, shape (m,), optional
        The target every row measures, on an arm with several: its index or its label.
    loads : Loads, optional
        Every row's payload and tip force (a model of joint compliance; default:
        the robot file's payload).
    exact : ndarray, shape (m, d), optional
        The noiseless points at ``truth`` when the caller has them already: a
        Monte Carlo draws many chunks of trials of one plan, and evaluating the
        arm once instead of per chunk keeps its cost linear in the plan's size.
        Ignored with encoder noise, whose points are at ``q + dq``.
    frames : ndarray, shape (m, 3, 3), optional
        For a model that measures orientations (a 6-DoF instrument), the rows'
        reference orientations (:attr:`armcal.models.Conditions.frames`): the
        points' orientations are turns from them, and their noise is drawn as
        such turns (the instrument's noise where the frames are the true
        orientations, :meth:`armcal.models.FitModel.anchor`).
    feature : ndarray of int, shape (m,), optional
        For an instrument of several features (:mod:`armcal.instruments`): the one
        every row touches (:attr:`armcal.models.Conditions.feature`).

    Returns
    -------
    ndarray, shape (m, d) or (trials, m, d)
        Measured points in mm.

    Raises
    ------
    ArmcalError
        If there is no noise to draw (no ``sigma``, ``row_sigma`` or noise
        model), or ``sigma``/``row_sigma`` are negative or not finite.

    Notes
    -----
    Instrument noise is ``N(0, Sigma_meas)``, drawn as ``L z`` with
    ``L L^T = Sigma_meas`` (Cholesky) and ``z`` standard normal; isotropic
    noise is ``sigma z``, the draws armcal has always made, so a seed gives the
    same data as before noise models existed.

    Encoder noise (``joint_sigma`` of the noise model) is errors in variables:
    the controller reports ``q`` but the arm was at ``q + dq`` with
    ``dq ~ N(0, diag(sigma_q^2))`` per pose, so the clean position is the exact
    ``p(q + dq, truth)``, not its linearization.  To first order the measured
    position then has the covariance ``Sigma_meas + J_q diag(sigma_q^2) J_q^T``
    that identification and the criteria assume
    (:meth:`armcal.noise.NoiseModel.pose_covariances`).  With encoder noise each
    pose draws ``d + n`` standard normals at once (instrument, then joints), in
    trial order, so sets drawn in chunks of trials equal those drawn at once.

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([2.0, 1.0])
    >>> synthesize_measurements(arm, np.zeros((1, 2)), np.zeros(4), 0.0).tolist()
    [[3.0, 0.0]]
    """
    rng = np.random.default_rng(rng)
    plan = np.asarray(plan, dtype=float)
    n, dim = model.n_joints, model.point_dim
    if plan.ndim != 2 or plan.shape[1] != n:
        raise ArmcalError(f"the plan must have shape (m, {n}) in rad, got {plan.shape}")
    truth = checked_truth(model, truth)
    if sigma is not None and sigma > 0 and row_sigma is None and model.reads_turns:
        # a sigma in mm is the coordinates': rows that read a turn keep the robot file's
        # (rad), as identify's --sigma does and as a 6-DoF instrument's orientations do
        model, sigma = model.with_noise(instrument_override(model.noise, sigma)), None
    rows = model.conditions(plan, target=target, loads=loads, feature=feature)
    conditions = rows.with_frames(frames)
    m = plan.shape[0]

    @cache
    def noiseless() -> np.ndarray:  # evaluated once, and only where needed
        return model.positions(conditions, truth) if exact is None else exact

    if row_sigma is None:  # the rows' own, where the model gives them (a feature's sigma)
        row_sigma = rows.sigma_mm
    factor = _instrument_factor(model, sigma, row_sigma, m, noiseless)
    joint_sigma = None if model.noise is None else model.noise.joint_sigma
    sets = () if trials is None else (int(trials),)
    if joint_sigma is None:
        clean = noiseless()
        noisy = rng.standard_normal((*sets, m, dim))
        _scale_instrument(noisy, factor)  # in place: the noise is a Monte Carlo's largest array
        noisy += clean
        return noisy
    draws = rng.standard_normal((*sets, m, dim + n))
    actual = draws[..., dim:]  # where the joints really were: q + dq
    actual *= np.broadcast_to(joint_sigma, (n,))
    actual += plan
    at = replace(conditions, q=actual, sigma_mm=None)
    positions = model.positions(at, truth)
    instrument = draws[..., :dim]
    _scale_instrument(instrument, factor)
    positions += instrument
    return positions
