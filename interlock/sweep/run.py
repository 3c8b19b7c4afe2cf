"""Run a sweep: points in chunks on an executor, records written as they arrive, resumable.

Local processes by default (:class:`concurrent.futures.ProcessPoolExecutor`,
all cores, each ending when the sweep's process ends, even by ``kill -9``:
:func:`die_with_parent`); any :class:`concurrent.futures.Executor`; or a
``dask.distributed.Client`` (its :meth:`get_executor`), which runs the same
chunks on a Dask cluster.  Records go to JSON lines (``*.jsonl``) or to a
Parquet dataset (``*.parquet``: a folder with one file per chunk, each written
whole, through pyarrow), so an interrupted sweep resumes where it stopped.
Resuming touches only an output that is recognisably a sweep's (its header,
or an empty file or folder); anything else is refused and left as it was.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import sys
import threading
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, Executor, ProcessPoolExecutor, wait
from pathlib import Path

import interlock
from interlock.blocks.limits import memory_text
from interlock.errors import InterlockError
from interlock.files import atomic_write, unwritable, write_atomically
from interlock.sweep.record import evaluate_chunk
from interlock.sweep.spec import SweepError, SweepSpec, load_spec

__all__ = ["run", "read_records", "check_size", "die_with_parent", "SweepWarning", "MAX_POINTS", "HEADER_KEY", "AHEAD",
           "PARENT_POLL_SECONDS"]

FORMATS = (".jsonl", ".parquet")
#: The most points :func:`run` evaluates unless ``max_points`` says more: each point and its record take
#: about :data:`BYTES_PER_POINT` in memory, and a point takes 10-100 ms.
MAX_POINTS = 1_000_000
#: Memory per point (the point, its record and its future), measured on p4 sweeps: about 1 KB.
BYTES_PER_POINT = 1_000
#: Chunks handed to the executor ahead of their results: the points are made as chunks are submitted, so
#: a run holds at most this many chunks of points (and their records, unless kept), whatever the sweep's size.
AHEAD = 1024
#: The key of the first line of a JSON lines output (and of ``sweep.json`` in a Parquet folder): the spec's
#: name, :attr:`~interlock.sweep.spec.SweepSpec.fingerprint`, number of points and interlock's version.
HEADER_KEY = "sweep"
# The header of a Parquet output folder.
_PARQUET_HEADER = "sweep.json"
#: Where the parent-death signal is not available (not Linux), a worker looks this often whether the sweep's
#: process still lives, and ends when it does not.
PARENT_POLL_SECONDS = 0.5
#: The most bytes of an output's first line read to recognise it as a sweep's header (a header is ~200 bytes).
_HEADER_BYTES = 1 << 16
_PR_SET_PDEATHSIG = 1  # linux/prctl.h


class SweepWarning(UserWarning):
    """Something in a sweep's output that was skipped (a damaged record): the point is computed again."""


