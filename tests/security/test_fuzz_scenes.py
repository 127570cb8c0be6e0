"""Fuzzing ``mechderive run FILE``: every scene file ends in a result or in one line saying what is wrong.

Scene files are made from the built-in scenes (shortened, so that a valid one solves in ~0.1 s)
by one mutation each: a key removed, added or renamed; a value replaced by a number, a string,
a list, a table, a boolean, a date, NaN, inf, 1e400 or an integer of 401 or 4400 digits; or the
text itself cut short, given junk bytes, a duplicated line or nesting 5000 deep.  Each is run
in-process through :func:`mechderive.cli.main` and must

- exit 0 (writing the table), or exit 2 with exactly one stderr line ``mechderive: error: scene ...``
  that names the key the mutation touched when one is at fault;
- print no traceback and no warning (a RuntimeWarning before the error is noise in front of it);
- leave no output file, complete or partial, and no temporary file after a failure;
- take at most 10 s and raise the process's peak memory by at most 1 GB.

Exit 70 (an internal error) or any other status is a bug.  The default run draws numbers from
what the schema refuses and from ordinary magnitudes (|x| ≤ 100); magnitudes the schema accepts
but the solvers must then handle (1e300, 5e-324: :data:`EXTREMES`) are swept key by key in a slow
test, each run forked and killed at the time limit.
The budgets are for a warm disk cache of compiled code: a module fixture first runs each base
scene once, so that the derivations (the same the built-in scenes need) are not timed.
"""

from __future__ import annotations

import contextlib
import datetime
import io
import os
import pickle
import re
import resource
import select
import signal
import tempfile
import time
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mechderive.cli import main
from mechderive.scenes.builtin import scene_text
from mechderive.systems.deformable.cat import DEFAULTS as CAT_DEFAULTS

TIME_LIMIT_S = 10.0
MEMORY_LIMIT_BYTES = 1_000_000_000


class Raw(str):
    """A TOML literal written as it is: what a Python value cannot say (1e400, nan, a 4400-digit integer)."""


# ----------------------------------------------------------------------------- TOML text

_BARE = re.compile(r"[A-Za-z0-9_-]+")


# The package's own TOML string writer (scene_to_toml uses it): the fuzz writes scenes the way the package does.
from mechderive.scenes.schema import _toml_string as toml_string  # noqa: E402


def toml_key(k: str) -> str:
    return k if _BARE.fullmatch(k) else toml_string(k)


def toml_value(v: Any) -> str:
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)  # finite: nan and inf are drawn as Raw literals
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, (datetime.date, datetime.time)):
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML for {v!r}")


