"""Run a sweep: points in chunks on an executor, records written as they arrive, resumable.

Local processes by default (:class:`concurrent.futures.ProcessPoolExecutor`,
all cores); any :class:`concurrent.futures.Executor`; or a
``dask.distributed.Client`` (its :meth:`get_executor`), which runs the same
chunks on a Dask cluster.  Records go to JSON lines (``*.jsonl``) or to a
Parquet dataset (``*.parquet``: a folder with one file per chunk, each written
whole, through pyarrow), so an interrupted sweep resumes where it stopped.
"""

from __future__ import annotations

import json
import os
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from pathlib import Path

from interlock.sweep.record import evaluate_chunk
from interlock.sweep.spec import SweepError, SweepSpec, load_spec

__all__ = ["run", "read_records"]

FORMATS = (".jsonl", ".parquet")


def run(spec, output=None, executor=None, workers: int | None = None, resume: bool = False,
        progress=None) -> list[dict]:
    """Evaluate every point of ``spec``; return all records, sorted by ``index``.

    Parameters
    ----------
    spec : SweepSpec, path or dict
        See :mod:`interlock.sweep.spec`.
    output : path, optional
        ``*.jsonl`` or ``*.parquet``; records are written as each chunk finishes.  An existing
        output needs ``resume=True``.
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where chunks run; default: a process pool of ``workers`` processes (default all cores).
        A Dask client runs them on its cluster.
    resume : bool
        Keep the records already in ``output`` and evaluate only the missing points.
    progress : callable, optional
        Called with the number of points finished by each chunk; when resuming, first with the number
        of points kept from ``output`` (so that a progress bar over all points reaches its total).

    Examples
    --------
    >>> from concurrent.futures import ThreadPoolExecutor
    >>> spec = {"group": "p1", "verdicts": ["criterion_4_3"], "parameters": {"s": {"values": [0.0, 0.1]}},
    ...         "points": [{"edge": 0, "along": 0.5, "offset": "s"}]}
    >>> with ThreadPoolExecutor(1) as pool:
    ...     [r["verdicts"]["criterion_4_3"] for r in run(spec, executor=pool)]
    ['fails', 'holds']
    """
    spec = spec if isinstance(spec, SweepSpec) else load_spec(spec)
    writer = None if output is None else _writer(Path(output), spec, resume)
    done = {} if writer is None else {r["index"]: r for r in writer.records}
    todo = [(i, p) for i, p in enumerate(spec.points()) if i not in done]
    chunks = [todo[k:k + spec.chunk] for k in range(0, len(todo), spec.chunk)]
    if done and progress is not None:
        progress(len(done))
    owned = executor is None
    if owned:
        executor = ProcessPoolExecutor(max_workers=workers or os.cpu_count())
    elif hasattr(executor, "get_executor"):  # a dask.distributed.Client
        executor = executor.get_executor()
    elif not isinstance(executor, Executor):
        raise SweepError(f"executor must be a concurrent.futures.Executor or a dask.distributed.Client, "
                         f"got {type(executor).__name__}")
    try:
        futures = [executor.submit(evaluate_chunk, spec, chunk) for chunk in chunks]
        for future in as_completed(futures):
            records = future.result()
            for record in records:
                done[record["index"]] = record
            if writer is not None:
                writer.write(records)
            if progress is not None:
                progress(len(records))
    finally:
        if owned:
            executor.shutdown(cancel_futures=True)
    return [done[i] for i in sorted(done)]


def read_records(path) -> list[dict]:
    """The records of a sweep's output (``*.jsonl`` or ``*.parquet``), sorted by ``index``."""
    path = Path(path)
    if not path.exists():
        raise SweepError(f"no sweep output at {path}")
    records = _JsonLines.read(path) if path.suffix == ".jsonl" else _Parquet.read(path)
    return sorted(records, key=lambda r: r["index"])


def _writer(path: Path, spec: SweepSpec, resume: bool):
    if path.suffix not in FORMATS:
        raise SweepError(f"the output must end in {' or '.join(FORMATS)}, got {path.name}")
    if path.exists() and not resume:
        raise SweepError(f"{path} exists: resume it (--resume) or choose another output")
    return (_JsonLines if path.suffix == ".jsonl" else _Parquet)(path, spec)


class _JsonLines:
    """One JSON object per line, appended and flushed per chunk.  A line cut short by a killed run is dropped."""

    def __init__(self, path: Path, spec: SweepSpec):
        self.path = path
        self.records = []
        if path.exists():  # keep the whole lines, cut a partial last one before appending
            whole = path.read_bytes()
            whole = whole[:whole.rfind(b"\n") + 1]
            path.write_bytes(whole)
            self.records = [json.loads(line) for line in whole.decode().splitlines()]

    @staticmethod
    def read(path: Path) -> list[dict]:
        return [json.loads(line) for line in path.read_text().splitlines(keepends=True) if line.endswith("\n")]

    def write(self, records: list[dict]) -> None:
        with self.path.open("a") as stream:
            stream.writelines(json.dumps(r, default=float) + "\n" for r in records)
            stream.flush()
            os.fsync(stream.fileno())


class _Parquet:
    """A folder of ``part-<first index>.parquet`` files, one per chunk, each renamed into place when complete."""

    def __init__(self, path: Path, spec: SweepSpec):
        self.pa, self.pq = _pyarrow()
        self.path = path
        self.records = self.read(path) if path.exists() else []
        path.mkdir(parents=True, exist_ok=True)

    @staticmethod
    def read(path: Path) -> list[dict]:
        _, pq = _pyarrow()
        records = []
        for part in sorted(path.glob("part-*.parquet")):
            for row in pq.read_table(part).to_pylist():
                records.append({**row, **{key: json.loads(row[key]) for key in ("parameters", "verdicts",
                                                                                 "tolerances")}})
        return records

    def write(self, records: list[dict]) -> None:
        rows = [{**r, **{key: json.dumps(r[key], default=float) for key in ("parameters", "verdicts", "tolerances")}}
                for r in records]
        name = f"part-{min(r['index'] for r in records):08d}.parquet"
        partial = self.path / f".{name}.partial"
        self.pq.write_table(self.pa.Table.from_pylist(rows), partial)
        os.replace(partial, self.path / name)


def _pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise SweepError('Parquet output needs pyarrow: pip install "interlock[sweep]" (or write *.jsonl)') from None
    return pa, pq
