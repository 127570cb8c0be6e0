"""Issue 12, findings 5 and 7 for scene files: odd files, numbers no double holds, runs too big to hold.

Each reproduction of the issue is run as ``mechderive run FILE`` in-process and must end in exit 2
with one line ``mechderive: error: ...`` naming the file or the key, no output file and no
traceback.  Before the fix: a 4400-digit integer raised ValueError and ``1`` followed by 400 zeros
OverflowError (exit 70); a link to /dev/zero read until memory ran out and a FIFO blocked forever
(killed by a 10 s timeout); a scene under an unreadable directory raised PermissionError (exit 70).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import resource
import shutil
import signal
import socket
import tempfile
import threading
from pathlib import Path

import pytest

from mechderive.cli import main
from mechderive.errors import InvalidInputError, NonFiniteValueError
from mechderive.scenes import schema
from mechderive.scenes.builtin import scene_text
from mechderive.scenes.schema import MAX_RUN_BYTES, QUANTITIES, SizeEstimate, load_scene

from ..conftest import run_python

SCENE = scene_text("default").replace("samples = 2001", "samples = 11")


def run(*argv: str) -> tuple[int, str, str]:
    """``mechderive *argv`` in-process: exit status, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(list(argv))
    return status, out.getvalue(), err.getvalue()


def refused(path: Path, tmp_path: Path) -> str:
    """Run ``path`` with ``-o``; assert exit 2, one error line, no output file; return the line."""
    target = tmp_path / "out.csv"
    status, _, err = run("run", str(path), "-o", str(target))
    assert status == 2, err
    assert len(err.splitlines()) == 1 and err.startswith("mechderive: error: ") and "Traceback" not in err, err
    assert not target.exists()
    return err.strip()


@contextlib.contextmanager
def deadline(seconds: float):
    """Fail instead of hanging (a FIFO that blocks): SIGALRM where the test runs in the main thread."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return

    def expire(signum, frame):
        raise TimeoutError(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


# ------------------------------------------------------------------------------------ numbers (finding 5)

def _numeric_fields() -> list[tuple[str, str, str]]:
    """(built-in scene, its key, the key as messages name it) for every number in them."""
    import tomllib

    return [(name, key, f"[{table}].{key}")
            for name in ("default", "gyroscope", "free_top_tumbling", "falling_cat")
            for table, content in tomllib.loads(scene_text(name)).items() if isinstance(content, dict)
            for key, value in content.items() if type(value) in (int, float)]


def _with(name: str, key: str, literal: str) -> str:
    """The built-in scene ``name`` with ``key``'s value replaced by ``literal`` (keys are unique in them)."""
    lines = scene_text(name).splitlines()
    i = next(i for i, line in enumerate(lines) if line.startswith(f"{key} = "))
    lines[i] = f"{key} = {literal}"
    return "\n".join(lines) + "\n"


NUMERIC_FIELDS = _numeric_fields()


HUGE = [("1" + "0" * 400, "an integer of 401 digits"), ("-" + "7" * 4400, "an integer of 4400 digits"),
        ("1e400", "1e400"), ("-2.5e999", "-2.5e999")]


def _expected(where: str, shown: str) -> str:
    if where == "[time].samples":  # an integer key: its range is the message
        return rf"^scene key \[time\]\.samples: expected an integer in \[2, 10000000\], got {re.escape(shown)}$"
    return (rf"^scene key {re.escape(where)}: expected .*\(a finite double: at most 1\.8e\+308 in size\), "
            rf"got {re.escape(shown)}$")


def test_every_numeric_key_refuses_numbers_no_double_holds_naming_the_key():
    """Issue 12 #5: ``1`` + 400 zeros (OverflowError), 4400 digits (ValueError), 1e400: each named."""
    assert len(NUMERIC_FIELDS) == 31  # heavy top 13 (M g l), gyroscope 11 (Mgl), free top 5, falling cat 2
    for name, key, where in NUMERIC_FIELDS:
        for literal, shown in HUGE:
            with pytest.raises(InvalidInputError, match=_expected(where, shown)):
                load_scene(_with(name, key, literal))


@pytest.mark.parametrize("literal, shown", HUGE)
def test_the_cli_says_so_in_one_line(tmp_path, literal, shown):
    path = tmp_path / "s.toml"
    path.write_text(_with("default", "psi_dot", literal))
    assert re.match(_expected("[initial].psi_dot", shown), refused(path, tmp_path).removeprefix("mechderive: error: "))


