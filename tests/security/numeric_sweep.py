"""A sweep of extreme but schema-valid numbers through ``mechderive run`` (issue 12, findings 5 and 7).

For each built-in system (free_top, heavy_top, falling_cat) and each numeric scene field
(parameters, initial values, ``t_end``, ``samples``, ``rtol``) it runs a base scene with that one
field set to an extreme value — 0, ±tiny (1e-300, 5e-324), ±huge (1e300, 1e308, 1.7e308) and
values one ulp past a physical limit — under each scene method, and classifies the outcome:

* ``ok``       exit 0, every output column finite (or a non-finite column the report's note names),
               the error estimate finite, nothing printed on stderr;
* ``refused``  exit 2 with ONE line ``mechderive: error: scene key [...]...: expected ...``;
* anything else is a finding: ``traceback``/``internal`` (exit 70), ``warning`` (a RuntimeWarning
  printed), ``nan`` (a non-finite value not named in the note, or a NaN estimate), ``unnamed`` (a
  refusal that names no scene key), ``timeout``, ``crash`` (killed by a signal).

Every case runs in a forked child (so a hang or a crash cannot stop the sweep), with the parent's
warm imports.  ``python tests/security/numeric_sweep.py [--quick] [--system S] [--timeout s]`` prints
one line per case and the counts per kind; the tests (``test_numeric_edges.py``) run a bounded
sample by default and the whole sweep under ``-m slow``.
"""

from __future__ import annotations

import io
import json
import math
import os
import select
import signal
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import numpy as np

TINY = (0.0, 5e-324, -5e-324, 1e-300, -1e-300)
HUGE = (1e300, -1e300, 1e308, -1e308, 1.7e308, -1.7e308)
EXTREMES = TINY + HUGE
METHODS = ("auto", "exact", "integrate")

