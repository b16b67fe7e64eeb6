"""Benchmark: identify for a spatial arm -- armcal against scipy's least squares, and its scaling.

What it measures
----------------
One run, one seeded ``numpy.random.Generator``.  The robot is the built-in
``industrial-6r`` (six revolute joints, parallel J2/J3, J3 read from the
horizon) measured by a laser tracker at three reflectors A, B, C, at
``[0, 0, 340]``, ``[120, 0, 300]`` and ``[0, 120, 300]`` mm in the flange
frame.  The model is the one ``armcal identify --robot industrial-6r`` builds
for a file with a target column: the reflectors' positions are found from the
data, and of the 51 parameters (base pose 6, joint placements 30, joint zeros
6, reflectors 9) the rule of :meth:`~armcal.models.spatial.arm.SpatialArm.prepared`
frees 33 (4R + 3k).  The true arm has an error on each of those free joint
parameters (normal, 0.3 mm or 0.05 deg std), its base is 4 m from the
tracker, tilted by a few tenths of a degree and turned 120 degrees about z
(the registration must find it: no start is given).  A data set of ``m`` rows
is ``m`` poses uniform within the joint limits (those outside the chain's
coupled elbow limit drawn again), row ``i`` measuring reflector ``i mod 3``,
with isotropic noise sigma = 0.03 mm; ``identify`` is told sigma = 0.03 mm.

1. ``armcal.identification.identify``, m = 10^4 rows: wall time of the whole
   call (the identifiable set and the registration, the rank check,
   Gauss-Newton, covariance, goodness of fit and the studentized outlier test,
   which needs every row's leverage) against ``scipy.optimize.least_squares``
   on the same residuals (points predicted by the same model at the same 33
   free parameters, the other 18 held) from the same start (the
   registration, :meth:`~armcal.models.spatial.arm.SpatialArm.start`).  The
   baseline is only the solve: the identifiable set and the start are given
   to it.  Baselines:

   * ``method='lm'`` with its default 2-point finite-difference Jacobian and
     default tolerances: the plain way (scipy's MINPACK Levenberg-Marquardt);
   * ``method='trf'`` with armcal's analytic Jacobian
     (:meth:`~armcal.models.spatial.arm.SpatialArm.jacobian`) as ``jac``;
   * ``method='lm'`` with that analytic Jacobian: the fastest of scipy's.

   Target for each: armcal within 1x (no slower).  Every estimate must agree
   with armcal's: predicted points at the data's rows within 1e-6 mm, and
   every free parameter within 1e-3 of its standard deviation.  A fourth row
   times armcal's Gauss-Newton loop alone
   (:func:`~armcal.identification.solvers.solve` on the prepared arm from
   the same start) against the last baseline: the like-for-like part of the
   comparison, without what ``identify`` judges after the fit.

2. The ``armcal identify`` command on a CSV file of that data set
   (``q1_deg..q6_deg, x_mm, y_mm, z_mm, target``, written by
   :func:`armcal.files.format_measurements_csv`) with ``--robot industrial-6r
   --sigma 0.03 -o out.json``: peak memory (target < 400 MB) and wall time
   (target <= 15 s), both against ``armcal --version`` (the interpreter and
   the imports).  Its estimate must be the in-process one (every free
   parameter within 1e-3 of its standard deviation).

3. ``identify`` at m = 10^3 rows (against the plain baseline: ``lm`` with a
   finite-difference Jacobian, as in 1) and at m = 10^5 rows, against
   ``identify`` at 10^3 rows: 100 times the rows, target <= 150x the time
   (near-linear scaling; no scipy baseline there).

Timing: functions are timed as the minimum over several interleaved runs
(timer and machine noise only ever add time); the command runs in a fresh
child of a fresh measuring process (:mod:`measure`), whose peak resident memory
comes from ``os.wait4`` (``ru_maxrss``): the least wall time of 2 runs, the
largest peak.  The table goes to stdout and to
``benchmarks/RESULTS_SPATIAL.md`` with the date and the machine (``nproc``,
load average at the start and end: the machines are shared).

Usage::

    .venv/bin/python benchmarks/bench_spatial.py [--seed S] [--quick] [--no-write]

``--quick`` skips m = 10^5.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np
from bench_scale import Row, best_times, finish, run_command
from measure import machine_and_date
from scipy.optimize import least_squares

from armcal.doe import random_plan
from armcal.files import format_measurements_csv, load_spatial_robot
from armcal.identification import Calibration, identify
from armcal.identification.solvers import solve
from armcal.models import Conditions, SpatialArm
from armcal.workflow.setup import model_arm

RESULTS = Path(__file__).with_name("RESULTS_SPATIAL.md")

ROBOT = "industrial-6r"
SIGMA_MM = 0.03
LABELS = ("A", "B", "C")
#: The reflectors in the flange frame (mm).
REFLECTORS_MM = np.array([[0.0, 0.0, 340.0], [120.0, 0.0, 300.0], [0.0, 120.0, 300.0]])
#: The true base pose: 4 m from the tracker, tilted a little, turned 120 degrees about z.
BASE_DISTANCE_MM = 4000.0
BASE_DIRECTION_DEG = 135.0
BASE_ANGLES_DEG = (0.2, -0.3, 120.0)
#: Standard deviations of the true joint errors: placement (mm, deg) and zeros (deg).
ERROR_MM, ERROR_DEG = 0.3, 0.05
#: How far another solver's estimate may be from armcal's.
AGREE_MM = 1e-6
AGREE_STD = 1e-3


# --------------------------------------------------------------------------- the data


def nominal_arm() -> SpatialArm:
    """The arm ``armcal identify --robot industrial-6r`` fits to a file naming A, B, C
    (:func:`armcal.workflow.measured.spatial_measured_arm`): reflectors found from the data."""
    arm = load_spatial_robot(ROBOT).arm
    assert not arm.known_targets, "the built-in robot file does not place reflectors"
    return arm.replace(targets=LABELS, target_positions=np.zeros((0, 3)))


def true_params(arm: SpatialArm, rng: np.random.Generator) -> np.ndarray:
    """The true arm's parameters, in ``arm.layout`` order (module notes)."""
    lay = arm.layout
    # The joint parameters the rule frees on generic rows (every reflector at every pose).
    probe = arm.prepared(arm.plan_conditions(random_plan(arm, 100, rng=rng)))
    joints = slice(lay.placement_start, lay.target_start)
    free_joints = probe.free[joints]
    truth = arm.nominal.copy()
    direction = np.radians(BASE_DIRECTION_DEG)
    truth[:3] = BASE_DISTANCE_MM * np.array([np.cos(direction), np.sin(direction), 0.0])
    truth[3:6] = np.radians(BASE_ANGLES_DEG)
    scale = np.where(lay.angles[joints], np.radians(ERROR_DEG), ERROR_MM)
    truth[joints] = np.where(free_joints, scale * rng.standard_normal(free_joints.size), 0.0)
    truth[lay.target_start :] = REFLECTORS_MM.ravel()
    return truth


