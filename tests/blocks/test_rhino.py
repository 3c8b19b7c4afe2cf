"""Rhino .3dm files: round trips of generated assemblies, files drawn by a person, and bad input."""

import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import trimesh

from interlock import wallpaper
from interlock.blocks import Assembly, cell_patch, escher_block, patch, periodic_cell, presets, random_hexagon
from interlock.blocks import rhomblock_assembly
from interlock.formats.rhino import read_3dm
from interlock.blocks.classes import block_classes
from interlock.formats.rhino import FRAME_LAYER, INFO_KEY, MARKER_KEY, RhinoError, write_3dm
from interlock.errors import InterlockError
from interlock.gallery import appearance

rhino3dm = pytest.importorskip("rhino3dm")


@pytest.fixture(scope="module")
def assemblies():
    """A p4 Escher patch of radius 2 cells and RhomBlocks on a 4x4x4 hexagon, both with their outer ring fixed, and
    a pg patch (mirror images)."""
    group = wallpaper.group("p4")
    p4 = patch(escher_block(group, {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}), 2 * math.sqrt(group.cell_area),
               frame="boundary")
    hexagon = rhomblock_assembly(random_hexagon(4, 4, 4, seed=3), variant=1, frame="boundary")
    pg = patch(escher_block(wallpaper.group("pg"), {0: [(0.25, 0.1)]}), 1.0, frame="boundary")
    assert p4.frame and hexagon.frame and pg.mirrored.any()
    return {"p4": p4, "rhomblock": hexagon, "pg": pg}


@pytest.mark.parametrize("name", ["p4", "rhomblock", "pg"])
def test_round_trip_keeps_blocks_volumes_names_classes_frame(tmp_path, assemblies, name):
    assembly = assemblies[name]
    back = read_3dm(write_3dm(assembly, tmp_path / f"{name}.3dm"))
    assert len(back) == len(assembly)
    for i in range(len(assembly)):  # double-precision vertices: every block bit for bit
        assert np.array_equal(back.mesh(i).vertices, assembly.mesh(i).vertices)
        assert np.array_equal(back.mesh(i).faces, assembly.mesh(i).faces)
    np.testing.assert_allclose(back.volumes, assembly.volumes, rtol=1e-12)
    assert back.labels == assembly.labels  # group elements and lozenges come back as such
    classes, kind = appearance.block_classes(assembly)
    back_classes, back_kind = appearance.block_classes(back)
    assert back_kind == kind and np.array_equal(back_classes, classes)
    assert back.frame == assembly.frame and back.info["frame_from"] == "file"
    assert {k: v for k, v in back.info.items() if k in assembly.info} == assembly.info
    assert back.info["format"] == "3dm"


def test_objects_are_named_and_layered_by_class_with_a_frame_layer(tmp_path, assemblies):
    assembly = assemblies["p4"]
    model = rhino3dm.File3dm.Read(str(write_3dm(assembly, tmp_path / "p4.3dm")))
    layers = [model.Layers[k].Name for k in range(len(model.Layers))]
    assert layers == ["coset_0", "coset_1", "coset_2", "coset_3", FRAME_LAYER]
    classes, _ = block_classes(assembly)
    for i in range(len(assembly)):
        item = model.Objects[i]
        strings = dict(item.Attributes.GetUserStrings())
        assert item.Attributes.Name == f"block_{i:04d} {assembly.labels[i]}"
        assert isinstance(item.Geometry, rhino3dm.Mesh) and item.Geometry.IsClosed
        layer = layers[item.Attributes.LayerIndex]
        assert layer == (FRAME_LAYER if i in assembly.frame else f"coset_{classes[i]}")
        assert strings["element"] == str(assembly.labels[i]) and strings["class"] == str(classes[i])
        assert strings["coset"] in {"x,y", "-y,x", "-x,-y", "y,-x"}
        assert strings["fixed"] == str(i in assembly.frame).lower()
    assert model.Strings[MARKER_KEY] == f"interlock blocks=69 fixed={len(assembly.frame)} classes=coset"
    assert model.Strings["group"] == "p4" and model.Strings["deformation"].startswith('{"0": [[0.25, 0.1]]')
    assert INFO_KEY in [model.Strings[k][0] for k in range(len(model.Strings))]


@pytest.mark.parametrize("build, kind, values", [
    (lambda: presets.cube_grid(), "type", {0}),
    (lambda: rhomblock_assembly(random_hexagon(2, 3, 2, seed=1)), "orientation", {0, 1, 2}),
    (lambda: patch(escher_block(wallpaper.group("p3"), {0: [(0.3, 0.1)]}), 1.0), "coset", {0, 1, 2}),
    (lambda: cell_patch(periodic_cell(escher_block(wallpaper.group("p4"), {0: [(0.25, 0.1)]})), 1), "coset",
     {0, 1, 2, 3}),
])
def test_classes_are_orientations_cosets_or_types(build, kind, values):
    assembly = build()
    classes, found = block_classes(assembly)
    assert appearance.block_classes is block_classes  # one set of rules for gallery colours and Rhino layers
    assert found == kind and set(classes.tolist()) == values and len(classes) == len(assembly)


