"""A spatial arm's sections of the calibration file: ``robot`` and ``elastostatic``.

The spatial family's codec (:mod:`armcal.families`, roles ``encode``, ``decode``,
``encode_effect`` and ``decode_effect``): the chain as joint origins (4 x 4
transforms, mm), the joint map and limits, the targets, the identifiable set and
why the rest is held; :mod:`armcal.files.calibration` writes and reads the rest.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..models import (
    CompliantSpatialArm,
    FitModel,
    SerialChain,
    SpatialArm,
    SpatialElastics,
    TermChoice,
)
from ..models.interface import Held
from ..models.wording import held_sentence
from ..noise import NoiseModel
from .checked import BadKey, array_of, list_of

__all__ = ["decode", "decode_effect", "encode", "encode_effect"]


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
        "merges": [held_sentence(held) for held in arm.merges],
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
        merges=tuple(Held((), said=str(text)) for text in list_of(data, "merges", "sentences")),
        known_targets=bool(data["known_targets"]),
        oriented=bool(data.get("oriented", False)),
        target_turns=array_of(
            data, "target_turns_rad", (-1, 3), "a rotation vector (rad) per target", []
        ),
    )
    # "fixed" lists every parameter held, by the user or a rule, an effect's too
    own = set(arm.layout.names) - set(held)
    return arm.replace(user_fixed=tuple(name for name in fixed if name in own))


def encode_effect(model: FitModel) -> dict[str, Any] | None:
    """The ``elastostatic`` section of a spatial model of joint compliance, None for a
    rigid arm."""
    if model.effect is None:
        return None
    compliant: CompliantSpatialArm = model  # type: ignore[assignment]  # the spatial effect
    return {
        **compliant.elastic.to_dict(),
        "known_loads": compliant.known_loads,
        "parameters": list(compliant.compliance_names),
        "held": list(compliant.held),
        "merges": [held_sentence(held) for held in compliant.merges],
    }


def decode_effect(arm: SpatialArm, data: dict[str, Any], user: TermChoice) -> CompliantSpatialArm:
    """The spatial compliance model of a calibration file's ``elastostatic`` section, with
    the terms the user held (``user``)."""
    model = CompliantSpatialArm(
        arm,
        replace(SpatialElastics.from_dict(data, arm.n_joints), terms=user),
        bool(data["known_loads"]),
        tuple(str(name) for name in data["held"]),
        tuple(Held((), said=str(text)) for text in data["merges"]),
    )
    if list(data["parameters"]) != list(model.compliance_names):
        raise ValueError(f"compliance parameters do not match {', '.join(model.compliance_names)}")
    return model
