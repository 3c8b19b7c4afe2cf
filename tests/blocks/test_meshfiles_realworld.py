"""Reading mesh files as other programs write them: OBJ groups over welded vertices, STL variants, glTF +Y up."""

import os
import struct
import warnings

import numpy as np
import pytest
import trimesh

from interlock.formats import read
from interlock.blocks import AssemblyError, presets
from interlock.formats import read_mesh_file
from interlock.formats.common import GLTF_TO_Z_UP
from interlock.cli import main
from interlock.formats import write as export

# a 3 x 3 grid of touching unit cubes, block k at (k // 3, k % 3, 0)
GRID = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]


def _welded_obj(meshes, tag=None, names=None):
    """One OBJ over one pool of welded vertices (coincident corners are one vertex), as Rhino or 3ds Max write it.

    ``tag``: 'g' or 'o' to start each block with a group or object line named ``names[k]`` (``block{k}``).
    """
    points, index = np.unique(np.vstack([m.vertices for m in meshes]).round(9), axis=0, return_inverse=True)
    index, lines, offset = index.ravel(), [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in points], 0
    for k, mesh in enumerate(meshes):
        if tag:
            lines.append(f"{tag} {names[k] if names else f'block{k}'}")
        lines += ["f " + " ".join(str(index[offset + i] + 1) for i in face) for face in mesh.faces]
        offset += len(mesh.vertices)
    return "\n".join(lines) + "\n"


def _ascii_stl(meshes, names):
    """An ASCII STL with one ``solid`` per mesh."""
    text = []
    for mesh, name in zip(meshes, names):
        text.append(f"solid {name}")
        for triangle in mesh.triangles:
            text += [" facet normal 0 0 0", "  outer loop", *(f"   vertex {x:.9g} {y:.9g} {z:.9g}"
                                                               for x, y, z in triangle), "  endloop", " endfacet"]
        text.append(f"endsolid {name}")
    return "\n".join(text) + "\n"


