"""armcal at numerical extremes: the result is correct, or a clear warning, or a clear error.

PRODUCT.md's contract at an extreme: exit status 0 with a correct result, or a warning
(a line ``armcal: warning: ...`` on stderr and the same ``{code, message}`` in the JSON),
or exit status 2 with one line ``armcal: error: ...``.  Never a NaN or an infinity in
any output (the table on stdout, the JSON, a file written), never a traceback, never
exit status 1.

The extremes: 12 joints; 10^4 poses; links from 1 mm to 10 m in one arm; near-singular
plans; compliance the data barely excite; sigma of 1e-6 mm and 1e3 mm; angles at
exactly +-180 deg and at the joint limits.  Most commands run in-process through
``armcal.cli.main`` (a subprocess costs about a second of interpreter start-up); a few
run as real processes to check the exit status itself.

Expected values are closed forms, not the program's output:

* the paper's orthogonal plans (Table I) give uncorrelated estimates with
  ``std(dl_i) = sigma / sqrt(m)``, ``std(dq_1) = sigma / (sqrt(m) L_1)`` and
  ``std(dq_i) = sigma / sqrt(m) * sqrt(1 / L_i^2 + 1 / L_{i-1}^2)`` (rad), with ``L`` the
  link lengths where the covariance is evaluated (nominal for a plan, nominal plus the
  identified deviations for a calibration: Table I's sums of cosines do not depend on
  the lengths or on constant angle offsets, so the plan stays orthogonal there);
* tips are computed by ``helpers.deviated_tip``, paper eq. (1) written out link by link;
* noiseless data are recovered to round-off: see :func:`recovery_tolerance`.

"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal.cli import main
from helpers import deviated_tip, run_cli

EPS = float(np.finfo(float).eps)

#: A NaN or an infinity written as a number (``nan``, ``-inf``, ``Infinity``, any case),
#: not as part of a word such as "information" or "financial".
NONFINITE = re.compile(r"(?<![A-Za-z_])[-+]?(?:nan|inf(?:inity)?)(?![A-Za-z_])", re.IGNORECASE)

#: The paper's lengths (mm) and deviations, the built-in robots' default truth (PRODUCT.md).
PAPER_LINKS = [260.0, 180.0, 120.0, 100.0]
PAPER_DL = [1.5, -0.6, -0.4, 0.7]
PAPER_DQ = [0.5, -0.5, 0.7, -0.3]

LINKS12 = [300.0, 250.0, 200.0, 180.0, 160.0, 140.0, 120.0, 100.0, 90.0, 80.0, 70.0, 60.0]
DL12 = [0.8, -0.5, 0.3, 1.2, -1.0, 0.4, -0.7, 0.9, -0.2, 0.6, -0.3, 0.5]
DQ12 = [0.4, -0.3, 0.6, -0.5, 0.2, 0.7, -0.4, 0.3, -0.6, 0.5, -0.2, 0.1]

#: One arm from 1 mm to 10 m, and deviations of the usual size (dl2 is 5 % of its link).
WIDE_LINKS = [10000.0, 1.0, 500.0]
WIDE_DL = [2.0, 0.05, -0.7]
WIDE_DQ = [0.01, 0.8, -0.4]

DL3 = [0.8, -0.5, 0.3]
DQ3 = [0.4, -0.3, 0.6]


# --------------------------------------------------------------------------- helpers


@dataclass(frozen=True)
class Run:
    code: int
    out: str
    err: str


def cli(*args: object) -> Run:
    """``armcal *args`` in-process: exit status, stdout and stderr.

    An exception other than the ones ``main`` turns into an exit status propagates and
    fails the test: in a real process it would be a traceback and exit status 1.
    """
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:  # argparse's own usage errors
            code = exc.code if isinstance(exc.code, int) else 1
    return Run(code, out.getvalue(), err.getvalue())


def check(run: Run, code: int, *files: Path) -> list[str]:
    """The contract for any outcome; returns the warning messages printed on stderr."""
    assert "Traceback" not in run.err, run.err
    assert run.code == code, f"exit {run.code}, expected {code}: {run.err}"
    lines = run.err.splitlines()
    assert all(line.startswith(("armcal: warning: ", "armcal: error: ")) for line in lines), (
        run.err
    )
    errors = [line for line in lines if line.startswith("armcal: error: ")]
    assert len(errors) == (1 if code == 2 else 0), run.err
    if code == 2:
        assert lines[-1] == errors[0]
    assert not NONFINITE.search(run.out), run.out
    for path in files:
        text = Path(path).read_text(encoding="utf-8")
        assert not NONFINITE.search(text), f"{path}: {NONFINITE.search(text)}"
    prefix = "armcal: warning: "
    return [line.removeprefix(prefix) for line in lines if line.startswith(prefix)]


def error_line(run: Run) -> str:
    check(run, 2)
    return run.err.splitlines()[-1]


def _reject(constant: str) -> float:
    raise AssertionError(f"non-finite number {constant} in a JSON document")


def load_json(text: str) -> dict:
    """A JSON document; NaN and Infinity (which Python's json accepts) fail the test."""
    document: dict = json.loads(text, parse_constant=_reject)
    return document


def codes(document: dict) -> list[str]:
    return [w["code"] for w in document["warnings"]]


def same_warnings(document: dict, printed: list[str]) -> None:
    """The JSON lists exactly the warnings said on stderr (PRODUCT.md)."""
    assert sorted(w["message"] for w in document["warnings"]) == sorted(printed)


def numbers(path: Path) -> np.ndarray:
    """The numeric table of a CSV file written by armcal, checked finite."""
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert np.all(np.isfinite(table)), path
    return table


def write_plan(path: Path, q_deg: np.ndarray | list) -> Path:
    q = np.asarray(q_deg, dtype=float)
    header = ",".join(f"q{j}_deg" for j in range(1, q.shape[1] + 1))
    rows = [",".join(repr(round(float(v), 9) + 0.0) for v in row) for row in q]
    path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    return path


def write_measurements(path: Path, q_deg: np.ndarray, xy: np.ndarray, z: float | None = None):
    n = q_deg.shape[1]
    header = [f"q{j}_deg" for j in range(1, n + 1)] + ["x_mm", "y_mm"]
    header += ["z_mm"] if z is not None else []
    rows = []
    for q, p in zip(q_deg, xy, strict=True):
        fields = [repr(float(v)) for v in (*q, *p)] + ([repr(z)] if z is not None else [])
        rows.append(",".join(fields))
    path.write_text("\n".join([",".join(header), *rows]) + "\n", encoding="utf-8")
    return path


def robot_file(
    path: Path,
    lengths: list[float],
    *,
    limits: list[list[float]] | None = None,
    sigma: float | None = None,
    extra: str = "",
) -> Path:
    text = f'name = "{path.stem}"\nlink_lengths_mm = {[float(v) for v in lengths]}\n'
    if limits is not None:
        text += f"joint_limits_deg = {[[float(a), float(b)] for a, b in limits]}\n"
    if sigma is not None:
        text += f"[measurement]\nsigma_mm = {sigma!r}\n"
    path.write_text(text + extra, encoding="utf-8")
    return path


def truth_file(path: Path, dl: list[float], dq: list[float], extra: str = "") -> Path:
    path.write_text(f"dl_mm = {dl}\ndq_deg = {dq}\n{extra}", encoding="utf-8")
    return path


def tips(q_deg: np.ndarray, links, dl, dq) -> np.ndarray:
    return np.array([deviated_tip(row, links, dl, dq) for row in q_deg])


def orthogonal_std(lengths, sigma: float, m: int) -> np.ndarray:
    """std of (dl_1..dl_n [mm], dq_1..dq_n [deg]) for an orthogonal plan (module docstring)."""
    inv2 = 1.0 / np.asarray(lengths, dtype=float) ** 2
    s = sigma / math.sqrt(m)
    dq = s * np.sqrt(inv2 + np.concatenate([[0.0], inv2[:-1]]))
    return np.concatenate([np.full(len(inv2), s), np.degrees(dq)])


def phasor_condition(q_deg: np.ndarray) -> float:
    """Condition number of the closed form's regressor ``A[k, i] = exp(i theta_ki)``.

    The tip is linear in the link phasors ``z_i = (l_i + dl_i) exp(i dtheta_i)`` (paper
    eq. 1) with these columns, which have unit modulus whatever the lengths; computed
    here with numpy, independently of armcal.  1 for an orthogonal plan.
    """
    theta = np.radians(np.cumsum(np.asarray(q_deg, dtype=float), axis=1))
    s = np.linalg.svd(np.exp(1j * theta), compute_uv=False)
    return float(s[0] / s[-1])


def recovery_tolerance(lengths, cond: float = 1.0) -> tuple[float, float]:
    """(mm, deg): how far round-off may move the estimates from noiseless data.

    The data carry an error of about ``eps R`` (``R`` the reach, the sum of the lengths:
    sums of n terms of size up to R; positions are written with 17 significant digits,
    so the files add nothing, and every command reads the same angles from them).  A
    backward-stable least-squares solve moves the link phasors by ``cond``
    (:func:`phasor_condition`) times that; a length by as much, a link's angle by that
    over the link's length, and a joint offset, the difference of two link angles, by
    twice that.  The factor 100 covers the sums over 2m rows and n links; the bounds stay
    orders of magnitude below any deviation worth identifying.
    """
    data = 100 * cond * EPS * float(sum(lengths))
    return data, math.degrees(2 * data / min(lengths))


def assert_recovered(values: dict[str, float], dl, dq, lengths, cond: float = 1.0) -> None:
    """The identified deviations are the truth up to :func:`recovery_tolerance`."""
    tol_mm, tol_deg = recovery_tolerance(lengths, cond)
    n = len(dl)
    assert_allclose([values[f"dl{i}"] for i in range(1, n + 1)], dl, rtol=0, atol=tol_mm)
    assert_allclose([values[f"dq{i}"] for i in range(1, n + 1)], dq, rtol=0, atol=tol_deg)


def names(n: int) -> list[str]:
    return [f"dl{i}" for i in range(1, n + 1)] + [f"dq{i}" for i in range(1, n + 1)]


def parameters(document: dict) -> tuple[dict[str, float], dict[str, float]]:
    values = {p["name"]: p["value"] for p in document["parameters"]}
    std = {p["name"]: p["std"] for p in document["parameters"]}
    return values, std


# ---------------------------------------------------------------- 1. twelve joints


def test_twelve_joints_from_design_to_validation(tmp_path):
    sigma, m, n = 0.05, 30, 12
    robot = robot_file(tmp_path / "arm12.toml", LINKS12, sigma=sigma)
    truth = truth_file(tmp_path / "truth.toml", DL12, DQ12)
    plan, meas, cal = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "cal.json"
    expected_plan_std = orthogonal_std(LINKS12, sigma, m)

    run = cli("design", "--robot", robot, "--poses", m, "-o", plan, "--json")
    check(run, 0, plan)
    designed = load_json(run.out)
    assert numbers(plan).shape == (m, n)
    # n = 12 has the paper's orthogonal plans for any m >= n: det Fs = 1 up to the
    # round-off of sums of m cosines (m eps), far inside 1e-9.
    assert designed["d_efficiency"] == pytest.approx(1.0, abs=1e-9)
    std = [designed["predicted_std"][k] for k in names(n)]
    assert_allclose(std, expected_plan_std, rtol=1e-9)

    run = cli("evaluate", "--robot", robot, "--plan", plan, "--json")
    check(run, 0)
    evaluated = load_json(run.out)
    assert_allclose(
        [evaluated["predicted_std"][k] for k in names(n)], expected_plan_std, rtol=1e-9
    )
    # orthogonal plan: sigma sqrt(2n/m) at every pose (README)
    assert evaluated["predicted_position_rms_mm"] == pytest.approx(sigma * math.sqrt(2 * n / m))

    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    data = numbers(meas)
    tol_mm, _ = recovery_tolerance(LINKS12)
    assert_allclose(data[:, n:], tips(data[:, :n], LINKS12, DL12, DQ12), rtol=0, atol=tol_mm)

    for method in ("closed-form", "gauss-newton"):
        run = cli("identify", "--robot", robot, "--measurements", meas, "--method", method,
                  "--json", "-o", cal)  # fmt: skip
        printed = check(run, 0, cal)
        document = load_json(run.out)
        same_warnings(document, printed)
        assert load_json(cal.read_text()) == document
        values, std = parameters(document)
        assert_recovered(values, DL12, DQ12, LINKS12)
        lengths = np.add(LINKS12, DL12)  # the covariance is evaluated at the solution
        assert_allclose([std[k] for k in names(n)], orthogonal_std(lengths, sigma, m), rtol=1e-6)
        assert document["degrees_of_freedom"] == 2 * m - 2 * n

    trials = 300
    run = cli("simulate", "--robot", robot, "--truth", truth, "--plan", plan,
              "--trials", trials, "--json")  # fmt: skip
    check(run, 0)
    simulated = load_json(run.out)
    empirical = np.array([simulated["empirical_std"][k] for k in names(n)])
    predicted = np.array([simulated["predicted_std"][k] for k in names(n)])
    # predicted at the truth, where the virtual arm's lengths are l + dl
    assert_allclose(predicted, orthogonal_std(np.add(LINKS12, DL12), sigma, m), rtol=1e-6)
    # the sample std of N normal draws has relative standard error 1/sqrt(2N) = 4.1 %
    # for N = 300; 20 % is about 5 of them for each of the 24 parameters
    assert_allclose(empirical, predicted, rtol=0.2)
    bias = np.array([simulated["bias"][k] for k in names(n)])
    assert np.all(np.abs(bias) <= 5 * predicted / math.sqrt(trials))

    # validation on 25 fresh random poses, noiseless: the calibrated model is exact up to
    # round-off; the nominal one errs by the deviations' effect, computed independently.
    rng = np.random.default_rng(12)
    test_plan = write_plan(tmp_path / "test_plan.csv", rng.uniform(-180, 180, (25, n)))
    test_meas = tmp_path / "test.csv"
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", test_plan,
              "--sigma", 0, "-o", test_meas)  # fmt: skip
    check(run, 0, test_meas)
    test = numbers(test_meas)
    nominal = tips(test[:, :n], LINKS12, [0.0] * n, [0.0] * n)
    before = math.sqrt(np.mean(np.sum((test[:, n:] - nominal) ** 2, axis=1)))
    run = cli("validate", "--calibration", cal, "--measurements", test_meas, "--json")
    check(run, 0)
    validated = load_json(run.out)
    assert validated["rms_before_mm"] == pytest.approx(before, rel=1e-9)
    assert validated["rms_after_mm"] <= 10 * tol_mm


