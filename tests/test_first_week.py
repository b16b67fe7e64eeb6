"""A new user's first week: odd inputs armcal accepts, and the warning or policy each gets.

The bad-input catalogue (``test_cli_errors.py``) holds what is refused with exit
status 2.  This file holds the rest of issue 20's list: inputs that are legal
but lead a careless reading to a wrong answer.  Each test runs the program as a
user would and checks that the output says what is wrong and points the right
way -- never a calibration the data cannot support, reported with exit 0 in
silence.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from armcal import load_robot, random_plan, synthesize_measurements
from armcal.files import format_measurements_csv
from helpers import run_cli


def _warnings(run) -> dict[str, str]:
    return {w["code"]: w["message"] for w in json.loads(run.stdout)["warnings"]}


# --------------------------------------------------------------------------- a wrong --fix


@pytest.fixture
def held_wrong(tmp_path: Path) -> Path:
    """paper-3link measured at 15 random poses (sigma 0.05 mm); its dl3 and dq3 are not 0.

    The paper's deviations have dl3 = -0.4 mm and dq3 = 0.7 deg, so holding them
    at 0 leaves a misfit of about a millimetre at every pose: 20 times sigma.
    """
    spec = load_robot("paper-3link")
    q = random_plan(spec.arm, 15, rng=np.random.default_rng(0))
    xy = synthesize_measurements(
        spec.arm, q, spec.default_truth, sigma=0.05, rng=np.random.default_rng(10)
    )
    (tmp_path / "meas.csv").write_text(format_measurements_csv(q, xy))
    return tmp_path


IDENTIFY_HELD = (
    "identify",
    "--robot",
    "paper-3link",
    "--measurements",
    "meas.csv",
    "--fix",
    "dl3,dq3",
    "--sigma",
    "0.05",
    "--json",
)


def test_a_wrong_fix_is_named_as_the_cause_not_outliers(held_wrong: Path) -> None:
    """Freeing the held parameters fits to the noise: that, not --robust, is the advice."""
    run = run_cli(held_wrong, *IDENTIFY_HELD)
    assert run.returncode == 0, run.stderr
    message = _warnings(run)["fit-inconsistent"]
    causes = message.split("likely causes, in order: ")[1]
    assert causes.startswith("the fixed parameters dl3, dq3 are not at nominal")
    # Free, the model is right: chi2 on 2*15 - 6 = 24 dof is near 24, far below the 10-fold
    # drop that names the held parameters.
    chi2 = float(causes.split("chi2 = ")[1].split(" ")[0])
    assert chi2 < 3 * 24
    assert "try --robust" not in message
    assert "not outliers" in message
    assert json.loads(run.stdout)["outliers"] == []  # the list agrees: none is an outlier


def test_a_robust_fit_never_drops_most_of_the_data(held_wrong: Path) -> None:
    """Most poses disagreeing is a model problem: none is left out, the dof stay, it says so."""
    run = run_cli(held_wrong, *IDENTIFY_HELD, "--robust")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    warnings = _warnings(run)
    assert "model-misfit" in warnings
    assert "15 of 15 poses disagree" in warnings["model-misfit"]
    assert "the fixed parameters dl3, dq3" in warnings["model-misfit"]
    assert not any(o["removed"] for o in document["outliers"])
    assert document["poses_used"] == 15
    assert document["degrees_of_freedom"] == 2 * 15 - 4  # 4 free parameters
    assert "armcal: warning: 15 of 15 poses disagree" in run.stderr


# --------------------------------------------------------------------------- lumped compliance

LUMPED_ROBOT = """name = "vertical-lumped"
link_lengths_mm = [400.0, 300.0, 200.0]
joint_limits_deg = [[-170, 170], [-150, 150], [-150, 150]]
base_offset = true
[measurement]
sigma_mm = 0.02
[elastostatic]
gravity_xy = [0, -1]
payload_kg = 10
"""
LUMPED_TRUTH = """dl_mm = [0.5, -0.3, 0.2]
dq_deg = [0.1, -0.2, 0.15]
base_mm = [100.0, -50.0]
c_mdeg_per_m = [20.0, 15.0, 8.0]
k_urad_per_Nm = [3.0, 5.0, 8.0]
"""


def _loaded_plan(path: Path, q_deg: np.ndarray, payload: np.ndarray) -> None:
    rows = [
        ",".join(f"{v:.6f}" for v in pose) + f",{p:g}"
        for pose, p in zip(q_deg, payload, strict=True)
    ]
    path.write_text("q1_deg,q2_deg,q3_deg,payload_kg\n" + "\n".join(rows) + "\n")


def _points(path: Path) -> np.ndarray:
    return np.loadtxt(path, delimiter=",", skiprows=1, usecols=(3, 4))


@pytest.fixture
def lumped(tmp_path: Path) -> Path:
    (tmp_path / "robot.toml").write_text(LUMPED_ROBOT)
    (tmp_path / "truth.toml").write_text(LUMPED_TRUTH)
    return tmp_path


def test_a_constant_payload_bends_a_lumped_virtual_arm(lumped: Path) -> None:
    """A pose at 10 kg lands where the same pose at 10 kg lands in a mixed plan (sigma 0).

    With one payload a fit merges it into c1..cn, but the virtual arm must still bend
    under it: synthesize once put every 10 kg pose where the 0 kg pose lands.
    """
    q = np.random.default_rng(1).uniform([-160, -140, -140], [160, 140, 140], (12, 3))
    _loaded_plan(lumped / "constant.csv", q, np.full(12, 10.0))
    _loaded_plan(lumped / "mixed.csv", q, np.tile([10.0, 0.0], 6))
    _loaded_plan(lumped / "empty.csv", q, np.zeros(12))
    for name in ("constant", "mixed", "empty"):
        run = run_cli(lumped, "synthesize", "--robot", "robot.toml", "--truth", "truth.toml",
                      "--plan", f"{name}.csv", "--sigma", "0", "-o", f"m_{name}.csv")  # fmt: skip
        assert run.returncode == 0, run.stderr
    constant, mixed, empty = (
        _points(lumped / f"m_{n}.csv") for n in ("constant", "mixed", "empty")
    )
    np.testing.assert_allclose(constant[::2], mixed[::2], atol=1e-9)  # the 10 kg rows
    np.testing.assert_allclose(empty[1::2], mixed[1::2], atol=1e-9)  # the 0 kg rows
    # 10 kg on a lever of up to 0.9 m with k of 3..8 urad/(N m) moves the tip ~0.1 mm.
    assert np.max(np.linalg.norm(constant - empty, axis=1)) > 0.05


def test_a_one_payload_lumped_calibration_holds_at_its_payload_and_says_so_elsewhere(
    lumped: Path,
) -> None:
    rng = np.random.default_rng(2)
    limits = ([-160, -140, -140], [160, 140, 140])
    _loaded_plan(lumped / "plan.csv", rng.uniform(*limits, (40, 3)), np.full(40, 10.0))
    _loaded_plan(lumped / "held10.csv", rng.uniform(*limits, (40, 3)), np.full(40, 10.0))
    _loaded_plan(lumped / "held0.csv", rng.uniform(*limits, (40, 3)), np.zeros(40))
    for seed, name in enumerate(("plan", "held10", "held0")):
        run = run_cli(lumped, "synthesize", "--robot", "robot.toml", "--truth", "truth.toml",
                      "--plan", f"{name}.csv", "--seed", str(seed),
                      "-o", f"m_{name}.csv")  # fmt: skip
        assert run.returncode == 0, run.stderr
    run = run_cli(lumped, "identify", "--robot", "robot.toml", "--measurements", "m_plan.csv",
                  "-o", "cal.json")  # fmt: skip
    assert run.returncode == 0 and run.stderr == "", run.stderr
    assert json.loads((lumped / "cal.json").read_text())["elastostatic"]["payload_kg"] == 10.0
    # At its payload the calibration predicts the held-out poses: no warning.
    run = run_cli(lumped, "validate", "--calibration", "cal.json", "--measurements",
                  "m_held10.csv", "--json")  # fmt: skip
    assert run.returncode == 0 and run.stderr == "", run.stderr
    # At 0 kg the payload's deflection is missing, and the warning says why.
    run = run_cli(lumped, "validate", "--calibration", "cal.json", "--measurements",
                  "m_held0.csv", "--json")  # fmt: skip
    assert "loads-unpredicted" in _warnings(run)
    assert "one payload, 10 kg" in _warnings(run)["loads-unpredicted"]
    (lumped / "prog.csv").write_text("q1_deg,q2_deg,q3_deg\n10,20,30\n40,-50,60\n")
    run = run_cli(lumped, "compensate", "--calibration", "cal.json", "--program", "prog.csv",
                  "--payload-kg", "0", "-o", "out.csv", "--json")  # fmt: skip
    assert "loads-unpredicted" in _warnings(run)


def test_plan_size_guard_uses_half_the_machine():
    from armcal.errors import ArmcalError
    from armcal.workflow.setup import BYTES_PER_DESIGNED_POSE, check_plan_size

    memory = 8 * 10**9
    check_plan_size(memory // (2 * BYTES_PER_DESIGNED_POSE), memory)  # exactly half: fine
    with pytest.raises(ArmcalError, match="more than half of this machine's 8 GB"):
        check_plan_size(memory // (2 * BYTES_PER_DESIGNED_POSE) + 1, memory)


# --------------------------------------------------------------------------- hints


def _paper_measurements(m: int, sigma: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """paper-4link at ``m`` random poses with the paper's deviations, noise ``sigma`` (mm)."""
    spec = load_robot("paper-4link")
    q = random_plan(spec.arm, m, rng=np.random.default_rng(seed))
    xy = synthesize_measurements(
        spec.arm, q, spec.default_truth, sigma=sigma, rng=np.random.default_rng(seed + 1)
    )
    return q, xy


