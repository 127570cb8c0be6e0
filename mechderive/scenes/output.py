"""Writing the results of a scene: a table of sampled quantities, and a JSON report.

Tables (:func:`write_table`) are chosen by the file's suffix:

- ``.csv``: a header ``t,<name>,...`` in the order given, then one row per sample,
  every number written with Python's ``repr`` (the shortest decimal that reads back
  to the same double, at most 17 significant digits), so ``np.loadtxt(path,
  delimiter=",", skiprows=1)`` recovers the arrays exactly; NaN and ±inf are written
  ``nan``, ``inf``, ``-inf``, which ``np.loadtxt`` reads;
- ``.npz``: one float64 array named ``t`` and one per quantity (``np.load``).

The file is written to a temporary name beside the target and renamed into place
(:func:`atomic_output`), so a failed or interrupted run (an error, Ctrl-C, SIGTERM)
never leaves a half-written table under the final name, nor a temporary file; a new
file gets the umask's permissions, a replaced one keeps its own, and a symbolic link
is written through.  :func:`check_output_path` checks a target (suffix, directory,
kind of file, permissions, length of names) before the work that fills it starts.

Reports (:func:`report_json`) are JSON with sorted keys.  JSON has no NaN or
infinity; non-finite floats are written as the *strings* ``"NaN"``, ``"Infinity"``
and ``"-Infinity"`` (every one, wherever it occurs), which ``float()`` reads back.

>>> print(report_json({"b": float("nan"), "a": [1, 2.5]}))
{
  "a": [
    1,
    2.5
  ],
  "b": "NaN"
}
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import re
import stat
from typing import TYPE_CHECKING, Any, Iterator, Mapping, Sequence

# pathlib, signal and threading are imported where a file is written, not here: the command line imports this
# module for every command, and they cost ~8 ms of a warm run that writes no file
if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

from ..errors import InvalidInputError, ShapeError

__all__ = ["TABLE_SUFFIXES", "write_table", "report_json", "check_output_path", "check_free_space", "atomic_output",
           "Terminated"]

TABLE_SUFFIXES = (".csv", ".npz")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _check_columns(t: Any, columns: Mapping[str, Any]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    import numpy as np  # here, not at import: the command line imports this module for every command

    times = np.asarray(t)
    if times.ndim != 1 or not np.issubdtype(times.dtype, np.number) or np.iscomplexobj(times):
        raise ShapeError(f"expected `t` to be a 1-D array of real numbers, got shape {times.shape} "
                         f"of {times.dtype}")
    if not isinstance(columns, Mapping):
        raise InvalidInputError(f"expected `columns` to be a mapping name -> array, got {type(columns).__name__}")
    out: dict[str, np.ndarray] = {}
    for name, values in columns.items():
        if not isinstance(name, str) or not _NAME.fullmatch(name) or name == "t":
            raise InvalidInputError(f"expected a column name matching [A-Za-z_][A-Za-z0-9_]* other than 't', "
                                    f"got {name!r}")
        arr = np.asarray(values)
        if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
            raise InvalidInputError(f"expected column {name!r} to hold real numbers, got {arr.dtype}")
        if arr.shape != times.shape:
            raise ShapeError(f"expected column {name!r} to have the shape of `t`, {times.shape}, got {arr.shape}")
        out[name] = arr.astype(np.float64)
    return times.astype(np.float64), out


_NAME_MAX = 255     # bytes in one file name, on every common file system (ext4, XFS, btrfs, APFS, NTFS)
_SYMLINKS_MAX = 40  # links followed before giving up, as Linux does (ELOOP)
_SHOWN_MAX = 120    # characters of a path quoted in a message; longer ones are cut in the middle


def _shown(path: str | os.PathLike) -> str:
    text = os.fspath(path)
    if len(text) > _SHOWN_MAX:
        text = f"{text[:_SHOWN_MAX // 2 - 1]}…{text[-(_SHOWN_MAX // 2):]}"
    return repr(text)


def _as_path(path: Any, what: str) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidInputError(f"{what}: expected a path (a string), got {type(path).__name__}")
    given = os.fspath(path)
    if isinstance(given, bytes):
        given = os.fsdecode(given)
    from pathlib import Path

    path = Path(given)
    text = os.fspath(path)
    if not text or text == ".":
        raise InvalidInputError(f"{what}: expected a file name, got an empty one")
    if given.endswith(tuple(sep for sep in (os.sep, os.altsep) if sep)):
        # Path() drops the separator: "out.csv/" would silently become a file "out.csv".
        raise InvalidInputError(f"{what} {_shown(given)}: expected a file name, got a directory name "
                                f"(ending in {given[-1]!r})")
    if "\0" in text:
        raise InvalidInputError(f"{what} {_shown(text)}: expected a file name without NUL characters, "
                                f"got one at position {text.index(chr(0))}")
    return path


def _refuse_planted_link(link: Path, st: os.stat_result, shown: str) -> None:
    """Refuse to follow ``link`` where another user could have planted it.

    The rule of Linux's ``fs.protected_symlinks``, applied here because the link is resolved
    by this code (to replace its target), not by the kernel, and because the setting is off
    on many machines and absent elsewhere: in a sticky, world-writable directory (``/tmp``)
    a link is followed only if its owner is the user running this or the directory's owner.
    Without it, anyone could leave ``/tmp/out.csv -> ~victim/.bashrc`` for a victim's
    ``-o /tmp/out.csv`` to overwrite.
    """
    try:
        parent = os.stat(link.parent)
    except OSError:
        return  # the lookup of the target reports it
    shared = parent.st_mode & stat.S_ISVTX and parent.st_mode & stat.S_IWOTH
    if shared and st.st_uid not in (os.geteuid(), parent.st_uid):
        raise InvalidInputError(f"{shown}: expected a symbolic link owned by you or by the owner of the shared "
                                f"directory {_shown(link.parent)}, got one owned by uid {st.st_uid} "
                                f"(not followed: another user may have planted it)")


def _follow_links(path: Path, shown: str) -> tuple[Path, bool]:
    """``path`` with its last component's symbolic links followed, and whether there were any.

    Only the last component is resolved here: the directories on the way are looked up by the
    kernel when the file is created, so the file is replaced in the directory it lives in.
    """
    from pathlib import Path

    target = path
    for _ in range(_SYMLINKS_MAX + 1):
        try:
            st = os.lstat(target)
        except (FileNotFoundError, NotADirectoryError):
            return target, target is not path  # a new file (perhaps through a dangling link)
        except OSError as exc:
            raise _lookup_error(target, exc, shown) from exc
        if not stat.S_ISLNK(st.st_mode):
            return target, target is not path
        _refuse_planted_link(target, st, shown)
        try:
            # No normalisation of "..": after a link it refers to the link target's parent.
            target = Path(os.path.join(os.path.dirname(target), os.readlink(target)))
        except OSError as exc:
            raise _lookup_error(target, exc, shown) from exc
    raise InvalidInputError(f"{shown}: expected a symbolic link that leads to a file, got a loop "
                            f"(more than {_SYMLINKS_MAX} links followed)")


def _lookup_error(path: Path, exc: OSError, shown: str) -> InvalidInputError:
    if exc.errno == errno.ENAMETOOLONG:
        longest = max(len(os.fsencode(part)) for part in path.parts)
        if longest > _NAME_MAX:
            return InvalidInputError(f"{shown}: expected names of at most {_NAME_MAX} bytes, "
                                     f"got one of {longest}")
        return InvalidInputError(f"{shown}: expected a path the system can look up, got one of "
                                 f"{len(os.fsencode(path))} bytes (File name too long)")
    if exc.errno == errno.ELOOP:
        return InvalidInputError(f"{shown}: expected a path that leads to a file, got a loop of symbolic links")
    return InvalidInputError(f"{shown}: expected a path that can be looked up, got {exc.strerror or exc}")


_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"),
          (stat.S_ISSOCK, "a socket"))


def _writable_target(path: Path, what: str) -> tuple[Path, os.stat_result | None]:
    """The file that writing ``path`` replaces (symbolic links followed), and its status if it exists.

    Raises :class:`~mechderive.errors.InvalidInputError` naming ``what`` and ``path`` if a
    file cannot be written there; see :func:`check_output_path`.
    """
    shown = f"{what} {_shown(path)}"
    target, via_link = _follow_links(path, shown)
    where = f" (where the symbolic link leads: {_shown(target)})" if via_link else ""
    if len(os.fsencode(target.name)) > _NAME_MAX:
        raise InvalidInputError(f"{shown}: expected names of at most {_NAME_MAX} bytes, "
                                f"got one of {len(os.fsencode(target.name))}{where}")
    old = _stat_or_none(target, shown)
    if old is not None:
        if stat.S_ISDIR(old.st_mode):
            raise InvalidInputError(f"{shown}: expected a file name, got a directory{where}")
        kind = next((name for test, name in _KINDS if test(old.st_mode)), "not a regular file")
        if not stat.S_ISREG(old.st_mode):
            raise InvalidInputError(f"{shown}: expected a regular file or a new name, got {kind}{where}")
        if not os.access(target, os.W_OK):
            raise InvalidInputError(f"{shown}: expected a file you may write to, got a read-only one{where}")
    parent = target.parent
    parent_st = _stat_or_none(parent, shown)
    if parent_st is None or not stat.S_ISDIR(parent_st.st_mode):
        raise InvalidInputError(f"{shown}: expected an existing directory, got {_shown(parent)}{where}")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InvalidInputError(f"{shown}: expected a directory you may write to, got {_shown(parent)}{where}")
    euid = os.geteuid() if hasattr(os, "geteuid") else None
    if (old is not None and euid not in (None, 0) and parent_st.st_mode & stat.S_ISVTX
            and euid not in (old.st_uid, parent_st.st_uid)):
        # In a sticky directory (/tmp) only a file's owner may replace it: the rename would fail
        # after the work is done.
        raise InvalidInputError(f"{shown}: expected a file of yours in the sticky directory {_shown(parent)}, "
                                f"got one owned by uid {old.st_uid}{where}")
    return target, old


def _stat_or_none(path: Path, shown: str) -> os.stat_result | None:
    """``os.stat(path)``, None when nothing is there; any other failure to look it up is the user's error."""
    try:
        return os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        raise _lookup_error(path, exc, shown) from exc


