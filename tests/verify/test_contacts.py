"""Face-to-face contacts (main paper Def. 3.3; only face pairs, Remark 3.11)."""

import io
import json
import math
import re

import networkx as nx
import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from interlock import InterlockError
from interlock.blocks.assembly import Assembly
from interlock.verify.contacts import (DEFAULT_ANGLE_TOL, DEFAULT_CONTACT_RTOL, DEFAULT_GAP_RTOL, Contact,
                                       ContactError, contacts, facets)

#: Recorded on the reference data (areas positive, normals opposite, vertices on both
#: facets, every contact checked against a brute-force triangle-by-triangle overlap).
BUNNY_CONTACTS, BUNNY_PAIRS, BUNNY_AREA = 1135, 447, 5.78515625
ANIA_CONTACTS = 6
#: compas_cra's solved armadillo (compas_cra/data/samples/armadillo_cra.json, tmax = 0.05, amin = 1e-4) has 1014
#: interfaces, one per pair of blocks; it skips pairs of two supports, which touch in 29 more pairs.
ARMADILLO_UPSTREAM_PAIRS, ARMADILLO_SUPPORT_PAIRS, ARMADILLO_DEFAULT_CONTACTS = 1014, 29, 341


def box(lo, hi):
    return trimesh.creation.box(bounds=[lo, hi])


def cube(x, y, z=0.0, side=1.0):
    return box([x, y, z], [x + side, y + side, z + side])


def prism(polygon, z0=0.0, height=1.0):
    mesh = trimesh.creation.extrude_polygon(polygon, height)
    return mesh.apply_translation([0, 0, z0])


def grid_3x3():
    return Assembly.from_meshes([cube(x, y) for x in range(3) for y in range(3)])


def check_geometry(assembly, found, atol=1e-9):
    """Facts every contact must satisfy: i < j, unit normal i->j, vertices on both facet planes."""
    fac = [facets(assembly.mesh(i)) for i in range(len(assembly))]
    for c in found:
        assert c.i < c.j and c.area > 0
        assert np.linalg.norm(c.normal) == pytest.approx(1)
        np.testing.assert_allclose(c.normal, fac[c.i].normals[c.facet_i], atol=1e-9)
        np.testing.assert_allclose(c.normal, -fac[c.j].normals[c.facet_j], atol=DEFAULT_ANGLE_TOL)
        for f, k in ((fac[c.i], c.facet_i), (fac[c.j], c.facet_j)):
            assert np.abs((c.vertices - f.origins[k]) @ f.normals[k]).max() < atol * assembly.scale + 1e-12
        assert len(c.vertices) == sum(c.ring_sizes)
        assert c.polygon.area == pytest.approx(c.area)
        np.testing.assert_allclose(np.cross(*c.basis), c.normal, atol=1e-12)
    keys = [(c.i, c.j, c.facet_i, c.facet_j) for c in found]
    assert keys == sorted(keys)


# --- the cube grids of Ex. 3.5 -----------------------------------------------------------------


def test_example_3_5_grid_has_12_unit_contacts():
    a = grid_3x3()
    found = contacts(a)
    check_geometry(a, found)
    assert len(found) == 12
    assert all(c.area == pytest.approx(1) and len(c.vertices) == 4 for c in found)
    for c in found:  # axis-aligned, pointing from i to j
        np.testing.assert_allclose(np.abs(c.normal), np.abs(c.normal).round(), atol=1e-12)
        assert c.normal @ (a.centroids[c.j] - a.centroids[c.i]) == pytest.approx(1)
    middle = [c for c in found if 4 in (c.i, c.j)]
    assert len(middle) == 4
    assert sorted(c.j if c.i == 4 else c.i for c in middle) == [1, 3, 5, 7]
    # the face contact vertices of the middle cube are the corners of its side faces
    corners = {tuple(v) for c in middle for v in c.vertices.round(9)}
    assert corners == {(x, y, z) for x in (1.0, 2.0) for y in (1.0, 2.0) for z in (0.0, 1.0)}


