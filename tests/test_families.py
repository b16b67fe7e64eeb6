"""The edge is family-blind: one registry, and no family check outside it.

* No module outside ``models/`` and ``families/`` asks which family an arm is
  (``isinstance(arm, SpatialArm)``) or types a value as one of several families
  (``PlanarArm | SpatialArm``): the edge dispatches through
  :mod:`armcal.families` as the middle dispatches through the model.
* Every role the built-in families name resolves to a callable, so a renamed
  function cannot leave a registry entry that fails only when a user reaches it.
* One ``load_robot`` takes every robot description: a planar TOML, a URDF, a
  robot TOML over a URDF, a modified DH table and the built-ins by name.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import armcal
from armcal import ArmcalError, InputError
from armcal.families import (
    PLANAR,
    ROLES,
    SPATIAL,
    Family,
    builtin_robots,
    family_for,
    family_named,
    family_of,
    load_robot,
)

PACKAGE = Path(armcal.__file__).resolve().parent
ROBOTS = PACKAGE / "robots"


def _family_classes() -> set[str]:
    """Every class a family defines (``models/planar/``, ``models/spatial/``)."""
    names = set()
    for folder in ("planar", "spatial"):
        for path in (PACKAGE / "models" / folder).glob("*.py"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            names |= {node.name for node in tree.body if isinstance(node, ast.ClassDef)}
    return names


def _named(node: ast.AST) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _union_members(node: ast.AST) -> list[str]:
    """The names of a ``A | B | C`` union, or of ``Union[A, B]``."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):
        return _union_members(node.left) + _union_members(node.right)
    if isinstance(node, ast.Subscript) and _named(node.value) == "Union":
        items = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        return [m for item in items for m in _union_members(item)]
    name = _named(node)
    return [] if name is None else [name]


def _family_checks(source: str, classes: set[str]) -> list[str]:
    """The family ``isinstance`` checks and family unions of a module's source."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if (
            isinstance(node, ast.Call)
            and _named(node.func) == "isinstance"
            and len(node.args) == 2
        ):
            kinds = node.args[1]
            members = kinds.elts if isinstance(kinds, ast.Tuple) else [kinds]
            named = {m for item in members for m in _union_members(item)} & classes
            if named:
                found.append(f"line {node.lineno}: isinstance(..., {', '.join(sorted(named))})")
        elif isinstance(node, (ast.BinOp, ast.Subscript)):
            members = [m for m in _union_members(node) if m in classes]
            where = f"line {node.lineno}: union"
            if len(members) >= 2 and not any(f.startswith(where) for f in found):
                found.append(f"{where} {' | '.join(members)}")
    return found


def test_no_family_check_outside_models_and_the_registry():
    classes = _family_classes()
    assert {"PlanarArm", "SpatialArm", "CompliantArm", "CompliantSpatialArm"} <= classes
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE).as_posix()
        if relative.startswith(("models/", "families/")):
            continue
        for found in _family_checks(path.read_text(encoding="utf-8"), classes):
            offenders.append(f"{relative} {found}")
    assert not offenders, offenders


def test_the_family_check_finder_finds_checks_and_unions():
    classes = {"PlanarArm", "SpatialArm"}
    source = (
        "def f(a: PlanarArm | SpatialArm, b: int | None):\n"
        "    if isinstance(a, SpatialArm):\n"
        "        pass\n"
        "    if isinstance(a, (int, models.PlanarArm)):\n"
        "        pass\n"
        "    return isinstance(b, int)\n"
    )
    found = _family_checks(source, classes)
    assert sorted(found) == [
        "line 1: union PlanarArm | SpatialArm",
        "line 2: isinstance(..., SpatialArm)",
        "line 4: isinstance(..., PlanarArm)",
    ]


@pytest.mark.parametrize("family", [PLANAR, SPATIAL], ids=lambda f: f.name)
def test_every_role_of_a_built_in_family_resolves(family: Family):
    for role in ROLES:
        if family.has(role):
            assert callable(family.role(role)), role
    assert family.has("load_robot") and family.has("encode") and family.has("decode")


def test_a_missing_role_is_a_sentence_not_a_traceback():
    bare = Family("toy-bare", "a toy", "nothing")
    with pytest.raises(ArmcalError, match="the toy-bare family of arm has no demo"):
        bare.role("demo")
    with pytest.raises(ValueError, match="unknown roles"):
        Family("toy", "a toy", "nothing", refs={"dance": print})


def test_families_are_found_by_name_by_older_name_and_by_model():
    assert family_named("planar") is PLANAR
    assert family_named("serial") is SPATIAL  # the word of calibration files before 35
    with pytest.raises(ArmcalError, match="the families are planar, spatial"):
        family_named("delta")
    assert family_of(armcal.PlanarArm([100.0, 50.0])) is PLANAR
    with pytest.raises(ArmcalError, match="no 'family' name"):
        family_of(object())


def test_every_family_lists_its_built_ins():
    builtins = builtin_robots()
    assert {name for name, f in builtins.items() if f is PLANAR} == set(
        armcal.files.BUILTIN_ROBOTS
    )
    assert {name for name, f in builtins.items() if f is SPATIAL} == set(
        armcal.files.BUILTIN_SPATIAL_ROBOTS
    )


MDH_ROBOT = """\
name = "two-axis"
[mdh]
alpha_deg = [0.0, 90.0]
a_mm = [0.0, 300.0]
theta_deg = [0.0, 0.0]
d_mm = [400.0, 0.0]
[tool]
xyz_mm = [250.0, 0.0, 0.0]
"""


def test_one_load_robot_takes_every_description(tmp_path):
    """Each description reaches its family's loader through the one ``load_robot``."""
    planar = tmp_path / "planar.toml"
    planar.write_text('link_lengths_mm = [300.0, 200.0]\nname = "two"\n', encoding="utf-8")
    over = tmp_path / "over.toml"
    over.write_text(f'urdf = "{(ROBOTS / "industrial-6r.urdf").as_posix()}"\n', encoding="utf-8")
    cases = {
        "paper-4link": ("planar", 4),
        str(planar): ("planar", 2),
        "industrial-6r": ("spatial", 6),
        "arm-7r": ("spatial", 7),
        str(ROBOTS / "industrial-6r.urdf"): ("spatial", 6),
        str(over): ("spatial", 6),
    }
    for description, (family, joints) in cases.items():
        robot = armcal.load_robot(description)
        assert (robot.arm.family, robot.arm.n_joints) == (family, joints), description
        assert family_for(description).name == family
    assert armcal.load_robot is load_robot is armcal.files.load_robot


