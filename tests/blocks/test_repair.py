"""Mesh conditioning: merged vertices, polygons triangulated inside their outline, T-junctions split."""

import numpy as np
import pytest
import shapely
import trimesh

from interlock.blocks.repair import (MERGE_RTOL, TJUNCTION_RTOL, closed_groups, group_meshes, merge_vertices,
                                     split_t_junctions, triangulate_polygons, unmatched_edges)


def _signed_volume(vertices, faces):
    t = np.asarray(vertices, dtype=float)[faces]
    return float(np.einsum("ij,ij->", t[:, 0], np.cross(t[:, 1], t[:, 2])) / 6)


def _box_with_t_junctions(points_on_edge=1):
    """A unit cube whose bottom square is split with extra vertices on the edge y = 0 (T-junctions)."""
    cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    bottom = np.isclose(cube.triangles_center[:, 2], 0)
    extra = [[x, 0, 0] for x in np.linspace(0, 1, points_on_edge + 2)[1:-1]]
    vertices = np.vstack([cube.vertices, extra])
    corner = {tuple(p): k for k, p in enumerate(cube.vertices.tolist())}
    a, b, c, d = (corner[p] for p in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
    run = [a, *range(len(cube.vertices), len(vertices)), b]
    fan = [[c, run[k + 1], run[k]] for k in range(len(run) - 1)] + [[a, d, c]]  # outward: normal -z
    return vertices, np.vstack([cube.faces[~bottom], fan])


@pytest.mark.parametrize("points", [1, 2, 5])
def test_t_junctions_are_split_into_a_closed_surface(points):
    vertices, faces = _box_with_t_junctions(points)
    assert len(unmatched_edges(faces)) > 0
    split = split_t_junctions(vertices, faces)
    assert len(unmatched_edges(split)) == 0
    assert _signed_volume(vertices, split) == pytest.approx(1.0)
    assert len(split) == len(faces) + points  # the cube's side triangle along y = 0 cut at every point


def test_t_junctions_within_the_tolerance_only():
    vertices, faces = _box_with_t_junctions(1)
    nudged = vertices.copy()
    nudged[-1, 1] += 0.5 * TJUNCTION_RTOL  # half the tolerance (the cube's diagonal is sqrt 3) off the edge
    assert len(unmatched_edges(split_t_junctions(nudged, faces))) == 0
    nudged[-1, 1] = 10 * TJUNCTION_RTOL * np.sqrt(3)
    assert len(unmatched_edges(split_t_junctions(nudged, faces))) > 0


def test_an_open_or_flipped_surface_stays_open():
    cube = trimesh.creation.box()
    open_box = cube.faces[:-1]
    assert len(unmatched_edges(split_t_junctions(cube.vertices, open_box))) == 3
    flipped = cube.faces.copy()
    flipped[0] = flipped[0, ::-1]
    assert len(unmatched_edges(split_t_junctions(cube.vertices, flipped))) == 3  # its edges, each now twice one way
    vertices, faces = _box_with_t_junctions(2)
    assert len(unmatched_edges(split_t_junctions(vertices, faces[1:]))) > 0  # a T-junction and a hole


def test_unmatched_edges_allow_four_triangles_at_an_edge():
    # two cubes sharing one edge, as one surface (voxel parts): every directed edge still has its partner
    cubes = [trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), trimesh.creation.box(bounds=[[1, 1, 0], [2, 2, 1]])]
    both = trimesh.util.concatenate(cubes)
    vertices, faces = merge_vertices(both.vertices, both.faces)
    assert len(vertices) == 14 and len(unmatched_edges(faces)) == 0


@pytest.mark.parametrize("scale", [1e-9, 1.0, 1e12])
def test_merging_is_relative_to_the_model_size(scale):
    cube = trimesh.creation.box()
    soup = cube.vertices[cube.faces].reshape(-1, 3) * scale
    soup[0] += 0.1 * MERGE_RTOL * scale  # rounding noise merges
    vertices, faces = merge_vertices(soup, np.arange(len(soup)).reshape(-1, 3))
    assert len(vertices) == 8 and len(unmatched_edges(faces)) == 0
    assert _signed_volume(vertices, faces) == pytest.approx(scale ** 3)


