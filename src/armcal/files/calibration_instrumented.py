"""The calibration file's ``robot`` section of an arm measured by an instrument other than
a tracker (:class:`~armcal.models.instrumented.InstrumentedArm`): the arm's own section,
as its family writes it, and the instrument's ``[instrument]`` table where the user
said it was, from which the instrument's parameters (in ``parameters``) start."""

from __future__ import annotations

from typing import Any

from ..families.registry import family_named, family_of
from ..models.instrumented import InstrumentedArm
from ..noise import NoiseModel
from .checked import BadKey
from .instrument_table import instrument_section, read_instrument

__all__ = ["decode", "encode"]


def encode(model: InstrumentedArm) -> dict[str, Any]:
    """``{"kind": "instrumented", "arm": ..., "instrument": ...}``."""
    return {
        "kind": "instrumented",
        "name": model.name,
        "arm": dict(family_of(model.inner).role("encode")(model.inner)),
        "instrument": instrument_section(model.instrument),
        "unseen": model.instrument.unseen,
    }


def decode(
    data: dict[str, Any], noise: NoiseModel | None, fixed: list[str], doc: dict[str, Any]
) -> InstrumentedArm:
    """The arm and its instrument of a section :func:`encode` wrote."""
    arm_data = data["arm"]
    if not isinstance(arm_data, dict):
        raise BadKey("robot.arm", "expected the arm's section, an object")
    inner = family_named(str(arm_data.get("kind", ""))).role("decode")(arm_data, noise, fixed, doc)
    instrument = read_instrument("calibration", data["instrument"], "robot.instrument")
    if instrument is None:
        raise BadKey(
            "robot.instrument", "expected a plane, point, distance, partial or camera instrument"
        )
    labels = tuple(inner.target_labels)
    if len(labels) == 1:  # the tool point names the tool's turns
        instrument = instrument.for_tool(labels[0])
    mine = set(instrument.param_names)
    return InstrumentedArm(inner, instrument, tuple(name for name in fixed if name in mine))
