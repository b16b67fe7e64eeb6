"""The planar family: the paper's arm in its plane, rigid or with joint compliance.

* :mod:`~armcal.models.planar.geometry`, :mod:`~armcal.models.planar.kinematics` --
  link vectors, joint map, targets, base pose; forward kinematics and Jacobians;
* :mod:`~armcal.models.planar.spec`, :mod:`~armcal.models.planar.arm` -- the arm's
  description and the fit model users construct (:class:`~armcal.models.planar.arm.PlanarArm`);
* :mod:`~armcal.models.planar.information` -- the scaled Jacobian and identifiability;
* :mod:`~armcal.models.planar.closed_form` -- the global optimum by one linear solve;
* :mod:`~armcal.models.planar.design`, :mod:`~armcal.models.planar.plans`,
  :mod:`~armcal.models.planar.criteria` -- the design view, the paper's orthogonal
  plans and its own criteria (D*, Table I);
* :mod:`~armcal.models.planar.compliance` -- joints twisting under gravity and load
  (:class:`~armcal.models.planar.compliance.CompliantArm`).
"""
