"""Figures: plan and validation panels, what they draw and label, atomic output, lazy import."""

import os
import stat
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle, Wedge
from matplotlib.quiver import Quiver, QuiverKey
from matplotlib.text import Text
from numpy.testing import assert_allclose

from armcal import (
    Annulus,
    Box,
    InputError,
    PlanarArm,
    Validation,
    load_robot,
    orthogonal_plan,
    random_plan,
)
from armcal.plotting import (
    NUMBERED_POSES_MAX,
    plot_error_map,
    plot_plan,
    plot_validation,
    save_figure,
)
from helpers import run_cli


def _pose_lines(ax) -> LineCollection:
    (lines,) = [c for c in ax.collections if isinstance(c, LineCollection)]
    return lines


def _region_patches(ax) -> list:
    return [p for p in ax.patches if p.get_label() == "measurement region"]


@pytest.mark.parametrize("plan", ["orthogonal", "random"])
def test_plot_plan_builtin_arm(plan):
    arm = load_robot("paper-4link").arm
    q = orthogonal_plan(arm, 20) if plan == "orthogonal" else random_plan(arm, 7, rng=0)
    fig = plot_plan(arm, q)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 2
    workspace, joint_space = fig.axes
    segments = _pose_lines(workspace).get_segments()
    assert len(segments) == q.shape[0]
    # each polyline runs base -> joints -> tip: n + 1 vertices
    assert all(s.shape == (arm.n_joints + 1, 2) for s in segments)
    assert_allclose([s[0] for s in segments], 0.0, atol=1e-12)
    assert workspace.get_xlabel() == "x in base frame [mm]"
    assert workspace.get_ylabel() == "y in base frame [mm]"
    assert not _region_patches(workspace)
    assert joint_space.get_ylabel() == "joint angle [deg]"
    labels = [t.get_text() for t in joint_space.get_xticklabels()]
    assert labels == ["q1", "q2", "q3", "q4"]
    assert fig.get_suptitle() == f"paper-4link: {q.shape[0]} poses"


def test_plot_plan_geometry_and_degrees():
    arm = PlanarArm([2.0, 1.0])
    q = np.array([[0.0, np.pi / 2], [np.pi / 2, 0.0]])
    fig = plot_plan(arm, q, title="custom")
    workspace, joint_space = fig.axes
    tips = [s[-1] for s in _pose_lines(workspace).get_segments()]
    assert_allclose(tips, [[2.0, 1.0], [0.0, 3.0]], atol=1e-12)  # round-off only
    (points,) = [c for c in joint_space.collections if c.get_gid() == "joint angles"]
    assert_allclose(np.sort(points.get_offsets()[:, 1]), [0.0, 0.0, 90.0, 90.0], atol=1e-12)
    assert fig.get_suptitle() == "custom"


@pytest.mark.parametrize(
    ("region", "patch_type"),
    [
        (Annulus((0.0, 0.0), 100.0, 400.0), Wedge),
        (Annulus((50.0, -20.0), 0.0, 300.0), Wedge),
        (Box(x=(100.0, 400.0), y=(-150.0, 150.0)), Rectangle),
    ],
)
def test_plot_plan_draws_region(region, patch_type):
    arm = PlanarArm([260.0, 180.0], name="x", region=region)
    fig = plot_plan(arm, random_plan(arm, 12, rng=1))
    (patch,) = _region_patches(fig.axes[0])
    assert isinstance(patch, patch_type)


@pytest.mark.parametrize("n", [1, 12])
@pytest.mark.parametrize("m", [1, 500])
def test_plot_plan_sizes_render(n, m):
    arm = PlanarArm(np.linspace(100.0, 20.0, n), name=f"{n}-link")
    fig = plot_plan(arm, random_plan(arm, m, rng=2))
    FigureCanvasAgg(fig).draw()  # drawing must not warn (filterwarnings = error)
    assert len(_pose_lines(fig.axes[0]).get_segments()) == m
    assert len(fig.axes[1].get_xticks()) == n


