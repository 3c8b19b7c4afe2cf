"""Assembly: instancing, loading, validation, neighbourhood, boundary, periodic cells."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import interlock
from interlock import InterlockError, wallpaper
from interlock.blocks import Assembly, AssemblyError, escher_block, patch, periodic_cell
from interlock.blocks.repair import unmatched_edges


def _row_of_cubes(n=3):
    return [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(n)]


def test_from_meshes_and_neighbours():
    grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    a = Assembly.from_meshes(grid, frame=[0, 1, 2, 3, 5, 6, 7, 8])
    assert len(a) == 9 and a.frame == (0, 1, 2, 3, 5, 6, 7, 8)
    # bounding boxes of the middle cube touch all 8 others (faces, edges, corners)
    assert sorted(a.neighbours[4]) == [0, 1, 2, 3, 5, 6, 7, 8]
    assert a.neighbours.number_of_edges() == 20
    assert a.neighbours.nodes[4]["fixed"] is False and a.neighbours.nodes[0]["fixed"] is True
    np.testing.assert_allclose(a.centroids[4], [1.5, 1.5, 0.5])
    assert a.boundary() == (0, 1, 2, 3, 5, 6, 7, 8)  # all but the middle touch the hull
    assert a.scale == pytest.approx(np.sqrt(19))


def test_separated_blocks_are_not_neighbours():
    cubes = [trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), trimesh.creation.box(bounds=[[1.01, 0, 0], [2, 1, 1]])]
    assert Assembly.from_meshes(cubes).neighbours.number_of_edges() == 0


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_load_mesh_files(tmp_path, suffix):
    paths = []
    for k, mesh in enumerate(_row_of_cubes()):
        path = tmp_path / f"part_{k}{suffix}"
        mesh.export(path)
        paths.append(path)
    a = Assembly.load(paths, frame=[0])
    assert len(a) == 3 and a.labels == tuple(p.name for p in paths)
    np.testing.assert_allclose(a.volumes, 1.0)

    # one file with several separate bodies: one block per body
    apart = tmp_path / f"apart{suffix}"
    trimesh.util.concatenate([m.copy().apply_translation([k, 0, 0]) for k, m in enumerate(_row_of_cubes(2))]).export(apart)
    assert len(Assembly.load(apart)) == 2


def test_one_obj_file_with_objects_gives_blocks_in_file_order(tmp_path):
    scene = trimesh.Scene()
    for k, mesh in enumerate(_row_of_cubes(3)):
        scene.add_geometry(mesh, geom_name=f"part{k}")
    path = tmp_path / "parts.obj"
    scene.export(path)
    a = Assembly.load(path)
    assert a.labels == ("parts.obj:part0", "parts.obj:part1", "parts.obj:part2")
    np.testing.assert_allclose(a.centroids[:, 0], [0.5, 1.5, 2.5])


def test_touching_bodies_in_one_stl_are_split_into_their_closed_bodies(tmp_path):
    # issue 38: the half-edges around each shared edge pair up by orientation and side (blocks.bodies)
    path = tmp_path / "row.stl"
    trimesh.util.concatenate(_row_of_cubes(2)).export(path)
    row = interlock.read(path)
    assert len(row) == 2 and np.allclose(row.volumes, 1.0) and all(m.is_watertight for m in row.world_meshes())


def test_load_errors(tmp_path):
    with pytest.raises(AssemblyError, match="does not exist"):
        Assembly.load(tmp_path / "missing.obj")
    junk = tmp_path / "junk.stl"
    junk.write_text("not a mesh at all")
    with pytest.raises(AssemblyError, match="junk.stl"):
        Assembly.load([junk])
    with pytest.raises(AssemblyError, match="no mesh files"):
        Assembly.load([])


def test_bad_assemblies_are_clear_errors():
    cube = trimesh.creation.box()
    open_box = trimesh.Trimesh(cube.vertices, cube.faces[:-1])
    with pytest.raises(AssemblyError, match="block 0 is not a closed"):
        Assembly.from_meshes([open_box])
    with pytest.raises(AssemblyError, match="frame index 5 is out of range for 1 blocks"):
        Assembly.from_meshes([cube], frame=[5])
    with pytest.raises(AssemblyError, match="frame must list block indices"):
        Assembly.from_meshes([cube], frame=["a"])
    with pytest.raises(AssemblyError, match="rigid motions or mirror images"):
        Assembly([cube], [0], [np.diag([2.0, 1, 1, 1])])
    with pytest.raises(AssemblyError, match="1 block types but 2 transforms"):
        Assembly([cube], [0], [np.eye(4), np.eye(4)])
    with pytest.raises(AssemblyError, match="must index the 1 meshes"):
        Assembly([cube], [1], [np.eye(4)])
    with pytest.raises(AssemblyError, match="linearly independent"):
        Assembly([cube], [0], [np.eye(4)], lattice=[[1, 0, 0], [2, 0, 0]])
    with pytest.raises(AssemblyError, match="trimesh.Trimesh"):
        Assembly.from_meshes(["cube"])
    assert issubclass(AssemblyError, InterlockError)


def test_inward_meshes_are_turned_outward():
    cube = trimesh.creation.box()
    cube.invert()
    assert Assembly.from_meshes([cube]).meshes[0].volume == pytest.approx(1.0)


def test_patch_instances_one_mesh_and_marks_its_outer_ring():
    group = wallpaper.group("p4")
    block = escher_block(group, {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]})
    p = patch(block, 1.5)
    assert len(p.meshes) == 1 and p.transforms.shape == (len(p), 4, 4)
    assert p.labels[0].is_identity and set(p.labels) == set(group.elements_within(1.5))
    ring = set(p.boundary())
    inner = [i for i in range(len(p)) if i not in ring]
    assert inner and ring
    # an inner block has all its edge-neighbours in the patch; a ring block lacks one
    present = set(p.labels)
    steps = [s.element for s in group.side_pairings()]
    assert all(all(p.labels[i] @ s in present for s in steps) for i in inner)
    assert all(any(p.labels[i] @ s not in present for s in steps) for i in ring)
    assert patch(block, 1.5, frame="boundary").frame == tuple(sorted(ring))
    with pytest.raises(InterlockError, match="frame must be None, 'boundary'"):
        patch(block, 1.0, frame="outer")
    with pytest.raises(InterlockError, match="needs a Block"):
        patch(block.mesh, 1.0)


@pytest.mark.parametrize("name", ["p1", "p3", "pgg", "p6m"])
def test_periodic_cell_repeats_to_the_patch(name):
    group = wallpaper.group(name)
    block = escher_block(group, {})
    cell = periodic_cell(block)
    assert len(cell) == group.point_group_order
    np.testing.assert_allclose(cell.lattice[:, :2], group.lattice)
    assert not cell.lattice[:, 2].any()
    # every block of a patch is a cell block moved by a lattice translation
    p = patch(block, 1.0)
    for g, transform in zip(p.labels, p.transforms):
        coset, shift = group.decompose(g)
        expected = cell.transforms[coset].copy()
        expected[:3, 3] += np.asarray(shift) @ cell.lattice
        np.testing.assert_allclose(transform, expected, atol=1e-12)


def test_world_meshes_keep_volume_and_orientation_when_mirrored():
    block = escher_block(wallpaper.group("pg"), {0: [(0.25, 0.1)]})
    p = patch(block, 1.0)
    assert p.mirrored.any() and not p.mirrored.all()
    for i in np.flatnonzero(p.mirrored):
        m = p.mesh(i)
        assert m.is_winding_consistent and m.volume == pytest.approx(block.volume)
    with pytest.raises(AssemblyError, match="out of range"):
        p.mesh(len(p))


CUBE_PARTS = 9
#: The TopoLite cube is a 4 x 4 x 4 voxel puzzle of voxels of side 0.2: 64 * 0.2**3 = 0.512.
CUBE_VOXEL = 0.2


def test_topolite_cube_parts_with_t_junctions_load_closed(reference_data):
    folder = reference_data / "topolite" / "cube"
    a = Assembly.load([folder / f"part_{k}.obj" for k in range(1, CUBE_PARTS + 1)])
    assert len(a) == CUBE_PARTS and a.info["frame_from"] == "none"
    assert all(len(unmatched_edges(mesh.faces)) == 0 for mesh in a.meshes)
    assert (a.volumes > 0).all()
    voxels = a.volumes / CUBE_VOXEL ** 3
    np.testing.assert_allclose(voxels, voxels.round(), atol=1e-9)
    assert voxels.round().tolist() == [7] * 7 + [8, 7] and voxels.sum() == pytest.approx(4 ** 3)
    # their polygons are non-convex: the triangles cover each one exactly (a fan would add area)
    assert sum(mesh.area for mesh in a.meshes) == pytest.approx(sum(_outline_areas(folder / f"part_{k}.obj")
                                                                    for k in range(1, CUBE_PARTS + 1)))


def _outline_areas(path):
    """Sum of the areas of an OBJ file's polygons (Newell's formula: exact for planar polygons)."""
    lines = path.read_text().splitlines()
    vertices = np.array([line.split()[1:4] for line in lines if line.startswith("v ")], dtype=float)
    total = 0.0
    for line in lines:
        if line.startswith("f "):
            p = vertices[[int(token.split("/")[0]) - 1 for token in line.split()[1:]]]
            total += np.linalg.norm(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)) / 2
    return total


def _cube_with_a_t_junction():
    """A unit cube, one bottom triangle cut in two at the middle of its side: a T-junction with the side face."""
    cube = trimesh.creation.box()
    vertices = cube.vertices
    for k, face in enumerate(cube.faces):
        for shift in range(3):
            u, v, w = np.roll(face, -shift)
            bottom = (vertices[[u, v, w], 2] == -0.5).all()
            if bottom and np.count_nonzero(vertices[u] != vertices[v]) == 1:  # a side of the square, not its diagonal
                cut = np.vstack([np.delete(cube.faces, k, axis=0), [[u, 8, w], [8, v, w]]])
                return np.vstack([vertices, (vertices[u] + vertices[v]) / 2]), cut


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2 ** 32 - 1))
def test_triangles_wound_the_other_way_or_repeated_give_the_same_solid(seed):
    # what CAD and scanning tools write: some triangles flipped, some twice; the solid is the same
    rng = np.random.default_rng(seed)
    mesh = trimesh.creation.icosphere(subdivisions=1)
    faces = mesh.faces.copy()
    flipped = rng.random(len(faces)) < 0.3
    faces[flipped] = faces[flipped][:, ::-1]
    faces = np.vstack([faces, faces[rng.choice(len(faces), size=3)]])
    block = Assembly.from_meshes([trimesh.Trimesh(mesh.vertices, rng.permutation(faces), process=False)])
    assert block.volumes[0] == pytest.approx(mesh.volume, rel=1e-12)
    assert len(block.meshes[0].faces) == len(mesh.faces) and not len(unmatched_edges(block.meshes[0].faces))


def test_a_flipped_triangle_beside_a_hole_is_still_refused():
    cube = trimesh.creation.box()
    faces = cube.faces[:-1].copy()
    faces[0] = faces[0][::-1]
    with pytest.raises(AssemblyError, match=r"block 0 is not a closed surface .* it has holes or loose triangles"):
        Assembly.from_meshes([trimesh.Trimesh(cube.vertices, faces, process=False)])


def test_a_hollow_block_with_a_flipped_triangle_is_refused_not_guessed():
    # two shells: whether the inner one is a cavity or a second solid depends on its winding, which a flipped
    # triangle leaves in doubt
    outer, inner = trimesh.creation.box(extents=(2, 2, 2)), trimesh.creation.box(extents=(1, 1, 1))
    faces = np.vstack([outer.faces, inner.faces[:, ::-1] + 8])
    faces[0] = faces[0][::-1]
    hollow = trimesh.Trimesh(np.vstack([outer.vertices, inner.vertices]), faces, process=False)
    with pytest.raises(AssemblyError, match="block 0 is not a closed surface"):
        Assembly.from_meshes([hollow])


def test_a_box_missing_a_triangle_is_refused_also_with_t_junctions():
    cube = trimesh.creation.box()
    with pytest.raises(AssemblyError, match=r"block 0 is not a closed surface \(3 edges"):
        Assembly.from_meshes([trimesh.Trimesh(cube.vertices, cube.faces[:-1], process=False)])
    vertices, faces = _cube_with_a_t_junction()
    assert len(unmatched_edges(faces)) > 0
    assert Assembly.from_meshes([trimesh.Trimesh(vertices, faces, process=False)]).volumes[0] == pytest.approx(1.0)
    top = np.flatnonzero((vertices[faces][:, :, 2] == 0.5).all(axis=1))[0]
    with pytest.raises(AssemblyError, match="also after splitting edges at the vertices on them"):
        Assembly.from_meshes([trimesh.Trimesh(vertices, np.delete(faces, top, axis=0), process=False)])


def test_a_list_of_files_takes_the_frame_its_files_store(tmp_path):
    paths = []
    for k, mesh in enumerate(_row_of_cubes()):
        path = tmp_path / f"part_{k}.obj"
        name = "part fixed" if k == 2 else "part"
        path.write_text(f"o {name}\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in mesh.vertices)
                        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in mesh.faces))
        paths.append(path)
    a = Assembly.load(paths)
    assert a.frame == (2,) and a.info["frame_from"] == "file"
    b = Assembly.load(paths, frame=[0])
    assert b.frame == (0,) and b.info["frame_from"] == "argument"
