"""Planes, fixed points and distances through the front door: robot and truth files, the
measurement CSV, the calibration JSON and the commands (issue 38).

A virtual lab is a built-in six-axis arm's robot file with a tool point in ``[targets]``
and an ``[instrument]`` table (where the user roughly knows the instrument is), and its
built-in truth without the tracker's ``base`` and with the true instrument (10 mm and
1-2 degrees from the user's).  The plan is random poses within the limits moved onto
the rough instrument (what ``design`` does before it chooses); ``synthesize`` moves
them onto the true one.  Tolerances: readings of points about 2 m from the base are
exact to about 1e-12 mm (5 ulp at 2000 mm); a held-out RMS below 1e-9 mm is round-off.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from armcal.choices import BUILTIN_SPATIAL_ROBOTS
from armcal.criteria import position_accuracy
from armcal.files import load_robot
from helpers import run_cli
from helpers_instruments import met_plan, refused_measurements, refused_table, write_lab


def synthesized(
    folder: Path, robot_file: Path, truth: Path, plan: str, out: str, *options: str
) -> str:
    """``armcal synthesize`` of ``plan`` on the lab's truth into ``out`` (with ``options``)."""
    return ok(
        folder,
        "synthesize",
        "--robot",
        robot_file.name,
        "--plan",
        plan,
        "--truth",
        truth.name,
        *options,
        "-o",
        out,
    )


def ok(folder: Path, *args: str) -> str:
    run = run_cli(folder, *args)
    assert run.returncode == 0, run.stderr
    return run.stdout


