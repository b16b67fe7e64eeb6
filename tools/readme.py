"""Run every example of README.md and the guides and write (or check) their printed output.

The README cannot go stale: each ```console block is a script whose lines that
start with ``$ `` are run, in order, in one fresh temporary folder, with the
``armcal`` of this checkout on PATH; the lines after a command are its output
(stdout and stderr, as a terminal shows them).  A ```toml or ```yaml block whose first
line is ``# NAME`` (an ```xml block: ``<!-- NAME -->``) is written to NAME in that
folder before the blocks after it run, so the files the README shows are the
files the commands read.  A
```python block of ``>>>`` examples is run as a doctest.

    python tools/readme.py                   # rewrite every document with fresh output
    python tools/readme.py --check           # exit 1 and show a diff if one is stale
    python tools/readme.py docs/guide.md     # only this document
    python tools/readme.py --check --times docs/guide.md   # and each command's wall time

Wall-clock figures (``0.62 s``) differ from run to run; ``--check`` compares
them as ``<t> s``.  Figures that a command writes under ``docs/`` are copied
into the repository by a rewrite and must exist for ``--check``.
"""

from __future__ import annotations

import argparse
import difflib
import doctest
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# One BLAS thread, as `make test` runs: an optimizer's last digits depend on how the
# BLAS splits its sums, and a page must print the same digits wherever it is checked.
SERIAL = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _same_kernels() -> dict[str, str]:
    """The same arithmetic on every x86-64 machine with AVX2: the last digits of a sum or a
    sine depend on the CPU's vector kernels, and a design's optimizer (started from random
    poses) turns a last digit into another plan.  numpy's AVX-512 loops (its own sine,
    exponential, ...) are switched off, so it calls the C library's everywhere, and
    OpenBLAS takes its Haswell (AVX2) kernels, which it picks on AMD's Zen too, instead of
    its SkylakeX ones.  A CPU without AVX2 keeps its own (and may print other digits)."""
    pinned = {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR"}
    try:
        flags = Path("/proc/cpuinfo").read_text().split()
    except OSError:
        flags = []
    if "avx2" in flags and "fma" in flags:
        pinned["OPENBLAS_CORETYPE"] = "Haswell"
    return pinned


os.environ.update(SERIAL | _same_kernels())  # before any doctest imports numpy

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
#: Every document whose examples are run: the README, then every guide in docs/.
DOCUMENTS = (README, *sorted((ROOT / "docs").glob("*.md")))
FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.M | re.S)
SECONDS = re.compile(r"\b\d+(?:\.\d+)? s\b")
#: Files the README's commands write that are kept in the repository (as pictures),
#: by their path in the work folder; they are kept under their own name in docs/img.
KEPT_FIGURES = ("quickstart_residuals.png",)
FIGURE_DIR = ROOT / "docs" / "img"
#: A guide keeps every PNG its commands write into this folder of its work folder
#: (``--plot figures/NAME.png``), under its own name in docs/img.
GUIDE_FIGURES = "figures"


def _run(command: str, cwd: Path) -> str:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["COLUMNS"] = "100"
    done = subprocess.run(
        ["bash", "-o", "pipefail", "-c", command],
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        check=False,
    )
    differ = command.startswith("diff ") and done.returncode == 1  # diff: the files differ
    if done.returncode not in (0, 2) and not differ:  # 2: an error shown on purpose
        raise SystemExit(f"README command failed ({done.returncode}): {command}\n{done.stdout}")
    return done.stdout


#: With ``--times``, each command's wall time goes to stderr: which example makes a check slow.
TIMES = {"on": False}


def _console(body: str, cwd: Path) -> str:
    commands = [line[2:] for line in body.splitlines() if line.startswith("$ ")]
    out = []
    for command in commands:
        out.append(f"$ {command}\n")
        start = time.perf_counter()
        out.append(_run(command, cwd))
        if TIMES["on"]:
            print(f"{time.perf_counter() - start:7.1f} s  {command[:90]}", file=sys.stderr)
    return "".join(out)


def _python(body: str, cwd: Path, name: str) -> None:
    parser = doctest.DocTestParser()
    test = parser.get_doctest(body, {}, name, name, 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    here = Path.cwd()
    os.chdir(cwd)
    try:
        runner.run(test)
    finally:
        os.chdir(here)
    if runner.failures:
        raise SystemExit(f"{name}: python example failed ({runner.failures} failure(s))")


def render(text: str, name: str = "README.md") -> tuple[str, Path]:
    """README text with every console block's output regenerated, and the work folder."""
    work = Path(tempfile.mkdtemp(prefix="armcal-readme-"))
    pieces, last = [], 0
    for match in FENCE.finditer(text):
        kind, body = match.group(1), match.group(2)
        pieces.append(text[last : match.start()])
        if kind in ("toml", "yaml") and body.startswith("# "):
            filename = body.splitlines()[0][2:].strip()
            (work / filename).write_text(body, encoding="utf-8")
        elif kind == "xml" and body.startswith("<!-- ") and body.splitlines()[0].endswith("-->"):
            filename = body.splitlines()[0][5:-3].strip()
            (work / filename).write_text(body, encoding="utf-8")
        elif kind == "console":
            body = _console(body, work)
        elif kind == "python" and ">>>" in body:
            _python(body, work, name)
        pieces.append(f"```{kind}\n{body}```\n")
        last = match.end()
    pieces.append(text[last:])
    return "".join(pieces), work


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare instead of rewriting")
    parser.add_argument("--times", action="store_true", help="each command's wall time on stderr")
    parser.add_argument(
        "documents", nargs="*", type=Path, help="only these documents (default: all)"
    )
    args = parser.parse_args(argv)
    TIMES["on"] = args.times
    status = 0
    for document in [d.resolve() for d in args.documents] or DOCUMENTS:
        status = max(status, _one(document, check=args.check))
    return status


def _kept(document: Path, work: Path) -> list[Path]:
    """The figures of ``document``'s run (in ``work``) that the repository keeps."""
    if document == README:
        return [work / figure for figure in KEPT_FIGURES]
    return sorted((work / GUIDE_FIGURES).glob("*.png"))


def _one(document: Path, *, check: bool) -> int:
    """Check or rewrite one document; 1 when a check finds it stale."""
    name = document.relative_to(ROOT)
    text = document.read_text(encoding="utf-8")
    fresh, work = render(text, str(name))
    try:
        if check:
            old, new = SECONDS.sub("<t> s", text), SECONDS.sub("<t> s", fresh)
            missing = [f for f in _kept(document, work) if not (FIGURE_DIR / f.name).is_file()]
            if old != new or missing:
                diff = difflib.unified_diff(
                    old.splitlines(True), new.splitlines(True), str(name), "fresh run"
                )
                sys.stdout.writelines(diff)
                if missing:
                    names = ", ".join(f.name for f in missing)
                    print(f"missing figures in {FIGURE_DIR}: {names}")
                print(f"{name} is stale: run `make readme`")
                return 1
            print(f"{name} matches a fresh run of its examples")
            return 0
        document.write_text(fresh, encoding="utf-8")
        FIGURE_DIR.mkdir(parents=True, exist_ok=True)
        for figure in _kept(document, work):
            if figure.is_file():
                shutil.copyfile(figure, FIGURE_DIR / figure.name)
        print(f"rewrote {name} from a fresh run of its examples")
        return 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
