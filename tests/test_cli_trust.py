"""The silent cases of issue 9, through the real program: each is a warning or exit 2.

Every case runs the program (:func:`helpers.run_cli`, in-process, its streams
captured) on files written here.
Positions come from the model written out independently (paper eq. 1) with the
paper's deviations and seeded noise, so every expected number is derived here,
not taken from the program's output.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from helpers import deviated_tip, run_cli

LINKS_MM = (260.0, 180.0, 120.0, 100.0)
DL_MM = (1.5, -0.6, -0.4, 0.7)
DQ_DEG = (0.5, -0.5, 0.7, -0.3)
NAMES = ("dl1", "dl2", "dl3", "dl4", "dq1", "dq2", "dq3", "dq4")
JOINTS = ("q1_deg", "q2_deg", "q3_deg", "q4_deg")
SIGMA_MM = 0.02
SIGMA_ROBOT = (
    'name = "tracked"\nlink_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n'
    f"[measurement]\nsigma_mm = {SIGMA_MM}\n"
)
#: Rows (1-based) and offsets (mm) of the two gross outliers: 3.35 mm and 4.30 mm.
OUTLIERS = {7: (3.0, 1.5), 20: (-2.5, 3.5)}


def _tip(q_deg, dl=DL_MM, dq=DQ_DEG, links=LINKS_MM) -> tuple[float, float]:
    return deviated_tip(q_deg, links, dl, dq)


def _plan(m: int, seed: int = 9, limit_deg: float = 170.0) -> np.ndarray:
    """``m`` poses uniform within +-limit_deg on every joint."""
    return np.random.default_rng(seed).uniform(-limit_deg, limit_deg, (m, len(JOINTS)))


def _positions(plan_deg, sigma=SIGMA_MM, seed=5, **model) -> np.ndarray:
    exact = np.array([_tip(q, **model) for q in plan_deg])
    return exact + np.random.default_rng(seed).normal(0.0, sigma, exact.shape)


def _csv(plan_deg, xy, *, joints=JOINTS, extra: dict[str, list] | None = None) -> str:
    extra = extra or {}
    lines = [",".join([*joints, "x_mm", "y_mm", *extra])]
    for i, (q, p) in enumerate(zip(plan_deg, xy, strict=True)):
        fields = [repr(float(v)) for v in (*q, *p)] + [str(v[i]) for v in extra.values()]
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


def _plan_csv(plan_deg) -> str:
    rows = (",".join(repr(float(v)) for v in q) for q in plan_deg)
    return "\n".join([",".join(JOINTS), *rows]) + "\n"


def _no_nan(text: str) -> dict:
    def refuse(constant: str) -> float:
        raise AssertionError(f"{constant} in JSON")

    return json.loads(text, parse_constant=refuse)


def _warnings(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("armcal: warning: ")]


def _assert_error(result, *expected: str) -> str:
    assert "Traceback" not in result.stderr, result.stderr
    assert result.returncode == 2, result.stderr
    message = result.stderr.removesuffix("\n")
    assert len(message.splitlines()) == 1 and message.startswith("armcal: error: "), message
    for text in expected:
        assert text in message, f"{text!r} not in {message!r}"
    assert result.stdout == ""
    return message


def _assert_warned_once(result, document: dict, code: str, *expected: str) -> str:
    """One stderr line and one JSON entry for the warning ``code``, saying ``expected``."""
    entries = [w for w in document["warnings"] if w["code"] == code]
    assert len(entries) == 1, document["warnings"]
    message = entries[0]["message"]
    for text in expected:
        assert text in message, f"{text!r} not in {message!r}"
    lines = _warnings(result)
    assert lines.count(f"armcal: warning: {message}") == 1, result.stderr
    assert len(lines) == len(set(lines)) == len(document["warnings"]), result.stderr
    return message


# --------------------------------------------------------------------------- outliers


def _outlier_files(tmp_path: Path) -> np.ndarray:
    plan = _plan(30)
    xy = _positions(plan)
    for row, offset in OUTLIERS.items():
        xy[row - 1] += offset
    (tmp_path / "robot.toml").write_text(SIGMA_ROBOT)
    (tmp_path / "meas.csv").write_text(_csv(plan, xy))
    return plan


def test_two_outliers_plain_fit_warns_naming_the_rows(tmp_path):
    _outlier_files(tmp_path)
    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "-o", "cal.json")
    result = run_cli(tmp_path, *argv, "--json")

    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    assert _no_nan((tmp_path / "cal.json").read_text()) == document
    _assert_warned_once(result, document, "outlier", "row 7", "row 20", "--robust")
    # The chi-square is far beyond 2m - p = 52 with 3-4 mm errors at sigma 0.02 mm.
    _assert_warned_once(result, document, "fit-inconsistent", "outliers")
    assert [(o["row"], o["removed"]) for o in document["outliers"]] == [(7, False), (20, False)]
    fit = document["goodness_of_fit"]
    assert fit["dof"] == 2 * 30 - 8 and fit["p_value"] < 1e-3


def test_two_outliers_robust_fit_leaves_them_out_and_stays_on_the_truth(tmp_path):
    _outlier_files(tmp_path)
    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--robust")
    result = run_cli(tmp_path, *argv, "--json")

    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    outliers = document["outliers"]
    assert [(o["row"], o["pose"], o["removed"]) for o in outliers] == [
        (7, "7", True),
        (20, "20", True),
    ]
    for o in outliers:  # the offsets are far beyond the noise, so the residual is about them
        assert o["residual_mm"] == pytest.approx(math.hypot(*OUTLIERS[o["row"]]), abs=0.3)
    assert document["robust"] is True and document["poses_used"] == 28
    truth = dict(zip(NAMES, (*DL_MM, *DQ_DEG), strict=True))
    for parameter in document["parameters"]:
        error = abs(parameter["value"] - truth[parameter["name"]])
        assert error <= 4 * parameter["std"], parameter
    assert document["goodness_of_fit"]["dof"] == 2 * 28 - 8
    _assert_warned_once(result, document, "outlier", "row 7", "row 20")


# --------------------------------------------------------------------------- wrong units


def _identify_error(tmp_path: Path, csv_text: str, robot: str | None = None):
    (tmp_path / "meas.csv").write_text(csv_text)
    argv = ["identify", "--robot", "paper-4link", "--measurements", "meas.csv", "-o", "cal.json"]
    if robot is not None:
        (tmp_path / "robot.toml").write_text(robot)
        argv += ["--robot", "robot.toml"]
    result = run_cli(tmp_path, *argv)
    assert not (tmp_path / "cal.json").exists()
    return result


@pytest.mark.parametrize("robot", [None, SIGMA_ROBOT], ids=["sigma-estimated", "sigma-given"])
def test_angles_in_radians_under_deg_columns_are_an_error(tmp_path, robot):
    plan = _plan(30)
    csv_text = _csv(np.radians(plan), _positions(plan))  # radians written under q*_deg
    result = _identify_error(tmp_path, csv_text, robot)
    _assert_error(result, "meas.csv", "q1_deg..q4_deg", "radians", "convert them to degrees")


@pytest.mark.parametrize("robot", [None, SIGMA_ROBOT], ids=["sigma-estimated", "sigma-given"])
def test_positions_in_metres_under_mm_columns_are_an_error(tmp_path, robot):
    plan = _plan(30)
    result = _identify_error(tmp_path, _csv(plan, _positions(plan) / 1000.0), robot)
    _assert_error(result, "meas.csv", "x_mm, y_mm", "metres", "convert them to mm")


def test_tracker_data_without_a_base_offset_are_an_error(tmp_path):
    """A frame 72 mm from the base: within reach, but the fit improves a millionfold."""
    plan = _plan(30)
    xy = _positions(plan) + np.array([60.0, -40.0])
    result = _identify_error(tmp_path, _csv(plan, xy), SIGMA_ROBOT)
    _assert_error(result, "meas.csv", "base offset", "set base_offset = true")


def test_tracker_data_far_from_the_base_are_beyond_reach(tmp_path):
    """A tracker 1.7 m away: points beyond the 660 mm arm's reach, and the fix."""
    plan = _plan(30)
    xy = _positions(plan) + np.array([1500.0, 800.0])
    far = int(np.argmax(np.hypot(xy[:, 0], xy[:, 1]))) + 1
    result = _identify_error(tmp_path, _csv(plan, xy))
    _assert_error(result, "meas.csv", f"row {far} ", "reach", "set base_offset = true")