def test_omega_components_and_rtol_refuse_them_too():
    free = scene_text("free_top_tumbling")
    with pytest.raises(NonFiniteValueError, match=r"^scene key \[initial\]\.omega\[1\]: expected a finite number "
                                                  r"\(a finite double: at most 1\.8e\+308 in size\), got an "
                                                  r"integer of 4301 digits$"):
        load_scene(free.replace("omega = [1.0, 0.5, 1.0]", f"omega = [1.0, {'9' * 4301}, 1.0]"))
    with pytest.raises(NonFiniteValueError, match=r"^scene key rtol: expected a number in \[1e-15, 0\.01\] "
                                                  r"\(a finite double: at most 1\.8e\+308 in size\), got 1e400$"):
        load_scene(SCENE.replace('method = "auto"', 'method = "auto"\nrtol = 1e400'))


def test_hexadecimal_integers_beyond_any_double_are_named_without_converting_them_to_text():
    # 0x + 5000 f's is an int of 6021 decimal digits: str() of it raises past 4300 digits
    with pytest.raises(NonFiniteValueError, match=r"^scene key \[parameters\]\.g: .*got an integer of 6021 digits$"):
        load_scene(SCENE.replace("g = 10.0", "g = 0x" + "f" * 5000))
    with pytest.raises(InvalidInputError, match=r"^scene key \[time\]\.samples: expected an integer in "
                                                r"\[2, 10000000\], got an integer of 6021 digits$"):
        load_scene(SCENE.replace("samples = 11", "samples = 0x" + "f" * 5000))


def test_huge_integer_inside_a_list_or_under_an_unknown_key_is_still_named():
    with pytest.raises(InvalidInputError, match=r"^scene key \[output\]\.quantities\[1\]: expected a quantity "
                                                r"name \(a string\), got an integer of 4400 digits$"):
        load_scene(SCENE.replace('quantities = ["theta",', f'quantities = ["theta", {"3" * 4400},'))
    with pytest.raises(InvalidInputError, match=r"^scene key \[time\]\.dt: unknown key"):
        load_scene(SCENE.replace("samples = 11", f"samples = 11\ndt = {'3' * 4400}"))


# ------------------------------------------------------------------------------------ files (finding 5)

def test_a_link_to_dev_zero_is_refused_unread(tmp_path):
    """Issue 12 #5: the size check saw 0 bytes and the read went on until MemoryError."""
    link = tmp_path / "zero.toml"
    link.symlink_to("/dev/zero")
    with deadline(5):
        message = refused(link, tmp_path)
    assert message == f"mechderive: error: scene file {str(link)!r}: expected a regular file, got a character device"


def test_a_fifo_is_refused_without_blocking(tmp_path):
    """Issue 12 #5: opening a FIFO waited for a writer forever."""
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    with deadline(5):
        message = refused(fifo, tmp_path)
    assert message.endswith(": expected a regular file, got a FIFO (named pipe)")


@pytest.mark.parametrize("make, kind", [
    (lambda p: p.mkdir(), "a directory"),
    (lambda p: p.symlink_to("/dev/null"), "a character device"),
    (lambda p: socket.socket(socket.AF_UNIX).bind(str(p)), "a socket"),
])
def test_other_files_that_are_not_regular_are_refused(tmp_path, make, kind):
    path = tmp_path / "s.toml"
    make(path)
    assert refused(path, tmp_path).endswith(f"scene file {str(path)!r}: expected a regular file, got {kind}")


def test_reads_are_bounded_whatever_size_the_file_claims(tmp_path, monkeypatch):
    """/proc files are regular and claim 0 bytes: only MAX_SCENE_BYTES + 1 bytes are read, then refused."""
    maps = Path("/proc/self/maps")
    if not maps.exists() or maps.stat().st_size != 0:
        pytest.skip("needs a procfs file that claims 0 bytes")
    monkeypatch.setattr(schema, "MAX_SCENE_BYTES", 64)
    reads = []
    real_read = os.read
    monkeypatch.setattr(os, "read", lambda fd, n: reads.append(n) or real_read(fd, n))
    link = tmp_path / "maps.toml"
    link.symlink_to(maps)
    with pytest.raises(InvalidInputError, match=r"^scene file '.*maps\.toml': expected at most 64 bytes, got more$"):
        load_scene(link)
    assert sum(reads) <= 65 and reads[0] == 65
    sparse = tmp_path / "sparse.toml"
    with open(sparse, "wb") as f:
        f.truncate(10**12)  # a terabyte claimed, nothing stored: refused from its size, nothing read
    reads.clear()
    with pytest.raises(InvalidInputError, match=r"expected at most 64 bytes, got 1000000000000$"):
        load_scene(sparse)
    assert reads == []


