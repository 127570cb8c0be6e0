"""Issue 12, findings 2, 3 and the cache item of 7: the disk cache can be neither poisoned nor broken.

Each reproduction of the issue is a test: a cache folder others can write or another uid owns is
refused with one warning and the run succeeds without it; code planted in the cache by another
uid (``<fp>/heavy_top.invariants.numpy.py``, its ``.marshal``, ``c/dop853_*.so``) never runs — a
canary file it would write stays absent — and the numbers are right; an edited, truncated or
random cached file, a foreign library or another system's, is rebuilt and replaced; no build
leaves a folder in ``$TMPDIR``.  The planting is done as uid 65534 when the tests run as root,
else (the permission variant) by making the planted file or folder writable by others.

Cost: the heavy top's functions are rebuilt from the process's derivation (shared with the
suite's heavy-top tests; ~50 ms a rebuild), the C tests compile a one-line library (~40 ms), one
test compiles the heavy top's stepper; subprocesses only for the truncated library, which could
crash the process (SIGBUS), and for what a user sees on stderr.
"""

from __future__ import annotations

import logging
import marshal
import math
import os
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest

from mechderive.core import cachefs, cbuild, codecache

from ..conftest import run_python

ROOT = os.geteuid() == 0
OTHER = 65534  # nobody
HAS_CC = cbuild.c_enabled()
needs_cc = pytest.mark.skipif(not HAS_CC, reason="no C compiler on this machine")

# heavy top of the README: I1 (about the pivot), I3, M, g, l; a state with every rate non-zero
PARAMS = (1.0, 0.5, 1.0, 9.81, 0.1)
STATE = (0.5, 0.3, -0.7, 20.0)  # θ, θ̇, φ̇, ψ̇


def _energy_365(I1, I3, M, g, l, theta, theta_dot, phi_dot, psi_dot) -> float:
    """E = ½ I1 (θ̇² + φ̇² sin²θ) + ½ I3 ω3² + M g l cos θ, ω3 = ψ̇ + φ̇ cos θ (3.65), by hand."""
    w3 = psi_dot + phi_dot * math.cos(theta)
    kinetic = 0.5 * I1 * (theta_dot**2 + phi_dot**2 * math.sin(theta) ** 2) + 0.5 * I3 * w3**2
    return kinetic + M * g * l * math.cos(theta)


E_REF = _energy_365(*PARAMS, *STATE)
E_SCENE = _energy_365(*PARAMS, 0.5, 0.0, 0.0, 20.0)  # SCENE below: let go at θ = 0.5 spinning at 20 rad/s
INVARIANTS = "heavy_top.invariants.numpy.py"
ANSWER_C = "int md_answer(void) { return 42; }\n"


def _owned_by_someone_else(path: Path) -> None:
    """Make ``path`` another uid's (as root), else writable by everybody (the permission variant)."""
    if ROOT:
        os.chown(path, OTHER, OTHER, follow_symlinks=False)
    else:
        os.chmod(path, 0o777 if path.is_dir() else 0o666)


def _canary_py(canary: Path) -> str:
    return f"open({str(canary)!r}, 'w').write('ran')\ndef _lambdifygenerated(*args):\n    return [0.0, 0.0, 0.0]\n"


def _canary_c(canary: Path) -> str:
    return textwrap.dedent(f"""
        #include <stdio.h>
        __attribute__((constructor)) static void planted(void) {{
            FILE *f = fopen("{canary}", "w"); if (f) {{ fputs("ran", f); fclose(f); }}
        }}
        int md_answer(void) {{ return -1; }}
    """)


def _compile(source: str, target: Path) -> Path:
    subprocess.run([cbuild.compiler(), "-shared", "-fPIC", "-o", str(target), "-x", "c", "-"], input=source,
                   text=True, check=True)
    return target


def _invariants():
    """The heavy top's compiled (E, p_φ, p_ψ) through the disk cache, as the planner obtains it."""
    from mechderive.systems.heavy_top import system

    codecache.clear_memory()
    return system._heavy_invariants.__wrapped__()


def _answer():
    cbuild.clear_memory()
    return cbuild.load_library("sec_answer", lambda: ANSWER_C)


@pytest.fixture(autouse=True)
def _disk_cache_back():
    """Each test points the disk cache at a folder of its own; the switch goes back after it.  What
    the tests leave in memory was built by the package's own builders, so it stays."""
    yield
    codecache.set_disk_cache(None)


