"""Issue 12, finding 6 (output) and the command-line parts of findings 5 and 7.

Each reproduction of the issue, as a user meets it through ``mechderive run -o/--plot``:
a target that cannot be written is refused before anything is solved, with status 2 and one
line naming the option and the path, and nothing is left on disk; a write that fails half-way
(full disk, file size limit, SIGTERM, SIGHUP) leaves neither a partial file nor a temporary
one; files get the permissions any Unix tool would give them; symbolic links are written
through (but not one another user planted in /tmp); a closed pipe or a full disk on stdout
is reported in one line, never as a traceback or "Exception ignored".

The solver is replaced by a stub (:func:`solved`): these tests are about files, not physics,
and the stub also proves that refused targets are refused *before* solving.  Subprocesses
only where a signal or the interpreter's last flush is what is tested.
"""

from __future__ import annotations

import errno
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import mechderive.scenes.output as output
import mechderive.scenes.planner as planner
from mechderive.cli import EXIT_INPUT, EXIT_PIPE, build_parser, main, parse_args
from mechderive.errors import InvalidInputError
from mechderive.scenes.planner import RunResult

from ..conftest import ROOT

SCENE = """\
system = "free_top"
[parameters]
I1 = 1.0
I2 = 2.0
I3 = 3.0
[initial]
omega = [1e-6, 1.0, 1e-6]
[time]
t_end = 10.0
samples = {samples}
[output]
quantities = ["omega1"]
"""

IS_ROOT = os.name == "posix" and os.geteuid() == 0
NOBODY = 65534


def _stub_result(scene) -> RunResult:
    t = np.linspace(0.0, scene.t_end, scene.samples)
    report = {"system": scene.system, "method": "exact", "derived": [], "compiled": [], "timings": {},
              "error_estimate": None, "drift": {}, "note": "", "details": {}}
    return RunResult(scene=scene, t=t, columns={q: np.cos(t) for q in scene.quantities}, report=report)


@pytest.fixture
def solved(monkeypatch) -> list:
    """The scenes "solved" (by a stub that returns cos t for every quantity), in order."""
    calls: list = []

    def run_scene(scene):
        calls.append(scene)
        return _stub_result(scene)

    monkeypatch.setattr(planner, "run_scene", run_scene)
    return calls


@pytest.fixture
def scene(tmp_path_factory) -> str:
    path = tmp_path_factory.mktemp("scene") / "small.toml"
    path.write_text(SCENE.format(samples=11))
    return str(path)


@pytest.fixture
def out_dir(tmp_path) -> Path:
    d = tmp_path / "out"
    d.mkdir()
    return d


