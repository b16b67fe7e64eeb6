"""Benchmark: ordering a plan's poses for short joint travel (``armcal.doe.order_poses``).

What it measures
----------------
For m = 10^3, 10^4 and 10^5 poses of paper-4link (4 joints, each within
+-180 deg) and two kinds of plan:

* ``designed`` -- ``design(arm, m, order="none")``, the plan ``armcal design``
  writes (for this arm the analytic one: joints 2..4 step together by
  360 / m deg), in the order the method made it;
* ``random`` -- m poses uniform within the joint limits (no structure: the
  hard case; "the method's order" is the order drawn),

it times ``order_poses`` and reports the joint travel of its order as a
fraction of the travel of a random order (the mean of 5 random permutations)
and of the method's order, and the peak memory that ``tracemalloc`` traces
during one call (numpy arrays and Python objects; bytes per pose should stay
flat: memory is O(m k), no m x m matrix, which at 10^5 poses would take 80 GB).

Baselines, timed in the same run on the same poses
--------------------------------------------------
* ``argsort`` -- ``numpy.argsort`` of joint 1: the trivial order, as fast as
  ordering gets (:func:`baselines.argsort_by_joint1`);
* ``nearest neighbour`` -- the plain nearest-neighbour path from pose 0 with a
  k-d tree (``scipy.spatial.cKDTree``, L1) of the unvisited poses, written here
  without armcal (:func:`baselines.nearest_neighbour_order`): the textbook
  construction that ``order_poses`` improves on.

Times are the least of 3 runs (1 at 10^5), interleaved; the machines are
shared, so compare ratios, not seconds.

Usage::

    .venv/bin/python benchmarks/bench_order.py [--seed N] [--quick]

``--quick`` stops at 10^4 poses.
"""

from __future__ import annotations

import argparse
import platform
import time
import tracemalloc
from collections.abc import Callable

import numpy as np
import scipy.spatial  # noqa: F401  (pre-import: keep its one-off cost out of the timing)
from baselines import argsort_by_joint1, nearest_neighbour_order

from armcal import load_robot
from armcal.doe import design, joint_travel, order_poses, random_plan

RANDOM_ORDERS = 5


def least_time(functions: list[Callable[[], np.ndarray]], repeats: int) -> list[float]:
    """Least wall time of each function over ``repeats`` rounds, run in turn within a round."""
    best = [float("inf")] * len(functions)
    for _ in range(repeats):
        for i, function in enumerate(functions):
            start = time.perf_counter()
            function()
            best[i] = min(best[i], time.perf_counter() - start)
    return best


def peak_traced_bytes(function: Callable[[], np.ndarray]) -> int:
    """Peak memory ``tracemalloc`` traces during one call (numpy arrays included)."""
    tracemalloc.start()
    try:
        function()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def run(kind: str, q: np.ndarray, seed: int) -> dict:
    m = q.shape[0]
    rng = np.random.default_rng(seed)
    random_travel = float(
        np.mean([joint_travel(q[rng.permutation(m)]) for _ in range(RANDOM_ORDERS)])
    )
    contenders = {
        "order_poses": lambda: order_poses(q),
        "argsort": lambda: argsort_by_joint1(q),
        "nearest neighbour": lambda: nearest_neighbour_order(q),
    }
    seconds = least_time(list(contenders.values()), repeats=1 if m >= 100_000 else 3)
    row = {"kind": kind, "m": m, "method": joint_travel(q), "random": random_travel}
    for (name, function), spent in zip(contenders.items(), seconds, strict=True):
        order = function()
        assert np.array_equal(np.sort(order), np.arange(m)), name
        row[name] = (spent, joint_travel(q[order]))
    row["peak"] = peak_traced_bytes(lambda: order_poses(q))
    return row


def print_rows(rows: list[dict]) -> None:
    header = (
        f"{'plan':<9} {'m':>7}  {'contender':<18} {'time [s]':>9} {'x argsort':>10} "
        f"{'travel/random':>14} {'travel/method':>14}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        base_time = r["argsort"][0]
        for name in ("order_poses", "nearest neighbour", "argsort"):
            spent, travel = r[name]
            print(
                f"{r['kind']:<9} {r['m']:>7}  {name:<18} {spent:>9.3f} {spent / base_time:>9.0f}x "
                f"{travel / r['random']:>14.4g} {travel / r['method']:>14.4g}"
            )
        print(
            f"{'':<9} {'':>7}  peak traced memory of order_poses: {r['peak'] / 2**20:.1f} MiB "
            f"({r['peak'] / r['m']:.0f} bytes per pose)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--quick", action="store_true", help="stop at 10^4 poses")
    args = parser.parse_args()
    arm = load_robot("paper-4link").arm
    sizes = (1_000, 10_000) if args.quick else (1_000, 10_000, 100_000)
    print(
        f"armcal order benchmark: {arm.name}, {arm.n_joints} joints, seed {args.seed}; "
        f"python {platform.python_version()}, numpy {np.__version__}"
    )
    print(
        f"designed = design(arm, m, order='none') (analytic for this arm); random = poses "
        f"uniform in the limits.  travel/random: against the mean of {RANDOM_ORDERS} random "
        "orders; travel/method: against the order the plan came in\n"
    )
    rows = []
    for m in sizes:
        made = design(arm, m, rng=args.seed, with_certificate=False, order="none")
        rows.append(run("designed", made.q, args.seed))
        rows.append(run("random", random_plan(arm, m, rng=args.seed), args.seed))
    print_rows(rows)


if __name__ == "__main__":
    main()
