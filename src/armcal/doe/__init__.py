"""Design of calibration experiments: which poses to measure, and how many.

A plan is an array of joint angles of shape ``(m, n)`` in rad.  Plans are
judged by the criteria of :mod:`armcal.criteria` on the information of the
arm's model -- its noise model and fixed parameters: the Hadamard-normalized
``Fs`` of the paper (1 for its orthogonal plans) when every parameter is free
and the noise isotropic iid, the weighted information over the free
parameters otherwise.

* :mod:`~armcal.doe.model` -- a plan's information in the model, its
  gradient, and where the paper's bound ``det <= 1`` still holds;
* :mod:`~armcal.doe.plans` -- orthogonal (Table I), analytic (placed within the
  limits and region) and random plans; feasibility of poses;
* :mod:`~armcal.doe.optimizer` -- batched gradient ascent on a criterion,
  polished by L-BFGS-B / SLSQP;
* :mod:`~armcal.doe.exchange` -- modified Fedorov exchange over candidates;
* :mod:`~armcal.doe.certificate` -- a lower bound on the D-efficiency relative
  to the model's best plan within the constraints (Kiefer-Wolfowitz);
* :mod:`~armcal.doe.order` -- :func:`order_poses`: the order of a plan's poses
  with short joint travel (:func:`joint_travel`) for the shop floor;
* :mod:`~armcal.doe.designer` -- :func:`design`: all of the above in one call;
* :mod:`~armcal.doe.sizing` -- :func:`poses_needed`: the smallest ``m`` whose
  best plan reaches a target accuracy.
"""

from .certificate import Certificate, certify
from .designer import METHODS, Design, design
from .exchange import exchange_plan
from .optimizer import optimize_plan
from .order import ORDERS, joint_travel, order_poses
from .plans import (
    DISTINCT_TOLERANCE,
    analytic_plan,
    feasible,
    feasible_poses,
    orthogonal_plan,
    random_plan,
    repeated_poses,
)
from .sizing import TARGETS, PosesNeeded, accuracy_metric, poses_needed

__all__ = [
    "DISTINCT_TOLERANCE",
    "METHODS",
    "ORDERS",
    "TARGETS",
    "Certificate",
    "Design",
    "PosesNeeded",
    "accuracy_metric",
    "analytic_plan",
    "certify",
    "design",
    "exchange_plan",
    "feasible",
    "feasible_poses",
    "joint_travel",
    "optimize_plan",
    "order_poses",
    "orthogonal_plan",
    "poses_needed",
    "random_plan",
    "repeated_poses",
]
