"""Issue 12, ``mechderive check``: every budget enforced end to end, odd input a clear outcome, errors named.

The issue's reproductions (findings 4, 5 and 7) through the command line in-process, each with
its time measured: the decision (everything after the one-time derivation of the system's
model, which :meth:`~mechderive.formulas.systems.System.prepare` does before the clock starts)
must end within ``--budget`` + 1 s (measured: at most +0.05 s on an idle machine; the tests allow
:data:`~.test_fuzz_formulas.TEST_SLACK`).  Then the machinery of :mod:`mechderive.formulas.budget`
itself (nested scopes, the handler and timer restored, someone else's timer left alone, an
alarm falling in a finaliser, threads), the size limits on --given names, and, marked slow,
the worst claims in a fresh process under a 1 GB address-space limit.

Before the fix (measured on this branch's parent): ``dt(dt(dt(dt(dt(E))))) = 0`` ran 46 s with the
default 5 s budget; chains of --given names ran past 30 s (stopped by a watchdog), one grew the
process by 2.1 GB, one ended in an OverflowError (exit 70); error messages named neither the
claim nor the option.
"""

from __future__ import annotations

import gc
import resource
import signal
import subprocess
import sys
import threading
import time

import pytest

from mechderive.cli import main
from mechderive.formulas import check
from mechderive.formulas.budget import Budget, OutOfTime, run_until, timer_usable

from ..conftest import ROOT
from .test_fuzz_formulas import TEST_SLACK, problems, run_case

DT5 = "dt(dt(dt(dt(dt(E))))) = 0"  # its expansion along the motion alone takes ~15 s (800 000 nodes)
COSH13 = "cosh(" * 13 + "Lagrangian" + ")" * 13 + " = a + b"  # every point overflows, slowly


def _decided(system: str, claim: str, budget: float, given: tuple = ()) -> tuple:
    """(exit status, stdout, stderr) of ``mechderive check``, asserting the generic rules and the time."""
    o = run_case(system, claim, list(given), budget)
    assert not problems(o, budget, TEST_SLACK), (problems(o, budget, TEST_SLACK), o)
    assert o.seconds - o.prepared <= budget + TEST_SLACK  # (problems() checks it too; here it is the point)
    return o.status, o.out, o.err


# --- finding 4: hangs -------------------------------------------------------------------------------


@pytest.mark.parametrize("claim, budget, status, says", [
    # a counterexample at the first point: exp(exp(exp(exp(0.6463)))) = 1.7e352, not 1
    ("exp(exp(exp(exp(theta)))) = 1", 5, 1, "false (numeric)"),
    # the expansion along the motion does not fit in 0.3 s (nor in 5 s)
    (DT5, 0.3, 3, "the time budget of 0.3 s (--budget) ran out while"),
    # each point is refused for overflow; the budget ends the search
    (COSH13, 0.3, 3, "undecided"),
    # ten dt of u_ddot: the formal expansion alone outgrows the budget
    ("dt(" * 10 + "u_ddot" + ")" * 10 + " = atan(E) + (E_prime)**(1/2)", 0.3, 3, "undecided"),
])
def test_hangs_end_within_the_budget(claim, budget, status, says):
    got, out, _ = _decided("heavy_top", claim, budget)
    assert got == status and says in out, out


def test_the_budget_is_the_whole_decision():
    # expanding dt⁴(E) along the motion (72 000 nodes) alone takes about 1 s: undecided, saying where the
    # time went; with the default 5 s it is decided (on-shell)
    v = check("dt(dt(dt(dt(E)))) = 0", budget=0.1)
    assert v.verdict == "undecided" and v.detail.startswith("the time budget of 0.1 s (--budget) ran out while ")


def test_no_proof_outside_the_main_thread():
    """Without a timer (a thread) only checks between steps apply: no proof is attempted."""
    assert not _in_thread(timer_usable)
    v = _in_thread(lambda: check("dt(E) = 0"))
    assert (v.verdict, v.method) == ("on-shell", "numeric")  # the trig normal form would need a timer


@pytest.mark.slow
@pytest.mark.parametrize("claim, budget, says", [
    (DT5, 0.5, "the time budget of 0.5 s (--budget) ran out while"),
    # the expansion stops at 10 000 nodes (dt⁴(E) along the motion has 72 000), whatever the budget
    ("dt(dt(dt(dt(E)))) = 0", 30, "along the motion gives an expression of more than 10000 nodes"),
])
def test_size_limits_outside_the_main_thread(claim, budget, says):
    start = time.monotonic()
    v = _in_thread(lambda: check(claim, budget=budget))
    # measured 2.4 s and 3.3 s on a loaded machine: one differentiation of at most 10 000 nodes past a check
    assert v.verdict == "undecided" and says in v.detail and time.monotonic() - start < budget + 6, v


