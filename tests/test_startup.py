"""Start-up: ``import armcal`` and the program's help import only what they use.

Each check runs in a fresh interpreter (``sys.executable``), where ``sys.modules``
holds exactly what that start-up imported; this process has imported most of
armcal already.  The checks are on modules imported, never on time (machines are
noisy): ``benchmarks/bench_startup.py`` measures the CPU time.

Before issue 37, ``import armcal`` imported 118 of armcal's modules (numpy with
them), and ``armcal --version`` 127.
"""

from __future__ import annotations

import ast
import importlib
import json
import subprocess
import sys
from pathlib import Path
from typing import get_args

import pytest

import armcal
from armcal import choices
from armcal.cli.parser import COMMAND_TABLE
from helpers import run_cli

PACKAGE = Path(armcal.__file__).resolve().parent

#: Every package of armcal whose ``__init__`` gives names of its modules.
PACKAGES = (
    "armcal",
    "armcal.cli",
    "armcal.doe",
    "armcal.families",
    "armcal.files",
    "armcal.identification",
    "armcal.models",
    "armcal.report",
    "armcal.reproduction",
    "armcal.workflow",
)

#: Run in a fresh interpreter: import a module (``--import NAME``) or run the program once
#: per argv of a JSON list, then write the exit statuses and ``sys.modules`` to a file.
_PROBE = """
import json, sys
out, what = sys.argv[1], sys.argv[2:]
statuses = []
if what[0] == "--import":
    __import__(what[1])
else:
    from armcal.cli import main
    for argv in json.loads(what[0]):
        try:
            statuses.append(main(argv))
        except SystemExit as exc:  # --help and --version leave through argparse
            statuses.append(exc.code)
with open(out, "w", encoding="utf-8") as f:
    json.dump({"statuses": statuses, "modules": sorted(sys.modules)}, f)
"""


def _fresh(tmp_path: Path, *what: str) -> tuple[list, set[str]]:
    """The exit statuses and the modules imported by ``what`` in a fresh interpreter."""
    out = tmp_path / "modules.json"
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, str(out), *what],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    found = json.loads(out.read_text(encoding="utf-8"))
    return found["statuses"], set(found["modules"])


def _armcal_modules(modules: set[str]) -> set[str]:
    return {m for m in modules if m == "armcal" or m.startswith("armcal.")}


def _heavy(modules: set[str], prefixes: tuple[str, ...]) -> list[str]:
    """The modules of ``modules`` that are, or are inside, one of ``prefixes``."""
    return sorted(m for m in modules if any(m == p or m.startswith(p + ".") for p in prefixes))


#: What neither ``import armcal`` nor the program's help may import: the slow third-party
#: libraries, and armcal's numerics, files, reports and pictures (each a prefix).
HEAVY = (
    "scipy",
    "matplotlib",
    "armcal.models",
    "armcal.identification",
    "armcal.criteria",
    "armcal.doe.designer",
    "armcal.doe.certificate",
    "armcal.simulate",
    "armcal.validation",
    "armcal.workflow",
    "armcal.report",
    "armcal.reproduction",
    "armcal.demo",
    "armcal.demo_spatial",
    "armcal.files.robots",
    "armcal.files.spatial",
    "armcal.files.tables",
    "armcal.files.calibration",
    "armcal.plotting",
)


# --------------------------------------------------------------------------- import armcal


def test_import_armcal_imports_neither_numpy_nor_its_modules(tmp_path):
    _, modules = _fresh(tmp_path, "--import", "armcal")
    assert not _heavy(modules, ("numpy", *HEAVY))
    # The package's own file, its version and the helper that finds its names on first
    # use (armcal.lazy): 3 modules; 5 leaves room for a foundation module without numpy
    # (errors, choices). Eager, the package imported 118.
    assert len(_armcal_modules(modules)) <= 5, sorted(_armcal_modules(modules))


def test_a_name_imports_its_own_module_and_no_other_family(tmp_path):
    """``from armcal import PlanarArm`` imports the planar arm, not the spatial one."""
    _, modules = _fresh(tmp_path, "--import", "armcal.models.planar.arm")
    assert not _heavy(modules, ("scipy", "matplotlib", "armcal.models.spatial"))


# --------------------------------------------------------------------------- the program's help


