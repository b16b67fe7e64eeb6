"""Instruments other than a tracker: what each reports of the tool, and its unknowns.

An **instrument** maps the tool point, in the robot's base frame, to what it
reports, with unknown parameters of its own (nuisance, identified with the arm)
and its own noise (PRODUCT.md, "Instruments").  Each is a measurement equation
with its analytic derivatives (:class:`~armcal.instruments.base.Instrument`):

* :class:`~armcal.instruments.plane.Planes`: the tool point touches one of
  several planes; a row reports its signed distance from the plane (0 on a
  touch), mm.  Unknowns: every plane's normal and offset.
* :class:`~armcal.instruments.point.FixedPoints`: the tool point sits in one of
  several fixed points (a cone, a ball socket); a row reports its offset from
  the point (0 when seated), mm.  Unknowns: every point's position.
* :class:`~armcal.instruments.distance.Distance`: a ballbar or a draw-wire
  sensor reads the tool point's distance from a pivot, less an offset, mm.
  Unknowns: the pivot's position and the offset.
* :class:`~armcal.instruments.partial.Coordinates`: partial coordinates, some of
  the tool point's coordinates in the instrument's frame (a dial indicator, a
  displacement sensor) and of the tool's turn (a 6-DoF probe with gaps), each a
  number of its own.  Unknowns: the instrument's pose, and the tool's axes where it
  reads a turn.
* :class:`~armcal.instruments.camera.Camera`: the pixels of a checkerboard's
  corners, the camera on the tool or the board on it.  Unknowns: the camera's pose
  and the board's (hand-eye calibration with the arm's).

:class:`~armcal.models.instrumented.InstrumentedArm` puts an instrument on any
arm of the model interface: identification, simulation and validation then
work through it as for a tracker.
"""

from .base import Instrument, unseen_words
from .camera import Board, Camera, Intrinsics
from .distance import Distance
from .partial import Coordinates
from .plane import Plane, Planes
from .point import FixedPoints

__all__ = [
    "Board",
    "Camera",
    "Coordinates",
    "Distance",
    "FixedPoints",
    "Instrument",
    "Intrinsics",
    "Plane",
    "Planes",
    "unseen_words",
]
