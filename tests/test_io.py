"""Files: robot and truth TOML, plan and measurement CSV, calibration JSON."""

import hashlib
import json
import os
import stat

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import (
    Annulus,
    Box,
    InputError,
    PlanarArm,
    forward_kinematics,
    identify,
    orthogonal_plan,
)
from armcal.files import (
    MANIFEST,
    OutputFolder,
    atomic_write,
    calibration_document,
    check_outputs,
    format_measurements_csv,
    format_plan_csv,
    load_robot,
    load_truth,
    read_measurements,
    read_plan,
    to_json,
    write_folder,
    write_json,
)


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
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 0", "between 1e-06 and 1000 mm"),
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 5000", "check the unit"),
        ("link_lengths_mm = [1e-300, 1.0]", "link 1 length must be between 0.001 and 1e.07 mm"),
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
        # ---- noise model
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = [0.1]", "one number or two"),
        ("link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = [0.1, 0]", r"sigma_mm\[1\]"),
        (
            "link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 0.1\n"
            "covariance_mm2 = [[0.01, 0], [0, 0.01]]",
            "keep one",
        ),
        (
            "link_lengths_mm = [1.0]\n[measurement]\ncovariance_mm2 = [[0.01, 0.001], [0, 0.01]]",
            "symmetric",
        ),
        (
            "link_lengths_mm = [1.0]\n[measurement]\n"
            "covariance_mm2 = [[0.01, 0.02], [0.02, 0.01]]",
            "positive definite",
        ),
        ("link_lengths_mm = [1.0]\n[measurement]\ncovariance_mm2 = [0.01, 0.01]", r"2 x 2"),
        (
            "link_lengths_mm = [1.0]\n[measurement]\njoint_sigma_deg = 0.01",
            "needs the instrument noise",
        ),
        (
            "link_lengths_mm = [1.0, 1.0]\n[measurement]\nsigma_mm = 0.1\n"
            "joint_sigma_deg = [0.01, 0.01, 0.01]",
            "one number or 2",
        ),
        (
            "link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 0.1\njoint_sigma_deg = -0.01",
            "between 0 and 10 deg",
        ),
        (
            "link_lengths_mm = [1.0]\n[measurement]\nsigma_mm = 0.1\njoint_sigma_deg = 36",
            "check the unit",
        ),
        # ---- fixed and free parameters
        ("link_lengths_mm = [1.0, 1.0]\n[identify]\nfixed = ['dl3']", "dl1, dl2, dq1, dq2"),
        ("link_lengths_mm = [1.0, 1.0]\n[identify]\nfixed = ['x0']", "base_offset = true"),
        ("link_lengths_mm = [1.0]\n[identify]\nfixed = ['dl1']\nfree = ['dq1']", "keep one"),
        ("link_lengths_mm = [1.0]\n[identify]\nfree = []", "every parameter"),
        ("link_lengths_mm = [1.0]\n[identify]\nfixed = 'dl1'", "list of parameter names"),
        ("link_lengths_mm = [1.0]\n[identify]\nfix = ['dl1']", "did you mean 'fixed'"),
    ],
)
def test_robot_file_errors_name_the_file_and_key(tmp_path, text, match):
    path = tmp_path / "robot.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=match) as info:
        load_robot(path)
    assert str(info.value).startswith(f"{path}: ")


def test_robot_file_noise_models(tmp_path):
    path = tmp_path / "robot.toml"
    base = "link_lengths_mm = [260.0, 180.0]\n[measurement]\n"
    path.write_text(base + "sigma_mm = 0.05\n")
    noise = load_robot(path).arm.noise
    assert noise is not None and noise.isotropic_iid
    assert_allclose(noise.covariance_mm2, 0.05**2 * np.eye(2), rtol=1e-15)
    path.write_text(base + "sigma_mm = [0.08, 0.02]\njoint_sigma_deg = 0.01\n")
    noise = load_robot(path).arm.noise
    assert_allclose(noise.covariance_mm2, np.diag([0.08**2, 0.02**2]), rtol=1e-15)
    assert_allclose(noise.joint_sigma, [np.radians(0.01)], rtol=1e-15)
    # sigma_ref = sqrt(2 / tr(Sigma^-1)) = sqrt(2 / (1/0.0064 + 1/0.0004)) (noise.py)
    assert load_robot(path).arm.sigma == pytest.approx(np.sqrt(2 / (156.25 + 2500)), rel=1e-12)
    path.write_text(base + "covariance_mm2 = [[0.01, 0.004], [0.004, 0.0025]]\n")
    path.write_text(path.read_text() + "joint_sigma_deg = [0.01, 0.02]\n")
    noise = load_robot(path).arm.noise
    assert_allclose(noise.covariance_mm2, [[0.01, 0.004], [0.004, 0.0025]], rtol=1e-15)
    assert_allclose(noise.joint_sigma, np.radians([0.01, 0.02]), rtol=1e-15)
    path.write_text(base + "sigma_mm = 0.1\njoint_sigma_deg = 0\n")  # no encoder noise
    assert load_robot(path).arm.noise.joint_sigma is None