@pytest.mark.parametrize(
    ("mirror", "order", "signs"),
    [("swapped", [1, 0], [1.0, 1.0]), ("flipped", [0, 1], [1.0, -1.0])],
)
def test_mirrored_measurements_are_named_not_outliers(
    tmp_path: Path, mirror: str, order: list[int], signs: list[float]
) -> None:
    """x and y swapped, or y flipped (a camera's image y down): say so, not "try --robust".

    Undone, the mirror leaves the noise: chi2 on 2*20 - 8 = 32 dof stays below 3 x 32
    (probability about 1e-8 under the model).  In the plane with the base at the
    instrument's origin, dq1 takes up any rotation, so a swap is a flip turned 90 deg:
    the message names both.
    """
    q, xy = _paper_measurements(20, 0.1, 3)
    (tmp_path / "meas.csv").write_text(format_measurements_csv(q, xy[:, order] * signs))
    run = run_cli(tmp_path, "identify", "--robot", "paper-4link", "--measurements", "meas.csv",
                  "--sigma", "0.1", "--json")  # fmt: skip
    message = _warnings(run)["fit-inconsistent"]
    first = message.split("likely causes, in order: ")[1]
    assert first.startswith(
        "the measurements are mirrored: x and y are swapped, or one axis is flipped"
    )
    assert float(first.split("chi2 = ")[1].split(" ")[0]) < 3 * 32
    assert "try --robust" not in message