def test_odd_names_and_encodings(tmp_path):
    nul = tmp_path / "a\0b.toml"
    with pytest.raises(InvalidInputError, match=r"^scene file '.*a\\x00b\.toml': cannot read it: embedded null byte$"):
        load_scene(nul)
    long = tmp_path / ("x" * 300 + ".toml")
    with pytest.raises(InvalidInputError, match=r"^scene file '.*x{300}\.toml': cannot read it: File name too long$"):
        load_scene(long)
    odd = tmp_path / ("line\nbreak" + "y" * 120 + ".toml")  # not a valid scene name: the scene has none
    odd.write_text(SCENE)
    assert load_scene(odd).name is None and load_scene(odd, name="n").name == "n"
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + SCENE.encode())  # as some editors save UTF-8
    assert load_scene(bom).name == "bom"
    latin = tmp_path / "latin.toml"
    latin.write_bytes(SCENE.replace("[time]", "# caf\xe9\n[time]").encode().replace(b"\xc3\xa9", b"\xe9"))
    line = SCENE.replace("[time]", "# caf\xe9\n[time]").splitlines().index("# caf\xe9") + 1
    assert refused(latin, tmp_path) == (f"mechderive: error: scene file {str(latin)!r}: expected UTF-8 text, "
                                        f"got byte 0xe9, which is not UTF-8, at line {line}, column 6")


def _as_nobody(function, *args) -> str:
    """``function(*args)`` in a forked child running as uid/gid 65534 (for a root test run): its result."""
    reader, writer = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            os.setgroups([])
            os.setgid(65534)
            os.setuid(65534)
            result = str(function(*args))
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            result = f"{type(exc).__name__}: {exc}"
        os.write(writer, result.encode()[:65536])
        os._exit(0)
    os.close(writer)
    with os.fdopen(reader, "rb") as pipe:
        text = pipe.read().decode()
    os.waitpid(pid, 0)
    return text


@pytest.fixture
def open_dir() -> Path:
    """A directory every user may enter (pytest's tmp_path is under a 0700 directory of root's)."""
    path = Path(tempfile.mkdtemp(prefix="mechderive-scene-files-"))
    path.chmod(0o755)
    yield path
    for sub in path.iterdir():
        sub.chmod(0o700)
    shutil.rmtree(path)


@pytest.fixture
def locked_scene(open_dir) -> Path:
    """A scene file in a directory no one but root may enter (mode 000)."""
    locked = open_dir / "locked"
    locked.mkdir()
    (locked / "s.toml").write_text(SCENE)
    locked.chmod(0)
    return locked / "s.toml"


def _load_message(path: Path) -> str:
    try:
        load_scene(path)
    except InvalidInputError as exc:
        return f"InvalidInputError: {exc}"
    return "loaded"


def test_a_scene_under_an_unreadable_directory_is_refused_naming_the_file(locked_scene):
    """Issue 12 #5 (PermissionError): as a user who may not enter the directory."""
    if os.geteuid() == 0:
        message = _as_nobody(_load_message, locked_scene)
    else:
        message = _load_message(locked_scene)
    assert message == f"InvalidInputError: scene file {str(locked_scene)!r}: cannot read it: Permission denied"


def _cli_error(path: Path) -> str:
    status, _, err = run("run", str(path))
    return f"{status} {err.strip()}"


def test_the_cli_refuses_a_scene_under_an_unreadable_directory(locked_scene):
    run("run", str(locked_scene.parent.parent / "missing.toml"))  # import what the run needs while root
    message = _as_nobody(_cli_error, locked_scene) if os.geteuid() == 0 else _cli_error(locked_scene)
    assert message == f"2 mechderive: error: scene file {str(locked_scene)!r}: cannot read it: Permission denied"


def test_an_unreadable_file_is_refused_naming_the_file(open_dir):
    path = open_dir / "s.toml"
    path.write_text(SCENE)
    path.chmod(0)
    message = _as_nobody(_cli_error, path) if os.geteuid() == 0 else _cli_error(path)
    assert message == f"2 mechderive: error: scene file {str(path)!r}: cannot read it: Permission denied"


