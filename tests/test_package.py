"""Package-level promises: a light import, a small public API, and runnable derivation scripts."""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import pytest

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
    a minute.  Each script is still run whole, from its first line, as ``__main__``.
    """
    monkeypatch.setattr(sys, "argv", [str(script), *args])
    runpy.run_path(str(script), run_name="__main__")
    return capsys.readouterr().out


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_derivation_script_runs(script: Path, monkeypatch, capsys):
    out = _run_script(script, monkeypatch, capsys)
    assert out.strip(), "the script printed nothing"
    assert "failed" not in out.replace("0 failed", "")


@pytest.mark.parametrize("script", SCRIPTS[:1], ids=[p.name for p in SCRIPTS[:1]])
def test_derivation_script_latex(script: Path, monkeypatch, capsys):
    assert "\\begin{equation}" in _run_script(script, monkeypatch, capsys, "--latex")
