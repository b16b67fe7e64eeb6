"""Name the likely cause of a fit that is far off: swapped target labels, coupled joints.

A misfit has many possible causes, and the fit-inconsistent warning lists them
in general.  Two of them a cheap test can name, for every family of arm
(:class:`~armcal.models.interface.FitModel`), and then a warning says which rows
or which robot-file key to fix:

* **target labels swapped** (``targets-swapped``): a pose measured at several
  targets (a tracker's nest of reflectors) whose labels were exchanged puts two
  rows a target spacing away from the fit; one wrong label (a pose that carries one
  target twice) puts one row there.  At the fitted parameters, for the
  :data:`WORST_POSES` worst poses only, every exchange of two of a pose's labels
  and every other label of each of its rows is tried (one call of the model on a
  few rows); the best relabelling of each pose that cuts its residual sum of
  squares :data:`SWAP_GAIN` times is applied and the model refitted once, from the
  fit.  They are named when the refit's chi-square is :data:`SWAP_GAIN` times
  lower (its residual RMS halves) and each still fits that much better relabelled
  than as labelled.
* **coupled joints** (``coupled-joints``): a controller that reads a joint
  against the horizon (FANUC's J2/J3 interaction: the chain's elbow angle is
  ``J2 + J3``), described by a robot file without that ``joint_map``, or the
  other way round.  Tried only when the fit is far off (residual RMS beyond
  :data:`SUSPICIOUS_RMS_FRACTION` of the reach, or a chi-square
  :data:`IMPROVEMENT` times its degrees of freedom): for every pair of
  consecutive readings whose tool rotations are parallel (to :data:`PARALLEL_SINE`:
  a calibrated URDF's axes are tilted a little; every pair of a planar arm), the
  readings ``q_k + q_j`` and ``q_k - q_j`` in place of ``q_k``, and for every run of
  three or more such readings the running sums or the differences of the whole run
  (a planar arm's relative readings under an identity ``joint_map``, or absolute
  ones under the default map: every reading is wrong, not one), on at most
  :data:`COUPLING_ROWS` rows.  Each reading places the nominal arm on the
  data (the model's start, no fit); the one whose nominal arm fits best, and
  :data:`SWAP_GAIN` times better than the fit as read, is refitted, and named
  when its residual mean square is :data:`IMPROVEMENT` times lower than the fit
  as read and its residual RMS within :data:`SUSPICIOUS_RMS_FRACTION` of the reach.

Both tests run only on a fit that looks wrong (:func:`armcal.identification.identify`
calls them), and cost next to nothing unless a candidate passes its cheap screen:
then one refit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ArmcalError, ArmcalWarning
from ..models import Conditions, FitModel
from ..numerics import rms
from .problem import Fit, Problem

__all__ = [
    "COUPLING_ROWS",
    "IMPROVEMENT",
    "SUSPICIOUS_RMS_FRACTION",
    "SWAP_GAIN",
    "WORST_POSES",
    "coupled_joints",
    "far_off",
    "swapped_targets",
]

#: How many times smaller an alternative reading's residual mean square must be to be
#: named (two orders of magnitude: far beyond what chance or a few parameters give).
IMPROVEMENT = 100.0

#: A residual RMS above this fraction of the arm's reach (0.66 mm for the paper's
#: 660 mm arm) is more than an instrument good enough to calibrate the arm leaves:
#: calibration corrects deviations of about 1/200 of the reach (a few mm), so a
#: useful instrument is several times better than 1/1000 of it.
SUSPICIOUS_RMS_FRACTION = 1e-3

#: How many times an exchange of two target labels must lower the residual sum of
#: squares (of its pose, and of the whole fit after the refit): its RMS halves.
SWAP_GAIN = 4.0

#: The worst poses (largest residual sum of squares) whose label exchanges are tried.
WORST_POSES = 10

#: Rows a coupled reading is tried on (evenly spaced): 100 poses at three targets
#: identify a six-axis arm many times over, and keep the refits cheap at 10^5 rows.
COUPLING_ROWS = 300

#: Two tool rotations per reading are parallel when the sine of their angle is below this:
#: nominally parallel axes of a robot file with a calibration folded in (an exported
#: URDF) are tilted by a calibration's angular errors, about 0.01-0.1 deg (sine 2e-4 to
#: 2e-3), and a coupling may be read there; 0.01 (0.57 deg) stays far below the angle
#: of axes that are not meant to be parallel (90 deg on a six-axis arm).
PARALLEL_SINE = 1e-2

#: A reading turns the tool by round-off only (a slide) when its rotation, rad per rad,
#: is below this: parallel to any.
ROUND_OFF_TURN = 1e-6


def _chi2(fit: Fit, rows: np.ndarray | slice = slice(None)) -> float:
    return float(np.sum(fit.whitened[rows] ** 2))


def far_off(model: FitModel, fit: Fit, sigma: float | None) -> bool:
    """Whether a fit is far off: its residual RMS per coordinate beyond
    :data:`SUSPICIOUS_RMS_FRACTION` of the reach, or (with a given ``sigma``, mm) a
    chi-square :data:`IMPROVEMENT` times its degrees of freedom or more."""
    residuals = fit.residuals[:, : model.position_dim]
    if rms(residuals) > SUSPICIOUS_RMS_FRACTION * model.reach_mm:
        return True
    if sigma is None:
        return False
    dof = max(fit.whitened.size - model.n_free, 1)
    return _chi2(fit) / sigma**2 >= IMPROVEMENT * dof


def _fold(before: float, after: float) -> str:
    return "to round-off" if after <= 0 else f"{before / after:.3g}-fold"


# --------------------------------------------------------------------------- swapped labels


def _pose_groups(labels: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, int]:
    """Every row's pose index (by its label) and the number of poses."""
    _, group = np.unique(labels, return_inverse=True)
    return group.reshape(target.shape), int(group.max()) + 1


