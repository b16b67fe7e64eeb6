"""One call for an optimal plan: analytic if it fits and is optimal, else optimize and exchange."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..criteria import CRITERIA, d_efficiency, efficiencies
from ..errors import ArmcalError
from ..models import PlanarArm, unit_trace
from .certificate import Certificate, certify
from .exchange import exchange_plan
from .model import attains_unit_bound, model_description, rotation_invariant
from .optimizer import optimize_plan
from .order import ORDERS, Order, joint_travel, order_poses
from .plans import DISTINCT_TOLERANCE, analytic_plan, feasible_poses, repeated_poses

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
        The arm and the model designed for: its noise model and fixed
        parameters (:mod:`armcal.doe.model`).
    q : ndarray, shape (m, n)
        The plan's joint angles in rad.
    criterion : str
        Criterion optimized (key of :data:`armcal.criteria.CRITERIA`).
    method : str
        How the plan was made: ``analytic``, ``optimize``, ``optimize+exchange`` or
        ``exchange``.
    d_efficiency : float
        :func:`armcal.criteria.d_efficiency` on the arm's model.  For the paper's
        model ``(det F / det F_opt)^(1/p)``, relative to the unconstrained
        optimum; wherever :func:`armcal.models.planar_information.unit_trace` holds at most 1,
        and 1 only for a plan with identity normalized information; for other
        models the weighted information's ``det^(1/p_f)``, which compares plans
        of that model only (the certificate says how far from its optimum).
    certificate : Certificate or None
        Lower bound relative to the best plan within the constraints (None when
        not asked for).
    notes : tuple of str
        Why a method was not used (e.g. the analytic plan breaks the limits),
        whether the paper's closed-form plans are optimal for the arm's model,
        and what making the poses distinct cost.
    order : str
        How the poses are ordered (key of :data:`armcal.doe.order.ORDERS`):
        ``travel`` for short joint travel, ``none`` as the method made them.
    joint_travel : float
        :func:`armcal.doe.order.joint_travel` of ``q`` in its order (rad).
    joint_travel_unordered : float
        The joint travel (rad) in the order the method produced the poses, before
        ordering; equal to ``joint_travel`` for ``order="none"``.
    distinct : bool
        Whether the plan was made of distinct poses (no two within
        :data:`armcal.doe.plans.DISTINCT_TOLERANCE` on every joint).
    normalized : bool
        Whether ``d_efficiency`` is relative to an optimum of 1
        (:func:`~armcal.models.planar_information.unit_trace`); otherwise it is the
        D-criterion of the weighted information, and only the certificate compares
        the plan with the best one.
    """

    arm: PlanarArm
    q: np.ndarray
    criterion: str
    method: str
    d_efficiency: float
    certificate: Certificate | None
    notes: tuple[str, ...]
    order: str
    joint_travel: float
    joint_travel_unordered: float
    distinct: bool
    normalized: bool = True

    @property
    def optimum_by_search(self) -> bool:
        """Whether a search (not the closed form) found a plan at the optimum of 1."""
        return self.normalized and self.method != "analytic" and self.d_efficiency >= 1 - 1e-9

    def __repr__(self) -> str:
        cert = self.certificate
        certified = "" if cert is None else f", certified >= {cert.certified_d_efficiency:.4f}"
        return (
            f"Design({self.q.shape[0]} poses of {self.arm.name}, criterion {self.criterion}, "
            f"{self.method}: D {self.d_efficiency:.4f}{certified})"
        )


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


_PAPER_ASSUMES = (
    "the paper's orthogonal plans and its D* criterion assume isotropic iid noise and every "
    "parameter free"
)


@dataclass(frozen=True)
class _ClosedForm:
    """A closed-form orthogonal plan that fits, and its D-criterion on the model."""

    q: np.ndarray
    turns_joint1: bool
    d_efficiency: float


