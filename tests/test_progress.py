"""What a long command shows on a terminal while it works (issue 36): an elapsed-time line
after 2 s for any command, a bar where the command counts its work, nothing in a pipe or
a log, and nothing left on the line once the result is printed."""

from __future__ import annotations

import io
import time

from armcal.progress import Elapsed, ProgressBar, quiet


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_an_elapsed_line_appears_after_its_delay_and_is_erased():
    stream = _Terminal()
    with Elapsed("armcal identify", stream=stream, delay=0.05, interval=0.01) as line:
        time.sleep(0.3)
    text = stream.getvalue()
    assert line.shown and "\rarmcal identify ... 0 s" in text
    assert text.endswith(" " * len("armcal identify ... 0 s") + "\r")  # erased


def test_nothing_is_drawn_in_a_pipe_or_for_short_work():
    piped = io.StringIO()
    with Elapsed("armcal identify", stream=piped, delay=0.0, interval=0.01):
        time.sleep(0.05)
    assert piped.getvalue() == ""
    short = _Terminal()
    with Elapsed("armcal identify", stream=short, delay=5.0, interval=0.01):
        time.sleep(0.05)
    assert short.getvalue() == ""


def test_a_progress_bar_takes_over_and_printing_stops_the_line():
    stream = _Terminal()
    with Elapsed("armcal design", stream=stream, delay=0.0, interval=0.01):
        time.sleep(0.05)
        ProgressBar("design", stream=stream, delay=0.0)(1, 2)
        mark = len(stream.getvalue())
        time.sleep(0.05)
        assert "armcal design ..." not in stream.getvalue()[mark:]  # the bar says more
    stream = _Terminal()
    with Elapsed("armcal validate", stream=stream, delay=0.0, interval=0.01):
        time.sleep(0.05)
        quiet()  # what emit and print_warnings call before printing
        mark = len(stream.getvalue())
        time.sleep(0.05)
        assert stream.getvalue()[mark:] == ""
