"""Export a calibrated arm: as a robot file every command accepts, or as URDF for ROS.

Both exports describe the arm in its own frame (:meth:`CalibratedArm.in_robot_frame
<armcal.models.calibrated.CalibratedArm.in_robot_frame>`): the base pose ``x0, y0, phi0``
places the arm in the instrument's frame during calibration, so it belongs to the
instrument, not to the robot, and is written only as a comment.

**Robot file** (:func:`robot_toml`).  The identified deviations are folded into
the nominal values (:func:`folded_arm`): link lengths ``l + dl``, joint zero
offsets ``joint_offsets_deg = o + dq`` in joint space, and with several targets
each target's own length and direction.  The file's nominal model *is* the
calibrated arm, so ``design``, ``evaluate`` and ``compensate`` use it directly,
and a later calibration against it finds what has changed since.

**URDF** (:func:`urdf`).  One revolute joint about ``z`` per arm joint, links
``link1 .. linkn`` with their frame's ``x`` axis along the link, and one fixed
frame per target (``target_<label>``, or ``tool0`` without targets) whose ``x``
axis points along the target's calibrated direction.  URDF offers two places for
a joint's zero offset:

* ``<calibration rising="...">`` holds the reference position of a homing
  switch (URDF specification, joint element).  No kinematics consumer applies it
  (robot_state_publisher, KDL, MoveIt ignore it).  ROS's ``robot_calibration``
  package writes its joint offsets there and expects the robot's *driver* to
  add them to the readings (and subtract them from commands); for drivers that
  do not, it suggests calibrating a rotation of the joint's origin about the
  joint axis instead.
* ``<origin rpy="0 0 yaw">`` is the fixed transform from the parent link to the
  joint frame, which every consumer applies.

Here every joint's zero offset is folded into its origin's yaw: a rotation
about the joint axis commutes with the joint's own rotation about that axis, so
``Rz(c) Rz(v) = Rz(c + v)`` and the joint value ``v`` stays the reading.  The
URDF then gives the calibrated kinematics with the controller's readings, no
driver support needed, and no ``<calibration>`` element is written (a driver
that read one would apply the offset twice).  The previous link's calibrated
length goes into the joint's ``<origin xyz>``.  URDF lengths are in metres.

**Joint values.**  A URDF joint turns its link relative to the previous one:
the joint values are the relative link angles ``r = D M q`` (``M`` the joint
map, ``D`` the differences of consecutive link angles).  When ``D M`` is
diagonal with entries ``+-1`` (joints counted one way or the other round) each
reversed joint gets ``<axis xyz="0 0 -1">`` and the URDF joint values *are* the
controller's readings ``q``.  Otherwise (coupled axes, a joint read relative to
the horizon) the URDF joint values are ``r = D M q``, not the readings
(:func:`urdf_joint_values`); the URDF says so in a comment, and its limits are
the range of ``r`` over the readings' limits.
"""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ._version import __version__
from .export_text import (
    deviations_text,
    noise_toml,
    num,
    nums,
    one_line,
    pack,
    quoteattr,
    toml_key,
    toml_string,
    xml_comment,
    xml_name,
)
from .models import (
    INSTRUMENT_PARAMS,
    STANDARD_GRAVITY,
    Annulus,
    Box,
    CalibratedArm,
    Elastostatic,
    PlanarArm,
    Target,
    standard_joint_map,
)
from .numerics import box_image

__all__ = [
    "folded_arm",
    "robot_toml",
    "urdf",
    "urdf_joint_matrix",
    "urdf_joint_values",
    "urdf_joints_are_readings",
]

#: Suffix of the exported arm's name.
CALIBRATED_SUFFIX = "-calibrated"

#: URDF lengths are in metres, armcal's in mm.
_MM_PER_M = 1000.0