def _closed_form_plans(arm: PlanarArm, m: int) -> tuple[list[_ClosedForm], ArmcalError | None]:
    """The closed-form orthogonal plans that fit, and why the paper's own does not (or None).

    Besides the paper's family, the one with joint 1 stepping too when the
    model is not invariant to turning joint 1 (anisotropic instrument noise):
    for ``m > 2 n`` it is D-optimal there (:func:`analytic_plan`).
    """
    plans: list[_ClosedForm] = []
    failure: ArmcalError | None = None
    variants = [False] + ([True] if not (rotation_invariant(arm) or arm.base_offset) else [])
    for turns in variants:
        try:
            q = analytic_plan(arm, m, turn_joint1=turns)
        except ArmcalError as error:
            failure = failure if turns else error
            continue
        plans.append(_ClosedForm(q, turns, float(d_efficiency(arm, q))))
    return plans, failure


def _closed_form_would_be_optimal(arm: PlanarArm, m: int) -> bool:
    """Whether a closed-form plan would be D-optimal for the model without limits or region."""
    free = arm.replace(joint_limits=None, region=None)
    return any(attains_unit_bound(free, plan.q) for plan in _closed_form_plans(free, m)[0])


def _optimal_closed_form_note(arm: PlanarArm, chosen: _ClosedForm, paper_d: float | None) -> str:
    """Why a closed-form plan is D-optimal for a model that is not the paper's.

    ``paper_d`` is the D-criterion of the paper's plan (joint 1 held still), None
    when it does not fit.
    """
    how = "this closed-form orthogonal plan reaches it"
    if chosen.turns_joint1:
        paper = "does not fit" if paper_d is None else f"reaches only {paper_d:.4f}"
        how = (
            "the closed-form orthogonal plan with joint 1 stepping too reaches it (the paper's, "
            f"with joint 1 held still, {paper})"
        )
    return (
        f"{model_description(arm)}: every pose's information over the {arm.n_free} free "
        f"parameters still has trace {arm.n_free}, so no plan has a larger D-criterion than 1, "
        f"and {how}: it is D-optimal for this model"
    )


def _score(arm: PlanarArm, q: np.ndarray, criterion: str) -> float:
    """The efficiency ``criterion`` of plan ``q`` on the arm's model."""
    return float(efficiencies(arm, q)[criterion])