def test_groups_never_merge():
    cube = trimesh.creation.box()
    twice = np.vstack([cube.vertices, cube.vertices])
    faces = np.vstack([cube.faces, cube.faces + 8])
    vertices, merged = merge_vertices(twice, faces, groups=np.repeat([0, 1], 8))
    assert len(vertices) == 16 and (merged[12:] >= 8).all() and (merged[:12] < 8).all()


def _l_prism():
    """An L-shaped prism: two hexagons (non-convex) and six quadrilaterals; volume 3."""
    outline = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    vertices = [(x, y, 0) for x, y in outline] + [(x, y, 1) for x, y in outline]
    polygons = [[5, 4, 3, 2, 1, 0], [6, 7, 8, 9, 10, 11]] + [[k, (k + 1) % 6, (k + 1) % 6 + 6, k + 6] for k in range(6)]
    return np.array(vertices, dtype=float), polygons


def test_non_convex_polygons_are_triangulated_inside_their_outline():
    vertices, polygons = _l_prism()
    faces, polygon = triangulate_polygons(vertices, np.concatenate(polygons), [len(p) for p in polygons])
    assert len(faces) == 2 * 4 + 6 * 2 and np.array_equal(polygon, np.repeat(np.arange(8), [4, 4] + [2] * 6))
    assert len(unmatched_edges(faces)) == 0 and _signed_volume(vertices, faces) == pytest.approx(3.0)
    # the hexagons' triangles cover the L exactly: no triangle reaches into the missing square
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert mesh.area == pytest.approx(2 * 3 + 2 + 1 + 1 + 1 + 1 + 2)
    flat = shapely.union_all(shapely.polygons(vertices[faces[polygon == 0]][:, :, :2]))
    assert flat.area == pytest.approx(3.0) and flat.equals(shapely.Polygon(vertices[:6, :2]))


def test_a_dart_quadrilateral_is_cut_along_its_inner_diagonal():
    dart = np.array([[0, 0, 0], [1, 0.2, 0], [0, 1, 0], [0.3, 0.3, 0]], dtype=float)  # corner 3 points inwards
    faces, _ = triangulate_polygons(dart, [0, 1, 2, 3], [4])
    t = dart[faces]
    assert (np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])[:, 2] > 0).all()
    assert sorted(map(sorted, faces.tolist())) == [[0, 1, 3], [1, 2, 3]]


def test_a_self_intersecting_polygon_falls_back_to_the_fan():
    bow = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0], [0.5, 2, 0]], dtype=float)
    faces, polygon = triangulate_polygons(bow, [0, 1, 2, 3, 4], [5])
    assert faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4]] and polygon.tolist() == [0, 0, 0]


def test_edges_are_split_only_at_vertices_of_their_own_mesh():
    # an open box and an open tetrahedron (a triangle missing from each) whose corner at the tetrahedron's hole
    # lies in the middle of an edge of the box's hole
    cube = trimesh.creation.box()
    open_box = cube.faces[:-1]
    hole = cube.vertices[cube.faces[-1]]
    corner = (hole[0] + hole[1]) / 2
    tetrahedron = np.array([corner, corner + [0, 0, 1], corner + [0, 1, 0], corner + [1, 0, 0]])
    vertices = np.vstack([cube.vertices, tetrahedron])
    faces = np.vstack([open_box, [[8, 10, 9], [8, 11, 10], [9, 10, 11]]])
    mesh_of = np.repeat([0, 1], [8, 4])
    apart = split_t_junctions(vertices, faces, groups=mesh_of)
    assert (mesh_of[apart] == mesh_of[apart[:, :1]]).all() and len(apart) == len(faces)
    mixed = split_t_junctions(vertices, faces)  # as one mesh, the corner splits the box's edge
    assert not (mesh_of[mixed] == mesh_of[mixed[:, :1]]).all()


def test_closed_groups_split_t_junctions_block_by_block():
    vertices, faces = _box_with_t_junctions(2)
    twice = np.vstack([vertices, vertices + [1, 0, 0]])  # two such boxes side by side: they touch
    both = np.vstack([faces, faces + len(vertices)])
    merged, closed, group = closed_groups(twice, both, np.repeat([0, 1], len(faces)))
    assert len(unmatched_edges(closed)) == 0 and np.bincount(group).tolist() == [len(faces) + 2] * 2
    meshes = group_meshes(merged, closed, group)
    assert [round(float(m.volume), 9) for m in meshes] == [1.0, 1.0]
    assert closed_groups(twice, both[1:], np.repeat([0, 1], len(faces))[1:]) is None
