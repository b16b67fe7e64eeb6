"""What every command does beyond parsing arguments and writing files, as library calls.

A Python user gets the same checks and warnings as the command line:

* :mod:`~armcal.workflow.setup` -- the model a robot file and the options describe
  (``--fix``, ``--sigma``, ``[elastostatic]``), default noise and test poses;
* :mod:`~armcal.workflow.calibration` -- identify from a measurement file (unit
  mistakes, 3-D data, cross-validation), validate, compensate a program;
* :mod:`~armcal.workflow.plan` -- design, evaluate, size, simulate, synthesize.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .calibration import (
        CalibrationRun,
        CompensationRun,
        ExportRun,
        ValidationRun,
        calibrate,
        compensate_program,
        export,
        export_files,
        validate_measurements,
    )
    from .measured import measured_arm, spatial_measured_arm
    from .plan import (
        DesignRun,
        EvaluationRun,
        Synthesis,
        design_plan,
        evaluate_file,
        simulate_plan,
        size_plan,
        synthesize_plan,
    )
    from .setup import (
        DEFAULT_SIGMA_MM,
        FixError,
        design_sigma,
        fit_model,
        model_arm,
        model_spec,
        plan_model,
        prefixed,
        simulation_sigma,
        test_poses,
        with_fixed,
    )

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".calibration": (
                "CalibrationRun",
                "CompensationRun",
                "ExportRun",
                "ValidationRun",
                "calibrate",
                "compensate_program",
                "export",
                "export_files",
                "validate_measurements",
            ),
            ".measured": ("measured_arm", "spatial_measured_arm"),
            ".plan": (
                "DesignRun",
                "EvaluationRun",
                "Synthesis",
                "design_plan",
                "evaluate_file",
                "simulate_plan",
                "size_plan",
                "synthesize_plan",
            ),
            ".setup": (
                "DEFAULT_SIGMA_MM",
                "FixError",
                "design_sigma",
                "fit_model",
                "model_arm",
                "model_spec",
                "plan_model",
                "prefixed",
                "simulation_sigma",
                "test_poses",
                "with_fixed",
            ),
        },
    )

__all__ = [
    "DEFAULT_SIGMA_MM",
    "CalibrationRun",
    "CompensationRun",
    "DesignRun",
    "EvaluationRun",
    "ExportRun",
    "FixError",
    "Synthesis",
    "ValidationRun",
    "calibrate",
    "compensate_program",
    "design_plan",
    "design_sigma",
    "evaluate_file",
    "export",
    "export_files",
    "fit_model",
    "measured_arm",
    "model_arm",
    "model_spec",
    "plan_model",
    "prefixed",
    "simulate_plan",
    "simulation_sigma",
    "size_plan",
    "spatial_measured_arm",
    "synthesize_plan",
    "test_poses",
    "validate_measurements",
    "with_fixed",
]
