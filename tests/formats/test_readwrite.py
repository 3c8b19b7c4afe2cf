"""interlock.read / interlock.write (interlock/formats/readwrite.py): every format round-trips blocks, frame, unit
and sizes; one entry point; targets that cannot be written say why."""

import json
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import trimesh

import interlock
from interlock.blocks import presets, random_hexagon, rhomblock_assembly
from interlock.formats import FORMATS, FormatError, LABELLED_FORMATS, read, write
from interlock.formats.units import METRES, with_unit

SUFFIXES = tuple(FORMATS)
#: STL stores float32 coordinates and glTF float32 vertex positions: sizes come back to their precision.
FLOAT32_FORMATS = (".stl", ".glb")


@pytest.fixture(scope="module")
def hexagon():
    return rhomblock_assembly(random_hexagon(2, 2, 2, seed=3), 0, frame="boundary")


def _same_sizes(back, original, factor=1.0, suffix=""):
    rtol = 1e-6 if suffix in FLOAT32_FORMATS else 1e-12
    np.testing.assert_allclose(back.volumes, original.volumes * factor ** 3, rtol=rtol)
    np.testing.assert_allclose(back.bounds, original.bounds * factor, rtol=rtol, atol=rtol * factor)


@pytest.mark.parametrize("unit", [None, "mm", "in", "m"])
@pytest.mark.parametrize("suffix", SUFFIXES)
def test_read_and_write_round_trip_every_format_with_its_unit(tmp_path, hexagon, suffix, unit):
    original = hexagon if unit is None else with_unit(hexagon, unit)
    back = interlock.read(interlock.write(original, tmp_path / f"h{suffix}"))
    assert len(back) == len(original) and back.frame == original.frame
    assert back.unit == unit and back.info["frame_from"] == "file"
    _same_sizes(back, original, suffix=suffix)
    if suffix in LABELLED_FORMATS:
        assert back.labels == original.labels
    else:
        assert back.labels[0] == f"h{suffix}:block_0000"


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_writing_in_another_unit_keeps_every_size(tmp_path, hexagon, suffix):
    metres = with_unit(hexagon, "m")
    back = read(write(metres, tmp_path / f"h{suffix}", unit="mm"))
    assert back.unit == "mm"
    _same_sizes(back, metres, 1000.0, suffix)
    again = read(tmp_path / f"h{suffix}", unit="m")  # read into metres: the same sizes again
    assert again.unit == "m"
    _same_sizes(again, metres, suffix=suffix)


def test_a_model_without_unit_is_declared_not_scaled(tmp_path):
    grid = presets.cube_grid()
    back = read(write(grid, tmp_path / "grid.3mf", unit="in"))
    assert back.unit == "in" and np.allclose(back.bounds, grid.bounds)


def test_gltf_holds_metres_and_3mf_the_assembly_unit(tmp_path):
    grid = with_unit(presets.cube_grid(), "mm")
    scene = trimesh.load_scene(write(grid, tmp_path / "grid.glb"))
    extent = scene.bounds[1] - scene.bounds[0]
    np.testing.assert_allclose(sorted(extent), [0.001, 0.003, 0.003], rtol=1e-6)  # 3 mm is 0.003 m in glTF
    with zipfile.ZipFile(write(grid, tmp_path / "grid.3mf")) as package:
        model = ET.fromstring(package.read("3D/3dmodel.model"))
    assert model.get("unit") == "millimeter"
    with zipfile.ZipFile(write(presets.cube_grid(), tmp_path / "plain.3mf")) as package:
        assert ET.fromstring(package.read("3D/3dmodel.model")).get("unit") == "meter"  # as glTF: 1 unit = 1 m


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".off", ".vtu", ".xdmf"])
def test_up_y_files_are_y_up_and_read_back_z_up(tmp_path, suffix):
    tall = trimesh.creation.box(bounds=[[0, 0, 0], [1, 2, 5]])  # 5 high along interlock's +Z
    one = interlock.blocks.Assembly.from_meshes([tall])
    path = write(one, tmp_path / f"tall{suffix}", up="y")
    raw = trimesh.load(path, force="mesh", process=False) if suffix in (".obj", ".stl", ".ply", ".off") else None
    if raw is not None:
        extent = raw.bounds[1] - raw.bounds[0]
        assert extent[1] == pytest.approx(5.0)  # +Y is up in the file
    back = read(path)
    np.testing.assert_allclose(back.bounds[0], one.bounds[0], atol=1e-6)


@pytest.mark.parametrize("suffix", [".glb", ".3mf", ".3dm", ".json"])
def test_an_up_axis_against_the_format_s_convention_is_refused(tmp_path, suffix):
    up = "z" if suffix == ".glb" else "y"
    with pytest.raises(FormatError, match=f"{suffix} files are .* up by their format's convention"):
        write(presets.cube_grid(), tmp_path / f"g{suffix}", up=up)


def test_an_unknown_unit_names_the_known_ones(tmp_path):
    with pytest.raises(FormatError, match="unknown unit 'furlong'; use one of um, mm, cm, m, in, ft"):
        write(presets.cube_grid(), tmp_path / "g.3mf", unit="furlong")