def test_edge_and_corner_touches_are_not_contacts():
    diagonal = Assembly.from_meshes([cube(0, 0), cube(1, 1)])  # common edge only
    corner = Assembly.from_meshes([cube(0, 0), cube(1, 1, 1)])  # common corner only
    for a in (diagonal, corner):
        assert a.neighbours.has_edge(0, 1)
        assert contacts(a) == ()
    # in the 3x3 grid the middle cube touches its 4 diagonal neighbours along edges only
    assert not any({c.i, c.j} in ({0, 4}, {2, 4}, {4, 6}, {4, 8}) for c in contacts(grid_3x3()))


def test_half_offset_cubes():
    a = Assembly.from_meshes([cube(0, 0), cube(1, 0.5)])
    (c,) = contacts(a)
    assert c.area == pytest.approx(0.5)
    np.testing.assert_allclose(c.normal, [1, 0, 0], atol=1e-12)
    assert sorted(map(tuple, c.vertices.round(9))) == [(1, 0.5, 0), (1, 0.5, 1), (1, 1, 0), (1, 1, 1)]


def test_cube_on_larger_slab():
    a = Assembly.from_meshes([box([-2, -3, -1], [4, 3, 0]), cube(0.25, 0.5, 0)])
    (c,) = contacts(a)
    assert (c.i, c.j) == (0, 1) and c.area == pytest.approx(1)
    np.testing.assert_allclose(c.normal, [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(c.vertices[:, 2], 0, atol=1e-12)
    # the other way round: the normal still points from the lower index to the higher
    (d,) = contacts(Assembly.from_meshes([cube(0.25, 0.5, 0), box([-2, -3, -1], [4, 3, 0])]))
    np.testing.assert_allclose(d.normal, [0, 0, -1], atol=1e-12)


# --- non-convex overlaps, several parts, holes ----------------------------------------------


def test_l_prism_against_box_gives_nonconvex_overlap():
    ell = shapely.Polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)])
    a = Assembly.from_meshes([prism(ell), box([0.5, 0.5, 1], [2, 2, 2])])
    found = contacts(a)
    check_geometry(a, found)
    (c,) = found
    assert c.area == pytest.approx(0.75 + 0.5)
    assert c.polygon.convex_hull.area > c.area + 0.1  # genuinely non-convex
    assert len(c.vertices) == 6
    np.testing.assert_allclose(c.normal, [0, 0, 1], atol=1e-12)


def test_u_prism_against_box_gives_two_contacts():
    u = shapely.Polygon([(0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)])
    a = Assembly.from_meshes([prism(u), box([0, 2, 1], [3, 3, 2])])
    found = contacts(a)
    check_geometry(a, found)
    assert len(found) == 2 and len({(c.facet_i, c.facet_j) for c in found}) == 1
    assert [c.area for c in found] == pytest.approx([1, 1])


def test_overlap_with_a_hole_keeps_the_hole_vertices():
    frame = shapely.box(0, 0, 3, 3).difference(shapely.box(1, 1, 2, 2))
    a = Assembly.from_meshes([prism(frame), box([-1, -1, 1], [4, 4, 2])])
    (c,) = contacts(a)
    assert c.area == pytest.approx(8)
    assert c.ring_sizes == (4, 4) and len(c.vertices) == 8
    hole = {tuple(v) for v in c.vertices[4:].round(9)}
    assert hole == {(x, y, 1.0) for x in (1.0, 2.0) for y in (1.0, 2.0)}
    assert c.to_dict()["ring_sizes"] == [4, 4]


# --- tolerances --------------------------------------------------------------------------------


def test_gap_against_tolerance():
    # float64 unit cubes: the tolerance follows the blocks (1e-9 of their size), never the scene
    assert contacts(Assembly.from_meshes([cube(0, 0), cube(1 + 1e-6, 0)])) == ()  # open
    (c,) = contacts(Assembly.from_meshes([cube(0, 0), cube(1 + 1e-10, 0)]))  # within tolerance: a contact with play
    assert c.area == pytest.approx(1) and c.separation == pytest.approx(1e-10, rel=1e-3) and c.deviation == 0
    assert c.tolerance < 1e-12  # the margin's tolerance is the rounding, not the search distance
    # a far-away block changes nothing
    far = Assembly.from_meshes([cube(0, 0), cube(1 + 1e-6, 0), cube(1e9, 0)])
    assert contacts(far) == ()
    # one tolerance relative to the model size, when asked (the model of interlock 0.2)
    (c,) = contacts(Assembly.from_meshes([cube(0, 0), cube(1.001, 0)]), rtol=1e-3)
    assert c.area == pytest.approx(1) and c.vertices[:, 0] == pytest.approx(1)
    # an overlap thinner than the tolerance is an edge touch
    assert contacts(Assembly.from_meshes([cube(0, 0), cube(1, 1 - 1e-10)])) == ()