@pytest.fixture(scope="module")
def warm(tmp_path_factory) -> Path:
    """A cache holding the heavy top's invariants (source and bytecode), made once for the module."""
    root = tmp_path_factory.mktemp("warm") / "cache"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MECHDERIVE_CACHE_DIR", str(root))
        codecache.set_disk_cache(True)
        _invariants()
        _invariants()  # the first load from disk writes the bytecode
        codecache.set_disk_cache(None)
    return root


@pytest.fixture
def cache(warm, tmp_path, monkeypatch) -> Path:
    """A private copy of the warm cache for one test; returns its fingerprint folder."""
    root = tmp_path / "cache"
    shutil.copytree(warm, root, symlinks=True)
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(root))
    codecache.set_disk_cache(True)
    return root / codecache.fingerprint()


def _how(name: str) -> str:
    return [how for n, how, _ in codecache.compile_log() if n == name][-1]


def _energy(func) -> float:
    return float(func(*PARAMS, *STATE)[0])


def _refusals(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "mechderive.cache"]


# --- finding 2: folders others can write, or another uid owns, are refused -----------------------------

SCENE = """
system = "heavy_top"
method = "exact"
rtol = 1e-10
[parameters]
I1 = 1.0
I3 = 0.5
M = 1.0
g = 9.81
l = 0.1
[initial]
theta = 0.5
phi = 0.0
psi = 0.0
theta_dot = 0.0
phi_dot = 0.0
psi_dot = 20.0
[time]
t_end = 2.0
samples = 5
[output]
quantities = ["theta", "energy"]
"""


@pytest.mark.parametrize("mode", [0o777, 0o775, 0o1777], ids=["world", "group", "sticky"])
def test_a_root_others_can_write_is_refused_and_the_run_succeeds(cache, tmp_path, mode, caplog, capsys):
    from mechderive.cli import main
    from mechderive.systems.heavy_top import system as heavy_top

    canary = tmp_path / "canary"
    (cache / INVARIANTS).write_text(_canary_py(canary))  # what anybody could have put there
    (cache / (INVARIANTS + ".marshal")).unlink()
    cache.parent.chmod(mode)
    scene, out = tmp_path / "top.toml", tmp_path / "out.csv"
    scene.write_text(SCENE)
    heavy_top._heavy_invariants.cache_clear()
    codecache.clear_memory()
    try:
        with caplog.at_level(logging.WARNING, logger="mechderive.cache"):
            status = main(["run", str(scene), "-o", str(out)])
    finally:
        heavy_top._heavy_invariants.cache_clear()
    assert status == 0 and not canary.exists()
    energy = np.loadtxt(out, delimiter=",", skiprows=1)[:, 2]
    assert energy == pytest.approx(E_SCENE, rel=1e-12)  # E is a constant of the exact motion; 1e-12 ≫ rounding
    [line] = _refusals(caplog)  # one line however many functions were looked up
    assert "\n" not in line and f"{cache.parent} is writable by group or others (mode {mode:04o})" in line
    assert "running without a disk cache" in line and "chmod go-w" in line


def _plant_folder(cache: Path, where: str) -> Path:
    """Make the folder ``where`` someone else's (or a link to someone else's); returns the folder a
    planted file goes into."""
    if where == "root":
        _owned_by_someone_else(cache.parent)
        return cache
    if where == "fingerprint":
        _owned_by_someone_else(cache)
        return cache
    if where == "root link":  # MECHDERIVE_CACHE_DIR is a link to a folder of someone else
        target = cache.parent.with_name("elsewhere")
        cache.parent.rename(target)
        cache.parent.symlink_to(target)
        _owned_by_someone_else(target)
        return target / cache.name
    if where == "fingerprint link":  # planted in a folder of ours: never followed
        target = cache.parent.with_name("elsewhere")
        cache.rename(target)
        cache.symlink_to(target)
        return target
    raise AssertionError(where)


