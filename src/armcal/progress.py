"""A quiet progress bar for long work: it appears only after a delay, on a terminal.

Library functions that run long take ``progress: Callable[[int, int], None]``
and call it with ``(done, total)``; the command line passes a :class:`ProgressBar`.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["ProgressBar", "ProgressCallback", "share", "steps"]

#: ``progress(done, total)``, called as work advances.
ProgressCallback = Callable[[int, int], None]


class ProgressBar:
    """Draw ``label [#####.....] 50% 3.1 s`` on ``stream`` once work has taken ``delay`` s.

    Parameters
    ----------
    label : str
        What is running (``"simulate"``).
    stream : text stream, optional
        Where to draw (default ``sys.stderr``).  Nothing is drawn unless it is a
        terminal, so logs and pipes stay clean.
    delay : float
        Seconds of silence before the bar appears; short work shows nothing.
    clock : callable
        Monotonic clock in seconds (for tests).

    Examples
    --------
    >>> import io
    >>> bar = ProgressBar("work", stream=io.StringIO(), delay=0.0)
    >>> bar(5, 10); bar(10, 10)
    >>> bar.shown  # a StringIO is not a terminal
    False
    """

    def __init__(
        self,
        label: str,
        *,
        stream: TextIO | None = None,
        delay: float = 2.0,
        clock: Callable[[], float] = time.monotonic,
        width: int = 30,
    ) -> None:
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        self.delay = delay
        self.clock = clock
        self.width = width
        self.start = clock()
        self.shown = False

    def __call__(self, done: int, total: int) -> None:
        elapsed = self.clock() - self.start
        if elapsed < self.delay or not self.stream.isatty():
            return
        fraction = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
        filled = round(fraction * self.width)
        bar = "#" * filled + "." * (self.width - filled)
        end = "\n" if done >= total else ""
        self.stream.write(f"\r{self.label} [{bar}] {fraction:4.0%} {elapsed:.1f} s{end}")
        self.stream.flush()
        self.shown = True


def share(progress: ProgressCallback | None, start: float, stop: float) -> ProgressCallback | None:
    """The callback for one part of a piece of work: the part's ``(done, total)`` drawn
    between the fractions ``start`` and ``stop`` of the whole, reported out of 1000.

    Examples
    --------
    >>> calls = []
    >>> second_half = share(lambda *a: calls.append(a), 0.5, 1.0)
    >>> second_half(1, 4); second_half(4, 4)
    >>> calls
    [(625, 1000), (1000, 1000)]
    """
    if progress is None:
        return None
    report = progress

    def part(done: int, total: int) -> None:
        fraction = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
        report(round(1000 * (start + (stop - start) * fraction)), 1000)

    return part


def steps(progress: ProgressCallback | None, total: int) -> Callable[[], None]:
    """A callable that reports one more of ``total`` steps done to ``progress`` each time
    it is called (nothing without ``progress``): for work made of a few long stages.

    Examples
    --------
    >>> seen = []
    >>> step = steps(lambda done, total: seen.append((done, total)), 3)
    >>> step(); step()
    >>> seen
    [(1, 3), (2, 3)]
    """
    done = [0]

    def step() -> None:
        done[0] += 1
        if progress is not None:
            progress(done[0], total)

    return step