def test_version_imports_only_the_parser(tmp_path):
    """Not even numpy: the program's help then costs less than ``import numpy``."""
    statuses, modules = _fresh(tmp_path, json.dumps([["--version"]]))
    assert statuses == [0]
    assert not _heavy(modules, ("numpy", *HEAVY))
    # The parser, help and options (armcal.cli: 7 modules), the values they list
    # (choices), what checks paths before any work (files.common, files.paths,
    # files.kinds, formats), errors, progress, the family registry that loads a robot,
    # the packages' files and armcal.lazy: 20 now (127 before), 30 with room.
    assert len(_armcal_modules(modules)) <= 30, sorted(_armcal_modules(modules))


def test_every_help_imports_only_the_parser(tmp_path):
    argvs = [["--help"]] + [[command.name, "--help"] for command in COMMAND_TABLE]
    statuses, modules = _fresh(tmp_path, json.dumps(argvs))
    assert statuses == [0] * len(argvs)
    assert not _heavy(modules, ("numpy", *HEAVY))
    assert len(_armcal_modules(modules)) <= 30, sorted(_armcal_modules(modules))


def test_a_bad_robot_file_is_refused_before_the_command_imports_its_work(tmp_path):
    argv = ["identify", "--robot", "missing.toml", "--measurements", "missing.csv"]
    statuses, modules = _fresh(tmp_path, json.dumps([argv]))
    assert statuses == [2]
    assert not _heavy(
        modules, ("scipy", "matplotlib", "armcal.workflow", "armcal.identification.calibrate")
    )


# --------------------------------------------------------------------------- a command


ROBOT = "link_lengths_mm = [300.0, 200.0]\n"  # a 2-link planar arm, no limits


def test_design_imports_no_picture_and_no_identification_without_plot(tmp_path):
    (tmp_path / "robot.toml").write_text(ROBOT, encoding="utf-8")
    argv = ["design", "--robot", "robot.toml", "--poses", "4", "-o", "plan.csv"]
    statuses, modules = _fresh(tmp_path, json.dumps([argv]))
    assert statuses == [0]
    assert (tmp_path / "plan.csv").is_file()
    assert not _heavy(
        modules,
        (
            "matplotlib",
            "armcal.plotting",
            "armcal.identification.calibrate",
            "armcal.report.calibration",
            "armcal.simulate",
            "armcal.validation",
            "armcal.reproduction",
            "armcal.demo",
        ),
    )


def test_design_imports_matplotlib_when_a_plot_is_asked_for(tmp_path):
    """The check above can fail: the same run with ``--plot`` imports matplotlib."""
    (tmp_path / "robot.toml").write_text(ROBOT, encoding="utf-8")
    argv = ["design", "--robot", "robot.toml", "--poses", "4", "--plot", "plan.png"]
    statuses, modules = _fresh(tmp_path, json.dumps([argv]))
    assert statuses == [0]
    assert "matplotlib" in modules and "armcal.plotting" in modules


# --------------------------------------------------------------------------- the public names

#: For each package: every name of ``__all__`` resolves, ``dir`` lists it, and a name
#: that is no attribute raises AttributeError; a submodule is an attribute as an eager
#: package made it (``armcal.models``).
_NAMES = """
import importlib, json, sys
missing = []
for package in json.loads(sys.argv[1]):
    module = importlib.import_module(package)
    for name in module.__all__:
        try:
            getattr(module, name)
        except AttributeError as exc:
            missing.append(f"{package}.{name}: {exc}")
        if name not in dir(module):
            missing.append(f"{package}.{name}: not in dir()")
    try:
        getattr(module, "no_such_name")
        missing.append(f"{package}.no_such_name resolved")
    except AttributeError:
        pass
import armcal
missing += [] if armcal.models.PlanarArm is armcal.PlanarArm else ["armcal.models"]
print(json.dumps(missing))
"""