def run(spec, output=None, executor=None, workers: int | None = None, resume: bool = False,
        progress=None, max_points: int = MAX_POINTS, keep: bool = True) -> list[dict]:
    """Evaluate every point of ``spec``; return all records, sorted by ``index``.

    The points are made as they are handed out (:meth:`~interlock.sweep.spec.SweepSpec.iter_points`), at most
    :data:`AHEAD` chunks before their results, so a run starts at once and, with ``keep=False``, its memory
    does not grow with the sweep.

    Parameters
    ----------
    spec : SweepSpec, path or dict
        See :mod:`interlock.sweep.spec`.
    output : path, optional
        ``*.jsonl`` or ``*.parquet``; records are written as each chunk finishes, after a header with
        the spec's :attr:`~interlock.sweep.spec.SweepSpec.fingerprint`.  An existing output needs
        ``resume=True``.  The output is checked (its folder exists and is writable, it is not a folder)
        before any point is computed.
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Where chunks run; default: a process pool of ``workers`` processes (default all cores).
        A Dask client runs them on its cluster.
    resume : bool
        Keep the records already in ``output`` and evaluate only the missing points.  The output must
        be of the same spec: the same fingerprint, and every kept record at the parameters of the
        spec's point of its index.  A damaged record is skipped with a :class:`SweepWarning` and its
        point computed again.
    progress : callable, optional
        Called with the number of points finished by each chunk; when resuming, first with the number
        of points kept from ``output`` (so that a progress bar over all points reaches its total).
    max_points : int
        Refuse a spec with more points than this (default :data:`MAX_POINTS`), before making them.
    keep : bool
        Return every record (default).  False: return none (read them from ``output`` with
        :func:`read_records`), so memory stays bounded however many points the sweep has.

    Raises
    ------
    SweepError
        A bad spec, too many points, an output that cannot be written, or one that holds another
        spec's records.

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
    check_size(spec, max_points)
    if "stability" in spec.verdicts:  # a friction the solvers cannot represent would fail every point
        from interlock.verify.statics.equilibrium import friction_coefficient

        try:
            friction_coefficient(spec.mu)
        except InterlockError as error:
            raise SweepError(f"mu: {error}") from None
    if not isinstance(keep, bool):
        raise SweepError(f"keep must be True or False, got {keep!r}")
    writer = None if output is None else _writer(Path(output), resume)
    done = {} if writer is None else _kept(writer, spec)
    if writer is not None:
        writer.start(spec)
    skipped = set(done)
    if done and progress is not None:
        progress(len(done))
    if not keep:
        done = {}
    owned = executor is None
    if owned:
        executor = ProcessPoolExecutor(max_workers=workers or os.cpu_count(), initializer=die_with_parent,
                                       initargs=(os.getpid(),))
    elif hasattr(executor, "get_executor"):  # a dask.distributed.Client
        executor = executor.get_executor()
    elif not isinstance(executor, Executor):
        raise SweepError(f"executor must be a concurrent.futures.Executor or a dask.distributed.Client, "
                         f"got {type(executor).__name__}")

    def finish(finished) -> None:
        for future in finished:
            records = future.result()
            if keep:
                for record in records:
                    done[record["index"]] = record
            if writer is not None:
                writer.write(records)
            if progress is not None:
                progress(len(records))

    pending = set()
    try:
        for chunk in _chunks(spec, skipped):
            pending.add(executor.submit(evaluate_chunk, spec, chunk))
            if len(pending) >= AHEAD:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                finish(finished)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            finish(finished)
    finally:
        for future in pending:
            future.cancel()
        if owned:
            executor.shutdown(cancel_futures=True)
    return [done[i] for i in sorted(done)]


def die_with_parent(sweep: int | None = None) -> None:
    """End this process when the sweep's process ``sweep`` ends, however it ends (``kill -9`` too): the local
    workers' initializer.

    Where that process is this one's parent (the ``fork`` and ``spawn`` start methods) on Linux, the kernel
    sends this process SIGKILL when the parent dies (``prctl(PR_SET_PDEATHSIG)``, through ctypes); if the
    parent was already gone when that was asked for, the process ends at once.  Otherwise (another system,
    or workers started by a ``forkserver``) a daemon thread looks every :data:`PARENT_POLL_SECONDS` whether
    the sweep's process still exists and ends this one when it does not.  A worker so ended leaves nothing
    behind: its chunk's records were not written, and a resumed sweep computes them.
    """
    if sweep is None:
        sweep = os.getppid()
    if sys.platform.startswith("linux") and os.getppid() == sweep:
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            asked = libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0
        except (OSError, AttributeError):
            asked = False
        if asked:
            if os.getppid() != sweep:  # the parent died before the signal was asked for
                os._exit(1)
            return
    threading.Thread(target=_watch_sweep, args=(sweep,), name="interlock-sweep-watch", daemon=True).start()


def _watch_sweep(sweep: int) -> None:
    while _exists(sweep):
        time.sleep(PARENT_POLL_SECONDS)
    os._exit(1)


def _exists(pid: int) -> bool:
    """Whether process ``pid`` exists (and is no zombie, where /proc tells)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, another user's (the pid was reused)
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return True


