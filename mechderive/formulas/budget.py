"""Time budgets for ``mechderive check``: one deadline for a whole decision, enforced in every step.

A :class:`Budget` of ``seconds`` starts when it is made and is spent by every step of a
decision: parsing, expanding ``dt``, proving, sampling, simplifying.  It is enforced two ways.

- **Cooperatively**: :meth:`Budget.check` between steps (each ``dt``, each random point, each
  precision) raises :class:`OutOfTime` once the deadline has passed.
- **By an interval timer** (``signal.setitimer`` and ``SIGALRM``): :meth:`Budget.run`,
  :meth:`Budget.attempt` and :func:`run_until` interrupt a computation that is still running at
  its deadline, wherever it is in Python code — a single SymPy ``diff``, ``expand`` or
  ``simplify`` or an mpmath evaluation cannot check a deadline itself.  The alarm raises
  :class:`OutOfTime`, a ``BaseException``, so that SymPy's ``except Exception`` does not
  swallow it.  An interrupted SymPy call leaves no wrong state behind: SymPy's caches store a
  result only after it is computed, and an assumption only once it is known.

Scopes nest (a step inside the whole decision, a decision inside a caller's scope): the timer
is armed for the innermost scope's deadline, which is never later than an enclosing one's, and
re-armed for the enclosing scope when it ends; the alarm ends the outermost scope whose
deadline has passed (inner scopes let it through).  The bookkeeping runs with ``SIGALRM``
blocked.  An alarm that falls in a finaliser or a gc callback, where Python cannot raise it,
is dropped silently (not printed as "Exception ignored") and raised again 0.1 s later.  The
SIGALRM handler and the unraisable hook are installed by the outermost scope and restored
when it ends.

The timer is used only in the main thread, when ``setitimer`` exists and when nobody else's
timer is armed (that one is left alone); otherwise only the cooperative checks apply, and
:mod:`.check` bounds what a single call gets instead: no proof is attempted, and expansions
stop at :data:`~.check.MAX_UNTIMED_NODES` nodes.
"""

from __future__ import annotations

import signal
import sys
import threading
import time
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["Budget", "OutOfTime", "run_until", "timer_usable"]

_SHORTEST = 1e-4  # seconds: an already-passed deadline is raised this soon (setitimer(0) would disarm)


class OutOfTime(BaseException):
    """The time budget ran out: ``scope`` is the interrupted scope, or ``budget`` the :class:`Budget`
    whose cooperative check found it spent."""

    def __init__(self, scope: "_Scope | None" = None, budget: "Budget | None" = None) -> None:
        super().__init__("the time budget ran out")
        self.scope = scope
        self.budget = budget


class _Scope:
    __slots__ = ("at",)

    def __init__(self, at: float) -> None:
        self.at = at


_scopes: list[_Scope] = []  # the armed scopes, outermost first (main thread only)
_previous: list = []  # the SIGALRM handler and the unraisable hook to restore when the outermost scope ends


def timer_usable() -> bool:
    """Whether a computation can be interrupted here: main thread, setitimer, no foreign timer armed."""
    if not hasattr(signal, "setitimer") or threading.current_thread() is not threading.main_thread():
        return False
    return bool(_scopes) or signal.getitimer(signal.ITIMER_REAL)[0] == 0


_busy = [False]  # True while the scopes are updated: the handler then leaves them alone


@contextmanager
def _bookkeeping() -> Iterator[None]:
    """The scopes updated with SIGALRM held back, and the handler told not to raise meanwhile (a
    signal that arrived just before is handled at the next Python call, possibly in here)."""
    _busy[0] = True
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM}) if hasattr(signal, "pthread_sigmask") else None
    try:
        yield
    finally:
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
        _busy[0] = False


def _arm() -> None:
    if _scopes:
        signal.setitimer(signal.ITIMER_REAL, max(_scopes[-1].at - time.monotonic(), _SHORTEST))
    else:
        signal.setitimer(signal.ITIMER_REAL, 0)


def _alarm(signum, frame) -> None:
    if _busy[0]:
        return  # the bookkeeping re-arms the timer itself
    now = time.monotonic() + _SHORTEST
    for scope in _scopes:  # the outermost expired scope: what runs inside it is moot
        if scope.at <= now:
            # a reminder, in case some code swallows the exception: the scope's end re-arms it anyway
            signal.setitimer(signal.ITIMER_REAL, 0.1)
            raise OutOfTime(scope)
    _arm()  # early, or for a scope that has ended


def _settle() -> None:
    """Let no SIGALRM outlive our handler: one held back by the mask is taken, one already received is
    handled here (a Python call handles pending signals), while the handler is still ours.

    Never a blocking wait: ``sigpending`` reports signals pending for the *process* too, and another
    thread that does not block SIGALRM (pytest-xdist's and Dask's threads, a user's) may take such
    a signal between the look and a ``sigwait``, which then waits forever (seen: a test worker hung).
    ``sigtimedwait`` with a zero timeout takes it if it is still there and returns at once if not;
    where it is missing (macOS), the signal is unblocked instead and our handler, told by
    :func:`_bookkeeping` not to raise, takes it."""
    if hasattr(signal, "sigtimedwait"):
        signal.sigtimedwait({signal.SIGALRM}, 0)
    elif hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGALRM})
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})