def test_a_good_fit_is_never_called_mirrored(tmp_path: Path) -> None:
    """Control: the same data unmirrored give no fit-inconsistent warning at all."""
    q, xy = _paper_measurements(20, 0.1, 3)
    (tmp_path / "meas.csv").write_text(format_measurements_csv(q, xy))
    run = run_cli(tmp_path, "identify", "--robot", "paper-4link", "--measurements", "meas.csv",
                  "--sigma", "0.1", "--json")  # fmt: skip
    assert run.returncode == 0 and "fit-inconsistent" not in _warnings(run)


COUPLED_ROBOT = """name = "coupled"
link_lengths_mm = [260.0, 180.0, 120.0]
base_offset = true
joint_map = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
[measurement]
sigma_mm = 0.05
"""
COUPLED_TRUTH = "dl_mm = [0.5, -0.3, 0.2]\ndq_deg = [0.3, -0.2, 0.4]\nbase_mm = [400.0, -150.0]\n"


@pytest.fixture
def coupled(tmp_path: Path) -> Path:
    """The coupled arm measured at 12 random poses, its data turned 40 deg in the plane.

    Every joint is read from the horizon (joint map I), so a turn of the whole arm is
    dq1 + dq2 + dq3 together, and the 40 deg turn of the instrument's axes lands there.
    """
    (tmp_path / "robot.toml").write_text(COUPLED_ROBOT)
    (tmp_path / "truth.toml").write_text(COUPLED_TRUTH)
    spec = load_robot(tmp_path / "robot.toml")
    q = random_plan(spec.arm, 12, rng=np.random.default_rng(4))
    (tmp_path / "plan.csv").write_text(
        "q1_deg,q2_deg,q3_deg\n" + "".join(",".join(f"{v:.9f}" for v in np.degrees(p)) + "\n"
                                           for p in q)
    )  # fmt: skip
    run = run_cli(tmp_path, "synthesize", "--robot", "robot.toml", "--truth", "truth.toml",
                  "--plan", "plan.csv", "--seed", "5", "-o", "flat.csv")  # fmt: skip
    assert run.returncode == 0, run.stderr
    data = np.loadtxt(tmp_path / "flat.csv", delimiter=",", skiprows=1)
    turn = np.radians(40.0)
    rotation = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    turned = data[:, 3:5] @ rotation.T
    angles = np.radians(data[:, :3])
    (tmp_path / "turned.csv").write_text(format_measurements_csv(angles, turned))
    flat3d = np.column_stack([turned, np.full(len(turned), 250.0)])
    (tmp_path / "turned3d.csv").write_text(format_measurements_csv(angles, flat3d))
    return tmp_path