def test_float32_blocks_far_from_the_origin_keep_their_contacts():
    for offset in (0.0, 1e3, 1e5):
        boxes = [cube(offset + x, offset) for x in range(3)]
        for box in boxes:
            box.vertices = np.float32(box.vertices).astype(float)
        found = contacts(Assembly.from_meshes(boxes))
        assert _pairs(found) == {(0, 1), (1, 2)}, offset
        # the tolerance is the rounding of these coordinates (2^-24 |x|), whatever else is in the scene
        assert max(c.tolerance for c in found) <= 4 * 2.0**-24 * (offset + 4) * (1 + 1e-9)


def test_tilted_face_within_angle_tolerance():
    # faces that cross at a small angle (one presses into the other) are in contact, not planar, with their spread
    # as tolerance: rotated pieces of a file accurate to a few 1e-5 rad
    for angle in (1e-11, 1e-5):
        tilt = trimesh.transformations.rotation_matrix(angle, [0, 1, 0], point=[1, 0.5, 0.5])
        (c,) = contacts(Assembly.from_meshes([cube(0, 0), cube(1, 0).apply_transform(tilt)]))
        assert c.separation == 0 and c.tolerance >= 2 * c.deviation * (1 - 1e-9)
        assert c.planar == (angle < 1e-9) and c.deviation == pytest.approx(angle if angle > 1e-9 else 0, rel=1e-3)
    # the same tilt about the face's edge opens a wedge: a gap of up to 1e-5, open; crossing by 3e-5 is too much
    tilt = trimesh.transformations.rotation_matrix(1e-5, [0, 1, 0], point=[1, 0.5, 0])
    a = Assembly.from_meshes([cube(0, 0), cube(1, 0).apply_transform(tilt)])
    assert contacts(a) == ()
    tilt = trimesh.transformations.rotation_matrix(3e-5, [0, 1, 0], point=[1, 0.5, 0.5])
    a = Assembly.from_meshes([cube(0, 0), cube(1, 0).apply_transform(tilt)])
    assert contacts(a) == ()
    tilt = trimesh.transformations.rotation_matrix(3e-5, [0, 1, 0], point=[1, 0.5, 0.5])
    a = Assembly.from_meshes([cube(0, 0), cube(1, 0).apply_transform(tilt)])
    assert len(contacts(a, rtol=1e-5)) == 1 and contacts(a, rtol=1e-5, angle_tol=1e-5) == ()


def folded_pair(bend):
    """A block whose +x face is folded along a vertical ridge ``bend`` out of plane, and its matching neighbour."""
    ridge = shapely.Polygon([(0, 0), (1, 0), (1 + bend, 0.5), (1, 1), (0, 1)])
    valley = shapely.Polygon([(1, 0), (2, 0), (2, 1), (1, 1), (1 + bend, 0.5)])
    return Assembly.from_meshes([prism(ridge), prism(valley)])


def test_face_bent_within_tolerance_is_one_facet_marked_not_planar():
    bend = 1e-7
    pair = folded_pair(bend)
    fold = facets(pair.meshes[0])
    assert len(fold) == 6 and fold.planar.sum() == 5  # the two halves of the ridge face merged
    assert fold.flatness[~fold.planar][0] == pytest.approx(bend / 2, rel=1e-3)
    assert fold.flatness[fold.planar].max() < 1e-15
    (c,) = contacts(pair)
    assert not c.planar and c.deviation == pytest.approx(bend, rel=1e-3)
    assert "planar only within tolerance" in str(c) and c.to_dict()["planar"] is False
    pieces = contacts(pair, rtol=1e-12, angle_tol=1e-12)  # little slack: every piece of the fold is planar
    assert all(h.planar and h.deviation < 1e-15 for h in pieces) and sum(h.area for h in pieces) == pytest.approx(1)
    assert sorted(h.normal[1] for h in pieces) == pytest.approx([-2 * bend, 2 * bend])
    assert all(c.planar and c.deviation == 0 for c in contacts(grid_3x3()))



