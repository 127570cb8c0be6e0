"""Compiled functions that outlive the process: lambdify's generated source, cached on disk.

A function is requested by *name* together with a *builder* that derives it
(``build() -> (argument symbols, expressions)``).  The first request in a
process looks in memory, then on disk; only on a miss is the builder run —
importing SymPy and deriving — and the code that ``sympy.lambdify(..., cse=True)``
generates is written to the cache.  A later process loads that source and
compiles it with Python's ``compile`` in the namespace of NumPy, mpmath or math,
so it neither imports SymPy nor derives anything.

What the cache is keyed by: the function's name and target module, and a
fingerprint of everything it was derived from — the bytes of every source file
of the mechderive package and the versions of Python, SymPy, NumPy and mpmath.
Any change to the package's code therefore starts a fresh cache directory.  The
cache only ever holds code this package generated itself (never user input); it
is safe to delete at any time (remove the folder).

What is checked before a cached file is executed (the folder and file rules are
:mod:`.cachefs`'s): the cache root, the fingerprint folder and ``c/`` are created
0700 and used only if owned by this uid and writable by nobody else — else one
warning line and no disk cache for the run; a file is read through a descriptor
opened relative to its checked folder without following links, and only if it is a
regular file of this uid.  Each ``<name>.<module>.py`` starts with the SHA-256 of
its name and content, written when it was stored; its ``.marshal`` bytecode carries
the SHA-256 of that exact source.  A file that does not verify (edited, truncated,
random bytes, copied from another name, planted) is never executed: the function is
derived again and the file atomically replaced; the run succeeds either way.
(The hash is recorded at store time rather than being the file's name computed
from what would be generated: knowing that needs the very derivation the cache
exists to skip.)

Location: ``$MECHDERIVE_CACHE_DIR``, else ``$XDG_CACHE_HOME/mechderive``, else
``~/.cache/mechderive``.  Opt out with ``MECHDERIVE_NO_DISK_CACHE=1`` or
:func:`set_disk_cache`.
"""

from __future__ import annotations

import _thread
import functools
import importlib
import os
import sys
import time
from typing import TYPE_CHECKING, Any, Callable, Sequence

from ..errors import InvalidInputError
from . import cachefs

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

__all__ = ["cached_lambdify", "cache_dir", "fingerprint", "set_disk_cache", "disk_cache_enabled",
           "compile_log", "clear_memory"]

_MODULES = ("numpy", "mpmath", "math")
_MEMORY: dict[str, tuple[Callable[..., Any], dict]] = {}
_LOCK = _thread.allocate_lock()  # threading.Lock() itself, without importing threading (~1 ms of a warm run)
_ENABLED: list[bool | None] = [None]
#: (name, how, seconds) for every function obtained in this process, in order; how is "compiled"
#: or "disk" (loaded from the disk cache); seconds exclude the derivation the builder ran.
#: Memory hits are not logged.
_LOG: list[tuple[str, str, float]] = []


def compile_log() -> list[tuple[str, str, float]]:
    """(name, 'compiled' | 'disk', seconds) for each function obtained in this process, in order."""
    return list(_LOG)


def set_disk_cache(enabled: bool | None) -> None:
    """Turn the disk cache on or off for this process (``None``: follow the environment)."""
    _ENABLED[0] = enabled


def disk_cache_enabled() -> bool:
    """Whether compiled code is read from and written to disk in this process."""
    if _ENABLED[0] is not None:
        return _ENABLED[0]
    return os.environ.get("MECHDERIVE_NO_DISK_CACHE", "") in ("", "0")


def cache_dir() -> Path:
    """The root of the disk cache (see the module docstring)."""
    from pathlib import Path

    return Path(_root())


def _root() -> str:
    """:func:`cache_dir` as a string, without importing pathlib (~6 ms of a warm run; :mod:`.cachefs` normalizes
    it as pathlib would)."""
    env = os.environ.get("MECHDERIVE_CACHE_DIR")
    if env:
        return env
    xdg = os.environ.get("XDG_CACHE_HOME")
    return os.path.join(xdg if xdg else os.path.join(os.path.expanduser("~"), ".cache"), "mechderive")


def _version(dist: str) -> str:
    """The installed version of ``dist``, read off its ``.dist-info`` folder on ``sys.path``.

    ``importlib.metadata`` would give the same, but importing it (with ``email``) costs ~35 ms —
    a tenth of a warm ``mechderive run``.
    """
    prefix = dist.lower() + "-"
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        for name in names:
            if name.lower().startswith(prefix) and name.endswith(".dist-info"):
                return name[len(prefix):-len(".dist-info")]
    return "?"  # pragma: no cover - the runtime dependencies are installed


