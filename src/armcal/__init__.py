"""armcal: design, run and evaluate geometric calibration experiments for robot arms.

Every family of arm -- a planar arm, a spatial serial arm (a six-axis arm from a
URDF or a DH table), either with joint compliance -- goes through the same
calls: :func:`load_robot` takes any robot description, and :func:`design`,
:func:`evaluate_plan`, :func:`synthesize_measurements`, :func:`identify`,
:func:`validate`, :func:`compensate` and :func:`monte_carlo` take its arm.

The public API, by concern (each module's docstring says more):

* :mod:`armcal.models` -- the fit-model interface every family of arm implements
  (:class:`FitModel`), the planar arm (:class:`PlanarArm`: forward kinematics,
  Jacobians, regions), the spatial arm (:class:`SpatialArm`), joint compliance
  (:class:`CompliantArm`, :class:`CompliantSpatialArm`), the calibrated arm
  (:class:`CalibratedArm`);
* :mod:`armcal.families` -- the family registry: each family's robot files,
  calibration-file sections, exports, pictures and demo (:func:`load_robot`);
* :mod:`armcal.criteria` -- design criteria (:data:`CRITERIA`), predicted accuracy,
  :func:`evaluate_plan`;
* :mod:`armcal.doe` -- plans: :func:`design`, :func:`certify`, :func:`poses_needed`;
* :mod:`armcal.identification` -- :func:`identify` and its :class:`Calibration`;
* :mod:`armcal.instrument` -- 3-D instrument data: :func:`identify_3d` in the fitted
  :class:`Plane`;
* :mod:`armcal.validation` -- :func:`validate` on held-out poses, :func:`cross_validate`;
* :mod:`armcal.compensation` -- :func:`compensate` a program;
* :mod:`armcal.export_planar`, :mod:`armcal.export_spatial` -- a calibrated arm's robot
  TOML and URDF (:func:`export` writes either family's);
* :mod:`armcal.synthesis` and :mod:`armcal.simulate` -- :func:`synthesize_measurements`,
  batched :func:`monte_carlo`;
* :mod:`armcal.workflow` -- what each command does beyond its files, as library
  calls with the command line's checks and warnings (:func:`~armcal.workflow.calibrate`);
* :mod:`armcal.reproduction` -- the paper's tables and figures recomputed;
* :mod:`armcal.report` -- every result as text and as JSON;
* :mod:`armcal.files` -- robot, truth, plan, measurement and calibration files.

Importing armcal prints nothing, plots nothing and imports none of numpy, matplotlib
and scipy: each name imports its module the first time it is used (``armcal.identify``
imports the identification, not the design).
"""

from typing import TYPE_CHECKING

from ._version import __version__
from .lazy import exports

