"""``mechderive check``: formulas from the chapter and other standard treatments, right and wrong.

Every case states its source and the verdict it must get: identities (after the systems'
derived definitions are substituted), on-shell claims (true along every motion), and
deliberately wrong variants (a sign, a factor 2, a swapped moment) that must come out false
with a counterexample.  Then the safe parser against hostile input, the --given rules, and
the command line's exit statuses.
"""

from __future__ import annotations

import gc
import json
import random
import time
from fractions import Fraction

import mpmath
import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError
from mechderive.formulas import check, get_system, parse_claim, parse_expression
from mechderive.formulas.check import EXIT_STATUS

HEAVY = "heavy_top"
FREE = "free_top"

# (system, claim, given, verdict, source)
CASES = [
    # --- the heavy symmetric top, section 3.6 ---------------------------------------------------
    (HEAVY, "p_psi = I3*(psi_dot + cos(theta)*phi_dot)", [], "identity", "(3.63)"),
    (HEAVY, "p_psi = 2*I3*(psi_dot + cos(theta)*phi_dot)", [], "false", "(3.63) with a factor 2"),
    (HEAVY, "p_phi = I1*sin(theta)**2*phi_dot + I3*cos(theta)*(psi_dot + phi_dot*cos(theta))", [], "identity",
     "(3.64)"),
    (HEAVY, "p_phi = (I1*sin(theta)**2 + I3*cos(theta)**2)*phi_dot + I3*psi_dot*cos(theta)", [], "identity",
     "Goldstein's p_φ"),
    (HEAVY, "p_phi = I3*sin(theta)**2*phi_dot + I1*cos(theta)*(psi_dot + phi_dot*cos(theta))", [], "false",
     "(3.64) with I1, I3 swapped"),
    (HEAVY, "E = I1/2*(theta_dot**2 + phi_dot**2*sin(theta)**2) + I3/2*omega3**2 + M*g*l*cos(theta)", [],
     "identity", "(3.65)"),
    (HEAVY, "E = I1/2*(theta_dot**2 + phi_dot**2*sin(theta)**2) + I3/2*omega3**2 - M*g*l*cos(theta)", [],
     "false", "(3.65) with the sign of V flipped"),
    (HEAVY, "omega1 = phi_dot*sin(theta)*sin(psi) + theta_dot*cos(psi)", [], "identity", "(3.58)"),
    (HEAVY, "omega1 = phi_dot*sin(theta)*cos(psi) + theta_dot*sin(psi)", [], "false", "(3.58) sin/cos ψ swapped"),
    (HEAVY, "phi_dot = (b - a*cos(theta))/sin(theta)**2", [], "identity", "(3.67)"),
    (HEAVY, "psi_dot = I1*a/I3 - (b - a*cos(theta))*cos(theta)/sin(theta)**2", [], "identity", "(3.68)"),
    (HEAVY, "E_prime = I1/2*theta_dot**2 + I1*(b - a*cos(theta))**2/(2*sin(theta)**2) + M*g*l*cos(theta)", [],
     "identity", "(3.69)-(3.70)"),
    (HEAVY, "E_prime = I1/2*theta_dot**2 + (p_phi - p_psi*cos(theta))**2/(2*I1*sin(theta)**2) + M*g*l*cos(theta)",
     [], "identity", "Landau–Lifshitz §35, the heavy top's E'"),
    (HEAVY, "u_dot**2 = (1 - u**2)*(alpha - beta*u) - (b - a*u)**2", [], "identity", "(3.73)"),
    (HEAVY, "u_dot^2 = (1 - u^2)*(alpha - beta*u) + (b - a*u)^2", [], "false", "(3.73) with a sign flipped"),
    (HEAVY, "phi_dot = (b - a*u)/(1 - u**2)", [], "identity", "(3.74)"),
    (HEAVY, "psi_dot = I1*a/I3 - u*(b - a*u)/(1 - u**2)", [], "identity", "(3.75)"),
    (HEAVY, "u_ddot = (-2*u*(alpha - beta*u) - beta*(1 - u**2) + 2*a*(b - a*u))/2", [], "on-shell",
     "ü = f'(u)/2, from (3.73) and (3.79)"),
    (HEAVY, "dt(E) = 0", [], "on-shell", "energy conservation"),
    (HEAVY, "dt(p_phi) = 0", [], "on-shell", "φ ignorable"),
    (HEAVY, "dt(p_psi) = 0", [], "on-shell", "ψ ignorable"),
    (HEAVY, "dt(alpha) = 0", [], "on-shell", "E' conserved"),
    (HEAVY, "dt(theta_dot) = 0", [], "false", "θ̇ is not conserved"),
    (HEAVY, "I1*theta_ddot = I1*phi_dot**2*sin(theta)*cos(theta) - I3*omega3*phi_dot*sin(theta) + M*g*l*sin(theta)",
     [], "on-shell", "Goldstein's θ equation"),
    (HEAVY, "I1*theta_ddot = I1*phi_dot**2*sin(theta)*cos(theta) - I3*omega3*phi_dot*sin(theta) - M*g*l*sin(theta)",
     [], "false", "Goldstein's θ equation, gravity's sign flipped"),
    (HEAVY, "Lagrangian = (I1_cm + M*l**2)/2*(theta_dot**2 + phi_dot**2*sin(theta)**2)"
            " + I3/2*(psi_dot + phi_dot*cos(theta))**2 - M*g*l*cos(theta)",
     ["I1_cm = I1 - M*l**2"], "identity", "Goldstein's L with I1 about the centre of mass"),
    (HEAVY, "Lagrangian = I1_cm/2*(theta_dot**2 + phi_dot**2*sin(theta)**2)"
            " + I3/2*(psi_dot + phi_dot*cos(theta))**2 - M*g*l*cos(theta)",
     ["I1_cm = I1 - M*l**2"], "false", "the same, parallel-axis term forgotten"),
    (HEAVY, "a = b", ["theta = 0"], "identity", "the sleeping top, 3.6.3"),
    (HEAVY, "alpha = beta", ["theta = 0", "theta_dot = 0"], "identity", "the sleeping top, 3.6.3"),
    (HEAVY, "sqrt(1 - u**2) = sin(theta)", [], "identity", "sin θ ≥ 0 for 0 < θ < π"),
    # --- the free rigid body, sections 3.3-3.4 ----------------------------------------------------
    (FREE, "I1*dt(omega1) = (I2 - I3)*omega2*omega3", [], "on-shell", "(3.33)"),
    (FREE, "I1*dt(omega1) = (I3 - I2)*omega2*omega3", [], "false", "(3.33) with I2, I3 swapped"),
    (FREE, "I3*omega3_dot + omega1*omega2*(I2 - I1) = 0", [], "on-shell", "(3.33), third"),
    (FREE, "dt(T) = 0", [], "on-shell", "(3.46) conserved"),
    (FREE, "dt(Lsq) = 0", [], "on-shell", "(3.47) conserved"),
    (FREE, "dt(omega1**2 + omega2**2 + omega3**2) = 0", [], "false", "|ω| is not conserved"),
    (FREE, "I1*omega1**2 + I2*omega2**2 + I3*omega3**2 = 2*T", [], "identity", "ω·L = 2T, (3.46)/(3.49)"),
    (FREE, "dt(omega1) = Omega*omega2", ["I2 = I1", "Omega = omega3*(I1 - I3)/I1"], "on-shell", "(3.35)-(3.36)"),
    (FREE, "dt(omega1) = Omega*omega2", ["I2 = I1", "Omega = omega3*(I3 - I1)/I1"], "false",
     "(3.36) with the sign flipped"),
    (FREE, "dt(dt(omega1)) = -Omega**2*omega1", ["I2 = I1", "Omega = omega3*(I1 - I3)/I1"], "on-shell",
     "the symmetric top's ω1 oscillates at Ω (3.37)"),
    (FREE, "dt(omega3) = 0", ["I2 = I1"], "on-shell", "(3.34): ω3 constant"),
]