@pytest.mark.parametrize("shape", [(3, 3), (3,), (0, 2)])
def test_plot_plan_rejects_bad_shape(shape):
    with pytest.raises(ValueError, match=r"shape \(m, 2\)"):
        plot_plan(PlanarArm([2.0, 1.0]), np.zeros(shape))


def _texts(ax, gid: str) -> list:
    return [t for t in ax.texts if t.get_gid() == gid]


def _corners(text, renderer) -> np.ndarray:
    """The four corners ``(4, 2)`` of a text's box as drawn (pixels), turned with the text.

    Its window extent is the upright box round the turned text, far larger than
    the text when the text is turned: measure it upright, then turn it about
    its anchor (rotation_mode "anchor").  The text alone: an annotation's own
    extent holds its leader line.
    """
    angle = text.get_rotation()
    text.set_rotation(0.0)
    box = Text.get_window_extent(text, renderer)
    text.set_rotation(angle)
    anchor = text.axes.transData.transform(text.xyann)
    c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
    corners = np.array([[box.x0, box.y0], [box.x1, box.y0], [box.x1, box.y1], [box.x0, box.y1]])
    return anchor + (corners - anchor) @ np.array([[c, s], [-s, c]])


def _overlapping(texts, renderer) -> list[tuple[str, str]]:
    """Pairs of texts whose turned boxes overlap: no edge of either separates them."""
    boxes = [_corners(t, renderer) for t in texts]

    def apart(a: np.ndarray, b: np.ndarray) -> bool:
        for edge in (*np.diff(a[:3], axis=0), *np.diff(b[:3], axis=0)):
            normal = np.array([-edge[1], edge[0]])
            pa, pb = a @ normal, b @ normal
            if pa.max() <= pb.min() or pb.max() <= pa.min():
                return True
        return False

    return [
        (texts[i].get_text(), texts[j].get_text())
        for i in range(len(texts))
        for j in range(i)
        if not apart(boxes[i], boxes[j])
    ]


def _tip(lengths, q_row) -> np.ndarray:
    """The nominal tip of a planar arm, summed link by link (mm)."""
    angles = np.cumsum(q_row)
    return np.array([np.sum(lengths * np.cos(angles)), np.sum(lengths * np.sin(angles))])


def test_a_repeated_pose_is_drawn_once_and_numbered_with_its_multiplicity():
    """design repeats a smaller plan above 120 poses; each copy was drawn on top of the last."""
    arm = PlanarArm([2.0, 1.0])
    a, b, c = [0.0, 0.5], [1.0, -0.5], [-1.0, 1.5]
    q = np.array([a, b, b, b, c, a])  # pose a again at the end, b three times in a row
    workspace = plot_plan(arm, q).axes[0]
    segments = _pose_lines(workspace).get_segments()
    assert len(segments) == 3
    labels = {t.get_text(): t for t in _texts(workspace, "pose number")}
    assert set(labels) == {"1 ×2", "2 ×3", "5"}  # numbered by the row each first appears in
    for text, row in (("1 ×2", a), ("2 ×3", b), ("5", c)):
        assert_allclose(labels[text].xy, _tip(np.array([2.0, 1.0]), row), atol=1e-12)


@pytest.mark.parametrize("copies", [1, 3])
def test_pose_numbers_keep_clear_of_each_other_and_of_the_base(copies):
    """The demo's numbers overlapped where folded poses put their tips close to the base."""
    arm = load_robot("paper-4link").arm
    q = np.repeat(orthogonal_plan(arm, 20), copies, axis=0)
    fig = plot_plan(arm, q, numbers=True)
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    labels = _texts(fig.axes[0], "pose number")
    suffix = f" ×{copies}" if copies > 1 else ""
    assert [t.get_text() for t in labels] == [f"{copies * i + 1}{suffix}" for i in range(20)]
    reach = arm.link_lengths.sum()
    assert all(np.hypot(*t.xyann) >= reach for t in labels)  # outside the arm's reach
    assert not _overlapping(labels, renderer)


