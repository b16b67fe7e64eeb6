"""The ``armcal`` command line: parse arguments, call the library, write files.

Exit status: 0 on success, 2 for bad input (one ``armcal: error: ...`` line on
stderr, no traceback, no output file), 1 for bugs.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

import numpy as np

from ._version import __version__
from .arm import forward_kinematics
from .design import orthogonal_plan
from .errors import ArmcalError, NotIdentifiableError
from .identify import METHODS, Calibration, format_report, identify
from .io import (
    DEFAULT_ROBOT,
    RobotSpec,
    atomic_write,
    calibration_to_dict,
    format_measurements_csv,
    format_plan_csv,
    load_robot,
    load_truth,
    make_folder,
    read_measurements,
    read_plan,
    to_json,
)

__all__ = ["main"]

#: Noise assumed for design and simulation when neither --sigma nor the robot file gives it.
DEFAULT_SIGMA_MM = 0.1


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors become one ``armcal: error:`` line."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise ArmcalError(f"{message} (see '{self.prog} --help')")


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _non_negative(text: str) -> float:
    if text.strip() in ("0", "0.0"):
        return 0.0
    return _positive(text)


def _poses(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1 pose, got {value}")
    return value


def _sigma_for_simulation(args: argparse.Namespace, spec: RobotSpec) -> float:
    if args.sigma is not None:
        return args.sigma
    return spec.arm.sigma if spec.arm.sigma is not None else DEFAULT_SIGMA_MM


def _truth(args: argparse.Namespace, spec: RobotSpec) -> np.ndarray:
    if args.truth is not None:
        return load_truth(args.truth, spec.arm)
    if spec.default_truth is None:
        raise ArmcalError(
            f"{spec.source}: a robot file has no default truth; pass --truth truth.toml "
            "(dl_mm, dq_deg and, with a base offset, base_mm)"
        )
    return spec.default_truth


def _emit(args: argparse.Namespace, document: dict, text: str) -> None:
    print(to_json(document) if args.json else text, end="" if args.json else "\n")


# --------------------------------------------------------------------------- commands


def _synthesize(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    q = read_plan(args.plan, spec.arm)
    truth = _truth(args, spec)
    sigma = _sigma_for_simulation(args, spec)
    rng = np.random.default_rng(args.seed)
    xy = forward_kinematics(spec.arm, q, truth) + rng.normal(0.0, sigma, size=(q.shape[0], 2))
    text = format_measurements_csv(q, xy)
    if args.output is None:
        sys.stdout.write(text)
        return
    atomic_write(args.output, text)
    document = {"poses": int(q.shape[0]), "sigma_mm": sigma, "output": str(args.output)}
    _emit(
        args,
        document,
        f"wrote {q.shape[0]} measurements of {spec.arm.name} (sigma {sigma:g} mm, "
        f"seed {args.seed}) to {args.output}",
    )


def _identify_file(spec: RobotSpec, path: str, *, method: str, sigma: float | None) -> Calibration:
    meas = read_measurements(path, spec.arm)
    try:
        return identify(
            spec.arm, meas.q, meas.xy, method=method, sigma=sigma, pose_labels=meas.labels
        )
    except NotIdentifiableError as exc:
        raise NotIdentifiableError(f"{path}: {exc}", exc.combinations) from None
    except ArmcalError as exc:
        raise ArmcalError(f"{path}: {exc}") from None


def _warn_unconverged(cal: Calibration) -> None:
    if not cal.converged:
        print(
            f"armcal: warning: {cal.method} did not converge in {cal.iterations} iterations; "
            "try --method closed-form",
            file=sys.stderr,
        )


def _identify(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    cal = _identify_file(spec, args.measurements, method=args.method, sigma=args.sigma)
    document = calibration_to_dict(cal)
    if args.output is not None:
        atomic_write(args.output, to_json(document))
    _warn_unconverged(cal)
    _emit(args, document, format_report(cal))


def _demo(args: argparse.Namespace) -> None:
    spec = load_robot(args.robot)
    arm = spec.arm
    truth = _truth(args, spec)
    sigma = _sigma_for_simulation(args, spec)
    q = orthogonal_plan(arm, args.poses)
    rng = np.random.default_rng(args.seed)
    xy = forward_kinematics(arm, q, truth) + rng.normal(0.0, sigma, size=(q.shape[0], 2))
    cal = identify(arm, q, xy, sigma=sigma)
    document = calibration_to_dict(cal)
    lines = [
        f"armcal demo on {arm.name}: {args.poses}-pose orthogonal plan (paper Table I), "
        f"virtual robot with the paper's deviations, noise sigma {sigma:g} mm, seed {args.seed}",
        "",
        format_report(cal, truth=truth),
    ]
    if args.output is not None:
        folder = make_folder(args.output)
        files = {
            "plan.csv": format_plan_csv(q),
            "measurements.csv": format_measurements_csv(q, xy),
            "calibration.json": to_json(document),
        }
        for name, text in files.items():
            atomic_write(folder / name, text)
        lines += ["", f"wrote {', '.join(files)} to {folder}/"]
    _emit(args, document, "\n".join(lines))


# --------------------------------------------------------------------------- parser


def _add_common(
    sub: argparse.ArgumentParser, *, seed: bool = False, output: str | None = None
) -> None:
    sub.add_argument(
        "--robot",
        default=DEFAULT_ROBOT,
        metavar="NAME_OR_FILE",
        help=f"built-in robot name or robot TOML file (default {DEFAULT_ROBOT})",
    )
    if seed:
        sub.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sub.add_argument("--json", action="store_true", help="print a JSON document on stdout")
    if output is not None:
        sub.add_argument("-o", "--output", metavar="PATH", help=output)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``armcal`` program."""
    parser = _Parser(
        prog="armcal",
        description="Design, run and evaluate calibration experiments for planar serial arms.",
    )
    parser.add_argument("--version", action="version", version=f"armcal {__version__}")
    subs = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subs.required = True

    sub = subs.add_parser("synthesize", help="measurements of a virtual robot (truth + noise)")
    sub.add_argument("--plan", required=True, metavar="PLAN_CSV", help="plan CSV (q1_deg..)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument(
        "--sigma",
        type=_non_negative,
        metavar="MM",
        help=f"noise std in mm (default: robot file's sigma_mm, else {DEFAULT_SIGMA_MM})",
    )
    _add_common(sub, seed=True, output="measurements CSV to write (default: stdout)")
    sub.set_defaults(run=_synthesize)

    sub = subs.add_parser("identify", help="parameter deviations ± std from measurements")
    sub.add_argument("--measurements", required=True, metavar="CSV", help="measurements CSV")
    sub.add_argument(
        "--method",
        choices=["auto", *METHODS],
        default="auto",
        help="solver; auto = closed-form, the exact least-squares optimum (default auto)",
    )
    sub.add_argument(
        "--sigma",
        type=_positive,
        metavar="MM",
        help="instrument noise in mm (default: robot file's sigma_mm, else estimated)",
    )
    _add_common(sub, output="calibration JSON to write")
    sub.set_defaults(run=_identify)

    sub = subs.add_parser("demo", help="the whole workflow on a virtual robot")
    sub.add_argument("--poses", type=_poses, default=20, help="number of poses (default 20)")
    sub.add_argument("--truth", metavar="TRUTH_TOML", help="deviations (default: the built-in's)")
    sub.add_argument("--sigma", type=_positive, metavar="MM", help="noise std in mm")
    _add_common(sub, seed=True, output="folder for plan, measurements and calibration")
    sub.set_defaults(run=_demo)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``armcal`` program; returns the exit status."""
    try:
        args = build_parser().parse_args(argv)
        run: Callable[[argparse.Namespace], None] = args.run
        run(args)
    except ArmcalError as exc:
        print(f"armcal: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `armcal synthesize ... | head`
        sys.stderr.close()
        return 0
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