@pytest.mark.parametrize("system, claim, given, expected, source", CASES, ids=[c[4] for c in CASES])
def test_verdicts(system, claim, given, expected, source):
    v = check(claim, system, given=given)
    assert v.verdict == expected, (source, v)
    if expected == "false":
        c = v.counterexample
        assert c is not None and c["point"] and c["lhs"] != c["rhs"]
        assert v.exit_status == 1
    else:
        assert v.counterexample is None and v.exit_status == 0


def test_enough_cases():
    assert len(CASES) >= 20
    assert {c[3] for c in CASES} == {"identity", "on-shell", "false"}


def test_methods_say_proven_or_numeric():
    exact = check("phi_dot = (b - a*cos(theta))/sin(theta)**2")
    assert exact.method == "exact" and exact.detail.startswith("proven")
    assert "definitions used: a, b" in exact.detail
    numeric = check("sqrt(1 - u**2) = sin(theta)")
    assert numeric.method == "numeric" and numeric.detail.startswith("not proven")
    assert "probability of a false positive <" in numeric.detail


def test_counterexample_values_are_the_two_sides():
    v = check("p_psi = 2*I3*(psi_dot + cos(theta)*phi_dot)")
    c = v.counterexample
    assert float(c["rhs"]) == pytest.approx(2 * float(c["lhs"]), rel=1e-25)
    assert set(c["point"]) == {"I3", "theta", "phi_dot", "psi_dot"}
    assert len(c["lhs"].replace("-", "").replace(".", "")) >= 25  # shown to 30 digits