@functools.cache
def fingerprint() -> str:
    """A hash of the package's source files and the versions of Python, SymPy, NumPy and mpmath.

    Reading and hashing every source file took ~8 ms of each warm run.  So the hash is recorded in the
    cache root (``stamps/``, sealed as the code is) under a *stamp* of the same files' paths, sizes,
    modification and change times (ns) and inodes and of the versions (~2 ms to take): a later process with
    the same stamp reads the recorded fingerprint instead of the files — more than the trust Python's own bytecode
    cache puts in a source's size and modification time.  Any edit, checkout or install (the folders on
    ``sys.path`` change) changes the stamp, and the fingerprint is computed from the bytes again.
    """
    root = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
    files = []  # (relative path, os.stat_result)
    skip = len(root) + len(os.sep)  # (the relative path by slicing: os.path.relpath took ~4 ms for 190 files)
    folders = [root]
    while folders:
        folder = folders.pop()
        with os.scandir(folder) as entries:
            for entry in entries:
                if entry.is_dir(follow_symlinks=False):
                    if entry.name != "__pycache__":
                        folders.append(entry.path)
                elif entry.name.endswith(".py"):
                    files.append((entry.path[skip:], entry.stat()))
    files.sort(key=lambda f: f[0].split(os.sep))
    # the installed versions stand in the stamp as the modification times of the folders on sys.path, which
    # an install or removal changes (reading them off the .dist-info names is done on a miss only)
    installs = []
    for entry in sys.path:
        if entry in ("", "."):  # the working folder: it changes with every file written there
            continue
        try:
            installs.append((entry, os.stat(entry or ".").st_mtime_ns))
        except OSError:
            installs.append((entry, None))
    # the change time too: an edit that keeps the size and sets the modification time back (cp -p, tar, rsync -t,
    # touch -r over a file rewritten in place) still changes it, and no program can set it
    stamp = cachefs.sha256(repr(([(rel, st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino) for rel, st in files],
                                 sys.version, installs)).encode()).hexdigest()[:32]
    recorded = _stamped(stamp)
    if recorded is not None:
        return recorded
    h = cachefs.sha256()
    for rel, _ in files:
        h.update(rel.encode())
        with open(os.path.join(root, rel), "rb") as fh:
            h.update(fh.read())
    h.update(sys.version.encode())
    for dist in ("sympy", "numpy", "mpmath"):
        h.update(f"{dist}={_version(dist)}".encode())
    value = h.hexdigest()[:20]
    _stamped(stamp, value)
    return value


def _stamped(stamp: str, value: str | None = None) -> str | None:
    """The fingerprint recorded for ``stamp`` (or None); with ``value``, record it (when the disk cache is on)."""
    if not disk_cache_enabled():
        return None
    name = f"{stamp}.fingerprint"
    with cachefs.directory(_root(), ("stamps",), create=value is not None) as folder:
        if folder is None:
            return None
        if value is not None:
            cachefs.write_file(folder, name, cachefs.seal(name, value.encode()))
            return value
        payload = cachefs.unseal(name, cachefs.read_file(folder, name))
    if payload is None or len(payload) != 20 or not all(c in b"0123456789abcdef" for c in payload):
        return None
    return payload.decode()


def clear_memory() -> None:
    """Forget the functions held in memory (the disk cache is untouched); for tests."""
    with _LOCK:
        _MEMORY.clear()


@functools.lru_cache(maxsize=None)
def _file_name(name: str, module: str) -> str:
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in name)
    return f"{safe}.{module}.py"


def _path(name: str, module: str) -> str:
    """Where the source of ``name`` for ``module`` is kept (for reading; loads go through :mod:`.cachefs`)."""
    return os.path.join(_root(), fingerprint(), _file_name(name, module))


