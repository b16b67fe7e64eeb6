"""Every result as text and JSON: pure functions, one module per result, no numerics.

* :mod:`~armcal.report.common` -- the model in words, number cells, tables;
* :mod:`~armcal.report.calibration` -- a calibration, cross-validation;
* :mod:`~armcal.report.quality` -- a plan's quality (with the payloads where they count);
* :mod:`~armcal.report.design` -- a design, a sizing;
* :mod:`~armcal.report.monte_carlo` -- a Monte Carlo;
* :mod:`~armcal.report.validation` -- validation and compensation;
* :mod:`~armcal.report.reproduction` -- the paper recomputed.

The calibration *file* is written and read by :mod:`armcal.files.calibration`.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .calibration import effect_lines, format_calibration, format_cross_validation
    from .common import model_lines, model_to_dict, table_csv
    from .design import design_summary, poses_needed_summary
    from .monte_carlo import format_monte_carlo, monte_carlo_to_dict
    from .quality import format_quality, quality_report, quality_to_dict
    from .reproduction import format_reproduction, reproduction_summary
    from .validation import acceptance_report, compensation_report, validation_report

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".calibration": ("effect_lines", "format_calibration", "format_cross_validation"),
            ".common": ("model_lines", "model_to_dict", "table_csv"),
            ".design": ("design_summary", "poses_needed_summary"),
            ".monte_carlo": ("format_monte_carlo", "monte_carlo_to_dict"),
            ".quality": ("format_quality", "quality_report", "quality_to_dict"),
            ".reproduction": ("format_reproduction", "reproduction_summary"),
            ".validation": ("acceptance_report", "compensation_report", "validation_report"),
        },
    )

__all__ = [
    "acceptance_report",
    "compensation_report",
    "design_summary",
    "effect_lines",
    "format_calibration",
    "format_cross_validation",
    "format_monte_carlo",
    "format_quality",
    "format_reproduction",
    "model_lines",
    "model_to_dict",
    "monte_carlo_to_dict",
    "poses_needed_summary",
    "quality_report",
    "quality_to_dict",
    "reproduction_summary",
    "table_csv",
    "validation_report",
]
