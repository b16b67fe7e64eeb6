"""The paper's robots, deviations and printed numbers, as data.

Klimchik et al., *Design of Experiments for Calibration of Planar Anthropomorphic
Manipulators*, Sections V-VI: the 2-, 3- and 4-link arms, their true
deviations, the noise of the simulation study and the values printed in
Table III and the text.  The printed values are kept for comparison only
(:mod:`armcal.reproduction`); nothing is computed from them.
"""

from __future__ import annotations

import numpy as np

from .choices import BUILTIN_ROBOTS
from .models import PlanarArm

__all__ = [
    "BUILTIN_ROBOTS",
    "PAPER_100_POSE_ANGLES_DEG",
    "PAPER_DIGIT",
    "PAPER_DL_MM",
    "PAPER_DQ_DEG",
    "PAPER_FIGURE1_POSES",
    "PAPER_GOAL_LENGTH_MM",
    "PAPER_GOAL_POSES",
    "PAPER_LINK_LENGTHS_MM",
    "PAPER_RANGE_LENGTH_MM",
    "PAPER_RANGE_POSES",
    "PAPER_SIGMA_MM",
    "PAPER_TABLE3",
    "paper_arm",
]


#: The paper's arms (Sections V-VI): lengths in mm and the deviations used as truth.
PAPER_LINK_LENGTHS_MM = (260.0, 180.0, 120.0, 100.0)
PAPER_DL_MM = (1.5, -0.6, -0.4, 0.7)
PAPER_DQ_DEG = (0.5, -0.5, 0.7, -0.3)


#: Section VI: measurement noise, 1 std per coordinate.
PAPER_SIGMA_MM = 0.1


#: Table III as printed (mm for dL, deg for "dq"), by (links, poses) -- for comparison only.
PAPER_TABLE3: dict[tuple[int, int], dict[str, tuple[float, ...]]] = {
    (2, 3): {"dl": (0.058, 0.058), "dq": (0.013, 0.018)},
    (2, 20): {"dl": (0.058, 0.058), "dq": (0.005, 0.007)},
    (3, 3): {"dl": (0.058, 0.058, 0.058), "dq": (0.013, 0.018, 0.027)},
    (3, 20): {"dl": (0.022, 0.022, 0.022), "dq": (0.005, 0.007, 0.011)},
    (4, 3): {"dl": (0.058,) * 4, "dq": (0.013, 0.018, 0.027, 0.033)},
    (4, 20): {"dl": (0.022,) * 4, "dq": (0.005, 0.007, 0.011, 0.013)},
}


#: A printed value agrees when within one unit of its last printed digit.
PAPER_DIGIT = 0.001


#: Section V: Figure 1 is drawn for random plans of 10 poses.
PAPER_FIGURE1_POSES = 10


#: Section VI: "the identification error reduces from 0.022 mm to 0.005 mm while the
#: experiment number increases from 4 to 20" (4-link arm).
PAPER_RANGE_POSES = (4, 20)
PAPER_RANGE_LENGTH_MM = (0.022, 0.005)


#: Section VI: "to satisfy an accuracy of 0.001 mm for linear parameters it is required
#: to carry out 100 experiments, which will provide accuracy for angular parameters
#: 0.002, 0.003, 0.005 and 0.006 deg".
PAPER_GOAL_LENGTH_MM = 0.001
PAPER_GOAL_POSES = 100
PAPER_100_POSE_ANGLES_DEG = (0.002, 0.003, 0.005, 0.006)


def paper_arm(n: int) -> tuple[PlanarArm, np.ndarray]:
    """The paper's ``n``-link arm (``n`` = 2, 3, 4) and its true deviations (mm, rad).

    Examples
    --------
    >>> arm, truth = paper_arm(2)
    >>> arm.name, arm.link_lengths.tolist(), np.degrees(truth[2:]).round(6).tolist()
    ('paper-2link', [260.0, 180.0], [0.5, -0.5])
    """
    if n not in BUILTIN_ROBOTS.values():
        raise ValueError(f"the paper has 2-, 3- and 4-link arms, not {n}")
    arm = PlanarArm(np.array(PAPER_LINK_LENGTHS_MM[:n]), name=f"paper-{n}link")
    return arm, arm.params_from_display(np.array(PAPER_DL_MM[:n]), np.array(PAPER_DQ_DEG[:n]))