BASE: dict[str, dict[str, Any]] = {
    "heavy_top": {
        "system": "heavy_top", "rtol": 1e-9,
        "parameters": {"I1": 1.0, "I3": 0.5, "M": 0.1, "g": 10.0, "l": 1.0},
        "initial": {"theta": 0.5, "phi": 0.0, "psi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0, "psi_dot": 5.0},
        "time": {"t_end": 10.0, "samples": 51},
        "output": {"quantities": ["theta", "phi", "psi", "energy", "p_phi", "omega1", "R11", "apex_z",
                                  "phi_dot"]},
    },
    "heavy_top_mgl": {
        "system": "heavy_top", "rtol": 1e-9,
        "parameters": {"I1": 1.0, "I3": 0.5, "Mgl": 1.0},
        "initial": {"theta": 0.5, "phi": 0.0, "psi": 0.0, "theta_dot": 0.0, "phi_dot": 0.0, "psi_dot": 5.0},
        "time": {"t_end": 10.0, "samples": 51},
        "output": {"quantities": ["theta", "phi", "psi", "energy", "p_psi", "apex_x"]},
    },
    "free_top": {
        "system": "free_top", "rtol": 1e-9,
        "parameters": {"I1": 1.0, "I2": 2.0, "I3": 3.0},
        "initial": {"omega": [1.0, 0.5, 1.0], "phi": 0.0, "theta": 0.0, "psi": 0.0},
        "time": {"t_end": 10.0, "samples": 51},
        "output": {"quantities": ["omega1", "omega2", "omega3", "energy", "L_norm", "R11", "R23", "phi",
                                  "theta", "psi", "q0"]},
    },
    "falling_cat": {
        "system": "falling_cat", "rtol": 1e-9,
        "parameters": {},
        "time": {"t_end": 1.0, "samples": 51},
        "output": {"quantities": ["R11", "q0", "flip_angle", "L1", "shape_bend"]},
    },
}

#: The numeric fields per base scene: (table or None, key, index or None).
FIELDS: dict[str, list[tuple[str | None, str, int | None]]] = {
    "heavy_top": [("parameters", k, None) for k in ("I1", "I3", "M", "g", "l")]
                 + [("initial", k, None) for k in ("theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot")]
                 + [("time", "t_end", None), (None, "rtol", None)],
    "heavy_top_mgl": [("parameters", k, None) for k in ("I1", "I3", "Mgl")],
    "free_top": [("parameters", k, None) for k in ("I1", "I2", "I3")]
                + [("initial", "omega", i) for i in range(3)]
                + [("initial", k, None) for k in ("phi", "theta", "psi")]
                + [("time", "t_end", None), (None, "rtol", None)],
    "falling_cat": [("parameters", k, None) for k in ("half_mass", "joint_offset", "radius", "half_length",
                                                      "peak_bend")]
                   + [("time", "t_end", None), (None, "rtol", None)],
}


def _ulps(x: float, n: int = 1) -> list[float]:
    """x and its neighbours n ulps either side."""
    out = [x]
    up = down = x
    for _ in range(n):
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
        out += [up, down]
    return out


@dataclass
class Case:
    kind: str      # what is varied, e.g. "heavy_top [parameters].I1" or "limit: triangle"
    label: str     # the value or the limit case
    scene: dict    # the scene document (before TOML)
    method: str
    backend: str = "c"  # "c": the compiled DOP853 where a compiler is found; "scipy": MECHDERIVE_NO_C's path

    @property
    def name(self) -> str:
        return f"{self.kind} = {self.label} ({self.method}{', SciPy' if self.backend == 'scipy' else ''})"


def _with(base: dict, table: str | None, key: str, index: int | None, value: Any) -> dict:
    scene = json.loads(json.dumps(base))
    if table is None:
        scene[key] = value
    elif index is None:
        scene[table][key] = value
    else:
        scene[table][key][index] = value
    return scene


def _methods(system: str) -> tuple[str, ...]:
    return ("auto", "integrate") if system == "falling_cat" else METHODS


def field_cases() -> Iterator[Case]:
    """Every numeric field of every base scene at every extreme value, under every method."""
    for base_name, fields in FIELDS.items():
        base = BASE[base_name]
        for table, key, index in fields:
            where = (f"[{table}]." if table else "") + key + (f"[{index}]" if index is not None else "")
            values: tuple = EXTREMES
            if key == "theta":
                values = EXTREMES + tuple(_ulps(math.pi)) + (math.nextafter(0.0, 1.0),)
            for value in values:
                for method in _methods(base["system"]):
                    yield Case(f"{base_name} {where}", repr(value), _with(base, table, key, index, value), method)
        for samples in (2, 3):
            for method in _methods(base["system"]):
                yield Case(f"{base_name} [time].samples", str(samples),
                           _with(base, "time", "samples", None, samples), method)


def limit_cases() -> Iterator[Case]:
    """Values one ulp either side of the physical limits, and uniform scalings of a whole scene."""
    free, heavy = BASE["free_top"], BASE["heavy_top"]
    # the triangle inequality I1 + I2 >= I3 at equality (a flat plate) and one ulp past it
    for I3 in _ulps(3.0, 2):
        for method in METHODS:
            yield Case("free_top limit: I1 + I2 = I3", f"I3 = {I3!r}",
                       _with(free, "parameters", "I3", None, I3), method)
    # a heavy top's I1 - M l² >= I3/2: I1 = M l² + I3/2 and one ulp either side
    for I1 in _ulps(0.1 + 0.25, 2):
        for method in METHODS:
            yield Case("heavy_top limit: I1 = M l² + I3/2", f"I1 = {I1!r}",
                       _with(heavy, "parameters", "I1", None, I1), method)
    # the same moments scaled together (every scale of a body is a body)
    for c in (1e-300, 1e-150, 1e150, 1e300, 1e308):
        for method in METHODS:
            yield Case("free_top scale: (I1, I2, I3) = c (1, 2, 3)", repr(c),
                       dict(free, parameters={"I1": c, "I2": min(2 * c, 1.7e308), "I3": min(3 * c, 1.7e308)}),
                       method)
            yield Case("heavy_top scale: I1 = I3 = c", repr(c),
                       dict(heavy, parameters={"I1": c, "I3": c, "M": 0.1, "g": 10.0, "l": 1.0}), method)
    # time scaled: rates × c (and M g l × c² for the heavy top), t_end / c — the same motion
    for c in (1e-150, 1e-100, 1e100, 1e150):
        for method in METHODS:
            yield Case("free_top scale: omega × c, t_end / c", repr(c),
                       dict(free, initial={**free["initial"], "omega": [w * c for w in free["initial"]["omega"]]},
                            time={**free["time"], "t_end": free["time"]["t_end"] / c}), method)
            yield Case("heavy_top scale: rates × c, Mgl × c², t_end / c", repr(c),
                       dict(heavy, parameters={"I1": 1.0, "I3": 0.5, "Mgl": c * c},
                            initial={**heavy["initial"], "psi_dot": 5.0 * c},
                            time={**heavy["time"], "t_end": heavy["time"]["t_end"] / c}), method)
    # the ends of the allowed rtol, [1e-15, 1e-2]
    for base_name in ("heavy_top", "free_top", "falling_cat"):
        for rtol in (1e-15, 1e-2):
            for method in _methods(BASE[base_name]["system"]):
                yield Case(f"{base_name} rtol", repr(rtol), dict(BASE[base_name], rtol=rtol), method)
    # strict = false: moments no rigid body has, at the extremes (positivity is all that is checked)
    for base_name, keys in (("free_top", ("I1", "I2", "I3")), ("heavy_top", ("I1", "I3", "M", "l"))):
        for key in keys:
            for value in (5e-324, 1e-300, 1e300, 1.7e308):
                for method in METHODS:
                    yield Case(f"{base_name} strict = false [parameters].{key}", repr(value),
                               dict(_with(BASE[base_name], "parameters", key, None, value), strict=False), method)
    # a tiny spin on the built-in heavy tops' other starts (hanging, looping, horizontal)
    for theta, phi_dot in ((2.5, 0.0), (0.5, -0.5), (math.pi / 2, 0.0), (3.0, 1.0)):
        for method in METHODS:
            yield Case("heavy_top tiny spin", f"theta = {theta!r}, phi_dot = {phi_dot!r}, psi_dot = 1e-300",
                       _with(_with(_with(heavy, "initial", "theta", None, theta), "initial", "phi_dot", None, phi_dot),
                             "initial", "psi_dot", None, 1e-300), method)
    for psi_dot in (1e-300, 1e6, 1e100):
        for method in METHODS:
            yield Case("heavy_top spin", f"psi_dot = {psi_dot!r}",
                       _with(heavy, "initial", "psi_dot", None, psi_dot), method)


def scipy_cases() -> Iterator[Case]:
    """The integrations again on SciPy's DOP853 (the path without a C compiler)."""
    for case in (*field_cases(), *limit_cases()):
        if case.method == "integrate" and case.scene["system"] != "falling_cat" and not case.kind.startswith(
                "heavy_top_mgl"):
            yield Case(case.kind, case.label, case.scene, case.method, "scipy")


def all_cases() -> list[Case]:
    return list(field_cases()) + list(limit_cases()) + list(scipy_cases())


def _toml(scene: dict) -> str:
    from mechderive.scenes.schema import _toml_value

    def value(v: Any) -> str:
        return ("true" if v else "false") if isinstance(v, bool) else _toml_value(v)

    lines = [f"{k} = {value(v)}" for k, v in scene.items() if not isinstance(v, dict)]
    for table, content in scene.items():
        if isinstance(content, dict) and content:
            lines += ["", f"[{table}]"] + [f"{k} = {value(v)}" for k, v in content.items()]
    return "\n".join(lines) + "\n"


def run_in_process(argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)`` with stdout, stderr (Python's and fd 2) and every warning captured: (status, out, err)."""
    from mechderive.cli import main

    out, err = io.StringIO(), io.StringIO()
    old = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = out, err
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            status = main(argv)
    finally:
        sys.stdout, sys.stderr = old
    return status, out.getvalue(), err.getvalue()


def classify(status: int | None, out: str, err: str, columns: dict | None, seconds: float) -> tuple[str, str]:
    """(kind, detail) of one outcome; kinds as in the module docstring."""
    if status is None:
        return "timeout", f"no answer after {seconds:.0f} s"
    if status < 0:
        return "crash", f"killed by signal {-status}"
    lines = [line for line in err.splitlines() if line.strip()]
    if "Warning" in err:
        return "warning", next(line for line in lines if "Warning" in line)[:200]
    if status == 0:
        report = json.loads(out)
        est = report.get("error_estimate")
        note = report.get("note") or ""
        if est is not None and not math.isfinite(est):
            return "nan", f"error estimate {est}"
        for k, d in report.get("drift", {}).items():
            if d is not None and not math.isfinite(d):
                return "nan", f"drift {k} = {d}"
        for name, col in (columns or {}).items():
            if name != "t" and not np.all(np.isfinite(col)) and f"{name}:" not in note:
                return "nan", f"column {name} not finite, not named in the note"
        if lines:
            return "stderr", lines[0][:200]
        return "ok", f"estimate {est!r}, rtol_met {report.get('rtol_met')}" + (f"; note: {note}" if note else "")
    if status == 2 and len(lines) == 1 and lines[0].startswith("mechderive: error: "):
        message = lines[0]
        if "scene key" not in message and "scene table" not in message:
            return "unnamed", message[:300]
        return "refused", message[:300]
    if status == 70:
        return "internal", (lines[-1] if lines else "")[:300]
    return "other", f"exit {status}: " + " | ".join(lines)[:300]


def run_case(case: Case, workdir: Path, timeout: float = 30.0) -> dict:
    """Run one case in a forked child; returns {name, kind, detail, status, seconds}."""
    path = workdir / "scene.toml"
    path.write_text(_toml(case.scene))
    (workdir / "out.npz").unlink(missing_ok=True)
    argv = ["run", str(path), "-o", str(workdir / "out.npz"), "--json"]
    scene_method = dict(case.scene, method=case.method)
    path.write_text(_toml(scene_method))
    read, write = os.pipe()
    start = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child: run, answer through the pipe, never return into the parent's code
        os.close(read)
        try:
            if case.backend == "scipy":
                from mechderive.core import cbuild

                cbuild.set_c_enabled(False)
            fd2 = os.open(workdir / "fd2.txt", os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
            os.dup2(fd2, 2)
            status, out, err = run_in_process(argv)
            err += (workdir / "fd2.txt").read_text(errors="replace")
            payload = json.dumps({"status": status, "out": out, "err": err}).encode()
        except BaseException as exc:  # noqa: BLE001 - report whatever escaped main()
            payload = json.dumps({"status": 99, "out": "", "err": f"escaped main: {type(exc).__name__}: {exc}"}
                                 ).encode()
        with os.fdopen(write, "wb") as pipe:
            pipe.write(payload)
        os._exit(0)
    os.close(write)
    chunks, deadline = [], start + timeout
    with os.fdopen(read, "rb") as pipe:
        while True:
            left = deadline - time.perf_counter()
            ready, _, _ = select.select([pipe], [], [], max(left, 0))
            if not ready:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                seconds = time.perf_counter() - start
                kind, detail = classify(None, "", "", None, seconds)
                return {"name": case.name, "kind": kind, "detail": detail, "status": None, "seconds": seconds}
            chunk = os.read(pipe.fileno(), 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
    _, wait_status = os.waitpid(pid, 0)
    seconds = time.perf_counter() - start
    if not chunks:
        status = -os.WTERMSIG(wait_status) if os.WIFSIGNALED(wait_status) else 98
        kind, detail = classify(status, "", "", None, seconds)
        return {"name": case.name, "kind": kind, "detail": detail, "status": status, "seconds": seconds}
    answer = json.loads(b"".join(chunks))
    columns = None
    if answer["status"] == 0 and (workdir / "out.npz").exists():
        with np.load(workdir / "out.npz") as data:
            columns = {k: data[k] for k in data.files}
    kind, detail = classify(answer["status"], answer["out"], answer["err"], columns, seconds)
    return {"name": case.name, "kind": kind, "detail": detail, "status": answer["status"], "seconds": seconds}


GOOD = ("ok", "refused")


def sweep(cases: list[Case], timeout: float = 30.0, verbose: bool = True) -> list[dict]:
    """Run ``cases`` (each in a forked child of this process, which imports the code under test first)."""
    import mechderive.cli  # noqa: F401 - loaded before forking: every child runs the same code, warm
    import mechderive.scenes.planner  # noqa: F401

    results = []
    with tempfile.TemporaryDirectory(prefix="mechderive-numeric-sweep-") as tmp:
        for case in cases:
            r = run_case(case, Path(tmp), timeout)
            results.append(r)
            if verbose:
                print(f"{r['kind']:9s} {r['seconds']:6.2f}s  {r['name']}  --  {r['detail']}", flush=True)
    return results


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--system", help="only the cases whose kind starts with this (e.g. heavy_top)")
    parser.add_argument("--match", help="only the cases whose name contains this")
    parser.add_argument("--timeout", type=float, default=30.0)
    parser.add_argument("--json", metavar="FILE", help="write the results to FILE")
    args = parser.parse_args(argv)
    cases = all_cases()
    if args.system:
        cases = [c for c in cases if c.kind.startswith(args.system)]
    if args.match:
        cases = [c for c in cases if args.match in c.name]
    results = sweep(cases, args.timeout)
    counts: dict[str, int] = {}
    for r in results:
        counts[r["kind"]] = counts.get(r["kind"], 0) + 1
    print(f"{len(results)} cases: " + ", ".join(f"{k} {n}" for k, n in sorted(counts.items())))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0 if all(r["kind"] in GOOD for r in results) else 1


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    sys.exit(main())