def test_robot_file_fixed_and_free_parameters(tmp_path):
    path = tmp_path / "robot.toml"
    lengths = "link_lengths_mm = [260.0, 180.0, 120.0, 100.0]\nbase_offset = true\n"
    path.write_text(lengths + "[identify]\nfixed = ['dl4', 'x0']\n")
    arm = load_robot(path).arm
    assert arm.fixed == ("dl4", "x0") and arm.n_free == 8
    path.write_text(lengths + "[identify]\nfree = ['dq1', 'dq2', 'dq3', 'dq4']\n")
    arm = load_robot(path).arm
    assert arm.free_names == ("dq1", "dq2", "dq3", "dq4")
    assert arm.fixed == ("dl1", "dl2", "dl3", "dl4", "x0", "y0")


def test_joint_limits_in_radians_are_a_warning(tmp_path):
    path = tmp_path / "robot.toml"
    lengths = "link_lengths_mm = [260.0, 180.0]\n"
    path.write_text(lengths + "joint_limits_deg = [[-2.97, 2.97], [-3.1416, 3.1416]]\n")
    spec = load_robot(path)
    assert [w.code for w in spec.warnings] == ["limits-radians"]
    message = spec.warnings[0].message
    assert message.startswith(f"{path}: key 'joint_limits_deg'")
    # The fix, in degrees: 2.97 rad = 170.2 deg.
    assert "radians" in message and "[-170.2, 170.2]" in message
    # Degrees, even a narrow joint among wide ones, give no warning.
    path.write_text(lengths + "joint_limits_deg = [[-170, 170], [-5, 5]]\n")
    assert load_robot(path).warnings == ()
    assert load_robot("paper-4link").warnings == ()


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


def test_measurements_rows_and_per_row_sigma(tmp_path, arm2):
    path = tmp_path / "meas.csv"
    path.write_text("q1_deg,q2_deg,x_mm,y_mm,sigma_mm\n0,0,440,0,0.05\n\n0,90,260,180,0.2\n")
    meas = read_measurements(path, arm2)
    assert meas.rows == (1, 2)
    assert_allclose(meas.row_sigma, [0.05, 0.2], rtol=0)
    assert meas.warnings == ()
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,440,0\n")
    assert read_measurements(path, arm2).row_sigma is None


def test_measured_angles_slightly_beyond_a_limit_are_a_warning(tmp_path):
    arm = PlanarArm([260.0, 180.0], np.radians([[-170, 170], [-145, 145]]), name="limited")
    path = tmp_path / "meas.csv"
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,440,0\n0,145.004,110,100\n0,-146.5,110,-100\n")
    meas = read_measurements(path, arm)
    assert_allclose(np.degrees(meas.q[1:, 1]), [145.004, -146.5], rtol=1e-14)
    assert [w.code for w in meas.warnings] == ["beyond-limits"]
    message = meas.warnings[0].message
    assert "row 2 q2_deg = 145.004" in message and "row 3 q2_deg = -146.5" in message
    # Beyond the tolerance (LIMIT_TOLERANCE_DEG = 2): an error, as before.
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,440,0\n0,147.5,110,100\n")
    with pytest.raises(InputError, match=r"row 2 \(line 3\), column q2_deg: 147.5 deg is outside"):
        read_measurements(path, arm)
    # Plans are held to the limits exactly.
    path.write_text("q1_deg,q2_deg\n0,145.004\n")
    with pytest.raises(InputError, match="outside joint 2's limits"):
        read_plan(path, arm)


