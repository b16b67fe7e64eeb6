"""Helpers shared by the tests: random arms and deviations, the program run in-process
or in a subprocess, the vertical 3-link arm's cell, and the robot file of the virtual
six-axis cell with compliance.

Helpers of one concern have their own modules: ``helpers_spatial`` (spatial arms built
through armcal), ``helpers_slide`` (a slide arm written out independently of armcal),
``helpers_paper`` (the default robot's valid input files).  A test file imports only
helpers, never another test file (``test_tests_layout.py``)."""

import contextlib
import io
import math
import os
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armcal import PlanarArm
from armcal.cli import main


def random_arm(
    n: int, rng: np.random.Generator, *, base_offset: bool = False, limits_deg: float = 180.0
) -> PlanarArm:
    """An n-link arm with link lengths in [50, 300] mm and symmetric joint limits."""
    lengths = rng.uniform(50.0, 300.0, n)
    limits = np.radians(np.tile([-limits_deg, limits_deg], (n, 1)))
    return PlanarArm(lengths, limits, base_offset=base_offset, name=f"random-{n}link")


def random_truth(arm: PlanarArm, rng: np.random.Generator) -> np.ndarray:
    """Deviations of a few mm and about a degree, as PRODUCT.md describes real arms."""
    n = arm.n_joints
    dl = rng.uniform(-3.0, 3.0, n)
    dq = rng.uniform(-1.0, 1.0, n)
    base = rng.uniform(-20.0, 20.0, 2) if arm.base_offset else None
    return arm.params_from_display(dl, dq, base)


@dataclass(frozen=True)
class Run:
    """What a run of the program gave: its exit status and its two streams."""

    returncode: int
    stdout: str
    stderr: str


