"""What a robot file and the options make of the model a command works on.

The robot file gives the arm and, with ``[elastostatic]``, its joint
compliance; the options hold parameters fixed (the arm's and the compliance's
terms) and override the instrument's noise.  Every command goes through these,
so ``--fix`` and ``--sigma`` mean the same everywhere (and
:func:`armcal.noise.instrument_override` is the one place ``--sigma`` is
applied).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, TypeVar

import numpy as np

from ..choices import DEFAULT_SIGMA_MM
from ..doe import random_plan
from ..errors import ArmcalError, NotIdentifiableError, action
from ..files import RobotSpec, read_plan, unknown_parameter
from ..models import FitModel, Loads, TermChoice
from ..noise import instrument_override

__all__ = [
    "BYTES_PER_DESIGNED_POSE",
    "DEFAULT_SIGMA_MM",
    "FixError",
    "check_plan_size",
    "design_sigma",
    "fit_model",
    "model_arm",
    "model_spec",
    "plan_model",
    "prefixed",
    "simulation_sigma",
    "test_poses",
    "with_fixed",
]


class FixError(ArmcalError):
    """Parameters to hold that the arm cannot hold: the message starts with the option that
    named them (``fixed``; the command line says its ``--fix``)."""


def prefixed(source: str, exc: ArmcalError) -> ArmcalError:
    """``exc`` of the same kind (and, unidentifiable, with its combinations) naming ``source``;
    its actions are carried as raised, for the command line to say in its flags."""
    if isinstance(exc, NotIdentifiableError):
        return NotIdentifiableError(f"{source}: {exc.text}", exc.combinations)
    return type(exc)(f"{source}: {exc.text}")


#: A robot file's arm, of either family: what --fix and --sigma apply to.
Arm = TypeVar("Arm", bound=FitModel)


def with_fixed(arm: Arm, fixed: Sequence[str], terms: Sequence[str] = ()) -> Arm:
    """The arm with ``fixed`` held (replacing the robot file's set); FixError for a name
    that is neither the arm's nor one of an effect's ``terms`` (joint compliance, held
    by :func:`model_spec`), or when nothing of the arm would be left to identify."""
    known = (*arm.param_names, *terms)
    for name in fixed:
        if name not in known:
            raise FixError(f"{action('fixed')}: {unknown_parameter(name, known, arm.name)}")
    mine = [name for name in fixed if name in arm.param_names]
    if len(set(mine)) == arm.n_params:
        raise FixError(
            f"{action('fixed')}: every parameter would be fixed; leave at least one free"
        )
    return arm.with_fixed(tuple(mine))


def model_arm(
    arm: Arm,
    *,
    fixed: Sequence[str] | None = None,
    sigma: float | None = None,
    terms: Sequence[str] = (),
) -> Arm:
    """The arm with ``fixed`` parameters (None: the robot file's; names among an effect's
    ``terms`` are the effect's, :func:`model_spec`) and instrument noise ``sigma`` (mm;
    None or 0: the robot file's), its encoder noise kept."""
    if fixed is not None:
        arm = with_fixed(arm, fixed, terms)
    if sigma:  # 0 (noiseless synthesis) is no noise model
        arm = arm.with_noise(instrument_override(arm.noise, sigma))
    return arm


#: A robot file of either family.
Spec = TypeVar("Spec", bound=RobotSpec)


def model_spec(
    spec: Spec, arm: Arm, *, fixed: Sequence[str] | None = None, sigma: float | None = None
) -> tuple[Spec, Arm]:
    """The robot file and its arm ``arm`` (``spec.arm`` fitted to the data's targets and
    3-D columns) as the options ask: ``fixed`` (None: the robot file's ``[identify]``)
    replaces the held set of the arm and of the joint compliance's terms alike
    (``[elastostatic]``), and ``sigma`` the instrument noise (:func:`model_arm`).

    Raises FixError for a name that is neither a parameter of the arm nor a term of
    its compliance.
    """
    elastic: Any = spec.elastic
    terms: tuple[str, ...] = () if elastic is None else elastic.term_names(arm)
    if fixed is not None and elastic is not None:
        held = TermChoice(fixed=tuple(name for name in fixed if name in terms))
        spec = replace(spec, elastic=replace(elastic, terms=held))
    return spec, model_arm(arm, fixed=fixed, sigma=sigma, terms=terms)


def simulation_sigma(spec: RobotSpec, sigma: float | None) -> float | None:
    """The noise a simulation draws: ``sigma``, else None (the robot file's whole noise
    model, shape and encoders), else :data:`DEFAULT_SIGMA_MM`."""
    if sigma is not None:
        return sigma
    return None if spec.arm.noise is not None else DEFAULT_SIGMA_MM


def design_sigma(arm: FitModel) -> float:
    """The reference noise of a model arm (:func:`model_arm`), else :data:`DEFAULT_SIGMA_MM`."""
    return arm.noise.sigma_mm if arm.noise is not None else DEFAULT_SIGMA_MM


def fit_model(
    spec: RobotSpec,
    arm: FitModel,
    loads: Loads | None = None,
    *,
    virtual: bool = False,
) -> FitModel:
    """The model a robot file describes: the arm, or with ``[elastostatic]`` its compliant
    arm for data with ``loads`` (the robot file's payload when omitted): the one place
    the family of a robot file is chosen.

    ``virtual``: the model of a virtual robot to measure under ``loads`` rather
    than the one a fit of its data would use; they differ for a lumped arm under
    one constant payload, which a fit merges into ``c1..cn`` but which still
    bends the arm (:meth:`~armcal.models.planar.compliance.CompliantArm.for_loads`).

    Raises ArmcalError, naming the robot file, when nothing would twist the joints.
    """
    if spec.elastic is None:
        return arm
    given = loads is not None
    loads = Loads.create(1, spec.elastic.payload_kg) if loads is None else loads
    try:
        model = spec.elastic.model_for(arm, loads, virtual=virtual)
        if given and not virtual:  # the rows' own model: what it can identify is known
            _check_terms(model, spec.elastic.terms)
    except ArmcalError as exc:
        raise prefixed(spec.source, exc) from None
    return model


def _check_terms(model: FitModel, terms: TermChoice) -> None:
    """ArmcalError when the user asks for a compliance term the model of these rows does
    not have, or holds every one it has."""
    inner = model.nested
    names = model.param_names[0 if inner is None else inner.n_params :]
    absent = [name for name in terms.asked if name not in names]
    if absent:
        raise ArmcalError(
            f"[identify] free lists {', '.join(absent)}, which these rows cannot identify: "
            f"their model of the joint compliance has {', '.join(names)} (k, the compliance "
            "itself, is told from the lumped weight c only by payloads that vary); measure "
            "poses under two payloads or more, or leave it out of free"
        )
    if names and set(terms.held(names)) >= set(names):
        raise ArmcalError(
            f"every term of the joint compliance ({', '.join(names)}) would be held at zero, "
            "which is the geometry alone; leave one free, or fit the geometry without the "
            "compliance"
        )


def plan_model(
    spec: RobotSpec,
    arm: FitModel,
    m: int,
    payload: np.ndarray | None = None,
    *,
    virtual: bool = False,
) -> tuple[FitModel, Loads | None]:
    """The model of a plan of ``m`` poses and the plan's loads: with ``[elastostatic]``
    its payload column ``payload`` (kg), else the robot file's payload; no loads without.

    ``virtual``: the model of a virtual robot to measure (:func:`fit_model`).
    """
    if spec.elastic is None:
        return arm, None
    loads = Loads.create(m, spec.elastic.payload_kg if payload is None else payload)
    return fit_model(spec, arm, loads, virtual=virtual), loads


#: Memory a designed pose costs at its peak (bytes): the plan, its checks and its CSV
#: text.  Measured: design --poses 10^6 peaks at 673 MB, 130 MB of it the program.
BYTES_PER_DESIGNED_POSE = 1000


def physical_memory() -> int | None:
    """This machine's physical memory in bytes, where the system says (None elsewhere)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def check_plan_size(poses: int, memory: int | None = None) -> None:
    """Refuse, before any work, a plan too large for half of the machine's memory.

    ``memory`` is the machine's (default :func:`physical_memory`).
    """
    memory = physical_memory() if memory is None else memory
    need = poses * BYTES_PER_DESIGNED_POSE
    if memory is None or 2 * need <= memory:
        return
    raise ArmcalError(
        f"{action('poses', poses)}: a plan this large takes about {need / 1e9:.3g} GB to design, "
        f"check and write (about {BYTES_PER_DESIGNED_POSE} bytes a pose), more than half of "
        f"this machine's {memory / 1e9:.3g} GB; a plan's information per pose stops growing "
        "after a few hundred poses, so design fewer and repeat them (the plan of m poses "
        "taken k times is as good per pose)"
    )


def test_poses(
    spec: RobotSpec, seed: int, path: str | None = None, *, loaded: bool = False
) -> np.ndarray:
    """Poses where positioning accuracy matters: the plan file ``path``, else 1000 uniform
    in the limits (seeded by ``seed``).

    None, shape ``(0, n)``, for a robot with ``[elastostatic]`` (the file is not read):
    its plans are judged by the predicted std of the parameters, not by the position
    error at test poses -- unless ``loaded``: where a position error is asked for (a
    position target of poses-needed), the test poses carry the robot file's payload.
    """
    if spec.elastic is not None and not loaded:
        return np.zeros((0, spec.arm.n_joints))
    if path is not None:
        return read_plan(path, spec.arm)
    return random_plan(spec.arm, 1000, rng=np.random.default_rng(seed))
