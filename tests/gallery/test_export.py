"""Exports: every format loads back into the same blocks; orientation, colours, cell data, exploded views, errors."""

import math
import os
import xml.etree.ElementTree as ET
import zipfile

import meshio
import numpy as np
import pytest
import trimesh

from interlock import wallpaper
from interlock.blocks import Assembly, AssemblyError, escher_block, patch, random_hexagon, rhomblock, rhomblock_assembly
from interlock.blocks.assembly import HEADER_MARKER, STL_RECORD
from interlock.blocks.meshfiles import STL_FIXED_BIT, STL_MAX_FRAMED
from interlock.errors import GalleryError
from interlock.gallery.appearance import PALETTE, block_classes, block_colours
from interlock.gallery.export import FORMATS, LABELLED_FORMATS, STL_MAX_BLOCKS, export


@pytest.fixture(scope="module")
def assemblies():
    """A p4 patch (rotations only), a pg patch (mirror images, a frame) and a RhomBlock patch (three orientations)."""
    p4 = patch(escher_block(wallpaper.group("p4"), {0: [(0.25, 0.1)]}), 1.0)
    pg = patch(escher_block(wallpaper.group("pg"), {0: [(0.25, 0.1)]}), 1.0, frame="boundary")
    rhomb = rhomblock_assembly(random_hexagon(2, 3, 2, seed=1), variant=1)
    assert pg.mirrored.any() and not pg.mirrored.all() and not p4.mirrored.any()
    assert set(block_classes(rhomb)[0].tolist()) == {0, 1, 2}
    return {"p4": p4, "pg": pg, "rhomblock": rhomb}


def _world_bounds(assembly):
    return np.array([assembly.bounds[:, 0].min(axis=0), assembly.bounds[:, 1].max(axis=0)])


def _spread(points):
    return points - points.mean(axis=0)


@pytest.mark.parametrize("suffix", list(FORMATS))
@pytest.mark.parametrize("name", ["p4", "pg", "rhomblock"])
def test_every_format_loads_back_the_same_blocks(tmp_path, assemblies, name, suffix):
    assembly = assemblies[name]
    back = Assembly.load(export(assembly, tmp_path / f"{name}{suffix}"))
    assert len(back) == len(assembly)
    np.testing.assert_allclose(np.sort(back.volumes), np.sort(assembly.volumes), rtol=1e-6)
    assert all(mesh.is_watertight for mesh in back.meshes)
    np.testing.assert_allclose(_world_bounds(back), _world_bounds(assembly), atol=1e-6 * assembly.scale)
    # block i comes back as block i
    np.testing.assert_allclose(back.centroids, assembly.centroids, atol=1e-6 * assembly.scale)


@pytest.fixture(scope="module")
def framed():
    """Assemblies with their natural frame, as ``interlock generate`` writes them: a p4 patch of radius 2 cells
    (69 blocks, 24 in the frame) and RhomBlocks on a random 3 x 3 x 3 hexagon (ring frame)."""
    group = wallpaper.group("p4")
    p4 = patch(escher_block(group, {0: [(0.25, 0.1)]}), 2 * math.sqrt(group.cell_area), frame="boundary")
    hexagon = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0), frame="boundary")
    assert (len(p4), len(p4.frame)) == (69, 24) and 0 < len(hexagon.frame) < len(hexagon)
    return {"p4": p4, "hexagon": hexagon}


@pytest.mark.parametrize("suffix", list(FORMATS))
@pytest.mark.parametrize("name", ["p4", "hexagon"])
def test_the_frame_round_trips_through_every_format(tmp_path, framed, name, suffix):
    assembly = framed[name]
    path = export(assembly, tmp_path / f"{name}{suffix}")
    back = Assembly.load(path)
    assert back.frame == assembly.frame and back.info["frame_from"] == "file"
    np.testing.assert_allclose(back.centroids, assembly.centroids, atol=1e-6 * assembly.scale)
    other = Assembly.load(path, frame=[0])
    assert other.frame == (0,) and other.info["frame_from"] == "argument"
    unfixed = Assembly.load(export(assembly.with_frame([]), tmp_path / f"free{suffix}"))
    assert unfixed.frame == () and unfixed.info["frame_from"] == "file"