@pytest.mark.parametrize("where", ["root", "fingerprint", "root link", "fingerprint link"])
def test_a_folder_of_someone_else_is_refused(cache, tmp_path, where, caplog):
    canary = tmp_path / "canary"
    folder = _plant_folder(cache, where)
    (folder / INVARIANTS).write_text(_canary_py(canary))
    (folder / (INVARIANTS + ".marshal")).unlink()
    with caplog.at_level(logging.WARNING, logger="mechderive.cache"):
        func = _invariants()
    assert not canary.exists() and _how("heavy_top.invariants") == "compiled"
    assert _energy(func) == pytest.approx(E_REF, rel=1e-14)  # the compiled (3.65): a few roundings
    [line] = _refusals(caplog)
    assert "disk cache refused" in line
    if "link" in where and where != "root link":
        assert "is a symbolic link" in line
    elif ROOT:
        assert f"owned by uid {OTHER}" in line


def test_a_root_link_owned_by_someone_else_is_refused(tmp_path, monkeypatch, caplog):
    if not ROOT:
        pytest.skip("only root can make a link another uid owns")
    mine = tmp_path / "mine"
    mine.mkdir(mode=0o700)
    link = tmp_path / "link"
    link.symlink_to(mine)
    os.chown(link, OTHER, OTHER, follow_symlinks=False)  # they could repoint it at any time
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(link))
    codecache.set_disk_cache(True)
    with caplog.at_level(logging.WARNING, logger="mechderive.cache"):
        assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14)
    [line] = _refusals(caplog)
    assert f"is a symbolic link owned by uid {OTHER}" in line and not any(mine.iterdir())


def test_the_warning_is_one_line_on_stderr(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    code = ("from mechderive.core import cachefs\n"
            "for _ in range(3):\n"
            "    with cachefs.directory(__import__('pathlib').Path(%r), ('fp',), create=True) as d:\n"
            "        print(d)\n") % str(shared)
    proc = run_python("-c", code)
    assert proc.returncode == 0 and proc.stdout.split() == ["None"] * 3
    [line] = proc.stderr.splitlines()
    assert line.startswith("mechderive: warning: disk cache refused: ") and not (shared / "fp").exists()


def test_folders_are_created_private(tmp_path, monkeypatch):
    root = tmp_path / "a" / "b" / "cache"
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(root))
    codecache.set_disk_cache(True)
    _invariants()
    for folder in (tmp_path / "a", tmp_path / "a" / "b", root, root / codecache.fingerprint()):
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700, folder
    files = list((root / codecache.fingerprint()).iterdir())
    assert [f.name for f in files] == [INVARIANTS]  # no temporary file left beside it
    assert stat.S_IMODE(files[0].stat().st_mode) == 0o600


# --- finding 2: files planted in the cache never run -----------------------------------------------------

def _plant_source(cache: Path, canary: Path, *, sealed: bool) -> None:
    payload = _canary_py(canary).encode()
    (cache / INVARIANTS).write_bytes(cachefs.seal(INVARIANTS, payload) if sealed else payload)
    (cache / (INVARIANTS + ".marshal")).unlink()
    _owned_by_someone_else(cache / INVARIANTS)


def _plant_bytecode(cache: Path, canary: Path, *, sealed: bool) -> None:
    code = marshal.dumps(compile(_canary_py(canary), "planted", "exec"))
    target = cache / (INVARIANTS + ".marshal")
    if sealed:  # sealed as if for the genuine source beside it: only the owner check stops it
        import hashlib

        source = cachefs.unseal(INVARIANTS, (cache / INVARIANTS).read_bytes())
        code = cachefs.seal(f"{target.name}|{hashlib.sha256(source).hexdigest()}", code)
    target.write_bytes(code)
    _owned_by_someone_else(target)


def _plant_link(cache: Path, canary: Path, *, sealed: bool) -> None:
    planted, payload = cache.parent.parent / "planted.py", _canary_py(canary).encode()
    planted.write_bytes(cachefs.seal(INVARIANTS, payload) if sealed else payload)  # a file of ours, even
    (cache / INVARIANTS).unlink()
    (cache / INVARIANTS).symlink_to(planted)
    (cache / (INVARIANTS + ".marshal")).unlink()


@pytest.mark.parametrize("plant", [_plant_source, _plant_bytecode, _plant_link], ids=["py", "marshal", "link"])
@pytest.mark.parametrize("sealed", [False, True], ids=["raw", "with-a-valid-hash"])
def test_planted_code_never_runs(cache, tmp_path, plant, sealed):
    canary = tmp_path / "canary"
    plant(cache, canary, sealed=sealed)
    func = _invariants()
    assert not canary.exists()
    assert _energy(func) == pytest.approx(E_REF, rel=1e-14)
    # the planted file is replaced by ours, which the next process loads
    for name in (INVARIANTS, INVARIANTS + ".marshal"):
        path = cache / name
        if path.exists():
            assert not path.is_symlink() and path.stat().st_uid == os.geteuid()
    assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14) and _how("heavy_top.invariants") == "disk"


