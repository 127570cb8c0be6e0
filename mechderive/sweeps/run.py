"""Running a sweep's chunks: in this process, in a local pool of processes, or on a Dask cluster.

Whoever computes a chunk, this process writes it (:class:`~.table.Parts`) as it arrives, so a cluster's
workers need no shared disk, and the table is the same bit for bit whatever the backend and the number
of workers: chunk k's rows are a function of the sweep file and k (:mod:`.spec`), and the chunks are
assembled in order.

Faults: a local worker that dies (killed, out of memory) breaks the pool; the pool is rebuilt and the
chunks that had not come back are submitted again (each at most :data:`MAX_ATTEMPTS` times).  On Dask
the scheduler reruns the task of a lost worker itself.  An interrupted sweep (Ctrl-C, a crash) keeps
the chunks written; ``resume=True`` computes only the others.
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import json
import multiprocessing
import os
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..errors import InvalidInputError
from .evaluate import BASE_COLUMNS, evaluate_chunk
from .spec import Sweep, has_batch, parse_sweep
from .table import Parts, check_output, write_table

__all__ = ["SweepResult", "run_sweep", "columns_of", "MAX_ATTEMPTS"]

#: how often a chunk is submitted again after its worker died before the sweep gives up
MAX_ATTEMPTS = 3


@dataclass
class SweepResult:
    table: dict[str, np.ndarray]
    report: dict[str, Any]


def columns_of(sweep: Sweep) -> list[str]:
    """The table's columns in order: the swept keys, each quantity and its estimate, then the base columns."""
    return [a.name for a in sweep.axes] + [c for n in sweep.summary for c in (n, f"{n}_error")] + list(BASE_COLUMNS)


def units_of(sweep: Sweep) -> dict[str, str]:
    kinds = {q.name: q.unit for q in sweep.scene.model.summaries}
    units = {a.name: a.unit for a in sweep.axes}
    for n in sweep.summary:
        if kinds.get(n) and kinds[n] != "1":
            units[n] = units[f"{n}_error"] = kinds[n]
    return units


@functools.lru_cache(maxsize=4)
def _parsed(source_json: str, name: str) -> Sweep:
    return parse_sweep(json.loads(source_json), name=name)


def compute_chunk(source_json: str, name: str, k: int) -> tuple[int, dict[str, np.ndarray], float]:
    """(k, chunk k's table, seconds): the job a worker runs (the sweep re-read from its document, once
    per process)."""
    start = time.perf_counter()
    table = evaluate_chunk(_parsed(source_json, name), k)
    return k, table, time.perf_counter() - start


def _local(source: str, name: str, todo: list[int], workers: int, on_chunk: Callable) -> None:
    if workers <= 1:
        for k in todo:
            on_chunk(*compute_chunk(source, name, k))
        return
    # fork: the workers start with this process's warm caches (compiled functions, the parsed sweep)
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    attempts = {k: 0 for k in todo}
    pending = list(todo)
    while pending:
        written: set[int] = set()
        with cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(method)) as pool:
            futures = [pool.submit(compute_chunk, source, name, k) for k in pending]
            try:
                for fut in cf.as_completed(futures):
                    k, table, seconds = fut.result()
                    on_chunk(k, table, seconds)
                    written.add(k)
            except cf.process.BrokenProcessPool:
                pass  # a worker died: every chunk not written yet is submitted again to a new pool
        pending = [k for k in pending if k not in written]
        for k in pending:
            attempts[k] += 1
            if attempts[k] >= MAX_ATTEMPTS:
                raise InvalidInputError(f"sweep: chunk {k} lost its worker {MAX_ATTEMPTS} times (killed, or out of "
                                        f"memory?); the chunks finished are kept: rerun with --resume")


