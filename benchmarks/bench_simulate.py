"""Benchmark: batched Monte Carlo (``armcal.simulate``) vs a per-trial loop of solver calls.

What it measures
----------------
The issue-4 configuration: the paper's 4-link arm, an orthogonal 20-pose plan,
sigma = 0.1 mm, N = 10 000 noisy measurement sets drawn once from a seeded
generator.  Every contender identifies the same N sets:

* ``batched closed form`` -- ``solve_closed_form(arm, q, xy)`` on all N sets
  (one SVD, N right-hand sides);
* ``batched Gauss-Newton`` -- ``solve_gauss_newton(arm, q, xy)`` on all N sets
  (stacked normal equations, one batched solve per iteration);
* ``loop: closed form`` -- the same ``solve_closed_form`` called once per set;
* ``loop: Gauss-Newton`` -- the same ``solve_gauss_newton`` called once per set;
* ``loop: numpy lstsq Gauss-Newton`` -- the textbook per-trial solver: forward
  kinematics, the 40 x 8 Jacobian and ``numpy.linalg.lstsq`` per iteration,
  same start (zero), same step tolerance;
* ``loop: scipy least_squares`` -- ``scipy.optimize.least_squares`` (trust-region
  reflective, analytic Jacobian, ``xtol=1e-12``) per set.

Every loop gives the same estimates as the batched solvers (the largest
difference is printed), so the ratios compare equal work.  It also times the
whole ``monte_carlo`` call (noise drawn chunk by chunk, moments merged) and
records the peak traced memory of ``monte_carlo`` for N = 10^4, 10^5, 10^6: it
must stay flat (chunking).

Usage::

    .venv/bin/python benchmarks/bench_simulate.py [--trials N] [--seed S] [--quick]

``--quick`` times the slow loops on N / 10 sets and scales them (marked).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np
from baselines import numpy_gauss_newton
from scipy.optimize import least_squares

from armcal import forward_kinematics, jacobian, load_robot
from armcal.doe import orthogonal_plan
from armcal.models.planar.closed_form import solve_closed_form
from armcal.reproduction.algorithm import solve_gauss_newton
from armcal.simulate import monte_carlo


def lstsq_gauss_newton(arm, q, xy):
    """The obvious per-trial Gauss-Newton (:func:`baselines.numpy_gauss_newton`)."""
    return numpy_gauss_newton(arm.link_lengths, q, xy)


def scipy_fit(arm, q, xy):
    def residual(params):
        return (forward_kinematics(arm, q, params) - xy).ravel()

    def jac(params):
        return jacobian(arm, q, params).reshape(-1, arm.n_params)

    return least_squares(residual, np.zeros(arm.n_params), jac=jac, xtol=1e-12).x


def timed(function):
    start = time.perf_counter()
    value = function()
    return value, time.perf_counter() - start


def loop(solver, arm, q, xy, count):
    return np.array([solver(arm, q, xy[k]) for k in range(count)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="time slow loops on N/10 sets")
    args = parser.parse_args()

    spec = load_robot("paper-4link")
    arm, truth = spec.arm, spec.default_truth
    q = orthogonal_plan(arm, 20)
    n_trials = args.trials
    rng = np.random.default_rng(args.seed)
    xy = forward_kinematics(arm, q, truth) + 0.1 * rng.standard_normal((n_trials, 20, 2))
    print(f"paper-4link, orthogonal 20-pose plan, sigma 0.1 mm, {n_trials} trials\n")

    closed, t_closed = timed(lambda: solve_closed_form(arm, q, xy))
    (newton, _, converged), t_newton = timed(lambda: solve_gauss_newton(arm, q, xy))
    assert converged.all()
    mc, t_mc = timed(lambda: monte_carlo(arm, q, truth, 0.1, n_trials, rng=args.seed))
    rows = [
        ("batched closed form", t_closed, closed, None),
        ("batched Gauss-Newton", t_newton, newton, None),
        ("monte_carlo(), closed form, all included", t_mc, None, None),
    ]
    slow = max(1, n_trials // 10) if args.quick else n_trials
    loops = [
        ("loop: closed form (same solver)", lambda a, b, c: solve_closed_form(a, b, c), n_trials),
        ("loop: Gauss-Newton (same solver)", lambda a, b, c: solve_gauss_newton(a, b, c)[0], slow),
        ("loop: numpy lstsq Gauss-Newton", lstsq_gauss_newton, slow),
        ("loop: scipy least_squares", scipy_fit, slow),
    ]
    for name, solver, count in loops:
        estimates, seconds = timed(lambda s=solver, c=count: loop(s, arm, q, xy, c))
        scaled = seconds * n_trials / count
        diff = float(np.max(np.abs((estimates - closed[:count]) * arm.display_scale)))
        label = name + (" (scaled from N/10)" if count < n_trials else "")
        rows.append((label, scaled, None, diff))

    print(f"{'contender':<58}{'seconds':>10}{'per trial':>12}  agrees with batched")
    for name, seconds, _, diff in rows:
        note = "" if diff is None else f"max |diff| {diff:.1e} (mm, deg)"
        print(f"{name:<58}{seconds:>10.4f}{1e6 * seconds / n_trials:>10.1f} us  {note}")
    print()
    by_name = {name.split(" (scaled")[0]: seconds for name, seconds, _, _ in rows}
    pairs = [
        ("batched closed form", "loop: closed form (same solver)"),
        ("batched Gauss-Newton", "loop: Gauss-Newton (same solver)"),
        ("batched Gauss-Newton", "loop: numpy lstsq Gauss-Newton"),
        ("batched Gauss-Newton", "loop: scipy least_squares"),
        ("batched closed form", "loop: numpy lstsq Gauss-Newton"),
        ("monte_carlo(), closed form, all included", "loop: numpy lstsq Gauss-Newton"),
    ]
    for fast, base in pairs:
        print(f"speed-up {fast} vs {base}: x{by_name[base] / by_name[fast]:.0f}")

    worst = float(np.max(np.abs(mc.std / mc.predicted_std - 1)))
    print(f"\nmonte_carlo: empirical std within {100 * worst:.2f} % of predicted")

    print("\npeak traced memory of monte_carlo (closed form, no test poses):")
    for trials in (10_000, 100_000, 1_000_000):
        tracemalloc.start()
        _, seconds = timed(lambda t=trials: monte_carlo(arm, q, truth, 0.1, t, rng=args.seed))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        print(f"  N = {trials:>9}: {peak / 2**20:6.1f} MiB, {seconds:6.2f} s")


if __name__ == "__main__":
    main()
