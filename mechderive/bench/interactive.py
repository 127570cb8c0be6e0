"""Interactive speed: whole commands in fresh processes, ours against the same job by the usual path.

Each figure is the wall time of a new ``python`` process, measured from outside (interpreter start
and imports included), on this machine, in one run:

* ``derive heavy_top`` (L, the equations of motion, the momenta, E) against
  ``sympy.physics.mechanics``'s ``LagrangesMethod`` forming the same equations;
* ``check heavy_top 'dt(E) = 0'`` against deriving E by hand with SymPy and simplifying its time
  derivative on the equations of motion to 0;
* ``run`` (the default scene: 10 nutation periods, 2001 samples, θ, φ, ψ, error estimate and drift)
  against derive → ``lambdify(cse=True)`` → ``solve_ivp(DOP853, rtol 1e-10)`` of the same scene;
* ``verify --jobs 2`` (the chapter's 134 claims), which the usual path has no counterpart for.

"Cold" runs start from an empty ``MECHDERIVE_CACHE_DIR`` (SymPy derives, code is compiled); "warm"
runs repeat on the filled cache (median of a few).  The baseline has no cache: every run is cold.
"""

from __future__ import annotations

import statistics
import tempfile

from ._common import package_env, python_subprocess

__all__ = ["interactive", "BASELINES"]

_HEAVY_TOP = """
import sympy as sp
from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame, RigidBody,
                                     dynamicsymbols, inertia)
phi, theta, psi = dynamicsymbols("phi theta psi")
I1, I3, M, g, l = sp.symbols("I1 I3 M g l", positive=True)
N, B = ReferenceFrame("N"), ReferenceFrame("B")
B.orient_body_fixed(N, (phi, theta, psi), "ZXZ")
P = Point("P")
P.set_vel(N, 0)
G = P.locatenew("G", l * B.z)
G.v2pt_theory(P, N, B)
top = RigidBody("top", G, B, M, (inertia(B, I1, I1, I3), P))
top.potential_energy = M * g * G.pos_from(P).dot(N.z)
L = Lagrangian(N, top)
LM = LagrangesMethod(L, [phi, theta, psi])
LM.form_lagranges_equations()
"""

#: the usual path's script for each job (a fresh ``python -c``)
BASELINES = {
    "derive": _HEAVY_TOP + "rhs = LM.rhs()\nprint(sp.simplify(L))\nprint(rhs)\n",
    "check": _HEAVY_TOP + """
qs = [phi, theta, psi]
E = sum(q.diff() * L.diff(q.diff()) for q in qs) - L
rhs = LM.rhs()
on_shell = {q.diff().diff(): rhs[3 + i] for i, q in enumerate(qs)}
dE = sp.simplify(E.diff(dynamicsymbols._t).subs(on_shell))
assert dE == 0, dE
print("dE/dt = 0")
""",
    "run": _HEAVY_TOP + """
import numpy as np
from scipy.integrate import solve_ivp
qs = [phi, theta, psi]
rhs = LM.rhs()
f = sp.lambdify([*qs, *(q.diff() for q in qs), I1, I3, M, g, l], list(rhs), cse=True)
p = (1.0, 0.5, 0.1, 10.0, 1.0)
t = np.linspace(0.0, 35.177, 2001)
sol = solve_ivp(lambda _t, y: f(*y, *p), (0.0, 35.177), [0.0, 0.5, 0.0, 0.0, 0.0, 5.0], method="DOP853",
                t_eval=t, rtol=1e-10, atol=1e-12)
print(sol.y[:3, -1])
""",
}

_OURS = {
    "derive": ["derive", "heavy_top"],
    "check": ["check", "heavy_top", "dt(E) = 0"],
    "run": ["run"],
    "verify": ["verify", "--jobs", "2"],
}
_DRIVER = "import sys\nfrom mechderive.cli import main\nsys.exit(main(sys.argv[1:]))\n"


def _ours(args: list[str], cache: str) -> float:
    return python_subprocess(["-c", _DRIVER, *args], package_env(MECHDERIVE_CACHE_DIR=cache))[0]


def interactive(*, quick: bool = False) -> dict:
    """{job: {cold, warm, warm_runs, baseline}} in seconds, each job in fresh processes (module docstring)."""
    repeats = 1 if quick else 3
    jobs = [j for j in _OURS if not (quick and j == "verify")]
    rows: dict = {}
    with tempfile.TemporaryDirectory(prefix="mechderive-bench-interactive-") as root:
        for job in jobs:
            cache = f"{root}/{job}"  # each job cold on its own empty cache
            cold = _ours(_OURS[job], cache)
            warm = [_ours(_OURS[job], cache) for _ in range(repeats)]
            baseline = (python_subprocess(["-c", BASELINES[job]], package_env())[0] if job in BASELINES else None)
            rows[job] = {"command": "mechderive " + " ".join(repr(a) if " " in a else a for a in _OURS[job]),
                         "cold": cold, "warm": statistics.median(warm), "warm_runs": warm, "baseline": baseline}
    return {"rows": rows, "repeats": repeats}


def report_lines(result: dict) -> list[str]:
    """The section's table (Markdown)."""
    lines = ["## 7. Interactive speed: whole commands in fresh processes (interpreter start included)", "",
             "| job | mechderive cold | mechderive warm | sympy.physics.mechanics path | warm speed-up |",
             "|---|---|---|---|---|"]
    for job, r in result["rows"].items():
        base = r["baseline"]
        ratio = f"{base / r['warm']:.0f}×" if base else "—"
        lines.append(f"| `{r['command']}` | {r['cold']:.2f} s | {r['warm']:.2f} s | "
                     f"{f'{base:.2f} s' if base else 'no counterpart'} | {ratio} |")
    return lines + [""]