def test_the_most_poses_numbered_keep_clear_even_with_long_labels():
    arm = PlanarArm([300.0, 200.0, 100.0])
    q = np.repeat(random_plan(arm, NUMBERED_POSES_MAX, rng=3), 12, axis=0)
    fig = plot_plan(arm, q)
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    labels = _texts(fig.axes[0], "pose number")
    assert len(labels) == NUMBERED_POSES_MAX and labels[-1].get_text() == f"{q.shape[0] - 11} ×12"
    assert not _overlapping(labels, renderer)


def test_a_plan_of_many_distinct_poses_is_not_numbered_and_says_so():
    arm = PlanarArm([300.0, 200.0])
    m = NUMBERED_POSES_MAX + 1
    workspace = plot_plan(arm, random_plan(arm, m, rng=4)).axes[0]
    assert not _texts(workspace, "pose number")
    assert f"{m} distinct poses, too many to number" in workspace.get_title()


def test_a_large_plan_of_repeated_poses_is_numbered_by_its_distinct_poses():
    arm = PlanarArm([300.0, 200.0])
    q = np.tile(random_plan(arm, 30, rng=5), (1000, 1))  # 30 000 rows, 30 poses
    workspace = plot_plan(arm, q).axes[0]
    assert len(_pose_lines(workspace).get_segments()) == 30
    labels = [t.get_text() for t in _texts(workspace, "pose number")]
    assert labels == [f"{i + 1} ×1000" for i in range(30)]


def test_gravity_is_an_arrow_along_its_direction():
    arm = PlanarArm([300.0, 200.0])
    q = random_plan(arm, 5, rng=6)
    assert not _texts(plot_plan(arm, q).axes[0], "gravity")
    (arrow,) = _texts(plot_plan(arm, q, gravity=np.array([3.0, -4.0])).axes[0], "gravity")
    direction = np.subtract(arrow.xy, arrow.xyann)
    assert_allclose(direction / np.hypot(*direction), [0.6, -0.8], atol=1e-12)


def test_poses_that_carry_a_payload_are_ringed_one_size_per_payload():
    arm = PlanarArm([2.0, 1.0])
    q = np.array([[0.0, 0.5], [1.0, -0.5], [1.0, -0.5], [-1.0, 1.5], [0.0, 0.5]])
    payload = np.array([0.0, 10.0, 0.0, 5.0, 10.0])  # the same joints at 0 and 10 kg: two poses
    workspace = plot_plan(arm, q, payload_kg=payload).axes[0]
    rings = {c.get_label(): c for c in workspace.collections if c.get_gid() == "payload"}
    assert set(rings) == {"payload 5 kg", "payload 10 kg"}
    lengths = np.array([2.0, 1.0])
    assert_allclose(rings["payload 5 kg"].get_offsets(), [_tip(lengths, q[3])], atol=1e-12)
    assert_allclose(
        rings["payload 10 kg"].get_offsets(),
        [_tip(lengths, q[1]), _tip(lengths, q[4])],
        atol=1e-12,
    )
    assert rings["payload 10 kg"].get_sizes()[0] > rings["payload 5 kg"].get_sizes()[0]
    assert len(_pose_lines(workspace).get_segments()) == 5  # rows 1 and 5 differ in payload
    labels = {t.get_text() for t in _texts(workspace, "pose number")}
    assert labels == {"1", "2", "3", "4", "5"}


@pytest.mark.parametrize("bad", [{"payload_kg": np.zeros(3)}, {"gravity": np.zeros(3)}])
def test_plot_plan_rejects_loads_of_the_wrong_shape(bad):
    with pytest.raises(ValueError, match="shape"):
        plot_plan(PlanarArm([2.0, 1.0]), np.zeros((2, 2)), **bad)


VERTICAL_TOML = """name = "vertical"
link_lengths_mm = [600.0, 450.0, 200.0]
joint_limits_deg = [[-170, 170], [-150, 150], [-150, 150]]
[measurement]
sigma_mm = 0.02
[elastostatic]
gravity_xy = [1, -1]
link_masses_kg = [20, 12, 6]
payload_kg = 10
"""


def _captured_figures(monkeypatch) -> list:
    """The figures the program saves, kept instead of written (the program runs in-process)."""
    import armcal.plotting

    figures = []
    monkeypatch.setattr(armcal.plotting, "save_figure", lambda fig, path: figures.append(fig))
    return figures