@pytest.mark.parametrize("amplitude", [1e-5, 1e-4])
def test_vertex_noise_beyond_the_angle_tolerance_is_read_off_the_mesh(amplitude):
    """A unit cube cut into 768 triangles with Gaussian vertex noise (its triangles, 0.125 across, tilt by up to
    ~50 times the noise, far beyond DEFAULT_ANGLE_TOL) has six faces, grouped within several times the noise, and
    two such cubes side by side touch in one contact of the whole face."""
    rng = np.random.default_rng(5)
    fine = trimesh.creation.box().subdivide().subdivide().subdivide()
    noisy = [trimesh.Trimesh(fine.vertices + offset + rng.normal(scale=amplitude, size=fine.vertices.shape),
                             fine.faces) for offset in ([0, 0, 0], [1, 0, 0])]
    faces = facets(noisy[0])
    assert len(faces) == 6 and 3 * amplitude < faces.grouping < 100 * amplitude
    (c,) = contacts(Assembly.from_meshes(noisy))
    assert c.area == pytest.approx(1.0, abs=1e-3)


def test_a_tessellated_sphere_or_a_fold_reads_no_noise():
    """Creases of a designed surface are not noise: a sphere of 81,920 triangles creases by ~0.009 rad, all one
    way (noise creases both ways), and a fold is one crease among coplanar pairs."""
    mesh = trimesh.creation.icosphere(subdivisions=6)
    sphere = facets(mesh)  # grouped within the default tolerance only
    assert len(sphere) == 81920 and sphere.grouping == pytest.approx(DEFAULT_CONTACT_RTOL * mesh.scale)
    folded = folded_pair(1e-3).meshes[0]
    assert facets(folded).grouping == pytest.approx(DEFAULT_CONTACT_RTOL * folded.scale)
def test_bad_input():
    with pytest.raises(ContactError, match="Assembly"):
        contacts([cube(0, 0), cube(1, 0)])
    a = grid_3x3()
    for kwargs in ({"rtol": -1e-6}, {"angle_tol": float("nan")}, {"area_rtol": "0"}, {"rtol": True},
                   {"angle_tol": 2.0}):
        with pytest.raises(ContactError) as info:
            contacts(a, **kwargs)
        assert isinstance(info.value, InterlockError) and isinstance(info.value, ValueError)
    with pytest.raises(ContactError, match="Trimesh"):
        facets("box")


def test_small_and_separated_assemblies():
    assert contacts(Assembly.from_meshes([cube(0, 0)])) == ()
    assert contacts(Assembly.from_meshes([cube(0, 0), cube(5, 0)])) == ()
    assert len(contacts(grid_3x3(), rtol=0.0, angle_tol=0.0)) == 12  # exact input needs no slack


# --- contacts across a gap (compas_assembly's tmax) ---------------------------------------------


def test_gap_bridges_a_narrow_gap_on_the_mid_plane():
    a = Assembly.from_meshes([cube(0, 0), cube(1.001, 0)])
    assert DEFAULT_GAP_RTOL == 0 and contacts(a) == () and contacts(a, gap=1e-4) == ()  # 1e-4 * scale < 1e-3
    (c,) = contacts(a, gap=2e-3)  # 2e-3 * scale = 4.9e-3
    assert (c.i, c.j) == (0, 1) and c.area == pytest.approx(1) and len(c.vertices) == 4
    np.testing.assert_allclose(c.normal, [1, 0, 0], atol=1e-12)
    assert c.polygon.equals(shapely.box(-0.5, -0.5, 0.5, 0.5))  # about the facet's centroid
    assert sorted(map(tuple, c.vertices.round(9))) == [(1.0005, y, z) for y in (0, 1) for z in (0, 1)]
    np.testing.assert_allclose(c.origin + c.polygon.exterior.coords[0] @ c.basis, c.vertices[0], atol=1e-12)
    # it records the gap it bridges; the faces stay planar, so check() keeps trusting slides across it
    assert c.separation == pytest.approx(1e-3) and c.deviation == 0 and c.planar  # a gap is never a bend
    assert "across a gap of up to 0.001" in str(c) and c.to_dict()["separation"] == pytest.approx(1e-3)
    (half,) = contacts(Assembly.from_meshes([cube(0, 0), cube(1.001, 0.5)]), gap=2e-3)
    assert half.area == pytest.approx(0.5)
    # faces that touch are no gap contact, also with a gap tolerance
    assert all(c.separation == 0 for c in contacts(grid_3x3(), gap=2e-3))
    assert len(contacts(grid_3x3(), gap=2e-3)) == 12