def _unraisable(unraisable) -> None:
    """Drop an alarm that fell in a finaliser or a gc callback (Python would print it as "Exception
    ignored"): the reminder of :func:`_alarm` raises it again 0.1 s later, in the computation."""
    if unraisable.exc_type is OutOfTime:
        return
    (_previous[1] if len(_previous) > 1 else sys.__unraisablehook__)(unraisable)


@contextmanager
def _timed(scope: _Scope) -> Iterator[None]:
    """Interrupt the block at ``scope.at`` (no later than an enclosing scope); see :func:`timer_usable`."""
    depth = len(_scopes)
    try:
        with _bookkeeping():
            if not _scopes:
                _previous[:] = [signal.signal(signal.SIGALRM, _alarm), sys.unraisablehook]
                sys.unraisablehook = _unraisable
            else:
                scope.at = min(scope.at, _scopes[-1].at)
            _scopes.append(scope)
            _arm()
        yield
    finally:
        while True:
            try:
                with _bookkeeping():
                    del _scopes[depth:]  # this scope, and any inner one whose own exit was interrupted
                    _arm()
                    if not _scopes and _previous:
                        _settle()
                        handler, sys.unraisablehook = _previous
                        signal.signal(signal.SIGALRM, signal.SIG_DFL if handler is None else handler)
                        _previous.clear()
                break
            except OutOfTime:
                # an alarm handled before SIGALRM was held back (the reminder of an expired scope, 0.1 s after
                # it was raised: a process descheduled that long under load).  The scopes must still be
                # cleared and the handler restored, or a stale expired scope ends every later one and its
                # reminder fires outside (seen: a test worker's failure report interrupted).  Dropping it is
                # safe: _arm re-arms the timer for any enclosing scope whose deadline has passed.
                continue


def _mine(exc: OutOfTime, scope: _Scope) -> bool:
    """Whether ``exc`` ends ``scope``: raised for it, or for an inner scope that is gone (a late alarm)."""
    return exc.scope is scope or (exc.scope is not None and exc.scope not in _scopes)


def run_until(fn: Callable[[], Any], at: float, *, unbudgeted_ok: bool) -> tuple[bool, Any]:
    """(finished, result) of ``fn()``, interrupted at the instant ``at`` (:func:`time.monotonic`).

    Without a usable timer ``fn`` runs to its end if ``unbudgeted_ok`` (its own cooperative checks
    still apply), else not at all.  A deadline already passed returns (False, None) at once.
    :class:`OutOfTime` for an enclosing scope, or from a cooperative check, propagates.
    """
    if at <= time.monotonic():
        return False, None
    if not timer_usable():
        return (True, fn()) if unbudgeted_ok else (False, None)
    scope = _Scope(at)
    try:
        with _timed(scope):
            return True, fn()
    except OutOfTime as exc:
        if not _mine(exc, scope):
            raise
        return False, None


class Budget:
    """``seconds`` of wall-clock time from now for one decision; :attr:`doing` names the step under way."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.end = time.monotonic() + seconds
        self.doing = "starting"

    def left(self) -> float:
        """Seconds left (negative once spent)."""
        return self.end - time.monotonic()

    def expired(self) -> bool:
        return self.left() <= 0

    def check(self) -> None:
        """Raise :class:`OutOfTime` if the budget is spent (a cooperative check between steps)."""
        if self.expired():
            raise OutOfTime(budget=self)

    def run(self, doing: str, fn: Callable[[], Any]) -> Any:
        """``fn()``, a step the decision needs: :class:`OutOfTime` if the budget runs out during it."""
        self.doing = doing
        finished, result = run_until(fn, self.end, unbudgeted_ok=True)
        if not finished:
            raise OutOfTime(budget=self)
        return result

    def attempt(self, fn: Callable[[], Any], share: float = 1.0, *, unbudgeted_ok: bool) -> tuple[bool, Any]:
        """(finished, result) of an optional step given ``share`` of the time left (see :func:`run_until`);
        this budget's cooperative checks inside it end it too."""
        try:
            return run_until(fn, time.monotonic() + share * self.left(), unbudgeted_ok=unbudgeted_ok)
        except OutOfTime as exc:
            if exc.budget is not self:
                raise
            return False, None

    @contextmanager
    def backstop(self, slack: float) -> Iterator[None]:
        """Interrupt the block ``slack`` seconds after the budget's end, so that a step not run by
        :meth:`run` or :meth:`attempt` cannot overrun it by more (:class:`OutOfTime` propagates)."""
        if not timer_usable():
            yield
            return
        with _timed(_Scope(self.end + slack)):
            yield

    def spent(self, exc: OutOfTime) -> bool:
        """Whether ``exc`` ends this budget's decision: its own check, or a scope of it (gone once raised),
        not a scope of an enclosing caller (still armed)."""
        return exc.budget is self or (exc.scope is not None and exc.scope not in _scopes)
