"""interlock/files.py: the temporary files killed writes leave are removed by the next successful write (issue 36).

Only files named as ``atomic_write`` names its temporary files for that very target, and held by no running
write, are removed; a user's file that merely looks alike, or a write in progress, is left alone.
"""

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from interlock.files import PARTIAL, atomic_write, remove_stale_partials, write_atomically

# a process that starts writing ``target`` through atomic_write, says so, and waits (to be killed, or to go on)
WRITER = textwrap.dedent("""
    import sys, time
    from interlock.files import atomic_write
    with atomic_write(sys.argv[1]) as temporary:
        temporary.write_bytes(b"half of a file")
        print(temporary, flush=True)
        sys.stdin.readline()  # until told to go on (or killed)
        temporary.write_bytes(b"the whole file")
""")


def _start_writer(target: Path):
    writer = subprocess.Popen([sys.executable, "-c", WRITER, str(target)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    temporary = Path(writer.stdout.readline().strip())
    assert temporary.name.startswith(f".{target.name}.") and temporary.name.endswith(PARTIAL + target.suffix)
    return writer, temporary


def _killed_write(target: Path) -> Path:
    """The temporary file a write of ``target`` killed with SIGKILL leaves."""
    writer, temporary = _start_writer(target)
    os.kill(writer.pid, signal.SIGKILL)
    writer.wait()
    assert temporary.exists()
    return temporary


def test_a_killed_write_leaves_a_partial_file_that_the_next_write_removes(tmp_path):
    target = tmp_path / "results.json"
    target.write_text("old")
    stale = [_killed_write(target), _killed_write(target)]
    assert target.read_text() == "old"  # the kill left the old file whole
    write_atomically(target, "new")
    assert target.read_text() == "new"
    assert not any(p.exists() for p in stale)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]


def test_a_write_in_progress_keeps_its_temporary_file(tmp_path):
    target = tmp_path / "a.stl"
    writer, temporary = _start_writer(target)
    try:
        write_atomically(target, b"from another writer")
        assert temporary.exists()  # held by a running write: not stale
        assert remove_stale_partials(target) == []
    finally:
        writer.communicate("go on\n", timeout=60)
    assert writer.returncode == 0
    assert target.read_bytes() == b"the whole file" and not temporary.exists()


def test_only_the_temporary_files_of_the_same_target_are_removed(tmp_path):
    target = tmp_path / "a.obj"
    stale = _killed_write(target)
    other_target = _killed_write(tmp_path / "b.obj")  # another target's: its own next write removes it
    look_alikes = [tmp_path / name for name in (".a.obj.notes.partial.obj", ".a.obj.abcdefgh.partial.stl",
                                                 "a.obj.abcdefgh.partial.obj", ".a.obj.ABCDEFGH.partial.obj")]
    for path in look_alikes:
        path.write_text("a user's file")
    folder = tmp_path / ".a.obj.folder00.partial.obj"
    folder.mkdir()
    link = tmp_path / ".a.obj.link0000.partial.obj"
    link.symlink_to(tmp_path / "b.obj")
    write_atomically(target, "v 0 0 0\n")
    assert not stale.exists()
    assert other_target.exists() and folder.is_dir() and link.is_symlink()
    assert all(path.read_text() == "a user's file" for path in look_alikes)


def test_a_failed_write_removes_its_own_temporary_file_and_keeps_the_old_one(tmp_path):
    target = tmp_path / "a.glb"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with atomic_write(target) as temporary:
            temporary.write_bytes(b"half")
            raise RuntimeError("the exporter failed")
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.glb"]


@pytest.mark.parametrize("suffix", [".glb", ".obj", ".json", ".3mf", ".stl"])
def test_an_export_after_a_killed_export_leaves_no_partial_file(tmp_path, suffix):
    from interlock.blocks import presets
    from interlock import write

    target = tmp_path / f"grid{suffix}"
    stale = [_killed_write(target)] + ([_killed_write(target.with_suffix(".mtl"))] if suffix == ".obj" else [])
    write(presets.cube_grid(), target)
    assert not any(path.exists() for path in stale)
    assert not [p.name for p in tmp_path.iterdir() if PARTIAL in p.name]