def _chunks(spec: SweepSpec, skipped: set):
    """Lists of ``spec.chunk`` points ``(index, parameters)`` not in ``skipped``, made as they are asked for."""
    chunk = []
    for index, point in enumerate(spec.iter_points()):
        if index in skipped:
            continue
        chunk.append((index, point))
        if len(chunk) == spec.chunk:
            yield chunk
            chunk = []
    if chunk:
        yield chunk


def check_size(spec: SweepSpec, max_points: int = MAX_POINTS) -> int:
    """The number of points of ``spec``; a :class:`SweepError` above ``max_points``, before any is made.

    >>> from interlock.sweep.spec import load_spec
    >>> huge = load_spec({"group": "p1", "parameters": {"s": {"range": [0, 1], "steps": 100000},
    ...                   "t": {"range": [0, 1], "steps": 100000}}})
    >>> check_size(huge)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    interlock.sweep.spec.SweepError: the spec has 10,000,000,000 points (about 10 TB in memory), more than ...
    """
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 1:
        raise SweepError(f"max_points must be an integer >= 1, got {max_points!r}")
    size = spec.size
    if size > max_points:
        raise SweepError(f"the spec has {size:,} points (about {memory_text(size * BYTES_PER_POINT)} in memory), "
                         f"more than the limit {max_points:,}; use fewer steps or samples, or raise the limit "
                         "(--max-points)")
    return size


def read_records(path) -> list[dict]:
    """The records of a sweep's output (``*.jsonl`` or ``*.parquet``), sorted by ``index``.

    The header is left out; a damaged record is skipped with a :class:`SweepWarning`.
    """
    path = Path(path)
    if not path.exists():
        raise SweepError(f"no sweep output at {path}")
    records = (_JsonLines if path.suffix == ".jsonl" else _Parquet).read(path)[1]
    return sorted(records, key=lambda r: r["index"])


def _writer(path: Path, resume: bool):
    """The output's writer, after checking that it can be written: before any point is computed."""
    if path.suffix not in FORMATS:
        raise SweepError(f"the output must end in {' or '.join(FORMATS)}, got {path.name}")
    problem = unwritable(path, folder_output=path.suffix == ".parquet", hint="ending in .jsonl")
    if problem:
        raise SweepError(f"cannot write {path}: {problem}")
    if path.suffix == ".parquet" and path.exists() and not path.is_dir():
        raise SweepError(f"cannot write {path}: a Parquet output is a folder, and this is a file")
    if os.path.islink(path):  # resume the file it names (writing would replace the link by a file)
        try:
            target = path.resolve(strict=True)
        except (OSError, RuntimeError):  # missing, or a loop
            raise SweepError(f"cannot write {path}: it is a symbolic link to nothing that exists (or a loop); "
                             "give the file itself") from None
        if target.suffix != path.suffix:
            raise SweepError(f"cannot write {path}: it is a symbolic link to {target}, which does not end in "
                             f"{path.suffix}; give the file itself")
        path = target
    if path.exists() and not resume:
        raise SweepError(f"{path} exists: resume it (--resume) or choose another output")
    if path.exists():
        _recognise(path)
    try:
        return (_JsonLines if path.suffix == ".jsonl" else _Parquet)(path)
    except PermissionError as error:
        raise SweepError(f"cannot write {path}: {error.strerror or error}") from None


