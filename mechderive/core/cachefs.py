"""The disk cache's folders and files: private, checked before use, verified before load.

The disk cache (:mod:`.codecache` for generated Python, :mod:`.cbuild` for compiled C) holds code
that this process will execute, in a folder that may sit on a shared machine.  This module is the
only way either of them touches that folder, and it trusts nothing it finds there:

* **Folders.**  The root (``$MECHDERIVE_CACHE_DIR`` …) and every folder below it that the cache
  uses (the fingerprint folder, ``c/``) are created with mode 0700.  Before use, each one is
  opened and checked *through its file descriptor* (``fstat``): it must be owned by this
  process's effective uid and be writable by nobody else (no group or world write bit, sticky or
  not).  The root may be a symbolic link the user made (``~/.cache`` often is) — the folder it
  leads to is what is checked, and a link owned by another uid is refused; the folders below it
  are opened relative to their parent's descriptor with ``O_NOFOLLOW``, so a planted link or a
  rename race cannot redirect a later read or write.  A folder that fails a check is refused with
  ONE warning line per process on stderr (logger ``mechderive.cache``) and the run goes on
  without a disk cache; a folder that cannot be created or written (read-only, no permission)
  just means no disk cache, silently.
* **Files** are opened relative to the checked folder with ``O_NOFOLLOW | O_NONBLOCK`` (a link or
  a FIFO is never followed or waited on) and read only if ``fstat`` shows a regular file owned by
  this uid, writable by nobody else, and at most :data:`MAX_BYTES` long.  What is executed is the
  bytes that were read and verified — never the file again by name.
* **Content.**  Every artifact carries the SHA-256 of its name and content, written by us at
  store time (:func:`seal` puts it in a first line, or a ``.sha256`` sidecar for a shared
  library); a file whose hash does not match — edited, truncated, random bytes, a file copied from
  another name — is treated as absent: regenerated and replaced, never loaded.
* **Writes** go to a fresh ``O_EXCL`` temporary file (mode 0600) in the same folder, are
  ``fsync``-ed and published with ``os.replace``: readers see the old file or the new one, never
  half of one, and a failed write leaves nothing behind.

The checks need POSIX uids and the ``*at`` system calls; where they are missing there is no disk
cache at all.  What this cannot stop: a process of the *same* uid (or root) can rewrite the folder and its
hashes alike — but it can equally edit the user's shell profile; the checks make the cache no
weaker than the user's home directory.
"""

from __future__ import annotations

import contextlib
import os
import stat
from typing import TYPE_CHECKING, Iterator, Sequence

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

__all__ = ["directory", "read_file", "write_file", "seal", "unseal", "digest", "sha256", "MAX_BYTES"]

# SHA-256 as CPython implements it itself (module _sha2 from 3.12, _sha256 before), the implementation hashlib
# falls back to: hashlib's own constructors load OpenSSL's libcrypto, ~5 ms of every warm run for hashing a few
# kB.  The digests are the same; hashlib where neither module was built.
try:
    from _sha2 import sha256
except ImportError:  # pragma: no cover - Python < 3.12
    try:
        from _sha256 import sha256
    except ImportError:
        from hashlib import sha256

#: Largest artifact read from the cache (generated sources are ~0.2–30 kB, libraries ~30 kB).
MAX_BYTES = 64 * 2**20
_DIR_FLAGS = os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_CLOEXEC", 0)
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_READ_FLAGS = os.O_RDONLY | _NOFOLLOW | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
_WRITE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
_MAGIC = b"# mechderive-cache sha256="
#: Roots already warned about in this process (one line per root, not one per artifact).
_WARNED: set[str] = set()
#: The checks need uids and the ``*at`` calls (POSIX); elsewhere there is no disk cache at all.
_SUPPORTED = hasattr(os, "geteuid") and {os.open, os.mkdir, os.rename, os.unlink, os.stat} <= os.supports_dir_fd


def _normalized(root: str | os.PathLike) -> str:
    """``str(pathlib.Path(root))`` without importing pathlib (~6 ms of a warm run): :func:`os.path.normpath`'s
    result, which is the same (repeated and trailing separators and ``.`` dropped) except that it also folds
    ``a/..``, not the same folder when ``a`` is a symbolic link: a root with ``..`` goes through pathlib."""
    text = os.fspath(root)
    if ".." in text.split(os.sep):
        from pathlib import Path

        return str(Path(text))
    return os.path.normpath(text)


def _refuse(root: str, folder: str, why: str) -> None:
    """The one warning line for a refused cache folder (the run goes on without the disk cache)."""
    key = str(root)
    if key in _WARNED:
        return
    _WARNED.add(key)
    import logging  # only on this rare path: ~6 ms of a 0.3 s warm run otherwise

    fix = f"chmod go-w {folder}" if "writable" in why else "point MECHDERIVE_CACHE_DIR at a folder of your own"
    logging.getLogger("mechderive.cache").warning(
        "mechderive: warning: disk cache refused: %s %s; expected folders owned by uid %d and writable only by it "
        "(%s); running without a disk cache", folder, why, os.geteuid(), fix)


def _unsafe(st: os.stat_result) -> str | None:
    """Why a folder with this ``fstat`` may not be trusted, or None."""
    uid = os.geteuid()
    if st.st_uid != uid:
        return f"is owned by uid {st.st_uid}, not {uid}"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"is writable by group or others (mode {stat.S_IMODE(st.st_mode):04o})"
    return None


