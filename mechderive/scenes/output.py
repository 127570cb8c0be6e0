"""Writing the results of a scene: a table of sampled quantities, and a JSON report.

Tables (:func:`write_table`) are chosen by the file's suffix:

- ``.csv``: a header ``t,<name>,...`` in the order given, then one row per sample,
  every number written with Python's ``repr`` (the shortest decimal that reads back
  to the same double, at most 17 significant digits), so ``np.loadtxt(path,
  delimiter=",", skiprows=1)`` recovers the arrays exactly; NaN and ±inf are written
  ``nan``, ``inf``, ``-inf``, which ``np.loadtxt`` reads;
- ``.npz``: one float64 array named ``t`` and one per quantity (``np.load``).

The file is written to a temporary name beside the target and renamed into place,
so an interrupted run never leaves a half-written table under the final name.

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

import json
import math
import os
import re
import tempfile
import zipfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InvalidInputError, ShapeError

__all__ = ["TABLE_SUFFIXES", "write_table", "report_json"]

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


def _write_atomically(path: Path, write: Any) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


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
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        raise InvalidInputError(f"output file {str(path)!r}: expected a suffix {' or '.join(TABLE_SUFFIXES)}, "
                                f"got {path.suffix or 'none'!r}")
    times, cols = _check_columns(t, columns)
    if not path.parent.is_dir():
        raise InvalidInputError(f"output file {str(path)!r}: expected an existing directory, "
                                f"got {str(path.parent)!r}")
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
