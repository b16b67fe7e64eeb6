"""Benchmark: the start-up of the ``armcal`` program against ``python -c "import numpy"``.

What it measures
----------------
The CPU time (user + system, from ``os.wait4``) of a fresh process, with one BLAS
thread (``OPENBLAS_NUM_THREADS=1``: OpenBLAS's thread pool starts with numpy and
costs CPU on a many-core machine), least of interleaved runs (timer and machine
noise only ever add time):

* ``python -c "import numpy"`` -- the floor: every command imports numpy;
* ``armcal --version``, ``armcal --help``, ``armcal identify --help`` and
  ``armcal design --help`` -- what the program shows before it runs anything: the
  parser and the help text (:mod:`armcal.choices`), none of the library, no numpy;
* a bad input (``armcal identify --robot missing.toml ...``, exit status 2) --
  shown without a target: the robot loader runs before the error is known.

The target is within 2x the floor for the four that show the program; a figure over
it prints FAIL.  The armcal package is byte-compiled first (the byte-code is a cache
an installed package has; compiling it is not start-up).

Usage::

    .venv/bin/python benchmarks/bench_startup.py [--repeats N] [--no-write]
"""

from __future__ import annotations

import argparse
import compileall
import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from measure import armcal_argv, at_end, machine_and_date

RESULTS = Path(__file__).with_name("RESULTS_STARTUP.md")

#: The target: start-up within this many times ``import numpy``'s CPU time.
TARGET = 2.0


def cpu_seconds(argv: list[str], cwd: str) -> tuple[float, int]:
    """User + system CPU seconds of one run of ``argv`` in a fresh process, and its exit
    status; one BLAS thread."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    child = subprocess.Popen(
        argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=cwd
    )
    _, status, usage = os.wait4(child.pid, 0)
    return usage.ru_utime + usage.ru_stime, os.waitstatus_to_exitcode(status)


def cases() -> list[tuple[str, list[str], int, bool]]:
    """Each case: its name, argv, expected exit status and whether the target holds it."""
    missing = ["identify", "--robot", "missing.toml", "--measurements", "missing.csv"]
    return [
        ('python -c "import numpy"', [sys.executable, "-c", "import numpy"], 0, False),
        ("armcal --version", armcal_argv(["--version"]), 0, True),
        ("armcal --help", armcal_argv(["--help"]), 0, True),
        ("armcal identify --help", armcal_argv(["identify", "--help"]), 0, True),
        ("armcal design --help", armcal_argv(["design", "--help"]), 0, True),
        ("bad input (a missing robot file)", armcal_argv(missing), 2, False),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="interleaved runs (default 5)")
    parser.add_argument("--no-write", action="store_true", help=f"do not write {RESULTS.name}")
    args = parser.parse_args()

    spec = importlib.util.find_spec("armcal")  # its folder, without importing it
    assert spec is not None and spec.submodule_search_locations
    compileall.compile_dir(spec.submodule_search_locations[0], quiet=1)
    machine, date = machine_and_date()
    print(f"armcal start-up benchmark, {date}\n{machine}\n", flush=True)
    rows = cases()
    best = [float("inf")] * len(rows)
    with tempfile.TemporaryDirectory(prefix="armcal-startup-") as tmp:  # nothing to find
        for _ in range(args.repeats):
            for i, (name, argv, expected, _) in enumerate(rows):
                seconds, status = cpu_seconds(argv, tmp)
                if status != expected:
                    raise RuntimeError(f"{name}: exit status {status}, expected {expected}")
                best[i] = min(best[i], seconds)
    floor = best[0]
    lines = ["| run | CPU s | / import numpy | target | verdict |", "|---|---:|---:|---|---|"]
    failed = []
    for (name, _, _, held), seconds in zip(rows, best, strict=True):
        ratio = seconds / floor
        verdict = ("PASS" if ratio <= TARGET else "FAIL") if held else ""
        if verdict == "FAIL":
            failed.append(name)
        target = f"<= {TARGET:g}x" if held else ""
        print(f"{name:<34} {seconds:6.3f} s  {ratio:5.2f}x  {target:<7} {verdict}", flush=True)
        lines.append(f"| {name} | {seconds:.3f} | {ratio:.2f}x | {target} | {verdict} |")
    verdict = f"PASS: every start-up within {TARGET:g}x"
    if failed:
        verdict = "FAIL: " + ", ".join(failed)
    print(f"\n{verdict}")
    machine = at_end(machine)
    if not args.no_write:
        RESULTS.write_text(
            "# Start-up benchmark results\n\n"
            "Written by `benchmarks/bench_startup.py`; see its docstring for what each figure "
            f"is. CPU time (user + system), least of {args.repeats} interleaved runs, one "
            "BLAS thread.\n\n"
            f"- date: {date}\n- machine: {machine}\n\n" + "\n".join(lines) + f"\n\n{verdict}\n",
            encoding="utf-8",
        )
        print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
