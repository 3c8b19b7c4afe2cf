"""Reading mesh files: OBJ without objects (Rhino), polygons, frames stored in names, cut-short files."""

import numpy as np
import pytest
import trimesh

from interlock.formats import read
from interlock.blocks import AssemblyError
from interlock.formats import read_mesh_file
from interlock.formats.common import FIXED_WORD, file_header

BUNNY_PARTS = 80

# the corners of a unit cube and its six faces as outward quadrilaterals
CUBE_CORNERS = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
CUBE_QUADS = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]


def _grid_obj(shared_corners=True, objects=()):
    """A 3 x 3 grid of touching unit cubes as one OBJ: per cube a run of 'v' lines, then its faces.

    With ``shared_corners``, a cube's faces share its 8 vertices (Rhino); without, every face has
    its own 4 vertices (so only the runs of 'v' lines tell the cubes apart).  ``objects``: names
    for 'o' lines, one per cube.
    """
    lines, count = ["# 9 cubes, no objects"], 0
    for k, (x, y) in enumerate((x, y) for x in range(3) for y in range(3)):
        if objects:
            lines.append(f"o {objects[k]}")
        corners = CUBE_CORNERS + [x, y, 0]
        if shared_corners:
            lines += [f"v {a:g} {b:g} {c:g}" for a, b, c in corners]
            lines += ["f " + " ".join(str(count + i + 1) for i in quad) for quad in CUBE_QUADS]
            count += 8
        else:
            lines += [f"v {a:g} {b:g} {c:g}" for quad in CUBE_QUADS for a, b, c in corners[quad]]
            lines += ["f " + " ".join(str(count + 4 * q + i + 1) for i in range(4)) for q in range(6)]
            count += 24
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("shared_corners", [True, False], ids=["by vertex index", "by v runs"])
def test_one_obj_of_touching_cubes_without_objects_gives_one_block_per_cube(tmp_path, shared_corners):
    path = tmp_path / "rhino.obj"
    path.write_text(_grid_obj(shared_corners))
    a = read(path)
    assert len(a) == 9 and a.labels[0] == "rhino.obj:body0"
    np.testing.assert_allclose(a.volumes, 1.0)
    np.testing.assert_allclose(a.centroids, [[x + 0.5, y + 0.5, 0.5] for x in range(3) for y in range(3)])
    assert a.frame == () and a.info["frame_from"] == "none"


def test_the_bunny_as_one_obj_without_objects(tmp_path, reference_data):
    folder = reference_data / "topolite" / "bunny"
    paths = [folder / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)]
    lines, offset = [], 0
    for path in paths:  # vertex runs, then faces with indices offset: one OBJ, as Rhino writes a selection
        text = path.read_text().splitlines()
        vertices = [line for line in text if line.startswith("v ")]
        lines += vertices
        lines += ["f " + " ".join(str(int(i) + offset) for i in line.split()[1:])
                  for line in text if line.startswith("f ")]
        offset += len(vertices)
    assert not any(line.startswith(("o ", "g ")) for line in lines)
    whole = tmp_path / "bunny.obj"
    whole.write_text("\n".join(lines) + "\n")
    one, apart = read(whole), read(paths)
    assert len(one) == BUNNY_PARTS
    np.testing.assert_allclose(one.volumes, apart.volumes, rtol=1e-12)
    np.testing.assert_allclose(one.centroids, apart.centroids, atol=1e-12)


def test_touching_bodies_in_one_plain_stl_or_ply_are_split_into_their_bodies(tmp_path):
    cubes = trimesh.util.concatenate([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(2)])
    for suffix in (".stl", ".ply"):
        path = tmp_path / f"row{suffix}"
        cubes.export(path)
        row = read(path)
        assert len(row) == 2 and sorted(row.centroids[:, 0].round(9)) == [0.5, 1.5]


def test_an_obj_soup_of_touching_cubes_in_one_run_is_split_into_the_cubes(tmp_path):
    # every face with its own vertices and all vertices first: only the closed surfaces tell the cubes apart
    text = _grid_obj(shared_corners=False).splitlines()
    path = tmp_path / "soup.obj"
    path.write_text("\n".join([line for line in text if line.startswith("v ")]
                              + [line for line in text if line.startswith("f ")]) + "\n")
    soup = read(path)
    assert len(soup) == 9 and np.allclose(soup.volumes, 1.0)