def _one_error_line(capsys, *starts: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("mechderive: error: "), err
    assert any(err.startswith(f"mechderive: error: {s}") for s in starts), err
    return err


def _tree(d: Path) -> dict[str, bytes | str]:
    """Every entry under ``d`` (hidden ones too): file contents, link targets, "dir"."""
    found: dict[str, bytes | str] = {}
    for p in sorted(d.rglob("*")):
        key = p.relative_to(d).as_posix()
        found[key] = (f"-> {os.readlink(p)}" if p.is_symlink() else "dir" if p.is_dir()
                      else p.read_bytes() if p.is_file() else "special")
    return found


# --- refused before solving ----------------------------------------------------------------------

def _setup_refusals(d: Path) -> None:
    (d / "dir.csv").mkdir()
    (d / "file").write_text("x")
    os.symlink("loop.csv", d / "loop.csv")
    os.symlink("nowhere/new.csv", d / "dangling.csv")
    os.symlink(os.devnull, d / "null.csv")
    os.mkfifo(d / "fifo.csv")


# (option, path relative to the output directory, what the message must say after "OPTION 'PATH': ")
REFUSED = [
    ("-o", "dir.csv", r"expected a file name, got a directory"),
    ("-o", "missing/out.csv", r"expected an existing directory, got '.*missing'"),
    ("-o", "file/out.csv", r"expected an existing directory, got '.*file'"),  # ENOTDIR
    ("-o", "out.txt", r"expected a suffix \.csv or \.npz, got '\.txt'"),
    ("-o", "out", r"expected a suffix \.csv or \.npz, got 'none'"),
    ("-o", "a" * 300 + ".csv", r"expected names of at most 255 bytes, got one of 304"),  # ENAMETOOLONG
    ("-o", "d/" * 2100 + "x.csv", r"expected a path the system can look up, got one of \d+ bytes"),  # > PATH_MAX
    ("-o", "nul\0.csv", r"expected a file name without NUL characters, got one at position 3"),
    ("-o", "out.csv/", r"expected a file name, got a directory name \(ending in '/'\)"),  # not a file out.csv
    ("-o", "loop.csv", r"expected a symbolic link that leads to a file, got a loop"),
    ("-o", "dangling.csv", r"expected an existing directory, got '.*nowhere' \(where the symbolic link leads"),
    ("-o", "null.csv", r"expected a regular file or a new name, got a character device \(where the symbolic"),
    ("-o", "fifo.csv", r"expected a regular file or a new name, got a FIFO"),
    ("--plot", "out.jpg", r"expected a suffix \.png, \.pdf, \.svg, got '\.jpg'"),
    ("--plot", "b" * 300 + ".png", r"expected names of at most 255 bytes, got one of 304"),
    ("--plot", "missing/out.png", r"expected an existing directory"),
]


@pytest.mark.parametrize("option, name, message", REFUSED, ids=[f"{o} {n[:20]}" for o, n, _ in REFUSED])
def test_bad_target_refused_before_solving(monkeypatch, capsys, solved, scene, out_dir, option, name, message):
    import re

    _setup_refusals(out_dir)
    before = _tree(out_dir)
    monkeypatch.chdir(out_dir)  # relative names, as typed: a 4200-byte relative path is still too long
    assert main(["run", scene, option, name]) == EXIT_INPUT
    err = _one_error_line(capsys, f"{option} ")
    assert re.search(rf"^mechderive: error: {re.escape(option)} '.*': {message}", err), err
    assert len(err) < 400, err  # a 4200-character path is shortened in the message
    assert solved == []
    assert _tree(out_dir) == before


def test_unwritable_directory_and_read_only_file_refused_before_solving(monkeypatch, capsys, solved, scene,
                                                                         out_dir):
    locked = out_dir / "locked"
    locked.mkdir(mode=0o500)
    read_only = out_dir / "read_only.csv"
    read_only.write_text("old")
    read_only.chmod(0o444)
    if IS_ROOT:  # root may write anywhere: show the check what an ordinary user would get
        real_access = os.access
        denied = {os.fspath(locked), os.fspath(read_only)}
        monkeypatch.setattr(os, "access", lambda p, mode, *a, **k: False if os.fspath(p) in denied
                            and mode & os.W_OK else real_access(p, mode, *a, **k))
    assert main(["run", scene, "-o", str(locked / "out.csv")]) == EXIT_INPUT
    assert "expected a directory you may write to, got '" in _one_error_line(capsys, "-o ")
    assert main(["run", scene, "-o", str(read_only)]) == EXIT_INPUT
    assert "expected a file you may write to, got a read-only one" in _one_error_line(capsys, "-o ")
    assert solved == [] and list(locked.iterdir()) == [] and read_only.read_text() == "old"


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="Linux's /proc")
def test_a_file_system_that_creates_no_files_is_found_before_solving(capsys, solved, scene):
    # os.access says yes to root everywhere; only creating a file tells (here ENOENT in /proc).
    assert main(["run", scene, "-o", "/proc/mechderive-probe.csv"]) == EXIT_INPUT
    assert "expected a place where a file can be created, got " in _one_error_line(capsys, "-o ")
    assert solved == []


def test_a_table_that_cannot_fit_is_refused_before_solving(monkeypatch, capsys, solved, scene, tmp_path, out_dir):
    big = tmp_path / "big.toml"
    big.write_text(SCENE.format(samples=1_000_000))
    real_statvfs = os.statvfs

    def almost_full(path):
        fs = real_statvfs(path)
        # 100 blocks free: less than 1e6 samples x 2 columns x 8 bytes (npz), and x 4 (csv, "0.0,")
        return os.statvfs_result((fs.f_bsize, 4096, fs.f_blocks, 100, 100, *tuple(fs)[5:]))

    monkeypatch.setattr(os, "statvfs", almost_full)
    for suffix, need in ((".npz", 16_000_000), (".csv", 8_000_000)):
        assert main(["run", str(big), "-o", str(out_dir / f"out{suffix}")]) == EXIT_INPUT
        err = _one_error_line(capsys, "-o ")
        assert f"expected at least {need:,} bytes free for 1,000,000 samples of 2 columns, got 409,600 free" in err
    assert solved == [] and _tree(out_dir) == {}
    assert main(["run", scene, "-o", str(out_dir / "small.csv")]) == 0  # 11 samples: at least 88 bytes, they fit
    assert len(solved) == 1 and (out_dir / "small.csv").stat().st_size > 88
    capsys.readouterr()