def test_points_beyond_any_arms_reach_are_an_error(tmp_path, arm2):
    path = tmp_path / "meas.csv"
    # paper-2link reaches 440 mm; 10 % more is 484 mm.
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,440,0\n0,90,483,0\n")
    assert read_measurements(path, arm2).rows == (1, 2)
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,440,0\n0,90,260,5e8\n")
    with pytest.raises(InputError, match=r"row 2 \(line 3\), column y_mm: 5e\+08 .* reach"):
        read_measurements(path, arm2)
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,1400,800\n0,90,1200,980\n")
    with pytest.raises(InputError, match=r"column x_mm: 1400 .* set base_offset = true"):
        read_measurements(path, arm2)
    # With a base offset, points within 2 x 484 mm of their centroid are accepted.
    based = arm2.replace(base_offset=True)
    assert read_measurements(path, based).xy.shape == (2, 2)
    path.write_text("q1_deg,q2_deg,x_mm,y_mm\n0,0,1400,800\n0,90,1200,980\n0,0,3400,800\n")
    with pytest.raises(InputError, match=r"row 3 .* column x_mm: 3400 .* from the centroid"):
        read_measurements(path, based)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "file is empty"),
        ("q1_deg,q2_deg,x_mm\n0,0,1\n", "missing column 'y_mm'"),
        (
            "q1_deg,q2_deg,x_mm,y_mm,rz_deg\n0,0,1,2,3\n",
            "line 1: has rz_deg but not rx_deg, ry_deg",
        ),
        ("q1_deg,q2_deg,x_mm,x_mm,y_mm\n0,0,1,1,2\n", "duplicate column 'x_mm'"),
        ("q1_deg,q2_deg,x_mm,y_mm\n", "no poses"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1\n", r"row 1 \(line 2\) has 3 fields"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1,2\n0,0,nan,2\n", r"row 2 \(line 3\), column x_mm"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,0,1,2\n0,0,1,-inf\n", "y_mm: '-inf' is not a finite"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,abc,1,2\n", "column q2_deg: 'abc' is not a number"),
        ("q1_deg,q2_deg,x_mm,y_mm\n0,183,1,2\n", "outside joint 2's limits"),
        ("q1_deg,q2_deg,q3_deg,x_mm,y_mm\n0,0,0,1,2\n", "3 joint columns .* has 2 joints"),
        ("q1_deg,q3_deg,x_mm,y_mm\n0,0,1,2\n", "without gaps"),
        ("q1_deg,q2_deg,x_mm,y_mm,sigma_mm\n0,0,1,2,0\n", "column sigma_mm: 0 is not a noise"),
        ("q1_deg,q2_deg,x_mm,y_mm,sigma_mm\n0,0,1,2,-1\n", "column sigma_mm: -1"),
        ("q1_deg,q2_deg,x_mm,y_mm,sigma_mm\n0,0,1,2,x\n", "column sigma_mm: 'x' is not"),
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
    document = json.loads(to_json(calibration_document(identify(arm4, q, xy, sigma=0.1))))
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


# --------------------------------------------------------------------------- writing


def _umask() -> int:
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


