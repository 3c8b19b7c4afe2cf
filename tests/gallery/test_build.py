"""The quick gallery builds, links only files that exist, and its verdicts are the paper's."""

import dataclasses
import json
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from interlock import GalleryError
from interlock.blocks import Assembly
from interlock.gallery import build, entries


@pytest.fixture(scope="module")
def gallery(tmp_path_factory):
    return build(tmp_path_factory.mktemp("gallery"), quick=True, seed=0)


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links = []

    def handle_starttag(self, tag, attrs):
        self.links += [value for name, value in attrs if name in ("href", "src")]


def test_every_linked_file_exists_and_nothing_comes_from_the_network(gallery):
    parser = _Links()
    parser.feed(gallery.index.read_text(encoding="utf-8"))
    assert parser.links
    for link in parser.links:
        if link.startswith("#") or link == "data:,":  # the table of contents; no favicon request
            continue
        assert not re.match(r"^[a-z]+://", link), link  # offline: no CDN, no remote picture
        assert (gallery.folder / link).is_file(), link
    names = {e.name for e in entries(quick=True)}
    assert {r.name for r in gallery.entries} == names


def test_each_entry_has_block_assembly_exploded_stl_a_coloured_glb_pictures_and_a_record(gallery):
    for result in gallery.entries:
        files = set(result.files)
        assert {"block.stl", "assembly.stl", "exploded.stl", "assembly.glb", "block.png", "assembly.png",
                "exploded.png", "record.json"} <= files, result.name
        record = json.loads((gallery.folder / result.files["record.json"]).read_text())
        assert record["name"] == result.name and record["files"]["assembly.stl"] == result.files["assembly.stl"]
        assert set(record["timings"]) >= {"generate", "finite_verdict", "export", "render"}


def test_every_linked_file_loads(gallery):
    import matplotlib.image

    for result in gallery.entries:
        for name, path in result.files.items():
            path = gallery.folder / path
            if name.endswith(".png"):
                assert matplotlib.image.imread(path).shape[2] in (3, 4)
            elif name.endswith(".json"):
                assert json.loads(path.read_text())["name"] == result.name
            else:
                expected = 1 if name.startswith("block.") else result.record["blocks"]
                assert len(Assembly.load(path)) == expected, (result.name, name)


def test_stl_files_reload_block_by_block_watertight_with_the_assembly_volumes(gallery):
    for result in gallery.entries:
        blocks = result.record["blocks"]
        for name in ("assembly.stl", "exploded.stl"):
            loaded = Assembly.load(gallery.folder / result.files[name])
            assert len(loaded) == blocks, (result.name, name)
            assert all(m.is_watertight for m in loaded.world_meshes()), (result.name, name)
        single = Assembly.load(gallery.folder / result.files["block.stl"])
        assert len(single) == 1 and single.mesh(0).is_watertight


def test_verdicts_are_the_papers(gallery):
    by_name = {r.name: r.record for r in gallery.entries}
    assert gallery.contradictions == ()
    # Escher blocks with every deformable edge deformed satisfy Criterion 4.3 and interlock (p1: Thm. 4.7)
    for name in ("escher-p4", "escher-p1"):
        assert by_name[name]["criterion_4_3"]["holds"] is True
        assert by_name[name]["periodic"]["status"] == "interlocked"
        assert by_name[name]["finite"]["interlocked"] is True
    assert by_name["escher-p1"]["periodic_translational"]["status"] == "interlocked"
    # Ex. 3.5: the cube grid slides, finite and infinite
    grid = by_name["ex3.5-cube-grid"]
    assert grid["finite"]["interlocked"] is False and grid["finite"]["motion_kind"] == "sliding"
    assert grid["beyond"]["interlocked"] is False and grid["beyond"]["finite_motion"]["shown"] is True
    assert by_name["escher-p4"]["beyond"] is None  # interlocked at first order: nothing beyond
    motion = [name for name in next(r for r in gallery.entries if r.name == "ex3.5-cube-grid").files
              if name.startswith("motion")]
    assert len(motion) == 4  # pictures of the cube sliding out
    assert grid["periodic"]["status"] == "not interlocked"
    # Thm. 4.9: RhomBlocks on a hexagon with the ring fixed, and on a periodic staircase
    assert by_name["rhomblock-hexagon-3x3x3-v0"]["finite"]["interlocked"] is True
    staircase = by_name["rhomblock-staircase-1-1-0-v1"]
    assert staircase["periodic"]["status"] == "interlocked" and staircase["finite"]["interlocked"] is True
    for record in by_name.values():
        assert all(claim["holds"] is True for claim in record["claims"]), record["name"]


def test_the_same_seed_gives_the_same_blocks(gallery, tmp_path):
    again = build(tmp_path, quick=True, seed=0, names=["escher-p4"])
    first = next(r for r in gallery.entries if r.name == "escher-p4")
    assert again.entries[0].record["parameters"] == first.record["parameters"]
    other = build(tmp_path / "other", quick=True, seed=1, names=["escher-p4"])
    assert other.entries[0].record["parameters"]["deformation"] != first.record["parameters"]["deformation"]
    volumes = [Assembly.load(g.folder / "escher-p4" / "block.stl").volumes for g in (again, other)]
    assert np.all(np.isfinite(np.concatenate(volumes)))


def test_unknown_entries_and_unwritable_folders_are_clear_errors(tmp_path):
    with pytest.raises(GalleryError, match="unknown gallery entries"):
        build(tmp_path, quick=True, names=["no-such-entry"])
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(GalleryError, match="cannot write the gallery .*inside"):
        build(blocker / "inside", quick=True)
    with pytest.raises(GalleryError, match="cannot write the gallery"):  # a missing folder above it is not made
        build(tmp_path / "missing" / "gallery", quick=True)
    assert not (tmp_path / "missing").exists()


def test_a_contradiction_is_reported(tmp_path, monkeypatch):
    from interlock.gallery import builder as module

    real = module.check

    def wrong(assembly, **kwargs):  # a broken verifier that finds the cube grid interlocked
        return dataclasses.replace(real(assembly, **kwargs), interlocked=True)

    monkeypatch.setattr(module, "check", wrong)
    g = build(tmp_path, quick=True, names=["ex3.5-cube-grid"])
    assert len(g.contradictions) == 1 and "Ex. 3.5" in g.contradictions[0]
    page = g.index.read_text()
    assert "CONTRADICTS" in page