def check_output_path(path: str | os.PathLike, suffixes: Sequence[str], *, what: str = "output file") -> Path:
    """``path`` as a :class:`~pathlib.Path` if a file of one of the ``suffixes`` can be written there.

    Checked before any work is done, so that a long run does not end in a refusal: the
    suffix (case-insensitive); the file the name leads to, symbolic links followed (see
    :func:`atomic_output`), which must be new or a regular file you may write to; its
    directory, which must exist and be writable; names of at most 255 bytes.  Last, the
    temporary file the write will use is created and removed at once: only the file system
    knows whether it accepts the name (``/proc``, ``/sys``, a FAT stick, a quota, root on a
    read-only mount).  ``what`` names the file in the message (the command line passes its
    option, e.g. ``"-o"``).  Raises :class:`~mechderive.errors.InvalidInputError` otherwise.
    """
    path = _as_path(path, what)
    if path.suffix.lower() not in suffixes:
        allowed = " or ".join(suffixes) if len(suffixes) == 2 else ", ".join(suffixes)
        raise InvalidInputError(f"{what} {_shown(path)}: expected a suffix {allowed}, got {path.suffix or 'none'!r}")
    target, _ = _writable_target(path, what)
    with _signals_deferred():  # SIGTERM waits the few microseconds the probe lives
        try:
            fd, probe = _create_beside(target, path.suffix, None)
        except OSError as exc:
            raise InvalidInputError(f"{what} {_shown(path)}: expected a place where a file can be created, "
                                    f"got {exc.strerror or exc}") from exc
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(probe)
    return path


