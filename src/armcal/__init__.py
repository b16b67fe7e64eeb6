"""armcal: design, run and evaluate geometric calibration experiments for planar arms.

The public API, by concern (each module's docstring says more):

* :mod:`armcal.arm` -- :class:`PlanarArm`, forward kinematics, Jacobians, regions;
* :mod:`armcal.criteria` -- information matrix, design criteria (:data:`CRITERIA`),
  identifiability, predicted accuracy, :func:`evaluate_plan`;
* :mod:`armcal.doe` -- plans: :func:`design`, :func:`certify`, :func:`poses_needed`;
* :mod:`armcal.identification` -- :func:`identify` and its :class:`Calibration`;
* :mod:`armcal.instrument` -- 3-D instrument data: :func:`identify_3d` in the fitted
  :class:`~armcal.plane.Plane`;
* :mod:`armcal.compensate` -- :func:`validate` on held-out poses, :func:`cross_validate`,
  :func:`compensate` a program, from a :class:`CalibratedArm`;
* :mod:`armcal.export` -- :func:`robot_toml` and :func:`urdf` of a calibrated arm;
* :mod:`armcal.simulate` -- :func:`synthesize_measurements`, batched
  :func:`monte_carlo`, :func:`random_plan_study`;
* :mod:`armcal.reproduction` -- the paper's tables and figures recomputed;
* :mod:`armcal.report` -- every result as text and as JSON;
* :mod:`armcal.io` -- robot, truth, plan and measurement files.

Importing armcal prints nothing, plots nothing and imports neither matplotlib
nor scipy.
"""

from ._version import __version__
from .compensate import (
    Compensation,
    CrossValidation,
    Validation,
    compensate,
    cross_validate,
    validate,
)
from .criteria import (
    CRITERIA,
    PlanQuality,
    d_efficiency,
    evaluate_plan,
    position_accuracy,
    predicted_std,
)
from .diagnostics import GoodnessOfFit, Outlier
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
from .errors import ArmcalError, InputError, NotIdentifiableError
from .export import robot_toml, urdf
from .identification import (
    Calibration,
    identify,
    solve_closed_form,
    solve_gauss_newton,
    solve_model,
)
from .instrument import identify_3d
from .io import load_robot, load_truth, read_calibration, read_measurements, read_plan
from .models import (
    Annulus,
    Box,
    CalibratedArm,
    Identifiability,
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
from .noise import NoiseModel
from .report import format_calibration
from .simulate import (
    MonteCarlo,
    PlanStudy,
    monte_carlo,
    random_plan_study,
    synthesize_measurements,
)

__all__ = [
    "CRITERIA",
    "Annulus",
    "ArmcalError",
    "Box",
    "CalibratedArm",
    "Calibration",
    "Certificate",
    "Compensation",
    "CrossValidation",
    "Design",
    "GoodnessOfFit",
    "Identifiability",
    "InputError",
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
    "certify",
    "check_identifiable",
    "compensate",
    "cross_validate",
    "d_efficiency",
    "design",
    "evaluate_plan",
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
    "solve_closed_form",
    "solve_gauss_newton",
    "solve_model",
    "synthesize_measurements",
    "urdf",
    "validate",
    "wrap_angle",
]