def _binary_stl(meshes, count=None):
    """A plain binary STL (no interlock header) of the meshes; ``count`` overrides the header's triangle count."""
    triangles = np.vstack([m.triangles for m in meshes]).astype("<f4")
    records = np.zeros(len(triangles), dtype=[("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])
    records["vertices"] = triangles
    return b"plain".ljust(80) + struct.pack("<I", len(records) if count is None else count) + records.tobytes()


def _sorted_rows(points):
    return points[np.lexsort(points.T[::-1])]


# --- OBJ: groups over welded vertices ----------------------------------------------
def test_obj_g_groups_over_welded_vertices_are_the_blocks(tmp_path, capsys):
    path = tmp_path / "grid.obj"
    path.write_text(_welded_obj(GRID, "g", [f"Box{k:03d}" + (" fixed" if k != 4 else "") for k in range(9)]))
    found = read_mesh_file(path)
    assert found.names == tuple(f"Box{k:03d}" for k in range(9)) and found.frame == (0, 1, 2, 3, 5, 6, 7, 8)
    np.testing.assert_allclose([m.volume for m in found.meshes], 1.0)
    np.testing.assert_allclose([m.centroid for m in found.meshes], [m.centroid for m in GRID])
    assert main(["verify", str(path)]) == 1  # the middle cube slides: not interlocked (exit status 1)
    assert "blocks: 9, frame: [0, 1, 2, 3, 5, 6, 7, 8] (from the file)" in capsys.readouterr().out
    # groups that are not closed surfaces (one group per material of one cube) are not blocks
    cube = GRID[0]
    lines = [f"v {x:g} {y:g} {z:g}" for x, y, z in cube.vertices]
    lines += [("g top\n" if k == 0 else "g sides\n" if k == 4 else "") + "f " + " ".join(str(i + 1) for i in face)
              for k, face in enumerate(cube.faces)]
    path.write_text("\n".join(lines) + "\n")
    assert len(read_mesh_file(path).meshes) == 1


def test_welded_touching_cubes_without_objects_or_groups_are_their_cubes_not_one_block(tmp_path, capsys):
    # issue 38: welded cubes that share whole faces are still nine closed surfaces (blocks.bodies pairs the
    # half-edges around each shared edge); the grid with the ring fixed is Ex. 3.5: the middle cube slides up
    path = tmp_path / "welded.obj"
    path.write_text(_welded_obj(GRID))
    welded = read(path)
    assert len(welded) == 9 and np.allclose(welded.volumes, 1.0)
    middle = int(np.argmin(np.linalg.norm(welded.centroids[:, :2] - [1.5, 1.5], axis=1)))
    ring = ",".join(str(k) for k in range(9) if k != middle)
    assert main(["verify", str(path), "--fixed", ring]) == 1  # not interlocked
    assert capsys.readouterr().out.startswith("not infinitesimally interlocked")


def test_welded_cubes_that_touch_along_an_edge_only_are_told_apart_by_their_edges(tmp_path):
    diagonal = [GRID[0], GRID[4], GRID[8]]  # (0, 0), (1, 1), (2, 2): each shares one edge with the next
    path = tmp_path / "diagonal.obj"
    path.write_text(_welded_obj(diagonal))
    a = read(path)
    assert len(a) == 3
    np.testing.assert_allclose(a.volumes, 1.0)
    np.testing.assert_allclose(a.centroids, [[0.5, 0.5, 0.5], [1.5, 1.5, 0.5], [2.5, 2.5, 0.5]])


# --- STL variants ------------------------------------------------------------------
APART = [trimesh.creation.box(bounds=[[3 * x, 0, 0], [3 * x + 1, 1, 1]]) for x in range(2)]


@pytest.mark.parametrize("variant", ["upper case", "utf-8 names", "trailing blank lines"])
def test_ascii_stl_variants_that_exporters_write_are_read(tmp_path, variant):
    names = ["Würfel_0", "Würfel_1"] if variant == "utf-8 names" else ["part0", "part1"]
    text = _ascii_stl(APART, names)
    text = {"upper case": text.upper().replace("\n", "\r\n"), "trailing blank lines": text + "\n \t\n" * 150}.get(
        variant, text)
    path = tmp_path / "two.stl"
    path.write_bytes(text.encode("utf-8"))
    found = read_mesh_file(path)
    assert [name.lower() for name in found.names] == [name.lower() for name in names]
    np.testing.assert_allclose([m.volume for m in found.meshes], 1.0)


def test_binary_stl_padded_or_without_a_triangle_count_is_read_and_one_cut_short_is_refused(tmp_path):
    path = tmp_path / "two.stl"
    for data in (_binary_stl(APART) + b"\0\0", _binary_stl(APART, count=0)):
        path.write_bytes(data)
        found = read_mesh_file(path)
        assert found.names == ("body0", "body1")
        np.testing.assert_allclose([m.volume for m in found.meshes], 1.0)
    path.write_bytes(_binary_stl(APART) + bytes(50))  # a whole triangle more than announced: ambiguous
    with pytest.raises(AssemblyError, match=r"announces 24 triangles \(1,200 bytes after the header\), it holds "
                                            r"1,250 bytes; it is cut short or damaged"):
        read_mesh_file(path)
    path.write_bytes(_binary_stl(APART)[:-30])
    with pytest.raises(AssemblyError, match="is not a complete STL: .* it holds 1,170 bytes; it is cut short"):
        read_mesh_file(path)
    path.write_bytes(_ascii_stl(APART, ["a", "b"]).upper().rsplit("ENDSOLID", 1)[0].encode())
    with pytest.raises(AssemblyError, match="is cut short: an ASCII STL ends with 'endsolid', this one does not"):
        read_mesh_file(path)


# --- messages ----------------------------------------------------------------------
@pytest.mark.parametrize("name, content, message", [
    ("empty.obj", "", r"empty.obj is empty \(0 bytes\): it holds no mesh"),
    ("empty.glb", "", r"empty.glb is empty \(0 bytes\): it holds no mesh"),
    ("empty.off", "", r"empty.off is empty \(0 bytes\): it holds no mesh"),
    ("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n", r"holds no faces \('f' lines\), only 4 vertices"),
    ("nan.stl", _ascii_stl(APART[:1], ["x"]).replace("vertex 0 1 0", "vertex 0 1 NaN", 1),
     r"nan.stl line \d+: a vertex coordinate is not a finite number: 'vertex 0 1 NaN'"),
])
def test_a_file_without_a_mesh_or_with_nan_says_so(tmp_path, name, content, message, capsys):
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(AssemblyError, match=message):
        read_mesh_file(path)
    assert main(["verify", str(path)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "Error" not in error  # one line, no Python exception name


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_binary_stl_with_a_coordinate_not_finite_names_the_triangle(tmp_path, value):
    cube = APART[0].copy()
    cube.vertices[cube.faces[0, 1], 2] = value
    path = tmp_path / "bad.stl"
    path.write_bytes(_binary_stl([cube]))
    with pytest.raises(AssemblyError, match=r"bad.stl triangle 1: a vertex coordinate is not a finite number"):
        read_mesh_file(path)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes need POSIX")
def test_a_named_pipe_is_not_a_regular_file(tmp_path):
    path = tmp_path / "pipe.obj"
    os.mkfifo(path)
    with pytest.raises(AssemblyError, match=r"pipe.obj is not a regular file \(a pipe, socket or device\)"):
        read_mesh_file(path)


def test_a_flat_block_is_one_error_without_warnings(tmp_path):
    path = tmp_path / "flat.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(AssemblyError, match=r"block 0 \(flat.obj:body0\) encloses no volume"):
            read(path)
    assert [str(w.message) for w in caught] == []


# --- glTF: +Y up -------------------------------------------------------------------
def _lintel(up):
    """A post-and-lintel on a ground slab (block 0, fixed) as a GLB, +Z up or +Y up (as Blender writes glTF)."""
    boxes = [[[-2, -1, -1], [4, 2, 0]], [[0, 0, 0], [1, 1, 2]], [[2, 0, 0], [3, 1, 2]], [[0, 0, 2], [3, 1, 2.5]]]
    scene = trimesh.Scene()
    for i, bounds in enumerate(boxes):
        box = trimesh.creation.box(bounds=bounds)
        if up == "y":
            box.apply_transform(GLTF_TO_Z_UP.T)  # (x, y, z) -> (x, z, -y)
        scene.add_geometry(box, node_name=f"block{i}" + (" fixed" if i == 0 else ""), geom_name=f"g{i}")
    return scene.export(file_type="glb")


def test_gltf_is_read_y_up_so_gravity_points_down(tmp_path, capsys):
    path = tmp_path / "lintel.glb"
    path.write_bytes(_lintel("y"))
    found = read_mesh_file(path)
    assert found.frame == (0,)
    np.testing.assert_allclose(found.meshes[3].bounds, [[0, 0, 2], [3, 1, 2.5]])
    assert main(["stability", str(path), "--mu", "0.6"]) == 0
    assert capsys.readouterr().out.startswith("RBE stable")


@pytest.mark.parametrize("preset", ["cube_grid", "tetrahedra"])
def test_glb_export_is_y_up_and_reads_back_to_the_same_coordinates_names_and_frame(tmp_path, preset):
    a = getattr(presets, preset)()
    path = export(a, tmp_path / "a.glb")
    stored = trimesh.load_scene(path)
    world = np.vstack([a.mesh(i).vertices for i in range(len(a))])
    low, high = world.min(axis=0), world.max(axis=0)  # +Y up: the file's (x, y, z) is interlock's (x, z, -y)
    np.testing.assert_allclose(stored.bounds, [[low[0], low[2], -high[1]], [high[0], high[2], -low[1]]], atol=1e-6)
    for i in np.flatnonzero(~a.mirrored):  # each placement read back to the last bit
        node = f"block_{i:04d}" + (" fixed" if i in a.frame else "")
        np.testing.assert_array_equal(GLTF_TO_Z_UP @ stored.graph[node][0], a.transforms[i])
    back = read_mesh_file(path)
    assert back.names == tuple(f"block_{i:04d}" for i in range(len(a))) and back.frame == a.frame
    for i, mesh in enumerate(back.meshes):
        expected = _sorted_rows(a.mesh(i).vertices)
        if preset == "cube_grid":  # whole numbers: exact in the file's float32, so exact back
            np.testing.assert_array_equal(_sorted_rows(mesh.vertices), expected)
        else:  # the part's vertices are float32 in the file
            np.testing.assert_allclose(_sorted_rows(mesh.vertices), expected, atol=1e-6)


@pytest.mark.parametrize("suffix", [".stl", ".obj"])
def test_bodies_with_repeated_or_flipped_triangles_load_as_the_solids_they_bound(tmp_path, suffix):
    # a CAD export: two separate cubes in one plain file, one with a triangle written twice, the other with one
    # wound the other way round; they are two unit cubes, not "bodies that touch" nor "open surfaces"
    left, right = (trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 2))
    repeated = trimesh.Trimesh(left.vertices, np.vstack([left.faces, left.faces[:1]]), process=False)
    flipped = trimesh.Trimesh(right.vertices, np.vstack([right.faces[:-1], right.faces[-1:, ::-1]]), process=False)
    path = tmp_path / f"cad{suffix}"
    trimesh.util.concatenate([repeated, flipped]).export(path)
    loaded = read(path)
    assert len(loaded) == 2 and loaded.volumes.tolist() == pytest.approx([1.0, 1.0])
    assert sorted(len(mesh.faces) for mesh in loaded.meshes) == [12, 12]