def test_an_unknown_robot_lists_the_built_ins_of_every_family():
    with pytest.raises(InputError) as caught:
        load_robot("industrial-6")
    text = str(caught.value)
    assert "planar: paper-2link" in text and "spatial: industrial-6r" in text
    assert "did you mean 'industrial-6r'" in text


def test_links_are_refused_for_a_planar_robot():
    with pytest.raises(ArmcalError, match="this is a planar robot, not one from a URDF"):
        load_robot("paper-2link", tip_link="tool0")


def test_the_registry_reads_calibration_files_of_both_words(tmp_path):
    """A spatial calibration file written before the family had one word (``serial``)
    reads back as today's (``spatial``)."""
    robot = load_robot("industrial-6r")
    arm = robot.arm.replace(targets=("A",), target_positions=np.zeros((0, 3)))
    doc = SPATIAL.role("encode")(arm)
    assert doc["kind"] == "spatial"
    assert family_named("serial").role("decode") is SPATIAL.role("decode")


def test_one_export_entry_writes_either_family(tmp_path):
    """``armcal.export`` writes a planar and a spatial calibration through its family's
    exporters; each URDF reads back as a robot of the same family (an independent check of
    the files is in tests/test_export.py and tests/test_spatial_export.py)."""
    planar = load_robot("paper-2link").arm
    q = armcal.random_plan(planar, 12, rng=1)
    truth = np.array([0.5, -0.3, 0.01, -0.02])  # mm, mm, rad, rad: a calibration's size
    cal = armcal.identify(
        planar, q, armcal.synthesize_measurements(planar, q, truth, sigma=0.01, rng=2)
    )
    spatial = load_robot("industrial-6r").arm
    qs = armcal.random_plan(spatial, 30, rng=3)
    nominal = np.zeros(spatial.n_params)
    points = armcal.synthesize_measurements(spatial, qs, nominal, sigma=0.0, rng=4)
    cal6 = armcal.identify(spatial, qs, points)
    for calibration, family in ((cal, "planar"), (cal6, "spatial")):
        calibrated = calibration.calibrated()
        text = armcal.export(calibrated, "urdf")
        path = tmp_path / f"{family}.urdf"
        path.write_text(text, encoding="utf-8")
        assert "<robot" in text and load_robot(path).arm.family == "spatial"
        robot = tmp_path / f"{family}.toml"
        robot.write_text(armcal.export(calibrated, "robot"), encoding="utf-8")
        assert load_robot(robot).arm.family == family
        assert armcal.export(calibrated, "offsets").startswith("joint,")
    with pytest.raises(ArmcalError, match="the kinds are robot, urdf, origins, offsets"):
        armcal.export(cal.calibrated(), "step")


@pytest.mark.slow  # about 20 s: a six-axis design and two certificates
def test_certify_takes_a_spatial_arm_as_loaded():
    """``armcal.certify`` on the arm as loaded (51 parameters, 18 of them no plan
    separates) certifies the plan as ``design`` sees it: the same bound as on the
    prepared model, within (0, 1]."""
    arm = load_robot("industrial-6r").arm.replace(targets=("A", "B", "C"))
    plan = armcal.design(arm, 12, rng=0, with_certificate=False)
    loaded = armcal.certify(arm, plan.q, rng=1, candidates=200, rounds=1, search=200)
    prepared = armcal.certify(plan.model, plan.q, rng=1, candidates=200, rounds=1, search=200)
    assert 0 < loaded.certified_d_efficiency <= 1
    assert loaded.certified_d_efficiency == prepared.certified_d_efficiency


@pytest.mark.parametrize("name", ["paper-2link", "industrial-6r"])
def test_one_demo_entry_tells_either_family_story(name):
    """``armcal.run_demo`` runs the family's story through the registry, as ``armcal demo``
    does: a calibration file among its files, a report that names the robot, and its
    progress reported after each of its six stages (a bar on a terminal)."""
    seen: list[tuple[int, int]] = []
    story = armcal.run_demo(
        load_robot(name),
        poses=12 if name == "industrial-6r" else 8,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert name in story.text
    assert "calibration.json" in story.files
    assert seen == [(k, 6) for k in range(1, 7)]
