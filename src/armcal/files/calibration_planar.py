"""A planar arm's sections of the calibration file: ``robot`` and ``elastostatic``.

The planar family's codec (:mod:`armcal.families`, roles ``encode``, ``decode``,
``encode_effect`` and ``decode_effect``); :mod:`armcal.files.calibration` writes and
reads the rest of the document, the same for every family.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..models import (
    Annulus,
    Box,
    CompliantArm,
    Elastostatic,
    FitModel,
    PlanarArm,
    Region,
    Target,
    TermChoice,
)
from ..noise import NoiseModel
from .checked import BadKey, array_of
from .robots import parse_region

__all__ = ["decode", "decode_effect", "encode", "encode_effect"]


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


def encode_effect(model: FitModel) -> dict[str, Any] | None:
    """The ``elastostatic`` section of a planar model of joint compliance (gravity in
    m/s^2), None for a rigid arm."""
    if model.effect is None:
        return None
    compliant: CompliantArm = model  # type: ignore[assignment]  # the planar effect
    elastic = compliant.elastic
    return {
        "gravity_mps2": None if elastic.gravity is None else elastic.gravity.tolist(),
        "link_masses_kg": None
        if elastic.link_masses_kg is None
        else elastic.link_masses_kg.tolist(),
        "com_fraction": elastic.com_fraction.tolist(),
        "payload_kg": elastic.payload_kg,
        "known_loads": compliant.known_loads,
        "parameters": list(compliant.compliance_names),
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