def folded_arm(cal: CalibratedArm) -> PlanarArm:
    """The calibrated arm as a nominal arm: deviations folded into the nominal values.

    Parameters
    ----------
    cal : CalibratedArm
        The nominal arm and its identified deviations.

    Returns
    -------
    PlanarArm
        An arm whose nominal forward kinematics (no deviations) are those of
        ``cal.arm`` with its calibrated deviations in the robot's own frame.  Its
        name has ``-calibrated`` appended; joint limits, joint map, base offset,
        noise model and region are kept; it has no base rotation, and its fixed
        parameters are the calibration's minus the joint offset held only
        because of a base rotation.

    Notes
    -----
    With ``theta = M (q + o)`` the calibrated angle of link vector ``k`` is
    ``theta_a(k) + alpha_k + (A dq)_k`` (:attr:`PlanarArm.angle_map` ``A``) and
    its length ``L_k + dl_k``.  The folded arm has lengths ``L_k + dl_k``,
    offsets ``o' = o + (dq_1, .., dq_(n-1), dq_n@f)`` (``f`` the first target)
    and target directions ``alpha'_t``:

    * a shared link ``i < n`` turns with row ``i`` of ``A``, which is row ``i`` of
      ``M`` (whose last entry is 0 with several targets), so
      ``M_i (q + o') = M_i (q + o) + (A dq)_i``;
    * target ``t``'s row of ``A`` is ``(M[n, :n-1], M[n, n] e_t)``: the first
      target's is reproduced by ``o'_n`` as above, and every other by
      ``alpha'_t = alpha_t + M[n, n] (dq_n@t - dq_n@f)``.

    Without targets the last link is link ``n`` and ``o' = o + dq``.  A base
    rotation ``phi0`` turns every link vector alike; it is the instrument's and
    :meth:`~armcal.models.calibrated.CalibratedArm.in_robot_frame` drops it.

    Examples
    --------
    >>> arm = PlanarArm([200.0, 100.0])
    >>> params = np.array([0.5, -0.2, np.radians(1.0), 0.0])  # dl1, dl2 (mm), dq1, dq2 (rad)
    >>> cal = CalibratedArm(arm, params, np.zeros((4, 4)), 0.1)
    >>> folded = folded_arm(cal)
    >>> folded.name, folded.link_lengths.tolist(), np.degrees(folded.joint_offsets).tolist()
    ('arm-calibrated', [200.5, 99.8], [1.0, 0.0])
    """
    arm = cal.arm
    n, k = arm.n_joints, arm.n_links
    params = cal.robot_params()
    dl, dq = params[:k], params[k : 2 * k]
    lengths = arm.link_nominal + dl
    link_lengths = np.array(arm.link_lengths, dtype=float)
    link_lengths[: n - 1] = lengths[: n - 1]
    targets: tuple[Target, ...] = ()
    if arm.targets:
        # Joint n's offset is the first target's; the others differ in direction only.
        turn = arm.joint_map[n - 1, n - 1]
        targets = tuple(
            Target(
                t.label,
                float(lengths[n - 1 + i]),
                float(t.angle + turn * (dq[n - 1 + i] - dq[n - 1])),
            )
            for i, t in enumerate(arm.targets)
        )
    else:
        link_lengths[n - 1] = lengths[n - 1]
    offsets = arm.joint_offsets + dq[:n]
    structure = PlanarArm(
        link_lengths, base_offset=arm.base_offset, joint_map=arm.joint_map, targets=targets
    )
    fixed = [
        name
        for name in arm.fixed
        if name in structure.param_names and name not in _held_for_rotation(arm)
    ]
    return PlanarArm(
        link_lengths,
        arm.joint_limits,
        base_offset=arm.base_offset,
        name=arm.name + CALIBRATED_SUFFIX,
        noise=arm.noise,
        region=arm.region,
        fixed=fixed,
        joint_map=arm.joint_map,
        targets=targets,
        joint_offsets=offsets,
    )


def _held_for_rotation(arm: PlanarArm) -> tuple[str, ...]:
    """The joint offset :class:`PlanarArm` holds only because of its base rotation.

    It holds :attr:`~PlanarArm.rotation_partner` when no other fixed parameter
    lies on the rotation's direction; a partner fixed alongside another one on
    that direction was the user's choice and stays fixed.
    """
    if not arm.base_rotation:
        return ()
    names = arm.param_names
    on_direction = [
        name for name in arm.fixed if abs(arm.rotation_direction[names.index(name)]) > 1e-12
    ]
    return (arm.rotation_partner,) if on_direction == [arm.rotation_partner] else ()