def _relabels(rows: np.ndarray, target: np.ndarray, labels: int) -> list[list[tuple[int, int]]]:
    """Every relabelling tried on one pose's ``rows``, each a list of ``(row, new target)``:
    every exchange of two rows' different targets, and every row given another of the
    ``labels`` targets (a single wrong label, as when a pose carries one target twice)."""
    found = [
        [(int(a), int(target[b])), (int(b), int(target[a]))]
        for i, a in enumerate(rows)
        for b in rows[i + 1 :]
        if target[a] != target[b]
    ]
    found += [[(int(a), t)] for a in rows for t in range(labels) if t != target[a]]
    return found


def _relabelled(
    model: FitModel,
    conditions: Conditions,
    points: np.ndarray,
    params: np.ndarray,
    changes: np.ndarray,
) -> np.ndarray:
    """Squared position residuals ``(k,)`` at ``params`` of rows ``changes[:, 0]`` given
    targets ``changes[:, 1]``: one call of the model on ``k`` rows."""
    rows = changes[:, 0]
    trial = replace(conditions.take(rows), target=changes[:, 1])
    d = model.position_dim
    errors = points[rows, :d] - model.positions(trial, params)[:, :d]
    return np.sum(errors**2, axis=1)


def _describe(
    change: list[tuple[int, int]],
    target: np.ndarray,
    labels: Sequence[str],
    pose_labels: Sequence[str],
    rows: Sequence[int],
) -> str:
    """One relabelling in words: a swap of two targets, or one row's label."""
    a, new = change[0]
    if len(change) == 2:
        b = change[1][0]
        return (
            f"pose {pose_labels[a]}: targets {labels[target[a]]} and {labels[target[b]]} look "
            f"swapped (rows {rows[a]}, {rows[b]})"
        )
    return (
        f"pose {pose_labels[a]}: row {rows[a]} labelled {labels[target[a]]} fits as {labels[new]}"
    )