def test_the_large_deviation_remark_names_the_offsets_of_the_joint_map(coupled: Path) -> None:
    """In 2-D the 40 deg turn is in dq1 + dq2 + dq3 under this map, not in dq1 alone."""
    run = run_cli(coupled, "identify", "--robot", "robot.toml", "--measurements", "turned.csv",
                  "--json")  # fmt: skip
    message = _warnings(run)["large-deviation"]
    assert "with a base offset, dq1 + dq2 + dq3 also take up any rotation" in message


def test_the_3d_report_keeps_phi0_free_and_its_advice_works(coupled: Path) -> None:
    """--fix phi0 would put the tracker's 40 deg turn into the offsets; the report offers
    another offset to hold instead, and following that advice gives calibration-sized
    offsets (no large-deviation warning)."""
    base = ("identify", "--robot", "robot.toml", "--measurements", "turned3d.csv")
    run = run_cli(coupled, *base)
    assert run.returncode == 0, run.stderr
    line = next(x for x in run.stdout.splitlines() if x.startswith("base rotation phi0"))
    assert "--fix phi0" not in line
    assert "keep phi0 free" in line
    advice = line.split("--fix ")[1].rstrip(")")
    assert advice == "dq2"  # the next offset on the turn's direction dq1 + dq2 + dq3
    followed = run_cli(coupled, *base, "--fix", advice, "--json")
    assert followed.returncode == 0 and "large-deviation" not in _warnings(followed)
    held = run_cli(coupled, *base, "--fix", "phi0", "--json")
    assert "large-deviation" in _warnings(held)  # why phi0 is not to be held


def test_no_compliance_does_not_ask_for_the_table_the_file_has(lumped: Path) -> None:
    rng = np.random.default_rng(6)
    payload = np.tile([0.0, 10.0], 10)
    _loaded_plan(lumped / "plan.csv", rng.uniform([-160, -140, -140], [160, 140, 140], (20, 3)),
                 payload)  # fmt: skip
    run = run_cli(lumped, "synthesize", "--robot", "robot.toml", "--truth", "truth.toml",
                  "--plan", "plan.csv", "-o", "meas.csv")  # fmt: skip
    assert run.returncode == 0, run.stderr
    run = run_cli(lumped, "identify", "--robot", "robot.toml", "--measurements", "meas.csv",
                  "--no-compliance", "--json")  # fmt: skip
    message = _warnings(run)["loads-ignored"]
    assert "--no-compliance fits the geometry only; leave it out" in message
    assert "add [elastostatic]" not in message


def test_no_arguments_lists_the_commands(tmp_path: Path) -> None:
    """A first try, ``armcal`` alone: the commands on stdout, one error line, exit 2."""
    from armcal.cli.help import COMMANDS

    run = run_cli(tmp_path)
    assert run.returncode == 2
    for command in COMMANDS:
        assert f"    {command}" in run.stdout
    assert run.stderr == "armcal: error: no command given; pick one of the commands above\n"


