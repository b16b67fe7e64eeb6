"""One rule, one place: a joint map is read by one parser and judged by one check.

A planar robot TOML, a spatial one, :class:`PlanarArm` and :class:`SpatialArm`
refuse a singular or nearly singular ``joint_map`` with the same words, by one
scale-free threshold (:data:`armcal.numerics.RANK_RTOL` on ``s_n / s_1``), and
all four accept the coupled map of an industrial arm whose J3 is read against the
horizon (FANUC's J2/J3 coupling).  Before, the four had three rules (``s_n / s_1
<= 1e-9``, ``|det| < 1e-9`` and ``|det| < 1e-12``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from armcal import load_robot
from armcal.errors import InputError
from armcal.models import PlanarArm, SerialChain, SpatialArm, checked_joint_map
from armcal.numerics import RANK_RTOL
from helpers import run_cli

#: FANUC's J2/J3 coupling on three joints: the controller reads J3 against the horizon,
#: so the third joint value is u3 = q2 + q3 (tests/helpers_spatial.industrial, docs/six-axis.md).
COUPLED = [[1, 0, 0], [0, 1, 0], [0, 1, 1]]

#: Rows 2 and 3 equal: rank 2 exactly.
SINGULAR = [[1, 0, 0], [0, 1, 1], [0, 1, 1]]

#: Rows 2 and 3 differ by d = 1e-12 in one entry.  The block [[1, 1], [1, 1 + d]] has
#: singular values 2 + d/2 and d/2 (to first order in d: their product is det = d, their
#: sum the trace 2 + d), so s_n / s_1 = d / 4 = 2.5e-13: 400 times below RANK_RTOL.
#: |det| = 1e-12 is at the old spatial class's line (|det| < 1e-12), which took it.
NEARLY_SINGULAR = [[1, 0, 0], [0, 1, 1], [0, 1, 1 + 1e-12]]

#: Three joints of a shoulder-elbow arm as a modified DH table (the first three rows of the
#: built-in industrial-6r's, tests/helpers_spatial.industrial), with a tool 100 mm out.
MDH_TABLE = """
[mdh]
alpha_deg = [0, -90, 0]
a_mm = [0, 150, 600]
theta_deg = [0, -90, 0]
d_mm = [450, 0, 0]
tip_xyz_mm = [0, 0, 100]
"""


def _matrix_text(mapping) -> str:
    """A joint map as TOML, every number with Python's repr (round-trips exactly)."""
    return (
        "["
        + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in mapping)
        + "]"
    )


def _planar_file(tmp_path: Path, mapping) -> Path:
    path = tmp_path / "planar.toml"
    path.write_text(
        f"link_lengths_mm = [300.0, 250.0, 120.0]\njoint_map = {_matrix_text(mapping)}\n",
        encoding="utf-8",
    )
    return path


def _spatial_file(tmp_path: Path, mapping) -> Path:
    path = tmp_path / "spatial.toml"
    path.write_text(f"joint_map = {_matrix_text(mapping)}\n{MDH_TABLE}", encoding="utf-8")
    return path


def _chain() -> SerialChain:
    """The joints of :data:`MDH_TABLE`, built in Python (the tool left at the flange)."""
    return SerialChain.from_mdh(
        np.radians([0, -90, 0]), [0, 150, 600], np.radians([0, -90, 0]), [450, 0, 0]
    )


def _refusals(tmp_path: Path, mapping) -> dict[str, str]:
    """How each of the four ways in refuses ``mapping``: the error's text after the file."""
    texts = {}
    for name, path in [
        ("planar TOML", _planar_file(tmp_path, mapping)),
        ("spatial TOML", _spatial_file(tmp_path, mapping)),
    ]:
        with pytest.raises(InputError) as error:
            load_robot(path)
        prefix = f"{path}: "
        assert str(error.value).startswith(prefix), str(error.value)
        texts[name] = str(error.value).removeprefix(prefix)
    with pytest.raises(ValueError) as error:
        PlanarArm([300.0, 250.0, 120.0], joint_map=mapping)
    texts["PlanarArm"] = str(error.value)
    with pytest.raises(ValueError) as error:
        SpatialArm(_chain(), "arm", np.array(mapping, dtype=float))
    texts["SpatialArm"] = str(error.value)
    return texts


@pytest.mark.parametrize(
    ("mapping", "low", "high"),
    [(SINGULAR, 0.0, 1e-15), (NEARLY_SINGULAR, 2.5e-13 * 0.999, 2.5e-13 * 1.001)],
    ids=["singular", "nearly-singular"],
)
def test_a_singular_or_nearly_singular_map_is_refused_the_same_way_four_ways(
    tmp_path, mapping, low, high
):
    """The ratio the refusal names: an exactly singular map's smallest singular value is
    the SVD's round-off, 0 or a few eps of the largest (0 on some machines, 1.7e-17 on
    others: at most 1e-15 here); the nearly singular one's is d / 4 (its notes), to the
    three digits the message prints."""
    texts = _refusals(tmp_path, mapping)
    assert len(set(texts.values())) == 1, texts
    text = texts["PlanarArm"]
    assert text.startswith("joint_map must be invertible"), text
    found = re.search(r"its smallest singular value is (\S+) times its largest", text)
    assert found is not None, text
    assert low <= float(found.group(1)) <= high, text
    assert f"at most {RANK_RTOL:g}" in text, text


