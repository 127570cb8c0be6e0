"""``mechderive check SYSTEM --file FILE``: many claims in one process, a summary, the worst exit status.

The claims are the chapter's: E, p_φ conserved on every motion (3.64)-(3.65), p_ψ = I3(ψ̇ + cos θ φ̇)
an identity (3.63), and the free body's Euler equation (3.33) false for the heavy top.
"""

from __future__ import annotations

import io
import json

import pytest

from mechderive.cli import main

CLAIMS = """\
# the heavy top's conserved quantities (3.63)-(3.65)
dt(E) = 0                # on every motion

dt(p_phi) = 0
p_psi = I3*(psi_dot + cos(theta)*phi_dot)
"""


def _write(tmp_path, text, name="claims.txt"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_claims_that_hold_exit_0_with_a_summary(tmp_path, capsys):
    assert main(["check", "heavy_top", "--file", _write(tmp_path, CLAIMS)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in out[:3]] == [["2", "on-shell"], ["4", "on-shell"], ["5", "identity"]]
    assert out[-1].startswith("3 claims in ") and out[-1].endswith("2 on-shell, 1 identity")


def test_the_worst_verdict_sets_the_status_and_a_bad_line_is_only_that_line(tmp_path, capsys):
    false = CLAIMS + "I1*dt(omega1) = 0\n"
    assert main(["check", "heavy_top", "--file", _write(tmp_path, false)]) == 1
    capsys.readouterr()
    assert main(["check", "heavy_top", "--file", _write(tmp_path, false + "E = = 0\n"), "--json"]) == 2
    report = json.loads(capsys.readouterr().out)
    assert [r["verdict"] for r in report["claims"]] == ["on-shell", "on-shell", "identity", "false", "error"]
    assert report["claims"][-1]["line"] == 7 and "exactly one '='" in report["claims"][-1]["detail"]
    assert report["summary"] == {"on-shell": 2, "identity": 1, "false": 1, "error": 1}


def test_stdin_and_refusals(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO("dt(E) = 0\n"))
    assert main(["check", "heavy_top", "--file", "-"]) == 0
    capsys.readouterr()
    for argv, message in [
        (["--file", _write(tmp_path, "# nothing\n\n", "empty.txt")], "expected at least one claim"),
        (["--file", _write(tmp_path, "E = E\n" * 1001, "long.txt")], "expected at most 1000 claims, got 1001"),
        (["--file", "/dev/zero"], "expected a regular file, got a character device"),
        (["dt(E) = 0", "--file", _write(tmp_path, CLAIMS)], "expected either a CLAIM or --file"),
    ]:
        assert main(["check", "heavy_top", *argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err
