"""An acceptance test in the spirit of ISO 9283: pose accuracy and repeatability.

ISO 9283:1998 (*Manipulating industrial robots -- Performance criteria and
related test methods*) measures one commanded pose ``n`` times (30 cycles,
clause 6.9) and reports, clause 7.2:

* **pose accuracy** (7.2.1): the distance from the command position to the
  barycentre of the attained positions,
  ``AP_P = sqrt((xbar - x_c)^2 + (ybar - y_c)^2 + (zbar - z_c)^2)``, with its
  components ``AP_x = xbar - x_c`` (and so on);
* **pose repeatability** (7.2.2): the radius of the sphere about the barycentre
  that holds the attained positions, ``RP_l = lbar + 3 S_l`` with
  ``l_j = |x_j - xbar|``, ``lbar`` their mean and
  ``S_l = sqrt(sum (l_j - lbar)^2 / (n - 1))``;
* with a 6-DoF instrument, the orientation's: ``AP_a = abar - a_c`` and
  ``RP_a = +-3 S_a`` for the turns about x, y and z (``a, b, c``).

A robot's command position lives in its controller's model; an instrument
measures in its own frame.  Here the command position is where a model puts the
commanded joints, in the instrument's frame with the calibration's instrument
pose (registered once, as :func:`armcal.validation.validate` does): **before**
calibration the nominal model, **after** it the calibrated one -- what a
program compensated with the calibration would reach.  The attained positions
are the measurements, so ``RP`` does not depend on any model.  Every cycle of a
pose must repeat the same joint values (:data:`SAME_COMMAND`); then
``AP`` is the norm of the mean error of its rows.

The result is per pose and per target (a target's point is one measuring
point); the test's figures are its worst pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .errors import ArmcalError, ArmcalWarning
from .models.spatial.registration import best_rotation

if TYPE_CHECKING:
    from .models import Conditions, FitModel

__all__ = [
    "ISO_CYCLES",
    "SAME_COMMAND",
    "PoseCharacteristics",
    "pose_characteristics",
    "pose_characteristics_warnings",
    "robot_turn",
]

#: Cycles per pose that ISO 9283 prescribes for pose accuracy and repeatability (clause 6.9).
ISO_CYCLES = 30

#: The largest spread of a pose's joint values over its cycles (rad, or mm for a prismatic
#: joint, as the readings are kept): above it the rows are not one commanded pose.
SAME_COMMAND = 1e-8


@dataclass(frozen=True, eq=False)
class PoseCharacteristics:
    """Pose accuracy and repeatability of every measured pose (ISO 9283, 7.2).

    Attributes
    ----------
    poses : tuple of str
        The ``pose`` label of each group of cycles.
    targets : tuple of str or None
        Each group's target, for an arm with several.
    cycles : ndarray of int, shape (k,)
        How many times each pose was measured.
    accuracy_before : ndarray, shape (k, d)
        ``AP_x, AP_y, AP_z`` against the nominal model, mm (mean attained minus command).
    accuracy_after : ndarray, shape (k, d)
        The same against the calibrated model, mm.
    repeatability_mm : ndarray, shape (k,)
        ``RP_l = lbar + 3 S_l``, mm.
    barycentres : ndarray, shape (k, d)
        The mean attained positions, mm (instrument frame).
    orientation_before, orientation_after : ndarray, shape (k, 3), or None
        For a 6-DoF instrument: ``AP_a, AP_b, AP_c`` (rad), the mean turn from the
        command orientation to the attained one, about the instrument's x, y and z axes
        (the small-angle components of the turns, which the standard's angles ``a, b,
        c`` are to first order).
    orientation_repeatability : ndarray, shape (k, 3), or None
        ``RP_a, RP_b, RP_c = 3 S_a`` (rad, a +- band): three sample standard deviations
        of the attained orientation's components over the cycles.
    """

    poses: tuple[str, ...]
    targets: tuple[str, ...] | None
    cycles: np.ndarray
    accuracy_before: np.ndarray
    accuracy_after: np.ndarray
    repeatability_mm: np.ndarray
    barycentres: np.ndarray
    orientation_before: np.ndarray | None = None
    orientation_after: np.ndarray | None = None
    orientation_repeatability: np.ndarray | None = None
    robot_turn: np.ndarray | None = None

    @property
    def accuracy_after_robot(self) -> np.ndarray:
        """``(k, d)``: :attr:`accuracy_after` in the robot's base frame (``R^T AP`` with
        :attr:`robot_turn` ``R``, the instrument's turn from the robot's frame; as measured
        where it is unknown)."""
        if self.robot_turn is None:
            return self.accuracy_after
        return self.accuracy_after @ self.robot_turn

    @property
    def names(self) -> tuple[str, ...]:
        """Every pose's name: its label, ``pose/target`` with several targets."""
        if self.targets is None:
            return self.poses
        return tuple(f"{p}/{t}" for p, t in zip(self.poses, self.targets, strict=True))

    @property
    def accuracy_before_mm(self) -> np.ndarray:
        """``AP_P`` against the nominal model ``(k,)``, mm."""
        return np.linalg.norm(self.accuracy_before, axis=-1)

    @property
    def accuracy_after_mm(self) -> np.ndarray:
        """``AP_P`` against the calibrated model ``(k,)``, mm."""
        return np.linalg.norm(self.accuracy_after, axis=-1)

    def summary(self) -> dict[str, float | int]:
        """The test's figures: the worst pose's ``AP_P`` before and after and ``RP_l`` (mm),
        the number of poses and the fewest cycles of any pose; for a 6-DoF instrument the
        largest ``|AP_a|, |AP_b|, |AP_c|`` before and after and ``RP_a..c`` (deg)."""
        out: dict[str, float | int] = {
            "poses": len(self.poses),
            "fewest_cycles": int(self.cycles.min()),
            "ap_before_mm": float(self.accuracy_before_mm.max()),
            "ap_after_mm": float(self.accuracy_after_mm.max()),
            "rp_mm": float(self.repeatability_mm.max()),
        }
        turns = (self.orientation_before, self.orientation_after, self.orientation_repeatability)
        if all(t is not None for t in turns):
            for key, values in zip(("ap_before", "ap_after", "rp"), turns, strict=True):
                assert values is not None
                out[f"{key}_orientation_deg"] = float(np.degrees(np.max(np.abs(values))))
        return out


