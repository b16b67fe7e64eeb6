"""Benchmark: optimal calibration plans from ``armcal.doe.design`` vs random plans.

What it measures
----------------
For the paper's 4-link arm with joints 2-4 limited to +-60 deg (so the orthogonal
plans of the paper do not fit and ``design`` has to optimize), and for m = 8 and
m = 20 poses, it times one call of ``design(arm, m, rng=seed)`` (optimization,
exchange polish and the Kiefer-Wolfowitz certificate included) and reports

* the plan's D-efficiency, relative to the unconstrained analytic optimum (1.0 by
  construction: the Hadamard bound on the normalized information matrix);
* the certified D-efficiency: a lower bound on the plan's efficiency relative to
  the best plan possible *within the joint limits* (1.0 = provably optimal);
* the plan-only bound of the certificate (looser, needs no reference design);
* ``reference_d_efficiency``: the D-efficiency of the best weighted design found
  within the constraints, i.e. roughly the best achievable number on the first line.

Baseline, and why it is fair
----------------------------
"Best of N random feasible plans given equal time": random plans are drawn in
batches of 2000 with a single ``rng.uniform`` call within the joint limits (this
arm has no measurement region, so every such plan is feasible) and scored with
``armcal.criteria.d_efficiency``, which is vectorized over the batch -- no Python
loop per plan.  Batches are drawn until the baseline has used as much wall time
as ``design`` did (the last batch may overrun slightly; the actual time is
printed).  Random search thus gets the same budget at a cost of a few
microseconds per plan, which is as cheap as random search gets in NumPy.  The
best of exactly 1000 random plans is reported as well.

``scipy.optimize`` is imported before timing so that its one-off import cost
(~0.3 s) is not charged to the first ``design`` call.  Every random number comes
from ``np.random.default_rng(seed)`` (``design`` receives the seed itself and
builds the same kind of generator); the global NumPy RNG is never used.

Usage::

    .venv/bin/python benchmarks/bench_design.py [--seed N] [--quick]

``--quick`` runs m = 20 only.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import scipy.optimize  # noqa: F401  (pre-import: keep its one-off cost out of the timing)

from armcal import PlanarArm
from armcal.criteria import d_efficiency
from armcal.doe import design, feasible

BATCH = 2000
FIXED_N = 1000


def make_arm() -> PlanarArm:
    return PlanarArm(
        [260, 180, 120, 100],
        joint_limits=np.radians([[-180, 180], [-60, 60], [-60, 60], [-60, 60]]),
        name="paper-4link ±60°",
    )


def random_batch(arm: PlanarArm, m: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """``k`` random plans ``(k, m, n)`` uniform within the joint limits, in one draw."""
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return rng.uniform(lo, hi, size=(k, m, arm.n_joints))


def score(arm: PlanarArm, plans: np.ndarray) -> np.ndarray:
    """D-efficiency of each plan ``(k,)``; 0 for plans with a pose outside the region."""
    eff = d_efficiency(arm, plans)
    if arm.region is not None:  # joint limits hold by construction; check the region
        eff = np.where(np.all(feasible(arm, plans), axis=-1), eff, 0.0)
    return eff


def best_of_fixed(arm: PlanarArm, m: int, n: int, rng: np.random.Generator) -> float:
    return float(score(arm, random_batch(arm, m, n, rng)).max())


def best_in_time(
    arm: PlanarArm, m: int, budget: float, rng: np.random.Generator
) -> tuple[float, int, float]:
    """Best D-efficiency of random plans within ``budget`` seconds: (best, plans, seconds)."""
    best, count = 0.0, 0
    start = time.perf_counter()
    while True:
        best = max(best, float(score(arm, random_batch(arm, m, BATCH, rng)).max()))
        count += BATCH
        elapsed = time.perf_counter() - start
        if elapsed >= budget:
            return best, count, elapsed


def run(arm: PlanarArm, m: int, seed: int) -> dict:
    start = time.perf_counter()
    result = design(arm, m, rng=seed)
    seconds = time.perf_counter() - start
    cert = result.certificate
    rng = np.random.default_rng(seed)
    fixed = best_of_fixed(arm, m, FIXED_N, rng)
    best, count, spent = best_in_time(arm, m, seconds, rng)
    return {
        "m": m,
        "method": result.method,
        "seconds": seconds,
        "d_eff": result.d_efficiency,
        "certified": cert.certified_d_efficiency,
        "plan_only": cert.plan_only_bound,
        "reference": cert.reference_d_efficiency,
        "fixed": fixed,
        "random_best": best,
        "random_n": count,
        "random_seconds": spent,
        "ratio": result.d_efficiency / best if best > 0 else float("inf"),
    }


def print_table(rows: list[dict]) -> None:
    fields = [
        ("design: method", lambda r: r["method"]),
        ("design: wall time [s]", lambda r: f"{r['seconds']:.2f}"),
        ("design: D-efficiency (vs unconstrained 1.0)", lambda r: f"{r['d_eff']:.4f}"),
        ("design: certified D-eff (vs best in limits)", lambda r: f"{r['certified']:.4f}"),
        ("design: plan-only bound", lambda r: f"{r['plan_only']:.4f}"),
        ("reference: best weighted design in limits", lambda r: f"{r['reference']:.4f}"),
        ("unconstrained analytic optimum", lambda r: "1.0000"),
        (f"random: best of {FIXED_N} plans", lambda r: f"{r['fixed']:.4f}"),
        ("random, equal time: plans evaluated", lambda r: f"{r['random_n']:,}"),
        ("random, equal time: wall time [s]", lambda r: f"{r['random_seconds']:.2f}"),
        ("random, equal time: best D-efficiency", lambda r: f"{r['random_best']:.4f}"),
        ("ratio design / best random (equal time)", lambda r: f"x{r['ratio']:.2f}"),
    ]
    label_width = max(len(label) for label, _ in fields)
    cells = [[fmt(r) for r in rows] for _, fmt in fields]
    col_width = max(12, *(len(c) for row in cells for c in row))
    header = f"{'':<{label_width}}" + "".join(f"  {'m=' + str(r['m']):>{col_width}}" for r in rows)
    print(header)
    print("-" * len(header))
    for (label, _), row in zip(fields, cells, strict=True):
        print(f"{label:<{label_width}}" + "".join(f"  {c:>{col_width}}" for c in row))


def summary(r: dict) -> str:
    return (
        f"m={r['m']}: design {r['d_eff']:.3f} (certified >= {r['certified']:.3f} of best "
        f"possible) in {r['seconds']:.1f} s vs best of {r['random_n']} random plans "
        f"{r['random_best']:.3f} in the same time (x{r['ratio']:.2f})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--quick", action="store_true", help="m = 20 only")
    args = parser.parse_args()
    arm = make_arm()
    sizes = (20,) if args.quick else (8, 20)
    print(
        f"armcal design benchmark: {arm.name}, links {arm.link_lengths.tolist()} mm, "
        f"{arm.n_params} parameters, seed {args.seed}"
    )
    print(f"python {platform.python_version()}, numpy {np.__version__}, random batch {BATCH}")
    print()
    rows = [run(arm, m, args.seed) for m in sizes]
    print_table(rows)
    print()
    for r in rows:
        print(summary(r))


if __name__ == "__main__":
    main()
