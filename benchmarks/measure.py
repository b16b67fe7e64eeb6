"""How the benchmarks measure a process: wall time and peak resident memory.

A command runs in a fresh child of a fresh, small measuring process, whose
peak resident memory comes from ``os.wait4`` (``ru_maxrss``): Linux carries a
parent's peak RSS over into a forked child's ``ru_maxrss``, so measuring from
a benchmark's own (large) process would report that process's peak instead.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
import sys

import numpy as np

#: Runs argv[1:] and prints its wall time, exit status, peak RSS and stderr's tail.
_MEASURE = """
import json, os, subprocess, sys, time
start = time.perf_counter()
child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
stderr = child.stderr.read()
_, status, usage = os.wait4(child.pid, 0)
seconds = time.perf_counter() - start
code = os.waitstatus_to_exitcode(status)
report = {"seconds": seconds, "status": code, "maxrss_kib": usage.ru_maxrss}
print(json.dumps({**report, "stderr": stderr.decode()[-500:]}))
"""


def measure(argv: list[str]) -> tuple[float, float]:
    """Wall seconds and peak memory (MB) of one run of ``argv`` in a fresh process.

    Raises RuntimeError, with the end of its stderr, when it exits non-zero.
    """
    out = subprocess.run(
        [sys.executable, "-c", _MEASURE, *argv], capture_output=True, text=True, check=True
    )
    report = json.loads(out.stdout)
    if report["status"] != 0:
        raise RuntimeError(f"{' '.join(argv)} failed: {report['stderr']}")
    return report["seconds"], report["maxrss_kib"] / 1024  # Linux reports KiB


def _load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} {five:.2f} {fifteen:.2f}"


def machine_and_date() -> tuple[str, str]:
    """The machine (name, cores, interpreter, numpy, load average now) and the date."""
    machine = (
        f"{platform.node()}: nproc {os.cpu_count()}, {platform.machine()}, "
        f"python {platform.python_version()}, numpy {np.__version__}; "
        f"load average (1, 5, 15 min) at start {_load()}"
    )
    return machine, datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")


def at_end(machine: str) -> str:
    """``machine`` with the load average at the end of the run."""
    return f"{machine}, at end {_load()}"


def armcal_argv(args: list[str]) -> list[str]:
    """The argv of ``armcal ARGS`` with this interpreter."""
    return [sys.executable, "-m", "armcal", *args]