def _dask(source: str, name: str, todo: list[int], address: str, on_chunk: Callable) -> dict[str, Any]:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise InvalidInputError("sweep --dask needs dask.distributed: pip install 'mechderive[cluster]'") from None
    cluster = None
    if address.startswith("local:"):
        try:
            n = int(address.split(":", 1)[1])
        except ValueError:
            n = 0
        if n < 1:
            raise InvalidInputError(f"sweep --dask: expected local:N with N >= 1 workers, or a scheduler "
                                    f"address (tcp://host:8786), got {address!r}")
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    else:
        try:
            client = Client(address, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise InvalidInputError(f"sweep --dask: cannot reach the scheduler at {address!r} ({exc})") from None
    try:
        workers = len(client.scheduler_info().get("workers", {}))
        futures = [client.submit(compute_chunk, source, name, k, pure=False, retries=MAX_ATTEMPTS - 1,
                                 key=f"mechderive-sweep-{name}-{k}-{time.time_ns()}") for k in todo]
        for fut in as_completed(futures):
            on_chunk(*fut.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return {"dask_workers": workers}


def _warm(sweep: Sweep) -> None:
    """Derive and compile (or load) what the chunks need here, before the pool forks: each worker then
    starts warm instead of loading (or, on a cold cache, deriving) the same functions itself."""
    from .evaluate import _run_point, summarize_batch

    values = {name: col[:1] for name, col in sweep.chunk_values(0).items()}
    if has_batch(sweep.scene.model):
        summarize_batch(sweep, *sweep.batch_inputs(values))
    _run_point(sweep, {name: float(col[0]) for name, col in values.items()})


def run_sweep(sweep: Sweep, output: os.PathLike | str, *, workers: int | None = None, dask: str | None = None,
              resume: bool = False, progress: Callable[[int, int], None] | None = None,
              on_chunk: Callable[[int], None] | None = None) -> SweepResult:
    """Compute every chunk of ``sweep`` not yet written beside ``output``, then write the table to ``output``.

    ``workers``: local processes (default: every core); ``dask``: ``local:N`` or a scheduler's address
    (then ``workers`` is ignored).  ``progress(done_points, all_points)`` after each chunk; ``on_chunk(k)``
    after chunk k is written (tests use it to interrupt or kill mid-sweep).
    """
    output = check_output(output)
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidInputError(f"sweep --workers: expected an integer >= 1, got {workers!r}")
    parts = Parts(output.with_name(output.name + ".parts"), sweep.fingerprint, sweep.chunks, sweep.points)
    done = parts.start(resume=resume)
    todo = [k for k in range(sweep.chunks) if k not in set(done)]
    source = json.dumps(sweep.source)  # key order kept: the axes are in the order the file gives them
    start = time.perf_counter()
    counted = {"points": sum(len(sweep.chunk_rows(k)) for k in done), "seconds": 0.0}

    def arrived(k: int, table: dict[str, np.ndarray], seconds: float) -> None:
        parts.write(k, table)
        counted["points"] += len(table["status"])
        counted["seconds"] += seconds
        if progress is not None:
            progress(counted["points"], sweep.points)
        if on_chunk is not None:
            on_chunk(k)

    extra: dict[str, Any] = {}
    try:
        if todo and not dask and workers > 1 and len(todo) > 1:
            _warm(sweep)
        if dask:
            extra = _dask(source, sweep.name, todo, dask, arrived)
            backend = f"dask {dask}"
        else:
            _local(source, sweep.name, todo, min(workers, max(len(todo), 1)), arrived)
            backend = f"local, {workers} worker{'s' if workers != 1 else ''}"
    except BaseException:
        if not any(parts.chunk_path(k).exists() for k in range(sweep.chunks)):
            parts.remove()  # nothing to resume from (a cluster not reached, an error before the first chunk)
        raise
    wall = time.perf_counter() - start
    order = columns_of(sweep)
    table = parts.assemble(order)
    units = units_of(sweep)
    write_table(output, table, {"units": json.dumps(units), "fingerprint": sweep.fingerprint,
                                "sweep": json.dumps(sweep.source, sort_keys=True, default=repr)})
    parts.remove()
    status = table["status"]
    refused = int(sum(1 for s in status if str(s).startswith("refused")))
    by_point = int(sum(1 for p in table["path"] if p == "point"))
    computed = sum(len(sweep.chunk_rows(k)) for k in todo)
    report = {"points": sweep.points, "chunks": sweep.chunks, "resumed_chunks": len(done), "backend": backend,
              "ok": sweep.points - refused, "refused": refused, "batched": sweep.points - by_point,
              "one_by_one": by_point, "seconds": round(wall, 3),
              "points_per_second": round(computed / wall, 1) if wall > 0 else None, "output": str(output),
              "units": units, **extra}
    return SweepResult(table, report)