def toml_document(doc: dict[str, Any]) -> str:
    """Top-level values first, then one ``[table]`` per table (nested tables inline)."""
    lines = [f"{toml_key(k)} = {toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for k, v in doc.items():
        if isinstance(v, dict):
            lines += ["", f"[{toml_key(k)}]"] + [f"{toml_key(kk)} = {toml_value(x)}" for kk, x in v.items()]
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- the scenes mutated

def _shortened(name: str, t_end: float | None, samples: int) -> dict[str, Any]:
    doc = tomllib.loads(scene_text(name))
    doc["time"]["samples"] = samples
    if t_end is not None:
        doc["time"]["t_end"] = t_end
    return doc


#: Built-in scenes, shortened: each form of each system (heavy top with M g l and with Mgl).
BASES: dict[str, dict[str, Any]] = {
    "default": _shortened("default", 2.0, 11),
    "gyroscope": _shortened("gyroscope", 0.2, 11),
    "free_top_tumbling": _shortened("free_top_tumbling", 2.0, 11),
    "falling_cat": _shortened("falling_cat", None, 11),
    # the cat's [parameters] spelled out (the built-in scene takes the defaults), for mutating them
    "falling_cat_body": {**_shortened("falling_cat", None, 11), "parameters": dict(CAT_DEFAULTS)},
}

#: Never valid for any key: the error must name the key it is under.
REFUSED_NUMBERS = [Raw("nan"), Raw("+nan"), Raw("-nan"), Raw("inf"), Raw("-inf"), Raw("1e400"), Raw("-1.5e999"),
                   Raw("1" + "0" * 400), Raw("-" + "9" * 4400), Raw("1" * 4301), Raw("0x" + "f" * 300),
                   Raw("0x" + "f" * 5000), Raw("0o" + "7" * 400), Raw("1_000" * 200), Raw("1e" + "9" * 5000),
                   Raw("1" * 400 + ".5")]
DATES = [Raw("1979-05-27T07:32:00Z"), Raw("1979-05-27"), Raw("07:32:00"), Raw("1979-05-27T00:32:00.999999-07:00"),
         Raw("0001-01-01T00:00:00-23:59")]
#: Ordinary magnitudes, valid for some keys and not others.
ORDINARY = [0, 1, 2, 3, -1, 0.0, 0.5, 1.5, -0.25, 3.0, 7.5, -2.5, 1e-3, 10.0, 100, Raw("1e-400"), Raw("-0.0"),
            Raw("1_0.5e-0_1"), Raw("-1e-" + "9" * 5000)]
#: Accepted by the schema (finite doubles) and left to the solvers: swept only in the slow test.
EXTREMES = [1e300, -1e300, 1e308, 1.7976931348623157e308, 1e150, 1e-150, 1e-300, 5e-324, 4e-320, 1e30, 1e-30,
            2.0**-1022, 1e15, -1e15]
NAMES = ["I1", "I2", "I3", "M", "g", "l", "Mgl", "theta", "phi", "psi", "theta_dot", "phi_dot", "psi_dot",
         "omega", "t_end", "samples", "quantities", "system", "method", "rtol", "strict", "name", "parameters",
         "initial", "time", "output", "half_mass", "radius", "peak_bend", "dt", "colour", "a b", "1", "é",
         "__import__('os')", "x" * 60, "new\nline"]
STRINGS = ["", "heavy_top", "free_top", "falling_cat", "auto", "exact", "theta", "energy", "1.0", "nan",
           "__import__('os').system('true')", "{{7*7}}", "x" * 200, "\u202e\u0000", "é"]
# "integrate" compiles a C stepper per system (seconds, cold): only in the slow sweep.
SLOW_STRINGS = ["integrate", *STRINGS]


def _scalars(numbers: list, strings: list) -> st.SearchStrategy:
    return st.one_of(st.sampled_from(numbers), st.sampled_from(REFUSED_NUMBERS), st.sampled_from(DATES),
                     st.sampled_from(strings), st.booleans())


def _values(numbers: list, strings: list) -> st.SearchStrategy:
    scalars = _scalars(numbers, strings)
    return st.one_of(
        scalars,
        st.lists(scalars, max_size=4),
        st.lists(st.lists(scalars, max_size=3), max_size=3),
        st.dictionaries(st.sampled_from(NAMES), scalars, max_size=3),
        st.dictionaries(st.sampled_from(NAMES), st.dictionaries(st.sampled_from(NAMES), scalars, max_size=2),
                        max_size=2),
        st.lists(st.sampled_from(["theta", "phi", "omega1", "energy", "R11", "flip_angle", "L1", "q0", "apex_x",
                                  "theta", "nope"]), max_size=5),
    )


def _display(table: str | None, key: str, *, as_table: bool = False) -> str:
    """How an error message shows a key: ``[table].key``, ``key``, ``[key]`` for a table; odd names quoted."""
    shown = key if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key) and len(key) <= 40 else repr(key)
    if as_table:
        return f"[{shown}]"
    return f"[{table}].{shown}" if table else shown


def _is_refused(value: Any) -> bool:
    """A value no key accepts: then the error must name the key it is under."""
    if isinstance(value, Raw):
        return value in REFUSED_NUMBERS or value in DATES
    return isinstance(value, (dict, datetime.date, datetime.time))


