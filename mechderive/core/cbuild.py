"""Generated C, compiled by the system's C compiler and loaded with :mod:`ctypes`.

Hot loops whose every step is a handful of floating-point operations (an ODE stepper on
a derived right-hand side) cost ~1 µs a step in C against ~50–100 µs through Python and
NumPy.  This module turns C source that the package *generated itself* (from its own
SymPy derivations and its own templates — never user input) into a loaded shared
library:

* the compiler is ``$CC`` if set, else the first of ``cc``, ``gcc``, ``clang`` on ``PATH``;
  ``MECHDERIVE_NO_C=1`` (or :func:`set_c_enabled`) turns the C path off, and callers then
  fall back to their Python/SciPy path and say so;
* flags: ``-O2 -fPIC -shared -lm`` — no ``-ffast-math``, so IEEE semantics (and NaN
  checks) are kept and results do not depend on the optimiser's reassociation;
* the library is cached like generated Python code (:mod:`.codecache`), in the ``c/`` folder of
  the cache directory's folder for this package's fingerprint, named by the function name, the
  machine and the compiler, so a warm process neither derives (no SymPy import) nor compiles;
* what is checked before a cached library is loaded (folder and file rules of :mod:`.cachefs`):
  the folders are ours and writable by nobody else (else one warning and no disk cache), the
  library is a regular file of this uid, and its bytes match the SHA-256 (of its name and
  content) that the build wrote atomically into ``<library>.so.sha256``.  The verified *bytes*
  are what is loaded — through an in-memory file (``memfd``), else a private copy — never the
  cache file by name, so nothing can swap it between the check and ``dlopen``.  A library that
  does not verify (truncated: never mapped, so no SIGBUS; random bytes; a foreign library; the
  library of another system or name) or that this machine cannot load is rebuilt and replaced;
* the compiler runs in a private temporary folder removed on every path out (errors, timeout,
  Ctrl-C), with ``-pipe``; with the disk cache off, refused or read-only, the library is built
  there and loaded from memory, and nothing is left in ``$TMPDIR``.
"""

from __future__ import annotations

import _thread
import ctypes
import os
import time
from typing import TYPE_CHECKING, Callable

from ..errors import MechDeriveError
from . import cachefs, codecache

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

__all__ = ["compiler", "c_enabled", "set_c_enabled", "load_library", "load_or_none", "why_unavailable", "CBuildError",
           "build_log", "clear_memory"]

_FLAGS = ("-O2", "-fPIC", "-shared")
_MEMORY: dict[str, ctypes.CDLL] = {}
_LOCK = _thread.allocate_lock()  # threading.Lock(), without importing threading on every run
_ENABLED: list[bool | None] = [None]
#: The in-memory files the libraries were loaded from (see _open_bytes), open for the process.
_FDS: list[int] = []
_COMPILE_SECONDS = 120
#: Why a library could not be built or loaded in this process, by name (see load_or_none).
_FAILED: dict[str, str] = {}
#: (name, 'built' | 'disk', seconds) for each library obtained in this process; seconds exclude the
#: derivation that generating the source ran.
_LOG: list[tuple[str, str, float]] = []


class CBuildError(MechDeriveError, RuntimeError):
    """The system C compiler rejected generated code (a bug of this package: please report it)."""


def build_log() -> list[tuple[str, str, float]]:
    """(name, 'built' | 'disk', seconds) for each C library obtained in this process, in order."""
    return list(_LOG)


def clear_memory() -> None:
    """Forget the libraries held in memory, so the next request reads the disk cache again (loaded
    code stays mapped: objects built on it keep working); for tests."""
    with _LOCK:
        _MEMORY.clear()
        _FAILED.clear()


def set_c_enabled(enabled: bool | None) -> None:
    """Turn the compiled C path on or off for this process (``None``: follow the environment)."""
    _ENABLED[0] = enabled


def c_enabled() -> bool:
    """Whether the C path may be used: not switched off and a compiler is found."""
    if _ENABLED[0] is False:
        return False
    if _ENABLED[0] is None and os.environ.get("MECHDERIVE_NO_C", "") not in ("", "0"):
        return False
    return compiler() is not None


def compiler() -> str | None:
    """The C compiler's path (``$CC``, else cc, gcc or clang on ``PATH``), or None."""
    import shutil  # (shutil, platform, subprocess and tempfile where used: ~15 ms of every process's imports)

    cc = os.environ.get("CC")
    candidates = [cc] if cc else ["cc", "gcc", "clang"]
    for name in candidates:
        path = shutil.which(name)
        if path:
            return path
    return None


def _library_name(name: str) -> str:
    """The cache file of library ``name``: the function name, and a tag of the machine, the system
    and the compiler, so a cache shared between machines keeps one library per kind of machine."""
    import platform

    cc = compiler() or "none"
    tag = cachefs.sha256(f"{platform.machine()}|{platform.system()}|{cc}|{' '.join(_FLAGS)}".encode()).hexdigest()[:12]
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in name)
    return f"{safe}-{tag}.so"


def _library_path(name: str) -> Path:
    """Where the library ``name`` is kept in the disk cache (for reading; loads go through :mod:`.cachefs`)."""
    from pathlib import Path

    return Path(codecache._root()) / codecache.fingerprint() / "c" / _library_name(name)


def _cache_folder(create: bool):  # -> context manager of a checked folder descriptor or None
    return cachefs.directory(codecache._root(), (codecache.fingerprint(), "c"), create=create)