def test_gap_does_not_pair_faces_tilted_beyond_the_angle_tolerance():
    tilt = trimesh.transformations.rotation_matrix(0.01, [0, 1, 0], point=[1.001, 0.5, 0.5])
    a = Assembly.from_meshes([cube(0, 0), cube(1.001, 0).apply_transform(tilt)])
    assert contacts(a, gap=5e-3) == ()  # 0.01 rad > angle_tol = 1e-4
    (c,) = contacts(a, gap=5e-3, angle_tol=0.02)  # faces 1e-3 + 0.5 * sin(0.01) apart at most
    assert c.area == pytest.approx(1, rel=1e-3) and c.separation == pytest.approx(1e-3 + 0.005, rel=1e-2)


def test_default_gap_reproduces_the_contacts():
    for a in (grid_3x3(), Assembly.from_meshes(_mixed_meshes()), folded_pair(1e-7), Assembly.from_meshes(
            [cube(0, 0), cube(1 + DEFAULT_CONTACT_RTOL, 0.3)])):
        before, after = contacts(a), contacts(a, gap=0.0)
        assert [c.to_dict() for c in before] == [c.to_dict() for c in after]
        assert all(c.separation == 0 for c in after)
    assert len(contacts(grid_3x3(), gap=0)) == 12 and len(contacts(Assembly.from_meshes(_mixed_meshes()))) == 6


@pytest.mark.parametrize("bad", [-1e-3, float("nan"), float("inf"), "0.01", None, True])
def test_bad_gap(bad):
    with pytest.raises(InterlockError, match=r"gap must be a finite number >= 0"):
        contacts(grid_3x3(), gap=bad)


def _pairs(found):
    return {(c.i, c.j) for c in found}


def test_compas_cra_armadillo_with_upstream_gap(reference_data):
    from interlock.blocks import load_compas

    a = load_compas(reference_data / "compas_cra" / "armadillo.json")
    # upstream's absolute tmax = 0.05 and amin = 1e-4 relative to the model size; its faces pair up to 0.16 rad apart
    found = contacts(a, gap=0.05 / a.scale, area_rtol=1e-4 / a.scale**2, angle_tol=0.2)
    pairs = _pairs(found)
    supports = set(a.frame)
    both_supports = {p for p in pairs if set(p) <= supports}
    assert len(both_supports) == ARMADILLO_SUPPORT_PAIRS
    assert len(pairs - both_supports) == ARMADILLO_UPSTREAM_PAIRS
    assert max(c.separation for c in found) <= (DEFAULT_CONTACT_RTOL * a.scale + 0.05) * (1 + 1e-9)


@pytest.mark.parametrize("name, area", [("cube-curve-short", 0.471), ("cube-curve-tall", 0.471),
                                        ("curve-3-blocks", None)])
def test_compas_cra_curved_interfaces_as_small_planar_contacts(reference_data, name, area):
    from interlock.blocks import load_compas

    a = load_compas(reference_data / "compas_cra" / f"{name}.json")
    default = contacts(a)
    found = contacts(a, gap=1e-3, angle_tol=0.2)  # facing triangles of the two sides differ in angle and offset
    assert len(found) >= max(4 * len(default), 250) and all(c.planar for c in found)
    assert _pairs(found) == {(k, k + 1) for k in range(len(a) - 1)}  # a stack: every interface is found
    if area is not None:  # the curved surface's area (triangles of block 0 within 1e-3 * scale of block 1)
        assert sum(c.area for c in found) == pytest.approx(area, rel=0.01)
        assert sum(c.area for c in default) < 0.4 * area


# --- triangulated and polygonal faces --------------------------------------------------------


