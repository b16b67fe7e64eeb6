"""The planar family's own pieces at the edge: its truth files, its calibration-file
section, its exports, its plan picture and its demo, each behind a role of
:class:`~armcal.families.registry.Family` (:mod:`armcal.families` registers them).

The robot loader is :func:`armcal.files.robots.load_planar_robot`, the report's
lines :func:`armcal.report.common.planar_model_lines`; the rest is here, as thin
adapters onto the modules that do the work.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..errors import ACTIONS, ArmcalError
from ..export import robot_toml, urdf, urdf_joints_are_readings
from ..files.checked import BadKey, array_of
from ..files.robots import (
    COMPLIANCE_TRUTH_KEYS,
    load_compliance_truth,
    load_truth,
    parse_region,
)
from ..models import (
    Annulus,
    Box,
    CompliantArm,
    Elastostatic,
    PlanarArm,
    Region,
    Target,
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
    robot: RobotSpec[PlanarArm],
    model: PlanarArm | CompliantArm,
    path: str | os.PathLike | None,
    *,
    links: tuple[str | None, str | None] = (None, None),
    geometry_only: bool = False,
) -> np.ndarray:
    """The virtual robot's parameters of ``model``: a truth file's (``path``), with its
    compliance for a model of joint compliance, else the built-in robot's deviations.

    ``geometry_only`` (the demo's rigid arm) leaves a truth's compliance out.
    """
    if isinstance(model, CompliantArm):
        if path is None:
            keys = ", ".join(COMPLIANCE_TRUTH_KEYS[k] for k in dict.fromkeys(model.kinds))
            raise ArmcalError(
                f"{robot.source}: a robot with [elastostatic] needs a truth file with the "
                f"deviations and {keys}"
            )
        geometry = load_truth(path, model.arm)
        return np.concatenate([geometry, load_compliance_truth(path, model)])
    if path is not None:
        return load_truth(path, robot.arm, rigid=not geometry_only)
    assert isinstance(robot.default_truth, np.ndarray)
    return robot.default_truth


# --------------------------------------------------------------------------- calibration file


def _region_to_dict(region: Region | None) -> dict[str, Any] | None:
    if isinstance(region, Annulus):
        return {
            "kind": "annulus",
            "center_mm": list(region.center),
            "r_min_mm": region.r_min,
            "r_max_mm": region.r_max,
        }
    if isinstance(region, Box):
        return {"kind": "box", "x_mm": list(region.x), "y_mm": list(region.y)}
    return None


def encode(arm: PlanarArm) -> dict[str, Any]:
    """The ``robot`` section of a planar arm's calibration: everything needed to rebuild it.

    ``name``, ``link_lengths_mm``, ``joint_limits_deg``, ``base_offset``,
    ``base_rotation``, ``joint_map``, ``joint_offsets_deg``, ``targets``
    (label to ``{length_mm, angle_deg}``) and ``region`` (or null); the noise
    model and the fixed parameters are top-level keys of the document.
    """
    return {
        "kind": "planar",
        "name": arm.name,
        "link_lengths_mm": arm.link_lengths.tolist(),
        "joint_limits_deg": arm.joint_limits_deg.tolist(),
        "base_offset": arm.base_offset,
        "base_rotation": arm.base_rotation,
        "joint_map": arm.joint_map.tolist(),
        "joint_offsets_deg": np.degrees(arm.joint_offsets).tolist(),
        "targets": {
            t.label: {"length_mm": t.length, "angle_deg": math.degrees(t.angle)}
            for t in arm.targets
        },
        "region": _region_to_dict(arm.region),
    }


def decode(
    data: dict[str, Any], noise: NoiseModel | None, fixed: list[str], doc: dict[str, Any]
) -> PlanarArm:
    """The planar arm of a calibration file's ``robot`` section (:func:`encode`); ``fixed``
    without the compliance terms of the document ``doc``."""
    section = doc.get("elastostatic")
    terms = [] if not isinstance(section, dict) else list(section.get("parameters", []))
    fixed = [name for name in fixed if name not in terms]
    region = None
    if data.get("region") is not None:
        region = parse_region("", data["region"])
    targets = tuple(
        Target(label, float(entry["length_mm"]), math.radians(float(entry["angle_deg"])))
        for label, entry in data.get("targets", {}).items()
    )
    lengths = array_of(data, "link_lengths_mm", (-1,), "the nominal link lengths (mm)")
    n = lengths.size
    if n == 0:
        raise BadKey("robot.link_lengths_mm", "expected the nominal link lengths (mm); got none")
    each = f"for each of the {n} links in robot.link_lengths_mm"  # the count the rest follow
    offsets = data.get("joint_offsets_deg")
    joint_map = None
    if data.get("joint_map") is not None:
        joint_map = array_of(
            data, "joint_map", (n, n), f"the matrix theta = M q, a row and column {each}"
        )
    arm = PlanarArm(
        lengths,
        np.radians(array_of(data, "joint_limits_deg", (n, 2), f"a pair [lo, hi] (deg) {each}")),
        base_offset=bool(data["base_offset"]),
        name=str(data["name"]),
        noise=noise,
        region=region,
        fixed=fixed,
        joint_map=joint_map,
        targets=targets,
        base_rotation=bool(data.get("base_rotation", False)),
        joint_offsets=None
        if offsets is None
        else np.radians(array_of(data, "joint_offsets_deg", (n,), f"a joint offset (deg) {each}")),
    )
    if arm.base_rotation and doc.get("plane") is None:
        raise BadKey("plane", "a calibration from 3-D data must record its plane")
    return arm


def encode_effect(model: PlanarArm | CompliantArm) -> dict[str, Any] | None:
    """The ``elastostatic`` section of a planar model of joint compliance (gravity in
    m/s^2), None for a rigid arm."""
    if not isinstance(model, CompliantArm):
        return None
    elastic = model.elastic
    return {
        "gravity_mps2": None if elastic.gravity is None else elastic.gravity.tolist(),
        "link_masses_kg": None
        if elastic.link_masses_kg is None
        else elastic.link_masses_kg.tolist(),
        "com_fraction": elastic.com_fraction.tolist(),
        "payload_kg": elastic.payload_kg,
        "known_loads": model.known_loads,
        "parameters": list(model.compliance_names),
    }


def decode_effect(arm: PlanarArm, data: dict[str, Any], user: TermChoice) -> CompliantArm:
    """The planar compliance model of a calibration file's ``elastostatic`` section, with
    the terms the user held (``user``)."""
    gravity = data["gravity_mps2"]
    masses = data["link_masses_kg"]
    elastic = Elastostatic(
        None if gravity is None else np.array(gravity, dtype=float).reshape(2),
        None if masses is None else np.array(masses, dtype=float).reshape(arm.n_joints),
        np.array(data["com_fraction"], dtype=float).reshape(arm.n_joints),
        float(data["payload_kg"]),
        user,
    )
    model = CompliantArm(arm, elastic, bool(data["known_loads"]))
    if list(data.get("parameters", model.compliance_names)) != list(model.compliance_names):
        raise ValueError(f"compliance parameters do not match {', '.join(model.compliance_names)}")
    return model


# --------------------------------------------------------------------------- exports


def coupled_urdf(arm: PlanarArm) -> str | None:
    """What a URDF's joint values are when they are not the controller's readings."""
    return None if urdf_joints_are_readings(arm) else "the relative link angles D M q"


def exports() -> Mapping[str, Callable[..., str]]:
    """The planar arm's files: a robot TOML and a URDF."""
    return {"robot": robot_toml, "urdf": urdf}


# --------------------------------------------------------------------------- pictures, demo


def plan_figure(robot: RobotSpec[PlanarArm], run: Any, *, seed: int = 0) -> Any:
    """A designed plan (a :class:`~armcal.workflow.DesignRun`) in the workspace and in
    joint space, with its payloads and gravity."""
    from ..plotting import plot_plan  # matplotlib only when a plot is asked for

    gravity = None if robot.elastic is None else robot.elastic.gravity
    return plot_plan(robot.arm, run.q, payload_kg=run.payload_kg, gravity=gravity)


#: What the planar demo writes, for the line that says so.
DEMO_KINDS = "report.md, figures, plan, measurements, calibration, program, robot file, URDF"


def demo(
    robot: RobotSpec[PlanarArm],
    truth_of: Callable[[Any], np.ndarray],
    *,
    poses: int | None = None,
    sigma: float | None = None,
    seed: int = 0,
    words: Mapping[str, str] = ACTIONS,
) -> tuple[Any, str]:
    """The planar story (:func:`armcal.demo.run_demo`) and what it writes."""
    from ..demo import PLANAR_DEMO_POSES, run_demo
    from ..workflow.setup import design_sigma

    truth_ = truth_of(robot.arm)
    sigma = design_sigma(robot.arm) if sigma is None else sigma
    poses = PLANAR_DEMO_POSES if poses is None else poses
    result = run_demo(robot.arm, truth_, poses=poses, sigma=sigma, seed=seed, words=words)
    return result, DEMO_KINDS
