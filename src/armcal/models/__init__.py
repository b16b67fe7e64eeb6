"""The families of arm armcal fits, and what every family shares.

* :mod:`~armcal.models.regions` -- where the instrument measures;
* :mod:`~armcal.models.planar.geometry`, :mod:`~armcal.models.planar.kinematics`,
  :mod:`~armcal.models.planar.arm` -- the paper's planar arm (:class:`PlanarArm`);
* :mod:`~armcal.models.planar.information` -- the planar arm's scaled Jacobian,
  identifiability and its words;
* :mod:`~armcal.models.planar.design`, :mod:`~armcal.models.planar.plans`,
  :mod:`~armcal.models.planar.criteria` -- the planar arm's design view, the
  paper's closed-form plans and its own criteria (D*, Table I);
* :mod:`~armcal.models.planar.compliance` -- joint compliance under gravity and load;
* :mod:`~armcal.models.spatial.chain`, :mod:`~armcal.models.spatial.dh`,
  :mod:`~armcal.models.spatial.kinematics`, :mod:`~armcal.models.spatial.selection`,
  :mod:`~armcal.models.spatial.registration`, :mod:`~armcal.models.spatial.arm` -- a spatial
  serial arm (:class:`SpatialArm`) from a URDF or a modified DH table;
* :mod:`~armcal.models.spatial.gravity`, :mod:`~armcal.models.spatial.compliance` --
  its joints twisting under gravity and payload (:class:`CompliantSpatialArm`);
* :mod:`~armcal.models.instrumented` -- an arm measured by another instrument than a
  tracker (:class:`InstrumentedArm`: planes touched, fixed points);
* :mod:`~armcal.models.plane` -- the plane of motion of 3-D data;
* :mod:`~armcal.models.joint_maps` -- the one check of a joint map, every family's;
* :mod:`~armcal.models.calibrated` -- an arm with its identified deviations;
* :mod:`~armcal.models.wording` -- the interface's data in words, every family's.
"""

import importlib
from typing import TYPE_CHECKING

from ..lazy import exports

# ``identifiability`` names both a module of this package and the planar arm's function
# this package exports.  Importing a module binds it on its package the first time only:
# import the module now and unbind it, so that the name stays the function's (found on
# first use, as every name below) whatever imports the module later.
importlib.import_module(".identifiability", __name__)
del globals()["identifiability"]

