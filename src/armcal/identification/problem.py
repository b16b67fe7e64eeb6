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
from ..models import Conditions, FitModel
from ..models.information import covariance_factor_from
from ..noise import NoiseModel
from .judgement import PoseTest, studentized_test
from .solvers import solve

__all__ = [
    "Fit",
    "Problem",
    "point_norms",
    "reference_sigma",
]


def reference_sigma(model: FitModel, row_sigma: np.ndarray | None) -> float:
    """The noise every whitened residual is measured in (mm).

    The noise model's reference; with per-row sigma, ``sqrt(1 / mean(1 / s_i^2))``,
    the isotropic noise that carries the same information (:mod:`armcal.noise`).
    """
    if row_sigma is not None:
        return float(np.sqrt(1.0 / np.mean(1.0 / row_sigma**2)))
    return _noise(model).sigma_mm


def _noise(model: FitModel) -> NoiseModel:
    """The model's noise model, or unit isotropic noise (weights are relative)."""
    return model.noise if model.noise is not None else NoiseModel.isotropic(1.0)


def point_norms(points: np.ndarray) -> np.ndarray:
    """Euclidean length ``(...)`` of every point ``(..., d)`` (``hypot`` in the plane)."""
    if points.shape[-1] == 2:
        return np.hypot(points[..., 0], points[..., 1])
    return np.linalg.norm(points, axis=-1)


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
    ) -> None:
        model, cond = problem.model, problem.conditions
        self.params, self.used = params, used
        self.iterations, self.converged = iterations, converged
        self.residuals = problem.points - model.positions(cond, params)  # mm
        w = model.whitening(cond, params)
        if w is not None and cond.sigma_mm is not None:  # to the rows' own reference
            w = w * (reference_sigma(model, cond.sigma_mm) / _noise(model).sigma_mm)
        self._w, self._problem = w, problem
        self.whitened = self.residuals if w is None else (w @ self.residuals[:, :, None])[:, :, 0]

    @cached_property
    def jacobian(self) -> np.ndarray:
        """Whitened Jacobian ``(m, d, p_f)`` over the free parameters, at the estimate."""
        problem = self._problem
        jac = problem.model.jacobian(problem.conditions, self.params)[..., problem.model.free]
        return jac if self._w is None else self._w @ jac

    @cached_property
    def factor(self) -> np.ndarray:
        """``G`` ``(p_f, p_f)`` with ``(J_w^T J_w)^-1 = G G^T`` over the poses fitted.

        Unweighted over every pose: the model's own covariance factor (the planar
        arm's from its plan's factorization); otherwise from the SVD of the used
        rows.
        """
        problem = self._problem
        model = problem.model
        if self._w is None and self.used.all():
            factor, ok = model.covariance_factor(problem.conditions, self.params)
            factor = factor[..., model.free, :]
        else:
            rows = self.jacobian[self.used].reshape(-1, model.n_free)
            factor, ok = covariance_factor_from(rows, model.free)
            factor = factor[..., model.free, :]
        if not bool(ok):  # identifiable at nominal, so only for absurd deviations
            raise ArmcalError("the Jacobian is singular at the estimate; check the data")
        return factor

    @cached_property
    def leverage(self) -> np.ndarray:
        """``B_i B_i^T`` ``(m, d, d)`` with ``B_i = W_i J_i G``: each pose's hat block."""
        b = self.jacobian @ self.factor
        return b @ np.swapaxes(b, -1, -2)

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

    @property
    def m(self) -> int:
        return self.conditions.m

    def identifiable(self, used: np.ndarray) -> bool:
        """Whether the poses ``used`` identify every free parameter."""
        model = self.model
        if model.point_dim * int(np.count_nonzero(used)) < model.n_free:
            return False
        return model.identifiability(self.conditions.take(used))[0].identifiable

    def fit(
        self,
        used: np.ndarray,
        *,
        weights: np.ndarray | None = None,
        start: np.ndarray | None = None,
    ) -> Fit:
        """The fit to the poses ``used`` (times ``weights``, from ``start`` if given)."""
        everyone = bool(used.all())
        conditions = self.conditions if everyone else self.conditions.take(used)
        found = solve(
            self.model,
            conditions,
            self.points[used],
            method=self.method,
            weights=None if weights is None else weights[used],
            start=start,
            tol=self.tol,
            max_iter=self.max_iter,
        )
        return Fit(self, found.params[0], used, int(found.iterations[0]), bool(found.converged[0]))