@pytest.mark.skipif(not IS_ROOT, reason="planting a link owned by another user needs root")
def test_link_planted_by_another_user_in_a_shared_directory_is_not_followed(capsys, solved, scene, tmp_path):
    # /tmp/out.csv -> ~victim/.bashrc left by another user: the kernel's fs.protected_symlinks
    # rule, applied by mechderive itself (the setting is off on many machines, this one included).
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o1777)  # sticky, world-writable: like /tmp
    victim = tmp_path / "victim.csv"
    victim.write_text("precious")
    link = shared / "out.csv"
    os.symlink(victim, link)
    os.lchown(link, NOBODY, NOBODY)
    assert main(["run", scene, "-o", str(link)]) == EXIT_INPUT
    err = _one_error_line(capsys, "-o ")
    assert f"expected a symbolic link owned by you or by the owner of the shared directory" in err
    assert f"got one owned by uid {NOBODY}" in err
    assert victim.read_text() == "precious" and solved == []
    os.lchown(link, os.geteuid(), os.getegid())  # the user's own link in /tmp is followed
    assert main(["run", scene, "-o", str(link)]) == 0
    assert victim.read_text().startswith("t,omega1\n") and link.is_symlink()


@pytest.mark.skipif(not IS_ROOT, reason="a file owned by another user needs root to make")
def test_another_user_s_file_in_a_sticky_directory_refused_before_solving(monkeypatch, capsys, solved, scene,
                                                                          tmp_path):
    # Only its owner may replace it there: the rename would fail with EPERM after the solve.
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o1777)
    theirs = shared / "theirs.csv"
    theirs.write_text("theirs")  # owned by root, as is the directory
    monkeypatch.setattr(os, "geteuid", lambda: NOBODY)  # an ordinary user, who may write the directory
    assert main(["run", scene, "-o", str(theirs)]) == EXIT_INPUT
    err = _one_error_line(capsys, "-o ")
    assert f"expected a file of yours in the sticky directory '{shared}', got one owned by uid 0" in err
    assert solved == [] and theirs.read_text() == "theirs"


# --- failures while writing: no partial file, no temporary file -----------------------------------

def _failing_writer(monkeypatch, exc: BaseException) -> None:
    """The table writer writes a first row, then fails with ``exc``."""
    real = output._write_atomically

    def failing(path, write, *rest):
        def half(f):
            f.write(b"t,omega1\n0.0,")
            raise exc

        real(path, half, *rest)

    monkeypatch.setattr(output, "_write_atomically", failing)


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_disk_full_leaves_no_file_and_keeps_the_old_one(monkeypatch, capsys, solved, scene, out_dir, suffix):
    _failing_writer(monkeypatch, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
    target = out_dir / f"out{suffix}"
    assert main(["run", scene, "-o", str(target)]) == EXIT_INPUT
    err = _one_error_line(capsys, "-o ")
    assert f"-o '{target}': could not write it: {os.strerror(errno.ENOSPC)}" in err
    assert _tree(out_dir) == {}
    target.write_bytes(b"old table")
    assert main(["run", scene, "-o", str(target)]) == EXIT_INPUT
    capsys.readouterr()
    assert _tree(out_dir) == {target.name: b"old table"}


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE on Linux")
def test_file_size_limit_is_a_real_write_error(monkeypatch, capsys, solved, tmp_path, out_dir):
    # The kernel refuses the write itself (EFBIG; Python ignores SIGXFSZ): no mock in the way.
    import resource

    big = tmp_path / "big.toml"
    big.write_text(SCENE.format(samples=5000))  # about 120 kB of CSV
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, hard))
    try:
        status = main(["run", str(big), "-o", str(out_dir / "big.csv")])
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    assert status == EXIT_INPUT
    assert f"could not write it: {os.strerror(errno.EFBIG)}" in _one_error_line(capsys, "-o ")
    assert _tree(out_dir) == {}


def test_a_name_at_the_length_limit_gets_a_temporary_name_that_fits(solved, scene, out_dir, capsys):
    # 255 bytes is a valid name; ".NAME.xxxxxxxx.tmp.csv" beside it would not be.
    target = out_dir / ("c" * 251 + ".csv")
    assert main(["run", scene, "-o", str(target)]) == 0
    assert [p.name for p in out_dir.iterdir()] == [target.name]
    np.testing.assert_array_equal(np.loadtxt(target, delimiter=",", skiprows=1)[:, 1],
                                  np.cos(np.linspace(0.0, 10.0, 11)))  # what the stub solved, exactly