def pose_characteristics(
    q: np.ndarray,
    attained: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
    poses: tuple[str, ...],
    targets: tuple[str, ...] | None = None,
    rows: tuple[int, ...] = (),
    turns: tuple[np.ndarray, np.ndarray] | None = None,
) -> PoseCharacteristics:
    """ISO 9283 pose accuracy and repeatability from repeated measurements.

    Parameters
    ----------
    q : ndarray, shape (m, n)
        Every row's commanded joint values (rad; mm for a prismatic joint).
    attained : ndarray, shape (m, d)
        The measured positions, mm.
    before, after : ndarray, shape (m, d)
        Measured minus the nominal and the calibrated model's position of the
        row's command, mm (:class:`armcal.validation.Validation`).
    poses : tuple of str
        Every row's ``pose`` label; rows with the same label (and target) are the
        cycles of one commanded pose, in the order their labels first appear.
    targets : tuple of str, optional
        Every row's target.
    rows : tuple of int, optional
        Every row's 1-based data row in its file, for messages.
    turns : pair of ndarray, shape (m, 3), optional
        A 6-DoF instrument's turns from the nominal and the calibrated model's
        orientation to the measured one (rotation vectors, rad), as
        :class:`armcal.validation.Turns` holds them.

    Raises
    ------
    ArmcalError
        If a pose has a single cycle, or its cycles' joint values differ.

    Examples
    --------
    Three cycles of one pose, commanded at the origin (by hand: the barycentre
    is (1, 0, 0), so ``AP = 1``; the distances to it are 1, 1 and 0, so
    ``lbar = 2/3``, ``S_l = sqrt(1/3)`` and ``RP = 2/3 + sqrt(3)``):

    >>> x = np.array([[0.0, 0, 0], [2.0, 0, 0], [1.0, 0, 0]])
    >>> found = pose_characteristics(np.zeros((3, 1)), x, x, x, ("P1",) * 3)
    >>> float(found.accuracy_before_mm[0])
    1.0
    >>> bool(np.isclose(found.repeatability_mm[0], 2 / 3 + np.sqrt(3), rtol=1e-15))
    True
    """
    q = np.asarray(q, dtype=float)
    keys = list(zip(poses, targets if targets is not None else [""] * len(poses), strict=True))
    number = {key: g for g, key in enumerate(dict.fromkeys(keys))}  # first appearance
    order = list(number)
    index = np.array([number[key] for key in keys], dtype=int)
    k = len(order)
    cycles = np.bincount(index, minlength=k)
    first = np.unique(index, return_index=True)[1]  # the first row of every group

    def where(group: int) -> str:
        row = f"row {rows[first[group]]}, " if rows else ""
        return f"{row}column 'pose': pose {order[group][0]}"

    if cycles.max() < 2:
        raise ArmcalError(
            "no pose is repeated: ISO 9283 measures every commanded pose in several cycles "
            f"({ISO_CYCLES}); add a column 'pose' whose label repeats for the cycles of a pose"
        )
    single = np.flatnonzero(cycles < 2)
    if single.size:
        raise ArmcalError(
            f"{where(int(single[0]))} was measured once: ISO 9283 repeats every pose in "
            f"several cycles ({ISO_CYCLES}); give the rows of one commanded pose the same label"
        )
    spread = np.zeros(k)
    np.maximum.at(spread, index, np.max(np.abs(q - q[first][index]), axis=-1))
    moved = np.flatnonzero(spread > SAME_COMMAND)
    if moved.size:
        g = int(moved[0])
        raise ArmcalError(
            f"{where(g)} has cycles with different joint values (up to {spread[g]:.3g} rad, "
            "or mm for a prismatic joint, apart): ISO 9283 repeats one commanded pose; "
            "give its commanded joint values in every cycle, or different pose labels"
        )

    def mean(values: np.ndarray) -> np.ndarray:
        sums = np.zeros((k, values.shape[-1]))
        np.add.at(sums, index, values)
        return sums / cycles[:, None]

    def deviation(values: np.ndarray) -> np.ndarray:  # sample std over every pose's cycles
        centred = values - mean(values)[index]
        sums = np.zeros((k, values.shape[-1]))
        np.add.at(sums, index, centred**2)
        return np.sqrt(sums / (cycles - 1)[:, None])

    centre = mean(attained)
    distance = np.linalg.norm(attained - centre[index], axis=-1)
    mean_distance = np.bincount(index, distance, minlength=k) / cycles
    spread_l = deviation(distance[:, None])[:, 0]
    turned = None
    if turns is not None:  # the command is one orientation: the turns' spread is the pose's
        turned = (mean(turns[0]), mean(turns[1]), 3.0 * deviation(turns[1]))
    return PoseCharacteristics(
        poses=tuple(key[0] for key in order),
        targets=None if targets is None else tuple(key[1] for key in order),
        cycles=cycles,
        accuracy_before=mean(before),
        accuracy_after=mean(after),
        repeatability_mm=mean_distance + 3.0 * spread_l,
        barycentres=centre,
        orientation_before=None if turned is None else turned[0],
        orientation_after=None if turned is None else turned[1],
        orientation_repeatability=None if turned is None else turned[2],
    )


