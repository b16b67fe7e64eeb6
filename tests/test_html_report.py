"""The HTML report to hand over (issue 36): identify --report and validate --report write
one self-contained page whose verdict, parameters and figures agree with the JSON, and
which a real browser renders.

The browser is Debian's Chromium, headless (``apt-get install chromium``); where it is
not installed the rendering tests skip, saying so, and the page's own checks still run.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
import struct
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import armcal
from armcal.files.writers import format_measurements_csv
from helpers import run_cli

UR5 = Path(__file__).resolve().parent / "data" / "ur5_robot.urdf"
LABELS = ("A", "B", "C")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


class _Page(HTMLParser):
    """The page's text by element id, its images' bytes, and every URL it would load."""

    def __init__(self) -> None:
        super().__init__()
        self.text: dict[str, str] = {}
        self.images: list[bytes] = []
        self.urls: list[str] = []
        self.cells: list[str] = []
        self._open: list[str] = []

    def handle_starttag(self, tag, attrs):
        found = dict(attrs)
        for key in ("src", "href"):
            if key in found and not str(found[key]).startswith("data:"):
                self.urls.append(str(found[key]))
        if tag == "img":
            self.images.append(base64.b64decode(str(found["src"]).split(",", 1)[1]))
        self._open.append(str(found.get("id", "")) if tag != "td" else "td")
        if tag == "td":
            self.cells.append("")

    def handle_endtag(self, tag):
        if self._open:
            self._open.pop()

    def handle_data(self, data):
        for name in self._open:
            if name and name != "td":
                self.text[name] = self.text.get(name, "") + data
        if self._open and self._open[-1] == "td":
            self.cells[-1] += data


def _png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


@pytest.fixture(scope="module")
def cell(tmp_path_factory) -> Path:
    """A UR5 with three reflectors: 30 poses to calibrate, 15 fresh ones to validate."""
    tmp = tmp_path_factory.mktemp("report")
    (tmp / "ur5.toml").write_text(
        f'name = "ur5"\nurdf = "{UR5.as_posix()}"\nbase_link = "base_link"\ntip_link = "tool0"\n'
        "[targets]\nA = { xyz_mm = [60, 0, 40] }\nB = { xyz_mm = [-30, 52, 40] }\n"
        "C = { xyz_mm = [-30, -52, 40] }\n",
        encoding="utf-8",
    )
    arm = armcal.load_robot(tmp / "ur5.toml").arm
    rng = np.random.default_rng(1)
    truth = arm.nominal.copy()
    truth[:3] = [1500.0, 200.0, -300.0]
    errors = np.arange(6, arm.n_params - 9)
    units = np.array(arm.param_units)
    truth[errors] += (
        rng.normal(size=errors.size)
        * np.where(units[errors] == "mm", 0.3, 0.03)
        / (arm.display_scale[errors])
    )
    for name, poses, seed in (("meas.csv", 30, 2), ("fresh.csv", 15, 9)):
        rows = arm.plan_conditions(armcal.random_plan(arm, poses, rng=seed))
        labels = [LABELS[t] for t in rows.target]
        points = armcal.synthesize_measurements(arm, rows.q, truth, 0.02, target=labels, rng=seed)
        pose = [str(i // 3 + 1) for i in range(rows.m)]
        text = format_measurements_csv(rows.q, points, pose, labels, kinds=arm.joint_kinds)
        (tmp / name).write_text(text, encoding="utf-8")
    args = ["--robot", "ur5.toml", "--measurements", "meas.csv", "--sigma", "0.02"]
    result = run_cli(
        tmp, "identify", *args, "--cross-validate", "5", "-o", "cal.json",
        "--report", "calibration.html", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (tmp / "identify.json").write_text(result.stdout, encoding="utf-8")
    result = run_cli(
        tmp, "validate", "--calibration", "cal.json", "--measurements", "fresh.csv",
        "--report", "validation.html", "--json",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (tmp / "validate.json").write_text(result.stdout, encoding="utf-8")
    return tmp


def _read(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def _numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+\.?\d*(?:e[-+]?\d+)?", text)]


def test_the_calibration_page_says_what_the_json_says(cell):
    document = json.loads((cell / "identify.json").read_text())
    page = _read(cell / "calibration.html")
    assert page.urls == []  # nothing fetched: self-contained
    verdict = page.text["verdict-text"]
    cv = document["cross_validation"]
    for value in (cv["rms_per_point_mm"], cv["nominal_rms_per_point_mm"]):
        assert float(f"{value:.3g}") in _numbers(verdict), (value, verdict)
    assert "held-out" in verdict and "5-fold" in verdict
    # The parameter table: every parameter, value to 6 digits, its std or "held".
    cells = page.cells
    assert len(cells) == 4 * len(document["parameters"])
    for k, p in enumerate(document["parameters"]):
        name, value, std, unit = cells[4 * k : 4 * k + 4]
        assert (name, unit) == (p["name"], p["unit"])
        assert float(value) == pytest.approx(p["value"], rel=5e-6, abs=1e-300)
        assert std == "held" if p["fixed"] else float(std) == pytest.approx(p["std"], rel=5e-3)
    (figure,) = page.images
    width, height = _png_size(figure)
    assert width >= 800 and height == 640  # 6.4 in at 100 dpi: the residual figure
    assert "merges into the base rotation" in page.text["identifiable"]


def test_the_validation_page_says_what_the_json_says(cell):
    document = json.loads((cell / "validate.json").read_text())
    page = _read(cell / "validation.html")
    assert page.urls == []
    verdict = page.text["verdict-text"]
    for key in ("rms_after_per_point_mm", "rms_before_per_point_mm", "max_after_mm"):
        assert float(f"{document[key]:.3g}") in _numbers(verdict), (key, verdict)
    assert f"On {document['poses']} held-out rows" in verdict
    assert len(page.images) == 1 and _png_size(page.images[0])[0] > 0


def _chromium(*args: str, profile: Path) -> subprocess.CompletedProcess:
    """Headless Chromium as this machine runs it: no sandbox as root, no network."""
    assert CHROMIUM is not None
    flags = [
        "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        f"--user-data-dir={profile}", "--hide-scrollbars",
    ]  # fmt: skip
    return subprocess.run(
        [CHROMIUM, *flags, *args], capture_output=True, text=True, timeout=120, check=False
    )


@pytest.mark.skipif(CHROMIUM is None, reason="no headless Chromium (apt-get install chromium)")
@pytest.mark.parametrize("name", ["calibration.html", "validation.html"])
def test_a_real_browser_renders_the_page(cell, name, tmp_path):
    """Chromium parses the page into the same verdict and figures, and its screenshot at a
    readable width shows the verdict's green box and the figure (not a blank page)."""
    from matplotlib.image import imread

    url = (cell / name).as_uri()
    dom = _chromium("--dump-dom", url, profile=tmp_path / "dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    rendered = _Page()
    rendered.feed(dom.stdout)
    page = _read(cell / name)
    assert rendered.text["verdict-text"].strip() == page.text["verdict-text"].strip()
    assert rendered.images == page.images
    shot = tmp_path / "shot.png"
    result = _chromium(
        f"--screenshot={shot}", "--window-size=1200,1600", url, profile=tmp_path / "shot"
    )
    assert result.returncode == 0 and shot.exists(), result.stderr[-2000:]
    pixels = imread(shot)[..., :3]
    assert pixels.shape[:2] == (1600, 1200)
    green = np.all(np.abs(pixels - np.array([240, 255, 244]) / 255) < 2 / 255, axis=-1)
    assert green.sum() > 20_000  # the verdict's box, about 990 x 100 px
    assert pixels.std() > 0.05  # text, tables and a figure, not an empty page
