"""``interlock convert IN OUT``: every format to every other, blocks, volumes and frame kept; one-line errors."""

import numpy as np
import pytest

from interlock.formats import read
from interlock.blocks import rhomblock_assembly, random_hexagon
from interlock.cli import OUTPUT_SUFFIXES, main
from interlock.formats import write as export

pytest.importorskip("rhino3dm")


@pytest.fixture(scope="module")
def hexagon_file(tmp_path_factory):
    hexagon = rhomblock_assembly(random_hexagon(3, 3, 3, seed=1), frame="boundary")
    return hexagon, export(hexagon, tmp_path_factory.mktemp("convert") / "hexagon.stl")


@pytest.mark.parametrize("suffix", [s for s in OUTPUT_SUFFIXES if s != ".stl"])
def test_a_conversion_there_and_back_keeps_blocks_volumes_and_frame(hexagon_file, tmp_path, suffix, capsys):
    hexagon, source = hexagon_file
    there, back = tmp_path / f"hexagon{suffix}", tmp_path / "back.stl"
    assert main(["convert", str(source), str(there)]) == 0
    assert main(["convert", str(there), str(back)]) == 0
    assert "(from the file)" in capsys.readouterr().out
    for path in (there, back):
        loaded = read(path)
        assert len(loaded) == len(hexagon) and loaded.frame == hexagon.frame
        assert np.allclose(np.sort(loaded.volumes), np.sort(hexagon.volumes), rtol=1e-6)


def test_fixed_replaces_the_stored_frame(hexagon_file, tmp_path):
    _, source = hexagon_file
    assert main(["convert", str(source), str(tmp_path / "h.3dm"), "--fixed", "0-2"]) == 0
    assert read(tmp_path / "h.3dm").frame == (0, 1, 2)


@pytest.mark.parametrize("target, message", [("h.xyz", "unknown format .xyz"), ("SAME", "the same file")])
def test_bad_targets_are_one_line_errors(hexagon_file, tmp_path, capsys, target, message):
    _, source = hexagon_file
    target = str(source) if target == "SAME" else str(tmp_path / target)
    assert main(["convert", str(source), target]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1 and "Traceback" not in err


def test_a_file_that_is_not_a_3dm_is_a_one_line_error(tmp_path, capsys):
    (tmp_path / "bad.3dm").write_text("not a rhino file")
    assert main(["convert", str(tmp_path / "bad.3dm"), str(tmp_path / "out.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert "not a Rhino .3dm file" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("suffix", [".3dm", ".json"])
def test_slow_formats_report_progress_per_block(hexagon_file, tmp_path, suffix):
    hexagon, _ = hexagon_file
    written, seen = [], []
    path = export(hexagon, tmp_path / f"h{suffix}", progress=lambda done, total: written.append((done, total)))
    read(path, progress=lambda done, total: seen.append((done, total)))
    assert written == [(k, len(hexagon)) for k in range(len(hexagon))]
    assert seen == [(k, len(hexagon)) for k in range(len(hexagon))]


def test_labels_survive_every_labelled_format_and_the_others_say_they_drop_them(hexagon_file, tmp_path, capsys):
    hexagon, _ = hexagon_file
    source = export(hexagon, tmp_path / "hexagon.json")  # lozenge labels
    steps = (".obj", ".ply", ".glb", ".3mf", ".3dm")
    chain = [source] + [tmp_path / f"step{k}{suffix}" for k, suffix in enumerate(steps)]
    for there, back in zip(chain, chain[1:] + [tmp_path / "last.json"]):
        assert main(["convert", str(there), str(back)]) == 0
        assert "labels not kept" not in capsys.readouterr().out
    assert read(tmp_path / "last.json").labels == hexagon.labels
    assert main(["convert", str(source), str(tmp_path / "flat.stl")]) == 0
    assert "labels not kept (.stl stores none: use .obj, .ply, .off, .glb, .3mf, .3dm, .json)" in capsys.readouterr().out