def design(
    arm: PlanarArm,
    m: int,
    *,
    criterion: str = "D",
    method: Method = "auto",
    rng: np.random.Generator | int | None = None,
    candidates: np.ndarray | None = None,
    with_certificate: bool = True,
    order: Order = "travel",
    distinct: bool = False,
) -> Design:
    """An optimal ``m``-pose plan for the arm's model, within its joint limits and region.

    Parameters
    ----------
    arm : PlanarArm
        The arm, with the noise model and fixed parameters to design for.
    m : int
        Number of poses; at least ``ceil(p_f / 2)`` for ``p_f`` free parameters.
    criterion : {"D", "A", "E"}
        Criterion to maximize (the certificate is always for D).
    method : {"auto", "analytic", "optimize", "exchange"}
        ``auto`` takes a closed-form orthogonal plan when it fits the constraints
        and is provably optimal for the model (below), else optimizes and (for
        D) polishes by exchange over feasible candidates.
    rng : numpy.random.Generator or int or None
        The same seed gives the same plan.
    candidates : ndarray, shape (N, n), optional
        Poses the robot can really reach, for ``exchange`` (default: random
        feasible poses).
    with_certificate : bool
        Certify the plan (:func:`certify`); searches that design many plans
        skip it.
    order : {"travel", "none"}
        ``travel`` puts the poses in an order with short joint travel for the
        shop floor (:func:`armcal.doe.order.order_poses`); ``none`` keeps the
        order the method produced.  Either way the plan is the same set of
        poses, with the same criteria and certificate.
    distinct : bool
        Make every pose distinct: no two poses within
        :data:`armcal.doe.plans.DISTINCT_TOLERANCE` rad on every joint (see
        Notes).  Off by default: an optimal exact plan may repeat a pose.

    Returns
    -------
    Design

    Raises
    ------
    ArmcalError
        If ``m`` is too small for the free parameters, the criterion, method or
        order is unknown, ``method="analytic"`` and no closed-form plan fits
        (or, with ``distinct``, every one that fits repeats a pose), or
        ``distinct`` and fewer than ``m`` candidates are distinct.

    Notes
    -----
    Every criterion is the model's (:mod:`armcal.doe.model`): the weighted
    information over the free parameters.  The paper's orthogonal plans are
    optimal for its model -- isotropic iid noise, every parameter free -- by
    Hadamard's bound; ``auto`` takes a closed-form plan whenever the model keeps
    that bound (:func:`armcal.models.planar_information.unit_trace`) and the plan reaches it,
    which covers fixed lengths, base coordinates or leading offsets under
    isotropic noise, and anisotropic instrument noise with every parameter free
    (joint 1 stepping too, ``m > 2 n``).  Otherwise -- encoder noise, a fixed
    ``dq_j`` that ties links together, fixed parameters under anisotropic noise,
    or binding limits -- it optimizes on the model, starting also from the
    closed-form plans, and a note says how much better than them the plan is.

    **Repeated poses.**  Exchange may take a candidate pose more than once, and
    the optimizer may put several poses at the same corner of the limits (an
    optimal design often has fewer support points than the plan has poses).
    With ``distinct`` every candidate counts once (candidates equal within the
    tolerance are one), exchange never takes a candidate the plan holds, and
    the optimizer's repeated poses are replaced, one by one, by the candidate
    that adds the most information, before exchange (for D) improves the
    plan; a closed-form plan that repeats poses (one joint, held still) is not
    used.  A note then gives the D-criterion of the optimizer's plan with its
    repeats and of the distinct plan: distinct poses cost what the repeats
    were worth.

    **Order.**  The criteria and the certificate are computed for the plan as
    the method made it; ordering only permutes its poses.
    """
    if criterion not in CRITERIA:
        raise ArmcalError(f"unknown criterion {criterion!r}; choose one of {', '.join(CRITERIA)}")
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if order not in ORDERS:
        raise ArmcalError(f"unknown order {order!r}; choose one of {', '.join(ORDERS)}")
    p = arm.n_free
    min_poses = -(-p // 2)
    if m < min_poses:
        free = "" if p == arm.n_params else " free"
        raise ArmcalError(
            f"{m} poses give {2 * m} equations for the {p}{free} parameters of {arm.name}; "
            f"use --poses {min_poses} or more"
        )
    rng = np.random.default_rng(rng)
    notes: list[str] = []
    q: np.ndarray | None = None
    used: str = method
    closed: list[_ClosedForm] = []
    repeats, found = 0, 0.0  # the optimizer's repeated poses and its plan's D-criterion
    if method in ("auto", "analytic"):
        closed, failure = _closed_form_plans(arm, m)
        if not closed:
            if method == "analytic":
                assert failure is not None
                raise failure
            notes.append(_closed_form_note(arm, m))
        elif distinct and all(repeated_poses(plan.q).any() for plan in closed):
            if method == "analytic":
                raise ArmcalError(
                    f"the closed-form {m}-pose plan of {arm.name} repeats one pose (its one "
                    "joint is held still); distinct poses need --method optimize or exchange"
                )
            notes.append(
                f"the closed-form plan of {arm.name} repeats one pose {m} times (its one joint "
                "is held still); for distinct poses the optimizer searched other plans"
            )
            closed = []
        elif distinct:
            closed = [plan for plan in closed if not repeated_poses(plan.q).any()]
    best = max(closed, key=lambda plan: plan.d_efficiency) if closed else None
    optimal_closed = best is not None and attains_unit_bound(arm, best.q)
    paper_d = closed[0].d_efficiency if closed and not closed[0].turns_joint1 else None
    if method == "analytic" or (method == "auto" and optimal_closed):
        assert best is not None  # analytic_plan raised above otherwise
        q, used = best.q, "analytic"
        if not arm.standard:
            notes.append(
                _optimal_closed_form_note(arm, best, paper_d)
                if optimal_closed
                else f"{model_description(arm)}: {_PAPER_ASSUMES}; the closed-form plan is not "
                f"D-optimal for this model (D-criterion {best.d_efficiency:.4f}); --method auto "
                "optimizes for it"
            )
    elif method == "exchange":
        pool = feasible_poses(arm, 4000, rng=rng) if candidates is None else candidates
        q = exchange_plan(arm, m, pool, rng=rng, distinct=distinct)
        if criterion != "D":
            notes.append("exchange maximizes D; the plan was not tuned for " + criterion)
    else:
        initial = np.stack([plan.q for plan in closed]) if closed else None
        q = optimize_plan(arm, m, criterion=criterion, rng=rng, initial=initial)
        used = "optimize"
        repeats = int(np.count_nonzero(repeated_poses(q))) if distinct else 0
        found = float(d_efficiency(arm, q))
        single = arm.n_target_links == 1  # exchange evaluates one point per pose
        if criterion == "D" and single:
            pool = feasible_poses(arm, 4000, rng=rng) if candidates is None else candidates
            polished = exchange_plan(arm, m, pool, start=q, rng=rng, distinct=distinct)
            if repeats or float(d_efficiency(arm, polished)) > found * (1 + 1e-12):
                q, used = polished, "optimize+exchange"
        elif repeats and single:  # replace the repeats, without exchanges that tune for D
            pool = feasible_poses(arm, 4000, rng=rng) if candidates is None else candidates
            q = exchange_plan(arm, m, pool, start=q, rng=rng, max_swaps=0, distinct=True)
        if best is not None and _score(arm, best.q, criterion) > _score(arm, q, criterion):
            q, used = best.q, "analytic"  # not expected: the optimizer starts from it
        if arm.standard:
            pass  # the paper's model: the note above says why its closed form was not used
        elif best is not None:
            notes.append(
                f"{model_description(arm)}: {_PAPER_ASSUMES}; they are not D-optimal for this "
                f"model (the closed-form plan reaches D-criterion {best.d_efficiency:.4f}, "
                f"this plan {float(d_efficiency(arm, q)):.4f}), so the plan was optimized for it"
            )
        elif method == "auto" and not _closed_form_would_be_optimal(arm, m):
            notes.append(
                f"{model_description(arm)}: {_PAPER_ASSUMES}; even where they fit they are "
                "not D-optimal for this model, which the plan was optimized for"
            )
        else:
            notes.append(
                f"{model_description(arm)}: the plan was optimized for this model "
                f"({p} free parameters)"
            )
    q = np.asarray(q, dtype=float)
    efficiency = float(d_efficiency(arm, q))
    if distinct:
        assert not repeated_poses(q).any(), "a distinct plan repeats a pose"
        if repeats and used != "analytic":
            notes.append(
                f"distinct poses: the optimizer's plan repeated {repeats} of its {m} poses "
                f"(D-criterion {found:.4f}); each repeat was replaced by the candidate pose "
                f"adding the most information, no candidate taken twice (D-criterion "
                f"{efficiency:.4f}); poses count as one within {DISTINCT_TOLERANCE:g} rad on "
                "every joint"
            )
    certificate = certify(arm, q, rng=rng) if with_certificate else None
    travel_found = joint_travel(q)
    if order == "travel":
        q = q[order_poses(q)]
    return Design(
        arm=arm,
        q=q,
        criterion=criterion,
        method=used,
        d_efficiency=efficiency,
        certificate=certificate,
        notes=tuple(notes),
        order=order,
        joint_travel=joint_travel(q),
        joint_travel_unordered=travel_found,
        distinct=distinct,
        normalized=unit_trace(arm),
    )