# ------------------------------------------------------------------------------------ the size of a run

def test_ten_million_samples_are_refused_before_solving_with_the_estimate_and_the_way_out(tmp_path):
    """Issue 12 #5: 10⁷ samples took 2.3-4.5 GB; now refused at once, saying how many samples fit."""
    path = tmp_path / "big.toml"
    path.write_text(SCENE.replace("samples = 11", "samples = 10000000"))
    message = refused(path, tmp_path)
    # heavy top: 600 B per sample for the solve + 30 B per value, 4 columns: 720 B per sample
    assert message == ("mechderive: error: scene key [time].samples: expected a run of at most 1 GB, got an estimated "
                       "7.2 GB of memory (1 GB as CSV) for 10000000 samples of 4 columns (t and 3 quantities); use at "
                       "most 1388888 samples, or fewer [output].quantities")
    path.write_text(SCENE.replace("samples = 11", "samples = 1388888"))
    assert load_scene(path).size_estimate.memory_bytes <= MAX_RUN_BYTES
    path.write_text(SCENE.replace("samples = 11", "samples = 1388889"))
    with pytest.raises(InvalidInputError, match=r"use at most 1388888 samples"):
        load_scene(path)


def test_size_estimate_counts_samples_columns_and_bytes():
    scene = load_scene(SCENE)
    size = scene.size_estimate
    # t and theta, phi, psi at 11 samples: float64 in memory; repr of a double ≤ 24 characters + separator
    assert size == SizeEstimate(samples=11, columns=4, values=44, table_bytes=44 * 8, csv_bytes=44 * 25,
                                memory_bytes=11 * 600 + 44 * 30)
    assert len(repr(-2.2250738585072014e-308)) == 24  # the longest repr of a double: 24 characters


_MEASURE = """
import resource, sys, dataclasses
from mechderive.scenes.builtin import load_builtin
from mechderive.scenes.planner import run_scene
from mechderive.scenes.schema import QUANTITIES
from mechderive.scenes.output import write_table
name, method, which = sys.argv[1:4]
scene = load_builtin(name)
q = QUANTITIES[scene.system] if which == "all" else scene.quantities[:1]
run_scene(dataclasses.replace(scene, samples=11, quantities=q, method=method))
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
big = dataclasses.replace(scene, samples=11, quantities=q, method=method)
big = dataclasses.replace(big, samples=big.size_estimate.max_samples)
r = run_scene(big)
write_table(sys.argv[4], r.t, {k: r.columns[k] for k in q})
print(big.samples, big.size_estimate.memory_bytes, (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) * 1024,
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""


@pytest.mark.slow
@pytest.mark.parametrize("name, method, which", [
    ("default", "exact", "all"), ("default", "exact", "one"), ("default", "integrate", "one"),
    ("free_top_tumbling", "exact", "all"), ("free_top_tumbling", "integrate", "one"), ("falling_cat", "auto", "one"),
])
def test_the_largest_run_allowed_stays_within_its_estimate_and_a_gigabyte(tmp_path, name, method, which):
    """At the most samples allowed, the measured growth of the peak memory is below the estimate (each ~1 GB)."""
    proc = run_python("-c", _MEASURE, name, method, which, str(tmp_path / "out.csv"))
    assert proc.returncode == 0, proc.stderr
    samples, estimate, growth, peak = map(int, proc.stdout.split())
    assert growth <= estimate <= MAX_RUN_BYTES, (samples, estimate, growth)
    assert peak <= MAX_RUN_BYTES + 200_000_000, peak  # + the interpreter, NumPy and the compiled code


def test_a_run_at_the_limit_is_refused_at_once(tmp_path):
    """The refusal costs no solving: it comes from the schema, before the planner."""
    path = tmp_path / "cat.toml"
    quantities = ", ".join(f'"{q}"' for q in QUANTITIES["falling_cat"])
    path.write_text(scene_text("falling_cat").replace("samples = 201", "samples = 100000")
                    .replace('quantities = ["flip_angle", "L1", "L2", "L3"]', f"quantities = [{quantities}]"))
    start = resource.getrusage(resource.RUSAGE_SELF)
    message = refused(path, tmp_path)
    end = resource.getrusage(resource.RUSAGE_SELF)
    assert "scene key [time].samples: expected a run of at most 1 GB" in message
    assert end.ru_utime - start.ru_utime < 1.0  # a solve of 10⁵ cat samples takes ~5 s