def _table_bytes_at_least(rows: int, columns: int, suffix: str) -> int:
    """A size no table of ``rows`` × ``columns`` numbers in this format can be smaller than.

    ``.npz``: 8 bytes a number (the arrays alone, headers not counted); ``.csv``: 4 (``0.0``
    and a separator, the shortest a float's ``repr`` can be).
    """
    return rows * columns * (8 if suffix.lower() == ".npz" else 4)


def check_free_space(path: str | os.PathLike, rows: int, columns: int, *, what: str = "output file") -> None:
    """Refuse, before the work, a table of ``rows`` × ``columns`` that cannot fit where ``path`` leads.

    Compared with the space free to you on its file system is a size the table cannot be
    smaller than (:func:`_table_bytes_at_least`), so that a run which could fit is never
    refused; a disk filled while the run works is still reported when the write fails.
    Does nothing where the system does not tell the free space.
    """
    if not hasattr(os, "statvfs"):
        return  # pragma: no cover - Windows
    path = _as_path(path, what)
    target, _ = _writable_target(path, what)
    try:
        fs = os.statvfs(target.parent)
    except OSError:
        return
    free = fs.f_bavail * fs.f_frsize
    need = _table_bytes_at_least(rows, columns, path.suffix)
    if need > free:  # an old file replaced frees its space only after the rename: not counted
        raise InvalidInputError(f"{what} {_shown(path)}: expected at least {need:,} bytes free for {rows:,} samples "
                                f"of {columns} columns, got {free:,} free on its file system")