def test_twelve_joints_in_a_real_process(tmp_path):
    """The same flow's identify as a real process: exit status 0, no traceback."""
    m = 13  # 26 equations, 24 parameters: 2 degrees of freedom, a `few-dof` warning
    robot = robot_file(tmp_path / "arm12.toml", LINKS12, sigma=0.05)
    angles = np.outer(np.arange(m), np.linspace(25.0, 80.0, 12)) % 360 - 180
    plan = write_plan(tmp_path / "plan.csv", angles)
    truth = truth_file(tmp_path / "truth.toml", DL12, DQ12)
    meas = tmp_path / "meas.csv"
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    run = run_cli(tmp_path, "identify", "--robot", robot.name, "--measurements", "meas.csv",
                  "--json")  # fmt: skip
    printed = check(Run(run.returncode, run.stdout, run.stderr), 0)
    document = load_json(run.stdout)
    same_warnings(document, printed)
    assert "few-dof" in codes(document)  # 2 degrees of freedom: fewer than 4
    values, _ = parameters(document)
    assert_recovered(values, DL12, DQ12, LINKS12, phasor_condition(angles))


def test_twelve_joints_too_few_poses_and_no_sigma_are_clear_errors(tmp_path):
    robot = robot_file(tmp_path / "arm12.toml", LINKS12)  # no sigma in the robot file
    # 11 poses: 22 equations for 24 parameters
    assert "24 parameters" in error_line(
        cli("design", "--robot", robot, "--poses", 11, "-o", tmp_path / "p.csv")
    )
    assert not (tmp_path / "p.csv").exists()
    # 12 poses: no residual left to estimate sigma from
    plan = tmp_path / "plan.csv"
    check(cli("design", "--robot", robot, "--poses", 12, "-o", plan), 0, plan)
    meas = tmp_path / "meas.csv"
    truth = truth_file(tmp_path / "truth.toml", DL12, DQ12)
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0.05,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    assert "sigma" in error_line(cli("identify", "--robot", robot, "--measurements", meas))
    # with sigma given: exact interpolation, 0 degrees of freedom, a `few-dof` warning
    run = cli("identify", "--robot", robot, "--measurements", meas, "--sigma", 0.05, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "few-dof" in codes(document) and document["degrees_of_freedom"] == 0


@pytest.mark.slow
def test_twelve_joints_with_limits_optimized_design(tmp_path):
    """Joint limits of +-90 deg on joints 2..12: the optimizer, not the closed form (~30 s)."""
    limits = [[-170, 170]] + [[-90, 90]] * 11
    robot = robot_file(tmp_path / "arm12.toml", LINKS12, limits=limits, sigma=0.05)
    plan = tmp_path / "plan.csv"
    run = cli("design", "--robot", robot, "--poses", 30, "--seed", 0, "-o", plan, "--json")
    check(run, 0, plan)
    designed = load_json(run.out)
    q = numbers(plan)
    assert np.all(q >= np.array(limits)[:, 0]) and np.all(q <= np.array(limits)[:, 1])
    # efficiencies are fractions of the unconstrained optimum; the certificate a bound <= 1
    assert 0 < designed["d_efficiency"] <= 1 + 1e-12
    assert 0 < designed["certified_d_efficiency"] <= 1 + 1e-12
    truth = truth_file(tmp_path / "truth.toml", DL12, DQ12)
    meas = tmp_path / "meas.csv"
    check(cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas), 0, meas)  # fmt: skip
    run = cli("identify", "--robot", robot, "--measurements", meas, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    values, _ = parameters(document)
    assert_recovered(values, DL12, DQ12, LINKS12, phasor_condition(q))


@pytest.mark.slow
def test_twelve_joints_ten_thousand_poses(tmp_path):
    """Both extremes at once: 12 joints and 10^4 poses (~2 s in-process, more on a busy box)."""
    sigma, m, n = 0.05, 10_000, 12
    robot = robot_file(tmp_path / "arm12.toml", LINKS12, sigma=sigma)
    truth = truth_file(tmp_path / "truth.toml", DL12, DQ12)
    plan, meas = tmp_path / "plan.csv", tmp_path / "meas.csv"
    check(cli("design", "--robot", robot, "--poses", m, "-o", plan), 0, plan)
    check(cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--seed", 1,
              "-o", meas), 0, meas)  # fmt: skip
    run = cli("identify", "--robot", robot, "--measurements", meas, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    values, std = parameters(document)
    lengths = np.add(LINKS12, [values[f"dl{i}"] for i in range(1, 13)])
    assert_allclose([std[k] for k in names(n)], orthogonal_std(lengths, sigma, m), rtol=1e-6)
    error = np.array([values[k] for k in names(n)]) - np.array(DL12 + DQ12)
    assert np.all(np.abs(error) < 5 * np.array([std[k] for k in names(n)]))
    run = cli("simulate", "--robot", robot, "--truth", truth, "--plan", plan, "--trials", 200,
              "--json")  # fmt: skip
    check(run, 0)
    simulated = load_json(run.out)
    empirical = np.array([simulated["empirical_std"][k] for k in names(n)])
    # N = 200: relative standard error 5 %; 25 % is 5 of them
    assert_allclose(empirical, orthogonal_std(LINKS12, sigma, m), rtol=0.25)


# ------------------------------------------------------------------ 2. 10^4 poses


@pytest.mark.slow
def test_ten_thousand_poses_four_links(tmp_path):
    sigma, m, n = 0.05, 10_000, 4
    plan, meas, cal = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "cal.json"
    check(cli("design", "--poses", m, "-o", plan), 0, plan)
    assert numbers(plan).shape == (m, n)
    check(cli("synthesize", "--plan", plan, "--sigma", sigma, "--seed", 3, "-o", meas), 0, meas)
    run = cli(
        "identify",
        "--robot",
        "paper-4link",
        "--measurements",
        meas,
        "--sigma",
        sigma,
        "--json",
        "-o",
        cal,
    )
    printed = check(run, 0, cal)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert document["degrees_of_freedom"] == 2 * m - 2 * n
    assert document["outliers"] == []  # 0.1 % family-wise level on clean data
    values, std = parameters(document)
    lengths = np.add(PAPER_LINKS, [values[f"dl{i}"] for i in range(1, 5)])
    assert_allclose([std[k] for k in names(n)], orthogonal_std(lengths, sigma, m), rtol=1e-6)
    # 8 normal errors: |z| < 5 for all of them fails with probability 5e-6
    error = np.array([values[k] for k in names(n)]) - np.array(PAPER_DL + PAPER_DQ)
    assert np.all(np.abs(error) < 5 * np.array([std[k] for k in names(n)]))
    assert document["goodness_of_fit"]["p_value"] > 1e-3

    # fresh poses, fresh noise: the error is the noise of a point (2-D, E|e|^2 = 2 sigma^2)
    # plus the calibrated model's own, sigma^2 2n/m for an orthogonal plan.  Over 10^4
    # poses |e|^2 averages to within 1 % (its relative std is 1/sqrt(m)), the RMS to 0.5 %.
    rng = np.random.default_rng(4)
    test_plan = write_plan(tmp_path / "test_plan.csv", rng.uniform(-180, 180, (m, n)))
    test_meas = tmp_path / "test.csv"
    run = cli("synthesize", "--plan", test_plan, "--sigma", sigma, "--seed", 9, "-o", test_meas)
    check(run, 0, test_meas)
    test = numbers(test_meas)
    nominal = tips(test[:, :n], PAPER_LINKS, [0.0] * n, [0.0] * n)
    before = math.sqrt(np.mean(np.sum((test[:, n:] - nominal) ** 2, axis=1)))
    run = cli("validate", "--calibration", cal, "--measurements", test_meas, "--json")
    printed = check(run, 0)
    validated = load_json(run.out)
    same_warnings(validated, printed)
    assert validated["rms_before_mm"] == pytest.approx(before, rel=1e-9)
    assert validated["rms_after_mm"] == pytest.approx(sigma * math.sqrt(2 + 2 * n / m), rel=0.03)


@pytest.mark.slow
def test_ten_thousand_poses_other_fits_agree(tmp_path):
    """Gauss-Newton and the robust fit on 10^4 clean poses reach the least-squares answer."""
    sigma, m, n = 0.05, 10_000, 4
    rng = np.random.default_rng(5)
    plan = write_plan(tmp_path / "plan.csv", rng.uniform(-180, 180, (m, n)))
    meas = tmp_path / "meas.csv"
    check(cli("synthesize", "--plan", plan, "--sigma", sigma, "--seed", 6, "-o", meas), 0, meas)
    run = cli(
        "identify", "--robot", "paper-4link", "--measurements", meas, "--sigma", sigma, "--json"
    )
    check(run, 0)
    reference, std = parameters(load_json(run.out))
    # uniform random angles: Table I's sums vanish in expectation, so for m = 10^4 the
    # plan is orthogonal to O(1/sqrt(m)) = 1 %, and the std follow the closed form to 5 %
    assert_allclose([std[k] for k in names(n)], orthogonal_std(PAPER_LINKS, sigma, m), rtol=0.05)
    for option in (("--method", "gauss-newton"), ("--robust",)):
        run = cli(
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            meas,
            "--sigma",
            sigma,
            "--json",
            *option,
        )
        printed = check(run, 0)
        document = load_json(run.out)
        same_warnings(document, printed)
        assert document["outliers"] == []
        values, _ = parameters(document)
        # Gauss-Newton: the same minimum, stopped by a step below 1e-12 of the reach
        # (6.6e-10 mm, converging quadratically); robust: with no pose flagged, Huber keeps
        # every clean pose at full weight and the final fit is plain least squares on all.
        # 1e-5 std is 5e-9 mm here.
        assert all(abs(values[k] - reference[k]) < 1e-5 * std[k] for k in names(n)), option


# ------------------------------------------------------- 3. links from 1 mm to 10 m


@pytest.mark.parametrize("method", ["closed-form", "gauss-newton"])
@pytest.mark.parametrize("plan_kind", ["designed", "random"])
def test_links_from_one_millimetre_to_ten_metres(tmp_path, method, plan_kind):
    sigma, m, n = 0.05, 12, 3
    robot = robot_file(tmp_path / "wide.toml", WIDE_LINKS, sigma=sigma)
    truth = truth_file(tmp_path / "truth.toml", WIDE_DL, WIDE_DQ)
    plan, meas, cal = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "cal.json"
    if plan_kind == "designed":
        check(cli("design", "--robot", robot, "--poses", m, "-o", plan), 0, plan)
    else:
        write_plan(plan, np.random.default_rng(3).uniform(-180, 180, (m, n)))
    run = cli("evaluate", "--robot", robot, "--plan", plan, "--json")
    check(run, 0)
    evaluated = load_json(run.out)
    if plan_kind == "designed":
        # dq2 is the 1 mm link's angle: sigma / (sqrt(m) 1 mm) = 0.83 deg, honestly large
        std = [evaluated["predicted_std"][k] for k in names(n)]
        assert_allclose(std, orthogonal_std(WIDE_LINKS, sigma, m), rtol=1e-9)
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    data = numbers(meas)
    tol_mm, _ = recovery_tolerance(WIDE_LINKS)
    assert_allclose(data[:, n:], tips(data[:, :n], WIDE_LINKS, WIDE_DL, WIDE_DQ), atol=tol_mm)
    cond = phasor_condition(data[:, :n])  # 1 for the designed (orthogonal) plan

    run = cli("identify", "--robot", robot, "--measurements", meas, "--method", method,
              "--json", "-o", cal)  # fmt: skip
    printed = check(run, 0, cal)
    document = load_json(run.out)
    same_warnings(document, printed)
    values, std = parameters(document)
    assert "ill-conditioned" not in codes(document)
    # the 1 mm link's angle is recovered to ~1e-12 rad: round-off over a 1 mm lever arm
    assert_recovered(values, WIDE_DL, WIDE_DQ, WIDE_LINKS, cond)
    assert all(s > 0 and math.isfinite(s) for s in std.values())
    if plan_kind == "designed":
        lengths = np.add(WIDE_LINKS, WIDE_DL)
        assert_allclose([std[k] for k in names(n)], orthogonal_std(lengths, sigma, m), rtol=1e-6)
        # dq2 = dtheta2 - dtheta1 and dq3 = dtheta3 - dtheta2 share dtheta2, the 1 mm
        # link's angle; with uncorrelated dtheta_i of variance sigma^2 / (m L_i^2):
        # corr = -(1/L2^2) / sqrt((1/L2^2 + 1/L1^2)(1/L3^2 + 1/L2^2)), within 1e-5 of -1
        inv2 = 1.0 / lengths**2
        corr = -inv2[1] / math.sqrt((inv2[1] + inv2[0]) * (inv2[2] + inv2[1]))
        correlation = document["correlation"]
        i, j = correlation["names"].index("dq2"), correlation["names"].index("dq3")
        assert correlation["matrix"][i][j] == pytest.approx(corr, rel=1e-9)
        text = cli("identify", "--robot", robot, "--measurements", meas, "--method", method)
        check(text, 0)
        assert "strongly correlated" in text.out and "dq2/dq3" in text.out

    run = cli("validate", "--calibration", cal, "--measurements", meas, "--json")
    check(run, 0)
    assert load_json(run.out)["rms_after_mm"] <= 10 * recovery_tolerance(WIDE_LINKS, cond)[0]
    run = cli("simulate", "--robot", robot, "--truth", truth, "--plan", plan, "--trials", 300,
              "--method", method, "--json")  # fmt: skip
    check(run, 0)
    simulated = load_json(run.out)
    empirical = np.array([simulated["empirical_std"][k] for k in names(n)])
    predicted = np.array([simulated["predicted_std"][k] for k in names(n)])
    assert_allclose(empirical, predicted, rtol=0.2)  # 5 standard errors at N = 300


# ----------------------------------------------------------- 4. near-singular plans


def _identical(rng):
    return np.tile([10.0, 20.0, 30.0, 40.0], (20, 1))


def _jitter_4link(rng):
    return np.array([10.0, 20.0, 30.0, 40.0]) + rng.uniform(-1e-6, 1e-6, (20, 4))


def _q2_zero(rng):
    return np.column_stack([np.arange(-170.0, 170.0, 17.0), np.zeros(20)])


def _q2_jitter(rng):
    return np.column_stack([np.arange(-170.0, 170.0, 17.0), rng.uniform(-1e-6, 1e-6, 20)])


def _q3_nearly_fixed(rng):
    k = np.arange(12)
    q = np.column_stack([-165 + 30.0 * k, 15 + 30.0 * k, 30 + 1e-4 * (k % 3 - 1)])
    return (q + 180) % 360 - 180


#: (id, robot, plan, expected outcome, what the message must name)
NEAR_SINGULAR = [
    ("identical-poses", "paper-4link", _identical, "error", "dl1"),
    ("jitter-1e-6deg", "paper-4link", _jitter_4link, "ill-conditioned", "joint"),
    ("q2-zero", "paper-2link", _q2_zero, "error", "joint 2"),
    ("q2-jitter-1e-6deg", "paper-2link", _q2_jitter, "ill-conditioned", "joint 2"),
    ("q3-jitter-1e-4deg", "paper-3link", _q3_nearly_fixed, "ill-conditioned", "joint 3"),
]


def _near_singular_files(tmp_path, case):
    _, robot, make, _, _ = case
    plan = write_plan(tmp_path / "plan.csv", make(np.random.default_rng(1)))
    meas = tmp_path / "meas.csv"
    # synthesize needs no identifiable plan: it only evaluates the model (noiseless)
    check(cli("synthesize", "--robot", robot, "--plan", plan, "--sigma", 0, "-o", meas), 0, meas)
    return robot, plan, meas


@pytest.mark.parametrize("case", NEAR_SINGULAR, ids=[c[0] for c in NEAR_SINGULAR])
def test_near_singular_plans_evaluate_and_identify(tmp_path, case):
    _, _, _, outcome, named = case
    robot, plan, meas = _near_singular_files(tmp_path, case)
    evaluate = cli("evaluate", "--robot", robot, "--plan", plan, "--json")
    identify = cli("identify", "--robot", robot, "--measurements", meas, "--sigma", 0.05,
                   "--json")  # fmt: skip
    if outcome == "error":
        for run in (evaluate, identify):
            line = error_line(run)
            assert "cannot identify" in line and named in line
            assert run.out == ""
        return
    for run in (evaluate, identify):
        printed = check(run, 0)
        document = load_json(run.out)
        same_warnings(document, printed)
        assert "ill-conditioned" in codes(document)
        message = next(w["message"] for w in document["warnings"] if w["code"] == outcome)
        assert named in message
    predicted = load_json(evaluate.out)["predicted_std"].values()
    assert all(0 < s < math.inf for s in predicted)
    _, std = parameters(load_json(identify.out))
    assert all(0 < s < math.inf for s in std.values())
    # with noise the poorly determined combinations are far off, and said to be
    noisy = tmp_path / "noisy.csv"
    run = cli("synthesize", "--robot", robot, "--plan", plan, "--sigma", 0.05, "--seed", 2,
              "-o", noisy)  # fmt: skip
    check(run, 0, noisy)
    run = cli("identify", "--robot", robot, "--measurements", noisy, "--sigma", 0.05, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "ill-conditioned" in codes(document)
    _, std = parameters(document)
    assert all(0 < s < math.inf for s in std.values())


@pytest.mark.parametrize("case", NEAR_SINGULAR, ids=[c[0] for c in NEAR_SINGULAR])
def test_near_singular_plans_simulate_is_finite_or_an_error(tmp_path, case):
    _, _, _, outcome, named = case
    robot, plan, _ = _near_singular_files(tmp_path, case)
    run = cli("simulate", "--robot", robot, "--plan", plan, "--trials", 200, "--json")
    if outcome == "error":
        line = error_line(run)
        assert "cannot identify" in line and named in line
        return
    check(run, 0)
    document = load_json(run.out)
    assert all(0 < s < math.inf for s in document["predicted_std"].values())


@pytest.mark.parametrize(
    "case",
    [c for c in NEAR_SINGULAR if c[3] == "ill-conditioned"],
    ids=[c[0] for c in NEAR_SINGULAR if c[3] == "ill-conditioned"],
)
def test_near_singular_plans_simulate_warns(tmp_path, case):
    robot, plan, _ = _near_singular_files(tmp_path, case)
    run = cli("simulate", "--robot", robot, "--plan", plan, "--trials", 200, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "ill-conditioned" in codes(document)


def test_near_singular_noiseless_data_are_still_recovered(tmp_path):
    """An ill-conditioned plan warns, and noiseless data are still fitted to round-off.

    q3 varies by 1e-4 deg, so the phasor columns of links 2 and 3 are nearly parallel
    (:func:`phasor_condition` ~ 1e6) and :func:`recovery_tolerance` grows with it.
    """
    case = NEAR_SINGULAR[4]
    robot, plan, meas = _near_singular_files(tmp_path, case)
    cond = phasor_condition(numbers(plan))
    assert cond > 1e4  # the plan is ill-conditioned by any measure
    run = cli("identify", "--robot", robot, "--measurements", meas, "--sigma", 0.05, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "ill-conditioned" in codes(document)
    values, _ = parameters(document)
    # paper-3link's default truth: the paper's deviations of its first three links
    assert_recovered(values, PAPER_DL[:3], PAPER_DQ[:3], PAPER_LINKS[:3], cond)


# -------------------------------------------------- 5. barely observable compliance

VERTICAL = """
name = "vertical"
link_lengths_mm = [600.0, 450.0, 200.0]
{base}
[measurement]
sigma_mm = 0.02
{gravity}
[elastostatic]
{gravity_xy}
link_masses_kg = {masses}
payload_kg = {payload}
"""

COMPLIANCE_TRUTH = "k_urad_per_Nm = [1.5, 3.0, 6.0]\n"


def _vertical(tmp_path, *, masses="[20, 12, 6]", payload=10, three_d=None) -> Path:
    text = VERTICAL.format(
        base="base_offset = true" if three_d else "",
        gravity=f"gravity = {three_d}" if three_d else "",
        gravity_xy="" if three_d else "gravity_xy = [0, -1]",
        masses=masses,
        payload=payload,
    )
    path = tmp_path / "vertical.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _compliant_data(tmp_path, robot, q_deg, seed=1, sigma="0.02"):
    plan = write_plan(tmp_path / "plan.csv", q_deg)
    truth = truth_file(tmp_path / "truth.toml", DL3, DQ3, COMPLIANCE_TRUTH)
    meas = tmp_path / "meas.csv"
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--seed", seed,
              "--sigma", sigma, "-o", meas)  # fmt: skip
    check(run, 0, meas)
    return plan, meas


@pytest.mark.parametrize(
    ("case", "jitter"), [("one-configuration", 0.0), ("jitter-1e-6deg", 1e-6)]
)
def test_compliance_at_one_configuration_is_a_clear_error(tmp_path, case, jitter):
    robot = _vertical(tmp_path)
    rng = np.random.default_rng(2)
    q = np.array([10.0, 20.0, 30.0]) + jitter * rng.uniform(-1, 1, (40, 3))
    plan, meas = _compliant_data(tmp_path, robot, q)
    for run in (
        cli("identify", "--robot", robot, "--measurements", meas, "--json"),
        cli("evaluate", "--robot", robot, "--plan", plan, "--json"),
    ):
        line = error_line(run)
        # the torques do not vary: a constant torque is a joint offset (docs/compliance.md)
        assert "cannot identify" in line and "k1" in line


def test_compliance_with_gravity_nearly_normal_to_the_plane_is_a_clear_error(tmp_path):
    # a levelled tracker sees the arm move in its x-y plane: gravity [0, 1e-6, -1] has an
    # in-plane part of 1e-6 g, so nothing twists the joints measurably
    robot = _vertical(tmp_path, three_d="[0, 1e-6, -1]")
    q = np.random.default_rng(4).uniform(-150, 150, (40, 3))
    base = (20.0, -30.0)
    xy = tips(q, [600.0, 450.0, 200.0], DL3, DQ3) + base
    meas = write_measurements(tmp_path / "meas3d.csv", q, xy, z=5.0)
    line = error_line(cli("identify", "--robot", robot, "--measurements", meas, "--json"))
    assert "gravity is normal to the plane" in line


def _tiny_masses_fit(tmp_path):
    robot = _vertical(tmp_path, masses="[1e-6, 1e-6, 1e-6]", payload=0)
    q = np.random.default_rng(4).uniform(-150, 150, (40, 3))
    _, meas = _compliant_data(tmp_path, robot, q)
    run = cli("identify", "--robot", robot, "--measurements", meas, "--json")
    return run


def test_compliance_of_tiny_masses_is_honestly_uncertain(tmp_path):
    """Links of 1 mg: the joints' torques are ~1e-5 N*m and their compliance is invisible.

    Lower bound on std(k_j): least squares gives var(k_j) >= sigma^2 / |J_k|^2, and every
    entry of the column J_k is at most 1e-6 rad/(N*m) per urad/(N*m) times the largest
    torque (g * 3 mg * 1.25 m = 3.7e-5 N*m) times the largest lever arm (1250 mm):
    4.6e-8 mm.  Over 80 coordinates |J_k| <= 4.1e-7 mm, so std(k_j) >= 0.02 / 4.1e-7 =
    4.9e4 urad/(N*m).  The geometry is still identified as well as ever.
    """
    run = _tiny_masses_fit(tmp_path)
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    values, std = parameters(document)
    assert all(std[f"k{j}"] > 4e4 for j in (1, 2, 3))
    assert all(math.isfinite(values[f"k{j}"]) for j in (1, 2, 3))
    geometry = [f"dl{i}" for i in (1, 2, 3)] + [f"dq{i}" for i in (1, 2, 3)]
    assert all(abs(values[k] - t) < 5 * std[k] for k, t in zip(geometry, DL3 + DQ3, strict=True))


def test_compliance_of_tiny_masses_warns(tmp_path):
    run = _tiny_masses_fit(tmp_path)
    printed = check(run, 0)
    document = load_json(run.out)
    assert document["warnings"] and printed
    assert "compliance-unseen" in codes(document)


# -------------------------------------------------------------- spot checks: sigma


@pytest.mark.parametrize("sigma", [1e-6, 1e3])
def test_sigma_at_the_ends_of_its_range(tmp_path, sigma):
    m, n = 20, 4
    plan, meas = tmp_path / "plan.csv", tmp_path / "meas.csv"
    check(cli("design", "--poses", m, "-o", plan), 0, plan)
    run = cli("evaluate", "--plan", plan, "--sigma", sigma, "--json")
    check(run, 0)
    evaluated = load_json(run.out)
    std = [evaluated["predicted_std"][k] for k in names(n)]
    assert_allclose(std, orthogonal_std(PAPER_LINKS, sigma, m), rtol=1e-9)
    expected_rms = sigma * math.sqrt(2 * n / m)
    assert evaluated["predicted_position_rms_mm"] == pytest.approx(expected_rms, rel=1e-9)

    run = cli("simulate", "--plan", plan, "--sigma", sigma, "--trials", 300, "--json")
    check(run, 0)
    simulated = load_json(run.out)
    if sigma < 1:
        # linear regime (sigma / link ~ 1e-8): the Monte Carlo meets the prediction
        empirical = np.array([simulated["empirical_std"][k] for k in names(n)])
        assert_allclose(empirical, orthogonal_std(PAPER_LINKS, sigma, m), rtol=0.2)

    check(cli("synthesize", "--plan", plan, "--sigma", sigma, "--seed", 4, "-o", meas), 0, meas)
    run = cli(
        "identify", "--robot", "paper-4link", "--measurements", meas, "--sigma", sigma, "--json"
    )
    if sigma > 1:
        # 1 m of noise on a 660 mm arm puts points beyond any reach: refused, row named
        line = error_line(run)
        assert "reach" in line and "row" in line
        return
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    values, std = parameters(document)
    lengths = np.add(PAPER_LINKS, [values[f"dl{i}"] for i in range(1, 5)])
    assert_allclose([std[k] for k in names(n)], orthogonal_std(lengths, sigma, m), rtol=1e-6)
    error = np.array([values[k] for k in names(n)]) - np.array(PAPER_DL + PAPER_DQ)
    assert np.all(np.abs(error) < 5 * np.array([std[k] for k in names(n)]))


@pytest.mark.parametrize("sigma", ["1e-12", "1e6", "0.0"])
@pytest.mark.parametrize("command", ["evaluate", "simulate", "identify"])
def test_sigma_beyond_any_instrument_is_a_clear_error(tmp_path, sigma, command):
    angles = np.outer(np.arange(8), [45.0, 90.0, 135.0, 45.0]) % 360 - 180
    plan = write_plan(tmp_path / "plan.csv", angles)
    source = ("--measurements", plan) if command == "identify" else ("--plan", plan)
    line = error_line(cli(command, *source, "--sigma", sigma))
    assert "--sigma" in line


def _table_std(text: str, name: str, pattern: str) -> float:
    for line in text.splitlines():
        found = re.match(rf"^{name}\s+{pattern}", line)
        if found:
            return float(found.group(1))
    raise AssertionError(f"no row {name} in:\n{text}")


@pytest.mark.parametrize("command", ["identify", "evaluate", "simulate"])
def test_tiny_sigma_text_tables_show_the_std(tmp_path, command):
    sigma, m = 1e-6, 20
    plan, meas = tmp_path / "plan.csv", tmp_path / "meas.csv"
    check(cli("design", "--poses", m, "-o", plan), 0, plan)
    check(cli("synthesize", "--plan", plan, "--sigma", sigma, "--seed", 4, "-o", meas), 0, meas)
    expected = sigma / math.sqrt(m)  # std(dl1) of an orthogonal plan, 2.2e-7 mm
    if command == "identify":
        run = cli("identify", "--robot", "paper-4link", "--measurements", meas, "--sigma", sigma)
        shown = _table_std(run.out, "dl1", r"\S+\s+±\s+(\S+)")
    elif command == "evaluate":
        run = cli("evaluate", "--plan", plan, "--sigma", sigma)
        shown = _table_std(run.out, "dl1", r"(\S+)\s+mm")
    else:
        run = cli("simulate", "--plan", plan, "--sigma", sigma, "--trials", 300)
        shown = _table_std(run.out, "dl1", r"\S+\s+\S+\s+\S+\s+(\S+)")  # predicted std
    check(run, 0)
    assert shown == pytest.approx(expected, rel=0.05)


# ------------------------------------------------- spot checks: +-180 deg and limits


def test_angles_at_exactly_plus_and_minus_180(tmp_path):
    robot, n = "paper-3link", 3
    truth = truth_file(tmp_path / "truth.toml", DL3, DQ3)
    k = np.arange(8)
    q = np.column_stack([-20.0 + 10 * k, 45.0 * k, 45.0 * k])
    q = np.where(q > 180, q - 360, q)
    q[4] = [180.0, 180.0, -180.0]
    q = np.vstack([q, [-180.0, -180.0, 180.0]])  # the same pose as row 5, written otherwise
    plan, meas = write_plan(tmp_path / "plan.csv", q), tmp_path / "meas.csv"
    check(cli("evaluate", "--robot", robot, "--plan", plan), 0)
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    data = numbers(meas)
    assert_allclose(data[:, :n], q, rtol=0, atol=1e-12)  # +180 stays +180, -180 stays -180
    tol_mm, _ = recovery_tolerance(PAPER_LINKS[:3])
    assert_allclose(data[:, n:], tips(q, PAPER_LINKS[:3], DL3, DQ3), rtol=0, atol=tol_mm)
    assert_allclose(data[4, n:], data[8, n:], rtol=0, atol=tol_mm)
    run = cli("identify", "--robot", robot, "--measurements", meas, "--sigma", 0.05, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "beyond-limits" not in codes(document)  # +-180 is within the built-ins' range
    values, _ = parameters(document)
    assert_recovered(values, DL3, DQ3, PAPER_LINKS[:3], phasor_condition(q))


LIMITS = [[-90.0, 90.0], [-120.0, 120.0], [-45.0, 45.0]]


def _corner_plan() -> np.ndarray:
    """Every corner of the joint limits, and the centres of the faces: exactly at limits."""
    lo, hi = np.array(LIMITS).T
    corners = np.array([[a, b, c] for a in (0, 1) for b in (0, 1) for c in (0, 1)], float)
    faces = np.array([[0.5, 0.5, 0], [0.5, 0.5, 1], [0.5, 0, 0.5], [0.5, 1, 0.5]], float)
    return lo + np.vstack([corners, faces]) * (hi - lo)


def test_plan_exactly_at_the_joint_limits(tmp_path):
    robot = robot_file(tmp_path / "lim3.toml", PAPER_LINKS[:3], limits=LIMITS, sigma=0.05)
    truth = truth_file(tmp_path / "truth.toml", DL3, DQ3)
    plan, meas = write_plan(tmp_path / "plan.csv", _corner_plan()), tmp_path / "meas.csv"
    run = cli("evaluate", "--robot", robot, "--plan", plan, "--json")
    check(run, 0)
    assert 0 < load_json(run.out)["d_efficiency"] <= 1
    run = cli("synthesize", "--robot", robot, "--truth", truth, "--plan", plan, "--sigma", 0,
              "-o", meas)  # fmt: skip
    check(run, 0, meas)
    run = cli("identify", "--robot", robot, "--measurements", meas, "--json")
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert "beyond-limits" not in codes(document)
    assert "ill-conditioned" not in codes(document)
    values, _ = parameters(document)
    assert_recovered(values, DL3, DQ3, PAPER_LINKS[:3], phasor_condition(_corner_plan()))


@pytest.mark.parametrize(("beyond", "outcome"), [(0.0, "clean"), (1.5, "warning"), (2.5, "error")])
def test_measured_angle_beyond_a_limit(tmp_path, beyond, outcome):
    """PRODUCT.md / trust.md: up to 2 deg beyond a limit is accepted with a warning."""
    robot = robot_file(tmp_path / "lim3.toml", PAPER_LINKS[:3], limits=LIMITS, sigma=0.05)
    q = _corner_plan()
    q[0, 0] = LIMITS[0][0] - beyond  # row 1, q1 below its lower limit
    # consistent data: the arm really was at that angle
    meas = write_measurements(tmp_path / "meas.csv", q, tips(q, PAPER_LINKS[:3], DL3, DQ3))
    run = cli("identify", "--robot", robot, "--measurements", meas, "--json")
    if outcome == "error":
        line = error_line(run)
        assert "row 1" in line and "q1_deg" in line
        return
    printed = check(run, 0)
    document = load_json(run.out)
    same_warnings(document, printed)
    assert ("beyond-limits" in codes(document)) == (outcome == "warning")
    values, _ = parameters(document)
    # the reading beyond the limit is used as it is: the data are fitted to round-off
    assert_recovered(values, DL3, DQ3, PAPER_LINKS[:3], phasor_condition(q))


# ------------------------------------------------------- spot checks: poses-needed


def test_poses_needed_for_a_huge_target_is_the_smallest_identifying_plan(tmp_path):
    # 1 m of length std needs (sigma / A)^2 = 1e-8 poses by the 1/sqrt(m) law: the answer
    # is the fewest poses that identify the 8 parameters, ceil(8 / 2) = 4
    run = cli("poses-needed", "--length-std-mm", 1e3, "--json")
    check(run, 0)
    assert load_json(run.out)["poses"] == 4


def test_poses_needed_for_a_vanishing_target_is_a_clear_error_in_a_real_process(tmp_path):
    run = run_cli(tmp_path, "poses-needed", "--length-std-mm", "1e-300")
    check(Run(run.returncode, run.stdout, run.stderr), 2)


@pytest.mark.parametrize("target", ["--angle-std-deg", "--position-rms-mm"])
def test_poses_needed_for_a_vanishing_target_is_a_clear_error(target):
    check(cli("poses-needed", target, "1e-300"), 2)