# --------------------------------------------------------------------------- robot TOML


def _region_toml(region: Annulus | Box) -> str:
    if isinstance(region, Annulus):
        return (
            f'{{ kind = "annulus", center_mm = {nums(region.center)}, '
            f"r_min_mm = {num(region.r_min)}, r_max_mm = {num(region.r_max)} }}"
        )
    return f'{{ kind = "box", x_mm = {nums(region.x)}, y_mm = {nums(region.y)} }}'


def _base_pose_text(cal: CalibratedArm) -> str | None:
    """The base pose in the instrument frame, for a comment; None without one."""
    arm = cal.arm
    parts = []
    params = cal.arm_params
    for name in INSTRUMENT_PARAMS:
        if name in arm.param_names:
            i = arm.param_names.index(name)
            unit = arm.param_units[i]
            parts.append(f"{name} = {num(params[i] * arm.display_scale[i])} {unit}")
    return ", ".join(parts) if parts else None


def _elastostatic_toml(cal: CalibratedArm) -> tuple[list[str], tuple[str, ...]] | None:
    """The ``[elastostatic]`` lines of a calibration with joint compliance, gravity turned
    into the robot's frame, and the compliance terms the user held; None without one.

    The table is the loads model (gravity, masses, centres of mass, default payload),
    not the identified compliance: a calibration against the exported file fits the
    compliance anew with the same loads, as the calibration did.
    """
    model = cal.in_robot_frame()[0]
    if model.effect is None:  # a rigid arm: no loads model to write
        return None
    elastic: Elastostatic = model.elastic  # type: ignore[attr-defined]  # compliance's loads
    lines = []
    if elastic.gravity is not None:
        lines.append(f"gravity_xy = {nums(elastic.gravity / STANDARD_GRAVITY)}")
    if elastic.link_masses_kg is not None:
        lines.append(f"link_masses_kg = {nums(elastic.link_masses_kg)}")
    lines += [
        f"com_fraction = {nums(elastic.com_fraction)}",
        f"payload_kg = {num(elastic.payload_kg)}",
    ]
    return lines, elastic.terms.held(elastic.term_names(cal.arm))