def test_tiny_errors_are_not_passed():
    """No float tolerance hides a wrong formula: exact for trig-rational, 60-digit re-check otherwise."""
    assert check("p_psi = I3*omega3 + 10**(-30)").verdict == "false"
    v = check("sqrt(1 - u**2) = sin(theta) + 10**(-40)")
    assert v.verdict == "false" and v.counterexample is not None


def test_typed_approximations_of_constants_are_not_passed():
    """A 60-digit decimal of π agrees with π at 60 digits: the confirming precision grows with the digits typed."""
    pi60 = "3.14159265358979323846264338327950288419716939937510582097494"
    assert check(f"pi = {pi60}").verdict == "false"
    assert check(f"pi*sin(theta) = {pi60}*sin(theta)").verdict == "false"
    assert check("pi = 4*atan(1)").verdict == "identity"


def test_on_shell_counterexample_is_on_a_motion():
    v = check("dt(theta_dot) = 0", given=["theta_dot = 0"])
    assert v.verdict == "false" and "on a motion" in v.detail
    assert v.counterexample["given"] == {"theta_dot": "0"}
    assert "theta_dot" not in v.counterexample["point"]


def test_undecided():
    v = check("sqrt(-1 - theta_dot**2) = 1")
    assert v.verdict == "undecided" and "non-real" in v.detail and v.exit_status == 3
    singular = check("phi_dot = (b - a*cos(theta))/sin(theta)**2", given=["theta = 0"])
    assert singular.verdict == "undecided" and "singular" in singular.detail


def test_symbols_are_derived_definitions():
    heavy = get_system(HEAVY)
    assert str(heavy.definition(heavy.symbol("u_dot"))) == "-theta_dot*sin(theta)"
    names = {n for n, _, _ in heavy.describe()}
    assert {"a", "b", "alpha", "beta", "u", "u_dot", "p_phi", "p_psi", "E", "omega1", "theta_ddot"} <= names
    free = {n for n, _, _ in get_system(FREE).describe()}
    assert {"omega1", "omega1_dot", "I2", "T", "Lsq"} <= free and "L2" not in free


