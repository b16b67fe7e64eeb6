"""What the command line prints: the result on stdout, every warning once on stderr.

The library's warnings and errors advise in neutral words; here they are said
in the command line's, its flags (:data:`CLI_ACTIONS`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from ..errors import ArmcalWarning, unique_warnings
from ..files import to_json
from ..progress import quiet

__all__ = [
    "CLI_ACTIONS",
    "emit",
    "print_warnings",
    "warning_dicts",
]

#: The command line's words for the advice of warnings and errors
#: (:data:`armcal.errors.ACTIONS`); ``{}`` places an action's values, comma-joined.
CLI_ACTIONS = {
    "refit-robust": "rerun with --robust to fit without them",
    "try-robust": "try --robust",
    "try-closed-form": "try --method closed-form",
    "geometry-alone": "fit the geometry alone (--no-compliance)",
    "geometry-only": "--no-compliance fits the geometry only",
    "hold-terms": "--fix NAME, or fixed = [...] in the robot file's [identify] table",
    "design": "(armcal design)",
    "own-urdf": "export its own URDF (--urdf without --from)",
    "choose-tip": "name the tip link with --tip-link LINK (or tip_link in a robot TOML)",
    "choose-base": "name the base link with --base-link LINK (or base_link in a robot TOML)",
    "method": "--method {}",
    "poses": "--poses {}",
    "test-poses": "--test-poses",
    "sigma": "--sigma",
    "isotropic-noise": "--sigma",
    "hold": "--fix {}",
    "fixed": "--fix",
    "free-held": "--fix or the robot file's [identify]",
    "trials": "--trials {}",
    "cross-validate": "--cross-validate",
    "target": "--target",
    "target-label": "--target LABEL",
    "payload-kg": "--payload-kg",
    "payload-given": "--payload-kg/payload_kg",
    "design-defaults": "--criterion and --method at their defaults",
    "candidates": "--candidates",
    "position-requirement": "--position-rms-mm",
    "distinct": "--distinct",
    "payloads": "--payloads",
    "robot-file": "--robot",
    "measurements-file": "--measurements",
    "plan-file": "--plan",
    "calibration-file": "--calibration",
    "truth-file": "--truth",
    "robot-arm": "--robot",
}


def print_warnings(warnings: Sequence[ArmcalWarning]) -> None:
    """Each warning as one ``armcal: warning: ...`` line on stderr, in the command line's words."""
    quiet()  # an elapsed-time line stops before anything is printed
    for warning in warnings:
        print(f"armcal: warning: {warning.render(CLI_ACTIONS)}", file=sys.stderr)


def warning_dicts(warnings: Sequence[ArmcalWarning]) -> list[dict[str, str]]:
    """The JSON form of warnings (each once), in the command line's words."""
    return [w.to_dict(CLI_ACTIONS) for w in unique_warnings(warnings)]


def emit(
    args: argparse.Namespace,
    document: dict,
    text: str,
    warnings: Sequence[ArmcalWarning] = (),
) -> None:
    """Print the result, after every warning of the run (once each) on stderr.

    The warnings also replace the document's ``warnings`` list, so the JSON and
    stderr say the same.
    """
    warnings = unique_warnings(warnings)
    document["warnings"] = warning_dicts(warnings)
    print_warnings(warnings)  # an elapsed-time line stops first (quiet)
    args.loaded_warnings = ()  # printed: an error after this does not print them again
    if getattr(args, "stdout_taken", False):  # `-o -`: the file is the command's output
        return
    print(to_json(document) if args.json else text, end="" if args.json else "\n")