# --- permissions ------------------------------------------------------------------------------------

def test_new_file_gets_the_umask_and_a_replaced_file_keeps_its_mode(solved, scene, out_dir, capsys):
    old_umask = os.umask(0o027)
    try:
        new = out_dir / "new.csv"
        assert main(["run", scene, "-o", str(new)]) == 0
        assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~0o027  # as open(..., "w") would: 0o640
        for mode in (0o600, 0o644, 0o755, 0o400 if IS_ROOT else 0o600):
            old = out_dir / f"old{mode:o}.npz"
            old.write_bytes(b"old")
            old.chmod(mode)
            assert main(["run", scene, "-o", str(old)]) == 0
            assert stat.S_IMODE(old.stat().st_mode) == mode and old.read_bytes()[:2] == b"PK"
    finally:
        os.umask(old_umask)
    capsys.readouterr()


@pytest.mark.skipif(not IS_ROOT, reason="giving a file to another user needs root")
def test_replaced_file_keeps_its_owner(solved, scene, out_dir, capsys):
    theirs = out_dir / "theirs.csv"
    theirs.write_text("old")
    os.chown(theirs, NOBODY, NOBODY)
    theirs.chmod(0o604)
    assert main(["run", scene, "-o", str(theirs)]) == 0
    st = theirs.stat()
    assert (st.st_uid, st.st_gid, stat.S_IMODE(st.st_mode)) == (NOBODY, NOBODY, 0o604)
    capsys.readouterr()


# --- symbolic links: written through -----------------------------------------------------------------

def test_symbolic_links_are_written_through(solved, scene, tmp_path, capsys):
    data = tmp_path / "data"
    data.mkdir()
    links = tmp_path / "links"
    links.mkdir()
    real = data / "real.csv"
    real.write_text("old")
    real.chmod(0o640)
    os.symlink("../data/real.csv", links / "rel.csv")         # relative, to another directory
    os.symlink(links / "rel.csv", links / "chain.csv")        # a link to a link
    os.symlink("../data/created.csv", links / "dangling.csv")  # its directory exists: created
    for name in ("rel.csv", "chain.csv", "dangling.csv"):
        assert main(["run", scene, "-o", str(links / name)]) == 0
        assert (links / name).is_symlink()
    assert real.read_text().startswith("t,omega1\n") and stat.S_IMODE(real.stat().st_mode) == 0o640
    assert (data / "created.csv").read_text() == real.read_text()
    assert sorted(p.name for p in data.iterdir()) == ["created.csv", "real.csv"]  # no temporary file
    assert sorted(p.name for p in links.iterdir()) == ["chain.csv", "dangling.csv", "rel.csv"]
    capsys.readouterr()


# --- signals during the write: subprocesses ----------------------------------------------------------