def test_an_edited_source_is_detected_and_rebuilt(cache):
    path = cache / INVARIANTS
    path.write_text(path.read_text().replace("return [", "return [1.0 + ", 1))  # the wrong energy column
    (cache / (INVARIANTS + ".marshal")).unlink()
    assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14)
    assert _how("heavy_top.invariants") == "compiled"
    assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14) and _how("heavy_top.invariants") == "disk"


def test_edited_bytecode_is_detected_and_recompiled(cache):
    target = cache / (INVARIANTS + ".marshal")
    head = target.read_bytes().split(b"\n", 1)[0]
    text = (cache / INVARIANTS).read_text()
    edited = compile(text.replace("return [", "return [1.0 + ", 1), "x", "exec")
    target.write_bytes(head + b"\n" + marshal.dumps(edited))
    assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14)


# --- finding 3: a corrupt cache is rebuilt ----------------------------------------------------------

class _Blocked(Exception):
    """Not an OSError: code that swallows failed reads must not swallow this."""


@pytest.fixture
def no_hang():
    """A read that would block (a FIFO) fails the test in 5 s instead of hanging the suite."""
    def expire(*_):
        raise _Blocked("blocked reading the cache")
    old = signal.signal(signal.SIGALRM, expire)
    signal.alarm(5)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


@pytest.mark.parametrize("damage", ["random bytes", "truncated", "empty", "fifo", "directory"])
def test_a_corrupt_source_is_rebuilt(cache, damage, no_hang):
    path = cache / INVARIANTS
    (cache / (INVARIANTS + ".marshal")).unlink()
    data = path.read_bytes()
    if damage == "random bytes":
        path.write_bytes(np.random.default_rng(12).bytes(500))  # the UnicodeDecodeError
    elif damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    else:
        path.unlink()
        os.mkfifo(path) if damage == "fifo" else path.mkdir()
    assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14)
    if damage != "directory":  # a folder cannot be replaced by a file: that function is just not kept
        assert _energy(_invariants()) == pytest.approx(E_REF, rel=1e-14) and _how("heavy_top.invariants") == "disk"


# --- finding 2 and 3 for compiled C ----------------------------------------------------------------

@pytest.fixture
def c_cache(tmp_path, monkeypatch) -> Path:
    """A fresh cache holding the library sec_answer; returns the library's path."""
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path / "cache"))
    codecache.set_disk_cache(True)
    assert _answer().md_answer() == 42
    return cbuild._library_path("sec_answer")


def _replace(path: Path, data: bytes) -> None:
    """New bytes under ``path`` in a new file: the library loaded from the old one (mapped, in this
    process) is not pulled from under it — a regression fails as an assertion, not a SIGBUS."""
    path.unlink()
    path.write_bytes(data)


def _rebuilt_and_replaced(path: Path) -> None:
    assert _answer().md_answer() == 42 and cbuild.build_log()[-1][:2] == ("sec_answer", "built")
    assert _answer().md_answer() == 42 and cbuild.build_log()[-1][:2] == ("sec_answer", "disk")
    assert path.stat().st_uid == os.geteuid() and stat.S_IMODE(path.stat().st_mode) == 0o600


@needs_cc
@pytest.mark.parametrize("variant", ["library", "library and its hash", "link", "folder"])
def test_a_planted_library_never_runs(c_cache, tmp_path, variant, caplog):
    canary = tmp_path / "canary"
    evil = _compile(_canary_c(canary), tmp_path / "evil.so")
    sidecar = Path(str(c_cache) + ".sha256")
    if variant == "link":
        c_cache.unlink()
        c_cache.symlink_to(evil)
    else:
        _replace(c_cache, evil.read_bytes())
        if variant == "library and its hash":  # an attacker can compute the hash: the owner check stops it
            sidecar.write_text(cachefs.digest(c_cache.name, evil.read_bytes()) + "\n")
            _owned_by_someone_else(sidecar)
        _owned_by_someone_else(c_cache.parent if variant == "folder" else c_cache)
    with caplog.at_level(logging.WARNING, logger="mechderive.cache"):
        if variant == "folder":  # refused: built, and kept in memory only
            assert _answer().md_answer() == 42 and cbuild.build_log()[-1][:2] == ("sec_answer", "built")
        else:
            _rebuilt_and_replaced(c_cache)
    assert not canary.exists()
    assert bool(_refusals(caplog)) == (variant == "folder")


