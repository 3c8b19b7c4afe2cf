"""Files written whole or not at all: a temporary file beside the target, synced, then renamed over it.

A reader (or a user after ``kill -9``) sees the old file or the complete new
one, never a part: :func:`atomic_write` for one file, :func:`replace_folder`
for a folder built in full beside the one it replaces.  The temporary file a
killed write leaves beside its target is removed by the next successful write
of that target.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_write", "write_atomically", "replace_folder", "remove_stale_partials", "unwritable", "json_float",
           "PARTIAL"]

#: The marker in the names of temporary files and folders (``.NAME.<random>.partial.SUFFIX``); a killed write
#: leaves such a file beside its target, never a damaged target.
PARTIAL = ".partial"


@contextlib.contextmanager
def atomic_write(path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write; on success it replaces ``path`` in one step.

    The temporary file is in the target's folder (so the rename stays on one
    file system) and ends in the target's suffix (for writers that choose the
    format by suffix).  When the ``with`` block ends without an error, the
    file is flushed to disk (``fsync``), renamed over ``path``
    (``os.replace``), and the folder is synced; on an error it is removed and
    ``path`` is untouched.

    Parameters
    ----------
    path : str or path-like
        The file to write, in an existing folder.

    Yields
    ------
    pathlib.Path
        The temporary file (exists, empty) to write.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_write(folder / "a.txt") as temporary:
    ...     _ = temporary.write_text("whole")
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('whole', ['a.txt'])
    """
    path = Path(path)
    descriptor, temporary = _held_temporary(path)
    try:
        try:
            os.chmod(temporary, 0o666 & ~_umask())  # as an ordinary new file, not mkstemp's 0600
            yield temporary
            _sync_file(temporary)
            os.replace(temporary, path)
        except BaseException:
            temporary.unlink(missing_ok=True)
            raise
    finally:
        os.close(descriptor)  # releases the lock that marked the temporary file as being written
    _sync_folder(path.parent)
    remove_stale_partials(path)


def remove_stale_partials(path) -> list[Path]:
    """Remove the temporary files that killed writes of ``path`` left beside it; return them.

    Only files named as :func:`atomic_write` names its temporary files for
    ``path`` (``.NAME.<8 random characters>.partial.SUFFIX``) are candidates,
    and of those only the ones no running write holds: each write holds an
    exclusive ``flock`` on its temporary file until it is renamed, and the
    system releases it when the writer dies, however it dies.  Where files
    cannot be locked (no ``fcntl``: Windows), a file another process has open
    cannot be removed either, and is left.  :func:`atomic_write` calls this
    after each successful write.

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / ".a.stl.k2x9_q0w.partial.stl").write_bytes(b"cut short by kill -9")
    >>> _ = (folder / ".a.stl.notes.partial.stl").write_text("not interlock's: kept")
    >>> _ = write_atomically(folder / "a.stl", b"whole")
    >>> sorted(p.name for p in folder.iterdir())
    ['.a.stl.notes.partial.stl', 'a.stl']
    """
    path = Path(path)
    pattern = re.compile(re.escape(f".{path.name}.") + r"[a-z0-9_]{8}" + re.escape(PARTIAL + path.suffix))
    removed = []
    try:
        names = [entry for entry in os.scandir(path.parent) if pattern.fullmatch(entry.name)]
    except OSError:
        return removed
    for entry in names:
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
            descriptor = os.open(entry.path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        except OSError:
            continue
        try:
            if _lock(descriptor, wait=False):  # no write holds it: its writer is gone
                os.unlink(entry.path)
                removed.append(Path(entry.path))
        except OSError:  # removed meanwhile, or not removable (open elsewhere on Windows)
            pass
        finally:
            os.close(descriptor)
    return removed


def _held_temporary(path: Path) -> tuple[int, Path]:
    """A new temporary file for ``path``, open and locked (so :func:`remove_stale_partials` leaves it)."""
    while True:
        descriptor, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=PARTIAL + path.suffix, dir=path.parent)
        _lock(descriptor, wait=True)
        if os.fstat(descriptor).st_nlink > 0:
            return descriptor, Path(name)
        os.close(descriptor)  # another write's cleaning removed it before the lock was taken: make another


