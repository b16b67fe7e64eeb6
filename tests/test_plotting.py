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
from matplotlib.text import Text
from numpy.testing import assert_allclose

from armcal import (
    Annulus,
    Box,
    InputError,
    PlanarArm,
    load_robot,
    orthogonal_plan,
    random_plan,
)
from armcal.plotting import (
    NUMBERED_POSES_MAX,
    plot_plan,
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