def _compile(source: str, file: str) -> bytes:
    """The bytes of the shared library built from ``source``.

    The compiler works in a private temporary folder (mode 0700) that is removed on every path
    out — success, a compiler error, a timeout, Ctrl-C — so nothing is left in ``$TMPDIR``.
    """
    import subprocess
    import tempfile
    from pathlib import Path

    cc = compiler()
    if cc is None:  # pragma: no cover - callers check c_enabled() first
        raise CBuildError("expected a C compiler (cc, gcc or clang on PATH, or $CC), found none")
    stem = file[:-len(".so")]
    with tempfile.TemporaryDirectory(prefix="mechderive-c-", ignore_cleanup_errors=True) as tmp:
        src, out = Path(tmp) / f"{stem}.c", Path(tmp) / file
        src.write_text(source)
        try:  # -pipe: no compiler temporaries in $TMPDIR either
            proc = subprocess.run([cc, *_FLAGS, "-pipe", "-o", str(out), str(src), "-lm"], capture_output=True,
                                  text=True, timeout=_COMPILE_SECONDS)
        except subprocess.TimeoutExpired as exc:
            raise CBuildError(f"expected {cc} to compile the generated {stem}.c within {_COMPILE_SECONDS} s, "
                              f"it did not") from exc
        if proc.returncode != 0:
            raise CBuildError(f"expected {cc} to compile the generated {stem}.c, got exit code "
                              f"{proc.returncode}:\n{proc.stderr.strip()[:2000]}")
        return out.read_bytes()


def _open_bytes(data: bytes, file: str) -> ctypes.CDLL:
    """Load the library whose verified bytes are ``data``, never a file that could change after
    the check: an anonymous in-memory file (``memfd``, kept open for the process so that its
    ``/proc/self/fd`` name is never reused), else a copy in a private temporary folder removed
    as soon as it is loaded.  Raises OSError if the system cannot load it."""
    try:
        fd = os.memfd_create(file, getattr(os, "MFD_CLOEXEC", 0))
    except (AttributeError, OSError):  # not Linux
        fd = None
    if fd is not None:
        path = f"/proc/self/fd/{fd}"
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
            lib = ctypes.CDLL(path) if os.path.exists(path) else None
        except OSError:  # no exec from memfd here (vm.memfd_noexec), or a library this system rejects
            lib = None
        except BaseException:
            os.close(fd)
            raise
        if lib is not None:
            _FDS.append(fd)
            return lib
        os.close(fd)  # try the private copy; a library the system rejects fails there too
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory(prefix="mechderive-c-", ignore_cleanup_errors=True) as tmp:
        copy = Path(tmp) / file
        copy.write_bytes(data)
        return ctypes.CDLL(str(copy))  # mapped: removing the file afterwards is fine


def _load_cached(file: str) -> ctypes.CDLL | None:
    """The cached library if it is ours and its bytes match the SHA-256 recorded beside it, else None."""
    with _cache_folder(create=False) as folder:
        if folder is None:
            return None
        recorded = cachefs.read_file(folder, file + ".sha256", limit=256)
        data = cachefs.read_file(folder, file)
    if not data or not recorded or recorded.strip() != cachefs.digest(file, data).encode():
        return None  # absent, edited, truncated, foreign or another system's: rebuilt, never loaded
    try:
        return _open_bytes(data, file)
    except OSError:  # verified, yet this system cannot load it (a cache shared across machines): rebuilt
        return None


def _store(file: str, source: str, data: bytes) -> None:
    """Keep the library (and its C source, for reading) in the disk cache; quietly nothing if refused
    or read-only.  The hash is written after the library: a reader catching the two mid-update
    sees a mismatch and rebuilds, never a hash vouching for a library not yet written."""
    with _cache_folder(create=True) as folder:
        if folder is None:
            return
        cachefs.write_file(folder, file[:-len(".so")] + ".c", source.encode())
        if cachefs.write_file(folder, file, data):
            cachefs.write_file(folder, file + ".sha256", cachefs.digest(file, data).encode() + b"\n")


def load_library(name: str, build_source: Callable[[], str]) -> ctypes.CDLL:
    """The shared library ``name``: from memory, from the cache folder, or built from ``build_source()``.

    ``build_source`` is called only when the library is not cached (or its cached copy does not
    verify, see the module docstring); it returns the complete C source.  Raises
    :class:`CBuildError` if compilation fails.  Callers check :func:`c_enabled`.
    """
    with _LOCK:
        lib = _MEMORY.get(name)
        if lib is not None:
            return lib
        start = time.perf_counter()
        file = _library_name(name)
        disk = codecache.disk_cache_enabled()
        lib = _load_cached(file) if disk else None
        how = "disk"
        if lib is None:
            from .model import derivation_seconds, deriving

            before = derivation_seconds()
            with deriving():
                source = build_source()
            start += derivation_seconds() - before  # the derivation is reported as such, not as compiling
            data = _compile(source, file)
            if disk:
                _store(file, source, data)
            lib = _open_bytes(data, file)
            how = "built"
        _MEMORY[name] = lib
        _LOG.append((name, how, time.perf_counter() - start))
        return lib


def load_or_none(name: str, build_source: Callable[[], str]) -> ctypes.CDLL | None:
    """:func:`load_library`, or None when the C path is off, no compiler is found, or building or
    loading fails — the reason is kept for :func:`why_unavailable`, so callers can fall back to
    their uncompiled path and a caller that insisted on C can say why it cannot have it."""
    if not c_enabled():
        return None
    try:
        return load_library(name, build_source)
    except (CBuildError, OSError) as exc:  # a broken compiler or an unloadable file
        _FAILED[name] = f"{type(exc).__name__}: {exc}"
        return None


def why_unavailable(name: str) -> str:
    """Why :func:`load_or_none` gave None for the library ``name`` in this process."""
    if name in _FAILED:
        return _FAILED[name]
    if compiler() is None:
        return "no C compiler found (cc, gcc or clang on PATH, or $CC)"
    return "the C path is switched off (MECHDERIVE_NO_C or set_c_enabled(False))"