def central_differences(f, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """``d f / d x`` ``(..., len(x))`` by central differences of step ``h`` on every
    coordinate of ``x``: error ``h^2 |f'''| / 6`` plus round-off ``eps |f| / h``."""
    x = np.asarray(x, dtype=float)
    columns = []
    for i in range(x.size):
        step = np.zeros(x.size)
        step[i] = h
        columns.append((f(x + step) - f(x - step)) / (2 * h))
    return np.stack(columns, axis=-1)


def _text_stream(data: bytes = b"") -> io.TextIOWrapper:
    """A text stream over bytes, with ``.buffer`` like the real ones (not a terminal)."""
    return io.TextIOWrapper(io.BytesIO(data), encoding="utf-8", newline="")


def run_cli(cwd: Path, *args: str, stdin: str = "") -> Run:
    """Run ``armcal *args`` in-process (:func:`armcal.cli.main`) in the folder ``cwd``.

    The program's streams are captured (stdin reads ``stdin``), as a subprocess
    would see them, at a fiftieth of a subprocess's cost.  What only a real
    process shows (a signal, the interpreter's own exit) is tested with
    :func:`run_program`.
    """
    out, err, inp = _text_stream(), _text_stream(), _text_stream(stdin.encode("utf-8"))
    here = os.getcwd()
    os.chdir(cwd)
    try:
        with (
            contextlib.redirect_stdout(out),
            contextlib.redirect_stderr(err),
            _redirect_stdin(inp),
        ):
            code = main(list(args))
    finally:
        os.chdir(here)
    return Run(code, _read(out), _read(err))


@contextlib.contextmanager
def _redirect_stdin(stream: io.TextIOWrapper):
    saved = sys.stdin
    sys.stdin = stream
    try:
        yield
    finally:
        sys.stdin = saved


def _read(stream: io.TextIOWrapper) -> str:
    if stream.closed:  # the program closes stderr after a broken pipe
        return ""
    stream.flush()
    return stream.buffer.getvalue().decode("utf-8")  # type: ignore[attr-defined]


def run_program(
    cwd: Path, *args: str, stdin: str | None = None, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    """Run ``python -m armcal *args`` as a real process in ``cwd``, capturing its streams."""
    return subprocess.run(
        [sys.executable, "-m", "armcal", *args],
        cwd=cwd,
        input=stdin,
        capture_output=True,
        text=True,
        encoding="utf-8",
        timeout=timeout,
        check=False,
    )


def deviated_tip(
    q_deg: Sequence[float], links: Sequence[float], dl: Sequence[float], dq: Sequence[float]
) -> tuple[float, float]:
    """Paper eq. (1), written out link by link independently of armcal: the tip (mm)."""
    x = y = angle = 0.0
    for length, d_length, q, d_q in zip(links, dl, q_deg, dq, strict=True):
        angle += math.radians(q + d_q)
        x += (length + d_length) * math.cos(angle)
        y += (length + d_length) * math.sin(angle)
    return x, y


#: A planar vertical 3-link arm with its link masses known and a 10 kg payload, sigma
#: 0.02 mm: the compliance tests' arm (gravity along -y, in the arm's plane).
VERTICAL_3LINK = """name = "vertical-3link"
link_lengths_mm = [600.0, 450.0, 200.0]
joint_limits_deg = [[-170, 170], [-150, 150], [-150, 150]]
[measurement]
sigma_mm = 0.02
[elastostatic]
gravity_xy = [0, -1]
link_masses_kg = [20, 12, 6]
payload_kg = 10
"""


#: The true vertical 3-link arm of the compliance tests: link and joint errors and
#: every joint's compliance.
VERTICAL_3LINK_TRUTH = """dl_mm = [1.0, -0.5, 0.8]
dq_deg = [0.3, -0.2, 0.4]
k_urad_per_Nm = [1.5, 3.0, 6.0]
"""


def planar_cell(folder: Path, identify_table: str = "") -> None:
    """The vertical 3-link arm's cell in ``folder``: ``robot.toml`` (:data:`VERTICAL_3LINK`
    with ``identify_table``), ``truth.toml`` and 40 poses measured by ``synthesize``
    (``plan.csv``, ``meas.csv``), every other one under the 10 kg payload."""
    (folder / "robot.toml").write_text(VERTICAL_3LINK + identify_table)
    (folder / "truth.toml").write_text(VERTICAL_3LINK_TRUTH)
    rng = np.random.default_rng(4)
    rows = ["q1_deg,q2_deg,q3_deg,payload_kg"] + [
        f"{a:.6f},{b:.6f},{c:.6f},{10 if i % 2 else 0}"
        for i, (a, b, c) in enumerate(rng.uniform(-140, 140, (40, 3)))
    ]
    (folder / "plan.csv").write_text("\n".join(rows) + "\n")
    made = run_cli(
        folder, "synthesize", "--robot", "robot.toml", "--plan", "plan.csv",
        "--truth", "truth.toml", "-o", "meas.csv", "--seed", "3",
    )  # fmt: skip
    assert made.returncode == 0, made.stderr


#: The head of a robot TOML for the built-in industrial 6R's URDF (``{urdf}``) under
#: another ``{name}``: its coupled J2/J3 and its limits, as the built-in file has them.
INDUSTRIAL_HEAD = """name = "{name}"
urdf = "{urdf}"
base_link = "base_link"
tip_link = "flange"
joint_map = [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 1, 1, 0, 0, 0],
             [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
joint_limits_deg = [[-185, 185], [-60, 76], [-132, 150], [-360, 360], [-125, 125], [-360, 360]]
"""


def write_cycles(path: Path, poses: np.ndarray, cycles: int) -> None:
    """A plan of ``poses`` ``(k, n)`` (rad) each visited ``cycles`` times, one pose after
    the other in every cycle, with a 'pose' column (``P1``..): the rows of an ISO 9283
    test, which synthesize keeps labelled."""
    head = "pose," + ",".join(f"q{j + 1}_deg" for j in range(poses.shape[1]))
    text = [",".join(repr(float(v)) for v in np.degrees(pose)) for pose in poses]
    rows = [f"P{p + 1},{line}" for _ in range(cycles) for p, line in enumerate(text)]
    path.write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")


#: The virtual heavy six-axis cell of the compliance tests: its links' masses (kg), its
#: payload (kg) and its three reflectors in the flange frame (mm).
CELL_MASSES = [350.0, 150.0, 200.0, 60.0, 20.0, 5.0]
CELL_PAYLOAD = 165.0
CELL_TARGETS = {"A": [100.0, 0.0, 150.0], "B": [-50.0, 86.6, 150.0], "C": [-50.0, -86.6, 150.0]}


def cell_toml(
    urdf: str = "industrial-6r.urdf",
    *,
    lumped: bool = False,
    targets: bool = True,
    extra: str = "",
) -> str:
    """The robot TOML of the virtual cell: the built-in industrial-6r's URDF at ``urdf``
    with its J2/J3 joint map and limits, sigma 0.02 mm, the reflectors of
    :data:`CELL_TARGETS` (``targets``), and ``[elastostatic]`` with the masses of
    :data:`CELL_MASSES` (or ``lumped``); ``extra`` ends the file (more of
    ``[elastostatic]``, or tables after it)."""
    reflectors = "\n".join(f"{k} = {{ xyz_mm = {v} }}" for k, v in CELL_TARGETS.items())
    masses = "lumped = true" if lumped else f"link_masses_kg = {CELL_MASSES}"
    head = INDUSTRIAL_HEAD.format(name="cell-6r", urdf=urdf)
    return f"""{head}[measurement]
sigma_mm = 0.02
{"[targets]" if targets else ""}
{reflectors if targets else ""}
[elastostatic]
{masses}
payload_kg = {CELL_PAYLOAD}
payload_com_mm = [0, 0, 100]
{extra}
"""