def test_design_plot_of_a_vertical_arm_shows_gravity_and_the_payloads(tmp_path, monkeypatch):
    (tmp_path / "robot.toml").write_text(VERTICAL_TOML)
    figures = _captured_figures(monkeypatch)
    args = ["--robot", "robot.toml", "--poses", "12", "--payloads", "0,10", "--seed", "1"]
    run = run_cli(tmp_path, "design", *args, "-o", "plan.csv", "--plot", "plan.png")
    assert run.returncode == 0, run.stderr
    (workspace, _) = figures[0].axes
    (arrow,) = _texts(workspace, "gravity")
    direction = np.subtract(arrow.xy, arrow.xyann)
    assert_allclose(
        direction / np.hypot(*direction), np.array([1.0, -1.0]) / np.sqrt(2), atol=1e-9
    )
    header, *rows = (tmp_path / "plan.csv").read_text().splitlines()
    assert header.split(",")[-1] == "payload_kg"
    loaded = len({row for row in rows if float(row.split(",")[-1]) == 10.0})  # distinct poses
    (ring,) = [c for c in workspace.collections if c.get_gid() == "payload"]
    assert ring.get_label() == "payload 10 kg" and len(ring.get_offsets()) == loaded


def _validation(rows: int, rng: np.random.Generator, *, plane: bool = False) -> Validation:
    """Errors of about 1 mm before and 0.01 mm after at points spread over 1000 mm."""
    positions = rng.uniform(-500.0, 500.0, (rows, 2))
    before = rng.normal(0.0, 1.0, (rows, 2))
    after = rng.normal(0.0, 0.01, (rows, 2))
    predicted = rng.uniform(0.01, 0.02, rows)
    out_of_plane = rng.normal(0.0, 0.01, rows) if plane else None
    return Validation(before, after, predicted, predicted / 2, positions, out_of_plane)


def test_validation_draws_each_model_at_one_scale_with_a_key_in_mm():
    """Nominal arrows x10 and calibrated x100 shared one axes: the calibrated were unreadable."""
    result = _validation(30, np.random.default_rng(7))
    fig = plot_validation(PlanarArm([300.0, 200.0]), np.zeros((30, 2)), result)
    spread = np.ptp(result.positions, axis=0).max()
    drawn = [ax for ax in fig.axes if any(isinstance(c, Quiver) for c in ax.collections)]
    assert len(drawn) == 2
    for ax, errors in zip(drawn, (result.before, result.after), strict=True):
        (arrows,) = [c for c in ax.collections if isinstance(c, Quiver)]
        assert_allclose(np.column_stack([arrows.U, arrows.V]), errors)  # the errors, in mm
        magnification = 1.0 / arrows.scale  # scale_units "xy": an error e is drawn e / scale long
        assert f"×{magnification:g}" in ax.get_title(loc="left")
        longest = np.hypot(*errors.T).max() * magnification
        assert 0.04 * spread <= longest <= 0.1 * spread  # a tenth of the spread, 1-2-5 rounded
        (key,) = [a for a in ax.artists if isinstance(a, QuiverKey)]
        assert key.Q is arrows and key.text.get_text() == f"{key.U:g} mm"
        assert key.U <= np.hypot(*errors.T).max() < 2.5 * key.U
    assert drawn[0].get_xlim() == drawn[1].get_xlim()  # the same points, side by side