def test_a_value_beyond_any_reach_is_an_error_naming_row_column_and_value(tmp_path):
    plan = _plan(30)
    xy = _positions(plan)
    xy[11, 0] = 5e8
    result = _identify_error(tmp_path, _csv(plan, xy))
    _assert_error(result, "meas.csv", "row 12 (line 13)", "column x_mm", "5e+08", "reach")


def test_clean_files_pass_without_a_word(tmp_path):
    """Control: the files the cases above are derived from give no error and no warning."""
    plan = _plan(30)
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan)))
    (tmp_path / "robot.toml").write_text(SIGMA_ROBOT)
    for robot in ("paper-4link", "robot.toml"):
        result = run_cli(tmp_path, "identify", "--robot", robot, "--measurements", "meas.csv")
        assert result.returncode == 0 and result.stderr == "", result.stderr


# --------------------------------------------------------------------------- robot files


RADIAN_LIMITS = (
    "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n"
    "joint_limits_deg = [[-2.97, 2.97], [-2.09, 2.09], [-2.97, 2.97], [-2.09, 2.09]]\n"
)


@pytest.mark.parametrize(
    "argv",
    [
        ("evaluate", "--plan", "plan.csv", "--json"),
        ("simulate", "--plan", "plan.csv", "--truth", "truth.toml", "--trials", "20", "--json"),
        ("synthesize", "--plan", "plan.csv", "--truth", "truth.toml", "-o", "m.csv", "--json"),
    ],
    ids=lambda argv: argv[0],
)
def test_joint_limits_in_radians_are_a_warning_in_every_command(tmp_path, argv):
    plan = _plan(12, limit_deg=2.0)
    (tmp_path / "plan.csv").write_text(_plan_csv(plan))
    (tmp_path / "robot.toml").write_text(RADIAN_LIMITS)
    (tmp_path / "truth.toml").write_text(f"dl_mm = {list(DL_MM)}\ndq_deg = {list(DQ_DEG)}\n")

    result = run_cli(tmp_path, *argv, "--robot", "robot.toml")

    assert result.returncode == 0, result.stderr
    # 2.97 rad = 170.2 deg: the fix in the unit the file asks for.
    _assert_warned_once(
        result, _no_nan(result.stdout), "limits-radians", "robot.toml", "radians", "170.2"
    )