def test_split_triangles_still_give_one_polygon_per_face_pair():
    fine = cube(1, 0)
    for _ in range(3):
        fine = fine.subdivide()  # 64 triangles per side, vertices along every edge
    assert len(fine.faces) == 768 and len(facets(fine)) == 6
    a = Assembly.from_meshes([cube(0, 0), fine, cube(1, 1)])
    found = contacts(a)
    check_geometry(a, found)
    assert [(c.i, c.j) for c in found] == [(0, 1), (1, 2)]
    assert all(c.area == pytest.approx(1) and len(c.vertices) == 4 for c in found)


def test_polygonal_obj_faces():
    # a hexagonal prism written with two hexagon faces and six quads; trimesh triangulates them
    ring = [(math.cos(t), math.sin(t)) for t in (np.arange(6) + 0.5) * math.pi / 3]  # a side at x = sqrt(3)/2
    lines = [f"v {x} {y} {z}" for z in (0, 1) for x, y in ring]
    lines += ["f 6 5 4 3 2 1", "f 7 8 9 10 11 12"] + [f"f {k + 1} {(k + 1) % 6 + 1} {(k + 1) % 6 + 7} {k + 7}"
                                                    for k in range(6)]
    hexagon = trimesh.load(io.StringIO("\n".join(lines)), file_type="obj", force="mesh")
    assert len(hexagon.faces) == 20 and len(facets(hexagon)) == 8
    side_box = box([math.sqrt(3) / 2, -0.25, 0], [2, 0.25, 0.9])
    a = Assembly.from_meshes([hexagon, box([-2, -2, 1], [2, 2, 1.5]), side_box])
    found = contacts(a)
    check_geometry(a, found)
    top, side = found
    assert (top.i, top.j, side.i, side.j) == (0, 1, 0, 2)
    assert top.area == pytest.approx(3 * math.sqrt(3) / 2) and len(top.vertices) == 6
    assert side.area == pytest.approx(0.5 * 0.9) and len(side.vertices) == 4  # the box face, inside a side quad
    np.testing.assert_allclose(side.normal, [1, 0, 0], atol=1e-12)


def test_shared_types_and_mirror_images_match_world_meshes():
    wedge = prism(shapely.Polygon([(0, 0), (2, 0), (0, 1)]))
    mirror = np.diag([-1.0, 1, 1, 1])
    place = [np.eye(4), trimesh.transformations.translation_matrix([0, 0, 1]), mirror,
             trimesh.transformations.translation_matrix([0, 0, -1]) @ mirror]
    shared = Assembly([wedge], [0, 0, 0, 0], place)
    assert shared.mirrored.tolist() == [False, False, True, True]
    world = Assembly.from_meshes(shared.world_meshes())
    a, b = contacts(shared), contacts(world)
    assert [(c.i, c.j) for c in a] == [(0, 1), (0, 2), (2, 3)] and len(b) == 3
    for c, d in zip(a, b):
        assert (c.i, c.j, c.facet_i, c.facet_j) == (d.i, d.j, d.facet_i, d.facet_j)
        assert c.area == pytest.approx(d.area) and c.area == pytest.approx(1)
        np.testing.assert_allclose(c.normal, d.normal, atol=1e-12)
        assert sorted(map(tuple, c.vertices.round(9))) == sorted(map(tuple, d.vertices.round(9)))
    check_geometry(shared, a)


# --- results as values ---------------------------------------------------------------------


def test_contact_prints_and_serialises():
    c = contacts(grid_3x3())[0]
    assert isinstance(c, Contact)
    assert re.fullmatch(r"contact 0-1: 4 vertices, area 1, normal \(0, 1, 0\), facets \d+/\d+", str(c))
    data = json.loads(json.dumps(c.to_dict()))
    assert data["i"] == 0 and data["j"] == 1 and data["area"] == pytest.approx(1)
    np.testing.assert_allclose(data["vertices"], c.vertices)
    with pytest.raises(AttributeError):
        c.area = 2
    with pytest.raises(ValueError):
        c.vertices[0, 0] = 5


# --- reference data (TopoLite) ---------------------------------------------------------------


