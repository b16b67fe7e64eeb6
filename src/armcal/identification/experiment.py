"""What an experiment's rows can support: rows repeated exactly, and what a plan cannot see.

Two checks of the rows themselves, before any fit is judged, for every family
of arm (:class:`~armcal.models.interface.FitModel`):

**Rows repeated exactly.**  A row whose joint readings, target and measured
point all equal an earlier row's is a copy (a file appended twice, a row pasted
again): real repeated measurements differ by the instrument's noise.  A copy
counts one measurement twice, so every std shrinks as if it were new
information (by ``sqrt(2)`` for data copied whole) and the chi-square test
loses its meaning.  :func:`repeated_rows` finds them by sorting the rows
(``O(m log m)``), never by comparing every pair.

**What a plan cannot see.**  A family with an over-complete parameter set (the
spatial arm) holds, for a set of rows, what those rows cannot separate
(:meth:`~armcal.models.interface.FitModel.prepared`): a plan that never moves a
joint holds that joint's parameters.  The identification then succeeds, but
the calibration, its std and every error it predicts hold only at poses like
the plan's: elsewhere the held parameters act at their nominal values, which
is what calibration was to correct.  :func:`coverage` compares the rows' set
with the arm's own set -- the model prepared for :data:`PROBE_POSES` random poses
within the joint limits, every joint moving -- and names the parameters lost
and the joints whose readings never change.  A family whose parameters are
minimal prepares to itself and loses nothing here: rows that cannot identify
it are refused by its rank check.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArmcalError, ArmcalWarning, NotIdentifiableError
from ..models import FitModel, listing
from ..models.information import met_rows

__all__ = [
    "PROBE_POSES",
    "PROBE_SEED",
    "STILL_TOLERANCE",
    "Coverage",
    "coverage",
    "plan_degenerate_warning",
    "refuse_registration_only",
    "repeated_rows",
    "repeated_rows_warning",
]

#: Random poses that stand for a plan moving every joint: the arm's own set is what
#: these identify.  The set needs ``4R + 2P + 3k`` independent columns, which a few
#: dozen generic poses already give; 100 keep it well clear of a chance dependence at
#: a few hundredths of a second (the model's rule, not a fit).
PROBE_POSES = 100
#: The probe's seed: the same poses, hence the same set, on every run.
PROBE_SEED = 20260034

#: A joint whose readings span no more than this (rad, or mm for a prismatic joint)
#: never moves: the rule of :mod:`~armcal.models.spatial.selection` for a still joint.
STILL_TOLERANCE = 1e-9

#: How many names a warning lists before "and N more".
SHOWN = 12


def repeated_rows(
    q: np.ndarray,
    points: np.ndarray,
    target: np.ndarray | None = None,
    feature: np.ndarray | None = None,
) -> np.ndarray:
    """For every row, the index of the earlier row it repeats exactly, else -1 ``(m,)``.

    Rows are equal when their joint readings ``q`` ``(m, n)``, target ``(m,)``, an
    instrument's feature ``(m,)`` and measured point ``points`` ``(m, d)`` are equal
    number for number.  One sort of the rows (``O(m log m)``).

    Examples
    --------
    >>> q = np.array([[0.0, 1.0], [0.5, 1.0], [0.0, 1.0], [0.0, 1.0]])
    >>> xy = np.array([[1.0, 2.0], [3.0, 4.0], [1.0, 2.0], [1.0, 2.5]])
    >>> repeated_rows(q, xy).tolist()
    [-1, -1, 0, -1]
    """
    q = np.asarray(q, dtype=float)
    points = np.asarray(points, dtype=float)
    m = q.shape[0]
    columns = [q.reshape(m, -1), points.reshape(m, -1)]
    for more in (target, feature):
        if more is not None:
            columns.append(np.asarray(more, dtype=float).reshape(m, 1))
    rows = np.hstack(columns) + 0.0  # -0.0 and 0.0 are one number
    if m == 0:
        return np.zeros(0, dtype=int)
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    earliest = first[inverse.reshape(-1)]
    return np.where(earliest < np.arange(m), earliest, -1)


def repeated_rows_warning(
    repeats: np.ndarray, rows: Sequence[int], noun: str = "rows"
) -> ArmcalWarning | None:
    """``duplicate-rows`` naming a few of the rows that repeat another (1-based data rows
    ``rows``), or None when none does.  ``repeats`` is :func:`repeated_rows`'s answer."""
    copies = np.flatnonzero(repeats >= 0)
    if not copies.size:
        return None
    pairs = [f"row {rows[i]} repeats row {rows[repeats[i]]}" for i in copies[:3]]
    more = f" and {copies.size - 3} more" if copies.size > 3 else ""
    one = copies.size == 1
    return ArmcalWarning(
        "duplicate-rows",
        f"{copies.size} {noun[:-1] if one else noun} of {len(repeats)} "
        f"{'repeats' if one else 'repeat'} an earlier one exactly (the same joint readings, "
        f"target and measured point): {', '.join(pairs)}{more}; a copy counts one "
        "measurement twice, so every std is smaller than the data support (by up to "
        "sqrt(2)) and the chi-square test is off; remove the copies (real repeated "
        "measurements differ by the instrument's noise)",
    )