def test_validation_counts_poses_not_rows_when_a_pose_has_several_targets():
    """With 3 reflectors the per-pose axis ran to 3 times the poses."""
    rows, targets = 12, 3
    result = _validation(rows, np.random.default_rng(8))
    labels = np.repeat(["p7", "p2", "p9", "p4"], targets)  # labels in the file's order
    fig = plot_validation(PlanarArm([300.0, 200.0]), np.zeros((rows, 2)), result, pose=labels)
    ax = fig.axes[-1]
    for line in ax.get_lines():
        if line.get_gid() == "predicted":
            assert_allclose(line.get_xdata(), [1, 2, 3, 4])
            per_pose = result.predicted_mm.reshape(4, targets)
            assert_allclose(line.get_ydata(), np.sqrt(np.mean(per_pose**2, axis=1)))
        else:
            x = np.asarray(line.get_xdata())
            assert_allclose(np.round(x), np.repeat([1, 2, 3, 4], targets))
            assert np.all(np.abs(x - np.round(x)) <= 0.3 + 1e-12)
    assert fig.get_suptitle().endswith("validation on 4 held-out poses (12 points)")
    single = plot_validation(PlanarArm([300.0, 200.0]), np.zeros((rows, 2)), result)
    assert_allclose(single.axes[-1].get_lines()[0].get_xdata(), np.arange(1, rows + 1))


def test_validation_pose_labels_must_cover_every_row():
    result = _validation(4, np.random.default_rng(9))
    with pytest.raises(ValueError, match=r"one label per row, shape \(4,\)"):
        plot_validation(PlanarArm([300.0, 200.0]), np.zeros((4, 2)), result, pose=["1", "2"])


@pytest.mark.parametrize(("plane", "x_label"), [
    (False, "x in instrument frame [mm]"),
    (True, "u in instrument's plane of motion [mm]"),
])  # fmt: skip
def test_validation_axes_name_the_instrument_frame(plane, x_label):
    result = _validation(6, np.random.default_rng(10), plane=plane)
    fig = plot_validation(PlanarArm([300.0, 200.0]), np.zeros((6, 2)), result)
    assert [ax.get_xlabel() for ax in fig.axes[:2]] == [x_label, x_label]
    assert fig.axes[0].get_ylabel() == x_label.replace("x in", "y in").replace("u in", "v in")


def test_error_map_axes_name_the_base_frame():
    positions = np.random.default_rng(11).uniform(-400.0, 400.0, (20, 2))
    errors = np.linspace(0.1, 2.0, 20)
    fig = plot_error_map(
        PlanarArm([300.0, 200.0]), np.zeros((20, 2)), errors, errors / 10, positions
    )
    assert [ax.get_xlabel() for ax in fig.axes[:2]] == ["x in base frame [mm]"] * 2
    assert fig.axes[0].get_ylabel() == "y in base frame [mm]"


def test_validate_plot_groups_a_poses_targets(tmp_path, monkeypatch):
    """armcal validate --plot on an arm with two targets: the per-pose axis counts poses."""
    (tmp_path / "robot.toml").write_text(
        'name = "tool"\nlink_lengths_mm = [260.0, 180.0, 120.0]\n[measurement]\nsigma_mm = 0.02\n'
        "[targets]\nA = { length_mm = 150.0, angle_deg = 20.0 }\nB = { length_mm = 100.0 }\n"
    )
    (tmp_path / "truth.toml").write_text(
        "dl_mm = [0.2, -0.1, 0.3, 0.1]\ndq_deg = [0, 0.2, 0.6, -0.3]\n"
    )
    rows = [f"{15 * k},{40 * k - 150},{75 * k % 360 - 170}" for k in range(9)]
    (tmp_path / "plan.csv").write_text("q1_deg,q2_deg,q3_deg\n" + "\n".join(rows) + "\n")
    (tmp_path / "test.csv").write_text("q1_deg,q2_deg,q3_deg\n" + "\n".join(rows[::2]) + "\n")
    robot = ["--robot", "robot.toml"]
    for plan, out, seed in (("plan.csv", "meas.csv", "1"), ("test.csv", "held.csv", "2")):
        run = run_cli(tmp_path, "synthesize", *robot, "--truth", "truth.toml", "--plan", plan,
                      "--seed", seed, "-o", out)  # fmt: skip
        assert run.returncode == 0, run.stderr
    run = run_cli(tmp_path, "identify", *robot, "--measurements", "meas.csv", "-o", "cal.json")
    assert run.returncode == 0, run.stderr
    figures = _captured_figures(monkeypatch)
    run = run_cli(tmp_path, "validate", "--calibration", "cal.json", "--measurements", "held.csv",
                  "--plot", "v.png")  # fmt: skip
    assert run.returncode == 0, run.stderr
    (predicted,) = [ln for ln in figures[0].axes[-1].get_lines() if ln.get_gid() == "predicted"]
    assert_allclose(predicted.get_xdata(), [1, 2, 3, 4, 5])  # 5 poses, 10 rows (2 targets)