def robot_toml(cal: CalibratedArm) -> str:
    """The calibrated arm as a robot TOML file that :func:`armcal.files.load_robot` accepts.

    Parameters
    ----------
    cal : CalibratedArm
        The nominal arm and its identified deviations (internal units).

    Returns
    -------
    str
        The file's text: the arm of :func:`folded_arm` (``name`` with
        ``-calibrated``, ``link_lengths_mm``, ``joint_limits_deg``,
        ``base_offset``, ``joint_map`` unless the default, ``joint_offsets_deg``,
        ``[measurement]`` noise and region, ``[identify] fixed``, ``[targets]``,
        and for a calibration with joint compliance its ``[elastostatic]`` loads
        with gravity in the robot's frame),
        every number with full round-trip precision.  Comments give the
        deviations folded in and the base pose in the instrument frame (not part
        of the robot).

    Notes
    -----
    The file's nominal forward kinematics equal the calibrated ones in the robot
    frame (the deviations with the base pose at 0), to round-off
    (the derivation is in :func:`folded_arm`).  With several targets the first
    target's last-joint offset becomes joint ``n``'s, and the others' differences
    move their ``angle_deg``.

    Examples
    --------
    >>> arm = PlanarArm([200.0, 100.0])
    >>> params = np.array([0.5, -0.2, np.radians(1.0), 0.0])  # dl1, dl2 (mm), dq1, dq2 (rad)
    >>> cal = CalibratedArm(arm, params, np.zeros((4, 4)), 0.1)
    >>> text = robot_toml(cal)
    >>> print("\\n".join(line for line in text.splitlines() if not line.startswith("#")))
    name = "arm-calibrated"
    link_lengths_mm = [200.5, 99.8]
    joint_limits_deg = [[-180.0, 180.0], [-180.0, 180.0]]
    base_offset = false
    joint_offsets_deg = [1.0, 0.0]
    """
    arm = cal.arm
    folded = folded_arm(cal)
    lines = [
        f"# {one_line(folded.name)}: robot file written by armcal {__version__} export from "
        f"the calibration of {one_line(arm.name)}.",
        "# The identified deviations are folded into the nominal values (robot frame):",
        *(f"#   {line}" for line in deviations_text(cal)),
        "# so this file's nominal model is the calibrated arm: a calibration against it",
        "# measures what has changed since.",
    ]
    base_pose = _base_pose_text(cal)
    if base_pose is not None:
        lines += [
            "# Base pose in the instrument frame during calibration (the instrument's, not",
            "# part of the robot):",
            *(f"#   {line}" for line in pack(base_pose.split(", "))),
        ]
    if arm.targets:
        lines.append(
            f"# Joint {arm.n_joints}'s offset is target {arm.targets[0].label}'s; the other "
            "targets' differ in angle_deg."
        )
    lines += [
        f"name = {toml_string(folded.name)}",
        f"link_lengths_mm = {nums(folded.link_lengths)}",
        "joint_limits_deg = [" + ", ".join(nums(pair) for pair in folded.joint_limits_deg) + "]",
        f"base_offset = {'true' if folded.base_offset else 'false'}",
    ]
    if not np.array_equal(folded.joint_map, standard_joint_map(folded.n_joints)):
        lines.append("joint_map = [" + ", ".join(nums(row) for row in folded.joint_map) + "]")
    lines.append(f"joint_offsets_deg = {nums(np.degrees(folded.joint_offsets))}")
    measurement = [] if folded.noise is None else noise_toml(folded.noise)
    if folded.region is not None:
        measurement.append(f"region = {_region_toml(folded.region)}")
    if measurement:
        lines += ["", "[measurement]", *measurement]
    elastic = _elastostatic_toml(cal)
    held = [*folded.fixed, *(() if elastic is None else elastic[1])]
    if held:
        fixed = ", ".join(toml_string(name) for name in held)
        lines += ["", "[identify]", f"fixed = [{fixed}]"]
    if elastic is not None:
        lines += ["", "[elastostatic]", *elastic[0]]
    if folded.targets:
        lines += ["", "[targets]"]
        lines += [
            f"{toml_key(t.label)} = {{ length_mm = {num(t.length)}, "
            f"angle_deg = {num(math.degrees(t.angle))} }}"
            for t in folded.targets
        ]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- URDF


def urdf_joint_matrix(arm: PlanarArm) -> np.ndarray:
    """``D M`` ``(n, n)``: the relative link angles ``r = D M q`` the URDF joints turn by.

    ``D`` takes differences of consecutive absolute link angles
    (``r_1 = theta_1``, ``r_i = theta_i - theta_(i-1)``) and ``M`` is the joint
    map.  The identity for the default joint map.

    Examples
    --------
    >>> urdf_joint_matrix(PlanarArm([2.0, 1.0], joint_map=[[1, 0], [0, 1]])).tolist()
    [[1.0, 0.0], [-1.0, 1.0]]
    """
    return np.diff(arm.joint_map, axis=0, prepend=0.0)


def urdf_joints_are_readings(arm: PlanarArm) -> bool:
    """Whether the URDF's joint values are the controller's readings ``q``.

    True when ``D M`` (:func:`urdf_joint_matrix`) is diagonal with entries
    ``+-1``: a reversed joint then turns about ``-z``.  Otherwise (coupled axes)
    the URDF joint values are :func:`urdf_joint_values`.

    Examples
    --------
    >>> urdf_joints_are_readings(PlanarArm([2.0, 1.0], joint_map=[[1, 0], [1, -1]]))
    True
    >>> urdf_joints_are_readings(PlanarArm([2.0, 1.0], joint_map=[[1, 0], [0, 1]]))
    False
    """
    relative = urdf_joint_matrix(arm)
    diagonal = np.diag(np.diag(relative))
    return bool(np.array_equal(relative, diagonal) and np.all(np.abs(np.diag(relative)) == 1))


