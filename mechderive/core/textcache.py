"""The disk cache of answers that are text: ``mechderive derive`` and ``check`` replayed without deriving.

A ``derive`` or ``check`` command is a pure function of its arguments, of the files it reads (a scene, a
file of claims), of the package's source and of the SymPy, NumPy and mpmath versions (the
:func:`~.codecache.fingerprint` of the compiled-code cache).  Its printed output and exit status are
kept under that fingerprint, keyed by a SHA-256 of everything else, in the same private folder as the
compiled code and through the same checks (:mod:`.cachefs`: owned by this uid, sealed with a hash,
written atomically).  A warm command then prints the stored text without importing SymPy at all.

Only answers that cannot change are kept: the built-in systems (a system registered by a program may
be a different one under the same name next time), finished verdicts (never one left undecided by
its time budget), and nothing read from standard input.  The cache is safe to delete; a corrupt
entry is regenerated and replaced.  ``MECHDERIVE_NO_DISK_CACHE=1`` turns it off with the rest.

:func:`get` and :func:`put` keep other bytes the same way: the command line's scene documents as parsed from
their TOML (``scene-<SHA-256 of the text>.marshal``, :func:`mechderive.scenes.schema.load_scene`).
"""

from __future__ import annotations

from typing import Any, Sequence

from . import cachefs, codecache

__all__ = ["key", "lookup", "store", "get", "put"]

_FOLDER = "text"
_LIMIT = 16 * 2**20


def key(kind: str, parts: Sequence[Any]) -> str:
    """The entry name of the command ``kind`` with these ``parts`` (arguments, file contents as bytes)."""
    import json

    h = cachefs.sha256(kind.encode())
    for part in parts:
        data = part if isinstance(part, bytes) else json.dumps(part, sort_keys=True, default=repr).encode()
        h.update(len(data).to_bytes(8, "little") + data)
    return f"{kind}-{h.hexdigest()[:40]}.json"


def get(name: str) -> bytes | None:
    """The bytes stored under ``name`` (verified: see :mod:`.cachefs`), or None."""
    if not codecache.disk_cache_enabled():
        return None
    with cachefs.directory(codecache._root(), (codecache.fingerprint(), _FOLDER), create=False) as folder:
        if folder is None:
            return None
        return cachefs.unseal(name, cachefs.read_file(folder, name, limit=_LIMIT))


def put(name: str, payload: bytes) -> None:
    """Keep ``payload`` under ``name`` (silently nothing where there is no disk cache, or it is too long)."""
    if not codecache.disk_cache_enabled() or len(payload) > _LIMIT:
        return
    with cachefs.directory(codecache._root(), (codecache.fingerprint(), _FOLDER), create=True) as folder:
        if folder is not None:
            cachefs.write_file(folder, name, cachefs.seal(name, payload))


def lookup(name: str) -> tuple[str, int] | None:
    """(stdout text, exit status) stored under ``name``, or None."""
    payload = get(name)
    if payload is None:
        return None
    import json

    try:
        entry = json.loads(payload.decode("utf-8"))
        return str(entry["stdout"]), int(entry["status"])
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        return None


def store(name: str, stdout: str, status: int) -> None:
    """Keep ``stdout`` and ``status`` under ``name`` (silently nothing where there is no disk cache)."""
    import json

    put(name, json.dumps({"stdout": stdout, "status": status}).encode("utf-8"))
