"""A camera and a checkerboard (issue 38): the measurement equation, the arm it measures,
and the front door, eye-in-hand and eye-to-hand.

The virtual labs (``helpers_instruments``): a 1280 x 800 camera of 900 px focal length
with a little distortion, a board of 6 x 8 corners 30 mm apart; eye-in-hand, the camera
100 mm beyond the flange looking along it at a board on the floor; eye-to-hand, the
camera above the cell looking down at a board on the flange.  The user's placements are
3-10 mm and 1-2 degrees from the truth.  Tolerances: a pixel of a corner seen from a
metre away is exact to round-off near 1e-12 px (the readings are about 1e3 px, ulp
1e-13, and the projection a dozen operations); a held-out RMS below 1e-9 px is round-off.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from armcal.files import load_robot
from armcal.files.instrument_table import instrumented_truth
from armcal.instruments import Board, Camera, Intrinsics
from armcal.models.spatial.chain import vector_rotation
from armcal.simulate import monte_carlo
from helpers import run_cli
from helpers_instruments import CAMERA_INFO, CAMERAS, met_plan, refused_robot, write_lab

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

INTRINSICS = Intrinsics(
    np.array([[800.0, 0.5, 640.0], [0.0, 810.0, 400.0], [0.0, 0.0, 1.0]]),
    np.array([0.1, -0.05, 0.001, -0.002, 0.01]),
    1280,
    800,
)


def _camera(mount: str) -> Camera:
    return Camera(
        INTRINSICS,
        Board(6, 8, 25.0),
        mount,
        (np.array([10.0, 20.0, 100.0]), np.array([5.0, -3.0, 90.0])),
        (np.array([500.0, 100.0, -50.0]), np.array([180.0, 2.0, 3.0])),
    )


@pytest.mark.parametrize("mount", CAMERAS)
def test_the_pixels_derivatives_are_central_differences(mount):
    """By the tip's shift and turn (``R -> exp([w]) R``) and by the camera's and the board's
    twelve parameters, against central differences (step 1e-6 mm or rad: truncation
    h^2 |d3| and round-off eps |u| / h, about 1e-9 of the largest derivative here)."""
    camera = _camera(mount)
    rng = np.random.default_rng(0)
    m = 9
    shift = rng.normal(size=(m, 3)) * 300.0
    turn = vector_rotation(rng.normal(size=(m, 3)))
    tool = np.concatenate([shift, turn.reshape(m, 9)], axis=-1)
    feature = rng.integers(0, 48, m)
    params = rng.normal(size=12) * np.array([4, 4, 4, 0.04, 0.04, 0.04] * 2)
    by_tool, by_params = camera.derivatives(tool, feature, params)
    h = 1e-6

    def read(t: np.ndarray, p: np.ndarray = params) -> np.ndarray:
        return camera.reading(t, feature, p)

    numeric = np.stack(
        [(read(tool, params + h * e) - read(tool, params - h * e)) / (2 * h) for e in np.eye(12)],
        axis=-1,
    )
    np.testing.assert_allclose(by_params, numeric, atol=1e-7 * np.abs(by_params).max())
    moved = []
    for e in np.eye(3):  # the tip's shift
        up, down = tool.copy(), tool.copy()
        up[:, :3] += h * e
        down[:, :3] -= h * e
        moved.append((read(up) - read(down)) / (2 * h))
    for e in np.eye(3):  # its turn, in the base frame

        def turned(w: np.ndarray) -> np.ndarray:
            rotation = vector_rotation(w) @ turn
            return np.concatenate([shift, rotation.reshape(m, 9)], axis=-1)

        moved.append((read(turned(h * e)) - read(turned(-h * e))) / (2 * h))
    np.testing.assert_allclose(
        by_tool, np.stack(moved, axis=-1), atol=1e-7 * np.abs(by_tool).max()
    )
    np.testing.assert_array_equal(camera.tool_derivatives(tool, feature, params), by_tool)


@pytest.mark.parametrize("mount", CAMERAS)
def test_the_view_s_slack_derivatives_are_central_differences(mount):
    """A corner's depth and the cosine of its line of sight's tilt against the board, by
    the tip's shift and turn (``R -> exp([w]) R``), against central differences (step
    1e-6 mm or rad: truncation and round-off about 1e-9 of the largest derivative).  The
    poses are the derivatives test's, the cosine's sign taken as it comes (its absolute
    value is what the slack reads)."""
    camera = _camera(mount)
    rng = np.random.default_rng(1)
    m = 9
    shift = rng.normal(size=(m, 3)) * 300.0
    turn = vector_rotation(rng.normal(size=(m, 3)))
    feature = rng.integers(0, 48, m)
    params = rng.normal(size=12) * np.array([4, 4, 4, 0.04, 0.04, 0.04] * 2)
    h = 1e-6

    def tool(s: np.ndarray, w: np.ndarray) -> np.ndarray:
        return np.concatenate([s, (vector_rotation(w) @ turn).reshape(m, 9)], axis=-1)

    def slack(s: np.ndarray, w: np.ndarray) -> np.ndarray:
        return camera.slack(tool(s, w), feature, params)

    zero = np.zeros((m, 3))
    found = camera.slack_derivatives(tool(shift, zero), feature, params)
    numeric = np.stack(
        [(slack(shift + h * e, zero) - slack(shift - h * e, zero)) / (2 * h) for e in np.eye(3)]
        + [(slack(shift, h * e + zero) - slack(shift, zero - h * e)) / (2 * h) for e in np.eye(3)],
        axis=-1,
    )
    assert found is not None and found.shape == (m, 2, 6)
    for row in range(2):  # the depth (mm / mm) and the cosine (1 / mm), each to its scale
        np.testing.assert_allclose(
            found[:, row], numeric[:, row], atol=1e-7 * np.abs(numeric[:, row]).max()
        )


def test_the_projection_is_opencv_s_plumb_bob():
    """A point at (x, y) = (0.3, -0.2) on the unit plane, by hand from OpenCV's equations:
    r^2 = 0.13, c = 1 + 0.1 r^2 - 0.05 r^4 + 0.01 r^6, x'' = x c + 2 p1 x y + p2 (r^2 +
    2 x^2), y'' = y c + p1 (r^2 + 2 y^2) + 2 p2 x y, u = 800 x'' + 0.5 y'' + 640,
    v = 810 y'' + 400."""
    x, y = 0.3, -0.2
    r2 = x * x + y * y
    c = 1 + 0.1 * r2 - 0.05 * r2**2 + 0.01 * r2**3
    xd = x * c + 2 * 0.001 * x * y + (-0.002) * (r2 + 2 * x * x)
    yd = y * c + 0.001 * (r2 + 2 * y * y) + 2 * (-0.002) * x * y
    uv, _ = INTRINSICS.project(np.array([x * 700.0, y * 700.0, 700.0]))
    np.testing.assert_allclose(uv, [800 * xd + 0.5 * yd + 640, 810 * yd + 400], rtol=1e-14)


@pytest.mark.parametrize("robot", ["industrial-6r", "cobot-6r"])
@pytest.mark.parametrize("mount", CAMERAS)
def test_noiseless_photos_are_recovered_on_held_out_poses(tmp_path, robot, mount):
    """synthesize (noiseless) -> identify -> validate on 20 other poses: every held-out
    corner to round-off, from the user's rough camera and board; the identifiable count
    is the rank of the whole Jacobian at the truth (unit columns, 1e-10)."""
    robot_file, truth = write_lab(tmp_path, robot, mount)
    met_plan(tmp_path, robot_file, 30, 1, "train.csv")
    met_plan(tmp_path, robot_file, 20, 2, "test.csv")
    for plan, out in (("train.csv", "meas.csv"), ("test.csv", "held.csv")):
        run = run_cli(
            tmp_path,
            "synthesize",
            "--robot",
            robot_file.name,
            "--plan",
            plan,
            "--truth",
            truth.name,
            "--sigma",
            "0",
            "-o",
            out,
        )
        assert run.returncode == 0, run.stderr
    header = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()[0]
    assert header.endswith("u_px,v_px,corner")
    run = run_cli(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    assert run.returncode == 0, run.stderr
    assert "sigma 0.2 px" in run.stdout and "camera (48: 0 to 47)" in run.stdout
    run = run_cli(
        tmp_path, "validate", "--calibration", "cal.json", "--measurements", "held.csv", "--json"
    )
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["rms_after_mm"] < 1e-9 < 0.1 < summary["rms_before_mm"]  # px
    spec = load_robot(robot_file)
    model = spec.arm
    x_true = instrumented_truth(spec, model, truth)
    document = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    free = sum(not p["fixed"] for p in document["parameters"])
    from armcal.files import read_measurements

    meas = read_measurements(tmp_path / "meas.csv", model)
    rows = model.conditions(meas.q, feature=meas.feature)
    whole = model.jacobian(rows, x_true).reshape(-1, model.n_params)
    norms = np.linalg.norm(whole, axis=0)
    s = np.linalg.svd(whole[:, norms > 0] / norms[norms > 0], compute_uv=False)
    assert free == int(np.sum(s > 1e-10 * s[0]))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("robot", "mount"), [("industrial-6r", "eye-to-hand"), ("cobot-6r", "eye-in-hand")]
)
def test_monte_carlo_std_agrees_with_the_predicted_std(tmp_path, robot, mount):
    """4000 noisy photo sets (0.2 px) of 20 poses, identified from the truth, on two arms
    and both mounts: every free parameter's std within 5 % of the predicted one (a std
    known to 1.1 %)."""
    robot_file, truth = write_lab(tmp_path, robot, mount)
    spec = load_robot(robot_file)
    model = spec.arm
    x_true = instrumented_truth(spec, model, truth)
    from armcal.doe import feasible_poses

    q = feasible_poses(model, 20, rng=np.random.default_rng(3))
    mc = monte_carlo(model, q, x_true, 0.2, 4000, rng=np.random.default_rng(8))
    assert mc.not_converged == 0
    ratios = mc.std[mc.model.free] / mc.predicted_std[mc.model.free]
    assert np.all(np.abs(ratios - 1.0) <= 0.05), ratios


def _lab_with(folder: Path, table_edit=None, camera_text: str = CAMERA_INFO) -> Path:
    robot_file, _ = write_lab(folder, "cobot-6r", "eye-in-hand")
    (folder / "cam.yaml").write_text(camera_text, encoding="utf-8")
    if table_edit is not None:
        text = robot_file.read_text(encoding="utf-8")
        robot_file.write_text(table_edit(text), encoding="utf-8")
    return robot_file


BAD_CAMERAS = {
    "no camera matrix": (
        CAMERA_INFO.replace("camera_matrix:", "camera_matrx:"),
        "cam.yaml: field 'camera_matrix' is missing",
    ),
    "another distortion model": (
        CAMERA_INFO.replace("plumb_bob", "equidistant"),
        "cam.yaml: field 'distortion_model': 'equidistant' is not read",
    ),
    "a matrix of the wrong shape": (
        CAMERA_INFO.replace("  rows: 3\n  cols: 3", "  rows: 3\n  cols: 2", 1),
        "cam.yaml: field 'camera_matrix': data must be rows x cols = 6 numbers",
    ),
    "no width": (
        CAMERA_INFO.replace("image_width: 1280", "image_width: -5"),
        "cam.yaml: field 'image_width': expected a positive number of pixels",
    ),
    "not yaml": ("image_width: [1280\n", "cam.yaml: not a camera_info file (YAML or JSON)"),
}


@pytest.mark.parametrize("case", sorted(BAD_CAMERAS))
def test_a_camera_file_with_wrong_fields_is_one_line(tmp_path, case):
    text, words = BAD_CAMERAS[case]
    robot_file = _lab_with(tmp_path, camera_text=text)
    line = refused_robot(tmp_path, robot_file.name)
    assert words in line, line


BAD_TABLES = {
    "noise in mm": (
        lambda t: t.replace("sigma_px = 0.2", "sigma_mm = 0.02"),
        "key 'measurement.sigma_mm': a camera's noise is in pixels",
    ),
    "a tool point": (
        lambda t: t.replace(
            "[measurement]", "[targets]\ntool = { xyz_mm = [0, 0, 50] }\n[measurement]"
        ),
        "key 'targets': a camera on the tool is placed on the flange",
    ),
    "an unknown mount": (
        lambda t: t.replace('mount = "eye-in-hand"', 'mount = "on-the-wall"'),
        "key 'instrument.mount': expected 'eye-in-hand' or 'eye-to-hand'",
    ),
    "no board": (
        lambda t: t[: t.index("board = ")],
        "key 'instrument': a camera needs board",
    ),
    "the other mount's key": (
        lambda t: t.replace("camera_in_tool", "camera_in_base"),
        "key 'instrument.camera_in_base': a camera eye-in-hand is placed by camera_in_tool",
    ),
    "a camera file that is not there": (
        lambda t: t.replace('camera = "cam.yaml"', 'camera = "nowhere.yaml"'),
        "nowhere.yaml",
    ),
    "a margin beyond half the image": (
        lambda t: t.replace('mount = "eye-in-hand"', 'mount = "eye-in-hand"\nmargin_px = 400'),
        "key 'instrument.margin_px': expected at least 0 and below 400 (half the image), got 400",
    ),
    "a depth of 0": (
        lambda t: t.replace('mount = "eye-in-hand"', 'mount = "eye-in-hand"\nmin_depth_mm = 0'),
        "key 'instrument.min_depth_mm': expected above 0",
    ),
    "a tilt of 90 degrees": (
        lambda t: t.replace('mount = "eye-in-hand"', 'mount = "eye-in-hand"\nmax_tilt_deg = 90'),
        "key 'instrument.max_tilt_deg': expected above 0 and below 90 degrees, got 90",
    ),
}


def test_a_camera_s_view_keys_are_read_and_written_back(tmp_path):
    """margin_px, min_depth_mm and max_tilt_deg: the defaults (10 px, 150 mm, 60 deg)
    where absent, the file's where given, and the calibration file's instrument table
    carries them (read back, the same camera's view)."""
    from armcal.files.instrument_table import instrument_section, read_instrument

    robot_file = _lab_with(tmp_path)
    camera = load_robot(robot_file).arm.instrument
    assert (camera.margin_px, camera.min_depth_mm, camera.max_tilt_deg) == (10.0, 150.0, 60.0)
    edit = 'mount = "eye-in-hand"\nmargin_px = 25\nmin_depth_mm = 300.5\nmax_tilt_deg = 45'
    robot_file = _lab_with(tmp_path, lambda t: t.replace('mount = "eye-in-hand"', edit))
    camera = load_robot(robot_file).arm.instrument
    assert (camera.margin_px, camera.min_depth_mm, camera.max_tilt_deg) == (25.0, 300.5, 45.0)
    table = instrument_section(camera)
    assert (table["margin_px"], table["min_depth_mm"], table["max_tilt_deg"]) == (25, 300.5, 45)
    again = read_instrument(robot_file, table)
    assert (again.margin_px, again.min_depth_mm, again.max_tilt_deg) == (25.0, 300.5, 45.0)


@pytest.mark.parametrize("case", sorted(BAD_TABLES))
def test_a_bad_camera_table_is_one_line(tmp_path, case):
    edit, words = BAD_TABLES[case]
    robot_file = _lab_with(tmp_path, edit)
    line = refused_robot(tmp_path, robot_file.name)
    assert words in line, line


def test_pixels_outside_the_image_are_one_line(tmp_path):
    """A corner at u = 1500 px in a 1280 px image: the file, row, line and column named;
    a corner that is no corner of the board too."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "eye-in-hand")
    met_plan(tmp_path, robot_file, 3, 1, "plan.csv")
    run = run_cli(
        tmp_path,
        "synthesize",
        "--robot",
        robot_file.name,
        "--plan",
        "plan.csv",
        "--truth",
        truth.name,
        "-o",
        "meas.csv",
    )
    assert run.returncode == 0, run.stderr
    lines = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    head = lines[0].split(",")
    u = head.index("u_px")
    cells = lines[2].split(",")
    cells[u] = "1500"
    bad = [lines[0], lines[1], ",".join(cells), *lines[3:]]
    (tmp_path / "bad.csv").write_text("\n".join(bad) + "\n", encoding="utf-8")
    run = run_cli(tmp_path, "identify", "--robot", robot_file.name, "--measurements", "bad.csv")
    assert run.returncode == 2
    assert run.stderr.strip() == (
        "armcal: error: bad.csv: row 2 (line 3), column u_px: 1500 is outside the image "
        "(0 to 1280 px); check the camera file's image size and the column's unit"
    )
    cells = lines[2].split(",")
    cells[head.index("corner")] = "48"
    bad = [lines[0], lines[1], ",".join(cells), *lines[3:]]
    (tmp_path / "bad.csv").write_text("\n".join(bad) + "\n", encoding="utf-8")
    run = run_cli(tmp_path, "identify", "--robot", robot_file.name, "--measurements", "bad.csv")
    assert run.returncode == 2
    assert "row 2 (line 3), column corner: '48' is not a corner" in run.stderr
    # inside the image, but across it from where the camera and the arm put the corner:
    # more than half the image's diagonal (755 px) from the other rows' offset, in px
    cells = lines[2].split(",")
    u_here, v_here = float(cells[u]), float(cells[head.index("v_px")])
    cells[u] = "5" if u_here > 640 else "1275"
    cells[head.index("v_px")] = "5" if v_here > 400 else "795"
    bad = [lines[0], lines[1], ",".join(cells), *lines[3:]]
    (tmp_path / "bad.csv").write_text("\n".join(bad) + "\n", encoding="utf-8")
    run = run_cli(tmp_path, "identify", "--robot", robot_file.name, "--measurements", "bad.csv")
    assert run.returncode == 2, run.stderr
    line = run.stderr.strip()
    assert line.startswith("armcal: error: bad.csv: row 2: at its joint readings the nominal arm")
    assert " px from where the other rows put" in line and "half the image's diagonal" in line
    assert " mm" not in line and line.count("\n") == 0


def test_the_camera_is_placed_on_the_flange(tmp_path):
    """Without [targets], the tool point a camera on the tool is placed from is the
    flange's origin, held there (a built-in arm's default tool point is 112 mm out)."""
    robot_file, _ = write_lab(tmp_path, "industrial-6r", "eye-in-hand")
    model = load_robot(robot_file).arm
    np.testing.assert_array_equal(model.inner.target_positions, np.zeros((1, 3)))
    tool = [n for n in model.param_names if n.startswith(f"{model.inner.targets[0]}.")]
    assert len(tool) == 3 and set(tool) <= set(model.fixed)


def test_a_pincushion_lens_s_photos_stay_in_the_image(tmp_path):
    """k1 = 0.15 moves corners outward: the poses synthesize keeps see every corner
    inside the image where the lens puts it, so identify reads them (no pixel beyond
    the image), and a plan's pose that misses the board is said by evaluate."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "eye-in-hand")
    camera = CAMERA_INFO.replace("[0.05, -0.1, 0.0005, -0.0003, 0.0]", "[0.15, 0, 0, 0, 0]")
    (tmp_path / "cam.yaml").write_text(camera, encoding="utf-8")
    met_plan(tmp_path, robot_file, 20, 1, "plan.csv")
    run = run_cli(
        tmp_path,
        "synthesize",
        "--robot",
        robot_file.name,
        "--plan",
        "plan.csv",
        "--truth",
        truth.name,
        "-o",
        "meas.csv",
    )
    assert run.returncode == 0, run.stderr
    run = run_cli(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    assert run.returncode == 0, run.stderr
    run = run_cli(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "out.toml")
    assert run.returncode == 0, run.stderr
    exported = tomllib.loads((tmp_path / "out.toml").read_text(encoding="utf-8"))
    assert "measurement" not in exported  # pixels say nothing of the arm's noise in mm
    plan = (tmp_path / "plan.csv").read_text(encoding="utf-8")
    (tmp_path / "mixed.csv").write_text(plan + "0,0,0,0,0,0\n", encoding="utf-8")
    run = run_cli(tmp_path, "evaluate", "--robot", robot_file.name, "--plan", "mixed.csv")
    assert run.returncode == 0, run.stderr
    assert "1 of 21 poses (rows 21) do not meet the instrument" in run.stderr


@pytest.mark.parametrize(
    ("data", "words"),
    [
        ("  rows: -3\n  cols: -3", "field 'camera_matrix.rows': expected a positive whole number"),
        (
            "  rows: true\n  cols: 9",
            "field 'camera_matrix.rows': expected a positive whole number",
        ),
    ],
)
def test_a_camera_matrix_of_odd_rows_is_one_line(tmp_path, data, words):
    text = CAMERA_INFO.replace("  rows: 3\n  cols: 3", data, 1)
    robot_file = _lab_with(tmp_path, camera_text=text)
    (tmp_path / "p.csv").write_text("q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n0,0,0,0,0,0\n")
    run = run_cli(tmp_path, "evaluate", "--robot", robot_file.name, "--plan", "p.csv")
    assert run.returncode == 2 and words in run.stderr, run.stderr


def test_yaml_numbers_without_a_dot_are_numbers(tmp_path):
    """YAML 1.1 reads 1e-05 as text; a camera file's coefficient written so is a number."""
    from armcal.files.camera_info import read_camera_info

    text = CAMERA_INFO.replace("[0.05, -0.1, 0.0005, -0.0003, 0.0]", "[5e-02, -1e-01, 0, 0, 0]")
    (tmp_path / "cam.yaml").write_text(text, encoding="utf-8")
    found = read_camera_info(tmp_path / "cam.yaml")
    np.testing.assert_array_equal(found.distortion, [0.05, -0.1, 0.0, 0.0, 0.0])


def test_cross_validation_keeps_a_photos_corners_together(tmp_path):
    """identify --cross-validate of photos (it once stopped on a traceback: the folds'
    rows lost their corners): a photo's 48 corners stay in one fold, 12 photos make 3
    folds of 4, noiseless photos are predicted to round-off, in pixels (1e-6 px)."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "eye-to-hand")
    met_plan(tmp_path, robot_file, 12, 1, "plan.csv")
    for args in (
        ("synthesize", "--robot", robot_file.name, "--plan", "plan.csv", "--truth",
         truth.name, "--sigma", "0", "-o", "meas.csv"),
        ("identify", "--robot", robot_file.name, "--measurements", "meas.csv",
         "--cross-validate", "3", "--json"),
    ):  # fmt: skip
        run = run_cli(tmp_path, *args)
        assert run.returncode == 0, run.stderr
    checked = json.loads(run.stdout)["cross_validation"]
    assert checked["reading_unit"] == "px"
    assert [fold["points"] for fold in checked["per_fold"]] == [4 * 48] * 3
    assert checked["rms_per_point_mm"] < 1e-6


def test_a_camera_s_validation_warnings_and_reprs_speak_pixels():
    """Errors in pixels are reported in pixels: the validation-error, calibration-worse
    and cross-validation warnings and the reprs say px, never mm (they said mm)."""
    from armcal.validation import (
        CrossValidation,
        Validation,
        cross_validation_warnings,
        validation_warnings,
    )

    rng = np.random.default_rng(3)
    m = 200
    after = rng.normal(size=(m, 2)) * 3.0  # 3 px where 0.2 px is predicted: too large
    before = after.copy()  # and no better than the nominal arm
    predicted = np.full(m, 0.2)
    checked = Validation(before, after, predicted, predicted, after, unit="px")
    words = " ".join(w.message for w in validation_warnings(checked))
    assert {w.code for w in validation_warnings(checked)} >= {
        "validation-error",
        "calibration-worse",
    }
    assert " px" in words and " mm" not in words
    assert " px " in repr(checked) and " mm" not in repr(checked)
    folds = CrossValidation(3, np.arange(m) % 3, after, predicted, None, before, unit="px")
    words = " ".join(w.message for w in cross_validation_warnings(folds))
    assert {w.code for w in cross_validation_warnings(folds)} == {
        "cross-validation",
        "calibration-worse",
    }
    assert " px" in words and " mm" not in words
    assert " px" in repr(folds) and " mm" not in repr(folds)
