"""armcal: design, run and evaluate geometric calibration experiments for planar arms.

The public API (see each module for details):

* :mod:`armcal.arm` -- :class:`PlanarArm`, forward kinematics, Jacobians;
* :mod:`armcal.identify` -- :func:`identify` (closed form and Gauss-Newton) and
  the :class:`Calibration` result;
* :mod:`armcal.design` -- plan constructors;
* :mod:`armcal.simulate` -- batched Monte Carlo, random-plan studies, poses-needed;
* :mod:`armcal.reproduce` -- the paper's tables and figures recomputed;
* :mod:`armcal.io` -- robot, truth, plan, measurement and calibration files.

Importing armcal prints nothing, plots nothing and does not import matplotlib.
"""

from ._version import __version__
from .arm import (
    Annulus,
    Box,
    PlanarArm,
    forward_kinematics,
    jacobian,
    link_angles,
    paper_from_user_matrix,
    wrap_angle,
)
from .design import orthogonal_plan, random_plan
from .errors import ArmcalError, InputError, NotIdentifiableError
from .identify import (
    Calibration,
    check_identifiable,
    format_report,
    identifiability,
    identify,
    solve_closed_form,
    solve_gauss_newton,
)
from .io import load_robot, load_truth, read_measurements, read_plan
from .simulate import (
    MonteCarlo,
    PlanStudy,
    PosesNeeded,
    monte_carlo,
    poses_needed,
    random_plan_study,
)

__all__ = [
    "Annulus",
    "ArmcalError",
    "Box",
    "Calibration",
    "InputError",
    "MonteCarlo",
    "NotIdentifiableError",
    "PlanStudy",
    "PlanarArm",
    "PosesNeeded",
    "__version__",
    "check_identifiable",
    "format_report",
    "forward_kinematics",
    "identifiability",
    "identify",
    "jacobian",
    "link_angles",
    "load_robot",
    "load_truth",
    "monte_carlo",
    "orthogonal_plan",
    "paper_from_user_matrix",
    "poses_needed",
    "random_plan",
    "random_plan_study",
    "read_measurements",
    "read_plan",
    "solve_closed_form",
    "solve_gauss_newton",
    "wrap_angle",
]