def test_where_each_format_stores_the_frame(tmp_path, framed):
    p4 = framed["p4"]
    fixed = np.isin(np.arange(len(p4)), p4.frame)
    path = export(p4, tmp_path / "p4.stl")
    assert path.read_bytes()[:80].rstrip() == b"interlock blocks=69 fixed=24"
    records = np.fromfile(path, dtype=STL_RECORD, offset=84)
    blocks = records["block"] & (STL_FIXED_BIT - 1)
    np.testing.assert_array_equal(records["block"] >= STL_FIXED_BIT, fixed[blocks])
    obj = export(p4, tmp_path / "p4.obj").read_text().splitlines()
    assert obj[0] == f"# interlock blocks=69 fixed=24 triangles={len(records)}"
    assert [line for line in obj if line.startswith("o ")][44:46] == ["o block_0044", "o block_0045 fixed"]
    ply = trimesh.load(export(p4, tmp_path / "p4.ply"), process=False)
    raw = ply.metadata["_ply_raw"]["vertex"]["data"]  # block, fixed and colour per vertex (meshio reads them)
    np.testing.assert_array_equal(raw["fixed"].astype(bool), fixed[raw["block"]])
    scene = trimesh.load_scene(export(p4, tmp_path / "p4.glb"))
    assert scene.metadata["interlock"] == "interlock blocks=69 fixed=24"
    assert sorted(n for n in scene.graph.nodes_geometry if n.endswith(" fixed")) == [
        f"block_{i:04d} fixed" for i in p4.frame]
    with zipfile.ZipFile(export(p4, tmp_path / "p4.3mf")) as package:
        model = ET.fromstring(package.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    assert model.find("m:metadata", ns).text == "interlock blocks=69 fixed=24"
    assert model.find("m:metadata", ns).get("name") == "interlock:header"
    parts = [item.get("partnumber") for item in model.iterfind("m:build/m:item", ns)]
    assert [k for k, part in enumerate(parts) if part.endswith(" fixed")] == list(p4.frame)


def test_stl_beyond_the_frame_bit_keeps_block_indices_without_a_frame(tmp_path):
    n = STL_MAX_FRAMED + 1
    transforms = np.tile(np.eye(4), (n, 1, 1))
    transforms[:, 0, 3] = 2 * np.arange(n)
    assembly = Assembly([trimesh.creation.box()], np.zeros(n, dtype=int), transforms, frame=[0])
    path = export(assembly, tmp_path / "many.stl")
    assert path.read_bytes()[:80].rstrip() == f"interlock blocks={n}".encode()
    records = np.fromfile(path, dtype=STL_RECORD, offset=84)
    np.testing.assert_array_equal(records["block"], np.repeat(np.arange(n), 12))


def test_a_file_announcing_other_fixed_blocks_than_it_marks_is_an_error(tmp_path, framed):
    path = export(framed["p4"], tmp_path / "p4.stl")
    data = bytearray(path.read_bytes())
    data[:80] = b"interlock blocks=69 fixed=25".ljust(80)
    path.write_bytes(bytes(data))
    with pytest.raises(AssemblyError, match="announces 25 fixed blocks, its triangles mark 24"):
        Assembly.load(path)
    records = np.frombuffer(bytes(data[84:]), dtype=STL_RECORD).copy()
    records["block"][0] ^= STL_FIXED_BIT  # one triangle of block 0 says fixed, the others not
    path.write_bytes(bytes(data[:84]) + records.tobytes())
    with pytest.raises(AssemblyError, match="marks only some triangles of block 0 as fixed"):
        Assembly.load(path)


def test_mirror_image_blocks_are_written_outward(tmp_path, assemblies):
    pg = assemblies["pg"]
    records = np.fromfile(export(pg, tmp_path / "pg.stl"), dtype=STL_RECORD, offset=84)
    a, b, c = np.moveaxis(records["vertices"].astype(float), 1, 0)
    signed = np.bincount(records["block"] & (STL_FIXED_BIT - 1), np.einsum("ij,ij->i", a, np.cross(b, c)) / 6,
                         minlength=len(pg))
    np.testing.assert_allclose(signed, pg.volumes, rtol=1e-6)

    scene = trimesh.load_scene(export(pg, tmp_path / "pg.glb"))
    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[node]
        assert np.linalg.det(transform[:3, :3]) > 0 and scene.geometry[geometry].volume > 0


def test_exploded_spreads_the_centroids_by_the_factor_and_keeps_volumes(tmp_path, assemblies):
    p4 = assemblies["p4"]
    back = Assembly.load(export(p4, tmp_path / "p4.ply", exploded=0.5))
    np.testing.assert_allclose(_spread(back.centroids), 1.5 * _spread(p4.centroids), atol=1e-9)
    np.testing.assert_allclose(back.volumes, p4.volumes, rtol=1e-9)


def test_vtu_cell_data_carry_block_class_mirroring_and_frame(tmp_path, assemblies):
    pg = assemblies["pg"]
    mesh = meshio.read(export(pg, tmp_path / "pg.vtu"))
    data = {key: values[0] for key, values in mesh.cell_data.items()}
    block = data["block"]
    np.testing.assert_array_equal(np.unique(block), np.arange(len(pg)))
    np.testing.assert_array_equal(data["class"], block_classes(pg)[0][block])
    np.testing.assert_array_equal(data["mirrored"], pg.mirrored[block])
    np.testing.assert_array_equal(data["fixed"], np.isin(block, pg.frame))
    assert 0 < len(pg.frame) < len(pg)


def test_glb_of_rhomblocks_has_one_colour_per_orientation(tmp_path, assemblies):
    rhomb = assemblies["rhomblock"]
    scene = trimesh.load_scene(export(rhomb, tmp_path / "rhomb.glb"))
    colour = {node: tuple(scene.geometry[scene.graph[node][1]].visual.material.baseColorFactor.tolist())
              for node in scene.graph.nodes_geometry}
    orientations = [label.orientation for label in rhomb.labels]
    assert [colour[f"block_{i:04d}"] for i in range(len(rhomb))] == [tuple(PALETTE[k].tolist()) for k in orientations]
    assert len(set(colour.values())) == 3


def test_ply_and_3mf_colour_every_block_by_class(tmp_path, assemblies):
    rhomb = assemblies["rhomblock"]
    expected = block_colours(rhomb)
    ply = trimesh.load(export(rhomb, tmp_path / "rhomb.ply"), process=False)
    blocks = ply.metadata["_ply_raw"]["vertex"]["data"]["block"]
    np.testing.assert_array_equal(ply.visual.vertex_colors, expected[blocks])

    with zipfile.ZipFile(export(rhomb, tmp_path / "rhomb.3mf")) as package:
        model = ET.fromstring(package.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    bases = [base.get("displaycolor") for base in model.iterfind("m:resources/m:basematerials/m:base", ns)]
    pindex = {o.get("id"): int(o.get("pindex")) for o in model.iterfind("m:resources/m:object", ns)}
    items = list(model.iterfind("m:build/m:item", ns))
    assert [item.get("partnumber") for item in items] == [f"block_{i:04d}" for i in range(len(rhomb))]
    assert [bases[pindex[item.get("objectid")]] for item in items] == ["#" + bytes(rgba).hex().upper()
                                                                       for rgba in expected.tolist()]


def test_a_block_and_a_bare_mesh_export_too(tmp_path):
    block = escher_block(wallpaper.group("p4"), {0: [(0.25, 0.1)]})
    back = Assembly.load(export(block, tmp_path / "block.3mf"))
    assert len(back) == 1 and back.volumes[0] == pytest.approx(block.volume)
    back = Assembly.load(export(trimesh.creation.box(), tmp_path / "box.OBJ"))
    assert len(back) == 1 and back.volumes[0] == pytest.approx(1.0)


def test_4800_blocks_write_to_stl_with_their_block_indices(tmp_path):
    # RhomBlocks on a grid (a 4,800-lozenge tiling takes 2 s to draw); the time is benchmarks/gallery.py's
    mesh = rhomblock()
    transforms = np.tile(np.eye(4), (4800, 1, 1))
    transforms[:, :2, 3] = 2 * np.stack(np.divmod(np.arange(4800), 80), axis=1)
    assembly = Assembly([mesh], np.zeros(4800, dtype=int), transforms)
    path = export(assembly, tmp_path / "many.stl")
    assert path.read_bytes()[:80].startswith(HEADER_MARKER + b"4800")
    records = np.fromfile(path, dtype=STL_RECORD, offset=84)
    np.testing.assert_array_equal(np.bincount(records["block"]), np.full(4800, len(mesh.faces)))


def test_stl_beyond_the_attribute_range_carries_no_block_indices(tmp_path):
    n = STL_MAX_BLOCKS + 1
    transforms = np.tile(np.eye(4), (n, 1, 1))
    transforms[:, 0, 3] = 2 * np.arange(n)
    path = export(Assembly([trimesh.creation.box()], np.zeros(n, dtype=int), transforms), tmp_path / "huge.stl")
    records = np.fromfile(path, dtype=STL_RECORD, offset=84)
    assert not path.read_bytes()[:80].startswith(HEADER_MARKER)
    assert len(records) == 12 * n and not records["block"].any()


def test_loading_an_export_in_a_list_of_one_file_per_block_is_refused(tmp_path, assemblies):
    path = export(assemblies["p4"], tmp_path / "p4.stl")
    with pytest.raises(AssemblyError, match="holds 21 blocks.*load it on its own"):
        Assembly.load([path])


def test_a_cut_short_stl_export_is_a_clear_error(tmp_path, assemblies):
    path = export(assemblies["p4"], tmp_path / "p4.stl")
    path.write_bytes(path.read_bytes()[:-25])
    with pytest.raises(AssemblyError, match="cut short"):
        Assembly.load(path)


@pytest.mark.parametrize("target, obj, exploded, message", [
    ("blocks.dae", None, 0.0, r"unknown format \.dae; use one of \.stl, \.obj, \.ply, \.glb, \.3mf, \.vtu, \.xdmf"),
    ("blocks", None, 0.0, r"unknown format \(no suffix\)"),
    ("missing/blocks.stl", None, 0.0, r"the folder .*missing does not exist"),
    ("file.txt/blocks.stl", None, 0.0, r"the folder .*file\.txt is a file, not a folder"),
    ("folder.stl", None, 0.0, r"it is a folder"),
    ("x" * 300 + ".stl", None, 0.0, r"cannot write .*: File name too long"),
    ("blocks.stl", "a block", 0.0, r"expected a Block, an Assembly or a trimesh\.Trimesh, got str"),
    ("blocks.stl", Assembly([], [], np.zeros((0, 4, 4))), 0.0, r"nothing to write to blocks\.stl: .* no blocks"),
    ("blocks.stl", None, -1.0, r"exploded must be a finite number >= 0 .* got -1\.0"),
    ("blocks.stl", None, float("nan"), r"exploded must be a finite number >= 0 .* got nan"),
    ("blocks.stl", None, "wide", r"exploded must be a finite number >= 0 .* got 'wide'"),
])
def test_bad_exports_are_gallery_errors(tmp_path, assemblies, target, obj, exploded, message):
    (tmp_path / "file.txt").write_text("")
    (tmp_path / "folder.stl").mkdir()
    with pytest.raises(GalleryError, match=message):
        export(assemblies["p4"] if obj is None else obj, tmp_path / target, exploded=exploded)


def test_a_read_only_folder_is_a_gallery_error(tmp_path, assemblies, monkeypatch):
    folder = tmp_path / "read-only"
    folder.mkdir(mode=0o500)
    if os.access(folder, os.W_OK):  # root may write anywhere: let access() answer from the mode bits instead
        real = os.access
        monkeypatch.setattr(os, "access", lambda path, mode: real(path, mode) and not (
            mode & os.W_OK and not os.stat(path).st_mode & 0o200))
    with pytest.raises(GalleryError, match="read-only is not writable"):
        export(assemblies["p4"], folder / "blocks.stl")


@pytest.fixture(scope="module")
def labelled(assemblies):
    """Labels of every kind a generator makes: group elements (p4), lozenges (RhomBlocks), tuples of text and
    integers (the arch: ("support", "left"), ("voussoir", 3)), and text."""
    from interlock.blocks.arch import semicircular_arch

    arch = semicircular_arch(8)
    named = Assembly.from_meshes(list(arch.world_meshes()), frame=arch.frame,
                                 labels=[f"stone {k}" for k in range(len(arch))], info={"site": "yard", "mu": 0.6})
    return {"p4": assemblies["p4"], "rhomblock": assemblies["rhomblock"], "arch": arch, "named": named}


@pytest.mark.parametrize("suffix", LABELLED_FORMATS)
@pytest.mark.parametrize("name", ["p4", "rhomblock", "arch", "named"])
def test_labelled_formats_keep_the_labels_and_the_info(tmp_path, labelled, name, suffix):
    assembly = labelled[name]
    back = Assembly.load(export(assembly, tmp_path / f"{name}{suffix}"))
    assert back.labels == assembly.labels  # the objects, not their text: GroupElement, Lozenge, tuples
    assert [type(label) for label in back.labels] == [type(label) for label in assembly.labels]
    for key, value in assembly.info.items():
        assert back.info[key] == value, key


@pytest.mark.parametrize("suffix", [s for s in FORMATS if s not in LABELLED_FORMATS])
def test_other_formats_name_the_blocks_by_file_and_index(tmp_path, labelled, suffix):
    back = Assembly.load(export(labelled["arch"], tmp_path / f"arch{suffix}"))
    assert back.labels[:2] == (f"arch{suffix}:block_0000", f"arch{suffix}:block_0001")


def test_a_label_edited_by_hand_falls_back_to_the_text_or_the_object_name(tmp_path, labelled):
    arch = labelled["arch"]
    path = export(arch, tmp_path / "arch.obj")
    text = path.read_text().replace('# interlock label ["json","[\\"voussoir\\", 0]"]', '# interlock label ["json"',
                                    1)
    text = text.replace('# interlock label ["json","[\\"voussoir\\", 1]"]', '# interlock label ["int","one"]', 1)
    path.write_text(text)
    back = Assembly.load(path)
    assert back.labels[:2] == ("arch.obj:block_0000", "one") and back.labels[2:] == arch.labels[2:]


@pytest.mark.parametrize("suffix", [".obj", ".glb", ".3mf"])
def test_a_single_block_keeps_its_label_and_info(tmp_path, suffix):
    one = Assembly.from_meshes([trimesh.creation.box()], labels=[("solo", 1)], info={"note": "one block"})
    back = Assembly.load(export(one, tmp_path / f"one{suffix}"))
    assert back.labels == (("solo", 1),) and back.info["note"] == "one block"