def poses(arm: SpatialArm, m: int, rng: np.random.Generator) -> np.ndarray:
    """``m`` poses uniform within the limits of the readings and of the chain's joints."""
    q = random_plan(arm, m, rng=rng)
    outside = ~arm.feasible(q)
    while outside.any():
        q[outside] = random_plan(arm, int(outside.sum()), rng=rng)
        outside = ~arm.feasible(q)
    return q


def measurements(
    arm: SpatialArm, truth: np.ndarray, m: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poses ``(m, 6)``, reflector indices ``(m,)`` and measured points ``(m, 3)`` (mm)."""
    q = poses(arm, m, rng)
    target = np.arange(m) % len(LABELS)
    clean = arm.positions(arm.conditions(q, target=target), truth)
    return q, target, clean + rng.normal(scale=SIGMA_MM, size=clean.shape)


# --------------------------------------------------------------------------- the baseline


class SameResiduals:
    """The residuals identify minimises, over the free parameters, for scipy.

    ``model`` is armcal's prepared arm (registered to the points, reduced to
    the identifiable set); ``start`` its registration with the held parameters
    at their held values, as the Gauss-Newton loop starts them.  Noise is
    isotropic, so the residuals need no whitening.
    """

    def __init__(self, model: SpatialArm, q: np.ndarray, target: np.ndarray, points: np.ndarray):
        self.model, self.points = model, points
        self.conditions: Conditions = model.conditions(q, target=target)
        self.free = model.free
        start = model.start(self.conditions, points)[0]
        self.start = np.where(self.free, start, model.held_values)

    def params(self, x: np.ndarray) -> np.ndarray:
        out = self.start.copy()
        out[self.free] = x
        return out

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return (self.model.positions(self.conditions, self.params(x)) - self.points).ravel()

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        jac = self.model.jacobian(self.conditions, self.params(x))[..., self.free]
        return jac.reshape(-1, int(np.count_nonzero(self.free)))

    def least_squares(self, method: str, analytic: bool) -> np.ndarray:
        """scipy's estimate of all parameters ``(p,)``, default tolerances."""
        jac: Callable[[np.ndarray], np.ndarray] | str = self.jacobian if analytic else "2-point"
        found = least_squares(self.residuals, self.start[self.free], jac=jac, method=method)
        return self.params(found.x)

    def armcal_solve(self) -> np.ndarray:
        """armcal's Gauss-Newton loop alone, on the same model from the same start."""
        found = solve(
            self.model, self.conditions, self.points, method="gauss-newton", start=self.start
        )
        return found.params[0]