# --- the safe parser -----------------------------------------------------------------------------

HOSTILE = [
    ("__import__('os').system('echo hi') = 0", "call of"),
    ("().__class__.__bases__[0] = 0", "subscript"),
    ("theta.__class__ = 0", "attribute access"),
    ("theta**10**10 = 0", "exponent"),
    ("9**9**9 = 0", "exponent"),
    ("theta**theta = 0", "numeric exponent"),
    ("x" * 10**6, "at most 2000 characters"),
    ("(" * 100 + "theta" + ")" * 100 + " = 0", "nested at most"),
    ("-" * 1500 + "theta = 0", "nested at most"),
    ("eval('1') = 0", "call of 'eval'"),
    ("(lambda: 1)() = 0", "call of"),
    ("lambda: 1 = 0", "a lambda"),
    ("[t for t in theta] = 0", "comprehension"),
    ("sin(x=theta) = 0", "exactly one '='"),
    ("'theta' = 0", "string"),
    ("foo = 0", "unknown symbol 'foo' .* known symbols: .*theta"),
    (r"\frac{1}{2} = 0", "antlr4-python3-runtime"),
    ("1e999999 = 0", "decimal exponent"),
    ("(10**100)**100 = 0", "below 10\\^1000"),
    ("theta/0 = 0", "division by zero"),
    ("theta // 2 = 0", "operator"),
    ("theta < 1 = 0", "comparison"),
    ("2theta = 0", "syntax error"),
]


@pytest.mark.parametrize("text, message", HOSTILE, ids=[h[1] for h in HOSTILE])
def test_hostile_input_refused_fast(text, message):
    get_system(HEAVY)  # the symbol table (cheap), built before timing
    gc.disable()  # time the parser, not a full collection of the suite's garbage (0.1-0.2 s) that may fall here
    try:
        start = time.perf_counter()
        with pytest.raises(InvalidInputError, match=message):
            check(text, HEAVY)
        assert time.perf_counter() - start < 0.05
    finally:
        gc.enable()


def test_keyword_arguments_refused():
    with pytest.raises(InvalidInputError, match="keyword arguments in 'sin\\(x=theta\\)'"):
        parse_expression("sin(x=theta)", get_system(HEAVY).names)


@pytest.mark.parametrize("text, message", [
    ("theta", "exactly one '='"),
    ("theta == 0", "got '=='"),
    ("a = b = c", "exactly one '='"),
    ("E = 0", None),
])
def test_claim_syntax(text, message):
    if message is None:
        lhs, rhs = parse_claim(text, get_system(HEAVY).names)
        assert str(lhs) == "E" and rhs == 0
    else:
        with pytest.raises(InvalidInputError, match=message):
            check(text, HEAVY)


def test_caret_is_power_with_power_precedence():
    lhs, rhs = parse_claim("theta + theta_dot^2 = -theta^2", get_system(HEAVY).names)
    assert str(lhs) == "theta + theta_dot**2" and str(rhs) == "-theta**2"


def test_decimals_are_exact():
    lhs, _ = parse_claim("0.1*theta = 0", get_system(HEAVY).names)
    assert str(lhs) == "theta/10"


@pytest.mark.parametrize("given, message", [
    (["a = 1"], "the defined quantity 'a'"),
    (["theta_ddot = 0"], "the time derivative 'theta_ddot'"),
    (["theta_dot = 2*theta_dot"], "not to depend on theta_dot"),
    (["w = 1", "w = 2"], "defined once"),
    (["2*x = 1"], "plain name on the left"),
    (["sin = 1"], "not a function"),
    (["theta_dot = theta_ddot"], "in the state and the parameters"),
    (["theta_dot = dt(theta)"], "without dt"),
    (["x"], "one '='"),
    (["I1 = -1"], "expected a positive value for I1, got -1"),
])
def test_given_rules(given, message):
    with pytest.raises(InvalidInputError, match=message):
        check("E = E", HEAVY, given=given)


