"""One call for an optimal plan: analytic if it fits, else optimize and exchange; certified."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..arm import PlanarArm
from ..criteria import CRITERIA, d_efficiency
from ..errors import ArmcalError
from .certificate import Certificate, certify
from .exchange import exchange_plan
from .optimizer import optimize_plan
from .plans import analytic_plan, feasible_poses

__all__ = [
    "METHODS",
    "Design",
    "design",
]


Method = Literal["auto", "analytic", "optimize", "exchange"]


METHODS = ("auto", "analytic", "optimize", "exchange")


@dataclass(frozen=True, eq=False)
class Design:
    """An optimal calibration plan and what is known about its quality.

    Attributes
    ----------
    arm : PlanarArm
    q : ndarray, shape (m, n)
        The plan's joint angles in rad.
    criterion : str
        Criterion optimized (key of :data:`armcal.criteria.CRITERIA`).
    method : str
        How the plan was made: ``analytic``, ``optimize``, ``optimize+exchange`` or
        ``exchange``.
    d_efficiency : float
        ``(det F / det F_opt)^(1/p)``: relative to the unconstrained optimum.
    certificate : Certificate or None
        Lower bound relative to the best plan within the constraints (None when
        not asked for).
    notes : tuple of str
        Why a method was not used (e.g. the analytic plan breaks the limits).
    """

    arm: PlanarArm
    q: np.ndarray
    criterion: str
    method: str
    d_efficiency: float
    certificate: Certificate | None
    notes: tuple[str, ...]


def _closed_form_note(arm: PlanarArm, m: int) -> str:
    """Why the closed-form plans were not used -- only they, not orthogonal plans in general."""
    where = "joint limits" if arm.region is None else "joint limits and measurement region"
    first = 1 if arm.base_offset else 2  # joint 1 steps too when the base is identified
    return (
        f"the closed-form orthogonal plans (the paper's Table I family: joints "
        f"{first}..{arm.n_joints} at {m} angles {360 / m:g} deg apart"
        + (", placed for the largest joint-limit margin" if arm.region is not None else "")
        + f") do not fit the {where} of {arm.name}; the optimizer searched all plans within "
        f"the {where} instead"
    )


def design(
    arm: PlanarArm,
    m: int,
    *,
    criterion: str = "D",
    method: Method = "auto",
    rng: np.random.Generator | int | None = None,
    candidates: np.ndarray | None = None,
    with_certificate: bool = True,
) -> Design:
    """An optimal ``m``-pose plan within the arm's joint limits and measurement region.

    Parameters
    ----------
    arm : PlanarArm
    m : int
        Number of poses; at least ``ceil(p / 2)``.
    criterion : {"D", "A", "E"}
        Criterion to maximize (the certificate is always for D).
    method : {"auto", "analytic", "optimize", "exchange"}
        ``auto`` takes the analytic plan when it fits the constraints, else
        optimizes and (for D) polishes by exchange over feasible candidates.
    rng : numpy.random.Generator or int or None
        The same seed gives the same plan.
    candidates : ndarray, shape (N, n), optional
        Poses the robot can really reach, for ``exchange`` (default: random
        feasible poses).
    with_certificate : bool
        Certify the plan (:func:`certify`); searches that design many plans
        skip it.

    Returns
    -------
    Design
    """
    if criterion not in CRITERIA:
        raise ArmcalError(f"unknown criterion {criterion!r}; choose one of {', '.join(CRITERIA)}")
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    min_poses = -(-arm.n_params // 2)
    if m < min_poses:
        raise ArmcalError(
            f"{m} poses give {2 * m} equations for the {arm.n_params} parameters of {arm.name}; "
            f"use --poses {min_poses} or more"
        )
    rng = np.random.default_rng(rng)
    notes: list[str] = []
    q: np.ndarray | None = None
    used: str = method
    if method in ("auto", "analytic"):
        try:
            q, used = analytic_plan(arm, m), "analytic"
        except ArmcalError:
            if method == "analytic":
                raise
            notes.append(_closed_form_note(arm, m))
    if q is None and method == "exchange":
        pool = feasible_poses(arm, 4000, rng=rng) if candidates is None else candidates
        q = exchange_plan(arm, m, pool, rng=rng)
        if criterion != "D":
            notes.append("exchange maximizes D; the plan was not tuned for " + criterion)
    elif q is None:
        q, used = optimize_plan(arm, m, criterion=criterion, rng=rng), "optimize"
        if criterion == "D":
            pool = feasible_poses(arm, 4000, rng=rng) if candidates is None else candidates
            polished = exchange_plan(arm, m, pool, start=q, rng=rng)
            if float(d_efficiency(arm, polished)) > float(d_efficiency(arm, q)) * (1 + 1e-12):
                q, used = polished, "optimize+exchange"
    q = np.asarray(q, dtype=float)
    return Design(
        arm=arm,
        q=q,
        criterion=criterion,
        method=used,
        d_efficiency=float(d_efficiency(arm, q)),
        certificate=certify(arm, q, rng=rng) if with_certificate else None,
        notes=tuple(notes),
    )
