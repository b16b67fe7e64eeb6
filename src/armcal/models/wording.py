"""The model interface's data in words: one place for every family.

A family's members return data and codes (:class:`~armcal.models.interface.Held`,
:class:`~armcal.models.interface.Effect`,
:class:`~armcal.models.interface.DeviationBounds`,
:class:`~armcal.models.interface.UnpredictedLoads`, the held parameters that keep it
from a closed form, its :class:`~armcal.models.identifiability.Identifiability`);
this module makes the sentences of reports, warnings and errors from them.  A new
family then writes no prose, and every family says the same thing the same way.

It sits below everything that speaks -- the identification's warnings, the
calibration file, the report -- so that each takes its words from here.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ArmcalWarning, action
from ..numerics import COND_WARN
from .identifiability import Identifiability, combination, listing
from .interface import DeviationBounds, Effect, Held, Note, UnpredictedLoads

if TYPE_CHECKING:
    from .interface import FitModel

__all__ = [
    "DEVIATION_CHECKS",
    "EFFECT_ADVICE",
    "HELD_REASONS",
    "NEGATIVE_WORDS",
    "NOTES",
    "absorbing_note",
    "deviation_rule",
    "deviation_summary",
    "effect_advice",
    "effect_description",
    "held_sentence",
    "ill_conditioned_warning",
    "no_closed_form",
    "note_words",
    "plan_repeats",
    "unpredicted_loads",
]

#: Why held parameters merge into others (:attr:`Held.reason`), by code: the geometry's
#: reason, with ``{j}`` the first of :attr:`Held.joints`, ``{k}`` the second and
#: ``{joints}`` all of them in words.
HELD_REASONS: dict[str, str] = {
    "base-turn": "joint 1 turns the whole arm, as the base rotation does",
    "base-slide": "joint 1 slides the whole arm along its axis, as the base position does",
    "before-motion": "joint 1's placement comes before any joint moves, like the base pose",
    "tip-zero-turns": "{whom} turns with joint {j}, so its zero only moves the targets",
    "tip-zero-slides": "{whom} slides with joint {j}, so its zero only moves the targets",
    "tip-shift": "a shift along joint {j}'s axis moves every target alike",
    "parallel": "joints {joints} are parallel: a shift along their axes passes them",
    "slide-shift": "a shift along joint {j}'s axis is what its zero does: it slides there",
    "axis-shift": "a shift along joint {j}'s axis is the same before and after it turns",
    "turn-past-slide": "it turns about joint {j}'s axis, which the slide does not change",
    "shift-as-slide": "it shifts along joint {j}'s axis, as joint {j}'s zero does",
    "turn-as-zero": "it turns about joint {j}'s axis, as joint {j}'s zero does",
    "shift-past-turn": (
        "it shifts along joint {j}'s axis, which is the same before and after it turns"
    ),
    "still": "joint {j} does not move in these measurements",
    "no-effect": "it moves no measured point",
    "no-torque": "there is no torque on joint {j} that varies",
    "constant-torque": "a torque that does not change is a zero offset",
    "user": "",
}

#: What to do when the data do not show an effect (:attr:`Effect.advice`), by code.
EFFECT_ADVICE: dict[str, str] = {
    "load-more": "load the arm more (payload_kg) or {geometry}",
    "two-payloads": "measure poses under two payloads or more, or {geometry}",
}

#: What to check when deviations are implausibly large (:attr:`DeviationBounds.check`).
DEVIATION_CHECKS: dict[str, str] = {
    "description": "check the robot description and the units of the data",
    "links": (
        "check the robot file's link lengths, the units of the measurements (mm, deg), "
        "and base_offset"
    ),
    "variant": (
        "check that the robot file describes this arm (the variant of its URDF or MDH "
        "table, its joint_map) and the units of the measurements (mm, deg)"
    ),
}

#: Why a joint's compliance (``k``) or a lumped weight's (``c``) cannot be negative, and
#: what makes a fit find one (an :attr:`Effect.positive` effect's ``-negative`` warning).
NEGATIVE_WORDS = (
    "a joint's compliance (k) and a lumped weight's twist (c, compliance times weight) "
    "cannot be negative; a fit finds one where the data hold an effect the model lacks "
    "(a gravity balancer or a cable pulling on the arm, a gear's backlash), where the "
    "robot file's link masses or centres of mass are wrong, or in a term the poses' "
    "torques barely excite, where a misfit elsewhere lands"
)


def _subject(names: Sequence[str]) -> str:
    """Held parameters in words: a joint's zero by what it is."""
    return listing(
        [f"the zero of joint {n[2:]} ({n})" if n.startswith("dq") else n for n in names]
    )