def test_hints_for_clashing_names():
    with pytest.raises(InvalidInputError, match=r"'L2' \(L² is Lsq"):
        check("dt(L2) = 0", FREE)
    with pytest.raises(InvalidInputError, match="energy of the free top is T"):
        check("dt(E) = 0", FREE)
    with pytest.raises(InvalidInputError, match="write a time derivative as dt"):
        check("diff(E, t) = 0", HEAVY)


def test_bad_options():
    with pytest.raises(InvalidInputError, match="expected a system among free_top, heavy_top, rigid_body, got 'spinning'"):
        check("E = E", "spinning")
    with pytest.raises(InvalidInputError, match="^points: expected an integer between 20 and 1000, got 5$"):
        check("E = E", HEAVY, points=5)
    for budget in (0, -1, float("nan"), float("inf"), 601, "5", True):
        with pytest.raises(InvalidInputError, match="^budget: expected a time of more than 0 and at most 600 s"):
            check("E = E", HEAVY, budget=budget)
    with pytest.raises(InvalidInputError, match="^seed: expected an integer, got 1.5$"):
        check("E = E", HEAVY, seed=1.5)
    with pytest.raises(InvalidInputError, match="^given: expected a list of 'name = expression' strings"):
        check("E = E", HEAVY, given="I1 = 1")


# --- the command line ------------------------------------------------------------------------------


@pytest.mark.parametrize("argv, status", [
    (["check", "heavy_top", "p_psi = I3*(psi_dot + cos(theta)*phi_dot)"], 0),
    (["check", "heavy_top", "dt(E) = 0"], 0),
    (["check", "heavy_top", "dt(theta_dot) = 0"], 1),
    (["check", "heavy_top", "foo = 0"], 2),
    (["check", "heavy_top", "__import__('os').system('echo hi') = 0"], 2),
    (["check", "spinning", "E = 0"], 2),
    (["check", "heavy_top"], 2),
    (["check", "heavy_top", "sqrt(-1 - theta_dot**2) = 1"], 3),
    (["check", "free_top", "dt(omega1) = Omega*omega2", "--given", "I2 = I1",
      "--given", "Omega = omega3*(I1 - I3)/I1"], 0),
])
def test_cli_exit_status(argv, status, capsys):
    assert main(argv) == status