def test_obj_objects_named_fixed_are_the_frame(tmp_path):
    names = [f"cube {k}" + (f" {FIXED_WORD}" if k in (0, 8) else "") for k in range(9)]
    path = tmp_path / "named.obj"
    path.write_text(_grid_obj(objects=names))
    a = read(path)
    assert a.frame == (0, 8) and a.info["frame_from"] == "file"
    assert a.labels[0] == "named.obj:cube 0" and a.labels[8] == "named.obj:cube 8"
    other = read(path, frame=[4])
    assert other.frame == (4,) and other.info["frame_from"] == "argument"
    assert read(path, frame=[]).frame == ()


def test_obj_polygons_vertex_references_and_negative_indices(tmp_path):
    # an L-shaped prism: non-convex hexagons, 'v/vt/vn' references, negative (relative) indices
    outline = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    lines = [f"v {x} {y} {z}" for z in (0, 1) for x, y in outline] + ["vt 0 0", "vn 0 0 1"]
    lines += ["f " + " ".join(f"{k - 12}/1/1" for k in (5, 4, 3, 2, 1, 0)),
              "f " + " ".join(f"{k + 1}//1" for k in (6, 7, 8, 9, 10, 11))]
    lines += [f"f {k + 1} {(k + 1) % 6 + 1} {(k + 1) % 6 + 7} {k + 7}" for k in range(6)]
    path = tmp_path / "l.obj"
    path.write_text("\n".join(lines) + "\n")
    mesh = read(path).meshes[0]
    assert mesh.volume == pytest.approx(3.0)
    assert mesh.area == pytest.approx(2 * 3 + 8)  # a fan would overlap itself: more area


def test_an_obj_cut_short_is_an_error(tmp_path):
    path = tmp_path / "grid.obj"
    text = _grid_obj(objects=[f"block_{k:04d}" for k in range(9)])
    path.write_text(f"# {file_header(9, 0, triangles=9 * 12)}\n{text}")
    assert len(read(path)) == 9
    whole = path.read_text()
    path.write_text(whole[:whole.index("o block_0007")])  # two objects missing
    with pytest.raises(AssemblyError, match="cut short or damaged: it announces 9 blocks of 108 triangles in all, "
                                            "it holds 7 objects of 84 triangles"):
        read(path)
    path.write_text(whole[:-12])  # in the middle of the last object's faces, and of a line
    with pytest.raises(AssemblyError, match="cut short or damaged: it announces 9 blocks of 108 triangles in all, "
                                            "it holds 9 objects of 106 triangles"):
        read(path)
    path.write_text(f"# {file_header(9)}\n" + whole[whole.index("\n") + 1:whole.index("o block_0007")])
    with pytest.raises(AssemblyError, match="cut short or damaged: it announces 9 blocks, it holds 7"):
        read(path)


def test_a_malformed_obj_line_is_named(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text(_grid_obj().replace("v 0 0 1\n", "v 0 zero 1\n", 1))
    with pytest.raises(AssemblyError, match=r"bad.obj line 3: could not convert"):
        read(path)
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n")
    with pytest.raises(AssemblyError, match=r"vertex indices outside 1..3 \(e.g. 4\)"):
        read(path)


def test_read_mesh_file_gives_names_meshes_and_frame(tmp_path):
    path = tmp_path / "two.obj"
    path.write_text(_grid_obj(objects=[f"b{k}" + (" fixed" if k == 1 else "") for k in range(9)]))
    found = read_mesh_file(path)
    assert found.names[:2] == ("b0", "b1") and found.frame == (1,) and found.announced is None
    assert all(mesh.is_watertight for mesh in found.meshes)


@pytest.mark.parametrize("suffix", [".obj", ".stl"])
def test_one_block_with_t_junctions_in_a_file_of_its_own_stays_one_block(tmp_path, reference_data, suffix):
    part = reference_data / "topolite" / "cube" / "part_9.obj"  # polygons with vertices inside others' edges
    if suffix == ".stl":  # a plain triangle soup: the T-junctions are split before the bodies are told apart
        read_mesh_file(part).meshes[0].export(tmp_path / "part.stl")
        part = tmp_path / "part.stl"
    a = read(part)
    assert len(a) == 1 and a.volumes[0] == pytest.approx(7 * 0.2 ** 3, rel=1e-6)