def _in_thread(fn):
    out = []
    t = threading.Thread(target=lambda: out.append(fn()), daemon=True)
    t.start()
    t.join(60)
    assert out, "the thread did not finish within 60 s"
    return out[0]


# --- finding 5: crashes on odd input ---------------------------------------------------------------


@pytest.mark.parametrize("claim, status, says", [
    ("sinh(sinh(sinh(sinh(sinh(theta))))) = 0", 1, "false"),   # 1.05 at θ ≈ 0.65: simply false
    # sinh³(3) ≈ 10^4783, and its sinh is beyond the evaluator's range 10^±10000
    ("sinh(sinh(sinh(sinh(sinh(3))))) = 0", 3, "overflow: sinh(sinh(sinh(sinh(3)))) is beyond 10^10000"),
    ("exp(exp(1000)) = exp(exp(1000) + 1e-100)", 3, "overflow: exp(exp(1000)) is beyond 10^10000"),
    ("sqrt(-1 - theta_dot**2) = 1", 3, "non-real value"),
    # SymPy evaluates constants as it builds them: mpmath was asked for 1 << 10^k (MemoryError, exit 70)
    ("sinh(sinh(sinh(sinh(sinh(sinh(sinh(sinh(sinh(sinh(30)))))))))) = 0", 2,
     "expected an expression SymPy can build, got MemoryError: a number too large to hold"),
])
def test_overflow_and_odd_values_are_clear_outcomes(claim, status, says):
    got, out, err = _decided("heavy_top", claim, 5)  # (decided long before: all 200 points in well under 1 s)
    assert got == status and says in out + err, out + err


@pytest.mark.parametrize("system, given, says", [
    # each name squares the last: 900 · 2^k digits without the limit (a minute of multiplication at k = 20)
    ("heavy_top", [f"x0 = {'9' * 900}"] + [f"x{k} = x{k - 1}*x{k - 1}" for k in range(1, 20)],
     "--given 'x1 = x0*x0': expected numbers below 10^1000 in the value of x1, got one of about 1800 digits"),
    # each name uses the last three times: a tree of about 3^k nodes
    ("heavy_top", ["x0 = phi"] + [f"x{k} = sin(x{k - 1}) + cos(x{k - 1})*x{k - 1}" for k in range(1, 15)],
     "--given 'x9 = sin(x8) + cos(x8)*x8': expected the value of x9 of at most 20000 nodes"),
    # powers combine beyond the parser's exponent limit
    ("heavy_top", ["x0 = theta**100", "x1 = x0*x0"],
     "--given 'x1 = x0*x0': expected exponents p/q with |p|, q ≤ 100"),
    ("free_top", ["I2 = I1**100", "I3 = I2**100"], "--given 'I3 = I2**100': expected exponents p/q"),
    # nesting beyond what SymPy's recursive algorithms survive once dt is expanded (RecursionError, exit 70)
    ("heavy_top", ["x0 = " + "sin(" * 38 + "theta" + ")" * 38, "x1 = " + "sin(" * 38 + "x0" + ")" * 38],
     "--given 'x1 = sin(sin(sin(sin(sin(sin(sin(sin(sin…': expected the value of x1 nested at most 60 deep"),
    # SymPy's own error while building (atan2(0, zoo): "Invalid NaN comparison", exit 70)
    ("free_top", ["x = atan2(0, log(0))"], "--given 'x = atan2(0, log(0))': expected an expression SymPy can build, "
                                           "got TypeError: Invalid NaN comparison"),
])
def test_given_chains_are_refused(system, given, says):
    status, out, err = _decided(system, "E = E" if system == "heavy_top" else "T = T", 5, tuple(given))
    assert status == 2 and err.startswith("mechderive: error: " + says), err


def test_given_values_that_overflow_refuse_the_draw():
    # the solvers' validators get ±inf, not an OverflowError; sp.N(exp(exp(exp(I1)))) is never computed
    v = check("I2 = 0", "free_top", given=["I2 = exp(exp(exp(exp(I1))))"], budget=5)
    assert v.verdict == "undecided" and "overflow" in v.detail, v
    v = check("I2 = 0", "free_top", given=["I2 = 10**100*10**100*10**100*10**100*I1"], budget=5)  # 1e400 I1
    assert v.verdict == "undecided" and "the --given values make a body the solvers refuse" in v.detail, v


