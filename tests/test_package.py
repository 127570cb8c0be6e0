"""Package-level promises: a light import, a small public API, and runnable derivation scripts."""

from __future__ import annotations

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


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_derivation_script_runs(script: Path):
    proc = run_python(str(script))
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "failed" not in proc.stdout.replace("0 failed", "")


@pytest.mark.parametrize("script", SCRIPTS[:1], ids=[p.name for p in SCRIPTS[:1]])
def test_derivation_script_latex(script: Path):
    proc = run_python(str(script), "--latex")
    assert proc.returncode == 0, proc.stderr
    assert "\\begin{equation}" in proc.stdout