def test_save_figure_writes_png_atomically(tmp_path):
    arm = load_robot("paper-4link").arm
    target = tmp_path / "plan.png"
    save_figure(plot_plan(arm, orthogonal_plan(arm, 20)), target)
    assert target.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    save_figure(plot_plan(arm, random_plan(arm, 7, rng=0)), target)  # replaces
    assert target.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    assert [p.name for p in tmp_path.iterdir()] == ["plan.png"]


@pytest.mark.skipif(os.name != "posix", reason="POSIX file permissions")
def test_save_figure_file_mode_follows_umask(tmp_path):
    # mkstemp makes 0600 files; the figure must get the usual umask-based mode
    umask = os.umask(0o022)
    os.umask(umask)
    target = tmp_path / "plan.png"
    save_figure(plot_plan(PlanarArm([2.0, 1.0]), np.zeros((2, 2))), target)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask


def test_save_figure_removes_temp_file_on_failure(tmp_path, monkeypatch):
    fig = plot_plan(PlanarArm([2.0, 1.0]), np.zeros((2, 2)))

    def fail(*args, **kwargs):
        raise RuntimeError("render failed")

    monkeypatch.setattr(fig, "savefig", fail)
    with pytest.raises(RuntimeError, match="render failed"):
        save_figure(fig, tmp_path / "plan.png")
    assert list(tmp_path.iterdir()) == []


def test_save_figure_missing_folder(tmp_path):
    fig = plot_plan(PlanarArm([2.0, 1.0]), np.zeros((2, 2)))
    with pytest.raises(InputError, match="does not exist; create it first"):
        save_figure(fig, tmp_path / "missing" / "plan.png")
    assert list(tmp_path.iterdir()) == []


def test_import_armcal_does_not_import_matplotlib():
    code = "import sys, armcal; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    ("name", "magic"),
    [
        ("plan.png", b"\x89PNG"),
        ("plan.pdf", b"%PDF"),
        ("plan.svg", b"<?xml"),
        ("plan.eps", b"%!PS"),
    ],
)
def test_a_figure_is_written_in_the_format_its_suffix_names(tmp_path, name, magic):
    """--plot plan.pdf once wrote PNG bytes under a .pdf name (issue 20)."""
    run = run_cli(tmp_path, "design", "--poses", "6", "--plot", name)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / name).read_bytes().startswith(magic)
    assert f"wrote {name}" in run.stdout


@pytest.mark.parametrize("name", ["plan.jpg", "plan", "plan.PNG.txt"])
def test_a_figure_suffix_armcal_cannot_write_is_refused_before_any_work(tmp_path, name):
    run = run_cli(tmp_path, "design", "--poses", "6", "--plot", name)
    assert run.returncode == 2
    assert run.stderr.startswith(f"armcal: error: --plot {name}:")
    assert ".png, .pdf, .svg, .eps" in run.stderr
    assert list(tmp_path.iterdir()) == []


def test_validation_draws_the_errors_before_and_after_as_distributions_on_one_scale():
    """The ECDF panel: for each model, the sorted held-out errors against i/n (the share of
    points within each), on one logarithmic error axis."""
    result = _validation(25, np.random.default_rng(11))
    fig = plot_validation(PlanarArm([300.0, 200.0]), np.zeros((25, 2)), result)
    (ax,) = [a for a in fig.axes if any(str(ln.get_gid()).startswith("ecdf") for ln in a.lines)]
    assert ax.get_xscale() == "log"
    lines = {ln.get_gid(): ln for ln in ax.lines}
    for gid, errors in (
        ("ecdf nominal arm", result.before_mm),
        ("ecdf calibrated", result.after_mm),
    ):
        assert_allclose(lines[gid].get_xdata(), np.sort(errors))
        assert_allclose(lines[gid].get_ydata(), np.arange(1, 26) / 25)
