"""Task-aimed criteria: the calibrated arm's predicted accuracy where it will work.

A calibration engineer cares about the arm's accuracy at the poses of its
program, not about a determinant.  With ``M`` the plan's normalized information
in the design coordinates and ``B_t`` a test point's rows there (its position
Jacobian, unweighted by the instrument), the calibrated model's predicted
variance at test point ``t`` is proportional to ``v_t(M) = tr(M^-1 B_t^T B_t)``:

* **I** (integrated, Box and Draper 1959; "V-optimality"): the mean of ``v_t``
  over the test points, ``tr(M^-1 L)`` with ``L`` their mean ``B_t^T B_t``: an
  A-criterion weighted by the task, convex in ``M^-1``;
* **G** (global, Kiefer and Wolfowitz 1960, here over the test points rather than
  the design region): the largest ``v_t``.  The optimizer climbs a smooth
  maximum, ``(1/beta) log sum exp(beta log v_t)``, within ``log(T) / beta`` of
  the true one; efficiencies are reported with the true maximum.

Both are efficiencies in the registry's sense (larger is better, 1 for
``M = I``): ``tr(L) / tr(M^-1 L)`` and ``max_t tr(B_t^T B_t) / max_t v_t``.  The
predicted position error after calibration in mm is ``sigma sqrt(v_t / rows)``
(:func:`armcal.criteria.position_accuracy` reports it for every plan).
"""

from __future__ import annotations

import numpy as np

from ..choices import TASK_CRITERIA
from ..criteria import Criterion
from ..errors import ArmcalError
from ..models import FitModel
from ..numerics import spd_inverse

__all__ = [
    "SMOOTH_MAX_BETA",
    "TASK_CRITERIA",
    "task_criterion",
]


#: Sharpness of the smooth maximum the optimizer climbs for G: with ``T`` test points it
#: exceeds the maximum of ``log v_t`` by at most ``log(T) / beta`` (0.35 for 1000 points,
#: a variance within a factor 1.4), while its gradient spreads over the near-maximal
#: points, which a plain maximum's does not.
SMOOTH_MAX_BETA = 20.0


def _test_blocks(model: FitModel, test_q: np.ndarray) -> np.ndarray:
    """Every test point's rows ``(T, d, p_f)`` in the design coordinates, unweighted."""
    if model.point_dim != model.position_dim:
        raise ArmcalError(
            "the I and G criteria are for position measurements; design with D, A or E "
            "for a 6-DoF instrument"
        )
    plain = model.with_noise(None)  # the position Jacobian itself, not weighted by noise
    # The arm's own tool points (an instrument's readings are not where the arm is): its
    # parameters are the model's first, an instrument's columns zero.
    arm = plain.alone(np.zeros(plain.n_params), np.zeros((plain.n_params, plain.n_params)))[0]
    blocks = arm.plan_information(np.asarray(test_q, dtype=float)).blocks()
    blocks = blocks.reshape(-1, arm.position_dim, blocks.shape[-1])
    extra = model.n_free - blocks.shape[-1]
    return np.concatenate([blocks, np.zeros((*blocks.shape[:-1], extra))], axis=-1)


def task_criterion(name: str, model: FitModel, test_q: np.ndarray) -> Criterion:
    """The criterion ``"I"`` or ``"G"`` of ``model`` aimed at the test poses ``test_q``
    ``(k, n)`` (every target of each), for :func:`armcal.doe.optimize_plan`."""
    if name not in TASK_CRITERIA:
        raise ArmcalError(f"unknown task criterion {name!r}; choose I or G")
    blocks = _test_blocks(model, test_q)
    per_point = np.einsum("trp,trq->tpq", blocks, blocks)  # B_t^T B_t
    if name == "I":
        mean = per_point.mean(axis=0)
        scale = float(np.trace(mean))

        def i_eff(fs: np.ndarray) -> np.ndarray:
            return scale / np.einsum("...pq,qp->...", spd_inverse(fs), mean)

        def i_grad(fs: np.ndarray) -> np.ndarray:
            inv = spd_inverse(fs)
            weighted = inv @ mean @ inv
            return weighted / np.trace(inv @ mean, axis1=-2, axis2=-1)[..., None, None]

        return Criterion("I", TASK_CRITERIA["I"], i_eff, i_grad, _no_singular_values)
    largest = float(np.max(np.trace(per_point, axis1=-2, axis2=-1)))

    def variances(fs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        inv = spd_inverse(fs)
        return inv, np.einsum("...pq,tqp->...t", inv, per_point)

    def g_eff(fs: np.ndarray) -> np.ndarray:
        return largest / np.max(variances(fs)[1], axis=-1)

    def g_grad(fs: np.ndarray) -> np.ndarray:
        # d log v_t / d Fs = -Fs^-1 L_t Fs^-1 / v_t; the smooth maximum weighs them by
        # softmax(beta log v_t); the log-efficiency's gradient is minus that.
        inv, v = variances(fs)
        logs = SMOOTH_MAX_BETA * np.log(v)
        weights = np.exp(logs - logs.max(axis=-1, keepdims=True))
        weights /= weights.sum(axis=-1, keepdims=True)
        mix = np.einsum("...t,tpq->...pq", weights / v, per_point)
        return inv @ mix @ inv

    return Criterion("G", TASK_CRITERIA["G"], g_eff, g_grad, _no_singular_values)


def _no_singular_values(s: np.ndarray) -> np.ndarray:
    """Task criteria need the test poses, not only the information's singular values."""
    raise ArmcalError("the I and G criteria are evaluated on the information, with test poses")