def _contact_graph(assembly, found):
    graph = nx.Graph()
    graph.add_nodes_from(range(len(assembly)))
    graph.add_edges_from((c.i, c.j) for c in found)
    return graph


def test_topolite_bunny(reference_data):
    folder = reference_data / "topolite" / "bunny"
    paths = sorted(folder.glob("part_*.obj"), key=lambda p: int(p.stem.split("_")[1]))
    assert [p.name for p in paths[:3]] == ["part_1.obj", "part_2.obj", "part_3.obj"] and len(paths) == 80
    a = Assembly.load(paths)
    found = contacts(a)
    check_geometry(a, found)
    graph = _contact_graph(a, found)
    assert min(d for _, d in graph.degree) >= 1 and nx.is_connected(graph)
    assert len(found) == BUNNY_CONTACTS and graph.number_of_edges() == BUNNY_PAIRS
    assert sum(c.area for c in found) == pytest.approx(BUNNY_AREA)
    # voxel parts of side 1/16: every contact is a union of voxel faces
    areas = np.array([c.area for c in found]) * 16**2
    np.testing.assert_allclose(areas, areas.round(), atol=1e-9)


def test_topolite_ania(reference_data):
    folder = reference_data / "topolite" / "ania"
    a = Assembly.load([folder / f"{name}.obj" for name in ("piece4_tri", "piece0", "piece1", "piece3", "piece2")])
    found = contacts(a)
    check_geometry(a, found, atol=1e-5)
    graph = _contact_graph(a, found)
    assert sorted(graph.edges) == [(0, 1), (0, 2), (0, 3), (0, 4)]  # the four pieces rest on piece4_tri
    # pieces 3 and 2 are rotated by about 30 degrees and accurate to ~4e-5 rad only: one face of each crosses
    # piece4_tri's, pressed together, and carries the spread (6.5e-7) as a bend; their other faces are 1.2e-6
    # apart (5e-6 of the piece), open in float64; a tolerance of 1e-5 of the model takes those as contacts too
    tilted = [c for c in found if c.j in (3, 4)]
    assert len(found) == 4 and all(not c.planar and 6e-7 < c.deviation < 7e-7 for c in tilted)
    loose = contacts(a, rtol=1e-5)
    assert len(loose) == ANIA_CONTACTS and len(contacts(a, rtol=1e-5, angle_tol=1e-6)) == 2


# --- invariance (property test) ------------------------------------------------------------


def _mixed_meshes():
    ell = shapely.Polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)])
    return [prism(ell), box([0.5, 0.5, 1], [2, 2, 2]), cube(2, 0), cube(2, 1, 0.5), box([-1, -1, -1], [3, 3, 0])]


_BASE = _mixed_meshes()
_BASE_CONTACTS = contacts(Assembly.from_meshes(_BASE))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(quaternion=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
       shift=st.lists(st.floats(-50, 50), min_size=3, max_size=3), scale=st.floats(0.01, 100))
def test_contacts_follow_rigid_motions_and_scalings(quaternion, shift, scale):
    motion = trimesh.transformations.quaternion_matrix(np.asarray(quaternion) / np.linalg.norm(quaternion))
    motion[:3, 3] = shift
    motion[:3, :3] *= scale
    moved = contacts(Assembly.from_meshes([m.copy().apply_transform(motion) for m in _BASE]))
    assert len(moved) == len(_BASE_CONTACTS) == 6
    rotation = motion[:3, :3] / scale
    for c, d in zip(_BASE_CONTACTS, moved):
        assert (c.i, c.j, c.facet_i, c.facet_j) == (d.i, d.j, d.facet_i, d.facet_j)
        assert d.area == pytest.approx(c.area * scale**2, rel=1e-9)
        np.testing.assert_allclose(d.normal, rotation @ c.normal, atol=1e-9)
        expected = c.vertices @ motion[:3, :3].T + motion[:3, 3]
        assert len(d.vertices) == len(expected)
        distance = np.linalg.norm(d.vertices[:, None] - expected[None], axis=2)
        assert distance.min(axis=1).max() < 1e-9 * scale + 1e-9 * np.linalg.norm(shift)


