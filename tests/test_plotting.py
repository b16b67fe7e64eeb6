"""Plan figures: structure of the two panels, regions, atomic PNG output, lazy import."""

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
from numpy.testing import assert_allclose

from armcal import Annulus, Box, InputError, PlanarArm, load_robot, orthogonal_plan, random_plan
from armcal.plotting import plot_plan, save_figure
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
    assert workspace.get_xlabel() == "x [mm]"
    assert workspace.get_ylabel() == "y [mm]"
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
