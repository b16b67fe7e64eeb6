"""The spatial family: a serial arm in 3-D from a URDF or a modified DH table.

* :mod:`~armcal.models.spatial.chain`, :mod:`~armcal.models.spatial.dh` -- the nominal
  chain, and the same chain as an exact modified DH table;
* :mod:`~armcal.models.spatial.kinematics` -- parameters, points and analytic Jacobians;
* :mod:`~armcal.models.spatial.selection` -- the identifiable set, chosen and explained;
* :mod:`~armcal.models.spatial.registration` -- base pose and targets from the data;
* :mod:`~armcal.models.spatial.pose` -- a 6-DoF instrument's orientations;
* :mod:`~armcal.models.spatial.view`, :mod:`~armcal.models.spatial.gradient` -- what
  the instrument can measure, and how a design's information changes with the poses;
* :mod:`~armcal.models.spatial.arm` -- the fit model
  (:class:`~armcal.models.spatial.arm.SpatialArm`);
* :mod:`~armcal.models.spatial.gravity`, :mod:`~armcal.models.spatial.compliance` --
  joints twisting under gravity and payload
  (:class:`~armcal.models.spatial.compliance.CompliantSpatialArm`).
"""