def test_every_public_name_resolves_in_a_fresh_interpreter():
    done = subprocess.run(
        [sys.executable, "-c", _NAMES, json.dumps(PACKAGES)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert json.loads(done.stdout) == []


@pytest.mark.parametrize("name", armcal.__all__)
def test_each_name_of_armcal_resolves_and_is_listed(name):
    assert getattr(armcal, name) is not None
    assert name in dir(armcal)


def _type_checking_imports(package: str) -> dict[str, str]:
    """The names a package's ``if TYPE_CHECKING:`` block imports, by absolute module."""
    path = PACKAGE.joinpath(*package.split(".")[1:], "__init__.py")
    found = {}
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for child in node.body:
                assert isinstance(child, ast.ImportFrom), ast.dump(child)
                base = ".".join(package.split(".")[: len(package.split(".")) - child.level + 1])
                module = f"{base}.{child.module}" if child.module else base
                found.update({alias.name: module for alias in child.names})
    return found


LAZY = [p for p in PACKAGES if _type_checking_imports(p)]


def test_the_lazy_packages_are_every_package_but_the_registry():
    """The family registry imports its one light module eagerly; every other package's
    names are found on first use."""
    assert set(PACKAGES) - set(LAZY) == {"armcal.families"}


@pytest.mark.parametrize("package", LAZY)
def test_what_mypy_sees_is_what_a_name_resolves_to(package):
    """A package's ``if TYPE_CHECKING:`` imports (what mypy and editors see) name every
    lazy name of ``__all__``, each the object the package gives at run time."""
    module = importlib.import_module(package)
    seen = _type_checking_imports(package)
    eager = {"__version__"} if package == "armcal" else set()
    assert set(seen) == set(module.__all__) - eager
    for name, home in seen.items():
        assert getattr(module, name) is getattr(importlib.import_module(home), name), name


def test_identifiability_stays_the_function_after_its_module_is_imported(tmp_path):
    """``identifiability`` names a module of armcal.models and the function the package
    gives; importing the module first must not put it over the function."""
    code = (
        "import armcal.models.identifiability, armcal.models, armcal\n"
        "from armcal.models import identifiability\n"
        "print(callable(identifiability), armcal.identifiability is identifiability)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    assert done.stdout.split() == ["True", "True"]


# --------------------------------------------------------------------------- the values named once


def test_the_modules_that_act_on_a_choice_hold_the_same_object():
    from armcal import doe, files, identification, workflow
    from armcal.criteria import CRITERIA
    from armcal.doe import designer, order, sizing
    from armcal.identification import solvers

    assert doe.METHODS is choices.DESIGN_METHODS
    assert get_args(designer.Method) == choices.DESIGN_METHODS
    assert identification.METHODS is choices.IDENTIFY_METHODS
    assert get_args(solvers.Method) == ("auto", *choices.IDENTIFY_METHODS)
    assert doe.REQUIREMENTS is choices.REQUIREMENTS
    assert get_args(sizing.Requirement) == tuple(choices.REQUIREMENTS)
    assert doe.TASK_CRITERIA is choices.TASK_CRITERIA
    assert doe.ORDERS is choices.ORDERS
    assert get_args(order.Order) == choices.ORDERS
    assert doe.DISTINCT_TOLERANCE == choices.DISTINCT_TOLERANCE
    # the one list of names written twice: the parser's choices and the criteria's keys
    assert tuple(CRITERIA) == choices.CRITERION_NAMES
    assert workflow.DEFAULT_SIGMA_MM == choices.DEFAULT_SIGMA_MM
    assert files.DEFAULT_ROBOT == choices.DEFAULT_ROBOT
    assert files.SIGMA_RANGE_MM is choices.SIGMA_RANGE_MM
    assert files.BUILTIN_ROBOTS is choices.BUILTIN_ROBOTS
    assert files.BUILTIN_SPATIAL_ROBOTS is choices.BUILTIN_SPATIAL_ROBOTS
    assert all(path.is_file() for path in choices.BUILTIN_SPATIAL_ROBOTS.values())


@pytest.mark.parametrize(
    ("argv", "theirs"),
    [
        # a planar demo's folder is checked for the spatial demo's files too, as before
        (("demo", "-o", "out"), "joint_offsets.csv"),
        (("reproduce", "-o", "out"), "table2.csv"),  # a table the reproduction writes
    ],
)
def test_a_folder_output_is_checked_for_files_its_command_names_when_it_runs(
    tmp_path, argv, theirs
):
    """The names of a folder's files come from the command's own modules when it runs
    (not when the parser is built); a user's file of one of them is still refused."""
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / theirs).write_text("mine\n", encoding="utf-8")
    run = run_cli(tmp_path, *argv)
    assert run.returncode == 2
    assert f"out/{theirs}: exists and armcal did not write it" in run.stderr
