"""The families of arm armcal fits, and what every family shares.

* :mod:`~armcal.models.regions` -- where the instrument measures;
* :mod:`~armcal.models.planar_geometry`, :mod:`~armcal.models.planar_kinematics`,
  :mod:`~armcal.models.planar` -- the paper's planar arm (:class:`PlanarArm`);
* :mod:`~armcal.models.planar_information` -- the planar arm's scaled Jacobian,
  identifiability and its words;
* :mod:`~armcal.models.compliance` -- joint compliance under gravity and load;
* :mod:`~armcal.models.plane` -- the plane of motion of 3-D data;
* :mod:`~armcal.models.calibrated` -- an arm with its identified deviations.
"""

from .calibrated import BASE_POSE, CalibratedArm
from .compliance import (
    STANDARD_GRAVITY,
    Compliance,
    Elastostatic,
    Loads,
    barely_identifiable_warning,
    check_compliance_identifiable,
    compliance_identifiability,
)
from .planar import PlanarArm
from .planar_geometry import (
    PlanarGeometry,
    Target,
    link_angles,
    paper_from_user,
    paper_from_user_matrix,
    split_params,
    standard_joint_map,
    wrap_angle,
)
from .planar_information import (
    Identifiability,
    check_identifiable,
    combination,
    conditioning_warning,
    every_target,
    identifiability,
    listing,
    model_basis,
    model_columns,
    plan_rows,
    plan_svd,
    row_echelon,
    scaled_columns,
    scaled_jacobian,
    target_weights,
    user_from_scaled,
)
from .planar_kinematics import (
    Parametrization,
    check_target,
    forward_kinematics,
    jacobian,
    joint_jacobian,
    link_phasors,
    link_units,
    link_vectors,
    tool_angles,
)
from .plane import Plane, fit_plane
from .regions import Annulus, Box, Region

__all__ = [
    "BASE_POSE",
    "STANDARD_GRAVITY",
    "Annulus",
    "Box",
    "CalibratedArm",
    "Compliance",
    "Elastostatic",
    "Identifiability",
    "Loads",
    "Parametrization",
    "PlanarArm",
    "PlanarGeometry",
    "Plane",
    "Region",
    "Target",
    "barely_identifiable_warning",
    "check_compliance_identifiable",
    "check_identifiable",
    "check_target",
    "combination",
    "compliance_identifiability",
    "conditioning_warning",
    "every_target",
    "fit_plane",
    "forward_kinematics",
    "identifiability",
    "jacobian",
    "joint_jacobian",
    "link_angles",
    "link_phasors",
    "link_units",
    "link_vectors",
    "listing",
    "model_basis",
    "model_columns",
    "paper_from_user",
    "paper_from_user_matrix",
    "plan_rows",
    "plan_svd",
    "row_echelon",
    "scaled_columns",
    "scaled_jacobian",
    "split_params",
    "standard_joint_map",
    "target_weights",
    "tool_angles",
    "user_from_scaled",
    "wrap_angle",
]