def test_several_reflectors_count_poses_not_rows(tmp_path: Path) -> None:
    """8 poses at 2 targets are 8 poses and 16 measurements, not "16 poses"."""
    (tmp_path / "robot.toml").write_text(
        'name = "two-reflectors"\nlink_lengths_mm = [260.0, 180.0, 120.0]\n'
        "[measurement]\nsigma_mm = 0.05\n"
        "[targets]\nA = { length_mm = 100.0 }\nB = { length_mm = 60.0, angle_deg = 30.0 }\n"
    )
    (tmp_path / "truth.toml").write_text("dl_mm = [0.5, -0.3, 0.2]\ndq_deg = [0.3, -0.2, 0.4]\n")
    for argv in (
        ("design", "--robot", "robot.toml", "--poses", "8", "-o", "plan.csv"),
        ("synthesize", "--robot", "robot.toml", "--truth", "truth.toml", "--plan", "plan.csv",
         "-o", "meas.csv"),
    ):  # fmt: skip
        assert run_cli(tmp_path, *argv).returncode == 0
    run = run_cli(tmp_path, "identify", "--robot", "robot.toml", "--measurements", "meas.csv",
                  "-o", "cal.json")  # fmt: skip
    assert run.stdout.startswith("calibration of two-reflectors: 8 poses (16 measurements of 2 ")
    run = run_cli(tmp_path, "validate", "--calibration", "cal.json", "--measurements", "meas.csv")
    # The calibration's own rows: counted as poses, and not called held-out (battery 2).
    assert run.stdout.startswith(
        "validation of two-reflectors on 8 poses (16 points, all of them the calibration's "
        "own rows, not held out)"
    )


def test_a_robot_file_in_metres_is_named_on_every_command(tmp_path: Path) -> None:
    (tmp_path / "robot.toml").write_text("link_lengths_mm = [0.26, 0.18, 0.12]\n")
    run = run_cli(tmp_path, "design", "--robot", "robot.toml", "--poses", "6", "--json")
    assert run.returncode == 0, run.stderr
    message = _warnings(run)["lengths-in-metres"]
    assert "the links add up to 0.56 mm, which looks like metres" in message
    assert "[260, 180, 120]" in message


@pytest.mark.slow  # four designs of poses and payloads, about 10 s
def test_poses_needed_sizes_a_robot_with_compliance(lumped: Path) -> None:
    """Once refused; now plans of poses and payloads, checked by evaluate's own std."""
    run = run_cli(lumped, "poses-needed", "--robot", "robot.toml", "--length-std-mm", "0.008",
                  "-o", "plan.csv", "--json")  # fmt: skip
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout)
    header = (lumped / "plan.csv").read_text().splitlines()[0]
    assert header == "q1_deg,q2_deg,q3_deg,payload_kg"
    checked = run_cli(lumped, "evaluate", "--robot", "robot.toml", "--plan", "plan.csv", "--json")
    assert checked.returncode == 0, checked.stderr
    quality = json.loads(checked.stdout)
    largest = max(v for k, v in quality["predicted_std"].items() if k.startswith("dl"))
    assert largest <= 0.008 * (1 + 1e-9)
    assert found["with_one_pose_less"] > 0.008  # one pose fewer does not reach it
    assert found["poses"] == len((lumped / "plan.csv").read_text().splitlines()) - 1


def test_check_compliance_with_few_trials_says_the_ratios_mean_little(tmp_path: Path) -> None:
    """--trials 2 was accepted in silence; an empirical std of N trials is known to
    about 1/sqrt(2 (N - 1)): 100 % at N = 3."""
    run = run_cli(tmp_path, "check-compliance", "--trials", "3", "--json")
    assert run.returncode == 0, run.stderr
    assert "known to about +-50 %" in _warnings(run)["few-trials"]


def test_a_robot_file_may_not_hold_phi0(tmp_path: Path) -> None:
    """The policy: phi0 belongs to the set-up; the file says so, --fix phi0 stays."""
    (tmp_path / "robot.toml").write_text(
        'link_lengths_mm = [260.0, 180.0]\n[identify]\nfixed = ["phi0"]\n'
    )
    run = run_cli(tmp_path, "design", "--robot", "robot.toml", "--poses", "4")
    assert run.returncode == 2
    assert "belongs to the set-up, not the robot" in run.stderr
    assert "use --fix phi0" in run.stderr