def _mode(path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_atomic_write_through_a_link_keeps_the_link_and_the_mode(tmp_path):
    (tmp_path / "data").mkdir()
    target = tmp_path / "data" / "plan.csv"
    target.write_text("old\n")
    target.chmod(0o640)
    link = tmp_path / "plan.csv"
    link.symlink_to("data/plan.csv")
    atomic_write(link, "new\n")
    assert link.is_symlink() and os.readlink(link) == "data/plan.csv"
    assert target.read_text() == "new\n" and _mode(target) == 0o640
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["data", "plan.csv", "plan.csv"]


def test_atomic_write_through_a_dangling_link_makes_its_target(tmp_path):
    link = tmp_path / "out.csv"
    link.symlink_to("made.csv")
    atomic_write(link, b"bytes\n")
    assert link.is_symlink() and (tmp_path / "made.csv").read_bytes() == b"bytes\n"
    assert _mode(tmp_path / "made.csv") == 0o666 & ~_umask()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX FIFO")
def test_atomic_write_never_replaces_a_fifo_or_a_folder(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match=r"pipe: is a FIFO \(named pipe\), not a regular file"):
        atomic_write(fifo, "x")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    link = tmp_path / "link"
    link.symlink_to("pipe")  # a link is followed, and what it points to is checked
    with pytest.raises(InputError, match="FIFO"):
        atomic_write(link, "x")
    with pytest.raises(InputError, match="is a directory, expected a file"):
        atomic_write(tmp_path, "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "pipe"]


def test_atomic_write_interrupted_keeps_the_old_file(tmp_path):
    target = tmp_path / "cal.json"
    target.write_text("old\n")

    def interrupted(handle):
        handle.write(b"half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, interrupted)
    assert [p.name for p in tmp_path.iterdir()] == ["cal.json"]
    assert target.read_text() == "old\n"


def test_check_outputs_finds_an_input_under_any_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.csv").write_text("input\n")
    (tmp_path / "link.csv").symlink_to("m.csv")
    os.link(tmp_path / "m.csv", tmp_path / "hard.csv")
    inputs = {"--robot": None, "--measurements": "m.csv"}
    for name in ("m.csv", "./m.csv", str(tmp_path / "m.csv"), "link.csv", "hard.csv"):
        with pytest.raises(InputError, match=r"is the input --measurements m\.csv") as info:
            check_outputs({"-o": name}, inputs)
        assert str(info.value).startswith(f"{name}: ")
    check_outputs({"-o": "other.csv", "--plot": None}, inputs)  # a new file is fine
    with pytest.raises(InputError, match=r"two outputs \(-o a\.csv and --plot \./a\.csv\)"):
        check_outputs({"-o": "a.csv", "--plot": "./a.csv"})
    assert (tmp_path / "m.csv").read_text() == "input\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hard.csv", "link.csv", "m.csv"]


def test_check_outputs_folders(tmp_path):
    (tmp_path / "afile").write_text("keep\n")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "plan.csv").mkdir()
    files = ("plan.csv", "cal.json")
    cases = [
        (tmp_path / "afile", "is a file, expected a folder"),
        (tmp_path / "afile" / "sub", "afile is a file, not a folder"),
        (tmp_path / "out", r"out/plan\.csv: is a directory.*give -o another folder"),
    ]
    for path, match in cases:
        with pytest.raises(InputError, match=match):
            check_outputs({"-o": OutputFolder(path, files)})
    (tmp_path / "truth.toml").write_text("")
    with pytest.raises(InputError, match="is the input --truth"):
        check_outputs(
            {"-o": OutputFolder(tmp_path, ("truth.toml",))}, {"--truth": tmp_path / "truth.toml"}
        )
    with pytest.raises(InputError, match=r"afile: exists and armcal did not write it"):
        check_outputs({"-o": OutputFolder(tmp_path, ("afile",))})  # the user's file
    check_outputs({"-o": OutputFolder(tmp_path / "new" / "deeper", files)})  # made when written
    with pytest.raises(InputError, match="output folder name is empty"):  # "" is not "."
        check_outputs({"-o": OutputFolder("", files)})
    with pytest.raises(InputError, match="output file name is empty"):
        check_outputs({"-o": ""})
    assert sorted(p.name for p in tmp_path.rglob("*")) == [
        "afile",
        "out",
        "plan.csv",
        "truth.toml",
    ]


def test_write_folder_makes_a_new_folder_only_when_complete(tmp_path):
    folder = tmp_path / "a" / "b"
    write_folder(folder, {"x.txt": "text\n", "y.bin": lambda path: path.write_bytes(b"\x00")})
    assert (folder / "x.txt").read_text() == "text\n"
    assert (folder / "y.bin").read_bytes() == b"\x00"
    for made in (tmp_path / "a", folder):  # as mkdir would make them, not mkdtemp's 0700
        assert _mode(made) == 0o777 & ~_umask()
    assert _mode(folder / "x.txt") == 0o666 & ~_umask()
    assert sorted(p.name for p in tmp_path.rglob("*")) == [MANIFEST, "a", "b", "x.txt", "y.bin"]
    listed = (folder / MANIFEST).read_text().splitlines()  # sha256sum's format
    assert listed == [
        hashlib.sha256(b"text\n").hexdigest() + "  x.txt",
        hashlib.sha256(b"\x00").hexdigest() + "  y.bin",
    ]


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_write_folder_failure_leaves_nothing(tmp_path, error):
    def fail(path):
        path.write_bytes(b"half")
        raise error("render failed")

    with pytest.raises(error):
        write_folder(tmp_path / "new" / "out", {"x.txt": "text\n", "y.png": fail})
    assert list(tmp_path.iterdir()) == []
    old = tmp_path / "old"
    old.mkdir()
    (old / "x.txt").write_text("old\n")
    with pytest.raises(error):
        write_folder(old, {"x.txt": "text\n", "y.png": fail})
    assert [p.name for p in old.iterdir()] == ["x.txt"]
    assert (old / "x.txt").read_text() == "old\n"


def test_write_folder_into_an_existing_folder(tmp_path):
    (tmp_path / "real.txt").write_text("old\n")
    (tmp_path / "real.txt").chmod(0o600)
    out = tmp_path / "out"
    out.mkdir()
    (out / "other").write_text("keep\n")
    (out / "x.txt").symlink_to("../real.txt")
    write_folder(out, {"x.txt": "new\n", "y.txt": "y\n"})
    assert (out / "x.txt").is_symlink() and (tmp_path / "real.txt").read_text() == "new\n"
    assert _mode(tmp_path / "real.txt") == 0o600
    assert (out / "other").read_text() == "keep\n" and (out / "y.txt").read_text() == "y\n"
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "other", "x.txt", "y.txt"]