def robot_turn(model: FitModel, conditions: Conditions, params: np.ndarray) -> np.ndarray:
    """The rotation ``R`` ``(d, d)`` from the robot's base frame to the instrument's, for
    any family: the model's points at ``params`` and with the instrument's pose taken out
    (:meth:`~armcal.models.interface.FitModel.in_robot_frame`) differ by one rigid motion
    (:func:`~armcal.models.spatial.registration.best_rotation` finds its turn)."""
    robot_model, robot_params = model.in_robot_frame(params)
    dim = model.position_dim
    seen = np.asarray(model.positions(conditions, params))[..., :dim].reshape(-1, dim)
    own = np.asarray(robot_model.positions(conditions, robot_params))[..., :dim].reshape(-1, dim)
    return best_rotation(own, seen)


def pose_characteristics_warnings(found: PoseCharacteristics) -> list[ArmcalWarning]:
    """``iso9283-cycles`` when a pose has fewer cycles than the standard's 30: its ``RP``
    rests on ``S_l`` from ``n - 1`` degrees of freedom (relative standard error about
    ``1 / sqrt(2 (n - 1))``)."""
    fewest = int(found.cycles.min())
    if fewest >= ISO_CYCLES:
        return []
    error = 1.0 / np.sqrt(2.0 * (fewest - 1))
    return [
        ArmcalWarning(
            "iso9283-cycles",
            f"a pose has only {fewest} cycles where ISO 9283 asks for {ISO_CYCLES}: its "
            f"repeatability's S_l is uncertain by about {100 * error:.0f} %; measure "
            f"{ISO_CYCLES} cycles of every pose for an acceptance test",
        )
    ]
