"""Planning an experiment, as library calls: design, evaluate, size, simulate, synthesize.

What ``design``, ``evaluate``, ``poses-needed``, ``simulate`` and ``synthesize``
do beyond reading and writing files, for the model a robot file describes
(:func:`armcal.workflow.setup.fit_model`): a plan within the joint limits and
region, its quality and the warnings it deserves (a pose outside the region,
an ill-conditioned plan, solver trouble), virtual measurements of every target
of every pose.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..criteria import PlanQuality, evaluate_plan
from ..doe import (
    Design,
    PosesNeeded,
    design,
    design_with_loads,
    poses_needed,
    random_plan,
)
from ..errors import ArmcalError, ArmcalWarning, NotIdentifiableError, action
from ..files import RobotSpec
from ..identification.experiment import (
    coverage,
    plan_degenerate_warning,
    refuse_registration_only,
)
from ..models import FitModel, Loads
from ..models.information import met_rows
from ..progress import ProgressCallback
from .setup import DEFAULT_SIGMA_MM, check_plan_size, design_sigma, fit_model, plan_model, prefixed

if TYPE_CHECKING:
    from ..simulate import MonteCarlo

#: Poses of the random plan on which a model's identifiable set is chosen for sizing.
_SET_POSES = 200

__all__ = [
    "DesignRun",
    "EvaluationRun",
    "Synthesis",
    "design_plan",
    "evaluate_file",
    "simulate_plan",
    "size_plan",
    "synthesize_plan",
]


@dataclass(frozen=True, eq=False)
class Synthesis:
    """Virtual measurements: every target of every pose, with the rows' labels and loads.

    Attributes
    ----------
    q : ndarray, shape (r, n)
        The rows' joint angles (rad): each pose once per target.
    points : ndarray, shape (r, d)
        Measured points, mm.
    labels, targets : tuple of str or None
        Every row's pose label and target label, for an arm with several targets.
    payload_kg : ndarray, shape (r,), or None
        Every row's payload, for a model of joint compliance.
    sigma_mm : float
        The instrument noise drawn (mm; the noise model's reference when not given).
    effect : str
        What the virtual robot adds to its geometry ("joint compliance"), or "".
    warnings : tuple of ArmcalWarning
        ``truth-large`` for a virtual arm far from its nominal model
        (:func:`armcal.plausibility.truth_warning`); ``poses-unmet`` for poses where the
        true arm cannot meet its instrument (left out).
    feature : ndarray of int, shape (r,), or None
        The feature every row touches, for an instrument of several
        (:attr:`armcal.models.Conditions.feature`).
    """

    q: np.ndarray
    points: np.ndarray
    labels: tuple[str, ...] | None
    targets: tuple[str, ...] | None
    payload_kg: np.ndarray | None
    sigma_mm: float
    effect: str
    warnings: tuple[ArmcalWarning, ...] = ()
    feature: np.ndarray | None = None


def synthesize_plan(
    model: FitModel,
    q: np.ndarray,
    truth: np.ndarray,
    *,
    sigma: float | None,
    seed: int,
    loads: Loads | None = None,
    pose_labels: tuple[str, ...] | None = None,
) -> Synthesis:
    """Measurements of ``model`` (a plan's, :func:`~armcal.workflow.setup.plan_model`) at
    ``truth``, every target of every pose, each pose with its ``loads``; ``sigma`` as for
    :func:`armcal.synthesis.synthesize_measurements`.  The rows of a pose carry its label
    from ``pose_labels`` (the plan's ``pose`` column), else its number.

    Where a pose must meet the instrument (a touch, a seating, a distance within range)
    it is moved to where the true arm meets it, by the smallest joint change
    (:meth:`~armcal.models.interface.FitModel.meeting_poses`); a row that reports only
    that it meets it (:attr:`~armcal.models.interface.FitModel.touches`) reads 0, and
    its noise is where the arm stopped: its joints are moved on until the true reading
    is the noise drawn (with the sign that makes the reading 0 its measurement).  Poses
    that cannot are left out, with a ``poses-unmet`` warning.
    """
    # Imported here, not with the module: design and evaluate need neither the synthesis
    # nor the fit behind the truth's check (a lazy import of a slow dependency).
    from ..plausibility import truth_warning
    from ..synthesis import synthesize_measurements

    arm = model.arm
    # what the plan's poses touch, where they must meet the instrument at one feature each
    # (a photo meets it at every corner: its poses are moved until the true camera sees all)
    meant = model.plan_conditions(q, loads).feature if model.constrained else None
    if meant is not None and meant.shape[0] != q.shape[0]:
        meant = None
    moved, met = model.meeting_poses(q, truth, feature=meant)  # where the true arm does
    unmet = _unmet_warning(model, met)
    if not met.any():
        raise ArmcalError(str(unmet.message) if unmet else "no pose meets the instrument")
    q = moved[met]
    if pose_labels is not None:
        pose_labels = tuple(np.array(pose_labels, dtype=object)[met])
    if loads is not None:
        loads = loads.take(met)
    rows = model.plan_conditions(q, loads)
    count = rows.m // max(q.shape[0], 1)  # every target (every axis read) of every pose
    if meant is not None:
        rows = replace(rows, feature=meant[met])
    if model.point_dim > model.position_dim:  # a 6-DoF instrument's noise turns the true
        rows = rows.with_frames(None)  # orientations: drawn about them
        rows, _ = model.anchor(rows, model.positions(rows, truth))
    points = synthesize_measurements(
        model,
        rows.q,
        truth,
        sigma,
        rng=seed,
        target=rows.target,
        loads=rows.loads,
        frames=rows.frames,
        feature=rows.feature,
    )
    points = model.unanchor(rows, points)
    if model.touches:  # a touch reads 0: its noise is where the arm stopped
        noisy, stopped = model.meeting_poses(rows.q, truth, miss=-points, feature=rows.feature)
        rows = replace(rows.take(stopped), q=noisy[stopped])
        points = np.zeros_like(points[stopped])
        if pose_labels is not None:
            pose_labels = tuple(np.array(pose_labels, dtype=object)[stopped])
        kept = met.copy()
        kept[met] = stopped
        unmet = _unmet_warning(model, kept)
    labels = targets = None
    names = arm.target_labels
    if names or pose_labels is not None or count > 1:
        labels = tuple(
            str(i // count + 1) if pose_labels is None else pose_labels[i // count]
            for i in range(rows.m)
        )
    if names:
        index = np.zeros(rows.m, dtype=int) if rows.target is None else rows.target
        targets = tuple(names[t] for t in index)
    shown = sigma if sigma is not None else float(0.0 if arm.noise is None else arm.noise.sigma_mm)
    effect = "" if model.effect is None else model.effect.name
    payload_kg = None if rows.loads is None else rows.loads.payload_kg
    found = truth_warning(model, truth)
    warnings = tuple(w for w in (found, unmet) if w is not None)
    return Synthesis(
        rows.q, points, labels, targets, payload_kg, shown, effect, warnings, rows.feature
    )


def _unmet_warning(model: FitModel, met: np.ndarray) -> ArmcalWarning | None:
    """``poses-unmet``: poses of the plan where the true arm cannot meet its instrument (a
    touch beyond reach or the limits), left out of the virtual measurements."""
    if met.all():
        return None
    rows = np.flatnonzero(~met)
    shown = ", ".join(str(r + 1) for r in rows[:5]) + (", ..." if rows.size > 5 else "")
    return ArmcalWarning(
        "poses-unmet",
        f"{rows.size} of {met.size} poses of the plan (rows {shown}) cannot meet the "
        "instrument for the arm as it really is (beyond the joint limits or out of reach) "
        "and are left out of the measurements; design the plan for this instrument "
        "(armcal design) or move those poses",
    )


@dataclass(frozen=True, eq=False)
class EvaluationRun:
    """A plan's quality for the model of a robot file, and the warnings it deserves."""

    quality: PlanQuality
    warnings: tuple[ArmcalWarning, ...]


def _outside_warning(spec: RobotSpec, q: np.ndarray, source: str) -> ArmcalWarning | None:
    """``outside-region`` for the poses of ``q`` the instrument cannot see, or None."""
    outside = np.flatnonzero(~spec.arm.feasible(q))
    if not outside.size:
        return None
    poses = ", ".join(map(str, outside + 1))
    return ArmcalWarning(
        "outside-region",
        f"{source}: the tip of pose(s) {poses} is outside the measurement region",
    )


def unmet_plan_warning(model: FitModel, q: np.ndarray, source: str) -> ArmcalWarning | None:
    """``poses-unmet`` for poses of a plan that do not meet the instrument at the nominal arm
    (a touch off its plane, a photo that misses part of the board), or None: their rows
    are counted in the plan's figures as if measured, which they cannot be there."""
    if not model.constrained:
        return None
    moved, met = model.meeting_poses(q)
    off = np.flatnonzero(~met | (np.max(np.abs(moved - q), axis=-1) > _MEETS_RAD))
    if not off.size:
        return None
    shown = ", ".join(str(r + 1) for r in off[:5]) + (", ..." if off.size > 5 else "")
    return ArmcalWarning(
        "poses-unmet",
        f"{source}: {off.size} of {q.shape[0]} poses (rows {shown}) do not meet the "
        "instrument at the nominal arm (a touch off its plane, a board not wholly in view): "
        "their rows are counted as if measured, which they cannot be there; design the plan "
        "for this instrument (armcal design)",
    )


#: A plan's pose meets the instrument when it need move no joint by more than this (rad)
#: to meet it: a plan written to a file and read back is off by its digits' round-off.
_MEETS_RAD = 1e-6


def evaluate_file(
    spec: RobotSpec,
    arm: FitModel,
    q: np.ndarray,
    *,
    test_q: np.ndarray,
    payload: np.ndarray | None = None,
    source: str = "plan",
) -> EvaluationRun:
    """The quality of plan ``q`` for the model of ``spec`` (``arm`` with --fix and --sigma).

    ``payload`` ``(m,)`` (kg) loads a model whose points depend on the load
    (default: the robot file's payload).  Raises NotIdentifiableError, naming
    ``source``, for a plan that cannot identify every parameter (it has no
    finite quality).
    """
    model, loads = plan_model(spec, arm, q.shape[0], payload)
    rows = model.plan_conditions(q, loads)
    model = model.prepared(rows)
    # A plan that misses part of the arm: its predicted figures assume the rest nominal.
    found = coverage(model, q)
    try:
        refuse_registration_only(found, q.shape[0], "poses")
        quality = evaluate_plan(
            model, q, sigma=design_sigma(arm), test_q=test_q, loads=loads, rows=rows
        )
    except NotIdentifiableError as exc:  # PRODUCT.md: an error, exit 2, one line
        raise prefixed(source, exc) from None
    degenerate = plan_degenerate_warning(
        found,
        f"{source}'s poses",
        holds="its predicted std and predicted position error after calibration hold",
        like="the plan's",
    )
    found_warnings = (
        degenerate,
        _outside_warning(spec, q, source),
        unmet_plan_warning(model, q, source),
    )
    extra = tuple(w for w in found_warnings if w is not None)
    return EvaluationRun(quality, (*spec.warnings, *quality.warnings, *extra))


@dataclass(frozen=True, eq=False)
class DesignRun:
    """A designed plan, its quality, the wall time and the warnings."""

    design: Design
    quality: PlanQuality
    seconds: float
    warnings: tuple[ArmcalWarning, ...]

    @property
    def q(self) -> np.ndarray:
        """The plan (rad), in the order to measure it."""
        return self.design.q

    @property
    def payload_kg(self) -> np.ndarray | None:
        """The payload of every pose, for a design that chose them."""
        return self.design.payload_kg


def moving_set(model: FitModel, seed: int) -> FitModel:
    """The model reduced to what a plan moving every joint identifies (a family with minimal
    parameters is itself), from :data:`_SET_POSES` random poses of a stream of its own, so
    that the seed's stream (the design's, the search's) stays the same, moved onto an
    instrument that sees the tool only where it meets it (a camera's random pose seldom
    sees the board: its rows held all but one of the arm's parameters)."""
    probe = random_plan(model, _SET_POSES, rng=np.random.default_rng([seed, 1]))
    return model.prepared(met_rows(model, probe))


def design_plan(
    spec: RobotSpec,
    arm: FitModel,
    poses: int,
    *,
    criterion: str = "D",
    method: str = "auto",
    seed: int = 0,
    candidates: np.ndarray | None = None,
    candidates_source: str = "candidates",
    order: str = "travel",
    distinct: bool = False,
    payloads: tuple[float, ...] | None = None,
    test_q: np.ndarray,
    progress: ProgressCallback | None = None,
) -> DesignRun:
    """An optimal plan for the model of ``spec`` (``arm`` with --fix and --sigma).

    Where the model's points depend on the load (``[elastostatic]``) the poses
    and their payloads are designed together (D-optimal by exchange and polish,
    :func:`armcal.doe.design_with_loads`).

    Raises
    ------
    ArmcalError
        For options the model cannot use: payloads where the load moves
        nothing, a criterion or method other than D by exchange with loads,
        candidates outside the measurement region.
    """
    check_plan_size(poses)
    rng = np.random.default_rng(seed)
    model = fit_model(spec, arm)
    model = moving_set(model, seed)
    sigma = design_sigma(arm)
    start = time.perf_counter()
    if spec.elastic is not None:  # the poses carry payloads, chosen by the design
        if criterion != "D" or method not in ("auto", "exchange"):
            raise ArmcalError(
                "a robot with [elastostatic] is designed D-optimal by exchange and polish; "
                f"leave {action('design-defaults')}"
            )
        if candidates is not None:  # their payload_kg column too: refused, never dropped
            raise ArmcalError(
                f"{candidates_source}: a plan from candidate poses (with or without a "
                "payload_kg column) is not supported with [elastostatic] yet: the design "
                f"chooses the poses and their payloads itself; leave out {action('candidates')}"
            )
        if distinct:
            raise ArmcalError(f"{action('distinct')} is not supported with [elastostatic] yet")
        made = design_with_loads(model, poses, payloads=payloads, rng=rng, order=order)
        assert made.payload_kg is not None
        loads: Loads | None = Loads.create(poses, made.payload_kg)
    else:
        if payloads is not None:
            raise ArmcalError(
                f"{action('payloads')}: robot {spec.arm.name} has no [elastostatic] table, so a "
                "payload changes nothing; add the table to the robot file"
            )
        if candidates is not None and not np.all(spec.arm.feasible(candidates)):
            row = int(np.flatnonzero(~spec.arm.feasible(candidates))[0]) + 1
            raise ArmcalError(
                f"{candidates_source}: row {row}: the tip is outside the measurement region; "
                "remove the pose or widen the region"
            )
        made = design(
            model,
            poses,
            criterion=criterion,
            method=method,  # type: ignore[arg-type]  # checked by design
            rng=rng,
            candidates=candidates,
            order=order,  # type: ignore[arg-type]  # checked by design
            distinct=distinct,
            progress=progress,
            test_q=test_q,
        )
        loads = None
    seconds = time.perf_counter() - start
    quality = evaluate_plan(made.model, made.q, sigma=sigma, test_q=test_q, loads=loads)
    return DesignRun(made, quality, seconds, (*spec.warnings, *made.warnings, *quality.warnings))


def simulate_plan(
    model: FitModel,
    q: np.ndarray,
    truth: np.ndarray,
    *,
    trials: int,
    method: str = "auto",
    seed: int = 0,
    test_q: np.ndarray | None = None,
    loads: Loads | None = None,
    progress: ProgressCallback | None = None,
    source: str = "plan",
) -> MonteCarlo:
    """A Monte Carlo of plan ``q`` on ``model`` (a plan's,
    :func:`~armcal.workflow.setup.plan_model`), each pose with its ``loads``.

    The noise is the model's as it is (:data:`~armcal.workflow.setup.DEFAULT_SIGMA_MM`
    when the robot file gives none); no test poses (None or none) give no position
    figures.  Raises NotIdentifiableError, naming ``source``, for a plan that cannot
    identify every parameter.
    """
    # Imported here, not with the module: design and evaluate need neither the Monte Carlo
    # nor the fit behind the truth's check (a lazy import of a slow dependency).
    from ..plausibility import truth_warning
    from ..simulate import monte_carlo

    if test_q is not None and not len(test_q):
        test_q = None
    found = truth_warning(model, truth)  # of the truth as given, in the model's parameters
    unmet = unmet_plan_warning(model, q, source)
    # The Monte Carlo prepares the model for this plan and expresses the truth as its fit
    # sees it (a family whose parameters are minimal is itself).
    try:
        result = monte_carlo(
            model,
            q,
            truth,
            None if model.noise is not None else DEFAULT_SIGMA_MM,
            trials,
            method=method,
            rng=np.random.default_rng(seed),
            test_q=test_q,
            progress=progress,
            loads=loads,
        )
    except NotIdentifiableError as exc:
        raise prefixed(source, exc) from None
    said = tuple(w for w in (found, unmet) if w is not None)
    return replace(result, warnings=(*said, *result.warnings)) if said else result


def size_plan(
    spec: RobotSpec,
    arm: FitModel,
    requirement: str,
    goal: float,
    *,
    seed: int = 0,
    test_q: np.ndarray,
    max_poses: int = 5000,
    progress: ProgressCallback | None = None,
) -> tuple[PosesNeeded, float]:
    """The smallest number of poses whose best plan reaches ``goal`` (and the wall time).

    For a robot with ``[elastostatic]`` the plans are of poses and payloads,
    designed together (:func:`armcal.doe.design_with_loads`), and the accuracy is
    of the model with compliance.
    """
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    model = fit_model(spec, arm)
    model = moving_set(model, seed)
    found = poses_needed(
        model,
        requirement,
        goal,
        sigma=design_sigma(arm),
        rng=rng,
        test_q=test_q,
        max_poses=max_poses,
        plans="designed",
        progress=progress,
    )
    return found, time.perf_counter() - start