@dataclass
class Case:
    """One generated scene file: its bytes, what was done to the base, and the names the error may give."""

    data: bytes
    mutation: str
    expect: list[str] = field(default_factory=list)  # the message must contain one of these (if non-empty)
    doc: dict[str, Any] = field(default_factory=dict)  # the mutated document (before any text mutation)


@st.composite
def _mutated(draw: Any, numbers: list, strings: list) -> Case:
    base_name = draw(st.sampled_from(sorted(BASES)))
    doc = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BASES[base_name].items()}
    values = _values(numbers, strings)
    leaves = [(None, k) for k, v in doc.items() if not isinstance(v, dict)]
    leaves += [(t, k) for t, v in doc.items() if isinstance(v, dict) for k in v]
    tables = [t for t, v in doc.items() if isinstance(v, dict)]
    kind = draw(st.sampled_from(["number", "number", "replace", "replace", "table", "remove", "add", "rename",
                                 "text"]))
    if kind == "number":  # a number for a number: mostly valid scenes, which are solved
        numeric = [(t, k) for t, k in leaves if type((doc[t] if t else doc)[k]) in (int, float)]
        table, key = draw(st.sampled_from(numeric))
        value = draw(st.sampled_from(numbers))
        (doc[table] if table else doc)[key] = value
        return _case(doc, toml_document(doc).encode(), f"{base_name}: {_display(table, key)} = {toml_value(value)}")
    if kind == "replace":
        table, key = draw(st.sampled_from(leaves))
        value = draw(values)
        (doc[table] if table else doc)[key] = value
        expect = [_display(table, key)] if _is_refused(value) else []
        return _case(doc, toml_document(doc).encode(), f"{base_name}: {_display(table, key)} = {toml_value(value)[:80]}",
                    expect)
    if kind == "table":
        table = draw(st.sampled_from(tables))
        value = draw(_scalars(numbers, strings))
        doc[table] = value
        return _case(doc, toml_document(doc).encode(), f"{base_name}: [{table}] = {toml_value(value)[:80]}",
                    [f"[{table}]"])
    if kind == "remove":
        table, key = draw(st.sampled_from(leaves + [(None, t) for t in tables]))
        del (doc[table] if table else doc)[key]
        # a key with alternatives (Mgl or M, g, l) may be reported as the alternative missing
        return _case(doc, toml_document(doc).encode(), f"{base_name}: removed {_display(table, key)}",
                    [_display(table, key)] + ([f"[{table}]."] if table else []))
    if kind == "add":
        table = draw(st.sampled_from([None, *tables]))
        target = doc[table] if table else doc
        key = draw(st.sampled_from([n for n in NAMES if n not in target]))
        value = draw(values)
        target[key] = value
        shown = _display(table, key)
        # a table at the top level is an unknown table, [key], unless key is a known top-level key (rtol)
        names = [shown, _display(table, key, as_table=True)] if table is None else [shown]
        return _case(doc, toml_document(doc).encode(), f"{base_name}: added {shown} = {toml_value(value)[:80]}", names)
    if kind == "rename":
        table, key = draw(st.sampled_from(leaves))
        target = doc[table] if table else doc
        new = draw(st.sampled_from([n for n in NAMES if n not in target]))
        target[new] = target.pop(key)
        return _case(doc, toml_document(doc).encode(), f"{base_name}: renamed {_display(table, key)} to {new!r}",
                    [_display(table, key), _display(table, new), _display(None, new, as_table=True)]
                    + ([f"[{table}]."] if table else []))
    text = toml_document(doc).encode()
    how = draw(st.sampled_from(["truncate", "junk", "duplicate", "nest", "huge_line"]))
    at = draw(st.integers(0, len(text)))
    if how == "truncate":
        return _case(doc, text[:at], f"{base_name}: cut at byte {at}")
    if how == "junk":
        junk = draw(st.binary(min_size=1, max_size=8))
        return _case(doc, text[:at] + junk + text[at:], f"{base_name}: {junk!r} at byte {at}")
    lines = text.split(b"\n")
    i = draw(st.integers(0, len(lines) - 1))
    if how == "duplicate":
        return _case(doc, b"\n".join(lines[:i + 1] + lines[i:]), f"{base_name}: line {i + 1} duplicated")
    if how == "nest":
        depth = draw(st.sampled_from([10, 300, 5000]))
        opener, closer = draw(st.sampled_from([("[", "]"), ("{a = ", "}")]))
        table, key = draw(st.sampled_from(leaves))
        nested = opener * depth + "1" + closer * depth
        (doc[table] if table else doc)[key] = Raw(nested)
        return _case(doc, toml_document(doc).encode(), f"{base_name}: {_display(table, key)} nested {depth} deep",
                    [_display(table, key)] if depth < 300 else [])
    return _case(doc, text + b"x = " + b"1" * 50_000 + b"\n", f"{base_name}: a line of 50000 digits")