#: armcal's Gauss-Newton loop alone, timed beside the baselines.
LOOP_ALONE = "armcal Gauss-Newton alone"

BASELINES = {  # row name: (method, analytic Jacobian)
    "scipy least_squares lm, 2-point FD": ("lm", False),
    "scipy least_squares trf, analytic jac": ("trf", True),
    "scipy least_squares lm, analytic jac": ("lm", True),
}


def check_agrees(cal: Calibration, same: SameResiduals, params: np.ndarray, what: str) -> None:
    """Raise unless ``params`` predict armcal's points and are armcal's to 1e-3 std."""
    cond = same.conditions
    predicted = cal.model.positions(cond, cal.params)
    moved = np.max(np.abs(same.model.positions(cond, params) - predicted))
    free = same.free
    off = np.max(np.abs(params * cal.display_scale - cal.values)[free] / cal.std[free])
    print(f"  {what}: points within {moved:.1e} mm, parameters within {off:.1e} std of armcal's")
    if moved > AGREE_MM or off > AGREE_STD:
        raise RuntimeError(f"armcal identify and {what} disagree")


def fit(model: SpatialArm, q: np.ndarray, target: np.ndarray, points: np.ndarray) -> Calibration:
    return identify(model, q, points, target=target)


# --------------------------------------------------------------------------- the figures


def bench_identify(
    model: SpatialArm,
    data: tuple[np.ndarray, np.ndarray, np.ndarray],
    names: list[str],
    *,
    loop_alone: bool = False,
) -> tuple[Calibration, list[float]]:
    """identify, the baselines ``names`` and (``loop_alone``) armcal's Gauss-Newton loop on
    one data set: the fit, and the least times of identify and of each other in turn."""
    q, target, points = data
    m = q.shape[0]
    cal = fit(model, q, target, points)
    gof = cal.goodness_of_fit
    if not cal.converged or gof is None or not gof.consistent:
        raise RuntimeError(f"identify at m = {m} did not fit the data")
    codes = [w.code for w in cal.warnings] or "none"
    print(
        f"identify, m = {m}: {cal.model.n_free} free parameters, {cal.iterations} iterations, "
        f"chi-square p = {gof.p_value:.2f}, warnings: {codes}"
    )
    assert isinstance(cal.model, SpatialArm)
    same = SameResiduals(cal.model, q, target, points)
    solvers: dict[str, Callable[[], np.ndarray]] = {
        name: partial(same.least_squares, *BASELINES[name]) for name in names
    }
    if loop_alone:
        solvers[LOOP_ALONE] = same.armcal_solve
    for name, solver in solvers.items():
        check_agrees(cal, same, solver(), name)
    whole = partial(fit, model, q, target, points)
    return cal, best_times([whole, *solvers.values()], repeats=7, budget=60.0)


