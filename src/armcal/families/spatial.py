"""The spatial family's own pieces at the edge: its truth files, its calibration-file
section, its exports (robot TOML, URDF, Universal Robots' files), its plan picture
and its demo, each behind a role of :class:`~armcal.families.registry.Family`
(:mod:`armcal.families` registers them).

The robot loader is :func:`armcal.files.spatial.load_spatial_robot`, the report's
lines :func:`armcal.report.common.spatial_model_lines`; the rest is here, as thin
adapters onto the modules that do the work.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import ACTIONS, ArmcalError, unrendered
from ..export_spatial import spatial_robot_toml, spatial_urdf
from ..files.checked import BadKey, array_of, list_of
from ..files.spatial import load_spatial_truth
from ..files.ur import (
    FAR_FROM_NOMINAL_MM,
    UrDh,
    format_ur_calibration,
    format_ur_kinematics,
    ur_deltas,
    ur_frames,
    ur_model_of,
)
from ..models import (
    CalibratedArm,
    CompliantSpatialArm,
    SerialChain,
    SpatialArm,
    SpatialElastics,
    TermChoice,
)
from ..noise import NoiseModel
from .registry import RobotSpec

__all__ = [
    "coupled_urdf",
    "decode",
    "decode_effect",
    "demo",
    "encode",
    "encode_effect",
    "exports",
    "plan_figure",
    "truth",
]


def truth(
    robot: RobotSpec[SpatialArm],
    model: SpatialArm | CompliantSpatialArm,
    path: str | os.PathLike | None,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The virtual robot's parameters of ``model`` from a truth file (``path``, else the
    built-in robot's own): :func:`armcal.files.spatial.load_spatial_truth`."""
    found = path if path is not None else robot.default_truth
    assert found is not None
    return load_spatial_truth(found, model, links=links, geometry_only=geometry_only)


# --------------------------------------------------------------------------- calibration file


def encode(arm: SpatialArm) -> dict[str, Any]:
    """The ``robot`` section of a spatial arm's calibration: the chain as joint origins
    (mm, rad: 4 x 4 transforms), the joint map and limits, the targets, and the
    identifiable set with why the rest is held."""
    return {
        "name": arm.name,
        "kind": "spatial",
        "joint_types": list(arm.chain.kinds),
        "joint_names": list(arm.chain.joint_names),
        "origins": arm.chain.origins.tolist(),
        "tip": arm.chain.tip.tolist(),
        "joint_map": arm.joint_map.tolist(),
        "joint_limits": arm.limits.tolist(),
        "chain_limits": np.clip(arm.chain.joint_limits, -1e300, 1e300).tolist(),  # JSON: no inf
        "targets": list(arm.targets),
        "target_positions_mm": arm.target_positions.tolist(),
        "base_pose": arm.base_pose.tolist(),
        "known_targets": arm.known_targets,
        **(
            {"oriented": True, "target_turns_rad": arm.target_turns.tolist()}
            if arm.oriented
            else {}
        ),
        "held": list(arm.held),
        "merges": list(arm.merges),
    }


def decode(
    data: dict[str, Any], noise: NoiseModel | None, fixed: list[str], doc: dict[str, Any]
) -> SpatialArm:
    """The spatial arm of a calibration file's ``robot`` section (:func:`encode`)."""
    kinds = tuple(str(k) for k in list_of(data, "joint_types", "'R' or 'P' per joint"))
    n = len(kinds)
    if n == 0 or any(k not in ("R", "P") for k in kinds):
        raise BadKey("robot.joint_types", f"expected 'R' or 'P' per joint, got {kinds!r}")
    pairs = f"{n} pairs [lo, hi]"
    limits = array_of(data, "chain_limits", (n, 2), f"{pairs} (the URDF's limits, rad or mm)")
    chain = SerialChain(
        array_of(data, "origins", (n, 4, 4), f"{n} joint origins, each a 4 x 4 transform (mm)"),
        kinds,
        array_of(data, "tip", (4, 4), "the tip frame, a 4 x 4 transform (mm)"),
        tuple(str(name) for name in list_of(data, "joint_names", f"{n} joint names", n)),
        np.where(np.abs(limits) >= 1e300, np.copysign(np.inf, limits), limits),
    )
    targets = tuple(str(label) for label in list_of(data, "targets", "the target labels"))
    k = len(targets)
    held = tuple(str(name) for name in list_of(data, "held", "the parameters held"))
    arm = SpatialArm(
        chain,
        str(data["name"]),
        array_of(data, "joint_map", (n, n), f"a {n} x {n} matrix (joint values from readings)"),
        array_of(data, "joint_limits", (n, 2), f"{pairs} (the readings' limits, rad or mm)"),
        targets=targets,
        target_positions=array_of(
            data, "target_positions_mm", (k, 3), f"{k} positions [x, y, z] (mm), one per target"
        ),
        base_pose=array_of(
            data, "base_pose", (6,), "6 numbers: the instrument's x, y, z (mm), rx, ry, rz (rad)"
        ),
        noise=noise,
        held=held,
        merges=tuple(str(text) for text in list_of(data, "merges", "sentences")),
        known_targets=bool(data["known_targets"]),
        oriented=bool(data.get("oriented", False)),
        target_turns=array_of(
            data, "target_turns_rad", (-1, 3), "a rotation vector (rad) per target", []
        ),
    )
    # "fixed" lists every parameter held, by the user or a rule, an effect's too
    own = set(arm.layout.names) - set(held)
    return arm.replace(user_fixed=tuple(name for name in fixed if name in own))