def test_three_poses_with_sigma_given_warn_of_too_few_degrees_of_freedom(tmp_path):
    links, dl, dq = LINKS_MM[:2], DL_MM[:2], DQ_DEG[:2]
    plan = np.array([[0.0, 0.0], [0.0, 90.0], [90.0, 90.0]])
    xy = _positions(plan, links=links, dl=dl, dq=dq)
    (tmp_path / "meas.csv").write_text(_csv(plan, xy, joints=JOINTS[:2]))
    (tmp_path / "robot.toml").write_text(
        "link_lengths_mm = [260.0, 180.0]\n[measurement]\nsigma_mm = 0.02\n"
    )
    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json")
    result = run_cli(tmp_path, *argv)

    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    # 2 m - p = 6 - 4 = 2 degrees of freedom.
    assert document["goodness_of_fit"]["dof"] == 2
    _assert_warned_once(result, document, "few-dof", "2 degrees of freedom")


def test_a_measured_angle_just_beyond_a_limit_is_accepted_with_a_warning(tmp_path):
    plan = _plan(20, limit_deg=140.0)
    plan[4, 1] = 145.004
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan)))
    (tmp_path / "robot.toml").write_text(
        "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n"
        "joint_limits_deg = [[-170, 170], [-145, 145], [-170, 170], [-145, 145]]\n"
    )
    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json")
    result = run_cli(tmp_path, *argv)

    assert result.returncode == 0, result.stderr
    _assert_warned_once(
        result, _no_nan(result.stdout), "beyond-limits", "row 5 q2_deg = 145.004", "meas.csv"
    )


# --------------------------------------------------------------------------- fixed parameters