def _case(doc: dict[str, Any], *args: Any) -> Case:
    case = Case(*args)
    case.doc = doc
    return case


def scene_cases(numbers: list = ORDINARY, strings: list = STRINGS) -> st.SearchStrategy:
    """Scene files made by one mutation of a base scene."""
    return _mutated(numbers, strings)


# ----------------------------------------------------------------------------- running one

@dataclass
class Outcome:
    status: int
    stdout: str
    stderr: str
    seconds: float
    peak_growth_bytes: int
    warnings: list[str]
    files: list[str]


def run_case(case: Case, workdir: Path) -> Outcome:
    """``mechderive run scene.toml -o out.csv`` in-process, in the empty directory ``workdir``."""
    scene, out = workdir / "scene.toml", workdir / "out.csv"
    scene.write_bytes(case.data)
    stdout, stderr = io.StringIO(), io.StringIO()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(stdout), \
            contextlib.redirect_stderr(stderr):
        warnings.simplefilter("always")
        status = main(["run", str(scene), "-o", str(out)])
    seconds = time.perf_counter() - start
    growth = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - peak) * 1024  # Linux: KiB
    return Outcome(status, stdout.getvalue(), stderr.getvalue(), seconds, growth,
                   [f"{w.category.__name__}: {w.message}" for w in caught],
                   sorted(p.name for p in workdir.iterdir() if p.name != "scene.toml"))


def problems(case: Case, outcome: Outcome) -> list[str]:
    """What is wrong with ``outcome`` (empty: all is well)."""
    found = []
    lines = outcome.stderr.splitlines()
    if outcome.status == 0:
        if outcome.files != ["out.csv"]:
            found.append(f"exit 0 but the directory holds {outcome.files}")
    elif outcome.status == 2:
        if len(lines) != 1 or not lines[0].startswith("mechderive: error: scene "):
            found.append(f"expected one line 'mechderive: error: scene ...', got {outcome.stderr[:400]!r}")
        elif case.expect and not any(name in lines[0] for name in case.expect):
            found.append(f"the message names none of {case.expect}: {lines[0][:300]!r}")
        if outcome.files:
            found.append(f"failed but left {outcome.files}")
    else:
        found.append(f"exit {outcome.status}: {outcome.stderr[:400]!r}")
    if "Traceback" in outcome.stderr or "Traceback" in outcome.stdout:
        found.append("a traceback was printed")
    if outcome.warnings:
        found.append(f"warnings: {outcome.warnings[:3]}")
    if outcome.seconds > TIME_LIMIT_S:
        found.append(f"took {outcome.seconds:.1f} s")
    if outcome.peak_growth_bytes > MEMORY_LIMIT_BYTES:
        found.append(f"peak memory grew by {outcome.peak_growth_bytes / 1e9:.2f} GB")
    return found