def _make_root(root: str) -> bool:
    """Create ``root`` (normalized) and its missing parents with mode 0700; False if it cannot be (read-only …)."""
    missing = []
    path = root
    while not os.path.lexists(path):
        missing.append(path)
        parent = os.path.dirname(path) or os.curdir  # what pathlib's parent is
        if parent == path:
            break
        path = parent
    try:
        for p in reversed(missing):
            with contextlib.suppress(FileExistsError):  # another process made it meanwhile
                os.mkdir(p, 0o700)
    except OSError:
        return False
    return True


def _open_root(root: str, create: bool) -> int | None:
    try:
        link = os.lstat(root)
    except FileNotFoundError:
        if not create or not _make_root(root):
            return None
        try:
            link = os.lstat(root)
        except OSError:
            return None
    except OSError:
        return None
    if stat.S_ISLNK(link.st_mode) and link.st_uid not in (os.geteuid(), 0):
        _refuse(root, root, f"is a symbolic link owned by uid {link.st_uid}")
        return None
    try:
        fd = os.open(root, _DIR_FLAGS)  # the user's own link (~/.cache → /scratch/…) is followed once
    except OSError:
        return None  # not a folder, or not ours to open: no disk cache
    why = _unsafe(os.fstat(fd))
    if why is not None:
        os.close(fd)
        _refuse(root, root, why)
        return None
    return fd


def _open_child(root: str, path: str, parent: int, name: str, create: bool) -> int | None:
    if create:
        with contextlib.suppress(OSError):  # exists already, or read-only: opening tells which
            os.mkdir(name, 0o700, dir_fd=parent)
    try:
        fd = os.open(name, _DIR_FLAGS | _NOFOLLOW, dir_fd=parent)
    except FileNotFoundError:
        return None
    except OSError as exc:  # a link (ELOOP), a file where the folder should be (ENOTDIR), no access
        try:  # Linux says ENOTDIR or ELOOP for a link: ask the entry itself
            link = stat.S_ISLNK(os.stat(name, dir_fd=parent, follow_symlinks=False).st_mode)
        except OSError:
            link = False
        why = "is a symbolic link" if link else f"cannot be opened as a folder ({exc.strerror})"
        _refuse(root, os.path.join(path, name), why)
        return None
    why = _unsafe(os.fstat(fd))
    if why is not None:
        os.close(fd)
        _refuse(root, os.path.join(path, name), why)
        return None
    return fd


@contextlib.contextmanager
def directory(root: str | Path, parts: Sequence[str], *, create: bool) -> Iterator[int | None]:
    """A descriptor of the checked folder ``root/parts[0]/parts[1]/…``, or None (no disk cache).

    With ``create``, missing folders are made (mode 0700).  None when a folder is refused (one
    warning per process, see the module docstring) or is missing and cannot be made.
    """
    path = root = _normalized(root)
    fd = _open_root(root, create) if _SUPPORTED else None
    for name in parts:
        if fd is None:
            break
        child = _open_child(root, path, fd, name, create)
        os.close(fd)
        fd, path = child, os.path.join(path, name)
    try:
        yield fd
    finally:
        if fd is not None:
            os.close(fd)


def read_file(folder: int, name: str, *, limit: int = MAX_BYTES) -> bytes | None:
    """The bytes of the regular file ``name`` in the checked ``folder`` if it is ours, else None.

    None also for a link, a FIFO or device, a file another uid owns or may write, a file over
    ``limit`` bytes, or any error: the caller regenerates the artifact and replaces the file.
    """
    try:
        fd = os.open(name, _READ_FLAGS, dir_fd=folder)
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if (not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid()
                or st.st_mode & (stat.S_IWGRP | stat.S_IWOTH) or st.st_size > limit):
            return None
        chunks, total = [], 0
        while total <= limit:
            # first a byte more than its size: a file read whole in one call (a regular file's short read is its end)
            ask = min(1 << 20, limit + 1 - total, st.st_size + 1 if not chunks else 1 << 20)
            chunk = os.read(fd, ask)
            chunks.append(chunk)
            total += len(chunk)
            if len(chunk) < ask:
                break
        return None if total > limit else b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(fd)


def write_file(folder: int, name: str, data: bytes) -> bool:
    """Publish ``data`` as ``name`` in ``folder`` atomically (mode 0600); False if it cannot be written."""
    tmp = f".{name}.{os.getpid()}.{os.urandom(6).hex()}.tmp"
    try:
        fd = os.open(tmp, _WRITE_FLAGS, 0o600, dir_fd=folder)
    except OSError:
        return False
    try:
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, name, src_dir_fd=folder, dst_dir_fd=folder)
        return True
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(tmp, dir_fd=folder)
        return False
    except BaseException:  # Ctrl-C mid-write: no temporary file left behind either
        with contextlib.suppress(OSError):
            os.unlink(tmp, dir_fd=folder)
        raise


def digest(key: str, payload: bytes) -> str:
    """SHA-256 (hex) of ``key`` and ``payload``: binding the name means a file copied under another
    name does not verify."""
    return sha256(key.encode() + b"\0" + payload).hexdigest()


def seal(key: str, payload: bytes) -> bytes:
    """``payload`` behind a first line carrying its :func:`digest` (a comment, so a sealed
    Python source is still valid Python)."""
    return _MAGIC + digest(key, payload).encode() + b"\n" + payload


def unseal(key: str, data: bytes | None) -> bytes | None:
    """The payload of :func:`seal`'s ``data`` if its hash matches ``key`` and the content, else None."""
    if not data:
        return None
    head, newline, payload = data.partition(b"\n")
    if not newline or not head.startswith(_MAGIC) or head[len(_MAGIC):] != digest(key, payload).encode():
        return None
    return payload
