"""Writing the results of a scene: a table of sampled quantities, and a JSON report.

Tables (:func:`write_table`) are chosen by the file's suffix:

- ``.csv``: a header ``t,<name>,...`` in the order given, then one row per sample,
  every number written with Python's ``repr`` (the shortest decimal that reads back
  to the same double, at most 17 significant digits), so ``np.loadtxt(path,
  delimiter=",", skiprows=1)`` recovers the arrays exactly; NaN and ±inf are written
  ``nan``, ``inf``, ``-inf``, which ``np.loadtxt`` reads;
- ``.npz``: one float64 array named ``t`` and one per quantity (``np.load``).

The file is written to a temporary name beside the target and renamed into place
(:func:`atomic_output`), so a failed or interrupted run never leaves a half-written
table under the final name, nor a temporary file.  :func:`check_output_path` checks
a target (suffix, directory) before the work that fills it starts.

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
import json
import math
import os
import re
import secrets
import zipfile
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from ..errors import InvalidInputError, ShapeError

__all__ = ["TABLE_SUFFIXES", "write_table", "report_json", "check_output_path", "atomic_output"]

TABLE_SUFFIXES = (".csv", ".npz")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _check_columns(t: Any, columns: Mapping[str, Any]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
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


def check_output_path(path: str | os.PathLike, suffixes: Sequence[str], *, what: str = "output file") -> Path:
    """``path`` as a :class:`~pathlib.Path` if a file of one of the ``suffixes`` can be written there.

    Checked before any work is done, so that a long run does not end in a refusal: the
    suffix (case-insensitive), that the directory exists and is writable, and that
    ``path`` is not itself a directory.  ``what`` names the file in the message.
    Raises :class:`~mechderive.errors.InvalidInputError` otherwise.
    """
    path = Path(path)
    shown = f"{what} {str(path)!r}"
    if path.suffix.lower() not in suffixes:
        allowed = " or ".join(suffixes) if len(suffixes) == 2 else ", ".join(suffixes)
        raise InvalidInputError(f"{shown}: expected a suffix {allowed}, got {path.suffix or 'none'!r}")
    parent = path.parent
    if not parent.is_dir():
        raise InvalidInputError(f"{shown}: expected an existing directory, got {str(parent)!r}")
    if path.is_dir():
        raise InvalidInputError(f"{shown}: expected a file name, got a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InvalidInputError(f"{shown}: expected a directory you can write to, got {str(parent)!r}")
    return path


def _create_beside(path: Path) -> tuple[int, Path]:
    # Like tempfile.mkstemp, but with mode 0o666 so that the umask applies: the renamed file gets
    # the permissions a plainly written one would (mkstemp's 0o600 would make every table private).
    for _ in range(100):
        tmp = path.with_name(f".{path.stem}.{secrets.token_hex(4)}.tmp{path.suffix}")
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {str(path)!r}")  # pragma: no cover


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, *, what: str = "output file") -> Iterator[Path]:
    """A temporary file beside ``path``, renamed onto ``path`` when the ``with`` block ends normally.

    The temporary file has ``path``'s suffix (so writers that infer the format from the
    name work) and is removed when the block raises, also on Ctrl-C: ``path`` is never left
    half-written, and an existing ``path`` is kept until the new file is complete.
    An :class:`OSError` while writing (disk full, no permission) becomes
    :class:`~mechderive.errors.InvalidInputError` naming the file.
    """
    path = Path(path)
    try:
        fd, tmp = _create_beside(path)
    except OSError as exc:
        raise InvalidInputError(f"{what} {str(path)!r}: expected a writable location, "
                                f"got {exc.strerror or exc}") from exc
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, BrokenPipeError):
            raise InvalidInputError(f"{what} {str(path)!r}: could not write it: {exc.strerror or exc}") from exc
        raise


def _write_atomically(path: Path, write: Any) -> None:
    with atomic_output(path) as tmp, open(tmp, "wb") as f:
        write(f)


def _write_npz(f: Any, arrays: Mapping[str, np.ndarray]) -> None:
    # What np.savez writes (one NAME.npy per array in a zip), without np.savez's keyword
    # arguments, which a column named "file" or "allow_pickle" would collide with.
    with zipfile.ZipFile(f, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as archive:
        for name, arr in arrays.items():
            with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, arr, allow_pickle=False)


def write_table(path: str | os.PathLike, t: Any, columns: Mapping[str, Any]) -> Path:
    """Write the samples ``t`` and the ``columns`` (name -> array of the same length) to ``path``.

    The format follows the suffix, ``.csv`` or ``.npz`` (see the module docstring);
    any other suffix is refused.  Returns the path written.
    """
    path = check_output_path(path, TABLE_SUFFIXES)
    suffix = path.suffix.lower()
    times, cols = _check_columns(t, columns)
    if suffix == ".npz":
        _write_atomically(path, lambda f: _write_npz(f, {"t": times, **cols}))
        return path
    table = np.column_stack([times, *cols.values()]) if cols else times[:, None]
    row_format = ",".join(["%r"] * table.shape[1]) + "\n"

    def write_csv(f: Any) -> None:
        f.write((",".join(["t", *cols]) + "\n").encode("ascii"))
        for start in range(0, len(table), 4096):
            chunk = table[start:start + 4096].tolist()  # Python floats: repr is the shortest round trip
            f.write("".join(row_format % tuple(row) for row in chunk).encode("ascii"))

    _write_atomically(path, write_csv)
    return path


def _plain(value: Any, where: str) -> Any:
    """``value`` as JSON-ready Python objects, non-finite floats as strings."""
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
    if not isinstance(report, Mapping):
        raise InvalidInputError(f"expected the report to be a mapping, got {type(report).__name__}")
    return json.dumps(_plain(report, ""), sort_keys=True, indent=2, ensure_ascii=False, allow_nan=False)
