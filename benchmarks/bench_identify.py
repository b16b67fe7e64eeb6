"""Benchmark: ``identify`` on many poses against a plain numpy Gauss-Newton loop.

What it measures
----------------
A random 12-link arm (24 parameters), m = 10 000 random poses, noisy positions
(sigma = 0.1 mm), one measurement set.  Contenders, each timed best of
``--repeat`` runs, with the peak memory traced by :mod:`tracemalloc` in a
separate run:

* ``identifiability`` -- the rank check alone (thin QR of the 2m x p Jacobian);
* ``identify closed-form`` / ``identify gauss-newton`` -- the whole call: rank
  check, solve, residuals, covariance and warnings;
* ``plain numpy Gauss-Newton`` -- the textbook loop: forward kinematics, the
  2m x p Jacobian and ``numpy.linalg.lstsq`` per iteration, from zero, same
  step tolerance (no rank check, no covariance).

The estimates of all three solvers are compared (largest difference printed),
so the ratios compare equal work.  The targets: identify within 3x the plain
loop, and peak memory a few 2m x p arrays (O(m), never a 2m x 2m factor).

OpenBLAS on a loaded 2-core machine can be 10-25 times slower with its default
thread pool than with ``OPENBLAS_NUM_THREADS=1``; both contenders use the same
BLAS, so the ratio is what to read.

Usage::

    .venv/bin/python benchmarks/bench_identify.py [--poses M] [--links N] [--repeat R]
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from armcal import (
    PlanarArm,
    forward_kinematics,
    identifiability,
    identify,
    jacobian,
    paper_from_user_matrix,
    random_plan,
)


def plain_gauss_newton(arm, q, xy, tol=1e-12, max_iter=50):
    """The obvious Gauss-Newton: FK, the full Jacobian and lstsq every iteration."""
    to_user = np.linalg.inv(paper_from_user_matrix(arm.n_joints))
    scale = np.ones(arm.n_params)
    scale[: arm.n_joints] = arm.link_lengths
    threshold = tol * arm.link_lengths.sum()
    paper = np.zeros(arm.n_params)
    for _ in range(max_iter):
        user = to_user @ paper
        residual = (xy - forward_kinematics(arm, q, user)).ravel()
        jac = jacobian(arm, q, user, parametrization="paper").reshape(-1, arm.n_params)
        step = np.linalg.lstsq(jac, residual, rcond=None)[0]
        paper += step
        if np.max(np.abs(step * scale)) <= threshold:
            break
    return to_user @ paper


def measure(function, repeat):
    """Best wall time (s) of ``repeat`` runs, and the traced peak (bytes) of one more."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        value = function()
        best = min(best, time.perf_counter() - start)
    tracemalloc.start()
    function()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return value, best, peak


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=10_000)
    parser.add_argument("--links", type=int, default=12)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    n, m = args.links, args.poses
    arm = PlanarArm(rng.uniform(50.0, 300.0, n), name=f"random-{n}link")
    q = random_plan(arm, m, rng=rng)
    truth = arm.params_from_display(rng.uniform(-3, 3, n), rng.uniform(-1, 1, n))
    xy = forward_kinematics(arm, q, truth) + rng.normal(0.0, 0.1, (m, 2))
    regressor_mb = 2 * m * arm.n_params * 8 / 1e6
    print(f"{arm.name}, {arm.n_params} parameters, {m} poses; one 2m x p array = "
          f"{regressor_mb:.1f} MB, a 2m x 2m one = {(2 * m) ** 2 * 8 / 1e9:.1f} GB")  # fmt: skip

    reference, t_plain, peak_plain = measure(lambda: plain_gauss_newton(arm, q, xy), args.repeat)
    rows = [("plain numpy Gauss-Newton", t_plain, peak_plain, 0.0)]
    _, t, peak = measure(lambda: identifiability(arm, q), args.repeat)
    rows.append(("identifiability", t, peak, float("nan")))
    for method in ("closed-form", "gauss-newton"):
        run = lambda method=method: identify(arm, q, xy, method=method)  # noqa: E731
        cal, t, peak = measure(run, args.repeat)
        rows.append((f"identify {method}", t, peak, float(np.max(np.abs(cal.params - reference)))))
    print(f"{'contender':<28}{'time':>10}{'vs plain':>10}{'peak':>10}{'x 2mp':>8}  max |diff|")
    for name, seconds, peak, diff in rows:
        print(
            f"{name:<28}{seconds * 1e3:>8.1f}ms{seconds / t_plain:>9.2f}x"
            f"{peak / 1e6:>8.1f}MB{peak / 1e6 / regressor_mb:>8.1f}  {diff:.2g}"
        )


if __name__ == "__main__":
    main()
