"""A URDF with one origin in millimetres or its rpy in degrees (issue 34's battery).

A whole URDF in millimetres is refused with the advice to divide every xyz by 1000
(``tests/test_guard_files.py``).  One origin in mm among metres got that same advice,
which would break the rest of the file; it now names the origin.  An rpy written in
degrees (``rpy="90 0 0"``) was read as 90 rad, a plausible-looking but wrong turn, and
the arm loaded silently; any orientation has angles within +-pi, so an angle beyond
2 pi is refused.
"""

from __future__ import annotations

import math

from armcal.files.spatial import BUILTIN_SPATIAL_ROBOTS
from armcal.files.urdf import RPY_BOUND_RAD
from helpers import run_cli

#: The built-in industrial 6R's URDF: joint_3's origin is xyz="1.075 0 0" (the upper
#: arm, 1075 mm), joint_4's rpy="-1.5707963267948966 0 0".
URDF = BUILTIN_SPATIAL_ROBOTS["industrial-6r"].with_suffix(".urdf").read_text()


def _error(run) -> str:
    assert run.returncode == 2, (run.stdout, run.stderr)
    assert "Traceback" not in run.stderr
    (line,) = run.stderr.splitlines()
    assert line.startswith("armcal: error: ")
    return line


def test_one_origin_in_millimetres_among_metres_is_named(tmp_path):
    (tmp_path / "arm.urdf").write_text(URDF.replace('xyz="1.075 0 0"', 'xyz="1075 0 0"'))
    line = _error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "30"))
    assert "arm.urdf" in line and "joint 'joint_3' (xyz=\"1075 0 0\")" in line
    # the other offsets: 0.312, hypot(0.225, 1.28) and 0.215 m (the file's xyz)
    rest = 0.312 + math.hypot(0.225, 1.28) + 0.215
    assert f"add up to {rest:.3g} m" in line
    assert "divide that xyz by 1000" in line and "divide its xyz" not in line


def test_rpy_in_degrees_is_refused_with_the_joint_and_line(tmp_path):
    text = URDF.replace('rpy="-1.5707963267948966 0 0"/>\n', 'rpy="-90 0 0"/>\n', 1)
    assert text != URDF
    (tmp_path / "arm.urdf").write_text(text)
    line = _error(run_cli(tmp_path, "design", "--robot", "arm.urdf", "--poses", "30"))
    assert "joint 'joint_4'" in line and 'rpy="-90 0 0"' in line and "degrees" in line
    joint_line = 1 + text[: text.index('<joint name="joint_4"')].count("\n")
    assert f"line {joint_line}, joint 'joint_4'" in line


def test_the_rpy_bound_admits_two_pi_written_to_a_few_digits():
    # 2 pi as a file may write it (6.2832) is an orientation; 6.3 rad (361 deg) is not
    # an angle anyone writes in radians, and 90 (degrees) is far beyond.
    assert 6.2832 < RPY_BOUND_RAD < 6.3 < 90
