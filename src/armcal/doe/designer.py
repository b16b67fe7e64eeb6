"""One call for an optimal plan: analytic if it fits and is optimal, else optimize and exchange."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from ..choices import DESIGN_METHODS
from ..criteria import CRITERIA, Criterion, attains_unit_bound, d_efficiency, efficiencies
from ..errors import ArmcalError, ArmcalWarning, action, render
from ..models import ClosedFormPlan, ClosedFormPlans, FitModel, equations_per_pose
from ..models.information import identifying, met_rows
from ..models.wording import note_words, plan_repeats
from ..progress import ProgressCallback, share
from .certificate import Certificate, certify, certify_pool
from .exchange import exchange_plan
from .optimizer import optimize_plan
from .order import ORDERS, Order, joint_travel, order_poses
from .plans import DISTINCT_TOLERANCE, feasible_poses, random_plan, repeated_poses
from .pool import PoolPlan, distinct_count, pool_design
from .task import TASK_CRITERIA, task_criterion

__all__ = [
    "METHODS",
    "PROBE_POSES",
    "REPLICATE_ABOVE",
    "ClosedForms",
    "Design",
    "MadePlan",
    "analytic_plan",
    "certified",
    "check_options",
    "check_size",
    "closed_forms",
    "closing_notes",
    "design",
    "exchanged_plan",
    "identifiable_model",
    "pool_made_plan",
    "pool_warnings",
    "replicated_plan",
    "searched_plan",
]


Method = Literal["auto", "analytic", "optimize", "exchange"]


#: Above this many poses a searched plan is the optimal plan of at most this many
#: poses, repeated.  The normalized information ``F / m`` of a plan repeated ``k``
#: times is the plan's own, and an optimal design has at most ``p (p + 1) / 2``
#: support points (Caratheodory), so a plan of this size already reaches the
#: optimum of the continuous design within rounding (the 4-link arm's searched
#: plans reach D-efficiency 1 from about 12 poses).  Searching all ``m`` poses
#: instead costs O(m) per step of an ascent of hundreds of steps, and the
#: exchange O(N m) memory: 325 s and 15.5 GB at m = 10^4 (issue 20).
REPLICATE_ABOVE = 120


#: How :func:`design` makes a plan (:data:`armcal.choices.DESIGN_METHODS`).
METHODS = DESIGN_METHODS

#: Poses of the random plan on which :func:`identifiable_model` chooses what a plan
#: moving every joint identifies (as the command line's design does): far more rows
#: than any arm's parameters, so that only what no plan separates is held.
PROBE_POSES = 200


@dataclass(frozen=True, eq=False)
class Design:
    """An optimal calibration plan and what is known about its quality.

    Attributes
    ----------
    model : FitModel
        The model designed for: its noise model and fixed parameters, and the
        loads it identifies with.
    q : ndarray, shape (m, n)
        The plan's joint angles in rad.
    criterion : str
        Criterion optimized (key of :data:`armcal.criteria.CRITERIA`).
    method : str
        How the plan was made: ``analytic``, ``optimize``, ``optimize+exchange``,
        ``exchange``, or from a pool of candidates ``pool`` or ``pool+exchange``.
    d_efficiency : float
        :func:`armcal.criteria.d_efficiency` on the model.  For the paper's
        model ``(det F / det F_opt)^(1/p)``, relative to the unconstrained
        optimum; wherever :attr:`~armcal.models.interface.FitModel.information_bound`
        holds at most 1, and 1 only for a plan with identity normalized
        information; for other models the D-criterion of the weighted
        information (with each plan's columns scaled to unit norm for the
        spatial and compliant families: how orthogonal they are), which says
        little across plans; :attr:`reference_efficiency` compares ``det M``
        itself with the certificate's best weighted design.
    certificate : Certificate or None
        Lower bound relative to the best plan within the constraints (None when
        not asked for).
    note_texts : tuple of str
        Why a method was not used (e.g. the analytic plan breaks the limits),
        whether the paper's closed-form plans are optimal for the arm's model,
        and what making the poses distinct cost; advice that is an option refers
        to an :func:`~armcal.errors.action` (:attr:`notes` says it in the
        library's words, :func:`armcal.errors.render` in another vocabulary).
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
    payload_kg : ndarray, shape (m,), or None
        Every pose's payload, for a design that chose them
        (:func:`armcal.doe.loads.design_with_loads`).
    payloads : tuple of float
        The payload values the design could choose from (empty otherwise).
    warnings : tuple of ArmcalWarning
        What the plan cannot do that was asked of it: ``pool-repeats`` when the
        candidates hold fewer distinct poses than the plan, which then measures
        some of them twice.
    """

    model: FitModel
    q: np.ndarray
    criterion: str
    method: str
    d_efficiency: float
    certificate: Certificate | None
    note_texts: tuple[str, ...]
    order: str
    joint_travel: float
    joint_travel_unordered: float
    distinct: bool
    payload_kg: np.ndarray | None = None
    payloads: tuple[float, ...] = ()
    warnings: tuple[ArmcalWarning, ...] = ()

    @property
    def notes(self) -> tuple[str, ...]:
        """The notes (:attr:`note_texts`) in the library's words."""
        return tuple(render(text) for text in self.note_texts)

    @property
    def normalized(self) -> bool:
        """Whether ``d_efficiency`` is relative to an optimum of 1
        (:attr:`~armcal.models.interface.FitModel.information_bound`); otherwise it is
        the D-criterion of the weighted information, and only the certificate compares
        the plan with the best one."""
        return self.model.information_bound

    @cached_property
    def reference_efficiency(self) -> float | None:
        """``(det M / det M(xi*))^(1/p_f)``: the plan against the best weighted design its
        certificate found (:attr:`Certificate.reference_d_efficiency`, the same
        coordinates), what the optimizer and the certificate compare; None without a
        certificate.  At most about 1 (``xi*`` may be the plan itself)."""
        cert = self.certificate
        if cert is None:
            return None
        log_det = float(self.model.plan_information(self.q).svd().log_det_gram())
        return float(np.exp(log_det / self.model.n_free) / cert.reference_d_efficiency)

    @property
    def optimum_by_search(self) -> bool:
        """Whether a search (not the closed form) found a plan at the optimum of 1."""
        return self.normalized and self.method != "analytic" and self.d_efficiency >= 1 - 1e-9

    def __repr__(self) -> str:
        cert = self.certificate
        certified = "" if cert is None else f", certified >= {cert.certified_d_efficiency:.4f}"
        if self.normalized:
            quality = f"D-efficiency {self.d_efficiency:.4f}"
        else:  # say which basis: the criterion is not an efficiency here
            quality = f"D-criterion {self.d_efficiency:.4f} in design coordinates"
            if self.reference_efficiency is not None:
                quality += f", {self.reference_efficiency:.4f} of the best weighted design"
        return (
            f"Design({self.q.shape[0]} poses of {self.model.name}, criterion {self.criterion}, "
            f"{self.method}: {quality}{certified})"
        )


def _score(model: FitModel, q: np.ndarray, criterion: str | Criterion) -> float:
    """The efficiency ``criterion`` of plan ``q`` on the model."""
    if isinstance(criterion, Criterion):  # a task's: on the information itself
        return float(criterion.efficiency(model.plan_information(q).information()))
    return float(efficiencies(model, q)[criterion])


def _planar_exchange(model: FitModel) -> bool:
    """Whether the closed-form exchange applies: one point in the plane per pose (its swaps
    are evaluated from ``2 x 2`` blocks, :mod:`armcal.doe.exchange`), not a camera's
    corners, a row each, two pixels a row."""
    if len(model.target_labels) > 1 or model.point_dim != 2:
        return False
    return bool(model.plan_conditions(np.asarray(model.joint_limits, dtype=float)[:, :1].T).m == 1)


def pool_warnings(pool: np.ndarray, q: np.ndarray) -> tuple[ArmcalWarning, ...]:
    """``pool-repeats`` for a plan ``q`` ``(m, n)`` from ``pool`` ``(N, n)`` that holds fewer
    distinct poses than the plan: it measures some poses twice or more (none otherwise)."""
    m, count = q.shape[0], distinct_count(pool)
    if count >= m:
        return ()
    repeats = m - distinct_count(q)
    return (
        ArmcalWarning(
            "pool-repeats",
            f"the candidate poses hold {count} distinct poses, fewer than the {m} poses asked "
            f"for: the plan measures {repeats} of its poses a second time or more (a repeat "
            "adds its information again, but shows nothing new of the arm); give more "
            f"candidates, use {action('poses', count)} or fewer, or ask for "
            f"{action('distinct')} to refuse repeats",
        ),
    )


def _would_be_optimal(family: ClosedFormPlans) -> bool:
    """Whether a closed-form plan would be D-optimal for the model without limits and view."""
    free = family.unconstrained()
    return any(attains_unit_bound(free.model, plan.q) for plan in free.plans)


def design(
    model: FitModel,
    m: int,
    *,
    criterion: str = "D",
    method: Method = "auto",
    rng: np.random.Generator | int | None = None,
    candidates: np.ndarray | None = None,
    with_certificate: bool = True,
    order: Order = "travel",
    distinct: bool = False,
    progress: ProgressCallback | None = None,
    test_q: np.ndarray | None = None,
) -> Design:
    """An optimal ``m``-pose plan for the arm's model, within its joint limits and region.

    Parameters
    ----------
    model : FitModel
        The model to design for: the arm with its noise model and fixed
        parameters (a model whose points depend on the load is designed with
        the payloads by :func:`armcal.doe.loads.design_with_loads`).  A model that a
        plan moving every joint does not identify as given (a spatial arm as
        loaded, with several targets or one) is designed for what such a plan
        identifies (:func:`identifiable_model`); :attr:`Design.model` is the model
        designed for.
    m : int
        Number of poses; at least ``ceil(p_f / 2)`` for ``p_f`` free parameters.
    criterion : {"D", "A", "E", "I", "G"}
        Criterion to maximize (the certificate is always for D); I and G are the
        mean and the largest predicted position variance after calibration over
        ``test_q`` (:mod:`armcal.doe.task`).
    method : {"auto", "analytic", "optimize", "exchange"}
        ``auto`` takes a closed-form orthogonal plan when it fits the constraints
        and is provably optimal for the model (below), else optimizes and (for
        D) polishes by exchange over feasible candidates.
    rng : numpy.random.Generator or int or None
        The same seed gives the same plan.
    candidates : ndarray, shape (N, n), optional
        A pool of poses the robot can really reach (a cell's collision-free poses):
        every pose of the plan is one of them, and the certificate compares the
        plan with the best design over them (:func:`certify_pool`).  ``auto``
        takes the pool's D-optimal weights, then DETMAX (:func:`pool_plan`) and,
        for one point in the plane a pose, the exchange if it does better;
        ``exchange`` exchanges over them; ``analytic`` and ``optimize``, which
        make poses of their own, are refused.  A pool of fewer (distinct) poses
        than ``m`` gives a plan that measures some poses twice, and the warning
        ``pool-repeats`` (:attr:`Design.warnings`); with ``distinct`` it is refused.
        Default: ``exchange`` uses random feasible poses.
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
    progress : callable, optional
        ``progress(done, 1000)`` as the optimizer and the certificate advance, and
        once the plan is found (500), certified (950) and ordered (1000).

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
    Every criterion is the model's
    (:meth:`~armcal.models.interface.FitModel.plan_information`): the weighted
    information over the free parameters.  The paper's orthogonal plans are
    optimal for its model -- isotropic iid noise, every parameter free -- by
    Hadamard's bound; ``auto`` takes a closed-form plan whenever the model keeps
    that bound (:func:`armcal.models.planar.information.unit_trace`) and the plan reaches it,
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

    **Steps.**  The options are checked (:func:`check_options`), the model made
    identifiable (:func:`identifiable_model`) and sized (:func:`check_size`); the
    closed-form plans that fit are found (:func:`closed_forms`); one method makes the
    plan (:func:`analytic_plan`, :func:`replicated_plan`, :func:`pool_made_plan`,
    :func:`exchanged_plan` or :func:`searched_plan`), the notes on it are added
    (:func:`closing_notes`), and it is certified (:func:`certified`) and ordered.
    """
    check_options(criterion, method, order, test_q)
    model = identifiable_model(model)
    check_size(model, m)
    aim: str | Criterion = criterion
    if criterion in TASK_CRITERIA:
        assert test_q is not None  # check_options refused a task criterion without
        aim = task_criterion(criterion, model, test_q)
    rng = np.random.default_rng(rng)
    drawn = candidates is None and model.constrained  # a pool of poses that meet it
    pool = candidate_pool(model, m, method, candidates, rng)  # every pose from it
    candidates = pool if drawn else candidates
    closed = closed_forms(model, m, method, distinct=distinct, from_pool=pool is not None)
    if method == "analytic" or (method == "auto" and closed.optimal and aim == criterion):
        made = analytic_plan(closed)
    elif m > REPLICATE_ABOVE and not distinct:
        made = replicated_plan(
            model, m, criterion=criterion, method=method, rng=rng, candidates=candidates,
            test_q=test_q,
        )  # fmt: skip
    elif pool is not None and (method == "auto" or not _planar_exchange(model)):
        made = pool_made_plan(model, m, pool, criterion=criterion, rng=rng, distinct=distinct)
    elif method == "exchange":
        made = exchanged_plan(
            model, m, candidates, criterion=criterion, rng=rng, distinct=distinct
        )
    else:
        made = searched_plan(
            model, m, aim, closed, criterion=criterion, rng=rng, distinct=distinct,
            progress=progress,
        )  # fmt: skip
    q = np.asarray(made.q, dtype=float)
    certificate = certified(  # over the instrument's constrained poses, not the pool drawn
        model, q, None if drawn else pool, with_certificate, rng=rng, progress=progress,
        work=made.pool,
    )  # fmt: skip
    if drawn and pool is not None and certificate is not None:
        q, certificate = chosen_again(model, m, pool, q, certificate, rng, distinct)
    efficiency = float(d_efficiency(model, q))
    notes = [*(() if made.replaces_notes else closed.notes), *made.notes]
    notes.extend(closing_notes(made, closed, q, efficiency, method, distinct=distinct))
    travel_found = joint_travel(q)
    if order == "travel":
        q = q[order_poses(q)]
    if progress is not None:
        progress(1000, 1000)
    return Design(
        model=model,
        q=q,
        criterion=criterion,
        method=made.method,
        d_efficiency=efficiency,
        certificate=certificate,
        note_texts=tuple(notes),
        order=order,
        joint_travel=joint_travel(q),
        joint_travel_unordered=travel_found,
        distinct=distinct,
        warnings=() if pool is None or drawn else pool_warnings(pool, q),
    )


#: Poses a plan for an instrument's constrained poses is chosen from: drawn within the
#: limits and moved to meet it (:func:`constrained_pool`), at least this many ...
CONSTRAINED_POOL = 3000
#: ... and this many per pose of the plan.
CONSTRAINED_POOL_PER_POSE = 30


def constrained_pool(model: FitModel, m: int, rng: np.random.Generator) -> np.ndarray:
    """Random poses within the limits moved to meet the instrument
    (:func:`~armcal.doe.plans.feasible_poses`): the pool a plan for a plane, a point or a
    distance is chosen from.  Its certificate is over every pose that meets the
    instrument (:func:`~armcal.doe.certificate.certify`), not over this pool."""
    size = max(CONSTRAINED_POOL, CONSTRAINED_POOL_PER_POSE * min(m, REPLICATE_ABOVE))
    pool = feasible_poses(model, size, rng=rng)
    labels = model.feature_labels
    feature = model.plan_conditions(pool).feature if len(labels) > 1 else None
    if feature is not None:
        met = np.bincount(feature, minlength=len(labels))
        missing = [label for label, count in zip(labels, met, strict=True) if count == 0]
        if missing:
            raise ArmcalError(
                f"{model.name}: of {size} poses that meet the instrument, none meets "
                f"{', '.join(missing)}: no pose within the joint limits reaches "
                f"{'it' if len(missing) == 1 else 'them'} where the robot file places "
                f"{'it' if len(missing) == 1 else 'them'}; check [instrument] and the limits"
            )
    return pool


def candidate_pool(
    model: FitModel,
    m: int,
    method: str,
    candidates: np.ndarray | None,
    rng: np.random.Generator,
) -> np.ndarray | None:
    """The poses every pose of the plan is taken from: the user's ``candidates``, else for
    an instrument whose poses must meet it a pool drawn and moved there
    (:func:`constrained_pool`), else None (poses of the method's own).  ArmcalError for a
    method that makes poses of its own (analytic, optimize) with either."""
    if candidates is None and not model.constrained:
        return None
    if method in ("analytic", "optimize"):
        if candidates is None:
            raise ArmcalError(
                f"a plan for {model.name}'s instrument is made of poses that meet it, drawn "
                f"and moved there; method {method!r} makes poses of its own: use "
                f"{action('method', 'auto')} or exchange"
            )
        raise ArmcalError(
            f"a plan from candidate poses takes every pose from them, and method {method!r} "
            f"makes poses of its own; use {action('method', 'auto')} or exchange"
        )
    if candidates is None:
        return constrained_pool(model, m, rng)
    return np.asarray(candidates, dtype=float)


def check_options(criterion: str, method: str, order: str, test_q: np.ndarray | None) -> None:
    """ArmcalError for an unknown criterion, method or order, or a task criterion
    (:data:`armcal.doe.task.TASK_CRITERIA`) without test poses; in that order."""
    names = [*CRITERIA, *TASK_CRITERIA]
    if criterion not in names:
        raise ArmcalError(f"unknown criterion {criterion!r}; choose one of {', '.join(names)}")
    if criterion in TASK_CRITERIA and (test_q is None or not len(test_q)):
        raise ArmcalError(f"the {criterion} criterion needs test poses ({action('test-poses')})")
    if method not in METHODS:
        raise ArmcalError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if order not in ORDERS:
        raise ArmcalError(f"unknown order {order!r}; choose one of {', '.join(ORDERS)}")


def identifiable_model(model: FitModel) -> FitModel:
    """The model reduced to what a plan moving every joint identifies: itself when
    :data:`PROBE_POSES` random poses identify it (a minimal family, a model already
    prepared), else :meth:`~armcal.models.interface.FitModel.prepared` for them
    (:func:`~armcal.models.information.identifying`).

    The poses come from a stream of their own (seed 0), so that the design's stream
    stays the same, moved onto an instrument that sees the tool only where it meets it
    (:meth:`~armcal.models.interface.FitModel.meeting_poses`); the held set does not
    depend on them, being chosen by the family's fixed rule (for a spatial arm
    :mod:`armcal.models.spatial.selection`).
    """
    probe = random_plan(model, PROBE_POSES, rng=np.random.default_rng(0))
    return identifying(model, met_rows(model, probe))


def check_size(model: FitModel, m: int) -> None:
    """ArmcalError when ``m`` poses give fewer equations than the model's free parameters."""
    p = model.n_free
    per_pose = equations_per_pose(model)
    min_poses = -(-p // per_pose)
    if m < min_poses:
        free = "" if p == model.n_params else " free"
        raise ArmcalError(
            f"{m} poses give {per_pose * m} equations for the {p}{free} parameters of "
            f"{model.name}; use {action('poses', min_poses)} or more"
        )


@dataclass(frozen=True, eq=False)
class ClosedForms:
    """The family's closed-form plans a design may take, and what was said of them.

    Attributes
    ----------
    family : ClosedFormPlans or None
        The family's closed-form plans of the size (None: it has none, or the plan
        is from a pool).
    plans : tuple of ClosedFormPlan
        Those that fit the constraints (and, for a distinct plan, repeat no pose);
        empty unless the method is ``auto`` or ``analytic``.
    notes : tuple of str
        Why none was taken (none fits; every one repeats a pose).
    d : dict of str to float
        Every plan's D-efficiency, by label.
    best : ClosedFormPlan or None
        The plan of the highest D-efficiency.
    optimal : bool
        Whether ``best`` reaches the bound of 1 (:func:`armcal.criteria.attains_unit_bound`).
    """

    family: ClosedFormPlans | None
    plans: tuple[ClosedFormPlan, ...]
    notes: tuple[str, ...]
    d: dict[str, float]
    best: ClosedFormPlan | None
    optimal: bool


def closed_forms(
    model: FitModel, m: int, method: str, *, distinct: bool, from_pool: bool
) -> ClosedForms:
    """The closed-form ``m``-pose plans a design by ``method`` may take (none for a plan
    from a pool).

    Raises ArmcalError for ``method="analytic"`` where the family has none, none fits
    the constraints, or (``distinct``) every one that fits repeats a pose.
    """
    family = None if from_pool else model.closed_form_plans(m)
    if method == "analytic" and family is None:
        raise ArmcalError(
            f"{model.name} has no closed-form plans; use {action('method', 'auto')}, optimize or "
            "exchange"
        )
    plans: list[ClosedFormPlan] = []
    notes: list[str] = []
    if family is not None and method in ("auto", "analytic"):
        plans = list(family.plans)
        if not plans:
            if method == "analytic":
                assert family.failure is not None
                raise family.failure
            notes.append(note_words(family.unfit()))
        elif distinct and all(repeated_poses(plan.q).any() for plan in plans):
            if method == "analytic":
                raise ArmcalError(plan_repeats(family.model.name, m, refused=True))
            notes.append(plan_repeats(family.model.name, m, refused=False))
            plans = []
        elif distinct:
            plans = [plan for plan in plans if not repeated_poses(plan.q).any()]
    d = {plan.label: float(d_efficiency(model, plan.q)) for plan in plans}
    best = max(plans, key=lambda plan: d[plan.label]) if plans else None
    optimal = best is not None and attains_unit_bound(model, best.q, d[best.label])
    return ClosedForms(family, tuple(plans), tuple(notes), d, best, optimal)


@dataclass(frozen=True, eq=False)
class MadePlan:
    """A plan as one method made it, before notes, certificate and order.

    Attributes
    ----------
    q : ndarray, shape (m, n)
        The poses, rad.
    method : str
        :attr:`Design.method`.
    notes : tuple of str
        What the method says of the plan.
    replaces_notes : bool
        Whether ``notes`` replace the closed forms' (a replicated plan's are the
        smaller plan's).
    repeats : int
        The optimizer's repeated poses, replaced for a distinct plan.
    found : float
        The D-criterion of the optimizer's plan, before the repeats were replaced.
    searched : bool
        Whether the optimizer searched (the family's note on its closed forms follows).
    pool : PoolPlan or None
        A plan from the user's pool: the pool's blocks and weights, which its
        certificate reuses.
    """

    q: np.ndarray
    method: str
    notes: tuple[str, ...] = ()
    replaces_notes: bool = False
    repeats: int = 0
    found: float = 0.0
    searched: bool = False
    pool: PoolPlan | None = None


def analytic_plan(closed: ClosedForms) -> MadePlan:
    """The best closed-form plan, with the family's note on the choice."""
    assert closed.best is not None and closed.family is not None  # closed_forms raised
    note = closed.family.choice(closed.best, closed.d, closed.optimal)
    return MadePlan(closed.best.q, "analytic", () if note is None else (note_words(note),))


def replicated_plan(
    model: FitModel,
    m: int,
    *,
    criterion: str,
    method: Method,
    rng: np.random.Generator,
    candidates: np.ndarray | None,
    test_q: np.ndarray | None,
) -> MadePlan:
    """Above :data:`REPLICATE_ABOVE` poses: the optimal plan of at most that many poses,
    taken as many whole times as fit, then its first poses: ``m`` in all."""
    copies = -(-m // REPLICATE_ABOVE)
    size = m // copies
    base = design(
        model, size, criterion=criterion, method=method, rng=rng, candidates=candidates,
        with_certificate=False, order="none", test_q=test_q,
    )  # fmt: skip
    # whole copies, then the plan's first poses: ``m`` in all (``copies * size`` may
    # fall short by more than ``size`` poses, so count the copies of ``size`` anew)
    copies, extra = divmod(m, size)
    q = np.concatenate([np.tile(base.q, (copies, 1)), base.q[:extra]])
    note = (
        f"{m} poses: the optimal {size}-pose plan taken {copies} times"
        + (f", and its first {extra} poses once more" if extra else "")
        + f": a plan's information per pose is no better above {REPLICATE_ABOVE} poses "
        "than the best plan below, and searching every pose would cost time and memory "
        "in proportion"
    )
    # the family's notes are of the m-pose plans; the smaller plan's replace them
    return MadePlan(q, base.method, (*base.note_texts, note), replaces_notes=True)


#: A plan from a drawn pool certified at least this is kept as it is (chosen_again).
CHOSEN_WELL = 0.99


def chosen_again(
    model: FitModel,
    m: int,
    pool: np.ndarray,
    q: np.ndarray,
    certificate: Certificate,
    rng: np.random.Generator,
    distinct: bool,
) -> tuple[np.ndarray, Certificate]:
    """A plan from a pool drawn for an instrument, chosen again from the pool and the
    support of its certificate's reference design, where that is better: random poses
    that meet the instrument seldom lie where the best design puts its weight (a
    camera's best photos put the board's corners on the image's edges), and the
    certificate's search found those poses.  Its certificate is the same reference
    design's (:meth:`~armcal.doe.certificate.Certificate.rebased`), no second search.
    A plan certified :data:`CHOSEN_WELL` already, or one the other does not beat, is kept.
    (A 20-photo plan of a camera on cobot-6r, before its depth and tilt limits: the
    pool's plan had 0.15 of the reference design's D-criterion, the plan chosen again
    0.985.)"""
    if certificate.certified_d_efficiency >= CHOSEN_WELL:
        return q, certificate
    richer = np.concatenate([pool, certificate.support])
    again = pool_made_plan(model, m, richer, criterion="D", rng=rng, distinct=distinct)
    q_again = np.asarray(again.q, dtype=float)
    if float(d_efficiency(model, q_again)) <= float(d_efficiency(model, q)):
        return q, certificate
    rebased = certificate.rebased(model, q_again)
    if rebased is None or rebased.certified_d_efficiency <= certificate.certified_d_efficiency:
        return q, certificate
    return q_again, rebased


def pool_made_plan(
    model: FitModel,
    m: int,
    pool: np.ndarray,
    *,
    criterion: str,
    rng: np.random.Generator,
    distinct: bool,
) -> MadePlan:
    """Every pose from the user's ``pool``: the pool's D-optimal weights, then DETMAX
    (:func:`~armcal.doe.pool.pool_plan`), then (one point in the plane a pose) the
    Fedorov exchange over the pool, if better."""
    made = pool_design(model, m, pool, distinct=distinct)
    q = pool[made.index]
    used = "pool"
    if _planar_exchange(model):
        swapped = exchange_plan(model, m, pool, start=q, rng=rng, distinct=distinct)
        if float(d_efficiency(model, swapped)) > float(d_efficiency(model, q)) * (1 + 1e-12):
            q, used = swapped, "pool+exchange"
    notes = (
        ()
        if criterion == "D"
        else ("a plan from a pool maximizes D; it was not tuned for " + criterion,)
    )
    return MadePlan(q, used, notes, pool=made)


def exchanged_plan(
    model: FitModel,
    m: int,
    candidates: np.ndarray | None,
    *,
    criterion: str,
    rng: np.random.Generator,
    distinct: bool,
) -> MadePlan:
    """The Fedorov exchange over ``candidates`` (default: 4000 random feasible poses)."""
    pool = feasible_poses(model, 4000, rng=rng) if candidates is None else candidates
    q = exchange_plan(model, m, pool, rng=rng, distinct=distinct)
    notes = (
        ()
        if criterion == "D"
        else ("exchange maximizes D; the plan was not tuned for " + criterion,)
    )
    return MadePlan(q, "exchange", notes)


def searched_plan(
    model: FitModel,
    m: int,
    aim: str | Criterion,
    closed: ClosedForms,
    *,
    criterion: str,
    rng: np.random.Generator,
    distinct: bool,
    progress: ProgressCallback | None,
) -> MadePlan:
    """The optimizer's plan (:func:`~armcal.doe.optimizer.optimize_plan`, started also from
    the closed forms), polished for D by exchange (one point in the plane a pose), its
    repeated poses replaced for a distinct plan; the best closed form if it does better."""
    initial = np.stack([plan.q for plan in closed.plans]) if closed.plans else None
    q = optimize_plan(
        model, m, criterion=aim, rng=rng, initial=initial, progress=share(progress, 0, 0.5)
    )
    used = "optimize"
    repeats = int(np.count_nonzero(repeated_poses(q))) if distinct else 0
    found = float(d_efficiency(model, q))
    single = _planar_exchange(model)
    if criterion == "D" and single:
        pool = feasible_poses(model, 4000, rng=rng)
        polished = exchange_plan(model, m, pool, start=q, rng=rng, distinct=distinct)
        if repeats or float(d_efficiency(model, polished)) > found * (1 + 1e-12):
            q, used = polished, "optimize+exchange"
    elif repeats and single:  # replace the repeats, without exchanges that tune for D
        pool = feasible_poses(model, 4000, rng=rng)
        q = exchange_plan(model, m, pool, start=q, rng=rng, max_swaps=0, distinct=True)
    best = closed.best
    if best is not None and _score(model, best.q, aim) > _score(model, q, aim):
        q, used = best.q, "analytic"  # not expected: the optimizer starts from it
    return MadePlan(q, used, repeats=repeats, found=found, searched=True)


def closing_notes(
    made: MadePlan,
    closed: ClosedForms,
    q: np.ndarray,
    efficiency: float,
    method: str,
    *,
    distinct: bool,
) -> list[str]:
    """The notes on the plan ``q`` made: how a searched plan compares with the family's
    closed forms, and what making the poses distinct cost."""
    notes = []
    family = closed.family
    if made.searched and family is not None:
        note = family.searched(
            None if closed.best is None else closed.d[closed.best.label],
            efficiency,
            method,
            lambda: _would_be_optimal(family),
        )
        if note is not None:
            notes.append(note_words(note))
    if distinct:
        assert not repeated_poses(q).any(), "a distinct plan repeats a pose"
        if made.repeats and made.method != "analytic":
            notes.append(
                f"distinct poses: the optimizer's plan repeated {made.repeats} of its "
                f"{q.shape[0]} poses (D-criterion {made.found:.4f}); each repeat was replaced "
                f"by the candidate pose adding the most information, no candidate taken twice "
                f"(D-criterion {efficiency:.4f}); poses count as one within "
                f"{DISTINCT_TOLERANCE:g} rad on every joint"
            )
    return notes


def certified(
    model: FitModel,
    q: np.ndarray,
    pool: np.ndarray | None,
    with_certificate: bool,
    *,
    rng: np.random.Generator,
    progress: ProgressCallback | None,
    work: PoolPlan | None = None,
) -> Certificate | None:
    """The plan's certificate (None when not asked for): against the best design over the
    user's ``pool`` (:func:`certify_pool`), else over the constraints (:func:`certify`);
    ``progress`` from 500 to 950 of 1000; ``work`` is the pool design's, which the
    pool's certificate starts from."""
    tick = progress if progress is not None else (lambda done, total: None)
    tick(500, 1000)
    certificate = None
    if with_certificate and pool is not None:  # the best plan is the pool's best
        blocks, weights = (None, None) if work is None else (work.blocks, work.weights)
        certificate = certify_pool(model, q, pool, blocks=blocks, weights=weights)
    elif with_certificate:
        certificate = certify(model, q, rng=rng, progress=share(progress, 0.5, 0.95))
    tick(950, 1000)
    return certificate