@dataclass(frozen=True)
class Coverage:
    """What a set of rows identifies of an arm, against a plan that moves every joint.

    Attributes
    ----------
    lost : tuple of str
        Parameters the rows leave held that the arm's own set identifies.
    still : tuple of int
        1-based joints whose readings never change in the rows (empty when unknown).
    arm_seen : bool
        Whether the rows identify any parameter beyond the instrument's pose and the
        targets (:attr:`~armcal.models.interface.FitModel.instrument_params`).
    arm_needed : bool
        Whether the arm's own set has any such parameter (False when every one of
        them is held by the user).
    instrument : tuple of str
        The free parameters that place the instrument and the targets.
    """

    lost: tuple[str, ...]
    still: tuple[int, ...]
    arm_seen: bool
    arm_needed: bool
    instrument: tuple[str, ...]


def _probe(model: FitModel) -> np.ndarray:
    """:data:`PROBE_POSES` poses uniform within the joint limits, from :data:`PROBE_SEED`
    (an instrument that sees the tool only where it meets it moves them there:
    :meth:`~armcal.models.interface.FitModel.meeting_poses`)."""
    rng = np.random.default_rng(PROBE_SEED)
    limits = np.asarray(model.joint_limits, dtype=float)
    return rng.uniform(limits[:, 0], limits[:, 1], size=(PROBE_POSES, model.n_joints))


def coverage(model: FitModel, q: np.ndarray | None = None) -> Coverage:
    """What ``model``, prepared for a set of rows, identifies against the arm's own set.

    Parameters
    ----------
    model : FitModel
        The model as :meth:`~armcal.models.interface.FitModel.prepared` made it for
        the rows (registered to their points where the family places its instrument).
    q : ndarray, shape (m, n), optional
        The rows' joint readings, to name the joints that never move.

    Returns
    -------
    Coverage
    """
    try:
        rich = model.prepared(met_rows(model, _probe(model)))
    except ArmcalError:  # too few probe poses meet the instrument to judge by: no verdict
        rich = model
    held = set(model.fixed)
    lost = tuple(name for name in rich.param_names if name in held and name not in rich.fixed)
    still: tuple[int, ...] = ()
    if q is not None and len(q):
        span = np.ptp(np.asarray(q, dtype=float), axis=0)
        still = tuple(int(j) + 1 for j in np.flatnonzero(span <= STILL_TOLERANCE))
    instrument = np.asarray(model.instrument_params, dtype=bool)
    names = model.param_names
    return Coverage(
        lost=lost,
        still=still,
        arm_seen=bool(np.any(model.free & ~instrument)),
        arm_needed=bool(np.any(rich.free & ~instrument)),
        instrument=tuple(names[i] for i in np.flatnonzero(model.free & instrument)),
    )


def _joints(still: Sequence[int]) -> str:
    """``"joint 4"`` or ``"joints 1, 2 and 3"``."""
    return f"joint{'s' if len(still) > 1 else ''} {listing([str(j) for j in still])}"


def _names(names: Sequence[str]) -> str:
    """The first :data:`SHOWN` names, and how many more."""
    shown = ", ".join(names[:SHOWN])
    return shown + (f" and {len(names) - SHOWN} more" if len(names) > SHOWN else "")


def refuse_registration_only(found: Coverage, rows: int, noun: str = "rows") -> None:
    """Raise NotIdentifiableError when the rows identify nothing of the arm beyond the
    instrument's pose (identical poses) though a plan moving every joint would."""
    if found.arm_seen or not found.arm_needed:
        return
    why = (
        f"{_joints(found.still)} never move{'s' if len(found.still) == 1 else ''} in them"
        if found.still
        else "the poses do not move the joints enough"
    )
    raise NotIdentifiableError(
        f"{rows} {noun} identify only where the instrument and the targets are "
        f"({_names(found.instrument)}), nothing of the arm: {why}; measure poses that "
        "move every joint"
    )


def plan_degenerate_warning(
    found: Coverage,
    subject: str = "the measurements",
    *,
    holds: str = "the calibration, its std and every error it predicts hold",
    like: str = "these",
) -> ArmcalWarning | None:
    """``plan-degenerate`` when ``subject`` (plural: the rows, "the plan's poses") leaves
    parameters of the arm's own set held, or None.

    ``holds`` says which figures, with their verb, hold only at poses like ``like``
    (evaluate's predicted position error; validate's predicted error).
    """
    if not found.lost:
        return None
    count = len(found.lost)
    if found.still:
        one = len(found.still) == 1
        readings = "its reading takes" if one else "their readings take"
        cause = f"{subject} never move {_joints(found.still)} ({readings} one value), so they"
    else:
        cause = f"{subject} do not move the joints enough, so they"
    held = "it is" if count == 1 else "they are"
    return ArmcalWarning(
        "plan-degenerate",
        f"{cause} cannot identify {count} parameter{'' if count == 1 else 's'} that poses "
        f"moving every joint identify: {_names(found.lost)}; {held} held at nominal, so "
        f"{holds} only at poses like {like}, not over the workspace; measure poses that move "
        "every joint",
    )
