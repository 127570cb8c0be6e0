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
* the library is cached like generated Python code (:mod:`.codecache`): in the cache
  directory's folder for this package's fingerprint, named by the function name, the
  machine and the compiler, so a warm process neither derives (no SymPy import) nor
  compiles; with the disk cache off it is built in a private temporary folder per process.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable

from ..errors import MechDeriveError
from . import codecache

__all__ = ["compiler", "c_enabled", "set_c_enabled", "load_library", "load_or_none", "why_unavailable", "CBuildError",
           "build_log"]

_FLAGS = ("-O2", "-fPIC", "-shared")
_MEMORY: dict[str, ctypes.CDLL] = {}
_LOCK = threading.Lock()
_ENABLED: list[bool | None] = [None]
_TMP: list[str] = []
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
    cc = os.environ.get("CC")
    candidates = [cc] if cc else ["cc", "gcc", "clang"]
    for name in candidates:
        path = shutil.which(name)
        if path:
            return path
    return None


def _library_path(name: str, *, private: bool = False) -> Path:
    cc = compiler() or "none"
    tag = hashlib.sha256(f"{platform.machine()}|{platform.system()}|{cc}|{' '.join(_FLAGS)}".encode()).hexdigest()[:12]
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in name)
    if codecache.disk_cache_enabled() and not private:
        return codecache.cache_dir() / codecache.fingerprint() / "c" / f"{safe}-{tag}.so"
    if not _TMP:
        _TMP.append(tempfile.mkdtemp(prefix="mechderive-c-"))
    return Path(_TMP[0]) / f"{safe}-{tag}.so"


def _build(source: str, target: Path) -> None:
    cc = compiler()
    if cc is None:  # pragma: no cover - callers check c_enabled() first
        raise CBuildError("expected a C compiler (cc, gcc or clang on PATH, or $CC), found none")
    target.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src = Path(tmp) / (target.stem + ".c")
        src.write_text(source)
        out = Path(tmp) / target.name
        proc = subprocess.run([cc, *_FLAGS, "-o", str(out), str(src), "-lm"], capture_output=True, text=True,
                              timeout=120)
        if proc.returncode != 0:
            raise CBuildError(f"expected {cc} to compile the generated {target.stem}.c, got exit code "
                              f"{proc.returncode}:\n{proc.stderr.strip()[:2000]}")
        # keep the source next to the library, for reading; then publish atomically
        os.replace(src, target.with_suffix(".c"))
        os.replace(out, target)


def load_library(name: str, build_source: Callable[[], str]) -> ctypes.CDLL:
    """The shared library ``name``: from memory, from the cache folder, or built from ``build_source()``.

    ``build_source`` is called only when the library is not cached; it returns the complete C
    source.  Raises :class:`CBuildError` if compilation fails.  Callers check :func:`c_enabled`.
    """
    with _LOCK:
        lib = _MEMORY.get(name)
        if lib is not None:
            return lib
        start = time.perf_counter()
        path = _library_path(name)
        how = "disk"
        if not path.exists():
            from .model import derivation_seconds

            before = derivation_seconds()
            source = build_source()
            start += derivation_seconds() - before  # the derivation is reported as such, not as compiling
            try:
                _build(source, path)
            except OSError:  # a read-only or full cache folder: build privately for this process
                path = _library_path(name, private=True)
                _build(source, path)
            how = "built"
        lib = ctypes.CDLL(str(path))
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
