"""Identification of a model's parameters from measured poses, and the judgement of the fit.

* :mod:`~armcal.identification.problem` -- one problem (model, rows, points) and its fits;
* :mod:`~armcal.identification.solvers` -- the closed form where a family has one, one
  Gauss-Newton loop for every model, the rule behind ``method="auto"``;
* :mod:`~armcal.identification.robust` -- Huber's M-estimator, the outlier test, refits;
* :mod:`~armcal.identification.judgement` -- goodness of fit, outliers, an effect the
  data may not show, and the warnings they give;
* :mod:`~armcal.identification.result` -- :class:`Calibration`, a parameter by name;
* :mod:`~armcal.identification.calibrate` -- :func:`identify`, all of the above.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from .calibrate import identify
    from .judgement import FEW_DOF, FIT_ALPHA, OUTLIER_ALPHA, GoodnessOfFit, Outlier, PoseTest
    from .result import Calibration, Estimate, NestedFit
    from .robust import HUBER_K
    from .solvers import METHODS, Method, Solution, resolve_method, solve

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            ".calibrate": ("identify",),
            ".judgement": (
                "FEW_DOF",
                "FIT_ALPHA",
                "OUTLIER_ALPHA",
                "GoodnessOfFit",
                "Outlier",
                "PoseTest",
            ),
            ".result": ("Calibration", "Estimate", "NestedFit"),
            ".robust": ("HUBER_K",),
            ".solvers": ("METHODS", "Method", "Solution", "resolve_method", "solve"),
        },
    )

__all__ = [
    "FEW_DOF",
    "FIT_ALPHA",
    "HUBER_K",
    "METHODS",
    "OUTLIER_ALPHA",
    "Calibration",
    "Estimate",
    "GoodnessOfFit",
    "Method",
    "NestedFit",
    "Outlier",
    "PoseTest",
    "Solution",
    "identify",
    "resolve_method",
    "solve",
]
