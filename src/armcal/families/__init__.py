"""The families of arm at the edge: where loading, the calibration file, export,
pictures, the report's words and the demo find each family's own pieces.

:mod:`~armcal.families.registry` holds the :class:`Family` records and the
lookups; this module registers the built-in families, planar and spatial, whose
roles live in the modules they name, beside the work each role does: the
family's robot and truth files in :mod:`armcal.files`, its calibration-file
sections, its exports, its pictures and its demo.  A new family registers a :class:`Family` of its
own (``armcal.families.register``); the middle of armcal needs nothing but its
fit model.
"""

from .registry import (
    ROLES,
    Family,
    RobotSpec,
    builtin_robots,
    families,
    family_for,
    family_named,
    family_of,
    load_robot,
    register,
    run_demo,
    unregister,
)

PLANAR = register(
    Family(
        "planar",
        "a planar arm in its plane (the paper's family), rigid or with joint compliance",
        "a planar robot TOML (link_lengths_mm ...)",
        fallback=True,
        refs={
            "builtins": "armcal.paper:BUILTIN_ROBOTS",
            "load_robot": "armcal.files.robots:load_planar_robot",
            "truth": "armcal.files.robots:planar_truth",
            "encode": "armcal.files.calibration_planar:encode",
            "decode": "armcal.files.calibration_planar:decode",
            "encode_effect": "armcal.files.calibration_planar:encode_effect",
            "decode_effect": "armcal.files.calibration_planar:decode_effect",
            "calibrate": "armcal.workflow.measured:fit_planar",
            "exports": "armcal.export_planar:planar_exports",
            "coupled_urdf": "armcal.export_planar:planar_coupled_urdf",
            "describe": "armcal.report.common:planar_model_lines",
            "plan_figure": "armcal.plotting:planar_plan_figure",
            "residual_figure": "armcal.plotting_residuals:residual_figure",
            "demo": "armcal.demo:planar_demo",
        },
    )
)

SPATIAL = register(
    Family(
        "spatial",
        "a serial arm in 3-D (a six-axis industrial arm, a cobot), rigid or with joint compliance",
        "a URDF (the chain between a base and a tip link), or a robot TOML with urdf, [mdh], "
        "[dh] or [ur]",
        aliases=("serial",),
        refs={
            "builtins": "armcal.files.spatial:BUILTIN_SPATIAL_ROBOTS",
            "claims": "armcal.files.spatial:is_spatial_robot",
            "load_robot": "armcal.files.spatial:load_spatial_robot",
            "truth": "armcal.files.spatial:spatial_truth",
            "encode": "armcal.files.calibration_spatial:encode",
            "decode": "armcal.files.calibration_spatial:decode",
            "encode_effect": "armcal.files.calibration_spatial:encode_effect",
            "decode_effect": "armcal.files.calibration_spatial:decode_effect",
            "calibrate": "armcal.workflow.measured:fit_spatial",
            "exports": "armcal.export_spatial:spatial_exports",
            "controller_files": "armcal.files.ur:ur_texts",
            "coupled_urdf": "armcal.export_spatial:spatial_coupled_urdf",
            "calibrated_origins": "armcal.files.urdf_origins:calibrated_origins",
            "describe": "armcal.report.common:spatial_model_lines",
            "plan_figure": "armcal.plotting_spatial:spatial_plan_figure",
            "residual_figure": "armcal.plotting_residuals:residual_figure",
            "demo": "armcal.demo_spatial:spatial_demo",
        },
    )
)

INSTRUMENTED = register(
    Family(
        "instrumented",
        "an arm of another family measured by touches of planes, seatings in fixed points "
        "or distances from a pivot",
        "a robot file of another family with [instrument] kind plane, point or distance",
        refs={
            "truth": "armcal.files.instrument_table:instrumented_truth",
            "encode": "armcal.files.calibration_instrumented:encode",
            "decode": "armcal.files.calibration_instrumented:decode",
            "calibrate": "armcal.workflow.measured:fit_instrumented",
            "describe": "armcal.report.common:instrumented_model_lines",
            "plan_figure": "armcal.plotting_spatial:spatial_plan_figure",
            "residual_figure": "armcal.plotting_residuals:residual_figure",
        },
    )
)

__all__ = [
    "INSTRUMENTED",
    "PLANAR",
    "ROLES",
    "SPATIAL",
    "Family",
    "RobotSpec",
    "builtin_robots",
    "families",
    "family_for",
    "family_named",
    "family_of",
    "load_robot",
    "register",
    "run_demo",
    "unregister",
]
