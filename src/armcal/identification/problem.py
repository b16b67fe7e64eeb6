"""One identification problem -- a model, its rows and the measured points -- and its fits.

:class:`Problem` fits subsets of the rows, with weights or from a start
(:mod:`~armcal.identification.solvers`); every :class:`Fit` carries what the
judgement needs: residuals, whitened residuals, the covariance factor and each
pose's leverage, the last two computed on first use (the robust iterations only
need the residuals).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..errors import ArmcalError
from ..models import ROW_BLOCK, Conditions, FitModel
from ..models.information import factor_from_svd
from ..noise import NoiseModel, relative_noise
from ..numerics import RowTriangle
from .judgement import PoseTest, studentized_test
from .solvers import LastStep, solve

__all__ = [
    "Fit",
    "Problem",
    "reference_sigma",
    "sigma_parts",
    "sigma_unit",
    "sigma_words",
]


def reference_sigma(model: FitModel, row_sigma: np.ndarray | None) -> float:
    """The noise every whitened residual is measured in (mm).

    The noise model's reference; with per-row sigma, ``sqrt(1 / mean(1 / s_i^2))``,
    the isotropic noise that carries the same information (:mod:`armcal.noise`).
    """
    if row_sigma is not None:
        return float(np.sqrt(1.0 / np.mean(1.0 / row_sigma**2)))
    return _noise(model).sigma_mm


def sigma_parts(
    model: FitModel, conditions: Conditions | None, sigma: float
) -> tuple[float, float] | None:
    """For rows some of which read turns (partial coordinates' ``rx_deg``...), the
    coordinates' and the turns' sigma (mm, rad) that ``sigma``, in the rows' reference
    (:func:`reference_sigma`), stands for; None for rows of one unit."""
    turn = None if conditions is None else model.turn_rows(conditions)
    if turn is None or conditions is None or conditions.sigma_mm is None:
        return None
    if not np.any(turn) or np.all(turn):
        return None
    rows = np.asarray(conditions.sigma_mm, dtype=float)
    ratio = sigma / reference_sigma(model, rows)
    return reference_sigma(model, rows[~turn]) * ratio, reference_sigma(model, rows[turn]) * ratio


def sigma_unit(model: FitModel, conditions: Conditions | None, sigma: float) -> tuple[float, str]:
    """What a sigma (and a scale) in the rows' reference is multiplied by, and its unit, for
    words: 1 and the readings' unit; for rows of coordinates and turns, ``1 / sigma`` and
    "times the sigmas given (... mm a coordinate, ... deg a turn)"."""
    parts = sigma_parts(model, conditions, sigma)
    if parts is None:
        return 1.0, model.reading_unit
    return 1.0 / sigma, f"times the sigmas given ({sigma_words(parts)})"


def sigma_words(parts: tuple[float, float]) -> str:
    """``"0.01 mm a coordinate, 0.001 deg a turn"`` of :func:`sigma_parts`."""
    return f"{parts[0]:.4g} mm a coordinate, {np.degrees(parts[1]):.4g} deg a turn"


def _noise(model: FitModel) -> NoiseModel:
    """The model's noise model, or unit isotropic noise (weights are relative)."""
    return relative_noise(model.noise)


class Fit:
    """One least-squares fit of a :class:`Problem` and what the judgement needs, all m poses.

    Attributes
    ----------
    params : ndarray, shape (p,)
    used : ndarray of bool, shape (m,)
        The poses fitted.
    iterations : int
    converged : bool
    residuals : ndarray, shape (m, d)
        Measured minus fitted, mm, every pose (those left out too).
    whitened : ndarray, shape (m, d)
        ``W_i e_i`` in mm of the reference noise (:func:`reference_sigma`).
    """

    def __init__(
        self,
        problem: Problem,
        params: np.ndarray,
        used: np.ndarray,
        iterations: int,
        converged: bool,
        *,
        last: LastStep | None = None,
    ) -> None:
        model, cond = problem.model, problem.conditions
        self.params, self.used = params, used
        self._last = last  # the rows of a plain fit's last step (solvers.LastStep)
        self.iterations, self.converged = iterations, converged
        self.residuals = problem.points - model.positions(cond, params)  # mm
        w = model.whitening(cond, params)
        if w is not None and cond.sigma_mm is not None:  # to the rows' own reference
            w = w * (reference_sigma(model, cond.sigma_mm) / _noise(model).sigma_mm)
        self._w, self._problem = w, problem
        self.whitened = self.residuals if w is None else (w @ self.residuals[:, :, None])[:, :, 0]

    @cached_property
    def factor(self) -> np.ndarray:
        """``G`` ``(p_f, p_f)`` with ``(J_w^T J_w)^-1 = G G^T`` over the poses fitted.

        Unweighted over every pose: the model's own covariance factor (the planar
        arm's from its plan's factorization); otherwise from the SVD of the used
        rows' triangle (a block of rows at a time); where the fit's last step was
        within its tolerance, that step's rows'.
        """
        problem = self._problem
        model = problem.model
        if self._last is not None:
            factor, ok = factor_from_svd(self._last.rows.svd(), model.free)
        elif self._w is None and self.used.all():
            factor, ok = model.covariance_factor(problem.conditions, self.params)
        else:
            rows = RowTriangle(model.n_free)
            for block, part in problem.conditions.blocks():
                jac = self._jacobian_rows(block, part)[self.used[part]]
                rows.add(jac.reshape(-1, model.n_free))
            factor, ok = factor_from_svd(rows.svd(), model.free)
        if not bool(ok):  # identifiable at nominal, so only for absurd deviations
            raise ArmcalError(
                f"the Jacobian is singular at the estimate; {problem.suspect or 'check the data'}"
            )
        return factor[..., model.free, :]

    @cached_property
    def leverage(self) -> np.ndarray:
        """``B_i B_i^T`` ``(m, d, d)`` with ``B_i = W_i J_i G``: each pose's hat block.

        A block of rows at a time: the Jacobian ``(m, d, p)`` and its products would
        be the largest arrays of an identification at 10^5 rows, for blocks of ``d x d``.
        """
        factor = self.factor
        m, d = self.residuals.shape
        out = np.empty((m, d, d))
        for block, part in self._problem.conditions.blocks():
            last = self._last
            rows = last.blocks[part] if last is not None else self._jacobian_rows(block, part)
            b = rows @ factor
            out[part] = b @ np.swapaxes(b, -1, -2)
        self._last = None  # its rows have served the factor and every row's block
        return out

    def _jacobian_rows(self, block: Conditions, part: slice) -> np.ndarray:
        """The whitened Jacobian ``(k, d, p_f)`` over the free parameters of the rows
        ``part`` (whose conditions are ``block``), at the estimate."""
        model = self._problem.model
        jac = model.jacobian(block, self.params)[..., model.free]
        return jac if self._w is None else self._w[part] @ jac

    def scale(self, dof: int) -> float:
        """``sqrt(RSS_w / dof)`` over the poses in the fit (mm of the reference noise)."""
        return float(np.sqrt(np.sum(self.whitened[self.used] ** 2) / dof))

    def test(self, sigma: float, *, given: bool) -> PoseTest:
        """The studentized outlier test of every pose against this fit."""
        return studentized_test(
            self.whitened / sigma,
            self.leverage,
            self.used,
            self._problem.model.n_free,
            sigma_given=given,
        )


class Problem:
    """The data of one identification -- model, conditions, points -- and the fits made on it.

    Parameters
    ----------
    model : FitModel
    conditions : Conditions
        Of every row (:meth:`~armcal.models.interface.FitModel.conditions`).
    points : ndarray, shape (m, d)
        Measured points, mm.
    method : {"closed-form", "gauss-newton"}
        The solver (already resolved from ``"auto"``).
    tol, max_iter
        Gauss-Newton's step tolerance (relative to the reach) and iteration cap.
    """

    def __init__(
        self,
        model: FitModel,
        conditions: Conditions,
        points: np.ndarray,
        method: str,
        tol: float,
        max_iter: int,
    ) -> None:
        self.model, self.conditions, self.points = model, conditions, points
        self.method, self.tol, self.max_iter = method, tol, max_iter
        self._subsets: dict[bytes, Conditions] = {}
        #: What looks wrong with the data (:mod:`~armcal.identification.diagnosis`), said
        #: when a fit fails on its absurd estimate instead of "check the data".
        self.suspect: str | None = None

    @property
    def m(self) -> int:
        return self.conditions.m

    def rows(self, used: np.ndarray) -> Conditions:
        """The conditions of the poses ``used``, one object per subset: what one fit or
        check of a subset factors (:meth:`Conditions.memo`), the next reuses."""
        if used.all():
            return self.conditions
        key = used.tobytes()
        if key not in self._subsets:
            self._subsets[key] = self.conditions.take(used)
        return self._subsets[key]

    def identifiable(self, used: np.ndarray) -> bool:
        """Whether the poses ``used`` identify every free parameter."""
        model = self.model
        if model.point_dim * int(np.count_nonzero(used)) < model.n_free:
            return False
        return model.identifiability(self.rows(used))[0].identifiable

    def fit(
        self,
        used: np.ndarray,
        *,
        weights: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> Fit:
        """The fit to the poses ``used`` (times ``weights``, from ``start`` if given)."""
        # The last step's rows serve the covariance and leverage of a plain fit of every
        # row, where they save passes of the model (more rows than a block).
        plain = weights is None and bool(used.all()) and self.conditions.sigma_mm is None
        plain = plain and self.m > ROW_BLOCK
        found = solve(
            self.model,
            self.rows(used),
            self.points[used],
            method=self.method,
            weights=None if weights is None else weights[used],
            start=start,
            tol=self.tol,
            max_iter=self.max_iter,
            keep=plain,
        )
        return Fit(
            self,
            found.params[0],
            used,
            int(found.iterations[0]),
            bool(found.converged[0]),
            last=found.last,
        )
