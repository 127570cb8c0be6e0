"""Time budgets for ``mechderive check``: interrupt a symbolic step or a high-precision evaluation.

:func:`within` runs a function under a SIGALRM timer (main thread only; elsewhere, or when
another timer is armed, it runs unbudgeted if the caller allows it, else not at all).
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["within"]


class _OutOfTime(BaseException):
    """Raised by the alarm; a BaseException so that SymPy's ``except Exception`` does not swallow it."""


@contextmanager
def _budget(seconds: float) -> Iterator[bool]:
    """Yield True and interrupt the block after ``seconds`` (main thread with SIGALRM); else yield False."""
    usable = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
    if usable and signal.getitimer(signal.ITIMER_REAL)[0] > 0:
        usable = False  # someone else's timer is armed (e.g. pytest-timeout): leave it alone
    if not usable or seconds <= 0:
        yield False
        return

    def _alarm(signum, frame):
        raise _OutOfTime()

    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield True
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def within(fn: Callable[[], Any], seconds: float, *, unbudgeted_ok: bool) -> tuple[bool, Any]:
    """(finished, result) of ``fn()`` under a time budget; without a usable alarm only if ``unbudgeted_ok``."""
    try:
        with _budget(seconds) as armed:
            if not armed and not unbudgeted_ok:
                return False, None
            return True, fn()
    except _OutOfTime:
        return False, None