# --- finding 7: options anywhere, errors naming the argument --------------------------------------


@pytest.mark.parametrize("argv", [
    ["check", "heavy_top", "E = E", "--budget", "2"],
    ["check", "heavy_top", "--budget", "2", "E = E"],
    ["check", "--budget", "2", "--json", "heavy_top", "E = E"],
    ["check", "heavy_top", "E = E", "--points", "30", "--seed", "3", "--any-moments"],
    ["check", "heavy_top", "--", "-E = -E"],
    ["check", "heavy_top", "-E = -E", "--budget", "2"],  # a claim with a space is never taken for an option
])
def test_options_after_the_positionals(argv, capsys):
    assert main(argv) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("argv, line", [
    (["check", "heavy_top", "E = foo"], "mechderive: error: claim 'E = foo': expected a known symbol, got unknown "
                                         "symbol 'foo'"),
    (["check", "heavy_top", "E = E", "--given", "x = 1 +"], "mechderive: error: --given 'x = 1 +': expected a "
                                                             "formula in plain maths syntax"),
    (["check", "heavy_top", "E = E", "--given", "E = 1"], "mechderive: error: --given 'E = 1': expected a new name "
                                                           "or a state variable or parameter to specialise"),
    (["check", "heavy_top", "E = E", "--budget", "0"], "mechderive: error: --budget: expected a time of more than 0 "
                                                        "and at most 600 seconds, got 0.0"),
    (["check", "heavy_top", "E = E", "--budget", "nan"], "mechderive: error: --budget: expected a time"),
    (["check", "heavy_top", "E = E", "--points", "5"], "mechderive: error: --points: expected an integer between "
                                                        "20 and 1000, got 5"),
    (["check", "spinning", "E = E"], "mechderive: error: SYSTEM: expected a system among free_top, heavy_top, "
                                     "rigid_body, got 'spinning'"),
    (["check", "heavy_top"], "mechderive: error: CLAIM: expected a claim like 'dt(E) = 0'"),
    (["check", "heavy_top", "__import__('os').system('echo hi') = 0"],
     "mechderive: error: claim \"__import__('os').system('echo hi') = 0\": expected a call of one of sin"),
])
def test_errors_name_the_argument(argv, line, capsys):
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and captured.err.startswith(line), captured.err


def test_json_errors_name_the_argument(capsys):
    assert main(["check", "heavy_top", "E = E", "--given", "2x = 1", "--json"]) == 2
    assert '"detail": "--given \'2x = 1\': expected \'name = expression\' with a plain name' in capsys.readouterr().out


# --- the budget machinery ---------------------------------------------------------------------------


def _spin(seconds: float) -> str:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass
    return "done"


def test_nested_scopes_and_restoration():
    before = signal.getsignal(signal.SIGALRM), sys.unraisablehook
    start = time.monotonic()

    def outer():
        inner = run_until(lambda: _spin(5), time.monotonic() + 0.1, unbudgeted_ok=True)
        return inner, _spin(0.05)

    assert run_until(outer, time.monotonic() + 2, unbudgeted_ok=True) == (True, ((False, None), "done"))
    assert time.monotonic() - start < 1  # the inner spin was cut at 0.1 s
    # the outer deadline cuts an inner scope that asked for more
    assert run_until(lambda: run_until(lambda: _spin(5), time.monotonic() + 5, unbudgeted_ok=True),
                     time.monotonic() + 0.1, unbudgeted_ok=True) == (False, None)
    assert (signal.getsignal(signal.SIGALRM), sys.unraisablehook) == before
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert run_until(lambda: _spin(1), time.monotonic() - 1, unbudgeted_ok=True) == (False, None)  # already late


def test_an_alarm_on_the_way_out_still_restores_everything(monkeypatch):
    """An alarm handled as a scope ends but before SIGALRM is held back (a reminder 0.1 s after an expired scope, the
    process descheduled that long) must not leave the scope armed: a stale expired scope ended every later one and
    its reminder fired outside, during a test worker's failure report.  Simulated: the exit's bookkeeping is
    interrupted once, as by that alarm."""
    from contextlib import contextmanager

    from mechderive.formulas import budget

    real, entries = budget._bookkeeping, []

    @contextmanager
    def interrupted_once():
        entries.append(len(budget._scopes))
        if len(entries) == 2:  # the scope's exit (the first entry armed it)
            raise budget.OutOfTime(budget._scopes[-1])
        with real():
            yield

    monkeypatch.setattr(budget, "_bookkeeping", interrupted_once)
    before = signal.getsignal(signal.SIGALRM), sys.unraisablehook
    assert run_until(lambda: "done", time.monotonic() + 5, unbudgeted_ok=True) == (True, "done")
    assert len(entries) == 3  # interrupted, then done again
    assert budget._scopes == [] and (signal.getsignal(signal.SIGALRM), sys.unraisablehook) == before
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