def test_a_folder_output_replaces_only_the_files_armcal_wrote(tmp_path):
    """demo/reproduce -o name no file: they replace their own earlier files, never the user's."""
    out = tmp_path / "out"
    folder = OutputFolder(out, ("cal.json", "plan.csv"))
    check_outputs({"-o": folder})  # a new folder
    write_folder(out, {"cal.json": "{}\n", "plan.csv": "q\n"})
    check_outputs({"-o": folder})  # a second run replaces its own files
    (out / "notes.txt").write_text("mine\n")  # other files are no concern
    check_outputs({"-o": folder})
    (out / "plan.csv").write_text("q\n1\n")  # the user edited it
    with pytest.raises(InputError, match=r"out/plan\.csv: exists and armcal did not write it"):
        check_outputs({"-o": folder})
    (out / "plan.csv").unlink()
    (out / "cal.json").unlink()
    (out / "cal.json").write_text("{}\n")  # the same bytes, but the listing says so: ours
    check_outputs({"-o": folder})
    (out / MANIFEST).unlink()  # without the listing, nothing there is known to be ours
    with pytest.raises(InputError, match=r"cal\.json: exists and armcal did not write it"):
        check_outputs({"-o": folder})


def test_to_json_indents_objects_and_keeps_number_tables_on_one_line():
    """The fast layout (issue 20): objects indented, a list of numbers one line; the text
    parses back to the same document, and NaN is still refused."""
    rows = np.arange(20000.0).reshape(-1, 2).tolist()
    document = {"a": {"b": [1, 2], "c": None}, "rows": rows, "list": [{"x": 1}, {"y": [2]}]}
    text = to_json(document)
    assert json.loads(text) == document
    lines = text.splitlines()
    assert len(lines) == 13  # {; a {; b; c; }; rows; list [; {x}; {; y; }; ]; }
    assert lines[5].startswith('  "rows": [[0.0, 1.0], [2.0, 3.0]')
    with pytest.raises(ValueError):
        to_json({"x": [float("nan")]})


def test_a_read_plan_is_c_ordered(tmp_path):
    """The column-wise CSV parser must hand on C-ordered arrays: the fits' round-off
    follows the memory layout, and the docs print full-precision results."""
    path = tmp_path / "plan.csv"
    path.write_text("q1_deg,q2_deg\n0,10\n20,30\n40,50\n")
    q = read_plan(path, PlanarArm([2.0, 1.0]))
    assert q.flags.c_contiguous
    assert_allclose(np.degrees(q), [[0, 10], [20, 30], [40, 50]])