def run_case_forked(case: Case, workdir: Path, timeout: float = 3 * TIME_LIMIT_S) -> Outcome | None:
    """:func:`run_case` in a forked child, killed after ``timeout`` s (then None): for inputs that may hang
    in compiled code, which neither SIGALRM nor Ctrl-C interrupts (issue 12, finding 4)."""
    reader, writer = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            data = pickle.dumps(run_case(case, workdir))
        except BaseException as exc:  # noqa: BLE001 - a failure of the harness, reported as such
            data = pickle.dumps(Outcome(-1, "", f"harness: {type(exc).__name__}: {exc}", 0.0, 0, [], []))
        os.write(writer, data)
        os._exit(0)
    os.close(writer)
    try:
        ready, _, _ = select.select([reader], [], [], timeout)
        if not ready:
            os.kill(pid, signal.SIGKILL)
            return None
        chunks = []
        while chunk := os.read(reader, 1 << 16):
            chunks.append(chunk)
        return pickle.loads(b"".join(chunks))
    finally:
        os.close(reader)
        os.waitpid(pid, 0)


@pytest.fixture(scope="module")
def warm_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Run each base scene once, so that deriving and compiling (a cold cache) is not what is timed."""
    for name, doc in BASES.items():
        outcome = run_case(Case(toml_document(doc).encode(), name), Path(tmp_path_factory.mktemp(name)))
        assert outcome.status == 0, outcome.stderr


def _check(case: Case, tmp_path: Path) -> None:
    outcome = run_case(case, Path(tempfile.mkdtemp(dir=tmp_path)))
    assert problems(case, outcome) == [], case.mutation


# ----------------------------------------------------------------------------- the tests

@settings(max_examples=100, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(case=scene_cases())
def test_every_scene_file_runs_or_is_refused_in_one_line(case: Case, tmp_path: Path, warm_cache: None) -> None:
    _check(case, tmp_path)


@pytest.mark.slow
@settings(max_examples=1500, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(case=scene_cases(strings=SLOW_STRINGS))
def test_sweep_every_scene_file_runs_or_is_refused_in_one_line(case: Case, tmp_path: Path,
                                                               warm_cache: None) -> None:
    _check(case, tmp_path)


def _numeric_keys(doc: dict[str, Any]) -> list[tuple[str | None, str]]:
    """The numbers of a base scene, as (table, key); ``omega[i]`` for a free top's components."""
    keys = [(t, k) for t, v in doc.items() if isinstance(v, dict) for k, x in v.items() if type(x) in (int, float)]
    keys += [(None, k) for k, x in doc.items() if type(x) in (int, float)] + [(None, "rtol")]
    if "initial" in doc and "omega" in doc["initial"]:
        keys += [("initial", f"omega[{i}]") for i in range(3)] + [("initial", k) for k in ("phi", "theta", "psi")]
    return list(dict.fromkeys(keys))


def _set(doc: dict[str, Any], table: str | None, key: str, value: Any) -> dict[str, Any]:
    doc = {k: (dict(v) if isinstance(v, dict) else v) for k, v in doc.items()}
    if key.startswith("omega["):
        omega = list(doc["initial"]["omega"])
        omega[int(key[6])] = value
        doc["initial"]["omega"] = omega
    else:
        (doc[table] if table else doc)[key] = value
    return doc


@pytest.mark.slow
def test_extreme_magnitudes_of_every_numeric_key_run_or_are_refused_in_one_line(tmp_path: Path,
                                                                               warm_cache: None) -> None:
    """Every number of every base scene set to each of :data:`EXTREMES` (finite doubles the schema accepts),
    for the solvers to handle or refuse; each run forked and killed after :data:`TIME_LIMIT_S` (some hung
    in compiled code).  All problems are listed at once."""
    found = []
    for base, doc in BASES.items():
        for table, key in _numeric_keys(doc):
            for value in EXTREMES:
                case = _case(_set(doc, table, key, value), b"", f"{base}: {_display(table, key)} = {value!r}")
                case.data = toml_document(case.doc).encode()
                outcome = run_case_forked(case, Path(tempfile.mkdtemp(dir=tmp_path)), timeout=TIME_LIMIT_S)
                if outcome is None:
                    found.append(f"{case.mutation}: still running after {TIME_LIMIT_S} s")
                    continue
                found += [f"{case.mutation}: {problem}" for problem in problems(case, outcome)]
    assert found == [], f"{len(found)} problems:\n" + "\n".join(found)