_SLOW_WRITE = """\
import sys, time
import numpy as np
import mechderive.scenes.output as output
import mechderive.scenes.planner as planner
from mechderive.cli import main

def stub(scene):  # as _stub_result, without importing pytest into the child
    t = np.linspace(0.0, scene.t_end, scene.samples)
    report = {"system": scene.system, "method": "exact", "derived": [], "compiled": [], "timings": {},
              "error_estimate": None, "drift": {}, "note": "", "details": {}}
    return planner.RunResult(scene=scene, t=t, columns={q: np.cos(t) for q in scene.quantities}, report=report)

planner.run_scene = stub
real = output._write_atomically

def slow(path, write, *rest):
    def half(f):
        f.write(b"t,omega1\\n0.0,")
        f.flush()
        print("writing", flush=True)
        time.sleep(60)
    real(path, half, *rest)

output._write_atomically = slow
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
@pytest.mark.parametrize("signame, status", [("SIGTERM", 143), ("SIGHUP", 129)])
def test_signal_during_the_write_removes_the_temporary_file(scene, out_dir, signame, status):
    target = out_dir / "out.csv"
    target.write_bytes(b"old table")
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("MECHDERIVE_DEBUG", None)
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_WRITE, "run", scene, "-o", str(target)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline() == "writing\n", proc.stderr.read()
        assert len(list(out_dir.iterdir())) == 2  # the temporary file is there, half-written
        proc.send_signal(getattr(signal, signame))
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == status, err
    assert err == "mechderive: terminated; the output file being written was removed\n"
    assert _tree(out_dir) == {"out.csv": b"old table"}


def test_signal_handlers_are_restored_and_a_program_s_own_handler_is_kept(tmp_path):
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    with output.atomic_output(tmp_path / "a.csv") as tmp:
        installed = signal.getsignal(signal.SIGTERM)
        tmp.write_text("x")
    assert installed is not signal.SIG_DFL and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL

    def own(signum, frame):  # pragma: no cover - never called
        pass

    previous = signal.signal(signal.SIGTERM, own)
    try:
        with output.atomic_output(tmp_path / "b.csv") as tmp:
            assert signal.getsignal(signal.SIGTERM) is own
            tmp.write_text("x")
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_terminated_is_raised_by_the_handler_and_cleans_up(tmp_path):
    # In-process: the handler's exception unwinds the block like Ctrl-C does; old file intact.
    target = tmp_path / "t.csv"
    target.write_text("old")
    with pytest.raises(output.Terminated) as exc:
        with output.atomic_output(target) as tmp:
            tmp.write_text("half")
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # interrupted by the handler at once
    assert exc.value.code == 143 and exc.value.signum == signal.SIGTERM
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"] and target.read_text() == "old"


@pytest.mark.slow
@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
def test_sigterm_while_writing_a_large_table(tmp_path):
    # The reproduction: a real solve of 10⁶ samples (under the 1 GB run limit), SIGTERM once the
    # temporary file appears.
    scene = tmp_path / "big.toml"
    scene.write_text(SCENE.format(samples=1_000_000).replace('["omega1"]', '["omega1", "omega2", "omega3"]'))
    out = tmp_path / "out"
    out.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-m", "mechderive", "run", str(scene), "-o", str(out / "big.csv")],
                            cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list(out.iterdir()) and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.01)
        assert list(out.iterdir()), "the write never started"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 143, err
    assert list(out.iterdir()) == []


# --- stdout: a closed pipe, a full disk --------------------------------------------------------------

PIPED = [["scenes"], ["scenes", "default"], ["--help"], ["--version"], ["run", "--help"], ["run", "{scene}", "--json"],
         ["run", "{scene}"]]


def _closed_pipe_stdout(monkeypatch) -> None:
    read_end, write_end = os.pipe()
    os.close(read_end)
    monkeypatch.setattr(sys, "stdout", os.fdopen(write_end, "w"))


@pytest.mark.parametrize("argv", PIPED, ids=" ".join)
def test_closed_pipe_in_process(monkeypatch, capsys, solved, scene, argv):
    _closed_pipe_stdout(monkeypatch)
    argv = [a.replace("{scene}", scene) for a in argv]
    try:
        assert main(argv) == EXIT_PIPE
    finally:
        sys.stdout.close()
    assert capsys.readouterr().err == ""


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="/dev/full")
@pytest.mark.parametrize("argv", PIPED, ids=" ".join)
def test_full_disk_on_stdout_in_process(monkeypatch, capsys, solved, scene, argv):
    monkeypatch.setattr(sys, "stdout", open("/dev/full", "w"))
    argv = [a.replace("{scene}", scene) for a in argv]
    try:
        assert main(argv) == EXIT_INPUT
    finally:
        sys.stdout.close()
    err = capsys.readouterr().err
    assert err == f"mechderive: error: standard output: could not write it: {os.strerror(errno.ENOSPC)}\n"


def _into_closed_pipe(args: list[str], *, buffered: bool) -> subprocess.CompletedProcess:
    read_end, write_end = os.pipe()
    os.close(read_end)
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("MECHDERIVE_DEBUG", None)
    env.pop("PYTHONUNBUFFERED", None)
    if not buffered:
        env["PYTHONUNBUFFERED"] = "1"
    try:
        return subprocess.run([sys.executable, "-m", "mechderive", *args], stdout=write_end, stderr=subprocess.PIPE,
                              cwd=ROOT, env=env, text=True, timeout=300)
    finally:
        os.close(write_end)


@pytest.mark.parametrize("args", [["--help"], ["--version"]], ids=" ".join)
@pytest.mark.parametrize("buffered", [True, False], ids=["buffered", "unbuffered"])
def test_closed_pipe_real_process(args, buffered):
    # argparse's exits used to meet the closed pipe in the interpreter's final flush:
    # "Exception ignored ... BrokenPipeError", status 120 (unbuffered: 0, the help silently lost).
    proc = _into_closed_pipe(args, buffered=buffered)
    assert (proc.returncode, proc.stderr) == (EXIT_PIPE, "")


@pytest.mark.slow
@pytest.mark.parametrize("args", [["derive", "rotation"], ["derive", "heavy_top", "--list"],
                                  ["check", "heavy_top", "--json", "dt(E) = 0"], ["check", "heavy_top", "--symbols"],
                                  ["stress", "--list"], ["verify", "--section", "3.1", "--json"], ["run", "--json"],
                                  ["run", "--help"], ["scenes", "default"]], ids=" ".join)
@pytest.mark.parametrize("buffered", [True, False], ids=["buffered", "unbuffered"])
def test_closed_pipe_every_command(args, buffered):
    proc = _into_closed_pipe(args, buffered=buffered)
    assert (proc.returncode, proc.stderr) == (EXIT_PIPE, "")


# --- options anywhere (finding 7) --------------------------------------------------------------------

@pytest.mark.parametrize("argv", [
    ["run", "{scene}", "-o", "{out}", "--json"],
    ["run", "--json", "-o", "{out}", "{scene}"],
    ["run", "-o", "{out}", "{scene}", "--json"],
    ["run", "--json", "{scene}", "--output={out}"],
], ids=lambda a: " ".join(x.strip("{}") for x in a))
def test_run_options_anywhere(solved, scene, tmp_path, capsys, argv):
    out = tmp_path / "o.csv"
    assert main([a.replace("{scene}", scene).replace("{out}", str(out)) for a in argv]) == 0
    assert capsys.readouterr().out.startswith("{\n")
    np.testing.assert_array_equal(np.loadtxt(out, delimiter=",", skiprows=1)[:, 1], np.cos(np.linspace(0, 10, 11)))


@pytest.mark.parametrize("argv, expected", [
    (["derive", "heavy_top", "p_psi", "--shape", "solid_cone", "E"],
     {"system": "heavy_top", "quantities": ["p_psi", "E"], "shape": "solid_cone"}),
    (["derive", "--format", "latex", "heavy_top", "f_u"], {"quantities": ["f_u"], "format": "latex"}),
    (["scenes", "default"], {"name": "default"}),
])
def test_derive_and_scenes_options_anywhere(argv, expected):
    args = parse_args(build_parser(), argv)
    assert {k: getattr(args, k) for k in expected} == expected


# --- the scene argument (finding 5, its command-line part) ---------------------------------------------

@pytest.mark.parametrize("spec, message", [
    ("a" * 300 + ".toml", "cannot read it: File name too long"),
    ("a" * 300, "cannot read it: File name too long"),  # not even a built-in name
    ("d/" * 2100 + "x.toml", "cannot read it: File name too long"),
    ("loop.toml", "cannot read it: Too many levels of symbolic links"),
    ("unreadable/s.toml", "cannot read it: Permission denied"),
], ids=["long name .toml", "long name", "long path", "link loop", "unreadable directory"])
def test_scene_argument_the_system_cannot_look_up(monkeypatch, capsys, solved, tmp_path, spec, message):
    # Path.exists() used to raise these (ENAMETOOLONG, ELOOP, EACCES): status 70, "a bug".
    monkeypatch.chdir(tmp_path)
    os.symlink("loop.toml", "loop.toml")
    (tmp_path / "unreadable").mkdir(mode=0o000)
    real_stat = os.stat

    def stat_(path, *args, **kwargs):  # root searches any directory: show it what a user would get
        if os.fspath(path).startswith("unreadable/"):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), os.fspath(path))
        return real_stat(path, *args, **kwargs)

    monkeypatch.setattr(os, "stat", stat_)
    assert main(["run", spec]) == EXIT_INPUT
    err = _one_error_line(capsys, "scene file '")
    assert message in err and len(err) < 300, err
    assert solved == []


# --- the library function, directly ------------------------------------------------------------------

def test_check_output_path_refuses_what_it_cannot_use(tmp_path):
    with pytest.raises(InvalidInputError, match=r"^output file: expected a path \(a string\), got int$"):
        output.check_output_path(3, output.TABLE_SUFFIXES)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match=r"^output file: expected a file name, got an empty one$"):
        output.check_output_path("", output.TABLE_SUFFIXES)
    assert output.check_output_path(tmp_path / "A.CSV", output.TABLE_SUFFIXES) == tmp_path / "A.CSV"