def _load(name: str, module: str) -> tuple[Callable[..., Any], dict] | None:
    """The cached function, or None when it is absent or does not verify (then it is rebuilt)."""
    file = _file_name(name, module)
    with cachefs.directory(_root(), (fingerprint(),), create=False) as folder:
        if folder is None:
            return None
        source = cachefs.unseal(file, cachefs.read_file(folder, file))
        if source is None:
            return None
        try:
            text = source.decode("utf-8")
        except UnicodeDecodeError:  # pragma: no cover - sealed by us, so written by us as UTF-8
            return None
        code = _code(folder, file, source, text)
    meta, start = {}, 0
    while text.startswith("#", start):  # the header _store writes (comment lines), not the whole source
        end = text.find("\n", start)
        line = text[start:] if end < 0 else text[start:end]
        if line.startswith("# meta "):
            key, _, value = line[7:].partition("=")
            meta[key.strip()] = value.strip()
        if end < 0:
            break
        start = end + 1
    namespace = _namespace(module).copy()
    # Our own generated code, verified against the hash _store wrote (see the module docstring).
    exec(code, namespace)  # noqa: S102
    func = namespace.get("_lambdifygenerated")
    return None if func is None else (func, meta)


@functools.lru_cache(maxsize=None)
def _namespace(module: str) -> dict:
    """The globals a function compiled for ``module`` runs in, copied for each (the copy of NumPy's ~500 names
    took ~25 µs of every load)."""
    return dict(vars(importlib.import_module(module)))


def _code(folder: int, file: str, source: bytes, text: str) -> Any:
    """The code object of ``source``: its bytecode kept beside it (compiling anew took ~25 ms of a
    warm run; the folder is per Python version, see fingerprint), sealed with the hash of the very
    source it was compiled from, so a stale or edited ``.marshal`` is recompiled, never run."""
    import marshal

    compiled = file + ".marshal"
    key = f"{compiled}|{cachefs.sha256(source).hexdigest()}"
    payload = cachefs.unseal(key, cachefs.read_file(folder, compiled))
    if payload is not None:
        try:
            code = marshal.loads(payload)
            if isinstance(code, type(_code.__code__)):
                return code
        except (ValueError, EOFError, TypeError):  # pragma: no cover - verified, so ours
            pass
    code = compile(text, os.path.join(_root(), fingerprint(), file), "exec")
    cachefs.write_file(folder, compiled, cachefs.seal(key, marshal.dumps(code)))  # a read-only cache: no bytecode kept
    return code


def _store(name: str, module: str, source: str, meta: dict) -> None:
    file = _file_name(name, module)
    header = "".join(f"# meta {k} = {v}\n" for k, v in meta.items())
    text = "# generated by mechderive.core.codecache from sympy.lambdify; safe to delete\n" + header + source
    with cachefs.directory(_root(), (fingerprint(),), create=True) as folder:
        if folder is not None:  # a refused or read-only cache just means no disk cache
            cachefs.write_file(folder, file, cachefs.seal(file, text.encode("utf-8")))


#: "name|module" -> pid of the forked child building it (:func:`prefetch`)
_PREFETCH: dict[str, int] = {}
#: seconds a process waits for a prefetching child before building the function itself
PREFETCH_WAIT = 120.0


def prefetch(jobs: Sequence[tuple[str, Callable[[], tuple[Sequence[Any], Any]], str]],
             prepare: Callable[[], Any] | None = None) -> bool:
    """Start building ``jobs`` ((name, build, module), as :func:`cached_lambdify` takes them) in a forked
    child process that writes them to the disk cache, while this process goes on with other derivations:
    a cold start uses a second core.  True if a child was started.

    Only where it is safe and useful (and not turned off with ``MECHDERIVE_PARALLEL=0``): a POSIX fork, the
    disk cache on, at least 2 cores, no other thread in this process (a fork copies no thread: a lock one of them held would stay held in the child), and some
    job not on disk yet.  :func:`cached_lambdify` of a prefetched name waits for the child (at most
    :data:`PREFETCH_WAIT` s, then builds it itself), loads the function from disk and logs it as
    ``"parallel"``.  A child that fails leaves nothing behind but a missing file: the name is then built
    here as if never prefetched.  The caller asks only for what its request needs (laziness holds).

    ``prepare``, if given, is run here just before the fork, and only if a child is to be started: the
    derivations both this process and the jobs need (their common prefix), done once and inherited by the
    child, rather than twice — on two busy cores deriving them (and importing SymPy) in both processes cost
    more CPU than the second core gave back.  It must derive only what this process's request needs anyway.
    """
    if (not hasattr(os, "fork") or not disk_cache_enabled() or (os.cpu_count() or 1) < 2
            or os.environ.get("MECHDERIVE_PARALLEL", "1") == "0"):
        return False
    todo = [(n, b, m) for n, b, m in jobs if f"{n}|{m}" not in _MEMORY and f"{n}|{m}" not in _PREFETCH
            and not os.path.exists(_path(n, m))]
    if not todo:  # (a warm run: decided before importing threading, ~1 ms)
        return False
    import threading

    if threading.active_count() > 1:
        return False
    if prepare is not None:
        from .model import deriving

        with deriving():
            prepare()
        if threading.active_count() > 1:  # pragma: no cover - a derivation started a thread: no fork
            return False
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # the child: build, store, and leave without running the parent's exit handlers
        status = 0
        try:
            for n, b, m in todo:
                cached_lambdify(n, b, module=m)
        except BaseException:  # noqa: BLE001 - the parent builds what is missing
            status = 1
        os._exit(status)
    for n, _, m in todo:
        _PREFETCH[f"{n}|{m}"] = pid
    return True


