"""A hand-edited calibration file is refused in one line that names the key (issue 34).

Each edit a user makes by hand to a calibration file written by ``armcal identify
-o`` (a planar one and a spatial one) gives exit 2 and one line ``armcal: error:``
naming the file, the key, what it must hold, and the fix (write the calibration
again), never numpy's or Python's own text.  An unedited file passes; a covariance
no fit gives (a negative variance, a std that is not the root of its variance,
correlations that contradict each other) is refused rather than used.

The robot options' messages: an unknown robot lists the built-ins of both families.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from armcal.doe import random_plan
from armcal.errors import InputError
from armcal.files import BUILTIN_ROBOTS, BUILTIN_SPATIAL_ROBOTS, load_spatial_robot
from armcal.files.checked import BadKey, check_covariance
from helpers import run_cli

PLANAR = """name = "edited-3link"
link_lengths_mm = [300.0, 250.0, 150.0]
[measurement]
sigma_mm = 0.02
"""

PLANAR_TRUTH = "dl_mm = [0.4, -0.3, 0.2]\ndq_deg = [0.2, -0.1, 0.3]\n"

FAMILIES = ("planar", "spatial")

#: Text of numpy and Python that a message must never carry.
INTERNALS = ("reshape", "broadcast", "could not convert", "float()", "ndarray", "Traceback")


def _plan(path: Path, q_deg: np.ndarray) -> None:
    head = ",".join(f"q{j + 1}_deg" for j in range(q_deg.shape[1]))
    rows = [",".join(f"{v:.6f}" for v in pose) for pose in q_deg]
    path.write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")


@pytest.fixture(scope="module")
def calibrations(tmp_path_factory) -> dict[str, Path]:
    """A folder per family holding ``cal.json`` (identify -o on 30 synthesized poses) and
    the measurements ``meas.csv`` it was fitted on."""
    rng = np.random.default_rng(34)
    out = {}
    for family in FAMILIES:
        folder = tmp_path_factory.mktemp(family)
        if family == "planar":
            (folder / "robot.toml").write_text(PLANAR)
            (folder / "truth.toml").write_text(PLANAR_TRUTH)
            _plan(folder / "plan.csv", rng.uniform(-150, 150, (30, 3)))
            robot, truth = "robot.toml", ("--truth", "truth.toml")
        else:
            arm = load_spatial_robot("industrial-6r").arm
            _plan(folder / "plan.csv", np.degrees(random_plan(arm, 30, rng=rng)))
            robot, truth = "industrial-6r", ()
        run = run_cli(folder, "synthesize", "--robot", robot, "--plan", "plan.csv", *truth,
                      "--sigma", "0.02", "--seed", "1", "-o", "meas.csv")  # fmt: skip
        assert run.returncode == 0, run.stderr
        run = run_cli(folder, "identify", "--robot", robot, "--measurements", "meas.csv",
                      "-o", "cal.json")  # fmt: skip
        assert run.returncode == 0, run.stderr
        out[family] = folder
    return out


def _validate(folder: Path, doc: dict | list | str) -> str:
    """The one error line of ``validate`` on ``doc`` written as ``edited.json``."""
    text = doc if isinstance(doc, str) else json.dumps(doc)
    (folder / "edited.json").write_text(text, encoding="utf-8")
    run = run_cli(folder, "validate", "--calibration", "edited.json", "--measurements", "meas.csv")
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2, run.stderr
    assert len(lines) == 1 and lines[0].startswith("armcal: error: edited.json: "), run.stderr
    assert not any(word in lines[0] for word in INTERNALS), lines[0]
    return lines[0]


def _doc(folder: Path) -> dict:
    return json.loads((folder / "cal.json").read_text(encoding="utf-8"))


def _variance_index(doc: dict) -> int:
    """The first parameter with a variance > 0 (a parameter held has none)."""
    return next(i for i, e in enumerate(doc["parameters"]) if e["std"] > 0)


@pytest.mark.parametrize("family", FAMILIES)
def test_the_unedited_file_is_read(calibrations, family):
    folder = calibrations[family]
    run = run_cli(folder, "validate", "--calibration", "cal.json", "--measurements", "meas.csv")
    assert run.returncode == 0, run.stderr


# Each edit: (what it does to the document, words the error line must carry).
def _value_text(doc):
    doc["parameters"][0]["value"] = str(doc["parameters"][0]["value"])  # "0.6": a number quoted
    return ("key 'parameters'", f"the value of {doc['parameters'][0]['name']}", "got the text")


def _value_nan(doc):
    doc["parameters"][0]["value"] = float("nan")  # json.dumps writes NaN, as a hand edit can
    return ("key 'parameters'", f"the value of {doc['parameters'][0]['name']}", "finite")


def _negative_std(doc):
    i = _variance_index(doc)
    doc["parameters"][i]["std"] = -doc["parameters"][i]["std"]
    return ("key 'parameters'", doc["parameters"][i]["name"], "negative")


def _std_not_root(doc):
    i = _variance_index(doc)
    doc["parameters"][i]["std"] *= 2  # the variance keeps the old std's square
    return ("key 'parameters'", doc["parameters"][i]["name"], "not the root of its variance")


def _negative_variance(doc):
    i = _variance_index(doc)
    doc["covariance"]["matrix"][i][i] = -1.0
    return ("key 'covariance'", f"the variance of {doc['parameters'][i]['name']}", "negative")


def _rows_cut(doc):
    doc["covariance"]["matrix"] = doc["covariance"]["matrix"][:3]
    p = len(doc["parameters"])
    return ("key 'covariance.matrix'", f"shape {p} x {p}", f"got shape 3 x {p}")


def _covariance_text(doc):
    doc["covariance"]["matrix"][0][1] = "0"
    return ("key 'covariance.matrix'", "text or null among the numbers")


def _not_psd(doc):
    # Three parameters correlated +0.9 (1, 2), -0.9 (1, 3) and +0.9 (2, 3): each within +-1,
    # yet the correlation matrix R has R (1, -1, 1) = (1 - 0.9 - 0.9) (1, -1, 1), an
    # eigenvalue -0.8 (closed form), as no covariance can.  Variances and stds unchanged.
    seen = [i for i, e in enumerate(doc["parameters"]) if e["std"] > 0][:3]
    std = [doc["parameters"][i]["std"] for i in seen]
    rho = {(0, 1): 0.9, (0, 2): -0.9, (1, 2): 0.9}
    matrix = doc["covariance"]["matrix"]
    for (a, b), r in rho.items():
        matrix[seen[a]][seen[b]] = matrix[seen[b]][seen[a]] = r * std[a] * std[b]
    return ("key 'covariance'", "not positive semi-definite")


def _asymmetric(doc):
    i, j = [k for k, e in enumerate(doc["parameters"]) if e["std"] > 0][:2]
    matrix = doc["covariance"]["matrix"]
    matrix[i][j] = matrix[i][j] + 0.5 * doc["parameters"][i]["std"] * doc["parameters"][j]["std"]
    return ("key 'covariance'", "not symmetric")


def _no_parameters(doc):
    del doc["parameters"]
    return ("key 'parameters': missing",)


def _few_parameters(doc):
    doc["parameters"] = doc["parameters"][:-1]
    return ("key 'parameters'", "do not match the robot's")


def _no_sigma(doc):
    doc["sigma_mm"] = None
    return ("key 'sigma_mm'", "the noise std (mm)", "got null")


EDITS = [
    _value_text,
    _value_nan,
    _negative_std,
    _std_not_root,
    _negative_variance,
    _rows_cut,
    _covariance_text,
    _not_psd,
    _asymmetric,
    _no_parameters,
    _few_parameters,
    _no_sigma,
]


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("edit", EDITS, ids=lambda f: f.__name__.strip("_"))
def test_an_edited_key_is_named_with_what_it_must_hold(calibrations, family, edit):
    folder = calibrations[family]
    doc = _doc(folder)
    words = edit(doc)
    line = _validate(folder, doc)
    assert all(word in line for word in words), line
    assert "write the calibration again with armcal identify -o" in line, line


@pytest.mark.parametrize(
    ("key", "edit", "words"),
    [
        ("origins", lambda r: r["origins"].pop(), "key 'robot.origins': expected 6 joint"),
        ("tip", lambda r: r.__setitem__("tip", [[1, 0, 0]]), "key 'robot.tip'"),
        ("joint_types", lambda r: r.__setitem__("joint_types", ["R"] * 5 + ["X"]), "'R' or 'P'"),
        ("base_pose", lambda r: r.__setitem__("base_pose", [0.0] * 5), "got shape 5"),
        ("joint_map", lambda r: r["joint_map"][0].append(0.0), "key 'robot.joint_map'"),
        ("joint_names", lambda r: r["joint_names"].pop(), "a list of 6"),
        ("limits", lambda r: r.__setitem__("joint_limits", None), "got null"),
    ],
)
def test_an_edited_spatial_robot_section_names_the_sub_key(calibrations, key, edit, words):
    folder = calibrations["spatial"]
    doc = _doc(folder)
    edit(doc["robot"])
    line = _validate(folder, doc)
    assert words in line, line


def test_an_edited_planar_robot_section_names_the_link_count(calibrations):
    """A link removed from link_lengths_mm: the limits no longer agree, and the line says
    with which key they must agree."""
    folder = calibrations["planar"]
    doc = _doc(folder)
    doc["robot"]["link_lengths_mm"].pop()
    line = _validate(folder, doc)
    assert "key 'robot." in line and "the 2 links in robot.link_lengths_mm" in line, line
    doc = _doc(folder)
    doc["robot"]["link_lengths_mm"] = "300, 250, 150"
    line = _validate(folder, doc)
    assert "key 'robot.link_lengths_mm'" in line and "got the text" in line, line


@pytest.mark.parametrize("family", FAMILIES)
def test_a_file_cut_short_or_of_another_shape_says_so(calibrations, family):
    folder = calibrations[family]
    text = (folder / "cal.json").read_text(encoding="utf-8")
    line = _validate(folder, text[: len(text) // 2])
    assert "invalid JSON" in line and "cut short" in line, line
    line = _validate(folder, [])
    assert "a list where an object with a 'format' key was expected" in line, line


def test_a_covariance_from_a_fit_passes_the_check():
    """A covariance sigma^2 (J^T J)^-1 of a random, badly conditioned J (condition ~1e6):
    positive definite by construction, so the round-off allowance must let it through."""
    rng = np.random.default_rng(3)
    jac = rng.standard_normal((40, 8)) * np.logspace(0, 6, 8)
    cov = 0.02**2 * np.linalg.inv(jac.T @ jac)
    names = [f"p{k}" for k in range(8)]
    check_covariance(cov, names, list(np.sqrt(np.diag(cov))))
    # Round-off past the allowance is refused: the same matrix made asymmetric by 1e-6 of
    # the product of two stds (COVARIANCE_RTOL is 1e-9).
    cov[0, 1] += 1e-6 * np.sqrt(cov[0, 0] * cov[1, 1])
    with pytest.raises(BadKey, match="not symmetric"):
        check_covariance(cov, names, [None] * 8)


# --------------------------------------------------------------------------- unknown robot


@pytest.mark.parametrize(
    ("name", "meant"),
    [("industrial-6x", "industrial-6r"), ("cobot6r", "cobot-6r"), ("paper-4lnk", "paper-4link")],
)
def test_an_unknown_robot_lists_every_built_in_and_the_closest(tmp_path, name, meant):
    """The list names the built-ins of both families (the spatial ones were left out) and
    a typo of one gets did-you-mean."""
    run = run_cli(tmp_path, "identify", "--robot", name, "--measurements", "meas.csv")
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith(f"armcal: error: {name}: robot is neither a built-in"), lines[0]
    every = [*BUILTIN_ROBOTS, *BUILTIN_SPATIAL_ROBOTS]
    assert all(builtin in lines[0] for builtin in every), lines[0]
    assert f"did you mean '{meant}'?" in lines[0], lines[0]


def test_an_unknown_robot_far_from_every_name_gets_no_guess(tmp_path):
    with pytest.raises(InputError, match="neither a built-in") as caught:
        load_spatial_robot(tmp_path / "nowhere.toml")
    assert "did you mean" not in str(caught.value)
    assert "industrial-6r" in str(caught.value)


def test_identify_without_a_robot_lists_every_built_in(tmp_path):
    run = run_cli(tmp_path, "identify", "--measurements", "meas.csv")
    assert run.returncode == 2, run.stderr
    assert all(name in run.stderr for name in [*BUILTIN_ROBOTS, *BUILTIN_SPATIAL_ROBOTS])


# --------------------------------------------------------------------------- repeated --fix


def test_repeated_fix_options_add_up(calibrations):
    """``--fix dl1 --fix dq2`` holds both, as ``--fix dl1,dq2`` does (argparse kept only
    the last); a name given twice is held once."""
    folder = calibrations["planar"]
    base = ("identify", "--robot", "robot.toml", "--measurements", "meas.csv", "--json")
    documents = {}
    for argv in (("--fix", "dl1", "--fix", "dq2"), ("--fix", "dl1,dq2"), ("--fix", "dq2")):
        run = run_cli(folder, *base, *argv)
        assert run.returncode == 0, run.stderr
        documents[argv] = json.loads(run.stdout)
    repeated, joined, last = documents.values()
    assert set(repeated["fixed"]) == set(joined["fixed"]) == {"dl1", "dq2"}
    assert set(last["fixed"]) == {"dq2"}  # the difference the repeats make
    held = {e["name"]: e["fixed"] for e in repeated["parameters"]}
    assert held["dl1"] and held["dq2"] and not held["dl2"]
    assert repeated["parameters"] == joined["parameters"]
    run = run_cli(folder, *base, "--fix", "dl1", "--fix", "dl1,dq2")
    assert json.loads(run.stdout)["fixed"] == joined["fixed"]


# --------------------------------------------------------------------------- [dh] table keys

#: Universal Robots' UR5 in standard DH (their published table: alpha in deg, a, d in mm).
UR5_DH = {
    "alpha_deg": [90, 0, 0, 90, -90, 0],
    "a_mm": [0, -425, -392.25, 0, 0, 0],
    "theta_deg": [0, 0, 0, 0, 0, 0],
    "d_mm": [89.159, 0, 0, 109.15, 94.65, 82.3],
}


def _dh_toml(table: str, changes: dict) -> str:
    values = {**UR5_DH, **changes}
    return f'name = "ur5"\n[{table}]\n' + "".join(f"{k} = {v}\n" for k, v in values.items())


@pytest.mark.parametrize("table", ["dh", "mdh"])
def test_a_dh_table_s_messages_name_the_section_written(tmp_path, table):
    """Radians in alpha_deg (an error) and a table in metres (the lengths-in-metres
    warning) name ``dh.*`` for a [dh] table, ``mdh.*`` for an [mdh] one."""
    other = "mdh" if table == "dh" else "dh"
    radians = {"alpha_deg": [round(math.radians(a), 6) for a in UR5_DH["alpha_deg"]]}
    (tmp_path / "rad.toml").write_text(_dh_toml(table, radians))
    with pytest.raises(InputError) as caught:
        load_spatial_robot(tmp_path / "rad.toml")
    assert f"key '{table}.alpha_deg': " in str(caught.value)
    assert not re.search(rf"\b{other}\.", str(caught.value))  # "mdh." holds no \bdh.
    # Lengths in metres: a reach of about 1.19 m read as 1.19 mm.
    metres = {k: [v / 1000 for v in UR5_DH[k]] for k in ("a_mm", "d_mm")}
    (tmp_path / "m.toml").write_text(_dh_toml(table, metres))
    if table == "mdh":  # the UR5's table read as modified DH is no regular arm; skip it
        return
    spec = load_spatial_robot(tmp_path / "m.toml")
    (warned,) = [w for w in spec.warnings if w.code == "lengths-in-metres"]
    assert f"{table}.a_mm and {table}.d_mm are in mm" in warned.message
    assert not re.search(rf"\b{other}\.", warned.message)


# --------------------------------------------------------------------------- decimal commas


def _identify(folder: Path, measurements: str):
    return run_cli(folder, "identify", "--robot", "robot.toml", "--measurements", measurements)


def test_decimal_commas_in_a_comma_separated_file_are_named(calibrations):
    """The measurements written with decimal commas: each row has twice the header's
    fields, all whole numbers; the line says so and gives both fixes, and the second
    fix (';' between columns) reads."""
    folder = calibrations["planar"]
    head, *rows = (folder / "meas.csv").read_text(encoding="utf-8").splitlines()
    width = len(head.split(","))
    assert all("." in field for field in rows[0].split(","))  # every value has a decimal part
    commas = [row.replace(".", ",") for row in rows]
    (folder / "commas.csv").write_text("\n".join([head, *commas]) + "\n", encoding="utf-8")
    run = _identify(folder, "commas.csv")
    assert run.returncode == 2, run.stderr
    assert f"row 1 (line 2) has {2 * width} fields but the header has {width}" in run.stderr
    assert "seems to use decimal commas" in run.stderr
    assert "write a point as the decimal separator" in run.stderr and "';'" in run.stderr
    semicolons = [row.replace(",", ";").replace(".", ",") for row in rows]
    text = "\n".join([head.replace(",", ";"), *semicolons]) + "\n"
    (folder / "semicolons.csv").write_text(text, encoding="utf-8")
    assert _identify(folder, "semicolons.csv").returncode == 0


def test_a_thousands_separator_and_a_missing_field_are_told_apart(calibrations):
    folder = calibrations["planar"]
    head, first, *rows = (folder / "meas.csv").read_text(encoding="utf-8").splitlines()
    fields = first.split(",")
    thousands = ",".join([*fields[:-1], "1,234.5"])  # y = 1234.5 mm, written "1,234.5"
    short = ",".join(fields[:-1])
    for row, words in (
        (thousands, "1,234.5 looks like one number with a thousands separator"),
        (short, "give every column a value"),
    ):
        (folder / "odd.csv").write_text("\n".join([head, row, *rows]) + "\n", encoding="utf-8")
        run = _identify(folder, "odd.csv")
        assert run.returncode == 2 and words in run.stderr, run.stderr
        assert "decimal commas" not in run.stderr


# --------------------------------------------------------------------------- wrong-kind files


def _kinds(folder: Path) -> None:
    """A plan (the measurements' joint columns), a truth file and a URDF beside cal.json."""
    head, *rows = (folder / "meas.csv").read_text(encoding="utf-8").splitlines()
    joints = [k for k, name in enumerate(head.split(",")) if name.startswith("q")]
    plan = [",".join(row.split(",")[k] for k in joints) for row in [head, *rows]]
    (folder / "plan-only.csv").write_text("\n".join(plan) + "\n", encoding="utf-8")
    (folder / "arm.urdf").write_text('<?xml version="1.0"?>\n<robot name="a"></robot>\n')


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (("identify", "--robot", "robot.toml", "--measurements", "plan-only.csv"),
         ("plan-only.csv: line 1: missing column 'x_mm'", "looks like a plan file", "--plan")),
        (("synthesize", "--robot", "robot.toml", "--plan", "meas.csv", "-o", "s.csv"),
         ("unknown column 'x_mm'", "looks like a measurements file", "--measurements takes")),
        (("identify", "--robot", "cal.json", "--measurements", "meas.csv"),
         ("cal.json: not a robot TOML file", "looks like a calibration file", "--calibration")),
        (("synthesize", "--robot", "robot.toml", "--truth", "arm.urdf", "--plan", "plan.csv",
          "-o", "s.csv"), ("arm.urdf: not a truth TOML file", "looks like a URDF", "--robot")),
        (("synthesize", "--robot", "robot.toml", "--truth", "robot.toml", "--plan", "plan.csv",
          "-o", "s.csv"), ("robot.toml: not a truth file", "looks like a robot file", "--robot")),
        (("synthesize", "--robot", "truth.toml", "--plan", "plan.csv", "-o", "s.csv"),
         ("truth.toml: not a robot file", "looks like a truth file", "--truth takes it")),
        (("validate", "--calibration", "robot.toml", "--measurements", "meas.csv"),
         ("robot.toml: not a calibration file", "looks like a robot file", "--robot takes it")),
        (("identify", "--robot", "robot.toml", "--measurements", "cal.json"),
         ("cal.json: not a measurements CSV file", "looks like a calibration file")),
        (("compensate", "--calibration", "cal.json", "--program", "meas.csv", "-o", "c.csv"),
         ("unknown column 'x_mm'", "looks like a measurements file")),
    ],
)  # fmt: skip
def test_a_file_given_to_the_wrong_option_is_named(calibrations, argv, words):
    folder = calibrations["planar"]
    _kinds(folder)
    run = run_cli(folder, *argv)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert all(word in lines[0] for word in words), lines[0]
    assert not (folder / "s.csv").exists() and not (folder / "c.csv").exists()