def _best_relabellings(
    problem: Problem, fit: Fit, group: np.ndarray, count: int
) -> list[list[tuple[int, int]]]:
    """The best relabelling of each of the :data:`WORST_POSES` worst poses that cuts its
    sum of squares :data:`SWAP_GAIN` times at the fit's parameters (none: an empty list)."""
    model, conditions, points = problem.model, problem.conditions, problem.points
    target = conditions.target
    assert target is not None
    d = model.position_dim
    row_squares = np.sum(fit.residuals[:, :d] ** 2, axis=1)
    pose_squares = np.bincount(group, weights=row_squares, minlength=count)
    order = np.argsort(group, kind="stable")
    starts = np.searchsorted(group[order], np.arange(count + 1))
    worst = [int(g) for g in np.argsort(-pose_squares)[:WORST_POSES]]
    candidates = [
        (g, change)
        for g in worst
        for change in _relabels(order[starts[g] : starts[g + 1]], target, len(model.target_labels))
    ]
    if not candidates:
        return []
    changes = np.array([pair for _, change in candidates for pair in change])
    owner = np.repeat(np.arange(len(candidates)), [len(c) for _, c in candidates])
    # The change of its pose's sum of squares if a candidate's relabelling is applied.
    delta = (
        _relabelled(model, conditions, points, fit.params, changes) - row_squares[changes[:, 0]]
    )
    change = np.bincount(owner, weights=delta, minlength=len(candidates))
    chosen: dict[int, int] = {}  # pose -> its best candidate
    for k, (g, _) in enumerate(candidates):
        after = pose_squares[g] + change[k]
        if after * SWAP_GAIN <= pose_squares[g] and (
            g not in chosen or change[k] < change[chosen[g]]
        ):
            chosen[g] = k
    return [candidates[k][1] for k in chosen.values()]


def _relabelled_refit(
    problem: Problem, fit: Fit, picked: list[list[tuple[int, int]]]
) -> tuple[Problem, Fit] | None:
    """The problem with the ``picked`` relabellings applied and its refit from the fit, or
    None when the refit fails or does not cut the chi-square :data:`SWAP_GAIN` times."""
    conditions = problem.conditions
    assert conditions.target is not None
    applied = np.array([pair for item in picked for pair in item])
    relabelled = conditions.target.copy()
    relabelled[applied[:, 0]] = applied[:, 1]
    swapped = Problem(
        problem.model,
        replace(conditions, target=relabelled),
        problem.points,
        problem.method,
        problem.tol,
        problem.max_iter,
    )
    try:
        refit = swapped.fit(np.ones(conditions.m, dtype=bool), start=fit.params)
    except ArmcalError:  # NotIdentifiableError among them: the relabelling tells nothing
        return None
    if _chi2(refit) * SWAP_GAIN > _chi2(fit):
        return None
    return swapped, refit


def _still_better(
    problem: Problem, swapped: Problem, refit: Fit, picked: list[list[tuple[int, int]]]
) -> list[list[tuple[int, int]]]:
    """The relabellings of ``picked`` that still fit :data:`SWAP_GAIN` times better than
    their labels at the refit's parameters."""
    target = problem.conditions.target
    assert target is not None
    applied = np.array([pair for item in picked for pair in item])
    back = np.column_stack([applied[:, 0], target[applied[:, 0]]])
    owners = np.repeat(np.arange(len(picked)), [len(item) for item in picked])
    as_labelled = np.bincount(
        owners,
        weights=_relabelled(problem.model, swapped.conditions, problem.points, refit.params, back),
    )
    d = problem.model.position_dim
    refit_squares = np.sum(refit.residuals[:, :d] ** 2, axis=1)
    relabelled_squares = np.bincount(owners, weights=refit_squares[applied[:, 0]])
    return [
        item
        for item, a, b in zip(picked, relabelled_squares, as_labelled, strict=True)
        if a * SWAP_GAIN <= b
    ]