def _other_library(tmp_path: Path, path: Path) -> None:
    """Another library of ours, with its genuine hash, copied under this name (the other system's)."""
    other = cbuild._library_path("sec_other")
    cbuild.load_library("sec_other", lambda: "int md_answer(void) { return 7; }\n")
    _replace(path, other.read_bytes())
    shutil.copyfile(str(other) + ".sha256", str(path) + ".sha256")


def _other_machine(tmp_path: Path, path: Path) -> None:
    """This library marked for another machine (ELF e_machine = AArch64), its hash recomputed: it
    verifies, and dlopen refuses it — a cache shared between machines."""
    data = bytearray(path.read_bytes())
    data[18:20] = (183).to_bytes(2, "little")
    _replace(path, bytes(data))
    Path(str(path) + ".sha256").write_text(cachefs.digest(path.name, bytes(data)) + "\n")


@needs_cc
@pytest.mark.parametrize("damage", ["random bytes", "empty", "foreign", "other system", "other machine", "fifo"])
def test_a_corrupt_library_is_rebuilt(c_cache, tmp_path, damage, no_hang):
    if damage == "random bytes":
        _replace(c_cache, np.random.default_rng(3).bytes(5000))
    elif damage == "empty":
        _replace(c_cache, b"")
    elif damage == "foreign":  # a real library without our symbols (the AttributeError)
        import _ctypes

        _replace(c_cache, Path(_ctypes.__file__).read_bytes())
    elif damage == "other system":
        _other_library(tmp_path, c_cache)
    elif damage == "other machine":
        _other_machine(tmp_path, c_cache)
    else:
        c_cache.unlink()
        os.mkfifo(c_cache)
    _rebuilt_and_replaced(c_cache)


@needs_cc
def test_a_truncated_library_is_never_mapped(c_cache, tmp_path):
    """The issue's SIGBUS (exit 135) when a truncated library is mapped: in a process of its own."""
    data = c_cache.read_bytes()
    _replace(c_cache, data[: len(data) // 2])
    code = textwrap.dedent("""
        from mechderive.core import cbuild
        lib = cbuild.load_library("sec_answer", lambda: "int md_answer(void) { return 42; }\\n")
        print(lib.md_answer(), [how for _, how, _ in cbuild.build_log()])
    """)
    proc = run_python("-c", code, env=dict(MECHDERIVE_CACHE_DIR=os.environ["MECHDERIVE_CACHE_DIR"],
                                           MECHDERIVE_NO_DISK_CACHE="0"), timeout=60)
    assert proc.returncode == 0, proc.stderr  # -7 (SIGBUS) before
    assert proc.stdout.split() == ["42", "['built']"] and c_cache.read_bytes() != data[: len(data) // 2]


@needs_cc
def test_a_planted_heavy_top_stepper_never_runs(tmp_path, monkeypatch):
    """The issue's ``c/dop853_*.so``: the heavy top integrated with C against SciPy's DOP853."""
    from mechderive.systems.heavy_top import integrate as hi

    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(tmp_path / "cache"))
    codecache.set_disk_cache(True)
    canary = tmp_path / "canary"
    evil = _compile(_canary_c(canary), tmp_path / "evil.so")
    target = cbuild._library_path("dop853_heavy_top")
    with cbuild._cache_folder(create=True) as folder:
        assert folder is not None
    shutil.copyfile(evil, target)
    _owned_by_someone_else(target)
    params, launch = dict(I1=1.0, I3=0.5, M=0.1, g=10.0, l=1.0), dict(theta=0.5, psi_dot=5.0)
    t = np.linspace(0.0, 2.0, 5)
    cbuild.clear_memory()
    c = hi.integrate_heavy_top(params, launch, t, rtol=1e-10, estimate_error=False, backend="c")
    s = hi.integrate_heavy_top(params, launch, t, rtol=1e-10, estimate_error=False, backend="scipy")
    assert not canary.exists() and c.backend == "c"
    # the same tableau and controller: the two differ by rounding (test_compiled_dop853.py)
    assert np.max(np.abs(c.omega - s.omega)) < 1e-12
    assert target.stat().st_uid == os.geteuid()


# --- finding 7: no cache, or no writable one, leaves nothing in $TMPDIR ------------------------------------

@needs_cc
@pytest.mark.parametrize("case", ["disk cache off", "root is a file", "root under a file", "compiler fails",
                                  "compiler hangs"])
def test_builds_leave_nothing_in_tmpdir(tmp_path, monkeypatch, case):
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmpdir))
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder should be")
    monkeypatch.setenv("MECHDERIVE_CACHE_DIR", str(blocker / "sub" if case == "root under a file" else blocker))
    codecache.set_disk_cache(case != "disk cache off")
    if case.startswith("compiler"):
        fake = tmp_path / "cc"
        fake.write_text("#!/bin/sh\nexit 1\n" if case == "compiler fails" else "#!/bin/sh\nexec sleep 30\n")
        fake.chmod(0o755)
        monkeypatch.setenv("CC", str(fake))
        monkeypatch.setattr(cbuild, "_COMPILE_SECONDS", 0.3)
        cbuild.clear_memory()
        assert cbuild.load_or_none("sec_answer", lambda: ANSWER_C) is None
        assert cbuild.why_unavailable("sec_answer").startswith("CBuildError: expected")
    else:
        assert _answer().md_answer() == 42
    assert list(tmpdir.iterdir()) == []
    assert blocker.read_text() == "a file where the cache folder should be"


