"""Replaying ``derive`` and ``check`` from the disk cache of text answers (:mod:`mechderive.core.textcache`)."""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import stat
import sys
import tomllib
from typing import Callable

#: derive's targets that are not systems of the registry (the kinematics and the inertia of shapes)
_NOT_SYSTEMS = ("rotation", "angular_velocity", "inertia")


_LIMIT = 1_000_000  # a scene or a file of claims is a page of text; anything else is not replayed


def _regular_bytes(path: str) -> bytes | None:
    """The bytes of ``path`` if it is a regular file of at most ``_LIMIT`` bytes, else None (a FIFO, a device,
    a directory: the command itself then reads or refuses it, as it would without a cache)."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        fd = os.open(path, flags)
    except (OSError, ValueError):
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_size > _LIMIT:
            return None
        data = os.read(fd, _LIMIT + 1)
        return data if len(data) <= _LIMIT else None
    except OSError:
        return None
    finally:
        os.close(fd)


def _builtin_target(target: str) -> bytes | str | None:
    """What identifies ``target`` (a built-in system's name, or a scene file's bytes), None if not cacheable."""
    from ..systems import registry

    if target.endswith(".toml"):
        data = _regular_bytes(target)
        if data is None:
            return None
        try:
            system = tomllib.loads(data.decode("utf-8")).get("system")
        except (ValueError, UnicodeDecodeError):
            return None
        return data if isinstance(system, str) and registry.is_builtin(system) else None
    return target if target in _NOT_SYSTEMS or registry.is_builtin(target) else None


class _Tee(io.TextIOBase):
    """Standard output as it goes (a long ``check --file`` shows each line at once), and a copy kept."""

    def __init__(self, out) -> None:
        self.out, self.copy = out, io.StringIO()

    def write(self, text: str) -> int:
        self.copy.write(text)
        return self.out.write(text)

    def flush(self) -> None:
        self.out.flush()


def cached(kind: str, args: argparse.Namespace, command: Callable[[argparse.Namespace], int],
           *, keep: tuple[int, ...] = (0,), files: tuple[str, ...] = (), ignore: tuple[str, ...] = (),
           replayed: str = "", parts: tuple = ()) -> int:
    """Run ``command(args)``, or print its stored answer: the stdout and status of an earlier identical run.

    ``files`` name the attributes of ``args`` that are paths whose contents the answer depends on
    (besides the system or scene), ``ignore`` those that do not change the answer (``--jobs``); an answer
    is stored only when its status is in ``keep``; ``replayed`` is said on stderr when one is replayed;
    ``parts`` are more of what the answer depends on (the claims ``verify`` checks).
    """
    from ..core import textcache

    target = _builtin_target(args.system) if hasattr(args, "system") else kind
    parts = [target, *parts] if target is not None else []
    for attr in files:
        path = getattr(args, attr, None)
        if path is None:
            continue
        if path == "-":
            target = None  # standard input: read once, never replayed
            break
        data = _regular_bytes(path)
        if data is None:
            target = None
            break
        parts.append(data)
    if target is None:
        return command(args)
    options = {k: v for k, v in sorted(vars(args).items())
               if k not in ("run", "system", *ignore) and not callable(v)}
    name = textcache.key(kind, [*parts, options])
    hit = textcache.lookup(name)
    if hit is not None:
        sys.stdout.write(hit[0])
        if replayed:
            sys.stderr.write(replayed + "\n")
        return hit[1]
    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):
        status = command(args)
    text = tee.copy.getvalue()
    if status in keep:
        textcache.store(name, text, status)
    return status
