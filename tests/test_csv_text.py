"""The CSV writers format whole columns at once: byte for byte what Python writes per value.

The reference is the rule itself, value by value in Python (``repr(round(deg,
12) + 0.0)`` for angles, ``repr(float)`` for other numbers), and the edge
cases' texts are derived here from that rule, not copied from a run.
"""

import math

import numpy as np
import pytest

from armcal.files import format_measurements_csv, format_plan_csv, format_program_csv
from armcal.files.csv_text import CHUNK_ROWS, csv_text, degree_cells, float_cells, floats


def _python_angle(q_rad: float) -> str:
    return repr(round(math.degrees(q_rad), 12) + 0.0)


def _texts(cells: np.ndarray) -> list[str]:
    return [bytes(c).replace(b"\0", b"").decode() for c in cells.reshape(-1, cells.shape[-1])]


def _reference_plan(q: np.ndarray, payload=None) -> str:
    """The writer as it was: one Python ``round`` and ``repr`` per value."""
    head = [f"q{j}_deg" for j in range(1, q.shape[1] + 1)]
    head += ["payload_kg"] if payload is not None else []
    lines = [",".join(head)]
    for i, row in enumerate(q.tolist()):
        fields = [_python_angle(v) for v in row]
        fields += [repr(float(payload[i]))] if payload is not None else []
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


def _edge_degrees() -> np.ndarray:
    return np.array(
        [
            0.0,
            -0.0,
            90.0,
            -180.0,
            1e-13,  # rounds to 0 at 12 decimals
            -4e-13,  # rounds to -0.0, written 0.0
            5e-13,
            1e-4,  # the smallest value of the integer path
            9.99e-5,  # below it: Python's own formatting (1e-4 > it > 0)
            2.0**-13,  # 0.0001220703125: a tie at 12 decimals, to the even 2
            -(2.0**-13),
            3 * 2.0**-13,  # 0.0003662109375: a tie, ...937 to the even ...938
            4095.999999999999,
            4096.0,  # the first value of Python's path
            123456.789,
            1e20,
            -1e300,
        ]
    )


def test_edge_angles_are_written_as_python_rounds_them():
    degrees = _edge_degrees()
    written = _texts(degree_cells(np.radians(degrees)))
    assert written == [_python_angle(v) for v in np.radians(degrees).tolist()]
    # The rule, worked out by hand where np.radians -> np.degrees is exact.
    assert written[0] == written[1] == written[4] == written[5] == written[6] == "0.0"
    assert written[2] == "90.0"
    assert written[3] == "-180.0"
    assert written[7] == "0.0001"
    assert written[9] == "0.000122070312"  # the tie ...12|5 goes to the even 2
    assert written[10] == "-0.000122070312"
    assert written[11] == "0.000366210938"  # ...937|5 goes to the even 8


def test_non_finite_angles_are_written_as_python_writes_them():
    written = _texts(degree_cells(np.array([np.inf, -np.inf, np.nan])))
    assert written == ["inf", "-inf", "nan"]


@pytest.mark.parametrize("scale", [1e-3, 1.0, 57.0, 1e3])
def test_random_angles_match_python_value_by_value(scale):
    rng = np.random.default_rng(20)
    q = rng.uniform(-np.pi, np.pi, (5000, 3)) * scale
    assert _texts(degree_cells(q)) == [_python_angle(v) for v in q.reshape(-1).tolist()]


def test_ties_at_twelve_decimals_round_to_even_as_python_does():
    rng = np.random.default_rng(21)
    degrees = 2.0**-13 * rng.integers(-(10**7), 10**7, 20000)  # every one a multiple of 2^-13
    q = np.radians(degrees)
    assert _texts(degree_cells(q)) == [_python_angle(v) for v in q.tolist()]


def test_values_across_magnitudes_match_python():
    rng = np.random.default_rng(22)
    q = rng.uniform(-1.0, 1.0, 20000) * 10.0 ** rng.integers(-20, 20, 20000)
    assert _texts(degree_cells(q)) == [_python_angle(v) for v in q.tolist()]


def test_floats_are_their_repr():
    values = np.array([0.0, -0.0, 0.1, 1 / 3, -2.5e-300, 1e22, 123456789.125, 7.0])
    assert _texts(float_cells(values)) == [repr(v) for v in values.tolist()]


@pytest.mark.parametrize("rows", [0, 1, CHUNK_ROWS + 3])
def test_plan_csv_is_the_per_value_writer_byte_for_byte(rows):
    rng = np.random.default_rng(23)
    q = rng.uniform(-np.pi, np.pi, (rows, 4))
    q[::7, 1] = 0.0
    q[::5, 2] = np.radians(90.0)
    payload = rng.choice([0.0, 2.5, 10.0, 1 / 3], rows)
    assert format_plan_csv(q) == _reference_plan(q)
    assert format_plan_csv(q, payload) == _reference_plan(q, payload)


def test_measurements_and_program_csv_hold_labels_targets_and_flags():
    rng = np.random.default_rng(24)
    q = rng.uniform(-np.pi, np.pi, (5, 2))
    xy = rng.normal(0.0, 300.0, (5, 3))
    labels = ["p1", "é,2", "", "P 4", "5"]  # text is written as it is, UTF-8
    targets = ["A", "B", "A", "B", "A"]
    payload = np.array([0, 1, 2, 3, 4])
    expected = ["pose,q1_deg,q2_deg,x_mm,y_mm,z_mm,target,payload_kg"]
    for i in range(5):
        fields = [labels[i], *map(_python_angle, q[i].tolist()), *map(repr, xy[i].tolist())]
        expected.append(",".join([*fields, targets[i], repr(float(payload[i]))]))
    text = format_measurements_csv(q, xy, labels, targets, payload)
    assert text == "\n".join(expected) + "\n"
    corrected = np.array([True, False, True, True, False])
    program = format_program_csv(q, corrected, labels, targets)
    rows = [
        ",".join([labels[i], *map(_python_angle, q[i].tolist()), targets[i], "10"[not c]])
        for i, c in enumerate(corrected)
    ]
    assert program == "pose,q1_deg,q2_deg,target,corrected\n" + "\n".join(rows) + "\n"


def test_a_text_holding_a_nul_is_written_as_it_is():
    text = csv_text(["a", "b"], [["x\0y", "z"], floats(np.array([1.5, 2.0]))])
    assert text == "a,b\nx\0y,1.5\nz,2.0\n"