def _temporary_name(target: Path, suffix: str) -> Path:
    # Hidden, beside the target (so that the rename is atomic), with the suffix of the name the
    # caller gave (writers infer the format from it), and short enough for the file system even
    # when the target's own name is at the limit.
    tag = f".{os.urandom(4).hex()}.tmp{suffix}"
    if len(os.fsencode(tag)) > _NAME_MAX // 2:
        tag = f".{os.urandom(4).hex()}.tmp"
    stem = target.stem
    while stem and len(os.fsencode(f".{stem}{tag}")) > _NAME_MAX:
        stem = stem[:-1]
    return target.with_name(f".{stem}{tag}")


def _create_beside(target: Path, suffix: str, old: os.stat_result | None) -> tuple[int, Path]:
    # Mode 0o666, so that the umask applies as for any file a program creates (mkstemp's 0o600
    # would make every table private); a file replaced keeps its permission bits and, where
    # allowed, its owner and group, as it would if it were written in place.
    for _ in range(100):
        tmp = _temporary_name(target, suffix)
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
        except FileExistsError:
            continue
        if old is not None and hasattr(os, "fchmod"):
            try:
                os.fchmod(fd, stat.S_IMODE(old.st_mode) & 0o777)  # set-id bits are not carried over
                if hasattr(os, "fchown") and (old.st_uid, old.st_gid) != (os.geteuid(), os.getegid()):
                    with contextlib.suppress(PermissionError):
                        os.fchown(fd, old.st_uid, old.st_gid)
            except BaseException:
                os.close(fd)
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
                raise
        return fd, tmp
    raise FileExistsError(f"no free temporary name beside {str(target)!r}")  # pragma: no cover


