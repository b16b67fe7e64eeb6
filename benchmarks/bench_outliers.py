"""Benchmark: false alarms of the outlier test and of the goodness of fit on clean data.

What it measures
----------------
1000 seeded clean datasets: paper-4link with the paper's deviations, 30 poses
uniform in the joint limits, sigma = 0.02 mm (a laser tracker), noise from
:func:`armcal.simulate.synthesize_measurements`.  For each, three fits:

* least squares with sigma given (the plain ``armcal identify``);
* ``robust=True`` with sigma given;
* ``robust=True`` with sigma estimated from the residuals.

It prints the fraction of datasets in which any pose was flagged (target:
at most 1 %; the Bonferroni-corrected test has a family-wise level of
``OUTLIER_ALPHA`` = 0.1 %), the fraction whose chi-square test warned
``fit-inconsistent`` (level ``FIT_ALPHA`` = 0.1 %), and the detection rate on
the same datasets with two gross outliers of 3-5 mm added at random rows.

Run: ``make bench`` (or ``python benchmarks/bench_outliers.py [datasets]``).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from armcal.doe import random_plan
from armcal.identification import identify
from armcal.identification.judgement import FIT_ALPHA, OUTLIER_ALPHA
from armcal.paper import paper_arm
from armcal.synthesis import synthesize_measurements

SIGMA = 0.02
POSES = 30


def main(datasets: int = 1000) -> None:
    arm, truth = paper_arm(4)
    fits = {
        "least squares, sigma given": {"sigma": SIGMA},
        "robust, sigma given": {"sigma": SIGMA, "robust": True},
        "robust, sigma estimated": {"robust": True},
    }
    alarms = dict.fromkeys(fits, 0)
    inconsistent = 0
    detected = dict.fromkeys(fits, 0)
    start = time.perf_counter()
    for seed in range(datasets):
        rng = np.random.default_rng(seed)
        q = random_plan(arm, POSES, rng=rng)
        xy = synthesize_measurements(arm, q, truth, SIGMA, rng=rng)
        rows = rng.choice(POSES, size=2, replace=False)
        size, angle = rng.uniform(3.0, 5.0, 2), rng.uniform(0.0, 2 * np.pi, 2)
        dirty = xy.copy()
        dirty[rows] += (size * np.array([np.cos(angle), np.sin(angle)])).T
        expected = sorted(int(r) + 1 for r in rows)
        for name, kwargs in fits.items():
            cal = identify(arm, q, xy, **kwargs)
            alarms[name] += bool(cal.outliers)
            if name == "least squares, sigma given":
                inconsistent += any(w.code == "fit-inconsistent" for w in cal.warnings)
            flagged = sorted(o.row for o in identify(arm, q, dirty, **kwargs).outliers)
            detected[name] += flagged == expected
    seconds = time.perf_counter() - start
    print(f"outlier test on {datasets} clean datasets ({POSES} poses, sigma {SIGMA} mm):")
    print(f"  family-wise level OUTLIER_ALPHA = {OUTLIER_ALPHA:g}; target: false alarms <= 1 %")
    for name in fits:
        rate = alarms[name] / datasets
        mark = "ok" if rate <= 0.01 else "ABOVE TARGET"
        print(
            f"  {name:28s} false alarms {100 * rate:5.2f} % ({alarms[name]}/{datasets}) {mark}; "
            f"two 3-5 mm outliers found exactly in {100 * detected[name] / datasets:.1f} %"
        )
    print(
        f"  chi-square test (level {FIT_ALPHA:g}): fit-inconsistent on "
        f"{100 * inconsistent / datasets:.2f} % of clean datasets"
    )
    print(f"  {seconds:.1f} s for {6 * datasets} fits")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
