"""The values options take, their defaults and the built-in robots' names, named once.

The modules that act on these values import them from here and keep them under
their own names (:data:`armcal.doe.METHODS` is :data:`DESIGN_METHODS`); the
command line's parser and help import only this module, so that ``armcal --help``
and ``armcal design --help`` import none of the numerics behind the choices they
list.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "BUILTIN_ROBOTS",
    "BUILTIN_SPATIAL_ROBOTS",
    "CRITERION_NAMES",
    "DEFAULT_ROBOT",
    "DEFAULT_SIGMA_MM",
    "DESIGN_METHODS",
    "DISTINCT_TOLERANCE",
    "IDENTIFY_METHODS",
    "ORDERS",
    "PLANAR_DEMO_POSES",
    "REQUIREMENTS",
    "ROBOT_FOLDER",
    "SIGMA_RANGE_MM",
    "SPATIAL_DEMO_POSES",
    "TASK_CRITERIA",
]

# --------------------------------------------------------------------------- design

#: The design criteria by name: the keys of :data:`armcal.criteria.CRITERIA`, which holds
#: each one's efficiency and gradient.
CRITERION_NAMES = ("D", "A", "E")

#: What each task criterion is, for help texts and reports (:mod:`armcal.doe.task`).
TASK_CRITERIA = {
    "I": "I-efficiency tr(L) / tr(Fs^-1 L): the mean predicted position variance after "
    "calibration over the test poses (Box and Draper 1959)",
    "G": "G-efficiency: the largest predicted position variance after calibration over the "
    "test poses (Kiefer and Wolfowitz 1960)",
}

#: How a plan's poses are ordered (:data:`armcal.doe.order.Order`): ``travel`` for short
#: joint travel, ``none`` for the order the design method produced.
ORDERS = ("travel", "none")

#: Two poses are one pose when every joint angle agrees within this many rad (0.2
#: arcsec: far below any arm's repeatability, so the robot would measure them as one):
#: :func:`armcal.doe.plans.repeated_poses`, a design's ``distinct``.
DISTINCT_TOLERANCE = 1e-6

#: How :func:`armcal.doe.design` makes a plan (``method``).
DESIGN_METHODS = ("auto", "analytic", "optimize", "exchange")

#: Accuracy requirements of :func:`armcal.doe.poses_needed`: what each measures, in which
#: unit.
REQUIREMENTS: dict[str, str] = {
    "length_std_mm": "largest std of a length of the arm itself (mm)",
    "angle_std_deg": "largest std of an angle of the arm itself (deg)",
    "position_rms_mm": (
        "predicted RMS tip error per point after calibration at the test poses (mm)"
    ),
}

#: Noise assumed for design and simulation when neither --sigma nor the robot file gives it.
DEFAULT_SIGMA_MM = 0.1

# --------------------------------------------------------------------------- identification

#: The solvers of :func:`armcal.identify` by name (``"auto"`` chooses one,
#: :func:`armcal.identification.resolve_method`).
IDENTIFY_METHODS = ("closed-form", "gauss-newton")

#: Instrument noise accepted (1 std, mm): from a nanometre to a metre.  Beyond it the
#: value is a unit mistake, and its square under- or overflows in the covariance.
SIGMA_RANGE_MM = (1e-6, 1e3)

# --------------------------------------------------------------------------- robots

#: Built-in planar robot names and their number of links (the paper's arms,
#: :mod:`armcal.paper`).
BUILTIN_ROBOTS = {f"paper-{n}link": n for n in (2, 3, 4)}

#: The folder of the built-in spatial robots' files.
ROBOT_FOLDER = Path(__file__).resolve().parent / "robots"

#: Built-in spatial robots by name: the robot file each is (:mod:`armcal.files.spatial`).
BUILTIN_SPATIAL_ROBOTS = {
    "industrial-6r": ROBOT_FOLDER / "industrial-6r.toml",
    "cobot-6r": ROBOT_FOLDER / "cobot-6r.toml",
    "arm-7r": ROBOT_FOLDER / "arm-7r.toml",
}

#: The robot used when a command is given none.
DEFAULT_ROBOT = "paper-4link"

# --------------------------------------------------------------------------- the demos

#: Poses of the planar demo's designed plan (:mod:`armcal.demo`).
PLANAR_DEMO_POSES = 20

#: Poses of the spatial demo's plan, each measured at three reflectors
#: (:mod:`armcal.demo_spatial`).
SPATIAL_DEMO_POSES = 60