@pytest.mark.parametrize(
    "argv",
    [
        ("identify", "--robot", "paper-4link", "--measurements", "meas.csv"),
        ("design", "--poses", "12"),
        ("evaluate", "--plan", "plan.csv"),
        ("simulate", "--plan", "plan.csv", "--trials", "10"),
        ("poses-needed", "--length-std-mm", "0.01"),
    ],
    ids=lambda argv: argv[0],
)
def test_fix_with_an_unknown_name_lists_the_valid_ones(tmp_path, argv):
    plan = _plan(20)
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan)))
    (tmp_path / "plan.csv").write_text(_plan_csv(plan))
    result = run_cli(tmp_path, *argv, "--fix", "dl4,dl9")
    _assert_error(result, "--fix", "'dl9'", "dl1, dl2, dl3, dl4, dq1, dq2, dq3, dq4")


FIXED_DL4 = (
    'name = "known-dl4"\nlink_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n'
    f"[measurement]\nsigma_mm = {SIGMA_MM}\n"
    '[identify]\nfixed = ["dl4"]\n'
)


def test_a_known_link_length_is_held_and_the_rest_recovered_from_noiseless_data(tmp_path):
    """dl4 measured otherwise (0 here: the nominal 100 mm is right); the rest recovered."""
    dl = (1.5, -0.6, -0.4, 0.0)
    plan = _plan(20)
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan, sigma=0.0, dl=dl)))
    (tmp_path / "robot.toml").write_text(FIXED_DL4)
    (tmp_path / "plain.toml").write_text(FIXED_DL4.split("[identify]")[0])
    for robot, fix in (("robot.toml", ()), ("plain.toml", ("--fix", "dl4"))):
        result = run_cli(
            tmp_path, "identify", "--robot", robot, "--measurements", "meas.csv", *fix, "--json"
        )
        assert result.returncode == 0, result.stderr
        document = _no_nan(result.stdout)
        # Noiseless data are too good for the file's sigma, and say so; nothing else.
        assert [w["code"] for w in document["warnings"]] == ["fit-too-good"], result.stderr
        assert document["fixed"] == ["dl4"]
        values = {p["name"]: p for p in document["parameters"]}
        expected = {"name": "dl4", "unit": "mm", "value": 0.0, "std": 0.0, "fixed": True}
        assert values["dl4"] == expected
        # Noiseless data: round-off of a 20-pose fit, about 1e-12 mm and deg.
        for name, true_value in zip(NAMES, (*dl, *DQ_DEG), strict=True):
            assert values[name]["value"] == pytest.approx(true_value, abs=1e-9), name
            assert values[name]["fixed"] is (name == "dl4")
        text = run_cli(tmp_path, "identify", "--robot", robot, "--measurements", "meas.csv", *fix)
        lines = text.stdout.splitlines()
        assert "fixed (held at nominal, not identified): dl4" in lines
        assert any(line.split()[:3] == ["dl4", "0.00000", "fixed"] for line in lines)


def test_fixed_parameters_reach_evaluate(tmp_path):
    plan = _plan(20)
    (tmp_path / "plan.csv").write_text(_plan_csv(plan))
    result = run_cli(tmp_path, "evaluate", "--plan", "plan.csv", "--fix", "dl4,dq1", "--json")
    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    assert document["fixed"] == ["dl4", "dq1"]
    assert document["predicted_std"]["dl4"] == 0.0 and document["predicted_std"]["dq1"] == 0.0
    assert all(document["predicted_std"][name] > 0 for name in NAMES if name not in ("dl4", "dq1"))


# --------------------------------------------------------------------------- noise models


def test_sigma_option_replaces_the_instrument_noise_and_keeps_the_encoder_noise(tmp_path):
    plan = _plan(30)
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan)))
    (tmp_path / "robot.toml").write_text(
        "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n"
        "[measurement]\nsigma_mm = [0.08, 0.02]\njoint_sigma_deg = 0.001\n"
    )
    argv = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json")
    document = _no_nan(run_cli(tmp_path, *argv).stdout)
    assert document["noise"]["covariance_mm2"] == [[0.08**2, 0.0], [0.0, 0.02**2]]
    assert document["noise"]["joint_sigma_deg"] == [pytest.approx(0.001, rel=1e-12)]

    document = _no_nan(run_cli(tmp_path, *argv, "--sigma", "0.05").stdout)
    assert document["noise"]["covariance_mm2"] == [[0.05**2, 0.0], [0.0, 0.05**2]]
    assert document["noise"]["joint_sigma_deg"] == [pytest.approx(0.001, rel=1e-12)]
    assert document["sigma_source"] == "given"