def _object(held: Held) -> str:
    """What held parameters merge into, grouped: the base pose, the targets' positions,
    or by name."""
    names = held.into
    if held.effect:
        return listing(names[:4]) + (" and more" if len(names) > 4 else "")
    base = [n for n in names if n.startswith("base.")]
    targets = sorted({n.split(".")[0] for n in names if n.split(".")[0] in held.targets})
    rest = [n for n in names if not n.startswith("base.") and n.split(".")[0] not in targets]
    words = []
    if base:
        turns = [n[-2] == "r" for n in base]
        words.append(
            "the base rotation"
            if all(turns)
            else "the base pose"
            if any(turns)
            else "the base position"
        )
    if targets:
        what = "pose" if held.oriented else "position"
        if targets == ["tool"]:
            words.append(f"the target's {what}")
        else:
            words.append(f"the {what}{'s' if len(targets) > 1 else ''} of {listing(targets)}")
    words += [f"the zero of joint {n[2:]} ({n})" if n.startswith("dq") else n for n in rest]
    return listing(words)


def _reason(held: Held) -> str:
    """The geometry's reason in words (empty when there is none)."""
    template = HELD_REASONS[held.reason] if held.reason else ""
    joints = held.joints
    if len(joints) == 2 and held.reason == "parallel":
        span = (
            f"{joints[0]} and {joints[1]}"
            if joints[1] == joints[0] + 1
            else (f"{joints[0]} to {joints[1]}")
        )
    else:
        span = listing(joints) if joints else ""
    whom = "every target" if held.oriented else "a point target"
    return template.format(j=joints[0] if joints else "", joints=span, whom=whom)


def held_sentence(held: Held) -> str:
    """One held group in words: what its members merge into, and why.

    Examples
    --------
    >>> print(held_sentence(Held(("dq1",), ("base.rz",), "base-turn", (1,))))
    the zero of joint 1 (dq1) merges into the base rotation: joint 1 turns the whole arm, \
as the base rotation does
    >>> print(held_sentence(Held(("j2.z", "j3.z"), ("j4.z",), "parallel", (2, 4))))
    j2.z and j3.z merge into j4.z: joints 2 to 4 are parallel: a shift along their axes \
passes them
    >>> print(held_sentence(Held(("k1",), reason="user")))
    k1 is held by the user (the robot file's [identify], or the fix option)
    """
    if held.said:
        return held.said
    one = len(held.members) == 1
    if held.reason == "user":
        return (
            f"{listing(held.members)} {'is' if one else 'are'} held by the user (the robot "
            "file's [identify], or the fix option)"
        )
    subject = listing(held.members) if held.effect else _subject(held.members)
    if held.into:
        text = f"{subject} {'merges' if one else 'merge'} into {_object(held)}"
    else:
        text = f"{subject} cannot be seen"
    reason = _reason(held)
    return text + (f": {reason}" if reason else "")


def no_closed_form(model: FitModel) -> str:
    """Why a closed form was asked of a model without one, with the fix (an error's text).

    Examples
    --------
    >>> from armcal.models import PlanarArm
    >>> no_closed_form(PlanarArm([2.0, 1.0], fixed=["dl2"]))[:60]
    'the closed form needs every parameter free, but dl2 is fixed'
    """
    nested = model.nested
    effect = model.effect
    if effect is not None and nested is not None and nested.closed_form_hold is not None:
        return (
            f"the closed form fits the {effect.nested} only; {effect.name} needs "
            f"{action('method', 'gauss-newton')} (or auto)"
        )
    held = model.closed_form_hold
    if held:
        verb = "is" if len(held) == 1 else "are"
        return (
            f"the closed form needs every parameter free, but {', '.join(held)} {verb} "
            f"fixed; use {action('method', 'gauss-newton')} or auto"
        )
    return (
        f"{model.name} has no closed form: the {model.family} family's points are not linear "
        f"in any coordinates of its parameters; use {action('method', 'gauss-newton')} "
        "(or auto)"
    )


