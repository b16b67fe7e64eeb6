"""Which of a spatial arm's parameters the measurements identify, chosen by a fixed rule.

A spatial arm's parameters (:mod:`~armcal.models.spatial.kinematics`) are
over-complete: an arm with ``R`` revolute and ``P`` prismatic joints measured at
``k`` point targets by an instrument whose pose is unknown identifies
``4R + 2P + 3k`` of them (Everett, Driels and Mooring's count ``4R + 2P + 6``
for a full pose, less the tool's orientation a point cannot see, plus 3 for
every further point); measured in full pose by a 6-DoF instrument,
``4R + 2P + 6k``.  :func:`select` keeps a set of that size:

* **deterministically** -- the columns of the scaled, whitened Jacobian are
  taken in a fixed priority order (:func:`priority`) and a column is kept when
  its part outside the span of those kept before is more than
  :data:`SELECT_RTOL` of its length.  Exact dependencies leave ``1e-13`` or
  less (a calibrated arm's small misalignments ``1e-3`` or less), real
  effects far more, so the set is the same on every machine, BLAS and row
  order, and for the nominal and the calibrated arm;
* **explained** -- every column left out is named with the kept parameters it
  merges into, and the reason where the geometry gives one ("joints 2 and 3
  are parallel"): :class:`~armcal.models.interface.Held` records, which
  :mod:`~armcal.models.wording` puts in words.

The priority: the base pose, the targets, every joint's zero (what a
controller takes), then the joints' placement errors from the tip down, each
joint's in the order ``x, y, rx, ry, z, rz``: a ``z`` error (along the axis)
is the one that moves along parallel axes into the next joint's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...numerics import scaled_svd
from ..interface import Held
from .chain import SerialChain
from .kinematics import SpatialLayout

__all__ = [
    "SELECT_RTOL",
    "Selection",
    "column_space",
    "parallel_runs",
    "priority",
    "select",
    "select_effect",
    "select_from_rows",
]

#: A column whose part outside the span of the columns kept before it is at most
#: this fraction of its length merges into them.  Structural dependencies of the
#: nominal geometry leave round-off (``1e-13`` and below on these well-scaled
#: columns); on a calibrated arm (an exported robot file) the same dependencies
#: are broken only by its small misalignments, ``1e-4`` to ``1e-3`` for errors of
#: a few hundredths of a degree, and a parameter seen that faintly could not be
#: estimated anyway (its std would be a hundred times or more another's).  Real
#: independent effects of a plan that moves every joint leave ``5e-2`` and more.
#: So the set does not change when the nominal model becomes the calibrated one.
SELECT_RTOL = 1e-2

#: A column this much shorter than the longest (in mm and rad) has no effect at all.
_ZERO_RTOL = 1e-12

#: Within a joint, the placement errors in order of priority (names' suffixes).
_WITHIN_JOINT = ("x", "y", "rx", "ry", "z", "rz")


@dataclass(frozen=True)
class Selection:
    """The identifiable set chosen, and why the others are left out.

    Attributes
    ----------
    kept : ndarray of bool, shape (p,)
        The parameters identified.
    merges : tuple of Held
        One record per group of parameters left out: what they merge into and why.
    still : tuple of int
        1-based joints that do not move in the measurements.
    """

    kept: np.ndarray
    merges: tuple[Held, ...]
    still: tuple[int, ...] = ()


def priority(layout: SpatialLayout) -> np.ndarray:
    """The order ``(p,)`` in which :func:`select` considers the parameters (module notes)."""
    names = layout.names
    index = {name: i for i, name in enumerate(names)}
    order = list(range(6))
    order += list(range(layout.target_start, layout.n_params))
    order += list(range(layout.zero_start, layout.target_start))
    for k in reversed(range(layout.n_joints)):
        order += [index[f"j{k + 1}.{c}"] for c in _WITHIN_JOINT if f"j{k + 1}.{c}" in index]
    return np.array(order)


def parallel_runs(chain: SerialChain, tol: float = 1e-9) -> list[tuple[int, int]]:
    """Runs ``(first, last)`` (0-based) of consecutive joints with parallel axes."""
    runs: list[tuple[int, int]] = []
    start = 0
    for k in range(1, chain.n_joints + 1):
        parallel = k < chain.n_joints and abs(abs(chain.origins[k, 2, 2]) - 1.0) < tol
        if not parallel:
            if k - 1 > start:
                runs.append((start, k - 1))
            start = k
    return runs


def _reason(
    dropped: str, partners: Sequence[str], layout: SpatialLayout, chain: SerialChain
) -> tuple[str, tuple[int, ...]]:
    """Why ``dropped`` merges into ``partners``, where the geometry says: a code of
    :data:`~armcal.models.wording.HELD_REASONS` and the 1-based joints it is about (an
    empty code where the geometry gives no reason)."""
    last = layout.n_joints
    into_base = all(p.startswith("base.") for p in partners)
    into_targets = all(p.split(".")[0] in layout.targets for p in partners)
    slides = [kind == "P" for kind in chain.kinds]  # a slide moves along its axis, not about
    if dropped == "dq1" and into_base:
        return ("base-slide" if slides[0] else "base-turn"), (1,)
    if dropped.startswith("j1.") and into_base:
        return "before-motion", (1,)
    if dropped == f"dq{last}" and into_targets:
        return ("tip-zero-slides" if slides[last - 1] else "tip-zero-turns"), (last,)
    if dropped == f"j{last}.z" and into_targets:
        return "tip-shift", (last,)
    if not dropped.startswith("j"):
        return "", ()
    k = int(dropped[1:].split(".")[0]) - 1
    component = dropped.split(".")[1]
    if component == "z":
        for first, end in parallel_runs(chain):
            if first <= k <= end:
                return "parallel", (first + 1, end + 1)
        return ("slide-shift" if slides[k] else "axis-shift"), (k + 1,)
    # An error about or along the previous joint's axis is that joint's zero, or passes it.
    direction = chain.origins[k, :3, :3] @ np.eye(3)["xyz".index(component[-1])]
    if k > 0 and abs(abs(direction[2]) - 1.0) < 1e-9:
        turn = component.startswith("r")
        if slides[k - 1]:  # a slide's zero shifts along its axis; a turn about it passes it
            return ("turn-past-slide" if turn else "shift-as-slide"), (k,)
        return ("turn-as-zero" if turn else "shift-past-turn"), (k,)
    return "", ()


def select(
    layout: SpatialLayout,
    chain: SerialChain,
    columns: np.ndarray,
    *,
    still: Sequence[int] = (),
    held: Sequence[str] = (),
    first: np.ndarray | None = None,
    first_names: Sequence[str] = (),
) -> Selection:
    """The identifiable set of a spatial arm from the scaled Jacobian's column space.

    Parameters
    ----------
    layout : SpatialLayout
    chain : SerialChain
    columns : ndarray, shape (r, p)
        A matrix with the column space of the whitened Jacobian (its triangular
        factor, or ``S V^T`` of its SVD), any column scaling.
    still : sequence of int
        0-based joints that do not move in the measurements (named in the report).
    held : sequence of str
        Parameters the user holds (``--fix``): never kept, never explained.
    first : ndarray, shape (r, t), optional
        Columns of another model's parameters, ``first_names``, that come before the
        arm's and are all kept (an instrument's, :mod:`~armcal.models.instrumented`): an
        arm's column is then judged by its part outside their span and the kept ones',
        against its own length.

    Returns
    -------
    Selection
    """
    names = layout.names
    norms = np.linalg.norm(columns, axis=0)
    scale = np.max(norms) if norms.size else 0.0
    basis = np.zeros((columns.shape[0], 0))
    extra = np.zeros((columns.shape[0], 0)) if first is None else np.asarray(first, dtype=float)
    if extra.shape[1]:
        basis = np.linalg.qr(extra)[0]
    kept = np.zeros(layout.n_params, dtype=bool)
    dropped: list[int] = []
    for i in priority(layout):
        if names[i] in held:
            continue
        col = columns[:, i]
        if norms[i] <= _ZERO_RTOL * scale:  # no effect at all (a joint that does not move)
            dropped.append(i)
            continue
        rest = col - basis @ (basis.T @ col)
        rest = rest - basis @ (basis.T @ rest)  # twice is enough (Kahan, Parlett)
        if np.linalg.norm(rest) <= SELECT_RTOL * norms[i]:
            dropped.append(i)
            continue
        basis = np.column_stack([basis, rest / np.linalg.norm(rest)])
        kept[i] = True
    merges = _explain(layout, chain, columns, kept, dropped, still, extra, tuple(first_names))
    return Selection(kept, merges, tuple(k + 1 for k in still))


def _explain(
    layout: SpatialLayout,
    chain: SerialChain,
    columns: np.ndarray,
    kept: np.ndarray,
    dropped: Sequence[int],
    still: Sequence[int],
    extra: np.ndarray,
    extra_names: tuple[str, ...],
) -> tuple[Held, ...]:
    """The parameters left out, grouped by what they merge into (the kept ones and the
    ``extra`` columns, named ``extra_names``) and why."""
    names = layout.names
    p = layout.n_params
    keep = np.concatenate([np.flatnonzero(kept), p + np.arange(extra.shape[1])])
    every = np.column_stack([columns, extra])
    unit = every / np.maximum(np.linalg.norm(every, axis=0), 1e-300)
    partner_names = (*names, *extra_names)
    groups: dict[tuple[tuple[str, ...], str, tuple[int, ...]], list[str]] = {}
    for i in dropped:
        joint = layout.joint_of(i)
        if joint is not None and joint in still:
            groups.setdefault(((), "still", (joint + 1,)), []).append(names[i])
            continue
        if not np.any(unit[:, i]):
            groups.setdefault(((), "no-effect", ()), []).append(names[i])
            continue
        coef = np.linalg.lstsq(unit[:, keep], unit[:, i], rcond=None)[0]
        big = np.abs(coef) >= 0.05 * np.max(np.abs(coef))
        partners = tuple(partner_names[j] for j in keep[big])
        reason, joints = _reason(names[i], partners, layout, chain)
        groups.setdefault((_grouped(partners, layout), reason, joints), []).append(names[i])
    return tuple(
        Held(tuple(members), into, reason, joints, layout.targets, layout.oriented)
        for (into, reason, joints), members in groups.items()
    )


def _grouped(partners: Sequence[str], layout: SpatialLayout) -> tuple[str, ...]:
    """``partners`` with one name for each group its words name together (the base's
    rotation, position or pose, every target's): parameters that merge into the same
    groups share a sentence."""
    base = [n for n in partners if n.startswith("base.")]
    turns = {n[-2] == "r" for n in base}
    out = (
        []
        if not base
        else ["base.rx"]
        if turns == {True}
        else ["base.x"]
        if turns == {False}
        else ["base.x", "base.rx"]
    )
    targets = sorted({n.split(".")[0] for n in partners if n.split(".")[0] in layout.targets})
    out += [f"{t}.x" for t in targets]
    out += [n for n in partners if not n.startswith("base.") and n.split(".")[0] not in targets]
    return tuple(out)


def column_space(rows: np.ndarray) -> np.ndarray:
    """A ``p x p`` matrix with the column space (and column norms) of ``rows`` ``(r, p)``:
    ``S V^T diag(c)`` of the SVD of the scaled rows, for :func:`select` at any ``r``."""
    svd = scaled_svd(rows)
    return svd.singular_values[:, None] * svd.vt * svd.column_norms


def select_from_rows(
    layout: SpatialLayout,
    chain: SerialChain,
    rows: np.ndarray,
    joints: np.ndarray,
    held: Sequence[str] = (),
    first_names: Sequence[str] = (),
) -> tuple[tuple[str, ...], tuple[Held, ...]]:
    """:func:`select` from the whitened Jacobian's ``rows`` ``(..., p + t)`` at joint
    values ``joints`` ``(..., n)`` (the joint map applied): the parameters it holds beyond
    ``held``, and why (:class:`~armcal.models.interface.Held`).  The last ``t`` columns
    are another model's parameters, ``first_names``, kept before the arm's (``first``)."""
    p = layout.n_params
    columns = column_space(rows.reshape(-1, p + len(first_names)))
    still = [j for j in range(layout.n_joints) if np.ptp(joints[..., j]) <= 1e-9]
    chosen = select(
        layout,
        chain,
        columns[:, :p],
        still=still,
        held=held,
        first=columns[:, p:],
        first_names=first_names,
    )
    left = zip(layout.names, chosen.kept, strict=True)
    return tuple(n for n, kept in left if not kept and n not in held), chosen.merges


def select_effect(
    columns: np.ndarray, kept_names: Sequence[str], names: Sequence[str], joints: np.ndarray
) -> tuple[tuple[str, ...], tuple[Held, ...]]:
    """An effect's parameters to hold and why (joint compliance of a spatial arm), by the
    rule of :func:`select`: from ``columns`` ``(r, g + P)``, the ``g`` columns the arm
    keeps (``kept_names``) then the effect's ``P`` (``names``, each twisting
    ``joints[i]``, 0-based), a column whose part outside the span of those kept before
    it is at most :data:`SELECT_RTOL` of its length is held, named with what it merges
    into; one of no effect at all "cannot be seen"."""
    g = len(kept_names)
    norms = np.linalg.norm(columns, axis=0)
    top = float(np.max(norms[g:], initial=0.0))
    basis, _ = np.linalg.qr(columns[:, :g])
    kept: list[int] = []
    groups: dict[tuple[tuple[str, ...], str, tuple[int, ...]], list[str]] = {}
    everyone = [*kept_names, *names]
    for i in range(len(names)):
        col = columns[:, g + i]
        if norms[g + i] <= _ZERO_RTOL * max(top, 1e-300):
            groups.setdefault(((), "no-torque", (int(joints[i]) + 1,)), []).append(names[i])
            continue
        rest = col - basis @ (basis.T @ col)
        rest = rest - basis @ (basis.T @ rest)  # twice is enough (Kahan, Parlett)
        if np.linalg.norm(rest) > SELECT_RTOL * norms[g + i]:
            basis = np.column_stack([basis, rest / np.linalg.norm(rest)])
            kept.append(i)
            continue
        keep = np.concatenate([np.arange(g), g + np.array(kept, dtype=int)])
        unit = columns / np.maximum(norms, 1e-300)
        coef = np.linalg.lstsq(unit[:, keep], unit[:, g + i], rcond=None)[0]
        big = np.abs(coef) >= 0.05 * np.max(np.abs(coef))
        partners = tuple(everyone[k] for k in keep[big])
        zero = any(p.startswith("dq") for p in partners)
        groups.setdefault((partners, "constant-torque" if zero else "", ()), []).append(names[i])
    held = tuple(n for members in groups.values() for n in members)
    reasons = tuple(
        Held(tuple(members), into, reason, joints, effect=True)
        for (into, reason, joints), members in groups.items()
    )
    return held, reasons