class Terminated(SystemExit):
    """Raised by the SIGTERM (or SIGHUP) handler that :func:`atomic_output` installs while writing.

    A :class:`SystemExit` whose code is 128 + the signal number (143 for SIGTERM), what a
    shell reports for a process the signal killed: the run stops as the signal's default
    action would, but only after the temporary file has been removed.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(128 + signum)
        self.signum = signum


def _terminating() -> tuple:
    """The signals that end the process by default and that a write defers or turns into :class:`Terminated`."""
    import signal

    return tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def _terminated_cleanly() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Terminated` inside the block instead of killing the process.

    Only where Python may set handlers (the main thread), and only for a signal whose action
    is still the default (killing the process): a program that installed its own handler, or
    ignores the signal, keeps it.  The previous handlers are restored on leaving.
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raised = []

    def handler(signum: int, _frame: Any) -> None:
        if not raised:  # a second signal while the first unwinds would cut the cleanup short
            raised.append(signum)
            raise Terminated(signum)

    installed = {}
    try:
        for signum in _terminating():
            if signal.getsignal(signum) is signal.SIG_DFL:
                installed[signum] = signal.signal(signum, handler)
        yield
    finally:
        for signum, previous in installed.items():
            signal.signal(signum, previous)


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """SIGTERM and SIGHUP held back in the block (delivered on leaving it), where the OS allows."""
    import signal

    terminating = _terminating()
    if not hasattr(signal, "pthread_sigmask") or not terminating:
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, terminating)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, *, what: str = "output file") -> Iterator[Path]:
    """A temporary file beside ``path``, renamed onto ``path`` when the ``with`` block ends normally.

    The temporary file has ``path``'s suffix (so writers that infer the format from the
    name work) and is removed when the block raises, also on Ctrl-C and on SIGTERM or SIGHUP
    (see :class:`Terminated`): ``path`` is never left half-written, and an existing ``path``
    is kept until the new file is complete.

    - A new file gets the permissions the umask gives (``0o666 & ~umask``); a file replaced
      keeps its permission bits (and its owner and group where the user may set them).
    - A symbolic link is written through: the file it leads to is replaced, in its own
      directory, and the link is kept; a dangling link creates its target if the target's
      directory exists.  As GNU ``sort -o`` or ``cp`` do under Linux's
      ``fs.protected_symlinks``, a link in a sticky world-writable directory (``/tmp``) is
      followed only if you or the directory's owner own it.
    - Other hard links to a file replaced keep the old content (the file is replaced, not
      rewritten in place).

    A target that cannot be written (see :func:`check_output_path`) or an :class:`OSError`
    while writing (disk full, no permission) becomes :class:`~mechderive.errors.InvalidInputError`
    naming ``what`` and the file.
    """
    path = _as_path(path, what)
    target, old = _writable_target(path, what)
    tmp: Path | None = None
    with _terminated_cleanly():
        try:
            with _signals_deferred():  # no signal between creating the file and knowing its name
                try:
                    fd, tmp = _create_beside(target, path.suffix, old)
                except OSError as exc:
                    raise InvalidInputError(f"{what} {_shown(path)}: expected a writable location, "
                                            f"got {exc.strerror or exc}") from exc
            os.close(fd)
            yield tmp
            os.replace(tmp, target)
        except BaseException as exc:
            if tmp is not None:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            if isinstance(exc, OSError) and not isinstance(exc, BrokenPipeError):
                raise InvalidInputError(f"{what} {_shown(path)}: could not write it: {exc.strerror or exc}") from exc
            raise


def _write_atomically(path: Path, write: Any, what: str = "output file") -> None:
    with atomic_output(path, what=what) as tmp, open(tmp, "wb") as f:
        write(f)


def _write_npz(f: Any, arrays: Mapping[str, np.ndarray]) -> None:
    # What np.savez writes (one NAME.npy per array in a zip), without np.savez's keyword
    # arguments, which a column named "file" or "allow_pickle" would collide with.
    import zipfile

    import numpy as np

    with zipfile.ZipFile(f, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as archive:
        for name, arr in arrays.items():
            with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, arr, allow_pickle=False)


def write_table(path: str | os.PathLike, t: Any, columns: Mapping[str, Any], *, what: str = "output file") -> Path:
    """Write the samples ``t`` and the ``columns`` (name -> array of the same length) to ``path``.

    The format follows the suffix, ``.csv`` or ``.npz`` (see the module docstring);
    any other suffix is refused.  The file is written as :func:`atomic_output` says
    (permissions, symbolic links, interruptions).  ``what`` names the file in error
    messages (the command line passes ``"-o"``).  Returns the path written.
    """
    path = check_output_path(path, TABLE_SUFFIXES, what=what)
    import numpy as np

    suffix = path.suffix.lower()
    times, cols = _check_columns(t, columns)
    if suffix == ".npz":
        _write_atomically(path, lambda f: _write_npz(f, {"t": times, **cols}), what)
        return path
    table = np.column_stack([times, *cols.values()]) if cols else times[:, None]
    row_format = ",".join(["%r"] * table.shape[1]) + "\n"

    def write_csv(f: Any) -> None:
        f.write((",".join(["t", *cols]) + "\n").encode("ascii"))
        for start in range(0, len(table), 4096):
            chunk = table[start:start + 4096].tolist()  # Python floats: repr is the shortest round trip
            f.write("".join(row_format % tuple(row) for row in chunk).encode("ascii"))

    _write_atomically(path, write_csv, what)
    return path


def _plain(value: Any, where: str) -> Any:
    """``value`` as JSON-ready Python objects, non-finite floats as strings."""
    import numpy as np

    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        x = float(value)
        if math.isnan(x):
            return "NaN"
        if math.isinf(x):
            return "Infinity" if x > 0 else "-Infinity"
        return x
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise InvalidInputError(f"report key at {where or 'top level'}: expected a string, got {k!r}")
            out[k] = _plain(v, f"{where}.{k}" if where else k)
        return out
    if isinstance(value, (list, tuple, np.ndarray)):
        items = value.tolist() if isinstance(value, np.ndarray) else value
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(items)]
    raise InvalidInputError(f"report value at {where or 'top level'}: expected a number, string, boolean, None, "
                            f"list or mapping, got {type(value).__name__}")


def report_json(report: Mapping[str, Any]) -> str:
    """The report as JSON text: sorted keys, 2-space indent, NaN/±inf as strings (module docstring).

    NumPy scalars and arrays become numbers and lists, paths strings; other objects are refused.
    """
    import json

    if not isinstance(report, Mapping):
        raise InvalidInputError(f"expected the report to be a mapping, got {type(report).__name__}")
    return json.dumps(_plain(report, ""), sort_keys=True, indent=2, ensure_ascii=False, allow_nan=False)


def summary_path(table: str | os.PathLike) -> Path:
    """Where ``-o OUT.csv`` (or ``.npz``) puts the scene's per-motion quantities: ``OUT.summary.json`` beside it."""
    from pathlib import Path

    path = Path(table)
    return path.with_name(path.stem + ".summary.json")


def write_summary(path: str | os.PathLike, report: Mapping[str, Any], units: Mapping[str, str], *,
                  what: str = "summary file") -> Path:
    """Write a run's per-motion quantities to ``path`` (JSON, written as :func:`atomic_output` says).

    The file holds ``summary`` ({name: value}), ``summary_error`` ({name: error estimate, or the reason a
    quantity does not apply}) and ``units`` ({name: SI unit}), as the ``--json`` report does, plus the
    run's ``system``, ``method`` and ``error_estimate`` so that the file stands on its own.
    """
    import json

    path = check_output_path(path, (".json",), what=what)
    content = {"system": report.get("system"), "method": report.get("method"),
               "error_estimate": report.get("error_estimate"),
               "summary": report.get("summary", {}), "summary_error": report.get("summary_error", {}),
               "units": dict(units)}
    text = json.dumps(_plain(content, ""), sort_keys=True, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    _write_atomically(path, lambda f: f.write(text.encode("utf-8")), what)
    return path
