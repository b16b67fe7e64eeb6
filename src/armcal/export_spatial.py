"""Export a calibrated spatial arm: URDF, a robot TOML with its modified DH table, and the
joint offsets a controller takes.

All three describe the arm in its own frame: the base pose places the arm in
the instrument's frame during calibration, so it belongs to the instrument and
is written only as a comment.

**URDF** (:func:`spatial_urdf`).  One joint per moving joint, its ``<origin>``
the calibrated placement (:meth:`SpatialArm.calibrated_chain
<armcal.models.SpatialArm.calibrated_chain>`) with the joint's zero folded in:
a turn about the joint's own axis (or a slide along it) commutes with the
joint's motion, so the joint value stays the reading.  Drivers and
``robot_state_publisher`` apply ``<origin>``; they ignore ``<calibration>``,
which is therefore not written (a driver that applied it would count the zero
twice).  Every axis is ``0 0 1`` (each joint's frame has its axis as z).
Lengths in metres, every number with full round-trip precision.  The targets are
listed in a comment (each a fixed frame would make several leaves).

**Robot TOML** (:func:`spatial_robot_toml`).  The calibrated chain as a modified
DH table (:func:`armcal.models.mdh_table`: Craig's rows, Hayati's ``beta_deg``
where consecutive axes are nearly parallel, ``base_*``/``tip_*`` frames where
needed), the joint map and limits, the noise, the calibrated targets and, from a
calibration with joint compliance, its ``[elastostatic]`` loads model (the centres of
mass turned into the table's link frames; :func:`_elastostatic_lines`).  It is
a robot file every command accepts, and a later calibration against it measures
what has changed since.  The limits are the arm's: ``joint_limits_deg`` on the
readings ``q``, and where the description's own limits on its joint values
``u = M q`` (a URDF's, under a coupled joint map) constrain more than those, they
too, as ``[mdh] joint_limits_deg`` (:func:`_own_limits`), so the file reads back as
the same arm with the same reachable readings.

**Joint offsets** (:func:`joint_offsets_csv`, any arm).  The zero offset ``dq_k``
of every controller reading (deg, or mm for a slide), its std, and whether the
data identified it (one held at 0 merged into another parameter: the report
names which): the real joint
value is ``reading + dq``, so a controller that takes a zero (mastering) offset
to add to its readings takes ``dq``.  With only these offsets the controller
still has the nominal link geometry; the URDF or robot TOML carry the rest.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

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
    STANDARD_GRAVITY,
    CalibratedArm,
    SerialChain,
    SpatialArm,
    SpatialElastics,
    matrix_rpy,
    mdh_table,
)
from .numerics import box_image

__all__ = [
    "joint_offsets_csv",
    "spatial_robot_toml",
    "spatial_urdf",
]

#: URDF lengths are in metres, armcal's in mm.
_MM_PER_M = 1000.0

#: A revolute joint without limits is written ``continuous``; a URDF slide needs limits, and
#: one without any gets this range each way (mm).
_OPEN_SLIDE_MM = 1.0e6


def _calibrated(cal: CalibratedArm) -> tuple[SpatialArm, np.ndarray]:
    arm: SpatialArm = cal.arm  # the spatial family's exports are given its calibrations
    return arm, cal.arm_params


def _comments(cal: CalibratedArm, what: str) -> list[str]:
    """The provenance, the errors folded in, the base pose and the targets, as lines."""
    arm, params = _calibrated(cal)
    lay = arm.layout
    scale = arm.display_scale
    base = ", ".join(
        f"{name} = {num(params[i] * scale[i])} {arm.param_units[i]}"
        for i, name in enumerate(arm.param_names[:6])
    )
    targets = [
        f"{label} = [{', '.join(num(v) for v in xyz)}] mm"
        for label, xyz in zip(arm.targets, lay.target_points(params), strict=True)
    ]
    return [
        f"{what} written by armcal {__version__} export from the calibration of "
        f"{one_line(arm.name)}.",
        "The identified errors are folded into the joint origins (robot frame):",
        *(f"  {line}" for line in deviations_text(cal)),
        "Base pose in the instrument frame during calibration (the instrument's, not the "
        "robot's):",
        *(f"  {line}" for line in pack(base.split(", "))),
        "Targets in the tip frame (mm):",
        *(f"  {line}" for line in pack(targets)),
    ]


def _limits_on_values(arm: SpatialArm) -> np.ndarray:
    """Limits of the URDF's joint values ``u = M q``: the chain's, within the range of
    ``M q`` over the readings' limits."""
    reached = box_image(arm.joint_map, arm.limits)
    lo = np.maximum(arm.chain.joint_limits[:, 0], reached[:, 0])
    hi = np.minimum(arm.chain.joint_limits[:, 1], reached[:, 1])
    return np.column_stack([lo, hi])