def _recognise(path: Path) -> None:
    """Refuse to resume an output that is not recognisably a sweep's: before it is read further or touched.

    A sweep's JSON lines start with its header line (``{"sweep": {"fingerprint": ...}}``), a Parquet output
    folder holds that header in ``sweep.json``; an empty file or folder holds nothing to lose.  Only the
    first line is read, so a large file of other data costs nothing to refuse.
    """
    if path.is_dir():
        if not any(path.iterdir()):
            return
        header_path = path / _PARQUET_HEADER
        try:
            with header_path.open("rb") as stream:
                header = _header_of(stream.read(_HEADER_BYTES))
        except OSError:
            header = None
        if header is None:
            raise SweepError(f"{path} is a folder that is not a sweep's Parquet output (no {_PARQUET_HEADER} with "
                             "a sweep header); resuming would write into it: choose another output")
        return
    try:
        with path.open("rb") as stream:
            first = stream.readline(_HEADER_BYTES)
    except OSError as error:
        raise SweepError(f"cannot read {path}: {error.strerror or error}") from None
    if not first or _header_of(first) is not None:
        return
    try:
        record = json.loads(first)
    except (ValueError, RecursionError):
        record = None
    if isinstance(record, dict) and isinstance(record.get("index"), int) and "status" in record:
        raise SweepError(f"{path} holds records without a spec fingerprint (an older interlock, or not a sweep); "
                         "resuming would replace them: choose another output")
    raise SweepError(f"{path} is not a sweep's output (its first line is no sweep header); resuming would "
                     "replace it: choose another output")


def _header_of(line: bytes) -> dict | None:
    """The sweep header a first line holds, or None: ``{"sweep": {..., "fingerprint": "<text>"}}``."""
    try:
        header = json.loads(line.decode("utf-8"))
    except (ValueError, RecursionError):  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        return None
    if isinstance(header, dict) and isinstance(header.get(HEADER_KEY), dict) \
            and isinstance(header[HEADER_KEY].get("fingerprint"), str):
        return header
    return None


def _header(spec: SweepSpec) -> dict:
    return {HEADER_KEY: {"name": spec.name, "fingerprint": spec.fingerprint, "points": spec.size,
                         "interlock": interlock.__version__}}


def _kept(writer, spec: SweepSpec) -> dict:
    """The records of an output that is resumed, after checking that they are this spec's."""
    header = writer.header
    if writer.records or header is not None:
        stored = (header or {}).get(HEADER_KEY, {})
        if stored.get("fingerprint") != spec.fingerprint:
            what = (f"the records of another spec ({stored.get('name', '?')}, fingerprint {stored.get('fingerprint')})"
                    if stored else "records without a spec fingerprint (an older interlock, or not a sweep)")
            raise SweepError(f"{writer.path} holds {what}, not of {spec.name} (fingerprint {spec.fingerprint}); "
                             "choose another output")
    records = sorted(writer.records, key=lambda r: r["index"] if isinstance(r["index"], int) else -1)
    points = enumerate(spec.iter_points())
    index, point = -1, None
    for record in records:
        wanted = record["index"]
        if isinstance(wanted, int) and 0 <= wanted < spec.size:
            while index < wanted:
                index, point = next(points)
        else:
            point = None
        if point is None or record.get("parameters") != point:
            raise SweepError(f"{writer.path} holds a record for point {wanted} at {record.get('parameters')}, but "
                             f"the spec's point {wanted} is {point if point is not None else 'none'}: "
                             "the output belongs to another spec; choose another output")
    return {r["index"]: r for r in writer.records}


def _record(line: str, where: str) -> dict | None:
    """One record of a JSON line; None (with a :class:`SweepWarning`) if it is damaged."""
    try:
        record = json.loads(line)
        if isinstance(record, dict) and isinstance(record.get("index"), int) and "status" in record:
            return record
    except json.JSONDecodeError:
        pass
    warnings.warn(f"{where} is not a sweep record; skipped, its point is computed again", SweepWarning,
                  stacklevel=3)
    return None


