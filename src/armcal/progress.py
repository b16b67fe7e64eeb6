"""A quiet progress bar for long work: it appears only after a delay, on a terminal.

Library functions that run long take ``progress: Callable[[int, int], None]``
and call it with ``(done, total)``; the command line passes a :class:`ProgressBar`.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["Elapsed", "ProgressBar", "ProgressCallback", "quiet", "share", "steps"]

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
        _BARS_DRAWN.set()  # an Elapsed line steps aside for the bar


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


#: Set once a :class:`ProgressBar` has drawn: the command's own bar says more than an
#: :class:`Elapsed` line, which stops drawing.
_BARS_DRAWN = threading.Event()

#: The :class:`Elapsed` lines running, so that :func:`quiet` can stop them.
_RUNNING: list[Elapsed] = []


class Elapsed:
    """``armcal identify ... 3 s`` on a terminal while a command runs longer than ``delay``
    seconds, redrawn every ``interval``; nothing when the stream is not a terminal, and
    nothing once a :class:`ProgressBar` draws (it says more) or the command prints its
    result (:func:`quiet`).  The line is erased when it stops.

    A context manager: ``with Elapsed("armcal identify"): run()``.

    Examples
    --------
    >>> import io
    >>> with Elapsed("work", stream=io.StringIO(), delay=0.0) as line:
    ...     pass
    >>> line.shown  # a StringIO is not a terminal
    False
    """

    def __init__(
        self,
        label: str,
        *,
        stream: TextIO | None = None,
        delay: float = 2.0,
        interval: float = 0.5,
    ) -> None:
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        self.delay = delay
        self.interval = interval
        self.shown = False
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def __enter__(self) -> Elapsed:
        _BARS_DRAWN.clear()
        if self.stream.isatty():
            self._thread = threading.Thread(target=self._draw, daemon=True)
            _RUNNING.append(self)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _draw(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(self.interval):
            elapsed = time.monotonic() - start
            if elapsed < self.delay:
                continue
            with self._lock:
                if self._stop.is_set() or _BARS_DRAWN.is_set():
                    continue
                self.stream.write(f"\r{self.label} ... {elapsed:.0f} s")
                self.stream.flush()
                self.shown = True

    def stop(self) -> None:
        """Stop drawing and erase the line (safe to call twice)."""
        self._stop.set()
        with self._lock:
            if self.shown and not _BARS_DRAWN.is_set():
                self.stream.write("\r" + " " * (len(self.label) + 12) + "\r")
                self.stream.flush()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self in _RUNNING:
            _RUNNING.remove(self)


def quiet() -> None:
    """Stop every :class:`Elapsed` line: the command is about to print."""
    for line in list(_RUNNING):
        line.stop()