def _own_limits(arm: SpatialArm) -> np.ndarray | None:
    """The limits of the joint values ``u = M q`` the robot TOML must carry
    (:func:`_limits_on_values`), or None where the readings' limits already imply them."""
    if not np.any(np.isfinite(arm.chain.joint_limits)):
        return None
    values = _limits_on_values(arm)
    return None if np.array_equal(values, box_image(arm.joint_map, arm.limits)) else values


def _limit_pairs(limits: np.ndarray, kinds: tuple[str, ...]) -> str:
    """``[[lo, hi], ...]`` in deg (mm for a prismatic joint) of ``limits`` (rad, mm)."""
    pairs = (
        nums(np.degrees(pair) if kind == "R" else pair)
        for pair, kind in zip(limits, kinds, strict=True)
    )
    return "[" + ", ".join(pairs) + "]"


def spatial_urdf(cal: CalibratedArm) -> str:
    """The calibrated spatial arm as a URDF (module notes).

    Reading it back (:func:`armcal.files.read_urdf`) gives the calibrated
    kinematics in the robot frame to round-off; its joint values are the
    chain's ``u = M q`` (the readings for an identity joint map).
    """
    arm, params = _calibrated(cal)
    chain = arm.calibrated_chain(params)
    limits = _limits_on_values(arm)
    name = xml_name(f"{arm.name}-calibrated")
    lines = ['<?xml version="1.0"?>', "<!--"]
    lines += [f"  {xml_comment(line)}" for line in _comments(cal, "URDF")]
    if not np.array_equal(arm.joint_map, np.eye(arm.n_joints)):
        lines.append(
            "  "
            + xml_comment(
                f"The joint values are u = M q, not the controller's readings q: "
                f"M = {[list(map(float, row)) for row in arm.joint_map]}."
            )
        )
    lines += ["-->", f"<robot name={quoteattr(name)}>", '  <link name="base_link"/>']
    parent = "base_link"
    for k, kind in enumerate(chain.kinds):
        child = f"link_{k + 1}"
        origin = chain.origins[k]
        xyz = " ".join(num(v / _MM_PER_M) for v in origin[:3, 3])
        rpy = " ".join(num(v) for v in matrix_rpy(origin[:3, :3]))
        lo, hi = limits[k]
        finite = bool(np.isfinite(lo) and np.isfinite(hi))
        if kind == "R":
            kind_text = "revolute" if finite else "continuous"
        else:
            kind_text = "prismatic"
            if not finite:
                lo, hi = -_OPEN_SLIDE_MM, _OPEN_SLIDE_MM
            lo, hi = lo / _MM_PER_M, hi / _MM_PER_M
        lines += [
            f'  <link name="{child}"/>',
            f'  <joint name={quoteattr(xml_name(chain.joint_names[k]))} type="{kind_text}">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{child}"/>',
            f'    <origin xyz="{xyz}" rpy="{rpy}"/>',
            '    <axis xyz="0 0 1"/>',
        ]
        if kind_text != "continuous":
            lines.append(
                f'    <limit lower="{num(lo)}" upper="{num(hi)}" effort="0" velocity="0"/>'
            )
        lines.append("  </joint>")
        parent = child
    xyz = " ".join(num(v / _MM_PER_M) for v in chain.tip[:3, 3])
    rpy = " ".join(num(v) for v in matrix_rpy(chain.tip[:3, :3]))
    lines += [
        '  <link name="flange"/>',
        '  <joint name="flange_joint" type="fixed">',
        f'    <parent link="{parent}"/>',
        '    <child link="flange"/>',
        f'    <origin xyz="{xyz}" rpy="{rpy}"/>',
        "  </joint>",
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


def spatial_robot_toml(cal: CalibratedArm) -> str:
    """The calibrated spatial arm as a robot TOML with its modified DH table (module notes)."""
    arm, params = _calibrated(cal)
    calibrated = arm.calibrated_chain(params)
    table = mdh_table(calibrated)
    lines = [f"# {line}" for line in _comments(cal, "Robot file")]
    lines += [
        f"name = {toml_string(arm.name + '-calibrated')}",
        "joint_map = [" + ", ".join(nums(row) for row in arm.joint_map) + "]",
        f"joint_limits_deg = {_limit_pairs(arm.limits, arm.chain.kinds)}",
        "",
        "[mdh]",
        f"alpha_deg = {nums(np.degrees(table.alpha))}",
        f"a_mm = {nums(table.a)}",
        f"theta_deg = {nums(np.degrees(table.theta))}",
        f"d_mm = {nums(table.d)}",
    ]
    if np.any(table.beta != 0):
        lines.append(f"beta_deg = {nums(np.degrees(table.beta))}")
    lines.append("joint_types = [" + ", ".join(f'"{k}"' for k in table.kinds) + "]")
    own = _own_limits(arm)
    if own is not None:
        lines.append(f"joint_limits_deg = {_limit_pairs(own, table.kinds)}")
    for where, frame in (("base", table.base), ("tip", table.tip)):
        if not np.array_equal(frame, np.eye(4)):
            lines.append(f"{where}_xyz_mm = {nums(frame[:3, 3])}")
            lines.append(f"{where}_rpy_deg = {nums(np.degrees(matrix_rpy(frame[:3, :3])))}")
    if arm.noise is not None:
        lines += ["", "[measurement]", *noise_toml(arm.noise)]
    if arm.target_labels:
        lines += ["", "[targets]"]
        lines += [
            f"{toml_key(label)} = {{ xyz_mm = {nums(xyz)} }}"
            for label, xyz in zip(arm.targets, arm.layout.target_points(params), strict=True)
        ]
    if cal.model.effect is not None:  # joint compliance: its loads model
        elastic: SpatialElastics = cal.model.elastic  # type: ignore[attr-defined]
        held = elastic.terms.held(elastic.term_names(arm))
        if held:
            lines += ["", "[identify]", f"fixed = [{', '.join(toml_string(n) for n in held)}]"]
        lines += ["", "[elastostatic]", *_elastostatic_lines(elastic, calibrated, table.chain())]
    return "\n".join(lines) + "\n"


def _elastostatic_lines(
    elastic: SpatialElastics, calibrated: SerialChain, written: SerialChain
) -> list[str]:
    """The ``[elastostatic]`` loads model of a calibration with joint compliance, for the
    file's modified DH table: gravity in the base frame and the payload in the tip frame
    (both kept by the table), and every link's centre of mass turned from the calibrated
    chain's joint frame into the table's (both frames ride on the same link, z along the
    joint's axis, so the transform between them is the one at zero joint values)."""
    lines = [f"gravity = {nums(elastic.gravity / STANDARD_GRAVITY)}"]
    if elastic.links is None:
        lines.append("lumped = true")
    else:
        old, new = calibrated.zero_frames(), written.zero_frames()
        com = np.column_stack([elastic.links.com_mm, np.ones(len(old))])
        moved = np.einsum("jab,jbc,jc->ja", np.linalg.inv(new), old, com)[:, :3]
        lines += [
            f"link_masses_kg = {nums(elastic.links.mass_kg)}",
            "link_com_mm = [" + ", ".join(nums(point) for point in moved) + "]",
        ]
    lines += [
        f"payload_kg = {num(elastic.payload_kg)}",
        f"payload_com_mm = {nums(elastic.payload_com_mm)}",
    ]
    return lines


def joint_offsets_csv(cal: CalibratedArm) -> str:
    """``joint,offset,unit,std``: the zero offset ``dq_k`` of every reading (module notes).

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> arm = PlanarArm([200.0, 100.0])
    >>> params = np.array([0.5, 0.0, np.radians(0.25), 0.0])
    >>> cal = CalibratedArm(arm, params, np.zeros((4, 4)), 0.1)
    >>> print(joint_offsets_csv(cal), end="")
    joint,offset,unit,std,identified
    1,0.25,deg,0.0,1
    2,0.0,deg,0.0,1
    """
    model = cal.model
    names = model.param_names
    scale = model.display_scale
    std = np.sqrt(np.clip(np.diagonal(cal.covariance), 0.0, None))
    lines = ["joint,offset,unit,std,identified"]
    for k in range(model.n_joints):
        i = names.index(f"dq{k + 1}")
        lines.append(
            f"{k + 1},{num(cal.params[i] * scale[i])},{model.param_units[i]},"
            f"{num(std[i] * scale[i])},{int(names[i] not in model.fixed)}"
        )
    return "\n".join(lines) + "\n"


def spatial_coupled_urdf(arm: SpatialArm) -> str | None:
    """What a URDF's joint values are when they are not the controller's readings."""
    return None if np.array_equal(arm.joint_map, np.eye(arm.n_joints)) else "M q"


def spatial_exports() -> dict[str, Callable[[CalibratedArm], str]]:
    """The spatial arm's files (:mod:`armcal.families`, role ``exports``): a robot TOML and
    a URDF (a UR controller's are role ``controller_files``)."""
    return {"robot": spatial_robot_toml, "urdf": spatial_urdf}
