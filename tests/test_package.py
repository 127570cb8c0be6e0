"""Package-level promises: a light import, a small public API, and runnable derivation scripts."""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import pytest

from ._package_sources import syntax_tree
from .conftest import ROOT, run_python

SCRIPTS = sorted((ROOT / "derivations").glob("s*.py"))


def test_import_is_light():
    code = ("import sys, mechderive; "
            "heavy = [m for m in ('sympy', 'matplotlib', 'scipy') if m in sys.modules]; "
            "print(','.join(heavy))")
    proc = run_python("-c", code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ""


def test_public_names_resolve_lazily():
    import mechderive

    for name in mechderive.__all__:
        assert getattr(mechderive, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        mechderive.nope  # noqa: B018


def _run_script(script: Path, monkeypatch, capsys, *args: str) -> str:
    """Run a derivation script as ``python script *args`` would, in this process.

    In-process rather than a subprocess so that the derivations the rest of the session has
    already made (SymPy models are cached per process) are shared: the scripts cost seconds, not
    a minute; with ``claims_checked_once`` the catalog's verdicts are too (test_catalog checks each claim).
    Each script is still run whole, from its first line, as ``__main__``.
    """
    monkeypatch.setattr(sys, "argv", [str(script), *args])
    runpy.run_path(str(script), run_name="__main__")
    return capsys.readouterr().out


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_derivation_script_runs(script: Path, monkeypatch, capsys, claims_checked_once):
    out = _run_script(script, monkeypatch, capsys)
    assert out.strip(), "the script printed nothing"
    assert "failed" not in out.replace("0 failed", "")


@pytest.mark.parametrize("script", SCRIPTS[:1], ids=[p.name for p in SCRIPTS[:1]])
def test_derivation_script_latex(script: Path, monkeypatch, capsys, claims_checked_once):
    assert "\\begin{equation}" in _run_script(script, monkeypatch, capsys, "--latex")


# Raises of built-in exception types that a user could meet and that are still to be turned into
# MechDeriveError subclasses: none are left (issue 11), and the test keeps it so.
_BUILTIN_RAISES_TO_CONVERT: set[tuple[str, str]] = set()
_BUILTIN_EXCEPTIONS = {"ValueError", "TypeError", "RuntimeError", "ZeroDivisionError", "ArithmeticError",
                       "OverflowError", "FloatingPointError", "KeyError", "IndexError", "LookupError",
                       "AssertionError", "NotImplementedError", "Exception", "OSError"}


def test_no_new_raise_of_a_builtin_exception():
    """Every error that reaches a user is a MechDeriveError subclass; no `assert` validates input."""
    import ast

    package = ROOT / "mechderive"
    found = []
    for path in sorted(package.rglob("*.py")):
        rel = path.relative_to(package).as_posix()
        for node in ast.walk(syntax_tree(path)):
            if isinstance(node, ast.Assert):
                found.append(f"{rel}:{node.lineno}: assert (removed by python -O)")
            elif isinstance(node, ast.Raise) and node.exc is not None:
                exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
                name = exc.id if isinstance(exc, ast.Name) else None
                if name in _BUILTIN_EXCEPTIONS and (rel, name) not in _BUILTIN_RAISES_TO_CONVERT:
                    found.append(f"{rel}:{node.lineno}: raise {name}")
    assert not found, "raise a mechderive.errors class instead:\n" + "\n".join(found)


def test_former_value_errors_are_mechderive_errors():
    import mpmath
    import sympy as sp

    from mechderive.core.symbols import coordinate, t, to_state_symbols
    from mechderive.errors import InvalidInputError
    from mechderive.special.highprec import complete_pi_mp

    with pytest.raises(InvalidInputError, match=r"expected n < 1 and 0 < m1 <= 1, got n = 2\.0, m1 = 0\.5"):
        complete_pi_mp(mpmath.mpf(2), mpmath.mpf("0.5"))
    with pytest.raises(InvalidInputError, match=r"expected derivatives of order <= 2, got order 3 in "):
        to_state_symbols(sp.diff(coordinate("phi"), t, 3))
    assert issubclass(InvalidInputError, ValueError)  # callers catching ValueError keep working
