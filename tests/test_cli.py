"""The command line: main([...]) for the flows, a real subprocess for the program itself."""

import json
import subprocess
import sys

import numpy as np
from numpy.testing import assert_allclose

from armcal import __version__
from armcal.cli import main


def _run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "armcal", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        check=False,
    )


def test_version_through_python_dash_m():
    result = _run("--version")
    assert result.returncode == 0
    assert result.stdout.strip() == f"armcal {__version__}"


def test_synthesize_identify_round_trip_noiseless(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    plan.write_text(
        "q1_deg,q2_deg,q3_deg,q4_deg\n"
        + "".join(
            f"{7 * k},{36 * k - 180},{72 * k % 360 - 180},{108 * k % 360 - 180}\n"
            for k in range(10)
        )
    )
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.json"
    assert main(["synthesize", "--plan", str(plan), "--sigma", "0", "-o", str(meas)]) == 0
    assert (
        main(
            [
                "identify",
                "--robot",
                "paper-4link",
                "--measurements",
                str(meas),
                "--sigma",
                "0.1",
                "-o",
                str(cal),
            ]
        )
        == 0
    )
    report = capsys.readouterr().out
    assert "dq4" in report and "± " in report
    document = json.loads(cal.read_text())
    values = [p["value"] for p in document["parameters"]]
    assert_allclose(values, [1.5, -0.6, -0.4, 0.7, 0.5, -0.5, 0.7, -0.3], rtol=0, atol=1e-9)


def test_identify_json_on_stdout_matches_file(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    meas = tmp_path / "measurements.csv"
    assert (
        main(
            [
                "identify",
                "--robot",
                "paper-4link",
                "--measurements",
                str(meas),
                "--json",
                "--method",
                "gauss-newton",
                "--robust",
            ]
        )
        == 0
    )
    document = json.loads(capsys.readouterr().out)
    saved = json.loads((tmp_path / "calibration.json").read_text())
    assert document["method"] == "gauss-newton" and document["converged"] is True
    # Estimated sigma here (the built-in robot gives none), given sigma in the demo; both
    # robust fits leave out the demo's bumped measurement.
    assert document["sigma_source"] == "estimated" and saved["sigma_source"] == "given"
    assert_allclose(
        [p["value"] for p in document["parameters"]],
        [p["value"] for p in saved["parameters"]],
        rtol=0,
        atol=1e-9,
    )


def test_same_seed_same_measurements(tmp_path):
    assert main(["demo", "-o", str(tmp_path / "a"), "--seed", "7"]) == 0
    assert main(["demo", "-o", str(tmp_path / "b"), "--seed", "7"]) == 0
    assert main(["demo", "-o", str(tmp_path / "c"), "--seed", "8"]) == 0
    a, b, c = ((tmp_path / d / "measurements.csv").read_bytes() for d in "abc")
    assert a == b and a != c


def test_robot_file_with_base_offset_and_truth(tmp_path, capsys):
    robot = tmp_path / "robot.toml"
    robot.write_text("link_lengths_mm = [300.0, 200.0]\nbase_offset = true\n")
    truth = tmp_path / "truth.toml"
    truth.write_text("dl_mm = [0.3, -0.2]\ndq_deg = [0.1, 0.2]\nbase_mm = [15.0, -5.0]\n")
    plan = tmp_path / "plan.csv"
    plan.write_text("q1_deg,q2_deg\n0,0\n72,72\n144,144\n-144,-144\n-72,-72\n")
    meas = tmp_path / "meas.csv"
    common = ["--robot", str(robot)]
    assert (
        main(
            [
                "synthesize",
                *common,
                "--plan",
                str(plan),
                "--truth",
                str(truth),
                "--sigma",
                "0",
                "-o",
                str(meas),
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert (
        main(
            [
                "identify",
                *common,
                "--measurements",
                str(meas),
                "--sigma",
                "0.1",
                "--json",
            ]
        )
        == 0
    )
    document = json.loads(capsys.readouterr().out)
    values = {p["name"]: p["value"] for p in document["parameters"]}
    expected = {"dl1": 0.3, "dl2": -0.2, "dq1": 0.1, "dq2": 0.2, "x0": 15.0, "y0": -5.0}
    assert values.keys() == expected.keys()
    assert_allclose([values[k] for k in expected], list(expected.values()), rtol=0, atol=1e-9)
    assert document["robot"]["base_offset"] is True


def test_import_prints_nothing_and_loads_no_heavy_dependency():
    # No wall-clock limit here: shared machines are too noisy for one (see STYLE.md).
    code = "import sys, armcal; print('matplotlib' in sys.modules, 'scipy' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stderr == ""
    assert result.stdout == "False False\n"


def test_synthesize_without_output_writes_csv_to_stdout(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    plan.write_text("q1_deg,q2_deg\n0,0\n0,90\n")
    assert main(["synthesize", "--robot", "paper-2link", "--plan", str(plan), "--sigma", "0"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "q1_deg,q2_deg,x_mm,y_mm"
    x, y = map(float, out[2].split(",")[2:])
    # Pose (0, 90) deg with the paper's truth: dtheta = (0.5, 0) deg, lengths 261.5 and 179.4.
    expected = [261.5 * np.cos(np.radians(0.5)), 261.5 * np.sin(np.radians(0.5)) + 179.4]
    assert_allclose([x, y], expected, rtol=0, atol=1e-9)


def test_design_and_evaluate_json_keys(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    png = tmp_path / "plan.png"
    args = ["design", "--poses", "12", "-o", str(plan), "--plot", str(png), "--json"]
    assert main(args) == 0
    designed = json.loads(capsys.readouterr().out)
    assert designed["poses"] == 12 and designed["method"] == "analytic"
    # 1 up to the round-off of sums of cosines (exactly 1 only by luck of the placement).
    assert_allclose(designed["d_efficiency"], 1.0, rtol=0, atol=1e-12)
    assert designed["certified_d_efficiency"] == 1.0
    assert png.read_bytes().startswith(b"\x89PNG")
    assert main(["evaluate", "--plan", str(plan), "--sigma", "0.1", "--json"]) == 0
    evaluated = json.loads(capsys.readouterr().out)
    assert_allclose(evaluated["d_efficiency"], 1.0, rtol=0, atol=1e-12)
    # Orthogonal plan: sigma * sqrt(2n/m) at every pose; dl std sigma / sqrt(m).
    assert_allclose(evaluated["predicted_position_rms_mm"], 0.1 * np.sqrt(8 / 12), rtol=1e-9)
    assert_allclose(evaluated["predicted_std"]["dl3"], 0.1 / np.sqrt(12), rtol=1e-9)
    assert set(evaluated["predicted_std"]) == {f"d{k}{i}" for k in "lq" for i in range(1, 5)}


def test_evaluate_rejects_an_unidentifiable_plan(tmp_path):
    """PRODUCT.md: a plan that cannot identify the parameters is an error (exit 2, one line)."""
    plan = tmp_path / "plan.csv"
    plan.write_text("q1_deg,q2_deg,q3_deg,q4_deg\n" + "10,20,30,40\n" * 6)
    result = _run("evaluate", "--plan", str(plan))
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"armcal: error: {plan}: ")
    # Six identical poses: 2 equations for 8 parameters, a 6-dimensional null space.
    assert "cannot identify" in lines[0] and "rank 2 of 8" in lines[0]
    # Every length can be moved freely, so the first unseen combination starts with dl1.
    assert "unseen combinations: dl1" in lines[0] and "(and 3 more)" in lines[0]


def test_simulate_json_and_seed(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    assert main(["design", "--poses", "20", "-o", str(plan)]) == 0
    capsys.readouterr()
    runs = []
    for _ in range(2):
        assert main(["simulate", "--plan", str(plan), "--trials", "3000", "--json"]) == 0
        runs.append(json.loads(capsys.readouterr().out))
    document = runs[0]
    assert set(document) >= {"trials", "empirical_std", "predicted_std", "bias", "seconds"}
    assert document["trials"] == 3000 and document["seconds"] > 0
    names = ["dl1", "dl2", "dl3", "dl4", "dq1", "dq2", "dq3", "dq4"]
    assert list(document["empirical_std"]) == names
    # Orthogonal 20-pose plan (Table II): sigma / sqrt(m) for every length.
    for name in names[:4]:
        assert_allclose(document["predicted_std"][name], 0.1 / np.sqrt(20), rtol=1e-9)
    empirical = np.array(list(document["empirical_std"].values()))
    predicted = np.array(list(document["predicted_std"].values()))
    # 3000 trials: 1.3 % sampling error of a std, 6 % is > 4 sigma.
    assert_allclose(empirical, predicted, rtol=0.06)
    assert runs[1]["empirical_std"] == document["empirical_std"]  # same --seed, same numbers


def test_simulate_gauss_newton_text_report(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    assert main(["design", "--poses", "12", "--robot", "paper-2link", "-o", str(plan)]) == 0
    capsys.readouterr()
    argv = ["simulate", "--robot", "paper-2link", "--plan", str(plan), "--method", "gauss-newton"]
    assert main([*argv, "--trials", "2000"]) == 0
    out = capsys.readouterr().out
    assert "2000 trials of 12 poses of paper-2link" in out and "gauss-newton" in out
    assert "bias within 4 std/sqrt(N)" in out and "tip error of the calibrated model" in out


def test_poses_needed_paper_examples_and_plan_file(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    assert main(["poses-needed", "--length-std-mm", "0.01", "--json", "-o", str(plan)]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["poses"] == 100 and document["achieved"] <= 0.01 * (1 + 1e-9)
    assert document["with_one_pose_less"] > 0.01
    assert len(plan.read_text().splitlines()) == 101  # header + 100 poses
    assert main(["poses-needed", "--position-rms-mm", "0.02", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["poses"] == 200
    assert main(["poses-needed", "--angle-std-deg", "0.01", "--sigma", "0.05"]) == 0
    assert "poses: the best" in capsys.readouterr().out


def test_demo_report_shows_its_figures_and_the_story(tmp_path, capsys):
    """Issue 10: the demo's report.md has at least 3 figures, each written beside it."""
    import re

    assert main(["demo", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for step in ("1. design", "3. identify (robust)", "4. validate", "5. compensate", "6. export"):
        assert step in out
    report = (tmp_path / "report.md").read_text()
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", report)
    assert len(figures) >= 3
    for name in figures:
        assert (tmp_path / name).stat().st_size > 10_000  # a drawn PNG, not an empty file
    # the bumped measurement (pose 7 of 20) is found and left out
    cal = json.loads((tmp_path / "calibration.json").read_text())
    assert [o["pose"] for o in cal["outliers"] if o["removed"]] == ["7"]


def test_synthesize_a_robot_with_one_target_labels_every_row_and_round_trips(tmp_path, capsys):
    """One [targets] entry: every row says which target it measured, and identify reads it.

    The truth (dl3@A 0.3 mm, dq3@A 0.6 deg, all else 0) comes back noiselessly.
    """
    robot = tmp_path / "tool.toml"
    robot.write_text(
        'name = "tool"\nlink_lengths_mm = [260.0, 180.0, 120.0]\n'
        "[targets]\nA = { length_mm = 150.0, angle_deg = 20.0 }\n"
    )
    truth = tmp_path / "truth.toml"
    truth.write_text("dl_mm = [0, 0, 0.3]\ndq_deg = [0, 0, 0.6]\n")
    plan = tmp_path / "plan.csv"
    plan.write_text(
        "q1_deg,q2_deg,q3_deg\n"
        + "".join(f"{15 * k},{40 * k - 150},{75 * k % 360 - 170}\n" for k in range(8))
    )
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.json"
    common = ["--robot", str(robot)]
    synthesize = ["synthesize", *common, "--truth", str(truth), "--plan", str(plan)]
    assert main([*synthesize, "--sigma", "0", "-o", str(meas)]) == 0
    rows = meas.read_text().splitlines()
    assert rows[0].split(",")[-1] == "target" and len(rows) == 9
    assert all(row.endswith(",A") for row in rows[1:])
    identify = [
        "identify",
        *common,
        "--measurements",
        str(meas),
        "--sigma",
        "0.05",
    ]
    assert main([*identify, "-o", str(cal)]) == 0
    capsys.readouterr()
    values = {p["name"]: p["value"] for p in json.loads(cal.read_text())["parameters"]}
    assert_allclose(values["dl3@A"], 0.3, atol=1e-9)
    assert_allclose(values["dq3@A"], 0.6, atol=1e-9)
    assert_allclose([v for k, v in values.items() if not k.endswith("@A")], 0, atol=1e-9)


#: The PRODUCT.md names of RMS figures, kept for scripts; each has a twin that says which.
RMS_ALIASES = {
    "residual_rms_mm": "residual_rms_per_coordinate_mm",
    "rms_before_mm": "rms_before_per_point_mm",
    "rms_after_mm": "rms_after_per_point_mm",
    "predicted_position_rms_mm": "predicted_position_rms_per_point_mm",
}


def _rms_keys(document, path=""):
    """Every (path, key, value) of a JSON document whose key names an RMS."""
    if isinstance(document, dict):
        for key, value in document.items():
            if "rms" in key:
                yield path, key, value, document
            yield from _rms_keys(value, f"{path}/{key}")
    elif isinstance(document, list):
        for item in document:
            yield from _rms_keys(item, path)


def test_every_rms_key_says_per_point_or_per_coordinate(tmp_path, capsys):
    """RMS per point (Euclidean errors) and per coordinate differ by sqrt(2) in the plane:
    every key of every command's JSON says which, but for the PRODUCT.md names kept for
    scripts, whose twin says it and holds the same number."""
    assert main(["demo", "-o", str(tmp_path)]) == 0
    robot = tmp_path / "robot_calibrated.toml"
    commands = [
        [
            "identify",
            "--robot",
            "paper-4link",
            "--measurements",
            str(tmp_path / "measurements.csv"),
            "--cross-validate",
            "4",
        ],
        [
            "validate",
            "--calibration",
            str(tmp_path / "calibration.json"),
            "--measurements",
            str(tmp_path / "measurements.csv"),
        ],
        [
            "compensate",
            "--calibration",
            str(tmp_path / "calibration.json"),
            "--program",
            str(tmp_path / "program.csv"),
            "-o",
            str(tmp_path / "corrected.csv"),
        ],
        ["evaluate", "--plan", str(tmp_path / "plan.csv")],
        ["simulate", "--plan", str(tmp_path / "plan.csv"), "--trials", "50"],
    ]
    seen = set()
    for command in commands:
        capsys.readouterr()
        assert main([*command, "--json"]) == 0, command
        document = json.loads(capsys.readouterr().out)
        for path, key, value, parent in _rms_keys(document):
            seen.add(key)
            if key in RMS_ALIASES:
                assert parent[RMS_ALIASES[key]] == value, (command[0], path, key)
            else:
                assert any(w in key for w in ("per_point", "per_coordinate", "per_pose")), (
                    command[0],
                    path,
                    key,
                )
    assert robot.exists() and set(RMS_ALIASES) <= seen


def test_identify_imports_scipy_special_not_scipy_stats(tmp_path):
    """Two survival functions cost 0.5-0.7 s and 70 MiB of scipy.stats; scipy.special
    gives the same values (issue 20).  Checked in a fresh process, with outliers and a
    chi-square test, so that every p-value is computed."""
    code = (
        "import sys; from armcal.cli import main; "
        "design = main(['design', '--poses', '12', '-o', 'plan.csv']); "
        "made = main(['synthesize', '--plan', 'plan.csv', '-o', 'meas.csv']); "
        "run = main(['identify', '--robot', 'paper-4link', '--measurements', 'meas.csv', "
        "'--sigma', '0.1']); "
        "print(design, made, run, 'scipy.special' in sys.modules, 'scipy.stats' in sys.modules)"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert result.stdout.splitlines()[-1] == "0 0 0 True False"