def test_the_refusal_is_the_same_through_the_command_line(tmp_path):
    """``armcal design`` on either family's file: exit 2, one line naming the file."""
    for path in (_planar_file(tmp_path, SINGULAR), _spatial_file(tmp_path, SINGULAR)):
        run = run_cli(tmp_path, "design", "--robot", path.name, "--poses", "10")
        assert run.returncode == 2
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"armcal: error: {path.name}: "), run.stderr
        assert "joint_map must be invertible" in lines[0]


def test_fanucs_coupled_map_is_accepted_four_ways(tmp_path):
    expected = np.array(COUPLED, dtype=float)
    planar = load_robot(_planar_file(tmp_path, COUPLED)).arm
    spatial = load_robot(_spatial_file(tmp_path, COUPLED)).arm
    assert planar.family == "planar" and spatial.family == "spatial"
    assert np.array_equal(planar.joint_map, expected)
    assert np.array_equal(spatial.joint_map, expected)
    assert np.array_equal(PlanarArm([300.0, 250.0, 120.0], joint_map=COUPLED).joint_map, expected)
    assert np.array_equal(SpatialArm(_chain(), "arm", expected).joint_map, expected)


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_the_rule_is_scale_free(tmp_path, scale):
    """Scaling a map scales its singular values alike: the verdict does not move.  The old
    determinant rules refused ``1e-4`` times FANUC's map (``det = 1e-12``) in a spatial
    file and from Python while taking the planar one."""
    coupled = scale * np.array(COUPLED, dtype=float)
    assert np.array_equal(load_robot(_planar_file(tmp_path, coupled)).arm.joint_map, coupled)
    assert np.array_equal(load_robot(_spatial_file(tmp_path, coupled)).arm.joint_map, coupled)
    assert np.array_equal(SpatialArm(_chain(), "arm", coupled).joint_map, coupled)
    texts = _refusals(tmp_path, scale * np.array(NEARLY_SINGULAR))
    assert len(set(texts.values())) == 1, texts


@pytest.mark.parametrize(
    ("smallest", "accepted"),
    [(2 * RANK_RTOL, True), (RANK_RTOL / 2, False)],
    ids=["above", "below"],
)
def test_the_line_is_rank_rtol_on_the_relative_smallest_singular_value(smallest, accepted):
    """``diag(1, 1, r)`` has singular values 1, 1 and ``r``: ``s_n / s_1 = r`` exactly."""
    mapping = np.diag([1.0, 1.0, smallest])
    builds = [
        lambda: checked_joint_map(mapping, 3),
        lambda: PlanarArm([300.0, 250.0, 120.0], joint_map=mapping),
        lambda: SpatialArm(_chain(), "arm", mapping),
    ]
    for build in builds:
        if accepted:
            build()
        else:
            with pytest.raises(ValueError, match="joint_map must be invertible"):
                build()


def test_a_map_that_is_not_finite_is_refused_by_both_classes():
    """The old spatial rule (|det| < 1e-12) let NaN through: NaN < 1e-12 is false."""
    mapping = np.array(COUPLED, dtype=float)
    mapping[2, 2] = np.nan
    with pytest.raises(ValueError, match="joint_map must be finite"):
        PlanarArm([300.0, 250.0, 120.0], joint_map=mapping)
    with pytest.raises(ValueError, match="joint_map must be finite"):
        SpatialArm(_chain(), "arm", mapping)


def test_both_robot_files_read_the_map_with_the_same_words(tmp_path):
    """One parser: a map of the wrong shape gets the same sentence in either family's file."""
    short = "[[1, 0, 0], [0, 1, 0]]"
    texts = []
    for path in (tmp_path / "planar.toml", tmp_path / "spatial.toml"):
        body = (
            "link_lengths_mm = [300.0, 250.0, 120.0]\n"
            if path.stem == "planar"
            else MDH_TABLE.lstrip()
        )
        path.write_text(f"joint_map = {short}\n{body}", encoding="utf-8")
        with pytest.raises(InputError) as error:
            load_robot(path)
        texts.append(str(error.value).removeprefix(f"{path}: "))
    assert texts[0] == texts[1]
    assert texts[0] == (
        "key 'joint_map': expected 3 rows of 3 numbers (the arm has 3 joints), "
        "got [[1, 0, 0], [0, 1, 0]]"
    )