@pytest.mark.parametrize("delimiter", [",", "\t"])
def test_a_plain_numeric_file_reads_as_one_with_a_comment_does(tmp_path, delimiter):
    """NumPy's reader takes plain files of numbers; a comment line sends the same rows
    through the general reader. Both give the same numbers, bit for bit."""
    rng = np.random.default_rng(25)
    q = rng.uniform(-170.0, 170.0, (300, 2))
    xy = rng.uniform(-250.0, 250.0, (300, 2))  # within the reach of 440 mm
    sigma = rng.uniform(0.01, 0.1, 300)
    header = delimiter.join(["q1_deg", "q2_deg", "x_mm", "y_mm", "sigma_mm"])
    rows = [
        delimiter.join([f" {a!r}", f"{b:.6f} ", repr(x), f"{y:.17g}", f"{s:.3e}"])
        for (a, b), (x, y), s in zip(q.tolist(), xy.tolist(), sigma.tolist(), strict=True)
    ]
    body = header + "\n" + "\n".join(rows)
    (tmp_path / "plain.csv").write_text("\n" + body + "\n")  # a blank line before the header
    (tmp_path / "commented.csv").write_text("# from the tracker\n" + body)
    arm = PlanarArm([260.0, 180.0])
    plain = read_measurements(tmp_path / "plain.csv", arm)
    general = read_measurements(tmp_path / "commented.csv", arm)
    for a, b in (
        (plain.q, general.q),
        (plain.xy, general.xy),
        (plain.row_sigma, general.row_sigma),
    ):
        assert np.array_equal(a, b)
    assert plain.q.flags.c_contiguous
    assert plain.rows == general.rows == tuple(range(1, 301))
    assert_allclose(np.degrees(plain.q[:, 0]), q[:, 0], rtol=1e-15)


def test_a_plain_file_with_a_bad_row_names_its_line(tmp_path):
    path = tmp_path / "plan.csv"
    path.write_text("\nq1_deg,q2_deg\n0,10\n20,3O\n40,50\n")
    with pytest.raises(InputError, match=r"row 2 \(line 4\), column q2_deg: '3O' is not a number"):
        read_plan(path, PlanarArm([2.0, 1.0]))
    path.write_text("q1_deg,q2_deg\n0,10\n20,30,5\n")
    with pytest.raises(InputError, match=r"row 2 \(line 3\) has 3 fields but the header has 2"):
        read_plan(path, PlanarArm([2.0, 1.0]))


def _one_dumps_per_object(rows: list, pad: str) -> str:
    """A list of flat objects as to_json wrote it before its columns were encoded at once."""
    lines = [pad + "  " + json.dumps(r, allow_nan=False, separators=(", ", ": ")) for r in rows]
    return "[\n" + ",\n".join(lines) + f"\n{pad}]"


def test_to_json_encodes_a_table_of_objects_as_one_dumps_per_object_would():
    rows = [
        {"row": 1, "pose": "1", "target": None, "dx_mm": -0.0, "used": True, "50%": 1e22},
        {"row": 2, "pose": 'p"é\n', "target": "tcp", "dx_mm": 1e-300, "used": False, "50%": 3},
        {"row": 3, "pose": "x", "target": "left", "dx_mm": 0.1, "used": True, "50%": None},
    ]
    text = to_json({"residuals": rows})
    assert text == '{\n  "residuals": ' + _one_dumps_per_object(rows, "  ") + "\n}\n"
    assert json.loads(text) == {"residuals": rows}


def test_to_json_keeps_the_object_by_object_path_for_other_lists():
    mixed = [{"a": 1}, {"b": 2}, {"a": np.float64(0.5)}]  # other keys; a numpy float
    assert (
        to_json({"t": mixed})
        == '{\n  "t": [\n    {"a": 1},\n    {"b": 2},\n    {"a": 0.5}\n  ]\n}\n'
    )
    with pytest.raises(ValueError):
        to_json({"t": [{"x": 1.0}, {"x": float("inf")}]})
    with pytest.raises(ValueError):
        to_json({"t": [{"x": float("nan")}, {"x": 1.0}]})


def test_write_json_writes_to_jsons_text_in_pieces(monkeypatch):
    import io

    import armcal.files.common as common

    monkeypatch.setattr(common, "WRITE_BATCH", 10)  # many pieces
    monkeypatch.setattr(common, "RECORD_CHUNK", 3)  # tables in several chunks
    rows = [{"row": i, "pose": f"p{i}", "dx_mm": i / 7, "used": i % 2 == 0} for i in range(10)]
    document = {"a": [1.5, 2.0], "residuals": rows, "other": [{"x": {"y": 1}}, {"z": None}]}
    handle = io.BytesIO()
    write_json(document, handle)
    assert handle.getvalue().decode() == to_json(document)
    assert json.loads(to_json(document)) == document