def urdf_joint_values(arm: PlanarArm, q: ArrayLike) -> np.ndarray:
    """The URDF joint values ``(..., n)`` (rad) for the controller's readings ``q`` ``(..., n)``.

    ``q`` itself when :func:`urdf_joints_are_readings`, else the relative link
    angles ``D M q``: what a ROS driver of a coupled arm publishes as
    ``joint_states`` for the exported URDF.

    Examples
    --------
    >>> horizon = PlanarArm([2.0, 1.0], joint_map=[[1, 0], [0, 1]])  # q2 from the horizon
    >>> urdf_joint_values(horizon, [0.5, 0.75]).tolist()
    [0.5, 0.25]
    """
    q = np.asarray(q, dtype=float)
    if q.ndim < 1 or q.shape[-1] != arm.n_joints:
        raise ValueError(f"q must have shape (..., {arm.n_joints}) in rad, got {q.shape}")
    if urdf_joints_are_readings(arm):
        return q.copy()
    return q @ urdf_joint_matrix(arm).T


def _urdf_limits(arm: PlanarArm) -> np.ndarray:
    """``[lower, upper]`` ``(n, 2)`` of every URDF joint value, rad.

    The readings' limits when the values are the readings; else the range of
    each ``r_i = (D M q)_i`` over the box of the readings' limits.
    """
    if urdf_joints_are_readings(arm):
        return np.array(arm.joint_limits)
    return box_image(urdf_joint_matrix(arm), arm.joint_limits)


def _triple(x: float, y: float, z: float) -> str:
    return quoteattr(f"{num(x)} {num(y)} {num(z)}")