def ill_conditioned_warning(model: FitModel, info: Identifiability) -> ArmcalWarning | None:
    """An ``ill-conditioned`` warning when the rows barely identify ``model``, else None.

    Names the poorly determined combinations (the right singular vectors of the
    smallest singular values, in echelon form like the unseen combinations), how
    much less precise they are than with an orthogonal plan, what round-off alone
    does to them (the condition number times the machine epsilon, times the arm's
    reach), and what to vary more: the torques for a model with an effect, else the
    joints that set the combinations (every joint where the family does not say).

    Examples
    --------
    >>> from armcal.models import PlanarArm, identifiability
    >>> arm = PlanarArm([2.0, 1.0])
    >>> q = np.column_stack([np.linspace(-3, 3, 8), 1e-7 * np.arange(8)])  # q2 barely moves
    >>> from armcal.models.planar.information import identifiability as planar_info
    >>> text = ill_conditioned_warning(arm, planar_info(arm, q)).message
    >>> text.startswith("the plan determines dl1 - dl2 and dq1 - 3*dq2 poorly")
    True
    >>> text.endswith("measure poses in which joint 2 moves more (armcal.design)")
    True
    """
    if not info.ill_conditioned:
        return None
    cond = info.condition_number
    combos = list(info.poorly_determined[:3])
    if len(info.poorly_determined) > 3:
        combos.append(f"{len(info.poorly_determined) - 3} more")
    joints = info.joints_to_vary
    if model.effect is not None:
        advice = "vary the torques more (poses, payloads)"
    elif joints:
        verb = "moves" if len(joints) == 1 else "move"
        which = ("joint " if len(joints) == 1 else "joints ") + listing(joints)
        advice = f"measure poses in which {which} {verb} more {action('design')}"
    else:
        advice = f"measure poses that move every joint more {action('design')}"
    round_off = cond * np.finfo(float).eps * float(model.reach_mm)
    return ArmcalWarning(
        "ill-conditioned",
        f"the plan determines {listing(combos)} poorly: the condition number of its "
        f"scaled Jacobian is {cond:.2g} (above {COND_WARN:.0e}), so these combinations are "
        f"up to {cond:.2g} times less precise than with an orthogonal plan, and round-off "
        f"alone can shift them by about {round_off:.1g} mm; {advice}",
    )


def effect_description(effect: Effect) -> str:
    """How the effect is parametrized (a clause).

    Examples
    --------
    >>> rigid_masses = Effect("joint compliance", "compliance", "geometry", False, False, "")
    >>> print(effect_description(rigid_masses))
    link masses known: k{j} is joint j's compliance
    """
    if not effect.lumped:
        return "link masses known: k{j} is joint j's compliance"
    if effect.stations:
        return (
            "lumped mode (masses unknown): c{j}.{s} is joint j's twist per metre of "
            "horizontal lever arm to station s"
        )
    return (
        "lumped mode (masses unknown): c{j} is joint j's twist per metre of horizontal "
        "lever arm to the tip"
    )


def effect_advice(effect: Effect) -> str:
    """What to do when the data do not show the effect (a clause)."""
    return EFFECT_ADVICE[effect.advice].format(geometry=action("geometry-alone"))


#: What a length's bound is a fraction of (:attr:`DeviationBounds.reference`): the
#: summary of implausible deviations, and the length in the rule's words.
_REFERENCES = {
    "link": ("a large part of a link", "a link"),
    "reach": ("a large part of the reach", "the reach"),
    "placement": ("larger than a calibration finds", "the reach"),
}


def deviation_summary(bounds: DeviationBounds) -> str:
    """What the implausible deviations are (``"a large part of a link"``)."""
    return _REFERENCES[bounds.reference][0]


def deviation_rule(bounds: DeviationBounds) -> str:
    """The bounds in words (``"10 % of a link or 10 deg"``)."""
    of = f"{100 * bounds.length_fraction:g} % of {_REFERENCES[bounds.reference][1]}"
    if bounds.reference == "placement":  # one length for every joint: said in mm too
        return f"{of}, {bounds.length_mm:.3g} mm, or {bounds.angle_deg:g} deg"
    return f"{of} or {bounds.angle_deg:g} deg"


def absorbing_note(bounds: DeviationBounds, names: Sequence[str]) -> str:
    """What the absorbing deviations take up (a clause), empty when none does."""
    turns = np.asarray(bounds.turns, dtype=float)
    mask = turns != 0
    if not np.any(mask):
        return ""
    picked = [n for n, m in zip(names, mask, strict=True) if m]
    one = int(np.count_nonzero(mask)) == 1
    return (
        f"with a base offset, {combination(turns[mask], picked)} also "
        f"take{'s' if one else ''} up any rotation of the instrument's axes"
    )


def unpredicted_loads(found: UnpredictedLoads) -> str:
    """The loads a lumped model cannot predict, in words (a ``loads-unpredicted`` warning)."""
    others = found.others
    shown = ", ".join(f"{v:g}" for v in others[:4]) + (", ..." if len(others) > 4 else "")
    what = f"payloads of {shown} kg" if others else "tip forces"
    terms = found.terms
    named = ", ".join(terms) if len(terms) <= 6 else f"{terms[0]} ... {terms[-1]}"
    return (
        f"the calibration's {named} hold the deflection under its data's one payload, "
        f"{found.payload_kg:g} kg (lumped mode: with one payload the compliance k cannot "
        f"be told from the weight), so the deflection under {what} is not predicted; "
        "calibrate with poses at two payloads or more to identify k"
    )


