"""Files: robot and truth TOML, plan and measurement CSV, calibration JSON."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import Annulus, Box, InputError, forward_kinematics, identify, orthogonal_plan
from armcal.io import (
    format_measurements_csv,
    format_plan_csv,
    load_robot,
    load_truth,
    read_measurements,
    read_plan,
)
from armcal.report import calibration_to_dict, to_json


def test_builtin_robots_carry_the_paper_geometry_and_truth():
    for n in (2, 3, 4):
        spec = load_robot(f"paper-{n}link")
        assert spec.arm.link_lengths.tolist() == [260.0, 180.0, 120.0, 100.0][:n]
        assert_allclose(np.degrees(spec.arm.joint_limits), [[-180.0, 180.0]] * n)
        assert not spec.arm.base_offset and spec.arm.sigma is None
        values = spec.default_truth * spec.arm.display_scale
        assert_allclose(values[:n], [1.5, -0.6, -0.4, 0.7][:n], rtol=0, atol=1e-15)
        assert_allclose(values[n:], [0.5, -0.5, 0.7, -0.3][:n], rtol=0, atol=1e-13)


def test_full_robot_file(tmp_path):
    path = tmp_path / "scara.toml"
    path.write_text(
        'name = "my-scara"\n'
        "link_lengths_mm = [260.0, 180, 120.0]\n"
        "joint_limits_deg = [[-170, 170], [-150, 150], [-90.5, 120]]\n"
        "base_offset = true\n"
        "[measurement]\n"
        "sigma_mm = 0.05\n"
        'region = { kind = "annulus", center_mm = [10, 0], r_min_mm = 150, r_max_mm = 600 }\n'
    )
    arm = load_robot(path).arm
    assert arm.name == "my-scara" and arm.base_offset and arm.sigma == 0.05
    assert arm.param_names[-2:] == ("x0", "y0")
    assert_allclose(np.degrees(arm.joint_limits[2]), [-90.5, 120.0], rtol=1e-14)
    assert arm.region == Annulus((10.0, 0.0), 150.0, 600.0)
    assert arm.region.contains(np.array([[200.0, 0.0], [10.0, 0.0]])).tolist() == [True, False]


def test_box_region_and_default_name(tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text(
        "link_lengths_mm = [1.0]\n"
        '[measurement]\nregion = { kind = "box", x_mm = [-1, 1], y_mm = [0, 2] }\n'
    )
    arm = load_robot(path).arm
    assert arm.name == "arm"
    assert arm.region == Box((-1.0, 1.0), (0.0, 2.0))


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("link_length_mm = [1.0]", "unknown key 'link_length_mm': did you mean 'link_lengths_mm'"),
        ("name = 'x'", "missing key 'link_lengths_mm'"),
        ("link_lengths_mm = [1.0, -2.0]", r"link_lengths_mm\[1\]"),
        ("link_lengths_mm = [1.0, true]", "expected a number"),
        ("link_lengths_mm = []", "at least one link"),
        ("link_lengths_mm = [1.0]\nbase_offset = 1", "true or false"),
        ("link_lengths_mm = [1.0]\njoint_limits_deg = [[10, -10]]", "lo < hi"),
        ("link_lengths_mm = [1.0, 1.0]\njoint_limits_deg = [[0, 10]]", "2 pairs"),
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 0", "must be > 0"),
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma = 0.1", "unknown key 'measurement.sigma'"),
        (
            "link_lengths_mm = [1.0]\n[measurement]\nregion = { kind = 'circle' }",
            "annulus.*box",
        ),
        (
            "link_lengths_mm = [1.0]\n[measurement]\n"
            "region = { kind = 'annulus', r_min_mm = 5, r_max_mm = 1 }",
            "r_min_mm < r_max_mm",
        ),
        ("link_lengths_mm = [1.0", "invalid TOML"),
    ],
)
def test_robot_file_errors_name_the_file_and_key(tmp_path, text, match):
    path = tmp_path / "robot.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=match) as info:
        load_robot(path)
    assert str(info.value).startswith(f"{path}: ")


def test_unknown_robot_name():
    with pytest.raises(InputError, match="neither a built-in"):
        load_robot("paper-5link")


def test_truth_file(tmp_path):
    arm = load_robot("paper-2link").arm
    path = tmp_path / "truth.toml"
    path.write_text("dl_mm = [1.0, -2.0]\ndq_deg = [0.5, 0.25]\n")
    assert_allclose(load_truth(path, arm), [1.0, -2.0, np.radians(0.5), np.radians(0.25)])
    path.write_text("dl_mm = [1.0, -2.0]\ndq_deg = [0.5, 0.25]\nbase_mm = [1, 2]\n")
    with pytest.raises(InputError, match="base_offset = false"):
        load_truth(path, arm)
    path.write_text("dl_mm = [1.0]\ndq_deg = [0.5, 0.25]\n")
    with pytest.raises(InputError, match="expected 2 numbers"):
        load_truth(path, arm)


def test_plan_round_trip_is_clean_and_exact(tmp_path):
    arm = load_robot("paper-4link").arm
    q = orthogonal_plan(arm, 12)
    path = tmp_path / "plan.csv"
    path.write_text(format_plan_csv(q))
    lines = path.read_text().splitlines()
    assert lines[0] == "q1_deg,q2_deg,q3_deg,q4_deg"
    assert lines[4] == "0.0,90.0,90.0,90.0"  # no 89.99999999999999
    assert_allclose(read_plan(path, arm), q, rtol=0, atol=1e-14)


def test_measurements_round_trip_keeps_full_precision(tmp_path, arm4, paper_truth4):
    q = orthogonal_plan(arm4, 8)
    xy = forward_kinematics(arm4, q, paper_truth4)
    path = tmp_path / "meas.csv"
    path.write_text(format_measurements_csv(q, xy, [f"P{i}" for i in range(8)]))
    meas = read_measurements(path, arm4)
    assert meas.labels[0] == "P0"
    assert np.array_equal(meas.xy, xy)


def test_measurement_columns_may_come_in_any_order_with_blank_lines(tmp_path, arm2):
    path = tmp_path / "meas.csv"
    path.write_text("x_mm, pose ,y_mm,q2_deg,q1_deg\n\n1.5,a,2.5,90,0\n\n")
    meas = read_measurements(path, arm2)
    assert_allclose(meas.q, [[0.0, np.pi / 2]])
    assert_allclose(meas.xy, [[1.5, 2.5]])
    assert meas.labels == ("a",)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "file is empty"),
        ("q1_deg,q2_deg,x_mm\n0,0,1\n", "missing column 'y_mm'"),
        ("q1_deg,q2_deg,x_mm,y_mm,z_mm\n0,0,1,2,3\n", "unknown column 'z_mm'"),
        ("q1_deg,q2_deg,x_mm,x_mm,y_mm\n0,0,1,1,2\n", "duplicate column 'x_mm'"),
        ("q1_deg,q2_deg,x_mm,y_mm\n", "no poses"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1\n", r"row 1 \(line 2\) has 3 fields"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1,2\n0,0,nan,2\n", r"row 2 \(line 3\), column x_mm"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1,2\n0,0,1,-inf\n", "y_mm: '-inf' is not a finite"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,abc,1,2\n", "column q2_deg: 'abc' is not a number"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,181,1,2\n", "outside joint 2's limits"),
        ("q1_deg,q2_deg,q3_deg,x_mm,y_mm\n0,0,0,1,2\n", "3 joint columns .* has 2 joints"),
        ("q1_deg,q3_deg,x_mm,y_mm\n0,0,1,2\n", "without gaps"),
    ],
)
def test_measurement_errors_name_file_row_and_column(tmp_path, arm2, text, match):
    path = tmp_path / "meas.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=match) as info:
        read_measurements(path, arm2)
    assert str(info.value).startswith(f"{path}: ")


def test_calibration_json_has_the_contract_keys(arm4, paper_truth4, rng):
    q = orthogonal_plan(arm4, 20)
    xy = forward_kinematics(arm4, q, paper_truth4) + rng.normal(0.0, 0.1, (20, 2))
    document = json.loads(to_json(calibration_to_dict(identify(arm4, q, xy, sigma=0.1))))
    assert document["format"] == "armcal-calibration/1"
    assert document["robot"]["link_lengths_mm"] == [260.0, 180.0, 120.0, 100.0]
    assert document["robot"]["base_offset"] is False
    assert (document["method"], document["poses"]) == ("closed-form", 20)
    assert (document["sigma_mm"], document["sigma_source"]) == (0.1, "given")
    names = [p["name"] for p in document["parameters"]]
    assert names == ["dl1", "dl2", "dl3", "dl4", "dq1", "dq2", "dq3", "dq4"]
    assert [p["unit"] for p in document["parameters"]] == ["mm"] * 4 + ["deg"] * 4
    cov = np.array(document["covariance"]["matrix"])
    assert_allclose(np.sqrt(np.diag(cov)), [p["std"] for p in document["parameters"]])
    assert document["converged"] is True and document["iterations"] == 1
    assert len(document["residuals"]) == 20
    assert 0.05 < document["residual_rms_mm"] < 0.15


def test_to_json_refuses_nan():
    with pytest.raises(ValueError):
        to_json({"x": float("nan")})
