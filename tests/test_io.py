"""Files: robot and truth TOML, plan and measurement CSV, calibration JSON."""

import json
import os
import stat

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal import Annulus, Box, InputError, forward_kinematics, identify, orthogonal_plan
from armcal.io import (
    OutputFolder,
    atomic_write,
    check_outputs,
    format_measurements_csv,
    format_plan_csv,
    load_robot,
    load_truth,
    read_measurements,
    read_plan,
    write_folder,
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
        ("q1_deg,q2_deg,x_mm,y_mm\n0,183,1,2\n", "outside joint 2's limits"),
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
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "b", "x.txt", "y.bin"]


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
    assert sorted(p.name for p in out.iterdir()) == ["other", "x.txt", "y.txt"]
