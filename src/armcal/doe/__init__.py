"""Design of calibration experiments: which poses to measure, and how many.

A plan is an array of joint angles of shape ``(m, n)`` in rad.  Every function
here works on any family of arm through its
:class:`~armcal.models.interface.FitModel`: plans are judged by the criteria of
:mod:`armcal.criteria` on the information of the model
(:meth:`~armcal.models.interface.FitModel.plan_information`) -- its noise model
and fixed parameters; for the planar arm the Hadamard-normalized ``Fs`` of the
paper (1 for its orthogonal plans) when every parameter is free and the noise
isotropic iid, the weighted information over the free parameters otherwise.

* :mod:`~armcal.doe.plans` -- random plans, feasible poses, distinct poses;
* :mod:`~armcal.doe.ascent` -- ascent within the joint limits and the view;
* :mod:`~armcal.doe.optimizer` -- batched gradient ascent on a criterion,
  polished by L-BFGS-B / SLSQP;
* :mod:`~armcal.doe.exchange` -- modified Fedorov exchange over candidates;
* :mod:`~armcal.doe.task` -- the task-aimed criteria I and G: the predicted
  position variance after calibration over test poses;
* :mod:`~armcal.doe.weights` -- D-optimal weights over a finite set of poses
  (the multiplicative algorithm, Newton's method on the simplex);
* :mod:`~armcal.doe.pool` -- D-optimal plans from a pool of safe poses, for any
  family (the pool's weights, then DETMAX);
* :mod:`~armcal.doe.certificate` -- a lower bound on the D-efficiency relative
  to the model's best plan within the constraints (Kiefer-Wolfowitz);
* :mod:`~armcal.doe.order` -- :func:`order_poses`: the order of a plan's poses
  with short joint travel (:func:`joint_travel`) for the shop floor;
* :mod:`~armcal.doe.designer` -- :func:`design`: the family's closed-form plans
  where they are optimal, else all of the above, in one call;
* :mod:`~armcal.doe.loads` -- :func:`design_with_loads`: poses and their payloads
  chosen together, for a model whose points depend on the load;
* :mod:`~armcal.doe.sizing` -- :func:`poses_needed`: the smallest ``m`` whose
  best plan reaches an accuracy requirement.

The planar family's closed-form plans (:func:`orthogonal_plan`,
:func:`analytic_plan`, :mod:`armcal.models.planar.plans`) are exported here too,
beside the other plans.
"""

from typing import TYPE_CHECKING

from ..lazy import exports

if TYPE_CHECKING:
    from ..models.planar.plans import analytic_plan, orthogonal_plan
    from .certificate import Certificate, certify
    from .designer import METHODS, Design, design
    from .exchange import exchange_plan
    from .loads import design_with_loads
    from .optimizer import optimize_plan
    from .order import ORDERS, joint_travel, order_poses
    from .plans import DISTINCT_TOLERANCE, feasible, feasible_poses, random_plan, repeated_poses
    from .sizing import REQUIREMENTS, PosesNeeded, accuracy_metric, poses_needed
    from .task import TASK_CRITERIA, task_criterion

# Out of mypy's sight: it sees the names imported above, and still flags a misspelt one.
if not TYPE_CHECKING:
    __getattr__, __dir__ = exports(
        __name__,
        {
            "..models.planar.plans": ("analytic_plan", "orthogonal_plan"),
            ".certificate": ("Certificate", "certify"),
            ".designer": ("METHODS", "Design", "design"),
            ".exchange": ("exchange_plan",),
            ".loads": ("design_with_loads",),
            ".optimizer": ("optimize_plan",),
            ".order": ("ORDERS", "joint_travel", "order_poses"),
            ".plans": (
                "DISTINCT_TOLERANCE",
                "feasible",
                "feasible_poses",
                "random_plan",
                "repeated_poses",
            ),
            ".sizing": ("REQUIREMENTS", "PosesNeeded", "accuracy_metric", "poses_needed"),
            ".task": ("TASK_CRITERIA", "task_criterion"),
        },
    )

__all__ = [
    "DISTINCT_TOLERANCE",
    "METHODS",
    "ORDERS",
    "REQUIREMENTS",
    "TASK_CRITERIA",
    "Certificate",
    "Design",
    "PosesNeeded",
    "accuracy_metric",
    "analytic_plan",
    "certify",
    "design",
    "design_with_loads",
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
    "task_criterion",
]
