"""The textbook catalog and `mechderive verify`: every claim is checked, and every check can fail."""

from __future__ import annotations

import json

import pytest
import sympy as sp

from mechderive.catalog.registry import all_claims, evaluate, perturb
from mechderive.cli import main

from .conftest import run_python

CLAIMS = all_claims()


def test_catalog_covers_the_foundation_equations():
    numbers = {c.equation.split()[0] for c in CLAIMS}
    for eq in ["3.1", "3.2", "3.5", "3.6", "3.7", "3.9", "3.10", "3.51", "3.52", "3.53", "3.54", "3.56",
               "3.57", "3.58"]:
        assert eq in numbers, f"({eq}) has no catalog entry"


@pytest.mark.parametrize("claim", CLAIMS, ids=[f"{c.equation}" for c in CLAIMS])
def test_claim_verified_or_documented_misprint(claim):
    result = evaluate(claim)
    assert result.status in ("verified", "misprint"), result.detail
    if claim.corrected is None:
        assert result.status == "verified", result.detail


@pytest.mark.parametrize("claim", CLAIMS, ids=[f"{c.equation}" for c in CLAIMS])
def test_check_fails_when_the_formula_is_perturbed(claim):
    # A check that passes a wrong formula is a defect: feed it one.
    wrong = claim.perturbed() if claim.perturbed is not None else perturb(claim.printed())
    assert not claim.check(wrong).passed


def test_perturb_changes_identically_zero_entries():
    x = sp.Symbol("x")
    m = sp.Matrix([[sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1, 1]])
    assert sp.simplify(perturb(m)[0] - m[0]) != 0


def test_verify_json_rows(capsys):
    code = main(["verify", "--section", "3.5", "--json"])
    rows = json.loads(capsys.readouterr().out)
    assert code == 0
    assert rows and {"equation", "section", "claim", "method", "status", "seconds"} <= set(rows[0])
    assert all(r["section"].startswith("3.5") for r in rows)
    assert {r["equation"] for r in rows} >= {"3.54", "3.58"}


def test_verify_unknown_section_is_an_input_error(capsys):
    assert main(["verify", "--section", "9.9"]) == 2
    assert "expected a section among" in capsys.readouterr().err


def test_verify_exits_nonzero_when_a_claim_fails(monkeypatch, capsys):
    from mechderive.catalog import registry

    bad = registry.Claim("0.0", "3.1", "a false claim", "symbolic", printed=lambda: sp.Integer(1),
                         check=lambda f: registry.Outcome(f == 2, "1 ≠ 2"))
    monkeypatch.setattr(registry, "_REGISTRY", registry._REGISTRY + [bad])
    assert main(["verify", "--section", "3.1"]) == 1
    assert "failed" in capsys.readouterr().out


def test_verify_console_table_runs():
    proc = run_python("-m", "mechderive.cli", "verify", "--section", "3.5")
    assert proc.returncode == 0, proc.stderr
    assert "verified" in proc.stdout and "(3.54)" not in proc.stderr
