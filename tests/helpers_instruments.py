"""Virtual labs of an instrument other than a tracker (issue 38): a built-in six-axis arm's
robot file with a tool point in ``[targets]`` and an ``[instrument]`` table (where the
user roughly knows the instrument is), and its built-in truth without the tracker's
``base`` and with the true instrument (10 mm and 1-2 degrees from the user's)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np

from armcal.choices import BUILTIN_SPATIAL_ROBOTS
from armcal.doe import feasible_poses
from armcal.files import format_plan_csv, load_robot
from helpers import run_cli


def instruments(reach: float, kind: str) -> tuple[str, str]:
    """Where the user says the instrument is, and where it really is (the truth file's),
    placed by the arm's reach as in ``test_instruments``: within reach of poses inside
    the limits."""

    def mm(*fractions: float, shift: float = 0.0) -> str:
        return "[" + ", ".join(f"{f * reach + shift:.1f}" for f in fractions) + "]"

    if kind == "plane":
        return (
            'kind = "plane"\nplanes = { top = { normal = [0, 0, 1], offset_mm = '
            f"{0.1 * reach + 10:.1f} }}, side = {{ normal = [1, 0, 0], offset_mm = "
            f"{0.45 * reach - 10:.1f} }} }}\n",
            f"planes = {{ top = {{ normal = [0.01, -0.02, 1], offset_mm = {0.1 * reach:.1f} }}, "
            f"side = {{ normal = [1, 0.03, -0.01], offset_mm = {0.45 * reach:.1f} }} }}\n",
        )
    if kind == "point":
        return (
            f'kind = "point"\npoints = {{ A = {{ xyz_mm = {mm(0.45, 0.1, 0.2, shift=10)} }}, '
            f"B = {{ xyz_mm = {mm(0.4, -0.2, 0.1, shift=10)} }} }}\n",
            f"points = {{ A = {{ xyz_mm = {mm(0.45, 0.1, 0.2)} }}, "
            f"B = {{ xyz_mm = {mm(0.4, -0.2, 0.1)} }} }}\n",
        )
    if kind == "partial":  # a CMM's frame, or a rig of dial indicators along its axes
        return (
            f'kind = "partial"\nreads = ["x", "y", "z"]\nxyz_mm = {mm(0.5, 0.1, 0.0, shift=10)}\n'
            "rpy_deg = [0, 0, 90]\n",
            f"xyz_mm = {mm(0.5, 0.1, 0.0)}\nrpy_deg = [1.0, -1.5, 92.0]\n",
        )
    if kind == "turned":  # a 6-DoF probe's frame read in part: two coordinates, two turns
        return (
            f'kind = "partial"\nreads = ["x", "z", "rx", "rz"]\n'
            f"xyz_mm = {mm(0.5, 0.1, 0.0, shift=10)}\nrpy_deg = [0, 0, 90]\n"
            "tool_rpy_deg = [0, 0, 30]\n",
            f"xyz_mm = {mm(0.5, 0.1, 0.0)}\nrpy_deg = [1.0, -1.5, 92.0]\n"
            "tool_rpy_deg = [1.2, -0.8, 31.0]\n",
        )
    if kind == "dial":  # one dial indicator along the base's x axis (its z turned onto x)
        return (
            f'kind = "partial"\nreads = ["z"]\nxyz_mm = {mm(0.6, 0.0, 0.1, shift=10)}\n'
            "rpy_deg = [0, 90, 0]\n",
            f"xyz_mm = {mm(0.6, 0.0, 0.1)}\nrpy_deg = [1.0, 88.5, 2.0]\n",
        )
    if kind in CAMERAS:  # a 6 x 8 board of 30 mm squares
        board = "rows = 6, cols = 8, square_mm = 30.0"
        if kind == "eye-in-hand":  # on the flange, looking along it; the board on the floor
            return (
                f'kind = "camera"\ncamera = "cam.yaml"\nmount = "eye-in-hand"\n'
                "camera_in_tool = { xyz_mm = [0, 60, 100], rpy_deg = [0, 0, 0] }\n"
                f"board = {{ {board}, xyz_mm = {mm(0.45, 0.0, 0.0, shift=-105)}, "
                "rpy_deg = [0, 0, 0] }\n",
                "camera_in_tool = { xyz_mm = [3, 57, 104], rpy_deg = [1.0, -1.2, 0.8] }\n"
                f"board = {{ xyz_mm = {mm(0.45, 0.0, 0.0, shift=-97)}, "
                "rpy_deg = [1.5, -0.7, 2.0] }\n",
            )
        return (  # eye-to-hand: above the cell looking down; the board on the flange
            f'kind = "camera"\ncamera = "cam.yaml"\nmount = "eye-to-hand"\n'
            f"camera_in_base = {{ xyz_mm = {mm(0.4, 0.0, 0.9)}, rpy_deg = [180, 0, 90] }}\n"
            f"board = {{ {board}, xyz_mm = [-105, -75, 60], rpy_deg = [0, 0, 0] }}\n",
            f"camera_in_base = {{ xyz_mm = {mm(0.4, 0.0, 0.9, shift=8)}, "
            "rpy_deg = [178.8, 1.1, 91.3] }\n"
            "board = { xyz_mm = [-101, -79, 63], rpy_deg = [0.9, -1.4, 1.6] }\n",
        )
    span = mm(0.2, 0.7)
    return (
        f'kind = "distance"\npivot_mm = {mm(0.5, 0.1, 0.3, shift=10)}\nrange_mm = {span}\n',
        f"pivot_mm = {mm(0.5, 0.1, 0.3)}\nrange_mm = {span}\noffset_mm = 50.0\n",
    )


#: The camera labs: its mount.
CAMERAS = ("eye-in-hand", "eye-to-hand")

#: A camera's camera_info (1280 x 800 pixels, 900 px focal length, a little distortion).
CAMERA_INFO = """image_width: 1280
image_height: 800
camera_name: lab
camera_matrix:
  rows: 3
  cols: 3
  data: [900.0, 0.0, 640.0, 0.0, 900.0, 400.0, 0.0, 0.0, 1.0]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0.05, -0.1, 0.0005, -0.0003, 0.0]