def test_per_row_sigma_column_weights_the_fit(tmp_path):
    """chi2 = sum over poses of |e_i|^2 / s_i^2, from the file's sigma_mm and the residuals."""
    plan = _plan(30)
    row_sigma = np.where(np.arange(30) % 2 == 0, 0.02, 0.05)
    exact = np.array([_tip(q) for q in plan])
    xy = exact + np.random.default_rng(3).normal(0.0, 1.0, (30, 2)) * row_sigma[:, None]
    (tmp_path / "meas.csv").write_text(_csv(plan, xy, extra={"sigma_mm": list(row_sigma)}))
    argv = ("identify", "--robot", "paper-4link", "--measurements", "meas.csv", "--json")
    result = run_cli(tmp_path, *argv)

    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    assert document["sigma_source"] == "given"
    residuals = np.array([[r["dx_mm"], r["dy_mm"]] for r in document["residuals"]])
    chi2 = float(np.sum((residuals / row_sigma[:, None]) ** 2))
    assert document["goodness_of_fit"]["chi2"] == pytest.approx(chi2, rel=1e-9)
    assert document["goodness_of_fit"]["dof"] == 2 * 30 - 8


def test_standardized_residuals_are_the_residuals_over_sigma(tmp_path):
    plan = _plan(30)
    (tmp_path / "meas.csv").write_text(_csv(plan, _positions(plan)))
    argv = (
        "identify",
        "--robot",
        "paper-4link",
        "--measurements",
        "meas.csv",
        "--sigma",
        "0.02",
        "--json",
    )
    document = _no_nan(run_cli(tmp_path, *argv).stdout)
    assert [r["row"] for r in document["standardized_residuals"]] == list(range(1, 31))
    for r, z in zip(document["residuals"], document["standardized_residuals"], strict=True):
        assert z["x"] == pytest.approx(r["dx_mm"] / 0.02, rel=1e-9, abs=1e-12)
        assert z["y"] == pytest.approx(r["dy_mm"] / 0.02, rel=1e-9, abs=1e-12)
    assert document["noise"] == {
        "covariance_mm2": [[0.02**2, 0.0], [0.0, 0.02**2]],
        "joint_sigma_deg": None,
    }


def test_a_noise_model_that_is_not_isotropic_iid_is_said_in_reports(tmp_path):
    plan = _plan(20)
    (tmp_path / "plan.csv").write_text(_plan_csv(plan))
    (tmp_path / "robot.toml").write_text(
        "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\n[measurement]\nsigma_mm = [0.08, 0.02]\n"
    )
    text = run_cli(tmp_path, "evaluate", "--robot", "robot.toml", "--plan", "plan.csv")
    assert text.returncode == 0, text.stderr
    assert "noise model: instrument per axis, sigma_x 0.08 mm, sigma_y 0.02 mm" in text.stdout
    assert "assume isotropic iid" in text.stdout
    document = _no_nan(
        run_cli(
            tmp_path, "evaluate", "--robot", "robot.toml", "--plan", "plan.csv", "--json"
        ).stdout
    )
    assert document["noise_isotropic_iid"] is False
    # sigma_ref = sqrt(2 / (1 / 0.08^2 + 1 / 0.02^2)) (armcal.noise)
    assert document["sigma_mm"] == pytest.approx(math.sqrt(2 / (1 / 0.0064 + 1 / 0.0004)))


def test_simulating_a_fixed_parameter_the_truth_moves_is_a_warning(tmp_path):
    """The built-in truth has dl4 = 0.7 mm; held at 0, dl4 is off by exactly that."""
    (tmp_path / "plan.csv").write_text(_plan_csv(_plan(20)))
    argv = ("simulate", "--plan", "plan.csv", "--trials", "50", "--fix", "dl4", "--json")
    result = run_cli(tmp_path, *argv)
    assert result.returncode == 0, result.stderr
    document = _no_nan(result.stdout)
    _assert_warned_once(result, document, "fixed-not-nominal", "dl4 = 0.7 mm")
    assert document["fixed"] == ["dl4"]
    assert document["bias"]["dl4"] == pytest.approx(-0.7, abs=1e-12)