class _JsonLines:
    """A header line, then one JSON object per record, appended and flushed per chunk.

    A line cut short by a killed run, or damaged otherwise, is dropped (with a :class:`SweepWarning`)
    when the output is resumed: the file is rewritten whole without it, and its point is computed again.
    """

    def __init__(self, path: Path):
        self.path = path
        self.header, self.records = self.read(path) if path.exists() else (None, [])

    def start(self, spec: SweepSpec) -> None:
        """Write the header and the kept records, whole, before new records are appended."""
        lines = [self.header or _header(spec)] + self.records
        write_atomically(self.path, "".join(json.dumps(r, default=float) + "\n" for r in lines))

    @staticmethod
    def read(path: Path) -> tuple[dict | None, list[dict]]:
        try:
            lines = path.read_text(encoding="utf-8", errors="replace").splitlines(keepends=True)
        except OSError as error:
            raise SweepError(f"cannot read {path}: {error.strerror or error}") from None
        header = None
        if lines and lines[0].startswith(f'{{"{HEADER_KEY}"'):
            header = _header_of(lines.pop(0).encode("utf-8")) or {}  # {}: a damaged header
        if lines and not lines[-1].endswith("\n"):  # cut short by a killed run
            lines.pop()
        records = [_record(line, f"{path} line {k + 1 + (header is not None)}") for k, line in enumerate(lines)
                   if line.strip()]
        return header, [r for r in records if r is not None]

    def write(self, records: list[dict]) -> None:
        with self.path.open("a", encoding="utf-8") as stream:
            stream.writelines(json.dumps(r, default=float) + "\n" for r in records)
            stream.flush()
            os.fsync(stream.fileno())


class _Parquet:
    """A folder of ``part-<first index>.parquet`` files, one per chunk, each renamed into place when complete.

    ``sweep.json`` holds the header.  A part that cannot be read is renamed ``*.damaged`` (with a
    :class:`SweepWarning`) when the output is resumed, and its points are computed again.
    """

    def __init__(self, path: Path):
        self.pa, self.pq = _pyarrow()
        self.path = path
        self.damaged = []
        self.header, self.records = self.read(path, self.damaged) if path.exists() else (None, [])

    def start(self, spec: SweepSpec) -> None:
        """Write the header (a new output) and set damaged parts aside."""
        self.path.mkdir(exist_ok=True)
        for part in self.damaged:
            os.replace(part, part.with_name(part.name + ".damaged"))
        if self.header is None:
            write_atomically(self.path / _PARQUET_HEADER, json.dumps(_header(spec)))

    @staticmethod
    def read(path: Path, damaged: list | None = None) -> tuple[dict | None, list[dict]]:
        _, pq = _pyarrow()
        header_path = path / _PARQUET_HEADER
        try:
            header = json.loads(header_path.read_text()) if header_path.is_file() else None
        except (OSError, ValueError):
            header = {}
        records = []
        for part in sorted(path.glob("part-*.parquet")):
            try:
                rows = pq.read_table(part).to_pylist()
                records += [{**row, **{key: json.loads(row[key]) for key in ("parameters", "verdicts", "tolerances")}}
                            for row in rows]
            except Exception as error:  # pyarrow raises several types for a damaged file
                warnings.warn(f"{part} cannot be read ({type(error).__name__}); skipped, its points are computed "
                              "again", SweepWarning, stacklevel=3)
                if damaged is not None:
                    damaged.append(part)
        return header, records

    def write(self, records: list[dict]) -> None:
        rows = [{**r, **{key: json.dumps(r[key], default=float) for key in ("parameters", "verdicts", "tolerances")}}
                for r in records]
        name = f"part-{min(r['index'] for r in records):08d}.parquet"
        with atomic_write(self.path / name) as temporary:
            self.pq.write_table(self.pa.Table.from_pylist(rows), temporary)


def _pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise SweepError('Parquet output needs pyarrow: pip install "interlock[sweep]" (or write *.jsonl)') from None
    return pa, pq