def test_cli_json(capsys):
    assert main(["check", "heavy_top", "dt(theta_dot) = 0", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "false" and set(out) == {"verdict", "method", "detail", "counterexample", "assumptions"}
    assert out["assumptions"][0].startswith("a real top: I1, I3, M, g, l > 0 and I1 ≥ M l² + I3/2")
    assert main(["check", "heavy_top", "foo = 0", "--json"]) == 2
    err = json.loads(capsys.readouterr().out)
    assert err["verdict"] == "error" and "unknown symbol 'foo'" in err["detail"]


def test_cli_symbols(capsys):
    assert main(["check", "free_top", "--symbols"]) == 0
    out = capsys.readouterr().out
    assert "Lsq" in out and "L² = Σ I_a² ω_a² (3.47)" in out
    assert EXIT_STATUS == {"identity": 0, "on-shell": 0, "false": 1, "undecided": 3}


# --- issue 11: counterexamples among real bodies only (reproduction 6) ------------------------------


def _fractions(values: dict) -> dict:
    return {k: Fraction(v) for k, v in values.items()}


@pytest.mark.parametrize("system, claim, impossible", [
    # a real body has I1 + I2 − I3 = 2 Σ m z² ≥ 0, so sqrt(x²) = |x| = x; only I1 + I2 < I3 breaks it
    (FREE, "sqrt((I1 + I2 - I3)**2) = I1 + I2 - I3", lambda p: p["I1"] + p["I2"] < p["I3"]),
    # a real top has I1 − M l² ≥ I3/2 (the triangle inequality about the centre of mass):
    # the same with x = I1 − M l² − I3/2
    (HEAVY, "sqrt((I1 - M*l**2 - I3/2)**2) = I1 - M*l**2 - I3/2",
     lambda p: p["I1"] - p["M"] * p["l"] ** 2 < p["I3"] / 2),
])
def test_false_only_for_impossible_bodies_is_an_identity_for_real_ones(system, claim, impossible):
    real = check(claim, system)
    assert real.verdict == "identity" and real.exit_status == 0, real
    assert "among real bodies" in real.detail and "--any-moments" in real.assumptions[0]
    assert ("triangle inequalities" if system == FREE else "I1 ≥ M l² + I3/2") in real.assumptions[0]
    anything = check(claim, system, any_moments=True)
    assert anything.verdict == "false" and impossible(_fractions(anything.counterexample["point"]))
    assert "real bodies or not" in anything.assumptions[0]


@pytest.mark.parametrize("system, claim", [
    (HEAVY, "I1 = 2*I3"),
    (HEAVY, "I1*theta_ddot = I1*phi_dot**2*sin(theta)*cos(theta) - I3*omega3*phi_dot*sin(theta) - M*g*l*sin(theta)"),
    (FREE, "I1*dt(omega1) = (I3 - I2)*omega2*omega3"),
])
def test_counterexamples_are_bodies_the_solvers_accept(system, claim):
    """The body shown with a counterexample passes the solvers' own validators (not the sampler's construction)."""
    from mechderive.inertia.validate import check_principal_moments
    from mechderive.systems.heavy_top.parameters import check_params

    v = check(claim, system)
    assert v.verdict == "false", v
    names = ("I1", "I2", "I3") if system == FREE else ("I1", "I3", "M", "g", "l")
    shown = {**v.counterexample["point"], **v.counterexample.get("body", {})}  # the body, where the point lacks some
    body = {k: float(shown[k]) for k in names}
    if system == FREE:
        check_principal_moments(body["I1"], body["I2"], body["I3"], rtol=0.0)
    else:
        check_params(body, rtol=0.0)
        assert min(body["M"], body["g"], body["l"]) > 0
    extra = v.counterexample.get("body", {})
    assert all(v.counterexample["point"][k] == extra[k] for k in v.counterexample["point"] if k in extra)


@pytest.mark.parametrize("system", [FREE, HEAVY])
def test_region_draws_fill_the_region_without_rejection(system):
    """Every draw is a real body (checked by the solvers' validators with no tolerance), and the draws reach
    near-plate bodies (free top) and near-limit tops (heavy top), so the boundary region is searched too."""
    from mechderive.inertia.validate import check_principal_moments
    from mechderive.systems.heavy_top.parameters import check_params

    region = get_system(system).region
    rng = random.Random(7)
    draws = [{k: float(x) for k, x in region.draw(rng).items()} for _ in range(400)]
    if system == FREE:
        for d in draws:
            check_principal_moments(d["I1"], d["I2"], d["I3"], rtol=0.0)
        closest = min((d["I1"] + d["I2"] - d["I3"]) / d["I3"] for d in draws)
    else:
        for d in draws:
            check_params(d, rtol=0.0)
        closest = min((d["I1"] - d["M"] * d["l"] ** 2 - d["I3"] / 2) / d["I1"] for d in draws)
    assert 0 < closest < 0.1  # 400 uniform draws of a slack of width ≥ 1 come within 5 % of the boundary


def test_given_values_are_kept_inside_the_region():
    v = check("I3 = I1", FREE, given=["I2 = I1"])
    assert v.verdict == "false" and v.counterexample["body"]["I2"] == v.counterexample["body"]["I1"]
    # I2 = I1 and I3 = 3 I1 give I1 + I2 = 2 I1 < I3: no real body, so nothing to decide (not "false")
    none = check("I1 + I2 = I3", FREE, given=["I2 = I1", "I3 = 3*I1"])
    assert none.verdict == "undecided" and "make a body the solvers refuse" in none.detail
    assert check("I1 + I2 = I3", FREE, given=["I2 = I1", "I3 = 3*I1"], any_moments=True).verdict == "false"


def test_later_givens_see_earlier_specialisations():
    # I2 = I1 then I3 = I2 means I3 = I1: a sphere, whose Euler equations give dω3/dt = 0
    assert check("dt(omega3) = 0", FREE, given=["I2 = I1", "I3 = I2"]).verdict == "on-shell"
    # I2 = I3 then I3 = I1: the claim sees I2 = I1 too, and so does the body shown (a sphere)
    body = check("I2 = 2*I3", FREE, given=["I2 = I3", "I3 = I1"]).counterexample["body"]
    assert body["I1"] == body["I2"] == body["I3"]


def test_proofs_state_the_positivity_they_use():
    # sqrt(M² l²) = |M l| = M l needs M l ≥ 0; (3.63) is algebra, true for any sign
    v = check("sqrt(M**2*l**2) = M*l")
    assert v.verdict == "identity" and v.method == "exact"
    assert v.assumptions == ("M, l > 0: the proof uses the parameters' positivity",)
    assert check("p_psi = I3*(psi_dot + cos(theta)*phi_dot)").assumptions == ()
    assert check("dt(E) = 0").assumptions == ()
    # the sign can be used in a --given value too: sqrt(I1²) = I1 only for I1 ≥ 0
    assert check("I1 = I2", FREE, given=["I2 = sqrt(I1**2)"]).assumptions == (
        "I1 > 0: the proof uses the parameters' positivity",)


# --- issue 11: no identity from digits that are not there (reproduction 7) -----------------------------


@pytest.mark.parametrize("claim", [
    "exp(exp(1000)) = 1",           # exp(1000) = 1.97e434: the value has 8.6e433 decimal digits
    "exp(10**100*exp(theta)) = 0",  # an exponent above 1e100
    "exp(exp(1000)) = exp(exp(1000) + 1e-100)",   # both sides overflow
])
def test_overflow_is_undecided(claim):
    v = check(claim, budget=5)
    assert v.verdict == "undecided" and v.exit_status == 3, v
    assert "overflow" in v.detail and "beyond 10^10000" in v.detail


def test_a_perturbation_below_the_working_precision_is_seen():
    """sin θ − sin(θ + 10^-100) = −10^-100 cos θ + O(10^-200): the shift is resolved, so the claim is false."""
    v = check("sin(theta) = sin(theta + 1e-100)")
    assert v.verdict == "false" and v.exit_status == 1, v
    c = v.counterexample
    with mpmath.workdps(150):  # 150 digits resolve the 1e-100 shift with 50 to spare
        theta = mpmath.mpf(Fraction(c["point"]["theta"]).numerator) / Fraction(c["point"]["theta"]).denominator
        expected = mpmath.sin(theta) - mpmath.sin(theta + mpmath.mpf(10) ** -100)
        assert abs(mpmath.mpf(c["difference"]) - expected) <= 1e-9 * abs(expected)  # 10 digits printed
    assert c["lhs"] != c["rhs"]  # shown to enough digits to differ


def _theta(v) -> mpmath.mpf:
    f = Fraction(v.counterexample["point"]["theta"])
    return mpmath.mpf(f.numerator) / f.denominator


@pytest.mark.parametrize("claim, difference", [
    # cos x − 1 = −x²/2 + x⁴/24 …: with x = 1e-100 θ the second term is 1e-200 below the first
    ("cos(1e-100*theta) = 1", lambda t: -(mpmath.mpf(10) ** -100 * t) ** 2 / 2),
    # sin x − x = −x³/6 + x⁵/120 …, relative to x only 1e-200: invisible at 60 digits
    ("sin(1e-100*theta) = 1e-100*theta", lambda t: -(mpmath.mpf(10) ** -100 * t) ** 3 / 6),
    # tanh y − 1 = −2 e^(−2y) (1 − e^(−2y) …): 1e-174 at y ≈ 200
    ("tanh(theta + 200) = 1", lambda t: -2 * mpmath.exp(-2 * (t + 200))),
    # both sides about 10^9566 and 1e-50 apart, relative
    ("exp(exp(10))*(1 + 1e-50) = exp(exp(10))", None),
])
def test_tiny_but_genuine_differences_are_false(claim, difference):
    v = check(claim, budget=5)
    assert v.verdict == "false", v
    if difference is None:
        assert float(v.counterexample["relative difference"]) == pytest.approx(1e-50, rel=1e-4)
        return
    with mpmath.workdps(50):  # the leading term: the next one is 1e-200 (or e^-400) smaller
        assert mpmath.mpf(v.counterexample["difference"]) == pytest.approx(difference(_theta(v)), rel=1e-9)


@pytest.mark.parametrize("claim, method", [
    ("(theta + 1e20) - 1e20 = theta", "exact"),           # SymPy folds the constants: no cancellation left
    ("sqrt((theta + 1e20)**2) - 1e20 = theta", "numeric"),  # |θ + 1e20| − 1e20 = θ (θ > −1e20): 20 digits cancel
    ("log(sqrt((theta + 1e30)**2) - 1e30) = log(theta)", "numeric"),  # the log of a 30-digit cancellation
])
def test_cancellations_that_hold_are_identities(claim, method):
    v = check(claim, budget=5)
    assert v.verdict == "identity" and v.method == method, v


def test_escalation_respects_the_budget():
    import sympy as sp

    from mechderive.formulas.significance import compare

    # with no time left nothing is evaluated, and nothing decided
    x = sp.Symbol("x", real=True)
    late = compare(sp.sin(x), sp.sin(x + sp.Rational(1, 10**100)), {x: sp.Rational(7, 5)}, base=60,
                   deadline=time.monotonic() - 1)
    assert late.kind == "reject" and late.reason == "the time budget (--budget) was spent before this point"
    v = check("sin(theta) = sin(theta + 1e-100)", budget=1e-3)  # 1 ms: not even enough to parse
    assert v.verdict == "undecided" and "the time budget of 0.001 s (--budget) ran out while " in v.detail, v


def test_compare_at_one_point():
    """significance.compare: digits lost are added, a depth asks for more, a cap refuses rather than agrees."""
    import sympy as sp

    from mechderive.formulas.significance import compare

    x = sp.Symbol("x", real=True)
    at = {x: sp.Rational(7, 5)}
    # sin²(10^40 x) + cos²(10^40 x) = 1 loses 40 digits to the argument; K = 2·40 + 30 = 110 more are asked
    lost = compare(sp.sin(10**40 * x) ** 2 + sp.cos(10**40 * x) ** 2, sp.Integer(1), at, base=60)
    assert lost.kind == "agree" and lost.agreed_to == 110 and lost.digits >= 150
    capped = compare(sp.sin(x), sp.sin(x + sp.Rational(1, 10**100)), at, base=60, cap=90)
    assert capped.kind == "reject" and "more than 90" in capped.reason
    gone = compare(sp.exp(-sp.exp(100)), sp.Integer(0), at, base=60)
    assert gone.kind == "reject" and gone.reason.startswith("underflow")


def test_cli_any_moments_and_assumptions(capsys):
    claim = "sqrt((I1 + I2 - I3)**2) = I1 + I2 - I3"
    assert main(["check", "free_top", claim]) == 0
    assert "assumes a real body: I1, I2, I3 > 0" in capsys.readouterr().out
    assert main(["check", "free_top", claim, "--any-moments"]) == 1
    assert "real bodies or not" in capsys.readouterr().out
    assert main(["check", "free_top", claim, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "identity" and "triangle inequalities" in out["assumptions"][0]
    assert main(["check", "heavy_top", "exp(exp(1000)) = 1"]) == 3