@pytest.mark.parametrize("target, message", [
    (".", r"cannot write \.: it is a folder; give a file name ending in one of \.stl"),
    ("/dev/null", r"cannot write /dev/null: it is not a regular file \(a device, pipe or socket\)"),
    ("grid.dae", r"unknown format \.dae; use one of \.stl"),
    ("grid", r"unknown format \(no suffix\)"),
])
def test_targets_that_cannot_be_written_say_what_is_wrong(tmp_path, monkeypatch, target, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(FormatError, match=message):
        write(presets.cube_grid(), target)


def test_the_top_level_offers_read_write_check_and_assembly(tmp_path):
    assert interlock.read is read and interlock.write is write
    assert interlock.check is interlock.verify.check and interlock.Assembly is interlock.blocks.Assembly
    grid = interlock.read(interlock.write(presets.cube_grid(), tmp_path / "grid.ply"))
    assert interlock.check(grid).interlocked is False


def test_meshio_plyfile_and_trimesh_read_our_ply(tmp_path, hexagon):
    meshio = pytest.importorskip("meshio")
    plyfile = pytest.importorskip("plyfile")
    path = write(hexagon, tmp_path / "h.ply")
    mesh = meshio.read(path)
    faces = sum(len(c.data) for c in mesh.cells)
    assert faces == sum(len(hexagon.meshes[t].faces) for t in hexagon.types)
    assert set(np.unique(mesh.point_data["block"])) == set(range(len(hexagon)))
    data = plyfile.PlyData.read(str(path))
    assert data["face"].count == faces and data["vertex"].count == len(mesh.points)
    np.testing.assert_array_equal(np.unique(data["vertex"]["block"]), np.arange(len(hexagon)))
    loaded = trimesh.load(path, process=False)
    assert len(loaded.faces) == faces


def test_glb_nodes_carry_block_label_class_and_frame_in_their_extras(tmp_path, hexagon):
    path = write(hexagon, tmp_path / "h.glb")
    data = path.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    tree = json.loads(data[20:20 + length])
    extras = {node["name"]: node["extras"] for node in tree["nodes"] if "extras" in node}
    assert len(extras) == len(hexagon)
    first = extras["block_0000 fixed" if 0 in hexagon.frame else "block_0000"]
    assert first["block"] == 0 and first["label_type"] == "lozenge" and first["fixed"] == (0 in hexagon.frame)
    assert {e["class_kind"] for e in extras.values()} == {"orientation"}
    assert {m["name"] for m in tree["materials"]} <= {"orientation_0", "orientation_1", "orientation_2"}


def test_3mf_items_carry_block_label_and_frame_metadata(tmp_path, hexagon):
    with zipfile.ZipFile(write(hexagon, tmp_path / "h.3mf")) as package:
        model = ET.fromstring(package.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    items = model.findall("m:build/m:item", ns)
    first = {m.get("name"): m.text for m in items[0].findall("m:metadatagroup/m:metadata", ns)}
    assert first["interlock:block"] == "0" and first["interlock:label_type"] == "lozenge"
    assert first["interlock:fixed"] == str(0 in hexagon.frame).lower()


@pytest.mark.parametrize("suffix", [".vtu", ".xdmf"])
def test_vtu_and_xdmf_classes_come_back(tmp_path, hexagon, suffix):
    back = read(write(hexagon, tmp_path / f"h{suffix}"))
    orientations = [label.orientation for label in hexagon.labels]
    assert back.info["classes"] == orientations and back.info["class_kind"] == "orientation"
    obj = read(write(back, tmp_path / "again.obj")).info  # and travel on: the OBJ's materials follow them
    assert obj["classes"] == orientations
    text = (tmp_path / "again.obj").read_text()
    assert "usemtl orientation_" in text


def test_material_names_are_one_per_class_in_every_format(tmp_path):
    p4 = presets.cube_grid()
    names = set()
    names |= {line.split()[1] for line in write(p4, tmp_path / "g.obj").with_suffix(".mtl").read_text().splitlines()
              if line.startswith("newmtl")}
    data = write(p4, tmp_path / "g.glb").read_bytes()
    names |= {m["name"] for m in json.loads(data[20:20 + int.from_bytes(data[12:16], "little")])["materials"]}
    with zipfile.ZipFile(write(p4, tmp_path / "g.3mf")) as package:
        names |= {b.get("name") for b in ET.fromstring(package.read("3D/3dmodel.model")).iter()
                  if b.tag.endswith("}base")}
    assert names == {"type_0"}


def test_units_table_is_in_metres():
    assert METRES["in"] == 0.0254 and METRES["mm"] == 1e-3


def test_off_is_read_by_meshio_and_checked_against_its_counts(tmp_path, hexagon):
    meshio = pytest.importorskip("meshio")
    path = write(hexagon, tmp_path / "h.off")
    assert sum(len(c.data) for c in meshio.read(path).cells) == sum(len(hexagon.meshes[t].faces) for t in hexagon.types)
    lines = path.read_text().splitlines()
    (tmp_path / "cut.off").write_text("\n".join(lines[:-5]) + "\n")
    with pytest.raises(FormatError, match="is cut short: its count line announces"):
        read(tmp_path / "cut.off")


def test_lib3mf_in_strict_mode_reads_our_3mf_without_warnings(tmp_path, hexagon):
    lib3mf = pytest.importorskip("lib3mf")
    path = write(with_unit(hexagon, "in"), tmp_path / "h.3mf")
    model = lib3mf.get_wrapper().CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    reader.ReadFromFile(str(path))
    assert reader.GetWarningCount() == 0
    items = model.GetBuildItems()
    assert items.MoveNext()
    group = items.GetCurrent().GetMetaDataGroup()
    assert {group.GetMetaData(k).GetName() for k in range(group.GetMetaDataCount())} >= {"block", "label", "fixed"}