@needs_cc
def test_a_read_only_cache_is_still_read(c_cache, monkeypatch):
    """A cache folder this process cannot write (mounted read-only, say) still serves what verifies."""
    monkeypatch.setattr(cachefs, "write_file", lambda *a: False)  # root ignores mode bits: simulate
    assert _answer().md_answer() == 42 and cbuild.build_log()[-1][:2] == ("sec_answer", "disk")
    _replace(c_cache, b"")
    assert _answer().md_answer() == 42 and cbuild.build_log()[-1][:2] == ("sec_answer", "built")
    assert c_cache.read_bytes() == b""  # not replaced, not loaded


# --- the fingerprint: a changed source file never loads code compiled from the old one ----------------------------

_FINGERPRINT = ("import sys; from mechderive.core import codecache; "
                "print(codecache.fingerprint(), sorted(sys.modules).count('hashlib'), codecache.__file__)")


def test_a_changed_source_file_changes_the_fingerprint_whatever_its_times(tmp_path):
    """The fingerprint is recorded under a stamp of the files' sizes, times and inodes (not their bytes, ~8 ms to
    hash): an edit of the same size with its modification time set back, or a new file, must change it all the
    same, and a stamp seen before gives the fingerprint of the bytes, never another's."""
    package = tmp_path / "src" / "mechderive"
    shutil.copytree(Path(codecache.__file__).resolve().parents[1], package,
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(package.parent), "MECHDERIVE_CACHE_DIR": str(tmp_path / "cache")}

    def fingerprint() -> str:  # (not run_python: it puts the repository's package first on the path)
        out = subprocess.run([sys.executable, "-c", _FINGERPRINT], env=env, cwd=tmp_path, capture_output=True,
                             text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        value, hashlib_imported, where = out.stdout.split()
        assert where == str(package / "core" / "codecache.py")
        assert hashlib_imported == "0"  # (CPython's own SHA-256: OpenSSL's load is ~5 ms of a warm run)
        return value

    first = fingerprint()
    assert list((tmp_path / "cache" / "stamps").iterdir()) and fingerprint() == first  # recorded, read back
    target = package / "systems" / "heavy_top" / "model.py"
    st = target.stat()
    text = target.read_bytes()
    edited = text.replace(b"import", b"imporT", 1)
    assert len(edited) == len(text) and edited != text
    with open(target, "r+b") as fh:  # in place: same inode, same size
        fh.write(edited)
    os.utime(target, ns=(st.st_atime_ns, st.st_mtime_ns))  # the modification time set back
    assert target.stat().st_mtime_ns == st.st_mtime_ns and target.stat().st_ino == st.st_ino
    second = fingerprint()
    assert second != first
    (package / "extra.py").write_text("# a new module\n")
    third = fingerprint()
    assert third not in (first, second)
    (package / "extra.py").unlink()
    target.write_bytes(text)
    assert fingerprint() == first  # the same bytes: the same fingerprint (and the code compiled from them)