@pytest.mark.parametrize("which", ["rhomblocks", "pg patch (mirror images)"])
def test_instanced_pairs_share_one_computation_per_kind(which):
    import sys

    from interlock import wallpaper
    from interlock.blocks import escher_block, patch, random_hexagon, rhomblock_assembly

    module = sys.modules["interlock.verify.contacts"]
    if which == "rhomblocks":
        assembly = rhomblock_assembly(random_hexagon(6, 6, 6, seed=3), 1)
    else:
        assembly = patch(escher_block(wallpaper.group("pg"), {0: [(0.25, 0.1)]}), 2.0)
    pairs = np.array(sorted(assembly.neighbours.edges))
    kinds, _, _ = assembly.pair_kinds(pairs)
    assert len(kinds) <= module.KIND_SHARE * len(pairs)  # the shared path is the one taken
    shared = contacts(assembly)
    tolerances = module._tolerances(assembly, None, module.DEFAULT_ANGLE_TOL, module.DEFAULT_AREA_RTOL, 0.0, None)
    direct = module._pair_contacts(assembly, pairs, tolerances)
    assert [(c.i, c.j, c.facet_i, c.facet_j) for c in shared] == [(c.i, c.j, c.facet_i, c.facet_j) for c in direct]
    for c, d in zip(shared, direct):
        assert c.area == pytest.approx(d.area, rel=1e-12)
        np.testing.assert_allclose(c.normal, d.normal, atol=1e-12)
        np.testing.assert_allclose(np.sort(c.vertices, axis=0), np.sort(d.vertices, axis=0), atol=1e-12)
        # rings stay counter-clockwise about the normal, also for mirror images
        assert np.dot(np.cross(c.vertices[1] - c.vertices[0], c.vertices[2] - c.vertices[1]), c.normal) > 0


@pytest.mark.parametrize("pieces, area", [
    # edge-matched: a square of two triangles (the coverage union's case)
    ([[(0, 0), (2, 0), (2, 2)], [(0, 0), (2, 2), (0, 2)]], 4.0),
    # a T-junction at (1, 1): not edge-matched, the general union is taken
    ([[(0, 0), (2, 0), (2, 2)], [(0, 0), (1, 1), (0, 2)], [(1, 1), (2, 2), (0, 2)]], 4.0),
    # overlapping triangles: area would be lost, the general union is taken
    ([[(0, 0), (2, 0), (0, 2)], [(0, 0), (2, 0), (0, 2)], [(0, 0), (2, 0), (2, 2)]], 3.0),
])
def test_facet_outlines_are_the_union_of_their_triangles_whatever_their_meshing(pieces, area):
    import shapely

    from interlock.verify.facets import _unions

    triangles = shapely.polygons(np.array(pieces, dtype=float))
    union = _unions(triangles, np.zeros(len(pieces), dtype=int), 1)[0]
    assert union.is_valid and union.geom_type == "Polygon" and abs(union.area - area) < 1e-12
    assert shapely.normalize(union).equals(shapely.union_all(triangles))


@pytest.mark.parametrize("shift", [208.0, 150.0])
def test_facets_rounded_to_nothing_are_no_crash(reference_data, tmp_path, shift):
    """The TopoLite cube 208 units from the origin written with 4 significant digits: rounding by 0.05 on parts
    0.8 across flattens some facets to empty polygons, which have no extent (were NaN, a crash inside cKDTree)."""
    import interlock

    cube = reference_data / "topolite" / "cube"
    parts = interlock.read([cube / f"part_{k}.obj" for k in range(1, 10)], frame=())
    lines, offset = [], 1
    for k, mesh in enumerate(parts.world_meshes()):
        lines.append(f"o block_{k}")
        lines.extend("v " + " ".join(f"{x:.4g}" for x in vertex) for vertex in mesh.vertices + [shift, 0.5 * shift, 0])
        lines.extend(f"f {a + offset} {b + offset} {c + offset}" for a, b, c in mesh.faces)
        offset += len(mesh.vertices)
    (tmp_path / "rounded.obj").write_text("\n".join(lines) + "\n")
    rounded = interlock.read(tmp_path / "rounded.obj")
    found = contacts(rounded)
    assert all(np.isfinite(c.vertices).all() for c in found)
    verdict = interlock.check(rounded, frame=[0, 8])
    assert verdict.interlocked is None and "coarser than its blocks" in verdict.status
