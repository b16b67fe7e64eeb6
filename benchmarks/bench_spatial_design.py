"""Benchmark: designed plans for a six-axis arm against the pool method and random plans.

What it measures
----------------
One run, one seed.  The arm is the built-in ``industrial-6r`` within its joint
limits, measured at three reflectors A, B, C (``[100, 0, 150]``,
``[-50, 87, 150]``, ``[-50, -87, 150]`` mm in the flange frame, known), with
isotropic noise sigma = 0.03 mm: 33 identifiable parameters (4R + 3k).  The
pool is 2000 poses uniform within the limits; the test poses for the position
error are 1000 more.  For every plan of ``m = 60`` poses:

* **D-efficiency** relative to the best plan within the limits: ``(det M /
  det M*)^(1/p)`` with ``M*`` the reference design of the designed plan's
  Kiefer-Wolfowitz certificate (``reference_d_efficiency``), the same reference
  for every plan, so the figures compare plans directly.  When the designed
  plan's own variance function certifies 0.999 (``CLOSE_ENOUGH``) it is its own
  reference: its figure is 1 and the best plan is at most 0.1 % better;
* **poses for equal information**: how many poses of the method give the
  designed plan's ``det F`` (``F = m M`` grows linearly with ``m``):
  ``60 / (efficiency / designed efficiency)``;
* **predicted position RMS** after calibration over the test poses (mm);
* **time**, also of the same design with a laser tracker's noise model (its
  weights move with the pose).

Contenders, in the same run:

1. ``armcal.doe.design`` over the continuous joint space (with its certificate);
2. the open tools' pool method (continuous D-optimal weights on the pool by the
   multiplicative algorithm, then the 60 poses of largest weight:
   :func:`armcal.doe.pool.pool_weights_plan`);
3. ``design`` restricted to the same pool (the weights, then DETMAX:
   :func:`armcal.doe.pool.pool_plan`); target: at least the pool method's D;
4. 100 random plans within the limits: the best D and the best position RMS
   among them; target: the designed plan beats both.

Timing is wall time of one run of each (a design takes seconds; the machine is
shared, so the ratios, not the seconds, are the figures).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from bench_scale import Row, finish
from measure import machine_and_date

from armcal.criteria import position_accuracy
from armcal.doe import design, feasible_poses, random_plan
from armcal.doe.pool import pool_plan, pool_weights_plan
from armcal.files import load_spatial_robot
from armcal.models import SpatialArm
from armcal.noise import NoiseModel, TrackerNoise

RESULTS = Path(__file__).with_name("RESULTS_SPATIAL_DESIGN.md")
SIGMA_MM = 0.03
POSES = 60
POOL = 2000
RANDOM = 100
REFLECTORS = np.array([[100.0, 0.0, 150.0], [-50.0, 87.0, 150.0], [-50.0, -87.0, 150.0]])


def model_of() -> SpatialArm:
    """The industrial arm with three known reflectors, reduced to its identifiable set."""
    arm = load_spatial_robot("industrial-6r").arm.replace(
        targets=("A", "B", "C"), target_positions=REFLECTORS, known_targets=True
    )
    arm = arm.with_noise(NoiseModel.isotropic(SIGMA_MM, dim=3))
    return arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))


def tracker_model_of() -> SpatialArm:
    """The same arm measured by a laser tracker 3.4 m away and turned (its weights move
    with the pose: :class:`armcal.noise.TrackerNoise`, a data sheet's form)."""
    arm = load_spatial_robot("industrial-6r").arm.replace(
        targets=("A", "B", "C"),
        target_positions=REFLECTORS,
        known_targets=True,
        base_pose=np.array([3000.0, -1500.0, -600.0, 0.01, -0.02, 2.0]),
    )
    arm = arm.with_noise(NoiseModel.laser_tracker(TrackerNoise(0.008, 0.0004, 0.010, 0.0025)))
    return arm.prepared(arm.plan_conditions(feasible_poses(arm, 200, rng=0)))


def log_det(model: SpatialArm, q: np.ndarray) -> float:
    return float(np.linalg.slogdet(model.plan_information(q).information())[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--no-write", action="store_true", help="do not write the results")
    args = parser.parse_args()
    machine, date = machine_and_date()
    print(f"armcal spatial design benchmark, {date}\n{machine}\n")
    rng = np.random.default_rng(args.seed)
    model = model_of()
    p = model.n_free
    pool = feasible_poses(model, POOL, rng=rng)
    test = feasible_poses(model, 1000, rng=rng)

    start = time.perf_counter()
    made = design(model, POSES, rng=rng)
    t_design = time.perf_counter() - start
    assert made.certificate is not None
    reference = p * np.log(made.certificate.reference_d_efficiency)  # log det M*

    def efficiency(q: np.ndarray) -> float:
        return float(np.exp((log_det(model, q) - reference) / p))

    def rms(q: np.ndarray) -> float:
        return position_accuracy(model, q, test, SIGMA_MM).rms_mm

    start = time.perf_counter()
    baseline = pool[pool_weights_plan(model, POSES, pool)]
    t_pool = time.perf_counter() - start
    start = time.perf_counter()
    ours_pool = pool[pool_plan(model, POSES, pool)]
    t_ours_pool = time.perf_counter() - start
    start = time.perf_counter()
    randoms = [random_plan(model, POSES, rng=rng) for _ in range(RANDOM)]
    random_eff = [efficiency(q) for q in randoms]
    random_rms = [rms(q) for q in randoms]
    t_random = time.perf_counter() - start

    tracked = tracker_model_of()
    start = time.perf_counter()
    design(tracked, POSES, rng=rng)
    t_tracker = time.perf_counter() - start

    designed = efficiency(made.q)
    print(
        f"designed: D-efficiency {designed:.4f} of the best plan within the limits, certified "
        f">= {made.certificate.certified_d_efficiency:.4f}; position RMS {rms(made.q):.4g} mm; "
        f"{t_design:.1f} s"
    )
    rows = [
        Row(
            "designed plan (m=60): D-efficiency vs the best plan within the limits",
            designed,
            "",
            "pool method, same m and pool",
            efficiency(baseline),
            ">= 1x baseline",
            designed >= efficiency(baseline),
        ),
        Row(
            "designed plan from the pool (DETMAX): D-efficiency",
            efficiency(ours_pool),
            "",
            "pool method, same m and pool",
            efficiency(baseline),
            ">= 1x baseline",
            efficiency(ours_pool) >= efficiency(baseline) * (1 - 1e-12),
        ),
        Row(
            "designed plan: D-efficiency",
            designed,
            "",
            f"best of {RANDOM} random plans",
            max(random_eff),
            "> 1x baseline",
            designed > max(random_eff),
        ),
        Row(
            "poses for the designed plan's information: designed",
            float(POSES),
            "poses",
            "pool method",
            POSES * designed / efficiency(baseline),
            "",
            True,
        ),
        Row(
            "poses for the designed plan's information: designed",
            float(POSES),
            "poses",
            f"best of {RANDOM} random plans",
            POSES * designed / max(random_eff),
            "",
            True,
        ),
        Row(
            "predicted position RMS after calibration, 1000 test poses",
            rms(made.q),
            "mm",
            f"best of {RANDOM} random plans",
            min(random_rms),
            "< 1x baseline",
            rms(made.q) < min(random_rms),
        ),
        Row(
            "predicted position RMS after calibration, 1000 test poses",
            rms(made.q),
            "mm",
            "pool method",
            rms(baseline),
            "",
            True,
        ),
        Row(
            "time: design with certificate (m=60)",
            t_design,
            "s",
            "pool method (weights on 2000 poses)",
            t_pool,
            "<= 15 s",
            t_design <= 15.0,
        ),
        Row(
            "time: design with certificate (m=60), a laser tracker's noise model",
            t_tracker,
            "s",
            "pool method (weights on 2000 poses)",
            t_pool,
            "<= 15 s",
            t_tracker <= 15.0,
        ),
        Row(
            "time: design from the pool (DETMAX)",
            t_ours_pool,
            "s",
            f"{RANDOM} random plans, evaluated",
            t_random,
            "",
            True,
        ),
    ]
    finish(
        rows,
        machine,
        date,
        None if args.no_write else RESULTS,
        "Spatial design benchmark results",
        "Written by `benchmarks/bench_spatial_design.py` (`make bench`); see its docstring "
        "for what each figure and baseline is.",
        f"seed: {args.seed}",
    )


if __name__ == "__main__":
    main()