def _lock(descriptor: int, wait: bool) -> bool:
    """An exclusive ``flock`` on an open file; False if another holds it (``wait=False``) or the file system
    cannot lock (some network mounts: then no file is taken for stale).  True without fcntl (Windows, where an
    open file cannot be removed, which protects it instead)."""
    try:
        import fcntl
    except ImportError:
        return True
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
    except OSError:  # BlockingIOError: held by a running write; ENOLCK and others: no locks here
        return False
    return True


def write_atomically(path, data: str | bytes) -> Path:
    """Write text (UTF-8) or bytes to ``path`` through :func:`atomic_write`; return the path.

    >>> import tempfile
    >>> write_atomically(Path(tempfile.mkdtemp()) / "b.txt", "x").read_text()
    'x'
    """
    path = Path(path)
    with atomic_write(path) as temporary:
        temporary.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
    return path


def replace_folder(built, target) -> None:
    """Put the complete folder ``built`` in the place of ``target`` (which may be missing), and remove the old one.

    ``built`` must be on the file system of ``target`` (a sibling, e.g. from
    :func:`tempfile.mkdtemp` with ``dir=target.parent``).  On Linux the two
    are exchanged in one step (``renameat2`` with ``RENAME_EXCHANGE``);
    elsewhere the old folder is renamed aside first, so that for a moment
    ``target`` is missing, but never a mixture of old and new files.

    >>> import tempfile
    >>> parent = Path(tempfile.mkdtemp())
    >>> (parent / "g").mkdir(); _ = (parent / "g" / "old.txt").write_text("old")
    >>> new = Path(tempfile.mkdtemp(dir=parent)); _ = (new / "new.txt").write_text("new")
    >>> replace_folder(new, parent / "g")
    >>> sorted(p.name for p in (parent / "g").iterdir()), sorted(p.name for p in parent.iterdir())
    (['new.txt'], ['g'])
    """
    built, target = Path(built), Path(target)
    _sync_folder(built)
    if not target.exists():
        os.rename(built, target)
    elif _exchange(built, target):
        shutil.rmtree(built)  # now the old folder
    else:
        old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=target.parent))
        os.rename(target, old / target.name)
        os.rename(built, target)
        shutil.rmtree(old)
    _sync_folder(target.parent)


def _exchange(first: Path, second: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2(..., RENAME_EXCHANGE)``); False where that is unavailable."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    at_cwd, exchange = -100, 2  # AT_FDCWD, RENAME_EXCHANGE
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return renameat2(at_cwd, os.fsencode(first), at_cwd, os.fsencode(second), exchange) == 0


def _sync_file(path: Path) -> None:
    with open(path, "rb+") as file:
        os.fsync(file.fileno())


def _sync_folder(folder: Path) -> None:
    """Make a rename in ``folder`` durable (where folders can be opened; not on Windows)."""
    try:
        descriptor = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def unwritable(path, folder_output: bool = False, hint: str = "") -> str | None:
    """Why a file cannot be written at ``path``, in words, or ``None`` if nothing stands in the way.

    Checked before any work is done, so that an export or a sweep fails at once with a message the caller
    prefixes by ``cannot write {path}: ``: the folder is missing, is a file or is not writable; ``path`` is a
    folder (unless ``folder_output``, for outputs that are folders; ``hint`` says what to give instead); or
    the file system refuses to look (a broken mount).  A name the file system refuses only when writing (too
    long) surfaces as the ``OSError`` of the write, which callers turn into their error.

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> unwritable(folder / "a.stl") is None, unwritable(folder / "missing" / "a.stl").endswith("create it first")
    (True, True)
    >>> unwritable(folder, hint="ending in .stl")
    'it is a folder; give a file name ending in .stl'
    """
    path = Path(path)
    folder = path.parent
    try:
        if not folder.is_dir():
            return f"the folder {folder} " + ("is a file, not a folder" if folder.exists()
                                              else "does not exist; create it first")
        if not os.access(folder, os.W_OK):
            return f"the folder {folder} is not writable"
        if path.is_dir() and not folder_output:
            return "it is a folder; give a file name" + (f" {hint}" if hint else "")
    except OSError as error:  # a name too long for the file system, a broken mount, ...
        return error.strerror or str(error)
    return None


def json_float(value: float) -> float | str:
    """``value`` itself where JSON can hold it, else its text (``"inf"``, ``"-inf"``, ``"nan"``).

    >>> json_float(0.5), json_float(float("inf"))
    (0.5, 'inf')
    """
    return value if math.isfinite(value) else str(value)
