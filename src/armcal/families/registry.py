"""The family registry: where the edge of armcal finds each family's own pieces.

The middle of armcal (identification, design, Monte Carlo, validation,
compensation) sees an arm only through :class:`~armcal.models.interface.FitModel`.
The edge -- robot files, the calibration file, export, pictures, the report's
words and the demo -- is where a family has pieces of its own.  A
:class:`Family` names them, role by role, and the edge dispatches through it:
by a model's :attr:`~armcal.models.interface.FitModel.family`
(:func:`family_of`), by the family's name in a file (:func:`family_named`), or
by the robot description a user gives (:func:`family_for`).

A role is a callable or, for the built-in families, the dotted ``"module:name"``
of one, imported when the role is first used (as Python's entry points are):
a command imports only the family code it runs, and this module imports
nothing of the layers that implement the roles.  A role a family lacks is None:
:meth:`Family.role` then says, in a sentence, that the family does not do it.
The core (a :class:`~armcal.models.interface.FitModel`) is all a family needs to be
identified, validated and simulated from Python; its calibration file needs
``encode`` and ``decode``; the rest adds commands.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from ..errors import ArmcalError, ArmcalWarning

if TYPE_CHECKING:  # annotations only: the command line's help loads no numpy
    import numpy as np

#: A role: a callable, or the ``"module:name"`` of one, imported on first use.
Ref = str | Callable[..., Any] | None


@dataclass(frozen=True)
class Family:
    """One family of arm as the edge sees it: its name and its roles.

    Attributes
    ----------
    name : str
        The family's one word, in code, files, JSON and messages (``"planar"``,
        ``"spatial"``); a model's :attr:`~armcal.models.interface.FitModel.family`.
    title : str
        What the family is, for help and reports ("a planar arm in its plane").
    descriptions : str
        The robot descriptions its loader takes, for ``--help``.
    aliases : tuple of str
        Older names of the family in files armcal wrote before (read, never written).
    fallback : bool
        Whether the family takes a robot description no other family claims (the
        planar robot TOML, armcal's first format).
    builtins
        ``() -> Mapping[str, Any]``: the built-in robots by name.
    claims
        ``(description: str) -> bool``: whether a robot description (a built-in's
        name or a file's path) is of this family.
    load_robot
        ``(description, *, base_link, tip_link) -> RobotSpec``.
    truth
        ``(robot, model, path, *, links, geometry_only) -> ndarray``: a virtual
        robot's parameters of ``model`` from a truth file (``path``; None: the
        built-in robot's own).
    encode, decode
        ``(arm) -> dict`` and ``(dict, noise, fixed) -> arm``: the calibration
        file's ``robot`` section.
    encode_effect, decode_effect
        ``(model) -> dict | None`` and ``(arm, dict, fixed) -> model``: its
        ``elastostatic`` section (an effect's model on the arm).
    calibrate
        ``(robot, meas, *, source, fixed, sigma, method, robust) -> (Calibration,
        points)``: the family's part of :func:`armcal.workflow.calibrate`.
    exports
        ``() -> Mapping[str, callable]``: the calibrated arm's files by kind
        (``"robot"``, ``"urdf"``, ``"dh"``, ``"offsets"``), each ``(cal) -> str``.
    controller_files
        ``(cal, ur_path, ros_path) -> dict[str, str]``: a controller's own calibration
        files by path (Universal Robots' calibration.conf and the ROS driver's YAML).
    calibrated_origins
        ``(cal, original) -> CalibratedOrigins``: the user's own URDF ``original`` with
        the calibrated joint origins, and those origins as YAML (a family whose arms come
        from a URDF).
    coupled_urdf
        ``(arm) -> str | None``: what a URDF's joint values are where they are not
        the controller's readings (coupled axes), None where they are.
    describe
        ``(model, *, registered, plan, words) -> list[str]``: the report's lines on what
        the arm is.
    plan_figure
        ``(robot, design_run, *, seed) -> Figure``: a designed plan drawn.
    residual_figure
        ``(calibration) -> Figure``: a fit's residuals drawn.
    demo
        ``(robot, truth, *, poses, sigma, seed, words, progress) -> Demo``: the family's
        story, with ``progress(done, 6)`` after each of its stages.
    """

    name: str
    title: str
    descriptions: str
    aliases: tuple[str, ...] = ()
    fallback: bool = False
    refs: Mapping[str, Ref] = field(default_factory=dict)

    def __post_init__(self) -> None:
        unknown = set(self.refs) - set(ROLES)
        if unknown:
            raise ValueError(f"unknown roles {sorted(unknown)}; the roles are {ROLES}")

    def has(self, role: str) -> bool:
        """Whether the family fills ``role``."""
        return self.refs.get(role) is not None

    def role(self, role: str) -> Callable[..., Any]:
        """The callable of ``role``, imported on first use.

        Raises
        ------
        ArmcalError
            For a role the family does not fill: it says which family and role.
        """
        ref = self.refs.get(role)
        if ref is None:
            raise ArmcalError(f"the {self.name} family of arm has no {_ROLE_WORDS[role]}")
        if callable(ref):
            return ref
        module, _, name = ref.partition(":")
        found = getattr(importlib.import_module(module), name)
        return found if callable(found) else (lambda: found)


#: What each role is, for the sentence of a role a family lacks.
_ROLE_WORDS = {
    "builtins": "built-in robots",
    "claims": "robot files",
    "load_robot": "robot files",
    "truth": "truth files",
    "encode": "calibration file",
    "decode": "calibration file",
    "encode_effect": "calibration file for its effect",
    "decode_effect": "calibration file for its effect",
    "calibrate": "measurement files",
    "exports": "exports",
    "controller_files": "controller files",
    "calibrated_origins": "calibrated origins of a user's URDF",
    "coupled_urdf": "URDF",
    "describe": "report lines",
    "plan_figure": "plan figure",
    "residual_figure": "residual figure",
    "demo": "demo",
}

#: The roles a family may fill (see :class:`Family`).
ROLES = tuple(_ROLE_WORDS)

_FAMILIES: dict[str, Family] = {}


def register(family: Family) -> Family:
    """Add ``family`` to the registry (a family of the same name is replaced); returns it."""
    _FAMILIES[family.name] = family
    return family


def unregister(name: str) -> None:
    """Remove the family ``name`` (a test's toy family, when the test is done)."""
    _FAMILIES.pop(name, None)


def families() -> tuple[Family, ...]:
    """Every registered family, in the order registered."""
    return tuple(_FAMILIES.values())


def family_named(name: str) -> Family:
    """The family called ``name`` (or one of its older names).

    Raises
    ------
    ArmcalError
        For a name no family has; it lists the families.
    """
    for family in _FAMILIES.values():
        if name == family.name or name in family.aliases:
            return family
    known = ", ".join(_FAMILIES)
    raise ArmcalError(f"no family of arm is called {name!r}; the families are {known}")


def family_of(model: Any) -> Family:
    """The family of a fit model (its :attr:`~armcal.models.interface.FitModel.family`)."""
    name = getattr(model, "family", None)
    if not isinstance(name, str):
        raise ArmcalError(
            f"{type(model).__name__} is not a fit model of a registered family: it has no "
            "'family' name (armcal.families.register adds one)"
        )
    return family_named(name)


def builtin_robots() -> dict[str, Family]:
    """Every family's built-in robots by name, in the families' order."""
    return {
        name: family
        for family in _FAMILIES.values()
        if family.has("builtins")
        for name in family.role("builtins")()
    }


def family_for(description: str | os.PathLike) -> Family:
    """The family of a robot description: a built-in's name or a file's path.

    Families that claim the description come first; the fallback family takes
    the rest (and its loader says what is wrong with a file that is none).
    """
    key = os.fspath(description)
    fallback = None
    for family in _FAMILIES.values():
        if family.fallback:
            fallback = fallback or family
        elif family.has("claims") and family.role("claims")(key):
            return family
    if fallback is None:
        raise ArmcalError(f"{key}: no family of arm reads this robot description")
    return fallback


A = TypeVar("A")


@dataclass(frozen=True, eq=False)
class RobotSpec(Generic[A]):
    """A robot as loaded from a built-in name or a robot description, of any family.

    Attributes
    ----------
    arm : FitModel
        The arm, with the file's noise model and fixed parameters.
    source : str
        The built-in name or the file it came from.
    default_truth : ndarray, Path or None
        The built-in robot's virtual truth (its deviations, or its truth file);
        None for a robot file.
    warnings : tuple of ArmcalWarning
        What reading the robot warns of; every command prints these.
    elastic : object or None
        The family's ``[elastostatic]`` table (gravity, masses, payload), None for
        a rigid arm.
    gravity_3d : ndarray, shape (3,), or None
        Gravity's direction in the instrument's frame, for a planar arm measured
        in 3-D (``[measurement] gravity``).
    """

    arm: A
    source: str
    default_truth: Any = None
    warnings: tuple[ArmcalWarning, ...] = ()
    elastic: Any = None
    gravity_3d: np.ndarray | None = None

    @property
    def family(self) -> Family:
        """The robot's family."""
        return family_of(self.arm)


def load_robot(
    description: str | os.PathLike,
    *,
    base_link: str | None = None,
    tip_link: str | None = None,
) -> RobotSpec[Any]:
    """A robot of any family: a built-in by name, a planar robot TOML, a URDF, a
    robot TOML over a URDF, or a modified DH, DH or Universal Robots table.

    ``base_link`` and ``tip_link`` choose a URDF's chain; a robot described
    otherwise refuses them.

    Raises
    ------
    InputError
        Naming the file and the key (or the URDF's line) and the fix.
    """
    family = family_for(description)
    loaded: RobotSpec[Any] = family.role("load_robot")(
        description, base_link=base_link, tip_link=tip_link
    )
    return loaded


def run_demo(
    robot: RobotSpec[Any],
    *,
    truth: str | os.PathLike | None = None,
    poses: int | None = None,
    sigma: float | None = None,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> Any:
    """The whole story on a robot of any family, nothing written: its family's demo
    (planar: design, measure, identify, validate, compensate, export; spatial: a tracker
    and three reflectors), on the virtual arm of ``truth`` (a truth file; None: the
    built-in robot's own).

    Returns
    -------
    Demo
        The report's text, the JSON document, the files it would write and the warnings
        (:class:`armcal.demo.Demo`).
    """
    family = robot.family
    read_truth = family.role("truth")

    def truth_of(arm: Any) -> np.ndarray:
        found: np.ndarray = read_truth(robot, arm, truth, geometry_only=True)
        return found

    story, _ = family.role("demo")(
        robot, truth_of, poses=poses, sigma=sigma, seed=seed, progress=progress
    )
    return story