@pytest.mark.parametrize(
    ("robot", "kind", "poses"),
    [
        ("industrial-6r", "plane", 150),
        ("cobot-6r", "plane", 150),
        ("industrial-6r", "point", 150),
        ("cobot-6r", "point", 150),
        ("industrial-6r", "distance", 150),
        ("cobot-6r", "distance", 150),
    ],
)
def test_noiseless_lab_is_recovered_on_held_out_rows(tmp_path, robot, kind, poses):
    """synthesize (noiseless) -> identify -> validate on other poses: the calibrated model
    predicts every held-out reading to round-off, from the user's rough instrument."""
    robot_file, truth = write_lab(tmp_path, robot, kind)
    train = met_plan(tmp_path, robot_file, poses, 1, "train.csv")
    test = met_plan(tmp_path, robot_file, 30, 2, "test.csv")
    for plan, meas in ((train, "meas.csv"), (test, "held.csv")):
        synthesized(tmp_path, robot_file, truth, plan.name, meas, "--sigma", "0")
    header = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()[0]
    assert "x_mm" not in header
    assert ("distance_mm" in header) == (kind == "distance")
    assert header.endswith(f",{kind}") == (kind in ("plane", "point"))
    ok(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    document = json.loads((tmp_path / "cal.json").read_text(encoding="utf-8"))
    assert document["robot"]["kind"] == "instrumented"
    assert document["robot"]["instrument"]["kind"] == kind
    assert document["robot"]["unseen"]
    names = [p["name"] for p in document["parameters"]]
    model = load_robot(robot_file).arm
    assert names == list(model.param_names)
    summary = json.loads(
        ok(
            tmp_path,
            "validate",
            "--calibration",
            "cal.json",
            "--measurements",
            "held.csv",
            "--json",
        )
    )
    assert summary["rms_after_mm"] < 1e-9
    assert summary["rms_before_mm"] > 1e-3  # the nominal arm misses by the arm's errors


def test_noisy_fit_is_consistent_with_sigma(tmp_path):
    """Touches with noise (sigma 0.01 mm, in where the arm stopped) fit with chi2 near its
    dof: the noise a touch carries is the noise the fit expects."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "plane")
    met_plan(tmp_path, robot_file, 80, 3, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv", "--seed", "4")
    document = json.loads(
        ok(
            tmp_path,
            "identify",
            "--robot",
            robot_file.name,
            "--measurements",
            "meas.csv",
            "--json",
        )
    )
    fit = document["goodness_of_fit"]
    assert 1e-3 < fit["p_value"] < 1 - 1e-3, fit
    assert not [w for w in document["warnings"] if w["code"] == "fit-inconsistent"]


def test_evaluate_and_simulate_take_an_instrument(tmp_path):
    """evaluate and simulate work through the instrument's model, and name its parameters."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "distance")
    met_plan(tmp_path, robot_file, 40, 5, "plan.csv")
    quality = json.loads(
        ok(tmp_path, "evaluate", "--robot", robot_file.name, "--plan", "plan.csv", "--json")
    )
    assert "pivot.x" in quality["predicted_std"] and "offset" in quality["predicted_std"]
    result = json.loads(
        ok(
            tmp_path,
            "simulate",
            "--robot",
            robot_file.name,
            "--plan",
            "plan.csv",
            "--truth",
            truth.name,
            "--trials",
            "40",
            "--json",
        )
    )
    assert result["trials"] == 40
    assert set(result["empirical_std"]) == set(result["predicted_std"])


BAD_ROBOTS = {
    "unknown kind": ('kind = "planes"\n', "did you mean 'plane'"),
    "camera without a mount": ('kind = "camera"\n', "key 'instrument.mount': expected"),
    "zero normal": (
        'kind = "plane"\nplanes = { top = { normal = [0, 0, 0], offset_mm = 1.0 } }\n',
        "zero length",
    ),
    "range": ('kind = "distance"\npivot_mm = [0, 0, 0]\nrange_mm = [200, 100]\n', "least"),
    "unreachable distance": (
        'kind = "distance"\npivot_mm = [9000, 0, 0]\nrange_mm = [100, 200]\n',
        "no pose can meet it",
    ),
    "unreachable plane": (
        'kind = "plane"\nplanes = { far = { normal = [0, 0, 1], offset_mm = 9000.0 } }\n',
        "beyond the tool's reach",
    ),
    "tracker key": (
        'kind = "plane"\nplanes = { a = { normal = [0, 0, 1], '
        "offset_mm = 1.0 } }\nposition_mm = [0, 0, 0]\n",
        "position_mm",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_ROBOTS))
def test_bad_instrument_table_is_one_line(tmp_path, case):
    table, words = BAD_ROBOTS[case]
    assert words in refused_table(tmp_path, table)


def test_bad_measurements_are_one_line(tmp_path):
    """A label that is no plane, a missing label column with two planes, a tracker's
    columns, and a row whose tool is far from its plane: exit 2, file and row named."""
    robot_file, truth = write_lab(tmp_path, "industrial-6r", "plane")
    met_plan(tmp_path, robot_file, 40, 6, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv")
    good = (tmp_path / "meas.csv").read_text(encoding="utf-8").splitlines()
    head, rows = good[0], good[1:]
    wrong_label = rows[0].rsplit(",", 1)[0] + ",tpo"
    other = "side" if rows[0].endswith("top") else "top"
    swapped = rows[0].rsplit(",", 1)[0] + "," + other
    cases = {
        "label": ([head, wrong_label, *rows[1:]], "row 1 (line 2), column plane", "'top'"),
        "no column": (
            [head.rsplit(",", 1)[0], *(r.rsplit(",", 1)[0] for r in rows)],
            "missing column 'plane'",
            "add a column 'plane'",
        ),
        "tracker": ([head + ",x_mm", *(r + ",1" for r in rows)], "unknown column 'x_mm'", ""),
        "geometry": ([head, swapped, *rows[1:]], "row 1:", "from where the other rows put"),
    }
    for name, (lines, where, words) in cases.items():
        refused_measurements(tmp_path, robot_file.name, lines, where, words, name=name)


def test_validation_figure_compensation_and_export_of_an_instrument(tmp_path):
    """validate draws a touch calibration's errors against the pose (no arrows: a touch
    reads no position), and the figure plots the validation's numbers; compensate and
    export work on the arm alone, in the frame the plate was placed in: every corrected
    command puts the calibrated arm's tool where the nominal arm holding it would have
    put it (1e-6 mm: the commands are written to 1e-12 deg, 2e-11 mm at 1.2 m), and the
    exported robot file, holding the calibrated tool (a comment there, as for a tracker),
    reads back as that calibrated arm (1e-9 mm: its numbers are written to round-trip)."""
    from armcal.files import read_calibration, read_measurements, read_program
    from armcal.plotting import plot_validation
    from armcal.validation import validate

    robot_file, truth = write_lab(tmp_path, "industrial-6r", "plane")
    met_plan(tmp_path, robot_file, 60, 7, "plan.csv")
    met_plan(tmp_path, robot_file, 30, 8, "check-plan.csv")
    for plan, meas in (("plan.csv", "meas.csv"), ("check-plan.csv", "check.csv")):
        synthesized(tmp_path, robot_file, truth, plan, meas)
    ok(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    ok(
        tmp_path,
        "validate",
        "--calibration",
        "cal.json",
        "--measurements",
        "check.csv",
        "--plot",
        "v.png",
        "--report",
        "v.html",
    )
    assert (tmp_path / "v.png").stat().st_size > 0 and (tmp_path / "v.html").is_file()
    cal = read_calibration(tmp_path / "cal.json")
    meas = read_measurements(tmp_path / "check.csv", cal.arm)
    result = validate(cal, meas.q, meas.readings, feature=meas.feature)
    fig = plot_validation(cal.arm, meas.q, result)
    assert len(fig.axes) == 2  # the errors against the pose and their distribution
    np.testing.assert_array_equal(fig.axes[1].lines[1].get_ydata(), result.after_mm)
    ok(
        tmp_path,
        "compensate",
        "--calibration",
        "cal.json",
        "--program",
        "check-plan.csv",
        "-o",
        "corrected.csv",
    )
    alone = cal.alone()
    assert alone.model is cal.model.inner and alone.params.size == cal.model.n_arm
    program = read_program(tmp_path / "check-plan.csv", alone.model)
    table = np.loadtxt(tmp_path / "corrected.csv", delimiter=",", skiprows=1)
    corrected, done = np.radians(table[:, :6]), table[:, 6] == 1  # q1_deg..q6_deg,corrected
    assert done.sum() >= 20
    # The goal: the nominal arm holding the calibrated tool (compensation's, in its notes).
    meant = np.where(alone.model.instrument_params, alone.params, 0.0)
    nominal = alone.model.positions(alone.model.conditions(program.q[done]), meant)
    reached = alone.positions(alone.model.conditions(corrected[done]))
    np.testing.assert_allclose(reached, nominal, atol=1e-6)
    ok(tmp_path, "export", "--calibration", "cal.json", "--robot-toml", "calibrated.toml")
    exported = load_robot(tmp_path / "calibrated.toml").arm  # the tool is a comment there
    tool = np.char.startswith(exported.param_names, "tool.")
    holding = np.where(tool, alone.params, exported.nominal)  # the calibrated tool held
    np.testing.assert_allclose(
        exported.positions(exported.conditions(program.q), holding),
        alone.positions(alone.model.conditions(program.q)),
        atol=1e-9,
    )


def test_a_plan_of_an_instrument_is_drawn(tmp_path):
    """design --plot for an arm measured by planes: the plan's four panels, the planes
    marked where the robot file puts them (each plane's point nearest the base's origin,
    offset times the unit normal), the arm's own predicted error over poses within the
    limits (criteria.position_accuracy at the same poses), and the variance function over
    poses that touch a plane at or below the certificate's maximum."""
    from armcal.doe import certify, feasible_poses
    from armcal.plotting_spatial import MAP_POSES, plot_spatial_plan

    robot_file, _ = write_lab(tmp_path, "cobot-6r", "plane")
    ok(
        tmp_path,
        "design",
        "--robot",
        robot_file.name,
        "--poses",
        "30",
        "-o",
        "plan.csv",
        "--plot",
        "plan.png",
    )
    assert (tmp_path / "plan.png").stat().st_size > 10_000
    model = load_robot(robot_file).arm
    q = feasible_poses(model, 30, rng=np.random.default_rng(3))
    model = model.prepared(model.plan_conditions(q))
    certificate = certify(model, q, rng=2, candidates=300, rounds=1, search=500)
    figure = plot_spatial_plan(model, q, sigma=0.01, certificate=certificate)
    marks = {t.get_text().strip(): t.get_position_3d() for t in figure.axes[0].texts}
    for label, plane in model.instrument.planes.items():
        np.testing.assert_allclose(marks[label], plane.offset_mm * plane.normal, atol=1e-9)
    workspace = feasible_poses(model.inner, MAP_POSES, rng=0)
    expected = position_accuracy(model, q, workspace, 0.01).per_pose_mm
    np.testing.assert_allclose(figure.axes[2].collections[0].get_array(), expected, rtol=1e-12)
    variance = figure.axes[-1].lines[0].get_ydata()
    assert np.max(variance) <= certificate.max_variance * (1 + 1e-9)


def test_fixing_an_instrument_parameter_keeps_the_base_held(tmp_path):
    """--fix of the arm's or the instrument's parameter leaves the arm's base held at the
    origin of its frame, where the instrument is placed."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "plane")
    met_plan(tmp_path, robot_file, 150, 9, "plan.csv")
    synthesized(tmp_path, robot_file, truth, "plan.csv", "meas.csv", "--sigma", "0")
    # The rule frees what merged into the held one (j1.z for the offset, j3.y for dq2):
    # the rows identify as many parameters as before, none of them the base's.
    for fixed, free in (("top.offset", 26), ("dq2", 26)):
        document = json.loads(
            ok(
                tmp_path,
                "identify",
                "--robot",
                robot_file.name,
                "--measurements",
                "meas.csv",
                "--fix",
                fixed,
                "--json",
            )
        )
        by_name = {p["name"]: p for p in document["parameters"]}
        assert all(by_name[f"base.{c}"]["fixed"] for c in ("x", "y", "z", "rx", "ry", "rz"))
        assert by_name[fixed]["fixed"]
        assert sum(not p["fixed"] for p in document["parameters"]) == free


MORE_BAD_ROBOTS = {
    "a label the arm has": (
        'kind = "point"\npoints = { tool = { xyz_mm = [500, 0, 300] } }\n',
        "",
        "rename them",
    ),
    "noise of a point": (
        'kind = "plane"\nplanes = { top = { normal = [0, 0, 1], offset_mm = 100 } }\n',
        "[measurement]\nsigma_mm = [0.01, 0.01, 0.03]\n",
        "key 'measurement'",
    ),
    "an underflowing normal": (
        'kind = "plane"\nplanes = { top = { normal = [0, 0, 1e-320], offset_mm = 100 } }\n',
        "",
        "zero length",
    ),
    "a bar to an unknown point": (
        'kind = "point"\npoints = { A = { xyz_mm = [500, 0, 300] } }\n'
        'known_distances_mm = [["A", "C", 100.0]]\n',
        "",
        "'C' is not a point",
    ),
}


@pytest.mark.parametrize("case", sorted(MORE_BAD_ROBOTS))
def test_more_bad_instrument_tables_are_one_line(tmp_path, case):
    table, measurement, words = MORE_BAD_ROBOTS[case]
    assert words in refused_table(tmp_path, table, measurement)


def test_a_tracker_said_by_kind_alone_is_a_tracker(tmp_path):
    """[instrument] kind = "tracker" (the default, written out) and nothing else."""
    source = BUILTIN_SPATIAL_ROBOTS["cobot-6r"].read_text(encoding="utf-8")
    (tmp_path / "r.toml").write_text(f'{source}\n[instrument]\nkind = "tracker"\n')
    (tmp_path / "p.csv").write_text(
        "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n"
        + "".join(
            f"{10 * i},{-20 + 7 * i},{30 - 4 * i},{5 * i},{40 - 11 * i},{3 * i}\n"
            for i in range(30)
        )
    )
    ok(tmp_path, "evaluate", "--robot", "r.toml", "--plan", "p.csv")


def test_a_known_distance_between_cones_is_kept_and_recovered(tmp_path):
    """A bar of known length between cones A and B: B is two turns about A, the distance
    holds exactly, and noiseless seatings recover the arm to round-off on held-out ones."""
    robot_file, truth = write_lab(tmp_path, "cobot-6r", "point")
    true = {
        label: np.array([float(v) for v in xyz.split(", ")])
        for label, xyz in re.findall(r"(\w) = \{ xyz_mm = \[([^\]]*)\] \}", truth.read_text())
    }
    bar = float(np.linalg.norm(true["B"] - true["A"]))
    with robot_file.open("a", encoding="utf-8") as handle:
        handle.write(f'known_distances_mm = [["A", "B", {bar!r}]]\n')
    model = load_robot(robot_file).arm
    assert "B.rx" in model.param_names and "B.x" not in model.param_names
    met_plan(tmp_path, robot_file, 150, 1, "train.csv")
    met_plan(tmp_path, robot_file, 30, 2, "test.csv")
    for plan, meas in (("train.csv", "meas.csv"), ("test.csv", "held.csv")):
        synthesized(tmp_path, robot_file, truth, plan, meas, "--sigma", "0")
    ok(
        tmp_path,
        "identify",
        "--robot",
        robot_file.name,
        "--measurements",
        "meas.csv",
        "-o",
        "cal.json",
    )
    summary = json.loads(
        ok(
            tmp_path,
            "validate",
            "--calibration",
            "cal.json",
            "--measurements",
            "held.csv",
            "--json",
        )
    )
    assert summary["rms_after_mm"] < 1e-9
