"""The textbook catalog and `mechderive verify`: every claim is checked, and every check can fail."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
import sympy as sp

from mechderive.catalog.checks import same
from mechderive.catalog.registry import Claim, Outcome, all_claims, evaluate, member_of, perturb
from mechderive.cli import main

from .conftest import verified

CLAIMS = all_claims()


def test_catalog_covers_the_foundation_equations():
    numbers = {c.equation.split()[0] for c in CLAIMS}
    for eq in ["3.1", "3.2", "3.5", "3.6", "3.7", "3.9", "3.10", "3.51", "3.52", "3.53", "3.54", "3.56",
               "3.57", "3.58"]:
        assert eq in numbers, f"({eq}) has no catalog entry"


@pytest.mark.parametrize("claim", CLAIMS, ids=[f"{c.equation}" for c in CLAIMS])
def test_claim_verified_or_documented_misprint(claim, claims_checked_once):
    result = verified(claim)
    assert result.status in ("verified", "misprint", "constructed"), result.detail
    if claim.constructed is not None:
        assert result.status == "constructed" and result.note == claim.constructed, result.detail
    elif claim.corrected is None:
        assert result.status == "verified", result.detail


# One case per member of every claim: for a misprint the members of the corrected form (the form
# that passes), otherwise those of the printed one.
MEMBERS = [(c, k) for c in CLAIMS for k in range(len(c.member_names()))]


@functools.cache
def _passing_form(claim):
    # Built once per claim and session: a formula is perturbed member by member, never rebuilt.
    return claim.passing_form()


@functools.cache
def _wrong_forms(claim):
    return claim.wrong_forms(_passing_form(claim))


@pytest.mark.parametrize("claim,k", MEMBERS,
                         ids=[c.equation + ("" if not c.parts else f" [{c.parts[k]}]") for c, k in MEMBERS])
def test_check_fails_when_a_member_is_perturbed(claim, k):
    # A check that passes a wrong formula is a defect: feed it one, one member at a time.
    name, wrong = _wrong_forms(claim)[k]
    right = _passing_form(claim)
    # structural inequality (repr of §3.7's long matrices took a second a test; the two agree on every claim)
    assert wrong != right, f"the perturbation left {name} unchanged"
    outcome = claim.check(wrong)
    assert not outcome.passed, f"{'corrected' if claim.corrected else 'printed'} form with {name} perturbed " \
                               f"passes: {outcome.detail}"


@pytest.mark.slow
@pytest.mark.parametrize("claim", CLAIMS, ids=[c.equation for c in CLAIMS])
def test_check_fails_when_any_entry_of_a_matrix_member_is_perturbed(claim):
    # The default run perturbs each member's first entry; this sweep (~2 min) perturbs every other entry of
    # every matrix member too, so an entry the check skips cannot hide.
    right = _passing_form(claim)
    for k, name in enumerate(claim.member_names()):
        part = member_of(right, k)
        for e in range(1, len(part) if isinstance(part, sp.MatrixBase) else 1):
            outcome = claim.check(perturb(right, k, entry=e) if claim.parts else perturb(right, entry=e))
            assert not outcome.passed, f"{name} with entry {e} perturbed passes: {outcome.detail}"


def test_a_check_that_ignores_a_member_is_caught():
    # The member-by-member perturbation is what exposes such a check; the whole-formula one does not.
    x = sp.Symbol("x")
    claim = Claim("0.0", "3.1", "two formulas, one checked", "symbolic", printed=lambda: (x, x**2),
                  check=lambda f: same(f[0], x), parts=("x", "x²"))
    assert not claim.check(perturb(claim.printed())).passed
    assert [claim.check(wrong).passed for _, wrong in claim.wrong_forms()] == [False, True]


def test_undeclared_members_are_refused():
    # A formula with several members must name them (parts), so that each one is perturbed.
    x = sp.Symbol("x")
    claim = Claim("0.0", "3.1", "two formulas, undeclared", "symbolic", printed=lambda: (x, x),
                  check=lambda f: same(sp.Matrix(f), sp.Matrix([x, x])))
    with pytest.raises(ValueError, match="expected 1 members"):
        claim.wrong_forms()


def test_misprint_entries_perturb_their_corrected_form():
    misprints = [c for c in CLAIMS if c.corrected is not None]
    assert {c.equation for c in misprints} >= {"3.16", "3.102", "3.103"}
    for c in misprints:
        assert c.corrected is not None and _passing_form(c) == c.corrected()


def _falling_cat_claim():
    return next(c for c in CLAIMS if c.equation == "3.7 (falling cat)")


def test_falling_cat_is_constructed_with_zero_L_as_evidence():
    result = evaluate(_falling_cat_claim())
    assert result.status == "constructed", result.detail
    assert "by construction" in result.note and "root-found" in result.note and "L = 0" in result.note
    assert result.detail.startswith("evidence: max |L| =")
    assert result.as_dict()["note"] == result.note


def test_falling_cat_fails_when_L_is_not_zero(monkeypatch):
    # Plant a perturbation in the run: the representatives are turned by ε·bend about e1 (a gauge change
    # (3.88)) while Ω and hence R stay as derived.  R still closes to the half turn (the constructed part
    # cannot tell), but r_i = R r̃_i now has L ≈ ε Ĩ_11 β̇ ≠ 0, which the evidence must catch.
    from mechderive.catalog import s3_7_deformable
    from mechderive.systems.deformable.cat import falling_cat
    from mechderive.systems.deformable.connection import ShapeConnection

    original, eps = ShapeConnection.positions, 1e-3

    def regauged(self, x):
        a = eps * np.asarray(x, dtype=float)[..., 0]
        c, s, one, zero = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
        S = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, c, -s], -1), np.stack([zero, s, c], -1)], -2)
        return np.einsum("...ab,...ib->...ia", S, original(self, x))

    monkeypatch.setattr(ShapeConnection, "positions", regauged)
    planted = falling_cat(samples=41)
    monkeypatch.undo()
    assert abs(planted.flip_angle[-1] - np.pi) < 1e-8  # the flip is untouched by the plant
    monkeypatch.setattr(s3_7_deformable, "_cat_run", lambda: planted)
    claim = _falling_cat_claim()
    outcome = claim.check(claim.printed())
    assert not outcome.passed and "max |L|" in outcome.detail, outcome.detail
    assert evaluate(claim).status == "failed"


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


def _only(monkeypatch, *claims):
    """Make `mechderive verify` see ``claims`` alone (no real check runs: these tests are about the CLI)."""
    from mechderive.catalog import registry

    monkeypatch.setattr(registry, "all_claims", lambda section=None: list(claims))


def test_verify_exits_nonzero_when_a_claim_fails(monkeypatch, capsys):
    bad = Claim("0.0", "3.1", "a false claim", "symbolic", printed=lambda: sp.Integer(1),
                check=lambda f: Outcome(f == 2, "1 ≠ 2"))
    _only(monkeypatch, bad)
    assert main(["verify", "--section", "3.1"]) == 1
    assert "failed" in capsys.readouterr().out


def test_verify_constructed_is_not_a_failure(monkeypatch, capsys):
    made = Claim("0.0", "3.1", "a claim made true", "numeric", printed=lambda: sp.Integer(1),
                 check=lambda f: Outcome(f == 1, "an independent measurement agrees"),
                 constructed="the parameter was chosen to make it hold")
    plain = Claim("0.1", "3.1", "a true claim", "symbolic", printed=lambda: sp.Integer(1),
                  check=lambda f: Outcome(f == 1, "1 = 1"))
    _only(monkeypatch, made, plain)
    assert main(["verify", "--section", "3.1"]) == 0
    out = capsys.readouterr().out
    assert "2 claims: 1 verified, 0 misprint, 1 constructed, 0 failed" in out
    assert "(0.0) constructed — the parameter was chosen to make it hold; evidence: an independent" in out
    assert main(["verify", "--section", "3.1", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [(r["status"], r["note"]) for r in rows] == [("constructed", "the parameter was chosen to make it hold"),
                                                        ("verified", "")]


def test_verify_console_table_runs(claims_checked_once, capsys):
    # in this process, on the session's verdicts (the command line as a fresh process: test_cli)
    assert main(["verify", "--section", "3.5", "--fresh"]) == 0
    out = capsys.readouterr()
    assert "verified" in out.out and "(3.54)" not in out.out + out.err


def test_verify_jobs_gives_the_same_rows_in_the_same_order(capsys):
    rows = {}
    for jobs in ("1", "2"):
        assert main(["verify", "--section", "3.4", "--json", "--jobs", jobs, "--fresh"]) == 0
        rows[jobs] = [{k: v for k, v in r.items() if k != "seconds"} for r in json.loads(capsys.readouterr().out)]
    assert rows["1"] == rows["2"] and len({r["section"] for r in rows["1"]}) > 1  # several sections, two processes
    assert main(["verify", "--jobs", "0"]) == 2
    assert "--jobs: expected an integer in [1, 64], got 0" in capsys.readouterr().err


def test_verify_replays_an_unchanged_packages_table_and_fresh_checks_again(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    assert main(["verify", "--section", "3.3", "--jobs", "1"]) == 0
    first = capsys.readouterr()
    assert main(["verify", "--section", "3.3", "--jobs", "2"]) == 0  # --jobs does not change the table
    again = capsys.readouterr()
    assert again.out == first.out and "replayed from the disk cache" in again.err
    assert main(["verify", "--section", "3.3", "--fresh"]) == 0
    fresh = capsys.readouterr()
    assert "replayed" not in fresh.err and fresh.out.splitlines()[-1] == first.out.splitlines()[-1].replace(
        first.out.splitlines()[-1].rsplit(" in ", 1)[1], fresh.out.splitlines()[-1].rsplit(" in ", 1)[1])


def test_a_changed_catalog_is_not_replayed(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MECHDERIVE_NO_DISK_CACHE", raising=False)
    assert main(["verify", "--section", "3.3", "--jobs", "1"]) == 0
    capsys.readouterr()
    plain = Claim("0.1", "3.3", "a true claim", "symbolic", printed=lambda: sp.Integer(1),
                  check=lambda f: Outcome(f == 1, "1 = 1"))
    _only(monkeypatch, plain)
    assert main(["verify", "--section", "3.3", "--jobs", "1"]) == 0
    out = capsys.readouterr()
    assert "replayed" not in out.err and "1 claims:" in out.out