def test_a_program_is_no_wrong_kind_for_a_plan_nor_a_typo_for_another_kind(calibrations):
    """A plan given as --program (the same columns) reads; a measurements file with a
    misspelt x column keeps its unit hint, not a guess of another kind."""
    folder = calibrations["planar"]
    _kinds(folder)
    run = run_cli(folder, "compensate", "--calibration", "cal.json", "--program",
                  "plan-only.csv", "-o", "compensated.csv")  # fmt: skip
    assert run.returncode == 0, run.stderr
    text = (folder / "meas.csv").read_text(encoding="utf-8").replace("x_mm", "x_m", 1)
    (folder / "xm.csv").write_text(text, encoding="utf-8")
    run = _identify(folder, "xm.csv")
    assert run.returncode == 2 and "give millimetres" in run.stderr, run.stderr
    assert "looks like" not in run.stderr


# --------------------------------------------------------------------------- truth keys

PLANAR_TRUTH_KEYS = ("dl_mm", "dq_deg", "base_mm", "k_urad_per_Nm", "c_mdeg_per_m")
SPATIAL_TRUTH_KEYS = ("robot", "base", "errors", "targets", "instrument", "compliance")


@pytest.mark.parametrize(
    ("family", "truth", "words"),
    [
        ("spatial", "dq_deg = [0.1, 0, 0, 0, 0, 0]\n",
         ("unknown key 'dq_deg'", "planar arm's truth file", "[errors] with dq1 = ...")),
        ("spatial", "base_mm = [1.0, 2.0]\n",
         ("unknown key 'base_mm'", "base = { xyz_mm = [x, y, z]",)),
        ("spatial", "dq1 = 0.1\n", ("unknown key 'dq1'", "belongs in the [errors] table")),
        ("spatial", "errros = 1\n", ("unknown key 'errros'", "did you mean 'errors'?")),
        ("planar", "[errors]\ndq1 = 0.1\n",
         ("unknown key 'errors'", "spatial arm's truth file", "dq_deg = [...] in deg")),
        ("planar", "dl_mm = [0, 0, 0]\ndq_rad = [0, 0, 0]\n",
         ("unknown key 'dq_rad'", "did you mean 'dq_deg'?")),
    ],
)  # fmt: skip
def test_an_unknown_truth_key_lists_the_family_s_keys(calibrations, family, truth, words):
    """Each family's truth file names its own keys; a key of the other family's says how
    this family writes it."""
    folder = calibrations[family]
    robot = "robot.toml" if family == "planar" else "industrial-6r"
    (folder / "odd-truth.toml").write_text(truth, encoding="utf-8")
    run = run_cli(folder, "synthesize", "--robot", robot, "--truth", "odd-truth.toml",
                  "--plan", "plan.csv", "-o", "odd-synth.csv")  # fmt: skip
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert all(word in lines[0] for word in words), lines[0]
    own = PLANAR_TRUTH_KEYS if family == "planar" else SPATIAL_TRUTH_KEYS
    assert lines[0].endswith(f"allowed keys are {', '.join(own)}"), lines[0]