"""

#: The tool point in the flange frame: off joint 6's axis (so its zero is seen) for a
#: touch or a distance; at the flange's centre for a seating.  Random seatings of a tool
#: off the flange see three of the arm's effects faintly (singular values about 1e-3 of
#: the largest, unit columns), which the arm's rule holds as barely seen
#: (:data:`armcal.models.spatial.selection.SELECT_RTOL`), so their noiseless fit is not
#: exact: a designed plan, or the flange's centre, sees every effect the rule keeps.
TOOLS = {
    "plane": "[targets]\ntool = { xyz_mm = [30, -20, 150] }\n",
    "point": "[targets]\ntool = { xyz_mm = [0, 0, 0] }\n",
    "distance": "[targets]\ntool = { xyz_mm = [30, -20, 150] }\n",
    "partial": "[targets]\ntool = { xyz_mm = [30, -20, 150] }\n",
    "dial": "[targets]\ntool = { xyz_mm = [30, -20, 150] }\n",
    "turned": "[targets]\ntool = { xyz_mm = [30, -20, 150] }\n",
    "eye-in-hand": "",  # a camera is placed on the flange
    "eye-to-hand": "",
}
TOOL = TOOLS["plane"]


def write_lab(folder: Path, robot: str, kind: str, sigma: str = "0.01") -> tuple[Path, Path]:
    """The robot file and the truth file of a virtual lab (module notes)."""
    source = BUILTIN_SPATIAL_ROBOTS[robot]
    for urdf in source.parent.glob(f"{robot}.urdf"):
        shutil.copy(urdf, folder / urdf.name)
    rough, true = instruments(load_robot(robot).arm.reach_mm, kind)
    text = source.read_text(encoding="utf-8")
    robot_file = folder / f"{robot}-{kind}.toml"
    noise = (
        f"sigma_px = {sigma if sigma != '0.01' else '0.2'}"
        if kind in CAMERAS
        else (f"sigma_mm = {sigma}")
    )
    if kind == "turned":  # a turn's component to a thousandth of a degree
        noise += "\norientation_sigma_deg = 0.001"
    if kind in CAMERAS:
        (folder / "cam.yaml").write_text(CAMERA_INFO, encoding="utf-8")
    robot_file.write_text(
        f"{text}\n{TOOLS[kind]}[measurement]\n{noise}\n[instrument]\n{rough}",
        encoding="utf-8",
    )
    truth = source.with_name(f"{robot}-truth.toml").read_text(encoding="utf-8")
    truth = re.sub(r"^base = .*$", "", truth, flags=re.M)
    truth_file = folder / f"{robot}-{kind}-truth.toml"
    truth_file.write_text(f"{truth}\n[instrument]\n{true}", encoding="utf-8")
    return robot_file, truth_file


def met_plan(folder: Path, robot_file: Path, m: int, seed: int, name: str) -> Path:
    """``m`` random poses moved onto the robot file's instrument, as a plan file."""
    model = load_robot(robot_file).arm
    q = feasible_poses(model, m, rng=np.random.default_rng(seed))
    path = folder / name
    path.write_text(format_plan_csv(q, kinds=model.joint_kinds), encoding="utf-8")
    return path


def refused_table(folder: Path, table: str, measurement: str = "") -> str:
    """The one line ``armcal evaluate`` refuses a cobot-6r robot file with ``[instrument]``
    ``table`` (and ``measurement``, a ``[measurement]`` table) in: exit 2, one line that
    names the file."""
    source = BUILTIN_SPATIAL_ROBOTS["cobot-6r"].read_text(encoding="utf-8")
    text = f"{source}\n{TOOL}{measurement}[instrument]\n{table}"
    (folder / "r.toml").write_text(text, encoding="utf-8")
    line = refused_robot(folder, "r.toml")
    assert line.startswith("armcal: error: r.toml"), line
    return line


def refused_robot(folder: Path, robot: str) -> str:
    """The one line ``armcal evaluate`` of a one-pose plan refuses the robot file ``robot``
    in ``folder`` with: exit 2, one line ``armcal: error: ...``."""
    (folder / "p.csv").write_text("q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n0,0,0,0,0,0\n")
    run = run_cli(folder, "evaluate", "--robot", robot, "--plan", "p.csv")
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("armcal: error:"), run.stderr
    return lines[0]


def refused_measurements(
    folder: Path, robot: str, lines: list[str], where: str, words: str, *, name: str = ""
) -> None:
    """``armcal identify`` of the measurement file of ``lines`` (written to ``bad.csv``) with
    the robot file ``robot`` refuses it in one line, exit 2, that names the file and says
    ``where`` and ``words``."""
    (folder / "bad.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    run = run_cli(folder, "identify", "--robot", robot, "--measurements", "bad.csv")
    assert run.returncode == 2, (name, run.stderr)
    err = run.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("armcal: error: bad.csv"), (name, run.stderr)
    assert where in err[0] and words in err[0], (name, err[0])