if TYPE_CHECKING:
    from .compensation import Compensation, compensate
    from .criteria import (
        CRITERIA,
        PlanQuality,
        d_efficiency,
        evaluate_plan,
        position_accuracy,
        predicted_std,
    )
    from .doe import (
        Certificate,
        Design,
        PosesNeeded,
        certify,
        design,
        orthogonal_plan,
        poses_needed,
        random_plan,
    )
    from .errors import ArmcalError, ArmcalWarning, InputError, NotIdentifiableError
    from .export_planar import robot_toml, urdf
    from .families import run_demo
    from .files import load_robot, load_truth, read_calibration, read_measurements, read_plan
    from .identification import Calibration, Estimate, GoodnessOfFit, Outlier, identify, solve
    from .instrument import identify_3d
    from .models import (
        Annulus,
        Box,
        CalibratedArm,
        CompliantArm,
        Conditions,
        Elastostatic,
        FitModel,
        Identifiability,
        Loads,
        PlanarArm,
        Plane,
        Target,
        check_identifiable,
        fit_plane,
        forward_kinematics,
        identifiability,
        jacobian,
        joint_jacobian,
        link_angles,
        paper_from_user_matrix,
        wrap_angle,
    )
    from .models.planar.closed_form import solve_closed_form
    from .noise import NoiseModel
    from .report import format_calibration
    from .reproduction.algorithm import solve_gauss_newton
    from .reproduction.study import PlanStudy, random_plan_study
    from .simulate import MonteCarlo, monte_carlo
    from .synthesis import synthesize_measurements
    from .validation import CrossValidation, Validation, cross_validate, validate
    from .workflow import calibrate, export

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".compensation": ("Compensation", "compensate"),
            ".criteria": (
                "CRITERIA",
                "PlanQuality",
                "d_efficiency",
                "evaluate_plan",
                "position_accuracy",
                "predicted_std",
            ),
            ".doe": (
                "Certificate",
                "Design",
                "PosesNeeded",
                "certify",
                "design",
                "orthogonal_plan",
                "poses_needed",
                "random_plan",
            ),
            ".errors": ("ArmcalError", "ArmcalWarning", "InputError", "NotIdentifiableError"),
            ".export_planar": ("robot_toml", "urdf"),
            ".families": ("run_demo",),
            ".files": (
                "load_robot",
                "load_truth",
                "read_calibration",
                "read_measurements",
                "read_plan",
            ),
            ".identification": (
                "Calibration",
                "Estimate",
                "GoodnessOfFit",
                "Outlier",
                "identify",
                "solve",
            ),
            ".instrument": ("identify_3d",),
            ".models": (
                "Annulus",
                "Box",
                "CalibratedArm",
                "CompliantArm",
                "Conditions",
                "Elastostatic",
                "FitModel",
                "Identifiability",
                "Loads",
                "PlanarArm",
                "Plane",
                "Target",
                "check_identifiable",
                "fit_plane",
                "forward_kinematics",
                "identifiability",
                "jacobian",
                "joint_jacobian",
                "link_angles",
                "paper_from_user_matrix",
                "wrap_angle",
            ),
            ".models.planar.closed_form": ("solve_closed_form",),
            ".noise": ("NoiseModel",),
            ".report": ("format_calibration",),
            ".reproduction.algorithm": ("solve_gauss_newton",),
            ".reproduction.study": ("PlanStudy", "random_plan_study"),
            ".simulate": ("MonteCarlo", "monte_carlo"),
            ".synthesis": ("synthesize_measurements",),
            ".validation": ("CrossValidation", "Validation", "cross_validate", "validate"),
            ".workflow": ("calibrate", "export"),
        },
    )

__all__ = [
    "CRITERIA",
    "Annulus",
    "ArmcalError",
    "ArmcalWarning",
    "Box",
    "CalibratedArm",
    "Calibration",
    "Certificate",
    "Compensation",
    "CompliantArm",
    "Conditions",
    "CrossValidation",
    "Design",
    "Elastostatic",
    "Estimate",
    "FitModel",
    "GoodnessOfFit",
    "Identifiability",
    "InputError",
    "Loads",
    "MonteCarlo",
    "NoiseModel",
    "NotIdentifiableError",
    "Outlier",
    "PlanQuality",
    "PlanStudy",
    "PlanarArm",
    "Plane",
    "PosesNeeded",
    "Target",
    "Validation",
    "__version__",
    "calibrate",
    "certify",
    "check_identifiable",
    "compensate",
    "cross_validate",
    "d_efficiency",
    "design",
    "evaluate_plan",
    "export",
    "fit_plane",
    "format_calibration",
    "forward_kinematics",
    "identifiability",
    "identify",
    "identify_3d",
    "jacobian",
    "joint_jacobian",
    "link_angles",
    "load_robot",
    "load_truth",
    "monte_carlo",
    "orthogonal_plan",
    "paper_from_user_matrix",
    "poses_needed",
    "position_accuracy",
    "predicted_std",
    "random_plan",
    "random_plan_study",
    "read_calibration",
    "read_measurements",
    "read_plan",
    "robot_toml",
    "run_demo",
    "solve",
    "solve_closed_form",
    "solve_gauss_newton",
    "synthesize_measurements",
    "urdf",
    "validate",
    "wrap_angle",
]