def _box_brep(lo, hi):
    return rhino3dm.Brep.CreateFromBox(rhino3dm.Box(rhino3dm.BoundingBox(*lo, *hi)))


def _layer(model, name, parent=None):
    layer = rhino3dm.Layer()
    layer.Name = name
    if parent is not None:
        layer.ParentLayerId = model.Layers[parent].Id
    return model.Layers.Add(layer)


def _attributes(layer, name=""):
    attributes = rhino3dm.ObjectAttributes()
    attributes.LayerIndex = layer
    attributes.Name = name
    return attributes


def _mesh(mesh: trimesh.Trimesh, weld=True):
    """A Rhino mesh of a trimesh; unwelded: every triangle with its own three vertices, as Rhino meshes often are."""
    out = rhino3dm.Mesh()
    vertices, faces = (mesh.vertices, mesh.faces) if weld else (mesh.vertices[mesh.faces].reshape(-1, 3),
                                                              np.arange(3 * len(mesh.faces)).reshape(-1, 3))
    for x, y, z in vertices.tolist():
        out.Vertices.AddPoint3d(x, y, z)
    for a, b, c in faces.tolist():
        out.Faces.AddFace(a, b, c)
    return out


def test_a_file_drawn_by_a_person_loads_with_its_frame(tmp_path):
    """A row of unit boxes as a person draws it: polysurfaces on a layer, the two ends on a 'Frame' layer (one on a
    sublayer), one block an unwelded mesh and one an extrusion."""
    model = rhino3dm.File3dm()
    blocks, frame = _layer(model, "blocks"), _layer(model, "Frame")
    left = _layer(model, "left", parent=frame)
    model.Objects.AddBrep(_box_brep((0, 0, 0), (1, 1, 1)), _attributes(left, "left end"))
    model.Objects.AddBrep(_box_brep((1, 0, 0), (2, 1, 1)), _attributes(blocks, "middle"))
    model.Objects.AddMesh(_mesh(trimesh.creation.box(bounds=[[2, 0, 0], [3, 1, 1]]), weld=False),
                          _attributes(blocks))
    extrusion = rhino3dm.Extrusion.CreateBoxExtrusion(rhino3dm.Box(rhino3dm.BoundingBox(3, 0, 0, 4, 1, 2)), True)
    model.Objects.AddExtrusion(extrusion, _attributes(blocks, "tall"))
    model.Objects.AddBrep(_box_brep((4, 0, 0), (5, 1, 1)), _attributes(frame, "right end"))
    path = tmp_path / "drawn.3dm"
    assert model.Write(str(path), 7)
    row = read_3dm(path)
    assert len(row) == 5 and row.frame == (0, 4) and row.info["frame_from"] == "file"
    np.testing.assert_allclose(row.volumes, [1, 1, 1, 2, 1])
    assert row.labels[0] == "drawn.3dm:left end" and row.labels[2].startswith("drawn.3dm:")
    assert sorted(row.neighbours.edges) == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert read_3dm(path, frame=[2]).frame == (2,)
    assert read_3dm(path, frame_layer="blocks").frame == (1, 2, 3)


def test_a_curved_polysurface_with_render_meshes_is_read_through_them(tmp_path):
    """Rhino saves render meshes with polysurfaces; a sphere then reads as its render mesh.  rhino3dm frees a mesh
    given to ``BrepFace.SetMesh`` twice at exit, so the file is made in a process that ends without cleaning up."""
    path = tmp_path / "sphere.3dm"
    script = textwrap.dedent(f"""
        import os, rhino3dm, trimesh
        brep = rhino3dm.Brep.CreateFromSphere(rhino3dm.Sphere(rhino3dm.Point3d(0, 0, 0), 1.0))
        sphere, mesh = trimesh.creation.icosphere(2), rhino3dm.Mesh()
        for x, y, z in sphere.vertices.tolist():
            mesh.Vertices.AddPoint3d(x, y, z)
        for a, b, c in sphere.faces.tolist():
            mesh.Faces.AddFace(a, b, c)
        assert brep.Faces[0].SetMesh(mesh, rhino3dm.MeshType.Render)
        model = rhino3dm.File3dm()
        model.Objects.AddBrep(brep)
        assert model.Write({str(path)!r}, 7)
        os._exit(0)
    """)
    subprocess.run([sys.executable, "-c", script], check=True, timeout=120)
    ball = read_3dm(path)
    assert len(ball) == 1 and ball.volumes[0] == pytest.approx(trimesh.creation.icosphere(2).volume, rel=1e-12)


def test_a_file_without_a_frame_layer_has_no_frame(tmp_path):
    model = rhino3dm.File3dm()
    model.Objects.AddBrep(_box_brep((0, 0, 0), (1, 1, 1)))
    model.Write(str(tmp_path / "one.3dm"), 8)
    one = read_3dm(tmp_path / "one.3dm")
    assert len(one) == 1 and one.frame == () and one.info["frame_from"] == "none"


