"""A tiny progress bar for long runs, drawn on a terminal only.

:class:`Progress` draws ``label [#######.......]  45% (450/1000) 3.2 s`` on one line,
redrawn in place with a carriage return, only when its stream is a terminal
(``stream.isatty()``) and the run has lasted at least ``min_seconds``; otherwise
it writes nothing at all, so logs, pipes and tests stay clean.  When a bar was
drawn, leaving the ``with`` block draws the final state and ends the line with a
newline (also when the block raised), so what follows starts on a fresh line.

>>> import io
>>> with Progress(3, label="steps", stream=io.StringIO()) as bar:   # not a terminal: silent
...     bar.update(3)
"""

from __future__ import annotations

import sys
import time
from types import TracebackType
from typing import Callable, TextIO

from ..errors import InvalidInputError

__all__ = ["Progress"]

_WIDTH = 30         # characters in the bar
_REDRAW_SECONDS = 0.1


def _is_tty(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):  # no isatty, or a closed stream
        return False


class Progress:
    """Report progress of ``total`` units of work; a context manager with :meth:`update`.

    With ``rate_unit`` (e.g. "points") the line ends with the rate so far and the time left at that rate.

    ``stream`` defaults to ``sys.stderr`` as it is when the bar is made.  Counts
    beyond ``total`` are shown as 100 %.  ``clock`` (seconds, monotonic) is for tests.
    """

    def __init__(self, total: int, *, label: str, stream: TextIO | None = None, min_seconds: float = 1.0,
                 clock: Callable[[], float] = time.monotonic, rate_unit: str | None = None) -> None:
        if isinstance(total, bool) or not isinstance(total, int) or total < 0:
            raise InvalidInputError(f"expected `total` to be an integer >= 0, got {total!r}")
        if not isinstance(label, str):
            raise InvalidInputError(f"expected `label` to be a string, got {label!r}")
        if isinstance(min_seconds, bool) or not isinstance(min_seconds, (int, float)) or not min_seconds >= 0:
            raise InvalidInputError(f"expected `min_seconds` to be a number >= 0, got {min_seconds!r}")
        self.total = total
        self.label = label
        self.done = 0
        self.stream = sys.stderr if stream is None else stream
        self.min_seconds = float(min_seconds)
        self.rate_unit = rate_unit
        self._clock = clock
        self._active = _is_tty(self.stream)
        self._start = clock()
        self._last_draw: float | None = None
        self._last_width = 0

    def __enter__(self) -> Progress:
        self._start = self._clock()
        return self

    def update(self, n: int = 1) -> None:
        """Count ``n`` more units done, and redraw if it is time to."""
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise InvalidInputError(f"expected `n` to be an integer >= 0, got {n!r}")
        self.done += n
        if not self._active:
            return
        now = self._clock()
        if now - self._start < self.min_seconds:
            return
        if self._last_draw is None or now - self._last_draw >= _REDRAW_SECONDS or self.done >= self.total:
            self._draw(now)

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if not self._active:
            return
        now = self._clock()
        if self._last_draw is None and now - self._start < self.min_seconds:
            return  # a short run: nothing was drawn, nothing to finish
        self._draw(now)
        self.stream.write("\n")
        self.stream.flush()

    def _line(self, now: float) -> str:
        fraction = 1.0 if self.total == 0 else min(self.done / self.total, 1.0)
        filled = int(round(fraction * _WIDTH))
        bar = "#" * filled + "." * (_WIDTH - filled)
        shown = min(self.done, self.total)
        elapsed = now - self._start
        line = f"{self.label} [{bar}] {fraction * 100:3.0f}% ({shown}/{self.total}) {elapsed:.1f} s"
        if self.rate_unit is not None and self.done > 0 and elapsed > 0:
            rate = self.done / elapsed
            left = max(self.total - self.done, 0) / rate
            line += f", {rate:,.0f} {self.rate_unit}/s, {left:.0f} s left"
        return line

    def _draw(self, now: float) -> None:
        line = self._line(now)
        pad = " " * max(self._last_width - len(line), 0)  # clear what a longer previous line left
        self.stream.write("\r" + line + pad)
        self.stream.flush()
        self._last_width = len(line)
        self._last_draw = now