def _wait_for(pid: int, published: str | None = None) -> None:
    """Wait for the prefetching child ``pid`` until it has published ``published`` (it builds its jobs in
    turn, atomically each: the first ones are ready before the last are done) or has exited (reaped once;
    later waits return at once), at most PREFETCH_WAIT s."""
    deadline = time.monotonic() + PREFETCH_WAIT
    while True:
        if published is not None and os.path.exists(published):
            return
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:  # reaped already (another of its names)
            return
        if done:
            return
        if time.monotonic() > deadline:
            import contextlib

            with contextlib.suppress(OSError):
                os.kill(pid, 9)
                os.waitpid(pid, 0)
            return
        time.sleep(0.005)


def cached_lambdify(name: str, build: Callable[[], tuple[Sequence[Any], Any]], *,
                    module: str = "numpy") -> tuple[Callable[..., Any], dict]:
    """The function ``name`` for ``module`` ('numpy', 'mpmath' or 'math'), and its metadata.

    ``build()`` returns (argument symbols, expressions); the expressions may be one
    expression, a Matrix or a (nested) list — they are flattened row-major, and the
    function returns a list.  The metadata has ``shape`` (of the expressions) and
    ``args`` (the argument names, comma-separated).
    """
    if module not in _MODULES:
        raise InvalidInputError(f"expected module one of {_MODULES}, got {module!r}")
    key = f"{name}|{module}"
    with _LOCK:
        hit = _MEMORY.get(key)
    if hit is not None:
        return hit
    start = time.perf_counter()
    disk = disk_cache_enabled()
    child = _PREFETCH.pop(key, None)
    if child is not None:
        _wait_for(child, _path(name, module) if disk else None)
        if child not in _PREFETCH.values():  # its last job: reaped (it exits right after publishing it)
            _wait_for(child)
    loaded = _load(name, module) if disk else None
    if loaded is not None:
        how = "parallel" if child is not None else "disk"
    else:
        from .model import derivation_seconds, deriving

        before = derivation_seconds()
        with deriving():
            import sympy as sp

            args, exprs = build()
        start += derivation_seconds() - before  # the derivation is reported as such, not as compiling
        import numpy as np

        if isinstance(exprs, sp.MatrixBase):
            shape, flat = exprs.shape, list(exprs)
        elif isinstance(exprs, (list, tuple)):
            arr = np.array(exprs, dtype=object)
            shape, flat = arr.shape, list(arr.ravel())
        else:
            shape, flat = (), [exprs]
        # the module object, not its name: lambdify then prints for it just the same (the printer is chosen by
        # the module's name) and takes its namespace as it is — by name it runs "from numpy import *", whose
        # lazily loaded submodules (numpy.testing, numpy.f2py, …) took ~0.3 s of a cold start.  The function
        # gets the globals a disk-cached one is loaded into (_load: the module's own namespace)
        func = sp.lambdify(list(args), flat, modules=importlib.import_module(module), cse=True)
        meta = {"shape": ",".join(map(str, shape)), "args": ",".join(str(a) for a in args)}
        if disk:
            import inspect

            _store(name, module, inspect.getsource(func), meta)
        loaded, how = (func, meta), "compiled"
    with _LOCK:
        _MEMORY.setdefault(key, loaded)
        _LOG.append((name, how, time.perf_counter() - start))
        return _MEMORY[key]


def shape_of(meta: dict) -> tuple[int, ...]:
    """The expressions' shape recorded in ``meta``."""
    text = meta.get("shape", "")
    return tuple(int(x) for x in text.split(",") if x)
