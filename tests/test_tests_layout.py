"""The house rules of the test suite, checked on the tree as it is.

* No module of ``tests/`` imports a test file (``test_*.py``): what several test
  files share lives in ``helpers.py`` or a ``helpers_*.py`` module, so that a test
  file can be run, moved or deleted alone, and pytest never imports one twice.
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def _test_file_imports(path: Path) -> list[str]:
    """The imports of test files in ``path``, as ``"line N: module"``: ``import test_x``,
    ``from test_x import ...``, ``from tests.test_x import ...``, ``from . import test_x``
    and ``from .test_x import ...``, at the top or inside a function."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = []
    for node in ast.walk(tree):
        modules: list[str] = []
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.module is not None:
                modules = [node.module]
            if node.level or node.module in (None, "tests"):  # from . import test_x
                modules += [alias.name for alias in node.names]
        for module in modules:
            if any(part.startswith("test_") for part in module.split(".")):
                found.append(f"line {node.lineno}: {module}")
    return found


def test_no_test_file_imports_another_test_file():
    offenders = {
        path.name: found
        for path in sorted(TESTS.glob("*.py"))
        if (found := _test_file_imports(path))
    }
    assert not offenders, f"move what they share into tests/helpers*.py: {offenders}"


def test_the_check_finds_every_form_of_import(tmp_path):
    sample = tmp_path / "test_sample.py"
    sample.write_text(
        "import numpy as np\n"
        "from helpers import run_cli\n"
        "from test_a import thing\n"
        "import test_b\n"
        "from tests.test_c import other\n"
        "from . import test_d\n"
        "\n"
        "def f():\n"
        "    from .test_e import late\n"
        "    return late\n",
        encoding="utf-8",
    )
    assert _test_file_imports(sample) == [
        "line 3: test_a",
        "line 4: test_b",
        "line 5: tests.test_c",
        "line 6: test_d",
        "line 9: test_e",
    ]
