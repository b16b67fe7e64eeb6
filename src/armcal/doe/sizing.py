"""How many poses an accuracy requirement needs: a search over m of the best plans."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..choices import REQUIREMENTS
from ..criteria import position_rms, predicted_std
from ..errors import ArmcalError, action
from ..models import FitModel, Loads, equations_per_pose
from ..progress import ProgressCallback, share
from .designer import design, identifiable_model
from .loads import design_with_loads
from .order import order_poses
from .plans import random_plan

__all__ = [
    "REQUIREMENTS",
    "REQUIREMENT_RTOL",
    "REQUIREMENT_UNITS",
    "UNREACHABLE_MARGIN",
    "PosesNeeded",
    "Requirement",
    "accuracy_metric",
    "poses_needed",
    "requirement_params",
]


Requirement = Literal["length_std_mm", "angle_std_deg", "position_rms_mm"]


#: Relative slack when comparing an accuracy with its requirement, so that a plan
#: reaching it exactly (sigma / sqrt(100) = 0.01) is not rejected by round-off.
REQUIREMENT_RTOL = 1e-9

#: How many times more poses than searched the 1/sqrt(m) law must ask for before a
#: target is refused at once, without designing the largest plan: a plan's
#: information per pose would have to grow this much with its size.
UNREACHABLE_MARGIN = 4

#: The display unit of the parameters a requirement on the arm's own parameters bounds.
REQUIREMENT_UNITS: dict[str, str] = {"length_std_mm": "mm", "angle_std_deg": "deg"}

_RELAX = f"relax the target or measure with a better instrument (smaller {action('sigma')})"


def _check_requirement(requirement: str) -> None:
    if requirement not in REQUIREMENTS:
        raise ArmcalError(
            f"unknown requirement {requirement!r}; choose one of {', '.join(REQUIREMENTS)}"
        )  # a library caller's mistake: the command line offers only these


def requirement_params(model: FitModel, requirement: str) -> np.ndarray:
    """Boolean ``(p,)``: the parameters whose largest std ``requirement`` bounds (every
    parameter for ``position_rms_mm``, which bounds none alone).

    A length (``length_std_mm``) or angle (``angle_std_deg``) requirement bounds the
    arm's own parameters of that display unit (mm or deg): a planar arm's link lengths
    ``dl`` and joint offsets ``dq`` (those of its targets' last links included), a
    spatial arm's joint placements and zeros (a slide's zero is a length); never the
    instrument's pose or the targets found from the data
    (:attr:`~armcal.models.interface.FitModel.instrument_params`), nor an effect's
    parameters in other units (compliance).

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([260.0, 180.0], base_offset=True)
    >>> [n for n, f in zip(arm.param_names, requirement_params(arm, "length_std_mm")) if f]
    ['dl1', 'dl2']
    """
    _check_requirement(requirement)
    unit = REQUIREMENT_UNITS.get(requirement)
    if unit is None:
        return np.ones(model.n_params, dtype=bool)
    units = np.array(model.param_units)
    return (units == unit) & ~np.asarray(model.instrument_params, dtype=bool)


def _check_measurable(model: FitModel, requirement: str) -> None:
    """Refuse a length or angle requirement the model has no free parameter for."""
    measured = requirement_params(model, requirement)
    if np.any(measured & model.free):
        return
    unit = REQUIREMENT_UNITS[requirement]
    kind = "length" if unit == "mm" else "angle"
    names = [name for name, picked in zip(model.param_names, measured, strict=True) if picked]
    free = f"choose a target on the free parameters ({', '.join(model.free_names)})"
    if names:
        raise ArmcalError(
            f"every parameter the target {requirement} measures ({', '.join(names)}) is fixed "
            f"for {model.name}; {free}"
        )
    raise ArmcalError(
        f"{model.name} has no {kind} of its own in {unit} for the target {requirement} to "
        f"bound (only the instrument's pose, the targets or other units); {free}, or "
        f"{action('position-requirement')}"
    )


def accuracy_metric(
    model: FitModel,
    q: np.ndarray,
    requirement: str,
    sigma: float,
    test_q: np.ndarray,
    *,
    loads: Loads | None = None,
) -> float:
    """Accuracy ``requirement`` (a key of :data:`REQUIREMENTS`) of plan ``q`` under its
    ``loads``; inf if singular."""
    _check_requirement(requirement)
    if requirement == "position_rms_mm":
        if not len(test_q):  # a mean over no poses is no accuracy
            raise ArmcalError("a position target needs test poses; none were given")
        return position_rms(model, q, test_q, sigma, loads=loads)
    _check_measurable(model, requirement)
    std = predicted_std(model, q, sigma, loads=loads)  # inf when the plan is singular
    # fixed parameters have std 0: the largest is over the free ones
    return float(std[requirement_params(model, requirement)].max())


@dataclass(frozen=True, eq=False)
class PosesNeeded:
    """The smallest number of poses whose best plan reaches an accuracy requirement.

    Attributes
    ----------
    requirement : str
        Key of :data:`REQUIREMENTS`.
    goal : float
        The accuracy asked for (mm or deg).
    sigma_mm : float
        Measurement noise (mm).
    poses : int
        Smallest ``m`` found whose best plan reaches ``goal``.
    achieved : float
        The accuracy of that plan.
    previous : float
        The accuracy of the best plan with ``poses - 1`` poses (inf when fewer
        poses cannot identify the parameters).
    method : str
        How the plans were made (``analytic`` or the optimizer's name).
    plan : ndarray, shape (poses, n)
        The plan that reaches the goal (rad), ordered for short joint travel
        (:func:`armcal.doe.order.order_poses`).
    evaluated : dict of int to float
        Every ``m`` tried and the accuracy of its best plan.
    payload_kg : ndarray, shape (poses,), optional
        Every pose's payload, for a model whose points depend on the load (the
        design chooses them with the poses, :func:`armcal.doe.design_with_loads`).
    model : FitModel, optional
        The model the plan fits (its identifiable set).
    measured : tuple of str
        The free parameters whose largest std the requirement bounds
        (:func:`requirement_params`; empty for ``position_rms_mm``).
    """

    requirement: str
    goal: float
    sigma_mm: float
    poses: int
    achieved: float
    previous: float
    method: str
    plan: np.ndarray
    evaluated: dict[int, float]
    payload_kg: np.ndarray | None = None
    model: FitModel | None = None
    measured: tuple[str, ...] = ()

    def __repr__(self) -> str:
        unit = self.requirement.rsplit("_", 1)[-1]
        fewer = (
            f"{self.poses - 1} reach {self.previous:.4g}"
            if math.isfinite(self.previous)
            else f"{self.poses - 1} cannot identify the parameters"
        )
        return (
            f"PosesNeeded({self.requirement} <= {self.goal:g} {unit}: {self.poses} poses reach "
            f"{self.achieved:.4g}, {fewer}; sigma {self.sigma_mm:g} mm, {self.method})"
        )


#: Random plans drawn per size by ``plans="random"``; the most accurate is kept.
RANDOM_PLANS = 20


@dataclass(frozen=True, eq=False)
class _Plan:
    """A plan of one size: its poses, the model it fits, how it was made, its loads."""

    q: np.ndarray
    model: FitModel
    method: str
    payload_kg: np.ndarray | None = None
    loads: Loads | None = None


def _best_plan(
    model: FitModel,
    m: int,
    rng: np.random.Generator,
    payloads: Sequence[float] | None,
    metric: Callable[[FitModel, np.ndarray, Loads | None], float],
    plans: str,
    progress: ProgressCallback | None = None,
) -> _Plan:
    """The best ``m``-pose plan (designed, or the most accurate of :data:`RANDOM_PLANS`
    uniform in the limits), with its loads where the design chooses the payloads."""
    if plans == "random":
        drawn = [random_plan(model, m, rng=rng) for _ in range(RANDOM_PLANS)]
        best = min(drawn, key=lambda q: metric(model, q, None))
        return _Plan(best, model, f"random (the best of {RANDOM_PLANS})")
    if model.design_loads(payloads) is None:
        made = design(model, m, rng=rng, with_certificate=False, order="none", progress=progress)
        return _Plan(made.q, made.model, made.method)
    made = design_with_loads(model, m, payloads=payloads, rng=rng, order="none")
    assert made.payload_kg is not None
    loads = Loads.create(m, made.payload_kg)
    return _Plan(made.q, made.model, made.method, made.payload_kg, loads)


class _SizeSearch:
    """The best plan of every size tried, designed once each, with the search's progress.

    ``low`` is the largest size known not to reach the goal once the search bisects
    (None while it jumps) and ``high`` the smallest known to reach it: they set how
    many designs the progress bar still expects.
    """

    def __init__(
        self,
        model: FitModel,
        rng: np.random.Generator,
        payloads: Sequence[float] | None,
        metric: Callable[[FitModel, np.ndarray, Loads | None], float],
        plans: str,
        progress: ProgressCallback | None,
    ) -> None:
        self.model, self.rng, self.payloads = model, rng, payloads
        self.metric, self.plans, self.progress = metric, plans, progress
        self.found: dict[int, tuple[_Plan, float]] = {}
        self.low: int | None = None
        self.high = 0
        self.shown = 0  # thousandths of the search reported, never going back

    def best(self, size: int) -> float:
        """The accuracy of the best plan of ``size`` poses (designed on first asking)."""
        found = self.found
        if size not in found:
            # designs left: 2 while jumping, then log2 of the span; the design of this
            # size fills the bar up to where its end is reported (a long design moves it)
            left = 2 if self.low is None else max(self.high - self.low - 1, 1).bit_length()
            after = max(self.shown, 1000 * (len(found) + 1) // (len(found) + 1 + left))
            part = share(self.progress, self.shown / 1000, after / 1000)
            made = _best_plan(
                self.model, size, self.rng, self.payloads, self.metric, self.plans, part
            )
            found[size] = (made, self.metric(made.model, made.q, made.loads))
            if self.progress is not None:
                self.shown = after
                self.progress(self.shown, 1000)
        return found[size][1]


def _jump(
    search: _SizeSearch,
    reaches: Callable[[int], bool],
    start: int,
    failed: int,
    goal: float,
    max_poses: int,
) -> tuple[int, int]:
    """Jump by the ``1/sqrt(m)`` law from ``start`` to a size that reaches the goal:
    ``(that size, the largest size known not to reach)``; refused when even
    ``max_poses`` cannot reach, or the law asks for far more."""
    m = start
    while not reaches(m):
        value = search.best(m)
        if m >= max_poses:
            raise ArmcalError(
                f"{max_poses} poses reach only {value:.4g} against a target of {goal:g}; {_RELAX}"
            )
        failed = m
        # 1/sqrt(m) law from here; an unidentifiable m (inf) just doubles.
        # std falls as 1/sqrt(m); the ratio is capped so a vanishing goal cannot overflow.
        jump = m * min(value / goal, 1e6) ** 2 if math.isfinite(value) else 2 * m
        if jump > UNREACHABLE_MARGIN * max_poses:
            # A larger plan gains at least 1/sqrt(m) per pose, hardly more: a plan's
            # information per pose grows only while its poses are few, and not 4-fold.
            raise ArmcalError(
                f"{m} poses reach {value:.4g} against a target of {goal:g}; as accuracy "
                f"grows like sqrt(poses), the target needs about {jump:.3g} poses, beyond "
                f"the {max_poses} searched; {_RELAX}"
            )
        m = min(max_poses, max(m + 1, math.ceil(jump * (1 - 1e-12))))
    return m, failed


def _bisect(search: _SizeSearch, reaches: Callable[[int], bool], failed: int, m: int) -> int:
    """The smallest size that reaches, between ``failed`` (does not) and ``m`` (does).

    The jump usually lands on the answer, so one pose less is tried first; if that
    reaches too, the span is bisected: O(log m) designs, not one per pose below an
    overshooting jump.
    """
    search.low, search.high = failed, m
    middle = m - 1
    while search.high - search.low > 1:
        if reaches(middle):
            search.high = middle
        else:
            search.low = middle
        middle = (search.low + search.high) // 2
    return search.high


def poses_needed(
    model: FitModel,
    requirement: str,
    goal: float,
    *,
    sigma: float,
    rng: np.random.Generator | int | None = None,
    test_q: np.ndarray | None = None,
    max_poses: int = 5000,
    payloads: Sequence[float] | None = None,
    plans: Literal["designed", "random"] = "designed",
    progress: ProgressCallback | None = None,
) -> PosesNeeded:
    """The smallest ``m`` whose best plan (:func:`armcal.doe.design`) reaches ``goal``.

    Parameters
    ----------
    model : FitModel
        The model to calibrate; one that a plan moving every joint does not identify
        as given (a spatial arm as loaded) is sized for what such a plan identifies
        (:func:`~armcal.doe.designer.identifiable_model`).
    requirement : {"length_std_mm", "angle_std_deg", "position_rms_mm"}
        What must reach ``goal`` (see :data:`REQUIREMENTS`).
    goal : float
        Accuracy asked for, in mm (lengths, position) or deg (joint offsets).
    sigma : float
        Measurement noise (mm): the reference ``sigma_ref`` of a weighted model.
    rng : numpy.random.Generator or int or None
        Seeds the plan optimizer and the default test poses.
    test_q : ndarray, shape (k, n), optional
        Poses for ``position_rms_mm`` (default: 1000 uniform within the limits).
    max_poses : int
        Give up beyond this many poses.
    payloads : sequence of float, optional
        For a model whose points depend on the load (joint compliance): the
        payloads (kg) a pose may carry, chosen with the poses
        (:func:`armcal.doe.design_with_loads`); default 0 and the model's payload.
    plans : {"designed", "random"}
        How the plan of each size is made: designed (:func:`armcal.doe.design`), or
        the most accurate of :data:`RANDOM_PLANS` uniform in the limits (what
        measuring random poses needs; the answer for a designed plan is at most it).
    progress : callable, optional
        Called after each size is designed with ``(done, 1000)``: thousandths of
        ``tried / (tried + left)``, never decreasing, ``left`` the designs the
        search still expects (2 while it jumps, then the bisection's ``log2`` of
        the sizes left); a design's own progress fills the bar between, so a long
        design of one size still moves it.

    Returns
    -------
    PosesNeeded

    Raises
    ------
    ArmcalError
        If even ``max_poses`` poses do not reach ``goal``, or every parameter the
        requirement measures is fixed.

    Notes
    -----
    Accuracy of the best plan falls like ``1 / sqrt(m)`` once ``m`` is a few
    times ``n`` (the plan's efficiency settles), so each step jumps to
    ``ceil(m (a_m / goal)^2)``; the first size that reaches is then checked
    against one pose less and, if that reaches too, bisected against the last
    size that failed (a few designs, not one per pose when a jump overshoots):
    the result ``m`` reaches the goal and ``m - 1`` does not.
    Plans are designed for the model (its noise model and fixed parameters,
    :func:`armcal.doe.design`), and ``sigma`` is its reference noise; fixed
    parameters have standard error 0 and do not count.
    For the paper's model on arms without binding limits the best plans are
    orthogonal and the answers are the closed forms ``ceil((sigma / goal)^2)`` for lengths,
    ``ceil((sigma / (goal l))^2)`` for a single joint offset and
    ``ceil(2 n (sigma / goal)^2)`` for the position RMS -- found here by search,
    not by formula.

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([260.0, 180.0, 120.0, 100.0])
    >>> poses_needed(arm, "length_std_mm", 0.01, sigma=0.1).poses
    100
    >>> poses_needed(arm, "position_rms_mm", 0.02, sigma=0.1).poses
    200
    """
    _check_requirement(requirement)
    if not (goal > 0 and math.isfinite(goal)):
        raise ArmcalError(f"the target accuracy must be a positive number, got {goal}")
    model = identifiable_model(model)  # a spatial arm as loaded: what plans identify
    chosen = model.design_loads(payloads)
    fitted = model if chosen is None else chosen[0]  # what a plan of poses and loads fits
    if requirement in REQUIREMENT_UNITS:  # before any plan is designed
        _check_measurable(fitted, requirement)
    rng = np.random.default_rng(rng)
    if test_q is None:
        test_q = random_plan(model, 1000, rng=rng)
    min_poses = -(-fitted.n_free // equations_per_pose(model))

    def metric(fitted: FitModel, q: np.ndarray, loads: Loads | None) -> float:
        return accuracy_metric(fitted, q, requirement, sigma, test_q, loads=loads)

    def reaches(size: int) -> bool:
        return search.best(size) <= goal * (1 + REQUIREMENT_RTOL)

    search = _SizeSearch(model, rng, payloads, metric, plans, progress)
    failed = min_poses - 1  # largest m known not to reach the goal
    m, failed = _jump(search, reaches, max(min_poses, 2 * model.n_joints), failed, goal, max_poses)
    m = _bisect(search, reaches, failed, m)
    if progress is not None:
        progress(1000, 1000)
    found = search.found
    made, achieved = found[m]
    measured: tuple[str, ...] = ()
    if requirement in REQUIREMENT_UNITS:
        picked = requirement_params(made.model, requirement) & made.model.free
        measured = tuple(str(name) for name in np.array(made.model.param_names)[picked])
    order = order_poses(made.q)  # only the plan kept is ordered: the order changes no accuracy
    return PosesNeeded(
        requirement=requirement,
        goal=float(goal),
        sigma_mm=float(sigma),
        poses=m,
        achieved=achieved,
        previous=search.best(m - 1) if m > min_poses else math.inf,
        method=made.method,
        plan=made.q[order],
        evaluated={key: value[1] for key, value in sorted(found.items())},
        payload_kg=None if made.payload_kg is None else made.payload_kg[order],
        model=made.model,
        measured=measured,
    )
