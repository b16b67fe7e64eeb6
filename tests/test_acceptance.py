"""ISO 9283 pose accuracy and repeatability (clause 7.2), checked by hand and end to end.

ISO 9283:1998, 7.2.1: ``AP_P = |barycentre of the attained positions - command position|``;
7.2.2: ``RP_l = lbar + 3 S_l``, ``l_j`` the distances from the barycentre and
``S_l = sqrt(sum (l_j - lbar)^2 / (n - 1))``.  For isotropic Gaussian noise of std
``s`` in 3-D the distance from the true point follows Maxwell's distribution, with
mean ``2 s sqrt(2/pi) = 1.5958 s`` and std ``s sqrt(3 - 8/pi) = 0.6734 s``, so RP
tends to ``3.616 s`` for many cycles (the barycentre's own noise lowers it by a
factor of about ``sqrt(1 - 1/n)``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from armcal.acceptance import ISO_CYCLES, pose_characteristics, pose_characteristics_warnings
from armcal.errors import ArmcalError
from helpers import run_cli, write_cycles
from helpers_spatial import plan_file


def test_pose_accuracy_and_repeatability_agree_with_hand_computed_values():
    """Two poses of four cycles.  P1: attained at +-1 on x and y about its command (0, 0, 0):
    barycentre 0, so AP = 0; every distance 1, so lbar = 1, S_l = 0, RP = 1.  P2: attained
    at (10, 0, 0) twice and (10, 0, +-3), command (9, 0, 0): barycentre (10, 0, 0), AP = 1
    along +x; distances 0, 0, 3, 3: lbar = 1.5, S_l = sqrt(4 x 1.5^2 / 3) = sqrt(3),
    RP = 1.5 + 3 sqrt(3)."""
    p1 = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])
    p2 = np.array([[10.0, 0, 0], [10, 0, 0], [10, 0, 3], [10, 0, -3]])
    attained = np.concatenate([p1, p2])[[0, 4, 1, 5, 2, 6, 3, 7]]  # cycles interleaved
    labels = ("P1", "P2") * 4
    command = np.where(np.array(labels)[:, None] == "P1", [0.0, 0, 0], [9.0, 0, 0])
    q = np.where(np.array(labels)[:, None] == "P1", [0.1, 0.2], [0.3, 0.4])
    after = attained - command - 0.5  # the calibrated model 0.5 mm off on every axis
    found = pose_characteristics(q, attained, attained - command, after, labels)
    assert found.poses == ("P1", "P2")
    np.testing.assert_array_equal(found.cycles, [4, 4])
    np.testing.assert_allclose(found.accuracy_before_mm, [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(found.accuracy_before, [[0, 0, 0], [1, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(found.accuracy_after[0], [-0.5, -0.5, -0.5])
    np.testing.assert_allclose(found.repeatability_mm, [1.0, 1.5 + 3 * np.sqrt(3)])
    np.testing.assert_allclose(found.barycentres, [[0, 0, 0], [10, 0, 0]], atol=1e-15)
    summary = found.summary()
    assert summary["ap_before_mm"] == 1.0
    assert summary["rp_mm"] == pytest.approx(1.5 + 3 * np.sqrt(3))
    (warning,) = pose_characteristics_warnings(found)  # 4 cycles, not 30
    assert warning.code == "iso9283-cycles" and "only 4 cycles" in warning.message


def test_several_targets_are_separate_measuring_points():
    attained = np.array([[0.0, 0, 0], [5, 0, 0], [2.0, 0, 0], [5, 0, 2]])
    found = pose_characteristics(
        np.zeros((4, 1)), attained, attained, attained, ("P",) * 4, ("A", "B", "A", "B")
    )
    assert found.targets == ("A", "B")
    np.testing.assert_allclose(found.barycentres, [[1, 0, 0], [5, 0, 1]])
    np.testing.assert_allclose(found.repeatability_mm, [1.0, 1.0])  # S_l = 0: both at 1


@pytest.mark.parametrize(
    ("q", "labels", "message"),
    [
        (np.zeros((3, 2)), ("P1", "P1", "P2"), "row 3, column 'pose': pose P2 was measured once"),
        (
            np.array([[0.0, 0.0], [0.0, 1e-4], [0.0, 0.0], [0.0, 0.0]]),
            ("P1", "P1", "P2", "P2"),
            "row 1, column 'pose': pose P1 has cycles with different joint values",
        ),
    ],
    ids=["once", "moved"],
)
def test_what_is_not_a_repeated_pose_is_refused(q, labels, message):
    points = np.zeros((q.shape[0], 3))
    with pytest.raises(ArmcalError, match=message):
        pose_characteristics(q, points, points, points, labels, rows=tuple(range(1, 5)))


def _cycles_file(tmp_path, poses: int, cycles: int, seed: int) -> None:
    """``iso.csv``: ``poses`` poses of the industrial arm, each measured ``cycles`` times:
    a plan with a 'pose' column, which synthesize copies into the measurements."""
    _, q = plan_file(tmp_path, "industrial-6r", m=poses, seed=seed, name="poses.csv")
    write_cycles(tmp_path / "cycles.csv", q, cycles)
    result = run_cli(
        tmp_path, "synthesize", "--robot", "industrial-6r", "--plan", "cycles.csv", "--sigma",
        "0.02", "--seed", str(seed), "-o", "iso.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    lines = (tmp_path / "iso.csv").read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("pose,") and lines[1].startswith("P1,") and lines[2][:3] == "P2,"


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """The industrial arm calibrated from 60 poses measured at 0.02 mm."""
    folder = tmp_path_factory.mktemp("cal")
    plan_file(folder, "industrial-6r", m=60, seed=4)
    result = run_cli(
        folder, "synthesize", "--robot", "industrial-6r", "--plan", "plan.csv", "--sigma",
        "0.02", "--seed", "4", "-o", "meas.csv",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    result = run_cli(
        folder, "identify", "--robot", "industrial-6r", "--measurements", "meas.csv", "--sigma",
        "0.02", "-o", "cal.json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return folder / "cal.json"


def test_validate_iso9283_on_a_virtual_arm(tmp_path, calibrated):
    """5 poses x 30 cycles at 0.02 mm: the calibration cuts AP from the nominal model's
    millimetres to the noise's and the calibration's level; RP is the noise's
    (3.616 s sqrt(1 - 1/30) = 0.0711 mm, the module notes; S_l from 29 degrees of freedom
    scatters RP by about 5 % per pose, so the mean of 5 poses is held within 8 %)."""
    _cycles_file(tmp_path, poses=5, cycles=ISO_CYCLES, seed=7)
    result = run_cli(
        tmp_path, "validate", "--calibration", str(calibrated), "--measurements", "iso.csv",
        "--iso9283", "--json", "--plot", "iso.png",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    iso = json.loads(result.stdout)["iso9283"]
    assert iso["poses"] == 5 and iso["fewest_cycles"] == 30
    assert "iso9283-cycles" not in result.stderr
    before = np.array([p["ap_before_mm"] for p in iso["per_pose"]])
    after = np.array([p["ap_after_mm"] for p in iso["per_pose"]])
    rp = np.array([p["rp_mm"] for p in iso["per_pose"]])
    assert np.all(before > 0.2) and np.all(after < 0.05)  # the truth's errors: 0.1-0.5 mm
    expected = 3.616 * 0.02 * np.sqrt(1 - 1 / 30)
    assert np.mean(rp) == pytest.approx(expected, rel=0.08)
    assert iso["rp_mm"] == max(rp) and iso["ap_after_mm"] == max(after)
    assert (tmp_path / "iso.png").stat().st_size > 10_000


def test_validate_iso9283_warns_with_few_cycles_and_refuses_single_poses(tmp_path, calibrated):
    _cycles_file(tmp_path, poses=3, cycles=5, seed=8)
    result = run_cli(
        tmp_path, "validate", "--calibration", str(calibrated), "--measurements", "iso.csv",
        "--iso9283", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "only 5 cycles" in result.stderr
    codes = [w["code"] for w in json.loads(result.stdout)["warnings"]]
    assert "iso9283-cycles" in codes
    result = run_cli(
        tmp_path, "validate", "--calibration", str(calibrated), "--measurements", "iso.csv",
        "--iso9283",
    )  # fmt: skip
    assert "ISO 9283 pose characteristics" in result.stdout
    plan_file(tmp_path, "industrial-6r", m=4, seed=9)
    result = run_cli(
        tmp_path, "synthesize", "--robot", "industrial-6r", "--plan", "plan.csv", "-o", "m.csv"
    )
    assert result.returncode == 0, result.stderr
    result = run_cli(
        tmp_path, "validate", "--calibration", str(calibrated), "--measurements", "m.csv",
        "--iso9283",
    )  # fmt: skip
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("armcal: error: m.csv: no pose is repeated") and "'pose'" in line


def test_a_6_dof_instrument_s_orientation_accuracy_and_repeatability():
    """One pose, four cycles, turns after calibration of (1, 3, 1, 3) mrad about x and 0
    about y and z: AP_a = 2 mrad, S_a = sqrt(4 x 1 / 3) mrad, RP_a = 3 S_a = 2 sqrt(3)
    mrad; the turns before are 5 mrad more, so AP_a before is 7 mrad."""
    after = np.zeros((4, 3))
    after[:, 0] = [1e-3, 3e-3, 1e-3, 3e-3]
    before = after + np.array([5e-3, 0.0, 0.0])
    points = np.zeros((4, 3))
    found = pose_characteristics(
        np.zeros((4, 1)), points, points, points, ("P",) * 4, turns=(before, after)
    )
    np.testing.assert_allclose(found.orientation_after, [[2e-3, 0, 0]], atol=1e-18)
    np.testing.assert_allclose(found.orientation_before, [[7e-3, 0, 0]], atol=1e-18)
    np.testing.assert_allclose(found.orientation_repeatability, [[2e-3 * np.sqrt(3), 0, 0]])
    summary = found.summary()
    assert summary["rp_orientation_deg"] == pytest.approx(np.degrees(2e-3 * np.sqrt(3)))
    assert summary["ap_before_orientation_deg"] == pytest.approx(np.degrees(7e-3))


def test_the_iso9283_figure_plots_ap_and_rp_on_linear_axes_in_the_robots_frame(
    tmp_path, calibrated
):
    """The figure's data: AP before and after, then AP after beside RP, on linear axes
    from 0; the AP components turned into the robot's base frame, R^T AP with R the
    tracker's turn, built here from the calibration's base.rx, ry, rz as extrinsic x-y-z
    angles by scipy (independently of armcal's own rotations)."""
    from scipy.spatial.transform import Rotation

    from armcal.files import read_calibration, read_measurements
    from armcal.plotting_acceptance import plot_acceptance
    from armcal.workflow import validate_measurements

    _cycles_file(tmp_path, poses=4, cycles=6, seed=5)
    cal = read_calibration(calibrated)
    meas = read_measurements(tmp_path / "iso.csv", cal.arm)
    found = validate_measurements(cal, meas, iso9283=True).acceptance
    assert found is not None
    before_ax, after_ax, parts = plot_acceptance(found).axes
    heights = [p.get_height() for p in before_ax.patches]
    assert_allclose(heights, [*found.accuracy_before_mm, *found.accuracy_after_mm], rtol=1e-12)
    heights = [p.get_height() for p in after_ax.patches]
    assert_allclose(heights, [*found.accuracy_after_mm, *found.repeatability_mm], rtol=1e-12)
    for ax in (before_ax, after_ax):
        assert ax.get_yscale() == "linear" and ax.get_ylim()[0] == 0.0
    turn = Rotation.from_euler("xyz", cal.params[3:6]).as_matrix()
    robot = found.accuracy_after @ turn  # rows: (R^T v)^T
    for axis, line in enumerate(parts.lines[:3]):
        assert_allclose(line.get_ydata(), robot[:, axis], rtol=0, atol=1e-9)
    assert parts.get_ylabel() == "mm (robot base frame)"


def test_validate_reports_its_progress(tmp_path, calibrated):
    """validate_measurements calls progress after the validation and after the ISO 9283
    test: a bar on a terminal (armcal validate), quiet elsewhere."""
    from armcal.files import read_calibration, read_measurements
    from armcal.workflow import validate_measurements

    _cycles_file(tmp_path, poses=3, cycles=4, seed=6)
    cal = read_calibration(calibrated)
    meas = read_measurements(tmp_path / "iso.csv", cal.arm)
    seen: list[tuple[int, int]] = []
    validate_measurements(cal, meas, iso9283=True, progress=lambda *done: seen.append(done))
    assert seen == [(1, 2), (2, 2)]
