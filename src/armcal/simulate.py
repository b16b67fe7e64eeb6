"""Simulated measurements, Monte Carlo accuracy studies and random-plan studies.

* :func:`synthesize_measurements` -- the one place noise is drawn: instrument
  noise ``N(0, Sigma_meas)`` and encoder noise through the exact tip at the
  joints' true angles (the noise model of :mod:`armcal.noise`);
* :func:`monte_carlo` -- ``N`` noisy measurement sets of one plan, identified
  together (one batched solve per chunk of trials), against the predicted
  covariance: ``sigma^2 (J^T J)^-1`` (paper eq. 16) for isotropic iid noise,
  the generalized-least-squares covariance of the free parameters otherwise;
* :func:`random_plan_study` -- the paper's Figure 1 criteria and the predicted
  accuracy of many random plans at once.

One rule for ``sigma`` everywhere here (as ``--sigma`` on the command line):
given, it is the instrument's isotropic noise and replaces the arm's
instrument covariance, the arm's encoder noise kept; omitted, the arm's noise
model is used as it is (:func:`simulated_noise`).

Memory is bounded by the chunk size, not by the number of trials: empirical
moments are merged chunk by chunk (Chan et al.'s pairwise update), the mean
square tip error follows exactly from a small second-moment matrix, and its
quantiles from a subsample of at most :data:`POSITION_SUBSAMPLE` errors.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .criteria import (
    CRITERIA,
    dstar,
    inverse_information_batch,
    model_singular_values,
    position_rms,
    std_from_covariance,
)
from .doe.plans import random_plan
from .errors import ArmcalError, ArmcalWarning
from .identification import METHODS, solve_compliant
from .models import (
    Compliance,
    Loads,
    PlanarArm,
    barely_identifiable_warning,
    check_compliance_identifiable,
    check_identifiable,
    conditioning_warning,
    forward_kinematics,
    jacobian,
    link_phasors,
    link_units,
    plan_rows,
    plan_svd,
)
from .noise import NoiseModel
from .progress import ProgressCallback

__all__ = [
    "CHUNK_BYTES",
    "POSITION_QUANTILES",
    "MonteCarlo",
    "PlanStudy",
    "PositionErrors",
    "monte_carlo",
    "random_plan_study",
    "simulated_noise",
    "synthesize_measurements",
]


#: Bytes of working arrays allowed per chunk of trials or plans.
CHUNK_BYTES = 32 * 2**20


#: Quantiles of the positioning error reported by :class:`PositionErrors`.
POSITION_QUANTILES = (0.5, 0.95, 0.99)


#: Largest number of (trial, test pose) pairs whose tip errors are kept for the
#: quantiles; runs with fewer pairs keep them all (exact quantiles).  At this size
#: the subsample's 50, 95 and 99 % quantiles sit within +-0.006, +-0.0025 and
#: +-0.0011 in level of those of all pairs (95 % intervals, see :func:`monte_carlo`),
#: and keeping them costs less than half the noise draw of 10 000 trials of 20 poses.
POSITION_SUBSAMPLE = 30_000


#: Pairs of the subsample whose tip errors are computed at once.
_PAIR_BLOCK = 2048


#: Normal quantile of the two-sided 95 % intervals of the subsample quantiles.
_Z95 = 1.959963984540054


def _chunk_size(per_item_floats: int, total: int) -> int:
    return int(max(1, min(total, CHUNK_BYTES // (8 * max(per_item_floats, 1)))))


class _Moments:
    """Running mean and scatter matrix of row vectors, merged chunk by chunk."""

    def __init__(self, p: int) -> None:
        self.count = 0
        self.mean = np.zeros(p)
        self.scatter = np.zeros((p, p))

    def add(self, rows: np.ndarray) -> None:
        k = rows.shape[0]
        mean = rows.mean(axis=0)
        centred = rows - mean
        scatter = centred.T @ centred
        total = self.count + k
        delta = mean - self.mean
        self.scatter += scatter + np.outer(delta, delta) * (self.count * k / total)
        self.mean += delta * (k / total)
        self.count = total

    def covariance(self) -> np.ndarray:
        return self.scatter / (self.count - 1)  # callers ensure count >= 2


@dataclass(frozen=True, eq=False)
class PositionErrors:
    """Tip error of the calibrated model at test poses, over every trial.

    The error at a test pose ``x`` in a trial is ``|p(x, estimate) - p(x, truth)|``
    (mm): where the calibrated model puts the tip against where the real arm
    is.  Every (trial, test pose) pair is one sample.

    Attributes
    ----------
    rms_mm : float
        RMS over all ``pairs`` samples, exact (see :func:`monte_carlo`, Notes);
        compare with ``predicted_rms_mm``.
    predicted_rms_mm : float
        ``sigma sqrt(mean_x tr(J(x) F^-1 J(x)^T))`` at the truth.
    quantiles_mm : dict of str to float
        ``"50"``, ``"95"``, ``"99"`` percent quantiles of the ``subsample``
        errors (:func:`numpy.quantile`, linear interpolation).
    quantile_intervals_mm : dict of str to tuple of float
        For each quantile, a 95 % confidence interval ``(low, high)`` for the
        quantile over all ``pairs`` samples; ``(value, value)`` when the
        subsample is every pair.
    pairs : int
        Trials times test poses.
    subsample : int
        Pairs whose errors give the quantiles: all of them up to
        :data:`POSITION_SUBSAMPLE`, else that many drawn at random.
    """

    rms_mm: float
    predicted_rms_mm: float
    quantiles_mm: dict[str, float]
    quantile_intervals_mm: dict[str, tuple[float, float]]
    pairs: int
    subsample: int

    @property
    def exact_quantiles(self) -> bool:
        """Whether the quantiles use every (trial, test pose) pair."""
        return self.subsample == self.pairs


class _PositionAccumulator:
    """Tip errors at test poses: an exact mean square and a bounded subsample.

    The tip is linear in the link phasors ``z`` (``x + i y = b + sum_k z_k
    u_k(x)``), so the error of an estimate at ``x`` is ``e = u(x)^T dz`` with
    ``dz = z(estimate) - z(truth)`` (the base ``b`` is the last entry of ``z``
    and ``u``), and ``|e|^2 = sum_kl dz_k conj(dz_l) u_k(x) conj(u_l(x))``.
    Averaged over trials and test poses this is ``tr(S G)`` with the second
    moment ``S = mean_trials dz dz^H`` and ``G = mean_x conj(u(x)) u(x)^T``,
    both ``(n + 1, n + 1)`` Hermitian: only ``S`` is accumulated per chunk.
    """

    def __init__(
        self,
        arm: PlanarArm,
        test_q: np.ndarray,
        truth: np.ndarray,
        covariance: np.ndarray,
        trials: int,
        rng: np.random.Generator,
    ) -> None:
        self.arm = arm
        self.truth = link_phasors(arm, truth)
        rows, target, _ = plan_rows(arm, test_q, None)  # every target of a test pose
        unit = link_units(arm, rows, target)  # (k, K)
        self.basis = np.concatenate([unit, np.ones((unit.shape[0], 1))], axis=1)  # u(x), (k, n+1)
        self.gram = self.basis.conj().T @ self.basis / self.basis.shape[0]  # G
        self.second_moment = np.zeros((self.truth.size, self.truth.size), dtype=complex)
        j0 = jacobian(arm, rows, truth, target=target)  # (k, 2, p)
        per_pose = np.sum((j0 @ covariance) * j0, axis=(1, 2))
        self.predicted_rms = float(np.sqrt(np.mean(per_pose)))
        self.trials, poses = trials, unit.shape[0]
        self.pairs = trials * poses
        if self.pairs <= POSITION_SUBSAMPLE:
            trial, pose = np.divmod(np.arange(self.pairs), poses)
        else:  # uniform with replacement: iid draws from the pairs' errors
            trial = rng.integers(0, trials, POSITION_SUBSAMPLE)
            trial.sort()  # chunks take consecutive trials
            pose = rng.integers(0, poses, POSITION_SUBSAMPLE)
        self.sample_trial, self.sample_pose = trial, pose
        self.sample = np.empty(trial.size)
        self.done = 0
        block = min(_PAIR_BLOCK, trial.size)
        width = self.basis.shape[1]
        self.buffers = (
            np.empty((block, width), dtype=complex),
            np.empty((block, width), dtype=complex),
            np.empty(block, dtype=complex),
        )

    def add(self, estimates: np.ndarray) -> None:
        dz = link_phasors(self.arm, estimates) - self.truth  # (chunk, n+1)
        self.second_moment += dz.T @ dz.conj()  # sum of dz dz^H
        first, stop = np.searchsorted(self.sample_trial, [self.done, self.done + dz.shape[0]])
        # Blocks of pairs through buffers allocated once: fresh multi-MB temporaries
        # per chunk cost more in page faults than the arithmetic.
        rows, terms, error = self.buffers
        for begin in range(first, stop, rows.shape[0]):
            end = min(begin + rows.shape[0], stop)
            size = end - begin
            np.take(dz, self.sample_trial[begin:end] - self.done, axis=0, out=rows[:size])
            np.take(self.basis, self.sample_pose[begin:end], axis=0, out=terms[:size])
            np.multiply(rows[:size], terms[:size], out=terms[:size])
            error[:size] = terms[:size, 0]
            for k in range(1, terms.shape[1]):  # a short-axis sum is slow as a reduction
                np.add(error[:size], terms[:size, k], out=error[:size])
            np.abs(error[:size], out=self.sample[begin:end])
        self.done += dz.shape[0]

    def result(self) -> PositionErrors:
        mean_square = np.trace(self.second_moment @ self.gram).real / self.trials
        size = self.sample.size
        exact = size == self.pairs
        # numpy.quantile's linear interpolation between the order statistics at
        # floor and ceil of (size - 1) level, plus the interval ranks.
        wanted: dict[float, tuple[int, int, int]] = {}
        for level in POSITION_QUANTILES:
            position = (size - 1) * level
            # The count of draws below the pairs' quantile is Binomial(size, level).
            half = _Z95 * math.sqrt(size * level * (1 - level))
            low = min(size - 1, max(0, math.floor(size * level - half) - 1))
            high = min(size - 1, math.ceil(size * level + half))
            wanted[level] = (math.floor(position), low, high)
        ranks = sorted(
            {r for f, lo, hi in wanted.values() for r in (f, min(f + 1, size - 1), lo, hi)}
        )
        ordered = np.partition(self.sample, ranks)
        quantiles, intervals = {}, {}
        for level, (floor, low, high) in wanted.items():
            key = f"{round(100 * level)}"
            below, above = ordered[floor], ordered[min(floor + 1, size - 1)]
            value = float(below + ((size - 1) * level - floor) * (above - below))
            quantiles[key] = value
            intervals[key] = (
                (value, value) if exact else (float(ordered[low]), float(ordered[high]))
            )
        return PositionErrors(
            rms_mm=math.sqrt(max(mean_square, 0.0)),
            predicted_rms_mm=self.predicted_rms,
            quantiles_mm=quantiles,
            quantile_intervals_mm=intervals,
            pairs=self.pairs,
            subsample=size,
        )


@dataclass(frozen=True, eq=False)
class MonteCarlo:
    """Empirical against predicted accuracy of a plan over ``trials`` noisy measurement sets.

    Internal units are mm and rad; the properties give display units (mm, deg).

    Attributes
    ----------
    arm : PlanarArm
        The arm as simulated: its noise model is the one the noise was drawn
        from (:func:`simulated_noise`), its fixed parameters those held at 0.
    q : ndarray, shape (m, n)
        The plan (rad).
    truth : ndarray, shape (p,)
        Deviations of the virtual robot (mm, rad).
    sigma_mm : float
        The instrument noise (mm): ``sigma`` when given, else the noise model's
        reference ``sqrt(2 / tr(Sigma_meas^-1))`` (the isotropic sigma when isotropic).
    method : str
        Solver (key of :data:`armcal.identification.METHODS`).
    trials : int
    mean : ndarray, shape (p,)
        Mean estimate (mm, rad).
    covariance : ndarray, shape (p, p)
        Empirical covariance of the estimates (``ddof=1``; mm, rad).
    predicted_covariance : ndarray, shape (p, p)
        The generalized-least-squares covariance at the truth,
        ``sigma_ref^2 (J_w^T J_w)^-1`` over the free parameters (zero rows and
        columns for fixed ones); ``sigma^2 (J^T J)^-1`` (paper eq. 16) for
        isotropic iid noise.
    position : PositionErrors or None
        Tip errors of the calibrated model at the test poses (None without test poses).
    not_converged : int
        Trials where Gauss-Newton hit its iteration cap (0 for the closed form).
    seconds : float
        Wall time of the Monte Carlo itself.
    warnings : tuple of ArmcalWarning
        ``fixed-not-nominal`` when the truth moves a parameter the model holds
        fixed (the fit is then misspecified, and the bias shows by how much).
    compliance : Compliance or None
        With joint compliance, every array also covers its parameters
        (:attr:`names`), after the arm's.
    """

    arm: PlanarArm
    q: np.ndarray
    truth: np.ndarray
    sigma_mm: float
    method: str
    trials: int
    mean: np.ndarray
    covariance: np.ndarray
    predicted_covariance: np.ndarray
    position: PositionErrors | None
    not_converged: int
    seconds: float
    warnings: tuple[ArmcalWarning, ...] = ()
    compliance: Compliance | None = None

    @property
    def names(self) -> tuple[str, ...]:
        if self.compliance is not None:
            return self.compliance.all_names
        return self.arm.param_names

    @property
    def units(self) -> tuple[str, ...]:
        if self.compliance is not None:
            return self.compliance.all_units
        return self.arm.param_units

    @property
    def display_scale(self) -> np.ndarray:
        if self.compliance is not None:
            return self.compliance.all_scale
        return self.arm.display_scale

    @property
    def bias(self) -> np.ndarray:
        """Mean estimate minus truth ``(p,)`` in mm / deg."""
        return (self.mean - self.truth) * self.display_scale

    @property
    def std(self) -> np.ndarray:
        """Empirical std ``(p,)`` in mm / deg."""
        return np.sqrt(np.diagonal(self.covariance)) * self.display_scale

    @property
    def predicted_std(self) -> np.ndarray:
        """Predicted std ``(p,)`` in mm / deg."""
        return np.sqrt(np.diagonal(self.predicted_covariance)) * self.display_scale

    @property
    def bias_limit(self) -> np.ndarray:
        """``4 std / sqrt(N)`` ``(p,)``: a bias beyond it is significant at about 1e-4."""
        return 4.0 * self.predicted_std / math.sqrt(self.trials)


def _fixed_truth_warning(arm: PlanarArm, truth: np.ndarray) -> tuple[ArmcalWarning, ...]:
    moved = [
        f"{name} = {value:g} {unit}"
        for name, unit, value, free in zip(
            arm.param_names, arm.param_units, truth * arm.display_scale, arm.free, strict=True
        )
        if not free and value != 0
    ]
    if not moved:
        return ()
    return (
        ArmcalWarning(
            "fixed-not-nominal",
            f"the truth has {', '.join(moved)}, but the model holds "
            f"{'it' if len(moved) == 1 else 'them'} at 0: every fit is misspecified and the "
            "bias shows the effect; to simulate a known parameter, put its value into the "
            "nominal arm and give it 0 in the truth",
        ),
    )


def _floats_per_trial(arm: PlanarArm, m: int, method: str) -> int:
    """Floats of working arrays a trial holds in one chunk (sets the chunk size)."""
    n, p = arm.n_joints, arm.n_params
    encoder = arm.noise is not None and arm.noise.joint_sigma is not None
    if method == "closed-form" and not encoder:
        # Noise and positions (2 x 2m) and the estimates (a few p): every set shares one
        # factorization (whitened alike when the noise is anisotropic).  The chunks are
        # then large enough that the command's default 10^4 trials are one solve.
        return 2 * m * 3 + 4 * p
    if arm.standard:
        # Gauss-Newton also holds Jacobian-sized products (3 x 2m p).
        return 2 * m * (3 * p + 2)
    # Weighted or reduced models solve set by set: whitening (4m), whitened Jacobian
    # and regressor rows with their factorization (a few 2m p); encoder noise draws
    # and evaluates the tip at q + dq (a few m n).  Measured peaks (tracemalloc, 4-link
    # arm, m = 20 and 100) are 0.75 to 1.05 CHUNK_BYTES.
    return 2 * m * (5 * p + 6) + (8 * m * n if encoder else 0)


def monte_carlo(
    arm: PlanarArm,
    q: np.ndarray,
    truth: np.ndarray,
    sigma: float | None,
    trials: int,
    *,
    method: str = "auto",
    rng: np.random.Generator | int | None = None,
    test_q: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
    compliance: Compliance | None = None,
    loads: Loads | None = None,
) -> MonteCarlo:
    """Identify ``trials`` noisy measurement sets of plan ``q`` and compare with theory.

    Parameters
    ----------
    arm : PlanarArm
        The nominal arm: its noise model and fixed parameters are the model
        simulated and identified.
    q : ndarray, shape (m, n)
        The plan (rad); must identify every free parameter.
    truth : ndarray, shape (p,)
        Deviations of the virtual robot (mm, rad).
    sigma : float or None
        Isotropic instrument noise (1 std, mm) overriding the arm's, the arm's
        encoder noise kept; None uses the arm's noise model as it is
        (:func:`simulated_noise`).
    trials : int
        Number of measurement sets.
    method : {"auto", "closed-form", "gauss-newton"}
        Solver; every chunk of trials is one batched call of it.  ``"auto"`` is
        the closed form when every parameter is free, else Gauss-Newton.
    rng : numpy.random.Generator or int or None
        Noise source; the same seed gives the same result.
    test_q : ndarray, shape (k, n), optional
        Poses where the positioning error of the calibrated model is measured.
    progress : callable, optional
        ``progress(done, total)`` after every chunk.
    compliance : Compliance, optional
        A robot whose joints deflect under load: ``truth`` holds the deviations
        then the compliance, and every set is fitted with both
        (:func:`armcal.identification.solve_compliant`; ``test_q`` is not used).
    loads : Loads, optional
        Every pose's payload and tip force, with ``compliance``.

    Returns
    -------
    MonteCarlo

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every free parameter.
    ArmcalError
        For fewer than 2 trials, no noise (or a ``sigma`` that is not positive and
        finite), an unknown method, or the closed form asked for a model with
        fixed parameters.

    Notes
    -----
    The noise is drawn by :func:`synthesize_measurements` from the model's
    noise (instrument covariance and encoder noise, the latter exactly, through
    the tip at ``q + dq``), and every set is identified by the solver
    :data:`armcal.identification.METHODS` ``[method]`` on the model (weighted,
    over the free parameters).  The prediction is the generalized-least-squares
    covariance at the truth (:func:`armcal.criteria.inverse_information_batch`),
    to which the estimates' covariance tends for small noise.

    Tip errors at the test poses (:class:`PositionErrors`) cost O(N + k), not
    O(N k):

    * **RMS, exact.**  The tip at ``x`` is ``b + sum_k z_k u_k(x)``, linear in
      the link phasors ``z`` (:func:`armcal.arm.link_phasors`, base last, with
      ``u_{n+1} = 1``), so the squared error of a trial at ``x`` is
      ``|u(x)^T dz|^2`` and its mean over the N trials and k test poses is
      ``tr(S G)`` with ``S = mean_trials dz dz^H`` and ``G = mean_x conj(u(x))
      u(x)^T``.  Only the ``(n + 1, n + 1)`` matrix ``S`` is accumulated.  A
      fixed parameter is 0 in every estimate, and its rows of the predicted
      covariance are 0, so both sides hold for reduced models as they are.
    * **Quantiles, from a subsample.**  With at most
      :data:`POSITION_SUBSAMPLE` pairs every error is kept and the quantiles are
      exact.  Otherwise ``B = POSITION_SUBSAMPLE`` pairs are drawn uniformly with
      replacement (trial and test pose independently, from a generator spawned
      from ``rng`` so that the noise does not depend on ``test_q``): B iid
      draws from the N k errors.  The number of draws below the pairs' true
      ``P``-quantile is then Binomial(B, P), so the subsample quantile sits at a
      level within ``P +- 1.96 sqrt(P (1 - P) / B)`` of the pairs' CDF with 95 %
      probability (+-0.0025 for the 95 % quantile at B = 30 000); the
      order statistics at those ranks give ``quantile_intervals_mm``.  The
      largest error is not reported: a subsample cannot bound it.

    Examples
    --------
    >>> from armcal.doe import orthogonal_plan
    >>> arm = PlanarArm([260.0, 180.0])
    >>> result = monte_carlo(arm, orthogonal_plan(arm, 20), np.zeros(4), 0.1, 20000, rng=1)
    >>> bool(np.allclose(result.std, result.predicted_std, rtol=0.03))
    True
    """
    q = np.asarray(q, dtype=float)
    if compliance is not None:
        return _monte_carlo_compliant(
            compliance, q, loads, truth, sigma, trials, rng=rng, progress=progress
        )
    truth = _checked_truth(arm, truth)
    if method == "auto":
        method = "closed-form" if arm.complete else "gauss-newton"
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of auto, {', '.join(METHODS)}")
    if method == "closed-form" and not arm.complete:
        raise ArmcalError(
            f"the closed form needs every parameter free, but {', '.join(arm.fixed)} "
            f"{'is' if len(arm.fixed) == 1 else 'are'} fixed; use method gauss-newton or auto"
        )
    _check_runs(trials, sigma)
    noise = simulated_noise(arm, sigma)
    model = arm.replace(noise=noise)
    reference = float(sigma) if sigma is not None else noise.sigma_mm
    svd = plan_svd(model, q)
    conditioning = conditioning_warning(model, check_identifiable(model, q, svd=svd))
    rng = np.random.default_rng(rng)
    inverse, ok = inverse_information_batch(model, q, truth, svd=svd)
    if not ok:
        raise ArmcalError("the plan cannot identify every parameter at the given truth")
    predicted = reference**2 * inverse
    rows, target, _ = plan_rows(model, q, None)  # every target of every pose
    m, p = rows.shape[0], arm.n_params
    chunk = _chunk_size(_floats_per_trial(model, m, method), trials)
    moments = _Moments(p)
    # Moments about the truth keep round-off small; a fixed parameter is 0 in every
    # estimate, so about 0 its mean and scatter are exactly 0 even when the truth moves it.
    centre = truth * model.free
    positions = None
    if test_q is not None:
        sampler = rng.spawn(1)[0]  # leaves the noise stream as it is without test poses
        positions = _PositionAccumulator(model, test_q, truth, predicted, trials, sampler)
    not_converged = 0
    start = time.perf_counter()
    done = 0
    while done < trials:
        size = min(chunk, trials - done)
        xy = synthesize_measurements(
            model, rows, truth, sigma, rng=rng, trials=size, target=target
        )
        estimates, _, converged = METHODS[method](model, rows, xy, target=target)
        not_converged += int(np.size(converged) - np.count_nonzero(converged))
        moments.add(estimates - centre)
        if positions is not None:
            positions.add(estimates)
        done += size
        if progress is not None:
            progress(done, trials)
    seconds = time.perf_counter() - start
    return MonteCarlo(
        arm=model,
        q=q,
        truth=truth,
        sigma_mm=reference,
        method=method,
        trials=int(trials),
        mean=centre + moments.mean,
        covariance=moments.covariance(),
        predicted_covariance=predicted,
        position=None if positions is None else positions.result(),
        not_converged=not_converged,
        seconds=seconds,
        warnings=(*_found(conditioning), *_fixed_truth_warning(model, truth)),
    )


def _found(warning: ArmcalWarning | None) -> tuple[ArmcalWarning, ...]:
    return () if warning is None else (warning,)


def _check_runs(trials: int, sigma: float | None) -> None:
    """At least 2 trials and, when given, a positive finite sigma (mm)."""
    if trials < 2:
        raise ArmcalError(f"a Monte Carlo needs at least 2 trials, got {trials}")
    if sigma is not None and not (sigma > 0 and math.isfinite(sigma)):
        raise ArmcalError(f"a Monte Carlo needs a positive noise sigma (mm), got {sigma}")


def _monte_carlo_compliant(
    compliance: Compliance,
    q: np.ndarray,
    loads: Loads | None,
    truth: np.ndarray,
    sigma: float | None,
    trials: int,
    *,
    rng: np.random.Generator | int | None,
    progress: ProgressCallback | None,
) -> MonteCarlo:
    """:func:`monte_carlo` of geometry plus joint compliance (Gauss-Newton on every set)."""
    arm = compliance.arm
    truth = _checked_truth(arm, truth, compliance)
    _check_runs(trials, sigma)
    noise = simulated_noise(arm, sigma)
    model = Compliance(arm.replace(noise=noise), compliance.elastic, compliance.known_loads)
    reference = float(sigma) if sigma is not None else noise.sigma_mm
    info, _ = check_compliance_identifiable(model, q, loads)
    conditioning = barely_identifiable_warning(info)
    predicted, ok = model.covariance(q, loads, reference, truth)
    if not ok:
        raise ArmcalError("the plan cannot identify every parameter at the given truth")
    rng = np.random.default_rng(rng)
    m, p = q.shape[0], truth.size
    chunk = _chunk_size(2 * m * (5 * p + 6) + 8 * m * arm.n_joints, trials)
    moments = _Moments(p)
    centre = truth * model.all_free
    not_converged = 0
    start = time.perf_counter()
    done = 0
    while done < trials:
        size = min(chunk, trials - done)
        xy = synthesize_measurements(
            model.arm, q, truth, sigma, rng=rng, trials=size, compliance=model, loads=loads
        )
        estimates, _, converged = solve_compliant(model, q, xy, loads, start=truth)
        not_converged += int(np.size(converged) - np.count_nonzero(converged))
        moments.add(estimates - centre)
        done += size
        if progress is not None:
            progress(done, trials)
    return MonteCarlo(
        arm=model.arm,
        q=q,
        truth=truth,
        sigma_mm=reference,
        method="gauss-newton",
        trials=int(trials),
        mean=centre + moments.mean,
        covariance=moments.covariance(),
        predicted_covariance=predicted,
        position=None,
        not_converged=not_converged,
        seconds=time.perf_counter() - start,
        warnings=(
            *_found(conditioning),
            *_fixed_truth_warning(model.arm, truth[: arm.n_params]),
        ),
        compliance=model,
    )


@dataclass(frozen=True, eq=False)
class PlanStudy:
    """Criteria and predicted accuracy of many random plans (paper Figure 1).

    Attributes
    ----------
    arm : PlanarArm
        The arm as studied, with the noise model of the predictions
        (:func:`simulated_noise`).
    n_poses : int
        Poses per plan.
    sigma_mm : float
        Instrument noise (mm) for the predicted std: ``sigma`` when given, else
        the noise model's reference.
    det_d : ndarray, shape (N,)
        ``det D'``: determinant of the Hadamard-normalized information matrix,
        ``= d_efficiency ** p`` (1 for an orthogonal plan).  For a weighted or
        reduced model, the determinant of its information matrix ``H^T H``
        (:func:`armcal.observability.scaled_jacobian`, ``p_f x p_f``), which
        compares plans of that model but is no longer at most 1.
    det_c : ndarray, shape (N,)
        ``det C'`` with ``C' = C / m`` (eq. 20 corrected, see :class:`~armcal.criteria.DStar`).
        The paper's D* assumes isotropic iid noise and every parameter free: it
        ignores the noise model and the fixed parameters.
    abs_det_s : ndarray, shape (N,)
        ``|det S'|`` with ``S' = S / m`` (the same caveat).
    std : ndarray, shape (N, p)
        Predicted std of the user parameters (mm, deg), 0 for fixed ones;
        ``inf`` rows for plans that cannot identify the parameters.
    position_rms : ndarray, shape (N,)
        Predicted RMS tip error after calibration at the test poses (mm; ``inf``
        if not identifiable).
    """

    arm: PlanarArm
    n_poses: int
    sigma_mm: float
    det_d: np.ndarray
    det_c: np.ndarray
    abs_det_s: np.ndarray
    std: np.ndarray
    position_rms: np.ndarray

    @property
    def identifiable(self) -> np.ndarray:
        return np.all(np.isfinite(self.std), axis=-1)


def random_plan_study(
    arm: PlanarArm,
    poses: int,
    plans: int,
    *,
    sigma: float | None = None,
    rng: np.random.Generator | int | None = None,
    test_q: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
) -> PlanStudy:
    """Evaluate ``plans`` random plans of ``poses`` poses (uniform within the joint limits).

    Every plan's criteria and predicted std are computed in batches of plans
    (one stacked SVD per batch), not one plan at a time, on the arm's model:
    its noise (weighted information) and its free parameters.

    Parameters
    ----------
    arm : PlanarArm
    poses : int
        Poses per plan.
    plans : int
        Number of random plans.
    sigma : float, optional
        Isotropic instrument noise (mm) overriding the arm's, its encoder noise
        kept; the arm's noise model when omitted (:func:`simulated_noise`).
    rng : numpy.random.Generator or int or None
    test_q : ndarray, shape (k, n), optional
        Poses for the positioning error (default: 1000 uniform within the limits).
    progress : callable, optional
        ``progress(done, total)`` after every batch.

    Returns
    -------
    PlanStudy

    Raises
    ------
    ArmcalError
        If ``sigma`` is not positive and finite, or is omitted for an arm
        without a noise model.

    Examples
    --------
    >>> study = random_plan_study(PlanarArm([260.0, 180.0, 120.0, 100.0]), 10, 500,
    ...                           sigma=0.1, rng=0)
    >>> bool(np.all(study.det_d < 1)), bool(np.all(study.det_c < 1))
    (True, True)
    """
    noise = simulated_noise(arm, sigma)
    model = arm.replace(noise=noise)
    reference = float(sigma) if sigma is not None else noise.sigma_mm
    rng = np.random.default_rng(rng)
    test_q = random_plan(arm, 1000, rng=rng) if test_q is None else np.asarray(test_q, dtype=float)
    p = model.n_free
    chunk = _chunk_size(2 * poses * arm.n_params * 4, plans)
    parts: dict[str, list[np.ndarray]] = {key: [] for key in ("d", "c", "s", "std", "pos")}
    done = 0
    while done < plans:
        size = min(chunk, plans - done)
        q = random_plan(arm, size * poses, rng=rng).reshape(size, poses, arm.n_joints)
        # One SVD per plan serves det D' (the product of the squared singular values,
        # 0 for plans the rank policy calls singular; a weighted or reduced model's
        # unnormalized ones) and the covariance.
        svd = plan_svd(model, q)
        parts["d"].append(
            CRITERIA["D"].from_singular_values(model_singular_values(model, q, svd)) ** p
        )
        star = dstar(model, q)
        parts["c"].append(star.det_c)
        parts["s"].append(star.abs_det_s)
        inverse, _ = inverse_information_batch(model, q, svd=svd)
        parts["std"].append(std_from_covariance(model, reference**2 * inverse))
        parts["pos"].append(position_rms(model, inverse, test_q, reference))
        done += size
        if progress is not None:
            progress(done, plans)
    joined = {key: np.concatenate(value) for key, value in parts.items()}
    return PlanStudy(
        arm=model,
        n_poses=int(poses),
        sigma_mm=reference,
        det_d=joined["d"],
        det_c=joined["c"],
        abs_det_s=joined["s"],
        std=joined["std"],
        position_rms=joined["pos"],
    )


def simulated_noise(arm: PlanarArm, sigma: float | None) -> NoiseModel:
    """The noise model a simulation of ``arm`` draws from, with ``sigma`` as the instrument.

    ``sigma`` (mm) overrides the instrument, as ``--sigma`` does: the
    instrument covariance becomes ``sigma^2 I`` and the arm's encoder noise
    stays (:meth:`armcal.noise.NoiseModel.with_instrument_sigma`).  Without
    ``sigma`` the arm's own noise model is used as it is: its instrument
    covariance (isotropic, per axis or full) and its encoder noise.

    Parameters
    ----------
    arm : PlanarArm
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
    >>> arm = PlanarArm([2.0, 1.0], noise=NoiseModel.per_axis(0.08, 0.02, joint_sigma=1e-4))
    >>> simulated_noise(arm, None) is arm.noise
    True
    >>> noise = simulated_noise(arm, 0.05)
    >>> noise.covariance_mm2.round(6).tolist(), noise.joint_sigma.tolist()
    ([[0.0025, 0.0], [0.0, 0.0025]], [0.0001])
    """
    if sigma is None:
        if arm.noise is None:
            raise ArmcalError(
                f"no measurement noise to simulate for {arm.name}: give the instrument "
                "sigma (mm), or a [measurement] table in the robot file"
            )
        return arm.noise
    if not (math.isfinite(sigma) and sigma > 0):
        raise ArmcalError(
            f"the instrument noise sigma must be positive and finite (mm), got {sigma}"
        )
    if arm.noise is None:
        return NoiseModel.isotropic(sigma)
    return arm.noise.with_instrument_sigma(sigma)


def _checked_truth(
    arm: PlanarArm, truth: np.ndarray, compliance: Compliance | None = None
) -> np.ndarray:
    """``truth`` as floats ``(p[+P],)``; ArmcalError unless it is that shape and finite."""
    values = np.asarray(truth, dtype=float)
    names = arm.param_names if compliance is None else compliance.all_names
    if values.shape != (len(names),) or not np.all(np.isfinite(values)):
        raise ArmcalError(
            f"the truth must hold {len(names)} finite "
            f"{'deviations' if compliance is None else 'values'} ({', '.join(names)}), "
            f"got {values.tolist()}"
        )
    return values


def _instrument_factor(
    arm: PlanarArm, sigma: float | None, row_sigma: np.ndarray | None, m: int
) -> float | np.ndarray:
    """What multiplies standard normal draws ``z`` ``(..., m, 2)`` into instrument noise.

    A number ``s`` (isotropic: ``s z``), a lower-triangular ``L`` ``(2, 2)`` with
    ``L L^T = Sigma_meas`` (``L z`` per pose), or per-row ``s_i`` ``(m, 1)``.
    """
    if row_sigma is not None:
        rows = np.asarray(row_sigma, dtype=float)
        if rows.shape != (m,) or not np.all(np.isfinite(rows) & (rows > 0)):
            raise ArmcalError(
                f"row_sigma must hold one positive, finite sigma (mm) per pose, shape ({m},), "
                f"got shape {rows.shape}"
            )
        return rows[:, None]
    if sigma is not None:
        if not (math.isfinite(sigma) and sigma >= 0):
            raise ArmcalError(f"the noise sigma must be finite and >= 0 (mm), got {sigma}")
        return float(sigma)  # exactly as given: the same draws give the same data as ever
    cov = simulated_noise(arm, None).covariance_mm2
    if cov[0, 1] == 0 and cov[0, 0] == cov[1, 1]:
        return float(np.sqrt(cov[0, 0]))
    return np.linalg.cholesky(cov)


def _scale_instrument(z: np.ndarray, factor: float | np.ndarray) -> None:
    """Turn standard normal draws ``z`` ``(..., m, 2)`` into instrument noise, in place."""
    if np.ndim(factor) == 2 and np.shape(factor) == (2, 2):
        lower = np.asarray(factor)
        # (x, y) = L (z0, z1) with L lower triangular: y first, while z0 is still z0.
        z[..., 1] *= lower[1, 1]
        z[..., 1] += lower[1, 0] * z[..., 0]
        z[..., 0] *= lower[0, 0]
    else:
        z *= factor


def synthesize_measurements(
    arm: PlanarArm,
    plan: np.ndarray,
    truth: np.ndarray,
    sigma: float | None = None,
    *,
    rng: np.random.Generator | int | None = None,
    trials: int | None = None,
    row_sigma: np.ndarray | None = None,
    target: np.ndarray | None = None,
    compliance: Compliance | None = None,
    loads: Loads | None = None,
) -> np.ndarray:
    """Measurements of a virtual robot: positions at ``truth`` drawn from the noise model.

    The one place where armcal draws measurement noise (``armcal synthesize``,
    ``armcal demo`` and :func:`monte_carlo` all call it).

    Parameters
    ----------
    arm : PlanarArm
        The nominal arm; its noise model (:attr:`PlanarArm.noise`) gives the
        shape of the instrument noise and the encoder noise.
    plan : ndarray, shape (m, n)
        Joint angles in rad, as the controller reports them.
    truth : ndarray, shape (p,)
        Deviations of the virtual robot (mm, rad).
    sigma : float, optional
        Isotropic instrument noise (1 std, mm) that overrides the arm's
        instrument covariance, as ``--sigma`` does; the arm's encoder noise
        stays.  0 gives no instrument noise.  Without it the arm's noise model
        is used as it is (see :func:`simulated_noise`).
    rng : numpy.random.Generator or int or None
        Noise source.
    trials : int, optional
        Draw this many independent measurement sets at once.
    row_sigma : ndarray, shape (m,), optional
        Per-row instrument noise (mm), for instruments that report each point's
        uncertainty: pose ``i`` gets ``s_i^2 I`` in place of the instrument
        covariance (and of ``sigma``).
    target : ndarray of int, shape (m,), optional
        The target every row measures, on an arm with several.
    compliance : Compliance, optional
        A virtual robot whose joints deflect under load (:mod:`armcal.elastostatic`):
        ``truth`` then holds the deviations followed by the compliance.
    loads : Loads, optional
        Every row's payload and tip force, with ``compliance``.

    Returns
    -------
    ndarray, shape (m, 2) or (trials, m, 2)
        Measured positions in mm.

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
    pose draws ``2 + n`` standard normals at once (instrument, then joints), in
    trial order, so sets drawn in chunks of trials equal those drawn at once.

    Examples
    --------
    >>> arm = PlanarArm([2.0, 1.0])
    >>> synthesize_measurements(arm, np.zeros((1, 2)), np.zeros(4), 0.0).tolist()
    [[3.0, 0.0]]
    """
    rng = np.random.default_rng(rng)
    plan = np.asarray(plan, dtype=float)
    if plan.ndim != 2 or plan.shape[1] != arm.n_joints:
        raise ArmcalError(f"the plan must have shape (m, {arm.n_joints}) in rad, got {plan.shape}")
    truth = _checked_truth(arm, truth, compliance)
    m, n = plan.shape
    factor = _instrument_factor(arm, sigma, row_sigma, m)
    joint_sigma = None if arm.noise is None else arm.noise.joint_sigma
    sets = () if trials is None else (int(trials),)

    def tip(q: np.ndarray) -> np.ndarray:
        if compliance is None:
            return forward_kinematics(arm, q, truth, target=target)
        return compliance.tip(q, truth, loads)

    if joint_sigma is None:
        clean = tip(plan)
        noisy = rng.standard_normal((*sets, m, 2))
        _scale_instrument(noisy, factor)  # in place: the noise is a Monte Carlo's largest array
        noisy += clean
        return noisy
    draws = rng.standard_normal((*sets, m, 2 + n))
    actual = draws[..., 2:]  # where the joints really were: q + dq
    actual *= np.broadcast_to(joint_sigma, (n,))
    actual += plan
    positions = tip(actual)
    instrument = draws[..., :2]
    _scale_instrument(instrument, factor)
    positions += instrument
    return positions
