"""A sweep's table on disk: the chunks written as they finish (for ``--resume``) and the final file.

Chunks live in ``OUT.parts/`` beside the output: ``manifest.json`` (the sweep's fingerprint, the
number of chunks and points) and ``chunk-000000.npz``, one per finished chunk, each written to a
temporary name and renamed, so that a chunk file is either whole or absent — a sweep killed at any
moment resumes from the chunks it finished.  Floats are stored as float64 (exact), text as Unicode
arrays (no pickles: a parts directory is data, never code).

The final table is written by the output's suffix: ``.csv`` (UTF-8, a header row, floats by
``repr``: round-trip exact), ``.npz`` (one array per column) or ``.parquet`` (pyarrow, the
``parquet`` extra).
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
from pathlib import Path
from typing import Mapping

import numpy as np

from ..errors import InvalidInputError

__all__ = ["Parts", "write_table", "read_table", "SUFFIXES"]

SUFFIXES = (".csv", ".npz", ".parquet")


def _stored(col: np.ndarray) -> np.ndarray:
    return col if col.dtype.kind == "f" else np.asarray([str(x) for x in col], dtype=str)


def _loaded(col: np.ndarray) -> np.ndarray:
    return col if col.dtype.kind == "f" else col.astype(object)


class Parts:
    """The finished chunks of one sweep, in ``directory``."""

    def __init__(self, directory: Path, fingerprint: str, chunks: int, points: int) -> None:
        self.directory = Path(directory)
        self.manifest = {"fingerprint": fingerprint, "chunks": chunks, "points": points}

    def chunk_path(self, k: int) -> Path:
        return self.directory / f"chunk-{k:06d}.npz"

    def start(self, *, resume: bool) -> list[int]:
        """Prepare the directory; return the chunks already finished (only with ``resume``)."""
        manifest_path = self.directory / "manifest.json"
        if self.directory.exists():
            if not resume:
                raise InvalidInputError(
                    f"sweep: {str(self.directory)!r} holds the chunks of an earlier run of this output; pass "
                    f"--resume to continue it, or delete the directory to start over")
            try:
                old = json.loads(manifest_path.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                old = None
            if old != self.manifest:
                raise InvalidInputError(
                    f"sweep: {str(self.directory)!r} holds chunks of a different sweep (the file, its chunking or "
                    f"the package changed since); delete the directory to start over")
            return sorted(k for k in range(self.manifest["chunks"]) if self.chunk_path(k).exists())
        self.directory.mkdir(parents=True)
        manifest_path.write_text(json.dumps(self.manifest), encoding="utf-8")
        return []

    def write(self, k: int, table: Mapping[str, np.ndarray]) -> None:
        tmp = self.directory / f".chunk-{k:06d}.{os.getpid()}.tmp.npz"
        np.savez(tmp, **{name: _stored(np.asarray(col)) for name, col in table.items()})
        os.replace(tmp, self.chunk_path(k))

    def read(self, k: int) -> dict[str, np.ndarray]:
        with np.load(self.chunk_path(k), allow_pickle=False) as data:
            return {name: _loaded(data[name]) for name in data.files}

    def assemble(self, order: list[str]) -> dict[str, np.ndarray]:
        """All chunks in order, as one table (a column that is text in any chunk is text throughout)."""
        chunks = [self.read(k) for k in range(self.manifest["chunks"])]
        out = {}
        for name in order:
            cols = [c[name] for c in chunks]
            if any(c.dtype.kind != "f" for c in cols):
                cols = [c if c.dtype.kind != "f" else
                        np.array(["" if math.isnan(x) else repr(float(x)) for x in c], dtype=object) for c in cols]
            out[name] = np.concatenate(cols) if cols else np.zeros(0)
        return out

    def remove(self) -> None:
        shutil.rmtree(self.directory, ignore_errors=True)


def _check_suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise InvalidInputError(f"sweep output {str(path)!r}: expected a file ending in {', '.join(SUFFIXES)}, "
                                f"got {suffix or 'no suffix'!r}")
    return suffix


def check_output(path: os.PathLike | str) -> Path:
    """The output path, its suffix checked (before any point is computed); parquet needs pyarrow."""
    path = Path(path)
    _check_suffix(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInputError(f"sweep output {str(path)!r}: expected an existing directory, got "
                                f"{str(parent)!r}, which is not one")
    if path.suffix.lower() == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InvalidInputError("sweep output .parquet needs pyarrow: pip install 'mechderive[parquet]' "
                                    "(or write .csv or .npz)") from None
    return path


def write_table(path: os.PathLike | str, table: Mapping[str, np.ndarray], metadata: Mapping[str, str]) -> None:
    """Write ``table`` (column → array) to ``path`` by its suffix, with ``metadata`` (units, the sweep's
    fingerprint) in the file where the format has a place for it (parquet's schema, npz's ``__meta__``;
    CSV keeps units in the header: ``theta [rad]``)."""
    path = check_output(path)
    suffix = path.suffix.lower()
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{suffix}")
    units = json.loads(metadata.get("units", "{}"))
    if suffix == ".csv":
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            writer = csv.writer(fh)
            names = list(table)
            writer.writerow([f"{n} [{units[n]}]" if units.get(n) else n for n in names])
            cols = [table[n] for n in names]
            for i in range(len(cols[0]) if cols else 0):
                writer.writerow(["" if (c.dtype.kind == "f" and math.isnan(c[i])) else
                                 (repr(float(c[i])) if c.dtype.kind == "f" else str(c[i])) for c in cols])
    elif suffix == ".npz":
        with open(tmp, "wb") as fh:
            np.savez(fh, **{n: _stored(np.asarray(c)) for n, c in table.items()},
                     __meta__=np.asarray(json.dumps(dict(metadata))))
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        arrays = {n: pa.array(c if c.dtype.kind == "f" else [str(x) for x in c]) for n, c in table.items()}
        schema_meta = {k.encode(): v.encode() for k, v in metadata.items()}
        pq.write_table(pa.table(arrays).replace_schema_metadata(schema_meta), tmp)
    os.replace(tmp, path)


def read_table(path: os.PathLike | str) -> dict[str, np.ndarray]:
    """A table written by :func:`write_table` (column → array: float64, or object for text)."""
    path = Path(path)
    suffix = _check_suffix(path)
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as data:
            return {n: _loaded(data[n]) for n in data.files if n != "__meta__"}
    if suffix == ".parquet":
        import pyarrow.parquet as pq

        t = pq.read_table(path)
        return {n: (np.asarray(t[n].to_numpy(), dtype=float) if t.schema.field(n).type == "double"
                    else np.asarray(t[n].to_pylist(), dtype=object)) for n in t.column_names}
    with open(path, encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    header = [h.split(" [")[0] for h in rows[0]]
    out = {}
    for j, name in enumerate(header):
        cells = [r[j] for r in rows[1:]]
        try:
            out[name] = np.array([float(c) if c != "" else math.nan for c in cells], dtype=float)
        except ValueError:
            out[name] = np.array(cells, dtype=object)
    return out