def bench_small_and_middle(
    model: SpatialArm,
    small: tuple[np.ndarray, np.ndarray, np.ndarray],
    middle: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[list[Row], float, Calibration]:
    plain = "scipy least_squares lm, 2-point FD"
    _, (t_small, t_small_lm) = bench_identify(model, small, [plain])
    cal, times = bench_identify(model, middle, list(BASELINES), loop_alone=True)
    t_armcal, t_lm, t_trf_jac, t_lm_jac, t_solve = times
    rows = [
        Row(
            f"identify(), {ROBOT}, m=10^4, 3 targets: wall time",
            t_armcal,
            "s",
            name,
            t_base,
            "<= 1x baseline",
            t_armcal <= t_base,
        )
        for name, t_base in zip(BASELINES, (t_lm, t_trf_jac, t_lm_jac), strict=True)
    ]
    rows.append(
        Row(
            "armcal Gauss-Newton loop alone (solve(), same model and start), m=10^4",
            t_solve,
            "s",
            "scipy least_squares lm, analytic jac",
            t_lm_jac,
            "<= 1x baseline",
            t_solve <= t_lm_jac,
        )
    )
    rows.append(
        Row(
            f"identify(), {ROBOT}, m=10^3, 3 targets: wall time",
            t_small,
            "s",
            plain,
            t_small_lm,
            "<= 1x baseline",
            t_small <= t_small_lm,
        )
    )
    return rows, t_small, cal


def bench_command(
    folder: Path, data: tuple[np.ndarray, np.ndarray, np.ndarray], cal: Calibration
) -> list[Row]:
    q, target, points = data
    path = folder / "spatial10000.csv"
    path.write_text(format_measurements_csv(q, points, targets=[LABELS[i] for i in target]))
    out = folder / "spatial10000.json"
    args = ["identify", "--robot", ROBOT, "--measurements", str(path), "--sigma", str(SIGMA_MM)]
    seconds, peak = run_command([*args, "-o", str(out)], runs=2)
    startup_seconds, startup_peak = run_command(["--version"], runs=2)

    found = {p["name"]: p for p in json.loads(out.read_text())["parameters"]}
    free = cal.model.free
    values = np.array([found[name]["value"] for name in cal.names])
    off = np.max(np.abs(values - cal.values)[free] / cal.std[free])
    print(f"armcal identify on the file: parameters within {off:.1e} std of identify()'s")
    if off > AGREE_STD:
        raise RuntimeError("the command's estimate is not identify()'s")
    return [
        Row(
            "armcal identify on that file (m=10^4): peak memory",
            peak,
            "MB",
            "armcal --version",
            startup_peak,
            "< 400 MB",
            peak < 400,
        ),
        Row(
            "armcal identify on that file (m=10^4): wall time",
            seconds,
            "s",
            "armcal --version",
            startup_seconds,
            "<= 15 s",
            seconds <= 15,
        ),
    ]


def bench_large(
    model: SpatialArm, large: tuple[np.ndarray, np.ndarray, np.ndarray], t_small: float
) -> list[Row]:
    q, target, points = large
    cal = fit(model, q, target, points)
    if not cal.converged:
        raise RuntimeError("identify at m = 10^5 did not converge")
    print(f"identify, m = {q.shape[0]}: {cal.iterations} iterations")
    (t_large,) = best_times([partial(fit, model, q, target, points)], repeats=2, budget=60.0)
    return [
        Row(
            f"identify(), {ROBOT}, m=10^5, 3 targets: wall time",
            t_large,
            "s",
            "identify(), m=10^3",
            t_small,
            "<= 150x baseline",
            t_large <= 150 * t_small,
        )
    ]


# --------------------------------------------------------------------------- report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--quick", action="store_true", help="skip m = 10^5")
    parser.add_argument("--no-write", action="store_true", help="do not write RESULTS_SPATIAL.md")
    args = parser.parse_args()

    machine, date = machine_and_date()
    print(f"armcal spatial benchmark, {date}\n{machine}\n")
    rng = np.random.default_rng(args.seed)
    arm = nominal_arm()
    truth = true_params(arm, rng)
    model = model_arm(arm, sigma=SIGMA_MM)  # as the command with --sigma
    small = measurements(arm, truth, 1_000, rng)
    middle = measurements(arm, truth, 10_000, rng)
    start = time.perf_counter()
    rows, t_small, cal = bench_small_and_middle(model, small, middle)
    with tempfile.TemporaryDirectory(prefix="armcal-bench-") as tmp:
        rows += bench_command(Path(tmp), middle, cal)
    if not args.quick:
        # Last: identify at 10^5 rows allocates about 700 MB in this process.
        rows += bench_large(model, measurements(arm, truth, 100_000, rng), t_small)
    print(f"measured in {time.perf_counter() - start:.0f} s")
    finish(
        rows,
        machine,
        date,
        None if args.no_write else RESULTS,
        "Spatial identify benchmark results",
        "Written by `benchmarks/bench_spatial.py` (`make bench`); see its docstring for "
        "what each figure and baseline is. Times are the minimum over several runs; the "
        "command runs in a fresh process, peak memory is its maximum resident set size.",
        f"seed: {args.seed}{' (quick: no m=10^5)' if args.quick else ''}",
    )


if __name__ == "__main__":
    main()
