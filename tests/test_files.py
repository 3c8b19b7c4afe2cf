"""Files written whole or not at all: atomic_write, replace_folder, and exports and galleries killed mid-write."""

import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from interlock.formats import read
from interlock.blocks import Assembly, random_hexagon, rhomblock_assembly
from interlock.files import PARTIAL, atomic_write, replace_folder, unwritable, write_atomically
from interlock.formats import write as export
from interlock.gallery import build

# --- the helpers ------------------------------------------------------------------------------------------------


def test_an_error_inside_atomic_write_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(target) as temporary:
            temporary.write_text("half")
            raise RuntimeError("stopped")
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_atomic_write_keeps_the_suffix_and_gives_an_ordinary_file_mode(tmp_path):
    with atomic_write(tmp_path / "model.vtu") as temporary:
        assert temporary.suffix == ".vtu" and temporary.parent == tmp_path and PARTIAL in temporary.name
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "model.vtu").stat().st_mode & 0o777 == 0o666 & ~mask


def test_write_atomically_replaces_a_file(tmp_path):
    target = write_atomically(tmp_path / "b.bin", b"old")
    write_atomically(target, b"new")
    assert target.read_bytes() == b"new"


def test_replace_folder_swaps_in_the_new_folder_whole(tmp_path):
    (tmp_path / "g").mkdir()
    (tmp_path / "g" / "old.txt").write_text("old")
    new = tmp_path / "new"
    new.mkdir()
    (new / "new.txt").write_text("new")
    replace_folder(new, tmp_path / "g")
    assert [p.name for p in (tmp_path / "g").iterdir()] == ["new.txt"] and [p.name for p in tmp_path.iterdir()] == ["g"]


# --- killed exports -----------------------------------------------------------------------------------------------

#: A process that writes an export and stops, ready to be killed, once the new file is written but not yet in place.
_STOP_BEFORE_RENAME = """
import sys, time
import interlock.files as files
synced = files._sync_file
def written(path):
    synced(path)
    print("written", flush=True)
    time.sleep(120)
files._sync_file = written
from interlock.cli import main
main(["generate", "rhomblock", "--hexagon", "4", "4", "4", "--seed", "1", "-o", sys.argv[1]])
"""


def _hexagon(seed: int) -> Assembly:
    return rhomblock_assembly(random_hexagon(4, 4, 4, seed=seed), 0, frame="boundary")


def _kill_when(process: subprocess.Popen, line: str) -> None:
    """SIGKILL the process (and its group) once it prints ``line``."""
    for printed in process.stdout:
        if printed.strip() == line:
            break
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".glb", ".3mf", ".ply", ".vtu"])
def test_an_export_killed_after_writing_leaves_the_old_file(tmp_path, suffix):
    target = tmp_path / f"design{suffix}"
    old = export(_hexagon(0), target).read_bytes()
    process = subprocess.Popen([sys.executable, "-c", _STOP_BEFORE_RENAME, str(target)], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True, start_new_session=True)
    _kill_when(process, "written")
    assert target.read_bytes() == old
    assert len(read(target)) == 48


@pytest.mark.parametrize("delay", [0.2, 0.6, 1.0, 1.5, 2.5])
def test_an_export_killed_at_any_moment_is_the_old_file_or_the_whole_new_one(tmp_path, delay):
    target = tmp_path / "design.obj"
    old = export(_hexagon(0), target).read_bytes()
    new = _hexagon(1)
    process = subprocess.Popen([sys.executable, "-m", "interlock", "generate", "rhomblock", "--hexagon", "4", "4", "4",
                                "--seed", "1", "-o", str(target)], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
    time.sleep(delay)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    if target.read_bytes() != old:
        loaded = read(target)
        assert len(loaded) == len(new) and loaded.frame == new.frame


# --- killed galleries ----------------------------------------------------------------------------------------------

_GALLERY = """
import sys
from interlock.gallery import build
build(sys.argv[1], quick=True, seed=int(sys.argv[2]), names=sys.argv[3:], progress=lambda n: print(n, flush=True))
"""
ENTRIES = ["escher-p4", "escher-p1"]


def _assert_one_whole_gallery(folder, seed: int, entries=ENTRIES):
    """Every file of the folder is the manifest's, with its hash, and every record is of ``seed``."""
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["seed"] == seed and manifest["entries"] == entries
    on_disk = {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}
    assert on_disk == set(manifest["files"]) | {"manifest.json", "index.html"}
    for name, digest in manifest["files"].items():
        assert hashlib.sha256((folder / name).read_bytes()).hexdigest() == digest, name
    for name in entries:
        assert json.loads((folder / name / "record.json").read_text())["parameters"]["seed"] == seed
    assert f"seed {seed}." in (folder / "index.html").read_text()


def test_a_gallery_killed_mid_build_leaves_the_previous_gallery_whole(tmp_path):
    folder = tmp_path / "gallery"
    build(folder, quick=True, seed=0, names=ENTRIES)
    _assert_one_whole_gallery(folder, 0)
    process = subprocess.Popen([sys.executable, "-c", _GALLERY, str(folder), "1", *ENTRIES], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True, start_new_session=True)
    _kill_when(process, ENTRIES[0])  # one entry of seed 1 written, the other not
    _assert_one_whole_gallery(folder, 0)
    rebuilt = build(folder, quick=True, seed=1, names=ENTRIES)
    _assert_one_whole_gallery(folder, 1)
    assert rebuilt.index == folder / "index.html"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gallery"]  # the killed run's folder cleared away


def test_a_gallery_does_not_replace_a_folder_of_other_files(tmp_path):
    from interlock import GalleryError

    (tmp_path / "thesis.tex").write_text("mine")
    with pytest.raises(GalleryError, match="holds other files .* no manifest.json"):
        build(tmp_path, quick=True, names=["escher-p4"])
    assert (tmp_path / "thesis.tex").read_text() == "mine"


@pytest.mark.parametrize("name,reason", [
    ("missing/a.json", r"the folder .*missing does not exist; create it first"),
    ("plain.txt/a.json", r"the folder .*plain.txt is a file, not a folder"),
    ("sub", r"it is a folder; give a file name ending in \.json"),
])
def test_unwritable_says_why_before_any_work(tmp_path, name, reason):
    (tmp_path / "plain.txt").write_text("x")
    (tmp_path / "sub").mkdir()
    assert re.fullmatch(reason, unwritable(tmp_path / name, hint="ending in .json"), flags=re.IGNORECASE)
    assert unwritable(tmp_path / "a.json") is None
    assert unwritable(tmp_path / "sub", folder_output=True) is None  # outputs that are folders (Parquet sweeps)


@pytest.mark.parametrize("suffix", [".json", ".3dm"])
def test_assembly_files_refuse_a_missing_folder_with_the_shared_reason(tmp_path, suffix):
    # COMPAS JSON and Rhino writers give the reason the exporters give, as their own error (an InterlockError)
    if suffix == ".3dm":
        pytest.importorskip("rhino3dm")
    from interlock.blocks import presets
    from interlock.errors import InterlockError

    with pytest.raises(InterlockError, match="does not exist; create it first"):
        export(presets.block_on_pins(), tmp_path / "missing" / f"a{suffix}")