def _one_object_file(tmp_path, add):
    model = rhino3dm.File3dm()
    add(model)
    path = tmp_path / "bad.3dm"
    assert model.Write(str(path), 7)
    return path


def _open_box(model):
    box = trimesh.creation.box()
    model.Objects.AddMesh(_mesh(trimesh.Trimesh(box.vertices, box.faces[1:], process=False)), _attributes(0, "lid"))


def _curve(model):
    model.Objects.AddCurve(rhino3dm.LineCurve(rhino3dm.Point3d(0, 0, 0), rhino3dm.Point3d(1, 0, 0)),
                           _attributes(0, "axis"))


def _sphere(model):
    model.Objects.AddBrep(rhino3dm.Brep.CreateFromSphere(rhino3dm.Sphere(rhino3dm.Point3d(0, 0, 0), 1.0)))


def _open_polysurface(model):
    box = trimesh.creation.box()
    brep = rhino3dm.Brep.CreateFromMesh(_mesh(trimesh.Trimesh(box.vertices, box.faces[2:], process=False)), True)
    assert not brep.IsSolid
    model.Objects.AddBrep(brep, _attributes(0, "box without a lid"))


@pytest.mark.parametrize("add, message", [
    (_open_box, r"object 0 'lid' \(id .*, layer .*\) of bad.3dm is a Mesh that is not a closed solid \(\d+ edges"),
    (_curve, r"object 0 'axis' .* of bad.3dm is a LineCurve, not a closed solid"),
    (_sphere, r"object 0 .* polysurface with curved faces or edges and no render mesh; rhino3dm cannot mesh it "
              r"outside Rhino"),
    (_open_polysurface, r"object 0 'box without a lid' .* is an open polysurface, not a closed solid"),
    (lambda model: None, r"bad.3dm holds no objects"),
])
def test_bad_objects_give_one_line_errors_naming_them(tmp_path, add, message):
    path = _one_object_file(tmp_path, add)
    with pytest.raises(RhinoError, match=message) as caught:
        read_3dm(path)
    assert "\n" not in str(caught.value) and isinstance(caught.value, InterlockError)


@pytest.mark.parametrize("content, message", [(b"", "empty, not a Rhino .3dm file"),
                                              (b"solid cube\nendsolid cube\n", "not a Rhino .3dm file")])
def test_empty_file_and_not_a_3dm_give_one_line_errors(tmp_path, content, message):
    path = tmp_path / "x.3dm"
    path.write_bytes(content)
    with pytest.raises(RhinoError, match=message) as caught:
        read_3dm(path)
    assert "\n" not in str(caught.value)


def test_missing_file_raises(tmp_path):
    with pytest.raises(RhinoError, match="does not exist"):
        read_3dm(tmp_path / "nothing.3dm")


def test_a_file_missing_blocks_is_cut_short(tmp_path):
    path = write_3dm(presets.cube_grid(), tmp_path / "grid.3dm")
    model = rhino3dm.File3dm.Read(str(path))
    model.Objects.Delete(model.Objects[4].Attributes.Id)
    model.Write(str(path), 7)
    with pytest.raises(RhinoError, match="announces 9 blocks but holds 8"):
        read_3dm(path)


def test_write_replaces_atomically_and_checks_its_input(tmp_path):
    grid = presets.cube_grid()
    path = tmp_path / "grid.3dm"
    path.write_text("old")
    assert write_3dm(grid, path) == path
    assert len(read_3dm(path)) == 9 and sorted(p.name for p in tmp_path.iterdir()) == ["grid.3dm"]
    with pytest.raises(RhinoError, match="does not exist"):
        write_3dm(grid, tmp_path / "no" / "grid.3dm")
    with pytest.raises(RhinoError, match="needs an Assembly"):
        write_3dm(grid.mesh(0), path)
    with pytest.raises(RhinoError, match="one class per block"):
        write_3dm(grid, path, classes=([0, 1], "type"))


def test_given_classes_name_the_layers(tmp_path):
    grid = presets.cube_grid()
    model = rhino3dm.File3dm.Read(str(write_3dm(grid, tmp_path / "g.3dm", classes=(np.arange(9) % 2, "parity"))))
    assert [model.Layers[k].Name for k in range(len(model.Layers))] == ["parity_0", "parity_1", FRAME_LAYER]


def test_missing_rhino3dm_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "rhino3dm", None)  # import rhino3dm raises ImportError
    with pytest.raises(RhinoError, match=r'pip install "interlock\[rhino\]"'):
        write_3dm(presets.cube_grid(), tmp_path / "grid.3dm")
    with pytest.raises(RhinoError, match=r'pip install "interlock\[rhino\]"'):
        read_3dm(tmp_path / "grid.3dm")


def test_mirror_images_stay_outward(tmp_path, assemblies):
    back = read_3dm(write_3dm(assemblies["pg"], tmp_path / "pg.3dm"))
    assert isinstance(back, Assembly) and np.all(back.volumes > 0)
    assert all(mesh.is_winding_consistent and mesh.volume > 0 for mesh in back.world_meshes())