if TYPE_CHECKING:
    from .calibrated import CalibratedArm
    from .defaults import LARGE_ANGLE_DEG, TermChoice
    from .identifiability import Identifiability, combination, listing, row_echelon
    from .instrumented import InstrumentedArm
    from .interface import (
        ROW_BLOCK,
        ClosedForm,
        ClosedFormPlan,
        ClosedFormPlans,
        Conditions,
        DesignEffort,
        DeviationBounds,
        Effect,
        FitModel,
        Held,
        LinearPositions,
        Loads,
        PaperCriteria,
        PlanInformation,
        UnpredictedLoads,
        equations_per_pose,
        position_jacobian,
    )
    from .joint_maps import checked_joint_map
    from .planar.arm import INSTRUMENT_PARAMS, LARGE_LENGTH_FRACTION, PlanarArm
    from .planar.compliance import (
        STANDARD_GRAVITY,
        CompliantArm,
        Elastostatic,
        check_compliance_identifiable,
        compliance_identifiability,
    )
    from .planar.geometry import (
        PlanarGeometry,
        Target,
        link_angles,
        paper_from_user,
        paper_from_user_matrix,
        split_params,
        standard_joint_map,
        wrap_angle,
    )
    from .planar.information import (
        check_identifiable,
        covariance_factor,
        every_target,
        identifiability,
        model_basis,
        model_columns,
        plan_rows,
        plan_svd,
        scaled_columns,
        scaled_jacobian,
        target_weights,
        unit_trace,
        user_from_scaled,
        weighted_user_jacobian,
    )
    from .planar.kinematics import (
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
    from .spatial.arm import SINGLE_TARGET, SpatialArm
    from .spatial.chain import (
        SerialChain,
        UrdfJoint,
        matrix_rpy,
        rotation_vector,
        rpy_matrix,
        transform,
        vector_rotation,
    )
    from .spatial.compliance import CompliantSpatialArm, SpatialElastics
    from .spatial.dh import MdhTable, mdh_table
    from .spatial.gravity import LinkMasses
    from .spatial.kinematics import LARGE_PLACEMENT_FRACTION, SpatialLayout, default_targets
    from .spatial.selection import Selection
    from .spatial.view import SpatialView

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".calibrated": ("CalibratedArm",),
            ".defaults": ("LARGE_ANGLE_DEG", "TermChoice"),
            ".identifiability": ("Identifiability", "combination", "listing", "row_echelon"),
            ".interface": (
                "ROW_BLOCK",
                "ClosedForm",
                "ClosedFormPlan",
                "ClosedFormPlans",
                "Conditions",
                "DesignEffort",
                "DeviationBounds",
                "Effect",
                "FitModel",
                "Held",
                "LinearPositions",
                "Loads",
                "PaperCriteria",
                "PlanInformation",
                "UnpredictedLoads",
                "equations_per_pose",
                "position_jacobian",
            ),
            ".joint_maps": ("checked_joint_map",),
            ".planar.arm": ("INSTRUMENT_PARAMS", "LARGE_LENGTH_FRACTION", "PlanarArm"),
            ".planar.compliance": (
                "STANDARD_GRAVITY",
                "CompliantArm",
                "Elastostatic",
                "check_compliance_identifiable",
                "compliance_identifiability",
            ),
            ".planar.geometry": (
                "PlanarGeometry",
                "Target",
                "link_angles",
                "paper_from_user",
                "paper_from_user_matrix",
                "split_params",
                "standard_joint_map",
                "wrap_angle",
            ),
            ".planar.information": (
                "check_identifiable",
                "covariance_factor",
                "every_target",
                "identifiability",
                "model_basis",
                "model_columns",
                "plan_rows",
                "plan_svd",
                "scaled_columns",
                "scaled_jacobian",
                "target_weights",
                "unit_trace",
                "user_from_scaled",
                "weighted_user_jacobian",
            ),
            ".planar.kinematics": (
                "Parametrization",
                "check_target",
                "forward_kinematics",
                "jacobian",
                "joint_jacobian",
                "link_phasors",
                "link_units",
                "link_vectors",
                "tool_angles",
            ),
            ".plane": ("Plane", "fit_plane"),
            ".regions": ("Annulus", "Box", "Region"),
            ".spatial.arm": ("SINGLE_TARGET", "SpatialArm"),
            ".spatial.chain": (
                "SerialChain",
                "UrdfJoint",
                "matrix_rpy",
                "rotation_vector",
                "rpy_matrix",
                "transform",
                "vector_rotation",
            ),
            ".spatial.compliance": ("CompliantSpatialArm", "SpatialElastics"),
            ".instrumented": ("InstrumentedArm",),
            ".spatial.dh": ("MdhTable", "mdh_table"),
            ".spatial.gravity": ("LinkMasses",),
            ".spatial.kinematics": (
                "LARGE_PLACEMENT_FRACTION",
                "SpatialLayout",
                "default_targets",
            ),
            ".spatial.selection": ("Selection",),
            ".spatial.view": ("SpatialView",),
        },
    )

__all__ = [
    "INSTRUMENT_PARAMS",
    "LARGE_ANGLE_DEG",
    "LARGE_LENGTH_FRACTION",
    "LARGE_PLACEMENT_FRACTION",
    "ROW_BLOCK",
    "SINGLE_TARGET",
    "STANDARD_GRAVITY",
    "Annulus",
    "Box",
    "CalibratedArm",
    "ClosedForm",
    "ClosedFormPlan",
    "ClosedFormPlans",
    "CompliantArm",
    "CompliantSpatialArm",
    "Conditions",
    "DesignEffort",
    "DeviationBounds",
    "Effect",
    "Elastostatic",
    "FitModel",
    "Held",
    "Identifiability",
    "InstrumentedArm",
    "LinearPositions",
    "LinkMasses",
    "Loads",
    "MdhTable",
    "PaperCriteria",
    "Parametrization",
    "PlanInformation",
    "PlanarArm",
    "PlanarGeometry",
    "Plane",
    "Region",
    "Selection",
    "SerialChain",
    "SpatialArm",
    "SpatialElastics",
    "SpatialLayout",
    "SpatialView",
    "Target",
    "TermChoice",
    "UnpredictedLoads",
    "UrdfJoint",
    "check_compliance_identifiable",
    "check_identifiable",
    "check_target",
    "checked_joint_map",
    "combination",
    "compliance_identifiability",
    "covariance_factor",
    "default_targets",
    "equations_per_pose",
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
    "matrix_rpy",
    "mdh_table",
    "model_basis",
    "model_columns",
    "paper_from_user",
    "paper_from_user_matrix",
    "plan_rows",
    "plan_svd",
    "position_jacobian",
    "rotation_vector",
    "row_echelon",
    "rpy_matrix",
    "scaled_columns",
    "scaled_jacobian",
    "split_params",
    "standard_joint_map",
    "target_weights",
    "tool_angles",
    "transform",
    "unit_trace",
    "user_from_scaled",
    "vector_rotation",
    "weighted_user_jacobian",
    "wrap_angle",
]
