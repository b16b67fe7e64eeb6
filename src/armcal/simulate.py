"""Monte Carlo: many noisy measurement sets of one plan, identified together, against theory.

:func:`monte_carlo` draws ``N`` measurement sets of a plan
(:func:`armcal.synthesis.synthesize_measurements`) and identifies them together,
one batched solve per chunk of trials
(:func:`armcal.identification.solve`), for any model
(:class:`~armcal.models.interface.FitModel`).  The prediction it is compared
with is the generalized-least-squares covariance at the truth,
``sigma_ref^2 (J_w^T J_w)^-1`` over the free parameters (paper eq. 16 for
isotropic iid noise).

Memory is bounded by the chunk size, not by the number of trials: empirical
moments are merged chunk by chunk (Chan et al.'s pairwise update), the mean
square tip error follows exactly from a small second-moment matrix, and its
quantiles from a subsample of at most :data:`POSITION_SUBSAMPLE` errors.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .errors import ArmcalError, ArmcalWarning, action
from .identification import resolve_method, solve
from .models import (
    Conditions,
    FitModel,
    Identifiability,
    LinearPositions,
    Loads,
    position_jacobian,
)
from .models.information import identified_or_prepared, predicted_covariance, tip_variances
from .models.wording import ill_conditioned_warning
from .notebook import html_table, number
from .progress import ProgressCallback
from .synthesis import checked_truth, simulated_noise, synthesize_measurements

__all__ = [
    "CHUNK_BYTES",
    "POSITION_QUANTILES",
    "MonteCarlo",
    "PositionErrors",
    "chunk_size",
    "monte_carlo",
]


#: Bytes of working arrays allowed per chunk of trials or plans.
CHUNK_BYTES = 32 * 2**20


#: Below this many trials a Monte Carlo warns ``few-trials``: an empirical std of N
#: normal trials has a relative standard error of about ``1 / sqrt(2 (N - 1))``, 7 %
#: at 100, so a std ratio then shows only a gross disagreement with the prediction.
FEW_TRIALS = 100

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


def chunk_size(per_item_floats: int, total: int) -> int:
    """Items per chunk whose working arrays of ``per_item_floats`` doubles each fit in
    :data:`CHUNK_BYTES` (at least 1, at most ``total``)."""
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

    The points are linear in coordinates ``z`` of the parameters
    (:class:`~armcal.models.interface.LinearPositions`: for the planar arm the
    link phasors and the base, ``x + i y = b + sum_k z_k u_k(x)``), so the error
    of an estimate at ``x`` is ``e = u(x)^T dz`` with
    ``dz = z(estimate) - z(truth)``, and
    ``|e|^2 = sum_kl dz_k conj(dz_l) u_k(x) conj(u_l(x))``.  Averaged over trials
    and test poses this is ``tr(S G)`` with the second moment
    ``S = mean_trials dz dz^H`` and ``G = mean_x conj(u(x)) u(x)^T``, both
    ``(L, L)`` Hermitian: only ``S`` is accumulated per chunk.
    """

    def __init__(
        self,
        model: FitModel,
        linear: LinearPositions,
        test: Conditions,
        truth: np.ndarray,
        covariance: np.ndarray,
        trials: int,
        rng: np.random.Generator,
    ) -> None:
        self.coordinates = linear.coordinates
        self.truth = linear.coordinates(truth)
        self.basis = linear.basis  # u(x), (k, L)
        self.gram = self.basis.conj().T @ self.basis / self.basis.shape[0]  # G
        self.second_moment = np.zeros((self.truth.size, self.truth.size), dtype=complex)
        variance = tip_variances(position_jacobian(model, test, truth), covariance)
        self.predicted_rms = float(np.sqrt(np.mean(variance)))
        self.trials, poses = trials, self.basis.shape[0]
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
        dz = self.coordinates(estimates) - self.truth  # (chunk, L)
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
    model : FitModel
        The model as simulated: its noise model is the one the noise was drawn
        from (:func:`~armcal.synthesis.simulated_noise`), its fixed parameters
        those held at 0.
    q : ndarray, shape (m, n)
        The plan (rad).
    truth : ndarray, shape (p,)
        Parameters of the virtual robot (mm, rad, ...).
    sigma_mm : float
        The instrument noise (mm): ``sigma`` when given, else the noise model's
        reference ``sqrt(2 / tr(Sigma_meas^-1))`` (the isotropic sigma when isotropic).
    method : str
        Solver (:data:`armcal.identification.METHODS`).
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
        ``ill-conditioned``, ``not-converged``, and ``fixed-not-nominal`` when the
        truth moves a parameter the model holds fixed (the fit is then
        misspecified, and the bias shows by how much).
    """

    model: FitModel
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

    def __repr__(self) -> str:
        ratio = self.std[self.model.free] / self.predicted_std[self.model.free]
        return (
            f"MonteCarlo({self.model.name}: {self.trials} trials of {self.q.shape[0]} poses, "
            f"{self.method}, empirical/predicted std {ratio.min():.3f} to {ratio.max():.3f})"
        )

    def _repr_html_(self) -> str:
        """The repr over a table of every free parameter's truth, bias, empirical and
        predicted std (display units), and the warnings below it: what a notebook shows."""
        free = self.model.free
        truth = self.truth * self.display_scale
        rows = [
            [
                self.names[i],
                number(truth[i], 6),
                number(self.bias[i], 3),
                number(self.std[i], 3),
                number(self.predicted_std[i], 3),
                self.units[i],
            ]
            for i in np.flatnonzero(free)
        ]
        header = ["parameter", "truth", "bias", "std", "predicted std", "unit"]
        notes = [f"warning {w.code}: {w.message}" for w in self.warnings]
        return html_table(repr(self), header, rows, notes=notes)

    @property
    def arm(self) -> Any:
        """The geometric arm of the model."""
        return self.model.arm

    @property
    def names(self) -> tuple[str, ...]:
        return self.model.param_names

    @property
    def units(self) -> tuple[str, ...]:
        return self.model.param_units

    @property
    def display_scale(self) -> np.ndarray:
        return self.model.display_scale

    def __getitem__(self, name: str) -> dict[str, float | str]:
        """A parameter by name: its truth, bias, empirical and predicted std, display units."""
        if name not in self.names:
            raise KeyError(f"no parameter {name!r}; the parameters are {', '.join(self.names)}")
        i = self.names.index(name)
        return {
            "truth": float(self.truth[i] * self.display_scale[i]),
            "bias": float(self.bias[i]),
            "std": float(self.std[i]),
            "predicted_std": float(self.predicted_std[i]),
            "unit": self.units[i],
        }

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
    def biased(self) -> tuple[str, ...]:
        """The parameters whose bias is beyond :attr:`bias_limit`."""
        return tuple(
            name
            for name, b, limit in zip(self.names, self.bias, self.bias_limit, strict=True)
            if abs(b) > limit
        )

    @property
    def bias_limit(self) -> np.ndarray:
        """``4 std / sqrt(N)`` ``(p,)``: a bias beyond it is significant at about 1e-4."""
        return 4.0 * self.predicted_std / math.sqrt(self.trials)


def _fixed_truth_warning(model: FitModel, truth: np.ndarray) -> tuple[ArmcalWarning, ...]:
    moved = [
        f"{name} = {value * scale:g} {unit}"
        for name, unit, value, held, scale, free in zip(
            model.param_names,
            model.param_units,
            truth,
            model.held_values,
            model.display_scale,
            model.free,
            strict=True,
        )
        if not free and value != held
    ]
    if not moved:
        return ()
    return (
        ArmcalWarning(
            "fixed-not-nominal",
            f"the truth has {', '.join(moved)}, but the model holds "
            f"{'it' if len(moved) == 1 else 'them'} at its nominal value: every fit is "
            "misspecified and the bias shows the effect; to simulate a known parameter, put "
            "its value into the nominal arm and give it 0 in the truth",
        ),
    )


def _floats_per_trial(model: FitModel, m: int, method: str, loaded: bool = False) -> int:
    """Floats of working arrays a trial holds in one chunk (sets the chunk size); ``loaded``
    rows with loads (a model of compliance)."""
    n, p = model.n_joints, model.n_params
    encoder = model.noise is not None and model.noise.joint_sigma is not None
    if method == "closed-form" and not encoder:
        # Noise and positions (2 x 2m) and the estimates (a few p): every set shares one
        # factorization (whitened alike when the noise is anisotropic).  The chunks are
        # then large enough that the command's default 10^4 trials are one solve.
        return 2 * m * 3 + 4 * p
    if method == "closed-form" or encoder or loaded:
        # A closed form re-whitened set by set: whitening (4m), whitened Jacobian and
        # regressor rows with their factorization (a few 2m p); encoder noise draws and
        # evaluates the tip at q + dq, and a model of compliance its loads (a few m n).
        # Measured peaks (tracemalloc, 4-link arm, m = 20 and 100) are 0.75 to 1.05
        # CHUNK_BYTES.
        return 2 * m * (5 * p + 6) + 8 * m * n
    # Gauss-Newton takes the rows a block at a time (ROW_BLOCK rows of all the sets, at
    # least 64 of each): a set holds its measurements, their noise and its copy in the
    # solve (3 m d), and its share of a block: the kinematics' screws and Jacobians, the
    # free columns and the triangle's rows (about 8 d (p + 1) a row; 64 rows at most
    # where the block is shared by many sets).  Measured (tracemalloc, six-axis arm, 900
    # rows, blocks of 200) a trial adds about half of this.
    d = model.point_dim
    return 3 * m * d + 8 * min(m, 64) * d * (p + 1)


def _check_runs(trials: int, sigma: float | None) -> None:
    """At least 2 trials and, when given, a positive finite sigma (mm)."""
    if trials < 2:
        raise ArmcalError(f"a Monte Carlo needs at least 2 trials, got {trials}")
    if sigma is not None and not (sigma > 0 and math.isfinite(sigma)):
        raise ArmcalError(f"a Monte Carlo needs a positive noise sigma (mm), got {sigma}")


def _position_accumulator(
    model: FitModel,
    test_q: np.ndarray | None,
    truth: np.ndarray,
    predicted: np.ndarray,
    trials: int,
    rng: np.random.Generator,
) -> _PositionAccumulator | None:
    """The accumulator of tip errors at the test poses, or None (no test poses, or a
    model whose points are not linear in coordinates of its parameters)."""
    if test_q is None:
        return None
    test = model.plan_conditions(np.asarray(test_q, dtype=float))
    linear = model.linear_positions(test)
    if linear is None:
        return None
    sampler = rng.spawn(1)[0]  # leaves the noise stream as it is without test poses
    return _PositionAccumulator(model, linear, test, truth, predicted, trials, sampler)


@dataclass
class _Trials:
    """What the trials gave: the estimates' moments about the centre, the count of fits
    that did not converge, and the time they took (s)."""

    moments: _Moments
    not_converged: int
    seconds: float


def _run_trials(
    model: FitModel,
    rows: Conditions,
    truth: np.ndarray,
    sigma: float | None,
    trials: int,
    method: str,
    rng: np.random.Generator,
    centre: np.ndarray,
    positions: _PositionAccumulator | None,
    progress: ProgressCallback | None,
) -> _Trials:
    """Synthesize and identify ``trials`` measurement sets, a chunk of them per solve; the
    estimates go into moments about ``centre`` and into ``positions`` (when given)."""
    chunk = chunk_size(
        _floats_per_trial(model, rows.m, method, loaded=rows.loads is not None), trials
    )
    moments = _Moments(model.n_params)
    not_converged = 0
    start = time.perf_counter()
    done = 0
    exact = model.positions(rows, truth)  # once: only the noise differs between chunks
    while done < trials:
        size = min(chunk, trials - done)
        xy = synthesize_measurements(
            model,
            rows.q,
            truth,
            sigma,
            rng=rng,
            trials=size,
            target=rows.target,
            loads=rows.loads,
            exact=exact,
            frames=rows.frames,
            feature=rows.feature,
        )
        # Estimates to a tiny part of their spread, not to round-off: a trial stops where
        # its steps shrink so fast that the rest are below the tolerance (one pass less).
        found = solve(model, rows, xy, method=method, start=truth, settle=True)
        not_converged += int(found.converged.size - np.count_nonzero(found.converged))
        moments.add(found.params - centre)
        if positions is not None:
            positions.add(found.params)
        done += size
        if progress is not None:
            progress(done, trials)
    return _Trials(moments, not_converged, time.perf_counter() - start)


def _trial_warnings(
    model: FitModel,
    truth: np.ndarray,
    conditioning: ArmcalWarning | None,
    trials: int,
    not_converged: int,
    method: str,
) -> tuple[ArmcalWarning, ...]:
    """The Monte Carlo's warnings: an ill-conditioned plan, a truth that moves a fixed
    parameter, too few trials to judge a std, fits that did not converge."""
    warnings: list[ArmcalWarning] = [] if conditioning is None else [conditioning]
    warnings.extend(_fixed_truth_warning(model, truth))
    if trials < FEW_TRIALS:
        spread = 100 / np.sqrt(2 * (trials - 1))
        warnings.append(
            ArmcalWarning(
                "few-trials",
                f"with {trials} trials each empirical std is known to about +-{spread:.0f} % "
                f"(1 std), so a std ratio far from 1 may be chance; use {action('trials', 1000)} "
                f"or more (+-{100 / np.sqrt(2 * 999):.1f} %)",
            )
        )
    if not_converged:
        warnings.append(
            ArmcalWarning(
                "not-converged",
                f"{method} did not converge in {not_converged} of {trials} trials; their "
                "last iterates are included",
            )
        )
    return tuple(warnings)


def _for_plan(
    model: FitModel, rows: Conditions, truth: np.ndarray
) -> tuple[FitModel, np.ndarray, Identifiability]:
    """The model the plan's ``rows`` identify, the truth in its parameters, and the
    identifiability (:func:`~armcal.models.information.identified_or_prepared`): the model
    as given where the rows identify it, else the model prepared for the truth's points
    and the truth as its fit sees it (:meth:`~armcal.models.interface.FitModel.expressed`).
    NotIdentifiableError where the prepared model is not identified either (a minimal
    family is itself)."""
    ready, identified = identified_or_prepared(
        model, rows, lambda it: it.check_identifiable(rows), lambda: model.positions(rows, truth)
    )
    return ready, (truth if ready is model else ready.expressed(rows, truth)), identified


def monte_carlo(
    model: FitModel,
    q: ArrayLike,
    truth: ArrayLike,
    sigma: float | None,
    trials: int,
    *,
    method: str = "auto",
    rng: np.random.Generator | int | None = None,
    test_q: np.ndarray | None = None,
    progress: ProgressCallback | None = None,
    loads: Loads | None = None,
) -> MonteCarlo:
    """Identify ``trials`` noisy measurement sets of plan ``q`` and compare with theory.

    Parameters
    ----------
    model : FitModel
        The nominal model: its noise model and fixed parameters are the model
        simulated and identified.  A model the plan does not identify as given (a
        spatial arm as loaded) is prepared for it
        (:func:`~armcal.models.information.identifying`) and the truth expressed in its
        parameters; :attr:`MonteCarlo.model` and :attr:`MonteCarlo.truth` are those.
    q : ndarray, shape (m, n)
        The plan (rad), measured at every target of every pose; must identify
        every free parameter.
    truth : ndarray, shape (p,)
        Parameters of the virtual robot (mm, rad, ...).
    sigma : float or None
        Isotropic instrument noise (1 std, mm) overriding the model's, the
        encoder noise kept; None uses the model's noise as it is
        (:func:`~armcal.synthesis.simulated_noise`).
    trials : int
        Number of measurement sets.
    method : {"auto", "closed-form", "gauss-newton"}
        Solver (:func:`~armcal.identification.resolve_method`); every chunk of
        trials is one batched call of it.  Gauss-Newton starts at the truth:
        the Monte Carlo measures the estimator's spread, not the solver's reach.
    rng : numpy.random.Generator or int or None
        Noise source; the same seed gives the same result.
    test_q : ndarray, shape (k, n), optional
        Poses where the tip error of the calibrated model is measured (for a
        model whose points are linear in coordinates of its parameters,
        :class:`~armcal.models.interface.LinearPositions`; ignored otherwise).
    progress : callable, optional
        ``progress(done, total)`` after every chunk.
    loads : Loads, optional
        Every pose's payload and tip force (a model of joint compliance).

    Returns
    -------
    MonteCarlo

    Raises
    ------
    NotIdentifiableError
        If the plan cannot identify every free parameter.
    ArmcalError
        For fewer than 2 trials, no noise (or a ``sigma`` that is not positive and
        finite), an unknown method, or the closed form asked for a model
        without one.

    Notes
    -----
    The noise is drawn by :func:`~armcal.synthesis.synthesize_measurements` from
    the model's noise (instrument covariance and encoder noise, the latter
    exactly, through the points at ``q + dq``), and every set is identified by
    :func:`~armcal.identification.solve` on the model (weighted, over the free
    parameters).  The prediction is the generalized-least-squares covariance at
    the truth (:meth:`~armcal.models.interface.FitModel.covariance_factor`), to
    which the estimates' covariance tends for small noise.

    Tip errors at the test poses (:class:`PositionErrors`) cost O(N + k), not
    O(N k):

    * **RMS, exact.**  The points are linear in coordinates ``z`` of the
      parameters (for the planar arm the link phasors and the base, with
      ``u_{n+1} = 1``), so the squared error of a trial at ``x`` is
      ``|u(x)^T dz|^2`` and its mean over the N trials and k test poses is
      ``tr(S G)`` with ``S = mean_trials dz dz^H`` and ``G = mean_x conj(u(x))
      u(x)^T``.  Only the ``(L, L)`` matrix ``S`` is accumulated.  A fixed
      parameter is 0 in every estimate, and its rows of the predicted
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
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([260.0, 180.0])
    >>> result = monte_carlo(arm, orthogonal_plan(arm, 20), np.zeros(4), 0.1, 20000, rng=1)
    >>> bool(np.allclose(result.std, result.predicted_std, rtol=0.03))
    True
    """
    q = np.asarray(q, dtype=float)
    truth = checked_truth(model, truth)
    method = resolve_method(model, method)
    _check_runs(trials, sigma)
    noise = simulated_noise(model, sigma)
    model = model.with_noise(noise)
    reference = float(sigma) if sigma is not None else noise.sigma_mm
    rows = model.plan_conditions(q, loads)  # every target of every pose
    model, truth, identified = _for_plan(model, rows, truth)
    conditioning = ill_conditioned_warning(model, identified)
    rng = np.random.default_rng(rng)
    predicted, ok = predicted_covariance(model, rows, reference, truth)
    if not ok:
        raise ArmcalError("the plan cannot identify every parameter at the given truth")
    # Moments about the truth keep round-off small; a fixed parameter keeps its held value
    # in every estimate, so about it its mean and scatter are exactly 0 even when the truth
    # moves it.
    centre = np.where(model.free, truth, model.held_values)
    positions = _position_accumulator(model, test_q, truth, predicted, trials, rng)
    run = _run_trials(model, rows, truth, sigma, trials, method, rng, centre, positions, progress)
    warnings = _trial_warnings(model, truth, conditioning, trials, run.not_converged, method)
    return MonteCarlo(
        model=model,
        q=q,
        truth=truth,
        sigma_mm=reference,
        method=method,
        trials=int(trials),
        mean=centre + run.moments.mean,
        covariance=run.moments.covariance(),
        predicted_covariance=predicted,
        position=None if positions is None else positions.result(),
        not_converged=run.not_converged,
        seconds=run.seconds,
        warnings=warnings,
    )