def urdf(cal: CalibratedArm) -> str:
    """The calibrated arm as a URDF (XML) in the robot's frame, for ROS.

    Parameters
    ----------
    cal : CalibratedArm
        The nominal arm and its identified deviations (internal units).

    Returns
    -------
    str
        A ``<robot>`` named like the arm with ``-calibrated``: ``base_link``;
        revolute joints ``joint1 .. jointn`` about ``z`` (``-z`` for a reversed
        joint) with the zero offsets in ``<origin rpy>`` and the calibrated
        lengths (m) in ``<origin xyz>``; empty links ``link1 .. linkn``; a fixed
        joint and frame per target (``target_<label>``, else ``tool0``) at the
        calibrated position with its ``x`` axis along the target's direction.
        Joint limits in rad; ``effort`` and ``velocity``, which URDF requires,
        are 0 placeholders (armcal knows no dynamics).  A comment gives the base
        pose in the instrument frame and the joint-value convention.

    Notes
    -----
    Composing ``Trans(origin xyz) Rz(origin yaw) Rz(s_i v_i)`` from
    ``base_link`` (``s_i`` the axis sign, ``v_i`` the joint value of
    :func:`urdf_joint_values`) places every target frame where
    the calibrated arm in its own frame puts the target, with the yaw of
    :func:`~armcal.models.planar.kinematics.tool_angles`.  The module docstring says why
    the offsets are in ``<origin>`` and not in ``<calibration>``.

    Examples
    --------
    >>> arm = PlanarArm([200.0, 100.0])
    >>> params = np.array([0.5, -0.2, np.radians(1.0), 0.0])  # dl1, dl2 (mm), dq1, dq2 (rad)
    >>> cal = CalibratedArm(arm, params, np.zeros((4, 4)), 0.1)
    >>> text = urdf(cal)
    >>> print("\\n".join(line for line in text.splitlines() if "<origin" in line))
        <origin xyz="0.0 0.0 0.0" rpy="0.0 0.0 0.017453292519943295"/>
        <origin xyz="0.2005 0.0 0.0" rpy="0.0 0.0 0.0"/>
        <origin xyz="0.0998 0.0 0.0" rpy="0.0 0.0 0.0"/>
    """
    arm = cal.arm
    folded = folded_arm(cal)
    n = folded.n_joints
    relative = urdf_joint_matrix(folded)
    readings = urdf_joints_are_readings(folded)
    signs = np.diag(relative) if readings else np.ones(n)
    yaw = relative @ folded.joint_offsets  # the zero offsets of the relative angles
    limits = _urdf_limits(folded)
    lengths_m = folded.link_lengths / _MM_PER_M

    header = [
        f"generated by armcal {__version__} export from the calibration of "
        f"{one_line(arm.name)}: the calibrated arm in the robot's frame (lengths in m, "
        "angles in rad).",
        "Each joint's zero offset is folded into its origin's yaw (a rotation about the "
        "joint axis commutes with the joint's own); no <calibration> element is written.",
    ]
    if readings:
        header.append("Joint values are the controller's readings q.")
    else:
        header.append(
            "Coupled axes: the joint values are the relative link angles r = D M q, NOT the "
            "controller's readings (M = joint_map "
            + json.dumps(folded.joint_map.tolist())
            + ", D the differences of consecutive link angles); convert before publishing "
            "joint_states. Limits are the range of r over the readings' limits."
        )
    base_pose = _base_pose_text(cal)
    if base_pose is not None:
        header.append(f"Base pose in the instrument frame during calibration: {base_pose}.")
    header.append(
        "effort and velocity limits are placeholders (0): armcal identifies geometry only."
    )
    lines = ['<?xml version="1.0"?>', "<!--"]
    for text in header:
        wrapped = textwrap.wrap(one_line(text), width=92, break_on_hyphens=False)
        lines += [f"  {xml_comment(line)}" for line in wrapped]
    robot = f"<robot name={quoteattr(xml_name(folded.name))}>"
    lines += ["-->", robot, '  <link name="base_link"/>']
    parent = "base_link"
    for j in range(n):
        x = 0.0 if j == 0 else lengths_m[j - 1]
        lines += [
            f'  <joint name="joint{j + 1}" type="revolute">',
            f"    <parent link={quoteattr(parent)}/>",
            f'    <child link="link{j + 1}"/>',
            f"    <origin xyz={_triple(x, 0.0, 0.0)} rpy={_triple(0.0, 0.0, yaw[j])}/>",
            f'    <axis xyz="0 0 {"-1" if signs[j] < 0 else "1"}"/>',
            f'    <limit lower="{num(limits[j, 0])}" upper="{num(limits[j, 1])}" '
            'effort="0" velocity="0"/>',
            "  </joint>",
            f'  <link name="link{j + 1}"/>',
        ]
        parent = f"link{j + 1}"
    if folded.targets:
        frames = [(f"target_{xml_name(t.label)}", t.length, t.angle) for t in folded.targets]
    else:
        frames = [("tool0", float(folded.link_lengths[-1]), 0.0)]
    for frame, length_mm, angle in frames:
        x, y = (length_mm / _MM_PER_M) * math.cos(angle), (length_mm / _MM_PER_M) * math.sin(angle)
        lines += [
            f'  <joint name={quoteattr(frame + "_joint")} type="fixed">',
            f"    <parent link={quoteattr(parent)}/>",
            f"    <child link={quoteattr(frame)}/>",
            f"    <origin xyz={_triple(x, y, 0.0)} rpy={_triple(0.0, 0.0, angle)}/>",
            "  </joint>",
            f"  <link name={quoteattr(frame)}/>",
        ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def planar_coupled_urdf(arm: PlanarArm) -> str | None:
    """What a URDF's joint values are when they are not the controller's readings."""
    return None if urdf_joints_are_readings(arm) else "the relative link angles D M q"


def planar_exports() -> dict[str, Callable[[CalibratedArm], str]]:
    """The planar arm's files (:mod:`armcal.families`, role ``exports``): a robot TOML and
    a URDF."""
    return {"robot": robot_toml, "urdf": urdf}