def swapped_targets(
    problem: Problem,
    fit: Fit,
    pose_labels: Sequence[str],
    rows: Sequence[int],
) -> ArmcalWarning | None:
    """A ``targets-swapped`` warning naming the poses whose target labels look exchanged,
    or one row whose label looks wrong.

    Parameters
    ----------
    problem : Problem
        The identification: its model, rows (with every row's target) and points.
    fit : Fit
        Its least-squares fit to every row.
    pose_labels : sequence of str
        Every row's pose (the rows of a pose share its label).
    rows : sequence of int
        Every row's 1-based row in its file, for the message.

    Returns
    -------
    ArmcalWarning or None
        None without several targets, or when no relabelling passes the tests of the
        module notes.
    """
    model, target = problem.model, problem.conditions.target
    labels = model.target_labels
    if target is None or len(labels) < 2:
        return None
    group, count = _pose_groups(np.asarray(pose_labels), target)
    picked = _best_relabellings(problem, fit, group, count)
    if not picked:
        return None
    refitted = _relabelled_refit(problem, fit, picked)
    if refitted is None:
        return None
    swapped, refit = refitted
    kept = _still_better(problem, swapped, refit, picked)
    if not kept:
        return None
    d = model.position_dim
    named = [_describe(item, target, labels, pose_labels, rows) for item in kept[:5]]
    more = f" and {len(kept) - 5} more" if len(kept) > 5 else ""
    before = rms(fit.residuals[:, :d])
    after = rms(refit.residuals[:, :d])
    return ArmcalWarning(
        "targets-swapped",
        f"{'; '.join(named)}{more}: relabelled, the residual RMS per coordinate falls from "
        f"{before:.3g} to {after:.3g} mm; check the target column of these rows",
    )


# --------------------------------------------------------------------------- coupled joints


def _parallel_pairs(model: FitModel, conditions: Conditions) -> list[int]:
    """The readings ``j`` (0-based) whose tool rotation is parallel to reading ``j + 1``'s
    at every one of the first rows (a zero rotation, a slide, counts as parallel)."""
    sample = conditions.take(slice(0, min(conditions.m, 5)))
    turns = np.asarray(model.orientation_joint_jacobian(sample))  # (k, dim, n)
    found = []
    for j in range(model.n_joints - 1):
        a, b = turns[:, :, j], turns[:, :, j + 1]
        sizes = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
        along = np.abs(np.sum(a * b, axis=1))
        # |a x b|^2 = |a|^2 |b|^2 - (a . b)^2, in any dimension (0 for one rotation axis);
        # a reading that turns the tool by round-off only (rad per rad) is parallel to any.
        across = np.sqrt(np.maximum(sizes**2 - along**2, 0.0))
        if np.all((across <= PARALLEL_SINE * sizes) | (sizes <= ROUND_OFF_TURN)):
            found.append(j)
    return found


def _map_text(matrix: np.ndarray) -> str:
    rows = ", ".join("[" + ", ".join(f"{v:g}" for v in row) + "]" for row in matrix)
    return f"[{rows}]"


@dataclass(frozen=True)
class Reading:
    """One alternative reading of the joints: the chain's values from ``coupling @ q``."""

    coupling: np.ndarray  # (n, n)
    text: str  # what each changed reading is read as
    head: str = ""  # the warning's opening when the robot file has no joint map


def _runs(pairs: Sequence[int]) -> list[tuple[int, int]]:
    """The maximal runs ``(a, b)`` of readings ``a..b`` (0-based) each parallel to the next."""
    runs: list[tuple[int, int]] = []
    for j in pairs:
        if runs and runs[-1][1] == j:
            runs[-1] = (runs[-1][0], j + 1)
        else:
            runs.append((j, j + 1))
    return runs


