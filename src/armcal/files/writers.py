"""The CSV files armcal writes: plans, measurements and programs, in the layouts
:mod:`~armcal.files.tables` reads (:mod:`armcal.formats` documents them).

A joint's column says its unit (:mod:`~armcal.files.joints`): ``q{j}_deg`` for a
revolute joint, ``q{j}_mm`` for a prismatic one.  Every writer takes the arm's
``kinds`` (``"R"``/``"P"`` per joint, ``arm.joint_kinds``); without them every
joint is revolute.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .csv_text import csv_text, degrees, floats
from .joints import joint_names, joint_values

__all__ = [
    "ORIENTATION_COLUMNS",
    "format_measurements_csv",
    "format_plan_csv",
    "format_program_csv",
]

#: The columns of a 6-DoF instrument's orientation: a rotation vector in degrees.
ORIENTATION_COLUMNS = ("rx_deg", "ry_deg", "rz_deg")


def format_plan_csv(
    q: np.ndarray,
    payload_kg: np.ndarray | None = None,
    targets: Sequence[str] | None = None,
    *,
    kinds: Sequence[str] | None = None,
) -> str:
    """Plan (or program) CSV text for joint values ``q`` ``(m, n)`` (rad; mm for a joint
    that ``kinds`` says is prismatic), and every pose's payload or target where given."""
    head = joint_names(kinds or q.shape[1]) + (["payload_kg"] if payload_kg is not None else [])
    columns: list = [joint_values(q, kinds)]
    if payload_kg is not None:
        columns.append(floats(payload_kg))
    if targets is not None:
        head.append("target")
        columns.append([str(target) for target in targets])
    return csv_text(head, columns)


def format_measurements_csv(
    q: np.ndarray,
    xy: np.ndarray,
    labels: Sequence[str] | None = None,
    targets: Sequence[str] | None = None,
    payload_kg: np.ndarray | None = None,
    *,
    kinds: Sequence[str] | None = None,
    instrument: Any = None,
    feature: np.ndarray | None = None,
) -> str:
    """Measurements CSV text; positions are written with full round-trip precision.

    ``q`` ``(m, n)`` are the joint values (rad; mm for a joint that ``kinds`` says is
    prismatic: :func:`joint_names`).

    ``xy`` of shape ``(m, 3)`` writes 3-D points (``z_mm``), of shape ``(m, 6)`` also a
    6-DoF instrument's orientation (a rotation vector in rad, written in degrees:
    ``rx_deg, ry_deg, rz_deg``); ``targets`` adds the ``target`` column,
    ``payload_kg`` the payload of every row.

    A plane, point or distance ``instrument`` (:mod:`armcal.instruments`) writes its own
    columns instead: ``xy`` its readings (``distance_mm``; none for a touch, which reads
    0) and every row's feature (its index ``feature``) in its label column.
    """
    xy = np.asarray(xy, dtype=float)
    if instrument is not None:
        return _readings_csv(q, xy, labels, targets, kinds, instrument, feature)
    head = ["pose"] if labels is not None else []
    head += joint_names(kinds or q.shape[1]) + ["x_mm", "y_mm", "z_mm"][: xy.shape[1]]
    head += list(ORIENTATION_COLUMNS) if xy.shape[1] == 6 else []
    head += ["target"] if targets is not None else []
    head += ["payload_kg"] if payload_kg is not None else []
    if xy.shape[0] != q.shape[0]:
        raise ValueError(f"q has {q.shape[0]} rows but xy has {xy.shape[0]}")
    columns: list = [[str(label) for label in labels]] if labels is not None else []
    columns += [joint_values(q, kinds), floats(xy[:, :3])]
    columns += [degrees(xy[:, 3:])] if xy.shape[1] == 6 else []
    columns += [[str(target) for target in targets]] if targets is not None else []
    if payload_kg is not None:
        columns.append(floats(payload_kg))
    return csv_text(head, columns)


