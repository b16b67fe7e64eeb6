"""Ascent within the joint limits and the instrument's view (optimizer and certificate).

* :func:`to_u` / :func:`to_q` -- unconstrained variables ``u`` with
  ``q = c + h sin u`` (``c, h`` the middle and half-width of each joint's
  range), so every iterate is inside the limits;
* :func:`view_penalty` -- ``sum min(0, g)^2`` of the view's constraints
  (:meth:`~armcal.models.interface.FitModel.view_constraints`) and its gradient,
  with :func:`penalty_weight` growing during an ascent;
* :func:`adam_ascent` -- batched Adam ascent of an objective in ``u``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..models import FitModel
from ..progress import ProgressCallback

__all__ = [
    "adam_ascent",
    "penalty_weight",
    "to_q",
    "to_u",
    "view_penalty",
]


def view_penalty(model: FitModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``sum min(0, g)^2`` over poses and constraints ``(...)`` and its gradient in ``q``."""
    constraints = model.view_constraints(q)
    if constraints is None:
        return np.zeros(q.shape[:-2]), np.zeros_like(q)
    g, dg = constraints
    violation = np.minimum(g, 0.0)
    grad = np.einsum("...k,...kn->...n", 2.0 * violation, dg)
    return np.sum(violation**2, axis=(-2, -1)), grad


def to_u(model: FitModel, q: np.ndarray) -> np.ndarray:
    """Unconstrained variables ``u`` with ``q = c + h sin u`` (``c, h``: middle, half-width)."""
    lo, hi = model.joint_limits[:, 0], model.joint_limits[:, 1]
    return np.arcsin(np.clip((q - (lo + hi) / 2) / ((hi - lo) / 2), -1.0, 1.0))


def to_q(model: FitModel, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles within the limits and ``dq/du`` for the variables of :func:`to_u`."""
    lo, hi = model.joint_limits[:, 0], model.joint_limits[:, 1]
    half = (hi - lo) / 2
    return (lo + hi) / 2 + half * np.sin(u), half * np.cos(u)


def adam_ascent(
    objective: Callable[[np.ndarray, int], tuple[np.ndarray, np.ndarray]],
    u: np.ndarray,
    *,
    steps: int,
    learning_rate: float,
    progress: ProgressCallback | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Batched Adam ascent of ``objective(u, step) -> (value (S,), grad like u)``;
    ``progress(step, steps)`` every 10 steps."""
    first = np.zeros_like(u)
    second = np.zeros_like(u)
    beta1, beta2, eps = 0.9, 0.999, 1e-12
    for step in range(1, steps + 1):
        _, grad = objective(u, step)
        first = beta1 * first + (1 - beta1) * grad
        second = beta2 * second + (1 - beta2) * grad**2
        lr = learning_rate * (0.05 + 0.95 * (1 - step / steps))  # anneal to refine
        u = u + lr * (first / (1 - beta1**step)) / (np.sqrt(second / (1 - beta2**step)) + eps)
        if progress is not None and step % 10 == 0:
            progress(step, steps)
    value, _ = objective(u, steps)
    return u, value


def penalty_weight(model: FitModel, progress: float) -> float:
    """The view penalty's weight at ``progress`` (0..1) of an ascent, per mm^2 of violation."""
    reach = model.reach_mm
    return 10.0 ** (1.0 + 5.0 * progress) / reach**2