def test_an_alarm_another_thread_took_is_not_waited_for(monkeypatch):
    """The outermost scope's end takes a SIGALRM still pending.  One that ``sigpending`` showed may be
    taken by another thread before it is waited for (xdist's and Dask's threads do not block it): a
    blocking ``sigwait`` then hung a test worker for good.  Here the signal is seen and gone; a thread
    sends one after 2 s so that a blocking wait ends, and fails the time check, instead of hanging."""
    from mechderive.formulas import budget

    previous = signal.signal(signal.SIGALRM, lambda *_: None)
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})
    rescue = threading.Timer(2.0, signal.pthread_kill, (threading.main_thread().ident, signal.SIGALRM))
    try:
        monkeypatch.setattr(signal, "sigpending", lambda: {signal.SIGALRM})
        rescue.start()
        start = time.monotonic()
        budget._settle()
        assert time.monotonic() - start < 1
    finally:
        rescue.cancel()
        rescue.join()
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
        signal.signal(signal.SIGALRM, previous)


def test_someone_elses_timer_is_left_alone():
    fired = []
    previous = signal.signal(signal.SIGALRM, lambda *_: fired.append(1))
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.1)
        assert not timer_usable()
        assert run_until(lambda: "ran", time.monotonic() + 0.01, unbudgeted_ok=True) == (True, "ran")
        assert run_until(lambda: "ran", time.monotonic() + 0.01, unbudgeted_ok=False) == (False, None)
        time.sleep(0.2)
        assert fired == [1]  # their alarm, at their time
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


class _SlowFinaliser:
    def __del__(self):
        _spin(0.1)  # the alarm falls in here, where Python cannot raise it


def test_an_alarm_in_a_finaliser_is_raised_again(capfd):
    def work():
        x = _SlowFinaliser()
        del x  # 0.1 s in __del__: the alarm at 0.05 s is dropped there...
        return _spin(5)  # ...and raised again 0.1 s later, here

    start = time.monotonic()
    assert run_until(work, time.monotonic() + 0.05, unbudgeted_ok=True) == (False, None)
    assert time.monotonic() - start < 1
    assert "Exception ignored" not in capfd.readouterr().err
    gc.collect()


def test_an_enclosing_callers_budget_is_not_taken_for_the_claims():
    # check() inside someone's run_until: their deadline interrupts check, which lets it through
    assert run_until(lambda: check(DT5, budget=30), time.monotonic() + 0.2, unbudgeted_ok=True) == (False, None)
    clock = Budget(0.01)
    time.sleep(0.02)
    with pytest.raises(OutOfTime):
        clock.check()
    assert clock.attempt(lambda: clock.check(), unbudgeted_ok=True) == (False, None)


# --- in a fresh process, under a memory limit ------------------------------------------------------------


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))  # the bound: 1 GB of address space


@pytest.mark.slow
@pytest.mark.parametrize("claim, given", [
    (DT5, []),
    (COSH13, []),
    ("dt(" * 10 + "u_ddot" + ")" * 10 + " = 0", []),
    ("x14 = 0", ["x0 = -(-(cosh(748887)))"] + [f"x{k} = sin(x{k - 1}) + cos(x{k - 1})*x{k - 1}" for k in range(1, 15)]),
    ("I1 = 0", [f"x0 = {'9' * 900}"] + [f"x{k} = x{k - 1}*x{k - 1}" for k in range(1, 20)]),
])
def test_worst_claims_in_a_fresh_process(claim, given):
    """The CLI in a new process, 1 GB of address space: exit 3 or 2 in one line, within the budget plus start-up."""
    budget = 3
    argv = [sys.executable, "-m", "mechderive", "check", "heavy_top", "--budget", str(budget),
            *(f"--given={g}" for g in given), "--", claim]
    start = time.monotonic()
    proc = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=120, preexec_fn=_limit_memory,
                          env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    seconds = time.monotonic() - start
    assert proc.returncode in (2, 3), proc
    assert "Traceback" not in proc.stderr and (proc.returncode == 3 or proc.stderr.count("\n") == 1), proc.stderr
    # start-up (~1 s) and the model's derivation (~1-5 s on a loaded machine) come before the budget
    assert seconds < budget + TEST_SLACK + 15, seconds