def _readings_csv(
    q: np.ndarray,
    readings: np.ndarray,
    labels: Sequence[str] | None,
    targets: Sequence[str] | None,
    kinds: Sequence[str] | None,
    instrument: Any,
    feature: np.ndarray | None,
) -> str:
    """The measurements of a plane, point or distance instrument (``readings`` columns);
    of partial coordinates, :func:`_partial_csv`."""
    if instrument.reads_every_feature and instrument.label_column is None:
        return _partial_csv(q, readings, labels, targets, kinds, instrument, feature)
    head = (["pose"] if labels is not None else []) + joint_names(kinds or q.shape[1])
    columns: list = [[str(label) for label in labels]] if labels is not None else []
    columns.append(joint_values(q, kinds))
    names = list(instrument.reading_columns)
    if names:
        head += names
        columns.append(floats(readings[:, : len(names)]))
    if instrument.label_column is not None:
        index = np.zeros(q.shape[0], dtype=int) if feature is None else feature
        head.append(instrument.label_column)
        columns.append([instrument.labels[k] for k in index])
    if targets is not None:
        head.append("target")
        columns.append([str(target) for target in targets])
    return csv_text(head, columns)


def _partial_csv(
    q: np.ndarray,
    readings: np.ndarray,
    labels: Sequence[str] | None,
    targets: Sequence[str] | None,
    kinds: Sequence[str] | None,
    instrument: Any,
    feature: np.ndarray | None,
) -> str:
    """Partial coordinates: the readings of one pose (consecutive rows of the same joints,
    label and target) on one line, a column per component, empty where it read none (a
    turn's in degrees)."""
    m = q.shape[0]
    index = np.zeros(m, dtype=int) if feature is None else np.asarray(feature)
    same = np.all(q[1:] == q[:-1], axis=1) & (index[1:] > index[:-1])
    for more in (labels, targets):
        if more is not None:
            same &= np.array([a == b for a, b in zip(more[1:], more[:-1], strict=True)], bool)
    line = np.concatenate([[0], np.cumsum(~same)]) if m else np.zeros(0, dtype=int)
    first = np.flatnonzero(np.concatenate([[True], ~same])) if m else np.zeros(0, dtype=int)
    names = list(instrument.reading_columns)
    cells = [[""] * first.size for _ in names]
    turn = np.array([name.endswith("_deg") for name in names], dtype=bool)  # radians inside
    values = np.asarray(readings, dtype=float).reshape(m, -1)[:, 0]
    shown = np.where(turn[index], np.degrees(values), values)
    for r in range(m):
        cells[index[r]][line[r]] = repr(float(shown[r]))
    head = (["pose"] if labels is not None else []) + joint_names(kinds or q.shape[1]) + names
    columns: list = [[str(labels[int(r)]) for r in first]] if labels is not None else []
    columns += [joint_values(q[first], kinds), *cells]
    if targets is not None:
        head.append("target")
        columns.append([str(targets[int(r)]) for r in first])
    return csv_text(head, columns)


def format_program_csv(
    q: np.ndarray,
    corrected: np.ndarray,
    labels: Sequence[str] | None = None,
    targets: Sequence[str] | None = None,
    *,
    kinds: Sequence[str] | None = None,
    payload_kg: np.ndarray | None = None,
    force_n: np.ndarray | None = None,
) -> str:
    """Program CSV text:
    ``[pose,]q1_deg..qn_deg[,payload_kg][,fx_N,fy_N][,target],corrected`` (1 or 0 per row);
    a prismatic joint's column is ``q{j}_mm`` (:func:`joint_names`).  The loads are the
    program's own (the corrections depend on them), written back as they were given."""
    head = (["pose"] if labels is not None else []) + joint_names(kinds or q.shape[1])
    head += ["payload_kg"] if payload_kg is not None else []
    head += ["fx_N", "fy_N"] if force_n is not None else []
    head += (["target"] if targets is not None else []) + ["corrected"]
    columns: list = [[str(label) for label in labels]] if labels is not None else []
    columns.append(joint_values(q, kinds))
    columns += [floats(payload_kg)] if payload_kg is not None else []
    columns += (
        [floats(np.asarray(force_n, dtype=float).reshape(-1, 2))] if force_n is not None else []
    )
    columns += [[str(target) for target in targets]] if targets is not None else []
    columns.append(["1" if c else "0" for c in np.asarray(corrected, dtype=bool).tolist()])
    return csv_text(head, columns)