def encode_effect(model: SpatialArm | CompliantSpatialArm) -> dict[str, Any] | None:
    """The ``elastostatic`` section of a spatial model of joint compliance, None for a
    rigid arm."""
    if not isinstance(model, CompliantSpatialArm):
        return None
    return {
        **model.elastic.to_dict(),
        "known_loads": model.known_loads,
        "parameters": list(model.compliance_names),
        "held": list(model.held),
        "merges": list(model.merges),
    }


def decode_effect(arm: SpatialArm, data: dict[str, Any], user: TermChoice) -> CompliantSpatialArm:
    """The spatial compliance model of a calibration file's ``elastostatic`` section, with
    the terms the user held (``user``)."""
    model = CompliantSpatialArm(
        arm,
        replace(SpatialElastics.from_dict(data, arm.n_joints), terms=user),
        bool(data["known_loads"]),
        tuple(str(name) for name in data["held"]),
        tuple(str(text) for text in data["merges"]),
    )
    if list(data["parameters"]) != list(model.compliance_names):
        raise ValueError(f"compliance parameters do not match {', '.join(model.compliance_names)}")
    return model


# --------------------------------------------------------------------------- exports


def coupled_urdf(arm: SpatialArm) -> str | None:
    """What a URDF's joint values are when they are not the controller's readings."""
    return None if np.array_equal(arm.joint_map, np.eye(arm.n_joints)) else "M q"


def _ur_arm(cal: CalibratedArm, path: str) -> tuple[SerialChain, str, UrDh]:
    """The calibrated chain of a UR arm (DH base frame to flange, whatever frames its
    description used: :func:`armcal.files.ur.ur_frames`), its model
    (:func:`armcal.files.ur.ur_model_of`) and its deltas from that model's table, for a
    controller's file at ``path``."""
    arm: SpatialArm = cal.arm
    if arm.n_joints != 6 or set(arm.chain.kinds) != {"R"}:
        raise ArmcalError(f"{path}: a UR file needs a six-axis revolute arm; {arm.name} is not")
    frames = ur_frames(arm.chain)  # of the nominal: they hold for its calibration
    if frames.distance_mm > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: {arm.name} is no UR model in any base and tip frames (nearest "
            f"{frames.model}, {frames.distance_mm:.4g} mm away); describe the arm with a robot "
            "file's [ur] table or Universal Robots' own URDF"
        )
    chain = frames.apply(arm.calibrated_chain(cal.arm_params))
    model, distance = ur_model_of(chain)
    if distance > FAR_FROM_NOMINAL_MM:
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} moves the flange {distance:.4g} mm from the "
            f"nominal {model}'s (a calibration moves it a few mm); check the calibration"
        )
    try:
        deltas = ur_deltas(chain, model)
    except ValueError as exc:  # what a UR's DH table cannot hold, e.g. a tilted joint 1
        raise ArmcalError(
            f"{path}: the calibrated {arm.name} has no UR DH table: {unrendered(exc)}; a UR's "
            "table starts "
            "at joint 1's axis, so leave the base pose free (the joint's placement merges "
            "into it) rather than fixing base.* and identifying j1.*"
        ) from None
    return chain, model, deltas


def ur_texts(cal: CalibratedArm, ur_path: str | None, ros_path: str | None) -> dict[str, str]:
    """A UR controller's calibration.conf deltas and the ROS driver's calibration YAML."""
    texts: dict[str, str] = {}
    first = ur_path if ur_path is not None else ros_path
    if first is None:
        return texts
    chain, model, deltas = _ur_arm(cal, first)
    if ur_path is not None:
        texts[ur_path] = format_ur_calibration(deltas)
    if ros_path is not None:
        try:
            texts[ros_path] = format_ur_kinematics(chain, model, f"armcal_{cal.arm.name}_{model}")
        except ValueError as exc:
            raise ArmcalError(
                f"{ros_path}: the calibrated {cal.arm.name}: {unrendered(exc)}"
            ) from None
    return texts


def exports() -> Mapping[str, Callable[..., Any]]:
    """The spatial arm's files: a robot TOML, a URDF, and a UR controller's files."""
    return {"robot": spatial_robot_toml, "urdf": spatial_urdf, "ur": ur_texts}


# --------------------------------------------------------------------------- pictures, demo


def plan_figure(robot: RobotSpec[SpatialArm], run: Any, *, seed: int = 0) -> Any:
    """A designed plan (a :class:`~armcal.workflow.DesignRun`) in four panels: the arm at
    every pose, the joints, the predicted error map and the certificate."""
    from ..plotting_spatial import plot_spatial_plan  # matplotlib only when asked for

    return plot_spatial_plan(
        run.design.model,
        run.q,
        sigma=run.quality.sigma_mm,
        certificate=run.design.certificate,
        rng=seed,
    )


#: What the six-axis demo writes, for the line that says so.
DEMO_KINDS = "report.md, residuals, measurements, calibration, program, URDF, DH table, offsets"


def demo(
    robot: RobotSpec[SpatialArm],
    truth_of: Callable[[Any], np.ndarray],
    *,
    poses: int | None = None,
    sigma: float | None = None,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
) -> tuple[Any, str]:
    """The six-axis story (:func:`armcal.demo_spatial.run_spatial_demo`): a tracker and
    three reflectors; and what it writes."""
    from ..demo_spatial import SPATIAL_DEMO_POSES, run_spatial_demo

    result = run_spatial_demo(
        robot.arm,
        truth_of,
        poses=SPATIAL_DEMO_POSES if poses is None else poses,
        sigma=sigma,
        seed=seed,
        words=words,
    )
    return result, DEMO_KINDS