# --------------------------------------------------------------------------- warnings kept


#: The planar arm with its limits written in radians (170 deg = 2.967 rad, each joint).
RADIAN_LIMITS = """name = "rad-3link"
link_lengths_mm = [300.0, 250.0, 150.0]
joint_limits_deg = [[-2.967, 2.967], [-2.967, 2.967], [-2.967, 2.967]]
[measurement]
sigma_mm = 0.02
"""


def test_robot_file_warnings_print_before_the_error_that_stops_the_command(calibrations):
    """Limits written in radians warn (limits-radians); the measurements in degrees then
    fall outside them, an error.  The warning, which explains the error, prints first,
    once; a command that succeeds prints it once, with its report."""
    folder = calibrations["planar"]
    (folder / "rad.toml").write_text(RADIAN_LIMITS, encoding="utf-8")
    run = run_cli(folder, "identify", "--robot", "rad.toml", "--measurements", "meas.csv")
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 2, run.stderr
    assert lines[0].startswith("armcal: warning: rad.toml: key 'joint_limits_deg'"), lines[0]
    assert "looks like radians" in lines[0]
    assert lines[1].startswith("armcal: error: meas.csv: ") and "outside" in lines[1], lines[1]
    # Readings within the limits as written (deg): the command succeeds, the warning once.
    rng = np.random.default_rng(8)
    _plan(folder / "small.csv", rng.uniform(-2.9, 2.9, (12, 3)))
    run = run_cli(folder, "evaluate", "--robot", "rad.toml", "--plan", "small.csv")
    assert run.returncode == 0, run.stderr
    assert run.stderr.count("looks like radians") == 1, run.stderr