#: What the paper's orthogonal plans and its D* criterion assume, said where a model
#: differs.
_PAPER_ASSUMES = (
    "the paper's orthogonal plans and its D* criterion assume isotropic iid noise and every "
    "parameter free"
)

#: The words of a :class:`~armcal.models.interface.Note`, by code: a template whose fields
#: are the note's values (``{differences}`` a model's differences from the paper's, said
#: one after the other), or a function of them where the words depend on the values.
NOTES: dict[str, str] = {
    "offsets-only": "joint offsets only ({fixed} fixed)",
    "fixed": "{fixed} fixed",
    "anisotropic": "anisotropic instrument noise (sigma_x = {sx:.4g} mm, sigma_y = {sy:.4g} mm)",
    "correlated": "correlated instrument noise (covariance_mm2 with x-y correlation)",
    "encoder": "encoder noise ({deg} deg)",
    "plans-unfit": (
        "the closed-form orthogonal plans (the paper's Table I family: joints "
        "{first}..{last} at {m} angles {spacing:g} deg apart{placed}) do not fit the {where} "
        "of {name}; the optimizer searched all plans within the {where} instead"
    ),
    "closed-not-optimal": (
        "{differences}: " + _PAPER_ASSUMES + "; the closed-form plan is not D-optimal for "
        "this model (D-criterion {d:.4f}); {auto} optimizes for it"
    ),
    "closed-optimal": (
        "{differences}: every pose's information over the {free} free parameters still has "
        "trace {free}, so no plan has a larger D-criterion than 1, and {how}: it is "
        "D-optimal for this model"
    ),
    "closed-beaten": (
        "{differences}: " + _PAPER_ASSUMES + "; they are not D-optimal for this model (the "
        "closed-form plan reaches D-criterion {closed_d:.4f}, this plan {plan_d:.4f}), so the "
        "plan was optimized for it"
    ),
    "closed-never-optimal": (
        "{differences}: " + _PAPER_ASSUMES + "; even where they fit they are not D-optimal "
        "for this model, which the plan was optimized for"
    ),
    "optimized": "{differences}: the plan was optimized for this model ({free} free parameters)",
}


def _field(key: str, value: Any) -> Any:
    """A note's value as its words place it."""
    if key == "differences":
        said = [note_words(note) for note in value]
        return "; ".join(said) if said else "the paper's model"
    if key == "fixed":
        return ", ".join(value)
    if key == "deg":
        shown = [f"{v:.4g}" for v in value]
        return shown[0] if len(shown) == 1 else "[" + ", ".join(shown) + "]"
    return value


def note_words(note: Note) -> str:
    """A note in words.

    Examples
    --------
    >>> note_words(Note("fixed", {"fixed": ("dl1", "dq2")}))
    'dl1, dq2 fixed'
    >>> note_words(Note("optimized", {"differences": (), "free": 6}))
    "the paper's model: the plan was optimized for this model (6 free parameters)"
    """
    values = {key: _field(key, value) for key, value in note.values.items()}
    if note.code == "plans-unfit":
        region = bool(values["region"])
        values["where"] = "joint limits and measurement region" if region else "joint limits"
        values["placed"] = ", placed for the largest joint-limit margin" if region else ""
    if note.code == "closed-not-optimal":
        values["auto"] = action("method", "auto")
    if note.code == "closed-optimal":
        paper_d = values["paper_d"]
        values["how"] = (
            "this closed-form orthogonal plan reaches it"
            if not values["stepping"]
            else "the closed-form orthogonal plan with joint 1 stepping too reaches it (the "
            "paper's, with joint 1 held still, "
            + ("does not fit" if paper_d is None else f"reaches only {paper_d:.4f}")
            + ")"
        )
    return NOTES[note.code].format(**values)


def plan_repeats(name: str, m: int, *, refused: bool) -> str:
    """Every closed-form plan of ``name`` repeats one pose: the error (``refused``) or the
    design's note."""
    if refused:
        return (
            f"the closed-form {m}-pose plan of {name} repeats one pose (its one joint is "
            f"held still); distinct poses need {action('method', 'optimize')} or exchange"
        )
    return (
        f"the closed-form plan of {name} repeats one pose {m} times (its one joint is held "
        "still); for distinct poses the optimizer searched other plans"
    )