def _readings(pairs: Sequence[int], n: int) -> list[Reading]:
    """The alternative readings tried: each parallel pair coupled (``q_k + q_j`` or
    ``q_k - q_j``), and each run of three or more parallel readings summed or
    differenced as a whole (a planar arm's relative readings taken for absolute ones,
    or the other way round: every reading of the run would be wrong, not one)."""
    found = []
    for j in pairs:
        first, second = f"J{j + 1}", f"J{j + 2}"
        for sign in (1.0, -1.0):
            coupling = np.eye(n)
            coupling[j + 1, j] = sign
            head = (
                f"the joint readings look like those of a controller that couples {first} "
                f"and {second} (FANUC-style: {second} read against the horizon)"
                if sign > 0
                else ""
            )
            text = f"{second} as {second} {'+' if sign > 0 else '-'} {first}"
            found.append(Reading(coupling, text, head))
    for a, b in _runs(pairs):
        if b - a < 2:
            continue  # a run of two is the pair above
        sums = np.eye(n)
        sums[a : b + 1, a : b + 1] = np.tril(np.ones((b - a + 1, b - a + 1)))
        named = [f"J{k + 1}" for k in range(a, b + 1)]
        summed = ", ".join(
            f"{named[k]} as {' + '.join(named[: k + 1])}" for k in range(1, len(named))
        )
        differences = ", ".join(
            f"{named[k]} as {named[k]} - {named[k - 1]}" for k in range(1, len(named))
        )
        found.append(Reading(sums, f"{summed} (running sums of the readings)"))
        found.append(
            Reading(
                np.linalg.inv(sums),
                f"{differences} (differences of consecutive readings)",
            )
        )
    return found


def coupled_joints(problem: Problem, fit: Fit) -> ArmcalWarning | None:
    """A ``coupled-joints`` warning when the readings fit far better with two joints coupled.

    Parameters
    ----------
    problem : Problem
        The identification: its model (with its joint map), rows and points.
    fit : Fit
        Its least-squares fit to every row, far off (:func:`far_off`).

    Returns
    -------
    ArmcalWarning or None
        Naming the two joints, the improvement and the robot file's ``joint_map``
        that reads them so; None when no coupling passes the tests of the module notes.
    """
    model, conditions, points = problem.model, problem.conditions, problem.points
    m, n = conditions.m, model.n_joints
    sub = np.unique(np.linspace(0, m - 1, min(m, COUPLING_ROWS)).astype(int))
    rows, measured = conditions.take(sub), points[sub]
    every = np.ones(len(sub), dtype=bool)
    dim = points.shape[1]
    before = _chi2(fit, sub) / max(dim * len(sub) - model.n_free, 1)
    placed: list[tuple[float, int, Reading, Problem, np.ndarray]] = []
    for index, reading in enumerate(_readings(_parallel_pairs(model, rows), n)):
        trial = replace(rows, q=np.asarray(rows.q) @ reading.coupling.T)
        try:
            prepared = model.prepared(trial, measured)
            prepared.check_identifiable(trial)
            start = prepared.start(trial, measured[None])[0]
        except (ArmcalError, ValueError, np.linalg.LinAlgError):
            continue  # this reading cannot be fitted: it explains nothing
        alternative = Problem(
            prepared, trial, measured, problem.method, problem.tol, problem.max_iter
        )
        dof = max(dim * len(sub) - prepared.n_free, 1)
        nominal = _chi2(Fit(alternative, start, every, 0, False)) / dof
        if nominal * SWAP_GAIN <= before:  # the nominal arm read so already fits better
            placed.append((nominal, index, reading, alternative, start))
    if not placed:
        return None
    _, _, reading, alternative, start = min(placed, key=lambda found: found[:2])
    try:  # the one refit: the reading whose nominal arm fits best
        refit = alternative.fit(every, start=start)
    except (ArmcalError, np.linalg.LinAlgError):
        return None
    after = _chi2(refit) / max(dim * len(sub) - alternative.model.n_free, 1)
    d = model.position_dim
    residual = rms(refit.residuals[:, :d])
    if after * IMPROVEMENT > before or residual > SUSPICIOUS_RMS_FRACTION * model.reach_mm:
        return None
    given = np.asarray(model.joint_map, dtype=float)
    proposed = given @ reading.coupling
    plain = np.array_equal(given, np.eye(n))
    head = (
        reading.head
        if plain and reading.head
        else ("the joint readings do not follow the robot file's joint map")
    )
    where = "add joint_map = {} to" if plain else "set joint_map = {} in"
    return ArmcalWarning(
        "coupled-joints",
        f"{head}: read with {reading.text}, the fit "
        f"improves {_fold(before, after)} (residual RMS per coordinate "
        f"{rms(fit.residuals[sub, :d]):.3g} -> {residual:.3g} mm on {len(sub)} rows); "
        + where.format(_map_text(proposed))
        + " the robot file",
    )
