"""The house rules of the code, checked on the tree as it is.

* The README's layout lists every module of ``src/armcal`` once, and nothing else.
* Imports run one way: a module imports only modules of its own line of that
  layout or of the lines above it, and no two modules import each other,
  directly or around a circle.
* No private name (``_x``) crosses a module boundary.
* No module has more than 600 lines of code (docstrings, comments and blank
  lines not counted) unless its opening docstring says why under the words
  "Why this module is long".
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "armcal"
MAX_CODE_LINES = 600


def _modules() -> dict[str, Path]:
    """Every module of the package by dotted name relative to ``armcal`` (``models.planar``)."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        found[".".join(parts)] = path
    return found


def _layout() -> list[set[str]]:
    """The README's layout: the modules of every line of the list, top line first.

    A line lists top-level modules (```name.py```) and, in its sub-items
    (``- `package/`: ...``), a package's modules.
    """
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index("- Layout of `src/armcal/`")
    end = text.index("\n- ", start + 1)
    layers = []
    for item in re.split(r"\n  - ", text[start:end])[1:]:  # one per line of the list
        parts = re.split(r"\n    - ", item)
        names = {f"{t[:-3]}" for t in re.findall(r"`([^`/]+\.py)`", parts[0])}
        for sub in parts[1:]:
            package = re.match(r"`([a-z_/]+)/`:", sub)
            assert package, sub
            modules = re.findall(r"`([^`/]+\.py)`", sub)
            dotted = package.group(1).replace("/", ".")
            names |= {f"{dotted}.{m[:-3]}" for m in modules}
        layers.append(names)
    return layers


def test_the_readme_layout_lists_every_module_once():
    listed = [name for layer in _layout() for name in layer]
    modules = set(_modules())
    assert len(listed) == len(set(listed)), "a module is listed twice"
    assert set(listed) == modules, (
        f"missing from the README: {sorted(modules - set(listed))}; "
        f"not in the tree: {sorted(set(listed) - modules)}"
    )


def _imports(name: str, path: Path) -> set[str]:
    """The package's modules that module ``name`` imports at its top level or in a function."""
    modules = _modules()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name.split(".")[:-1] if not path.name == "__init__.py" else name.split(".")
    if path.name == "__init__.py":
        package = [] if name == "__init__" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(tree):
        targets: list[str] = []
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                prefix = ".".join([*base, *(node.module.split(".") if node.module else [])])
            elif node.module and node.module.startswith("armcal"):
                prefix = node.module.removeprefix("armcal").lstrip(".")
            else:
                continue
            targets = [f"{prefix}.{a.name}".lstrip(".") for a in node.names] + [prefix]
        elif isinstance(node, ast.Import):
            targets = [
                a.name.removeprefix("armcal").lstrip(".")
                for a in node.names
                if a.name.startswith("armcal")
            ]
        for target in targets:
            if target in modules:
                found.add(target)
            elif f"{target}.__init__" in modules:
                found.add(f"{target}.__init__")
    found.discard(name)
    return found


def _graph() -> dict[str, set[str]]:
    return {name: _imports(name, path) for name, path in _modules().items()}


def test_no_import_cycle():
    graph = _graph()
    state: dict[str, int] = {}

    def visit(node: str, trail: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if nxt.endswith("__init__") and node.startswith(nxt.removesuffix("__init__")):
                continue  # a package's module importing its own package's names
            if state.get(nxt) == 1:
                pytest.fail("import cycle: " + " -> ".join([*trail, node, nxt]))
            if nxt not in state:
                visit(nxt, [*trail, node])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [])


def test_imports_run_one_way():
    """A module imports only modules of its own line of the layout or of lines above it."""
    layers = {name: index for index, names in enumerate(_layout()) for name in names}
    upward = [
        f"{name} imports {target}"
        for name, imported in _graph().items()
        for target in imported
        if layers[target] > layers[name]
    ]
    assert not upward, upward


def test_no_private_name_crosses_a_module_boundary():
    crossings = []
    for name, path in _modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                for alias in node.names:
                    if alias.name.startswith("_") and not alias.name.startswith("__"):
                        crossings.append(f"{name}: from {node.module} import {alias.name}")
    assert not crossings, crossings


def _code_lines(path: Path) -> int:
    """Lines holding code: not blank, not only a comment, not in a docstring."""
    source = path.read_text(encoding="utf-8")
    tree = ast.parse(source)
    docstrings: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                if isinstance(body[0].value.value, str):
                    docstrings.update(range(body[0].lineno, body[0].end_lineno + 1))
    lines: set[int] = set()
    skip = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type in skip or token.type == tokenize.ENDMARKER:
            continue
        lines.update(n for n in range(token.start[0], token.end[0] + 1) if n not in docstrings)
    return len(lines)


def test_no_module_is_over_600_lines_of_code_without_a_reason():
    long = []
    for name, path in _modules().items():
        count = _code_lines(path)
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        if count > MAX_CODE_LINES and "Why this module is long" not in doc:
            long.append(f"{name}: {count} lines of code")
    assert not long, long


def test_the_line_counter_counts_code_only(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text(
        '"""Doc\n\nstring."""\n\n# a comment\nx = 1  # code\n\n\ndef f():\n'
        '    """Doc."""\n    return (\n        x\n    )\n',
        encoding="utf-8",
    )
    assert _code_lines(sample) == 5  # x = 1; def f(): return ( x )
