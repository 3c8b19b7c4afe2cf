"""The Escher-trick generator: valid blocks, equivariant deformations, clear rejections."""

import math

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock import InterlockError, wallpaper
from interlock.blocks import DeformationError, escher, escher_block, patch
from tests.blocks.deformations import random_block, random_deformation

ROTATION_GROUPS = ["p1", "p2", "p3", "p4", "p6"]
OVERLAP_RTOL = 1e-9
UNION_RTOL = 1e-6  # manifold3d's union of face-sharing solids loses slivers of ~1e-7 relative volume


def _triangles(mesh, decimals=9):
    """Faces as sets of rounded vertex triples, for comparing surfaces of different meshes."""
    return {frozenset(map(tuple, np.round(tri, decimals))) for tri in mesh.triangles}


def _assert_no_overlaps(assembly):
    meshes = assembly.world_meshes()
    for i, j in assembly.neighbours.edges:
        common = trimesh.boolean.intersection([meshes[i], meshes[j]], engine="manifold")
        with np.errstate(invalid="ignore", divide="ignore"):  # empty intersections have no centre of mass
            assert common.volume <= OVERLAP_RTOL * meshes[i].volume, (i, j)
    union = trimesh.boolean.union(meshes, engine="manifold")
    assert union.volume == pytest.approx(sum(m.volume for m in meshes), rel=UNION_RTOL)


@pytest.mark.parametrize("name", ROTATION_GROUPS)
@pytest.mark.parametrize("seed", range(3))
def test_random_blocks_are_valid_and_tile_without_overlap(name, seed):
    rng = np.random.default_rng(seed)
    group = wallpaper.group(name, a=float(rng.uniform(0.5, 3)))
    block = random_block(group, rng, max_points=3, skip=0.3 if seed == 2 else 0.0)
    assert block.mesh.is_watertight and block.mesh.is_winding_consistent
    assert block.volume == pytest.approx(block.bottom.area * block.height, rel=1e-9)
    assert block.top.area == pytest.approx(block.bottom.area, rel=1e-9)
    p = patch(block, 0.8 * math.sqrt(group.cell_area))
    assert not p.mirrored.any()  # p1..p6: every block congruent
    _assert_no_overlaps(p)


@pytest.mark.parametrize("name", wallpaper.GROUPS)
def test_every_group_gives_a_closed_block_and_mirror_images_where_it_reflects(name):
    group = wallpaper.group(name)
    block = random_block(group, np.random.default_rng(7))
    assert block.mesh.is_watertight
    assert block.volume == pytest.approx(group.fundamental_domain().area * block.height, rel=1e-9)
    p = patch(block, 0.6 * math.sqrt(group.cell_area))
    reflecting = any(not group.is_orientation_preserving(r) for r in group.cosets)
    assert p.mirrored.any() == reflecting
    assert all(p.mirrored[i] == (not group.is_orientation_preserving(g)) for i, g in enumerate(p.labels))
    _assert_no_overlaps(p)


@pytest.mark.parametrize("name", ["p1", "p2", "pg", "cm", "pgg", "p3", "p4g", "p31m", "p6"])
def test_partner_edges_receive_the_image_points_and_meet_face_to_face(name):
    group = wallpaper.group(name)
    block = random_block(group, np.random.default_rng(3), max_points=3)
    own = _triangles(block.mesh)
    pairings = group.side_pairings()
    for s in pairings:
        points, partner_points = block.deformation[s.edge], block.deformation[s.partner]
        assert len(points) == len(partner_points)
        m = group.matrix(s.element)
        mapped = partner_points @ m[:2, :2].T + m[:2, 2]
        assert np.allclose(mapped, points) or np.allclose(mapped[::-1], points)
        # the neighbour across edge e shares exactly the side triangles (Fig. 13: m + 2 per edge)
        # of the edges it lies across (two for p2's half-edges, paired by one rotation)
        neighbour = block.mesh.copy().apply_transform(group.to_3d(s.element))
        across = [t.edge for t in pairings if t.element == s.element]
        assert len(own & _triangles(neighbour)) == sum(len(block.deformation[t]) + 2 for t in across)


def test_fig13_triangulation_for_one_point():
    group = wallpaper.group("p1", gamma=90)
    p = (0.5, -0.2)
    block = escher_block(group, {0: [p]}, height=2.0)
    v1, v2 = (0, 0, 0), (1, 0, 0)
    v1t, v2t, pt = (0, 0, 2), (1, 0, 2), (0.5, -0.2, 2)
    tris = _triangles(block.mesh)
    for tri in [(v1, v2, pt), (v1, v1t, pt), (v2, v2t, pt)]:
        assert frozenset(tri) in tris
    # partner edge 2 (top edge) carries the translated point
    np.testing.assert_allclose(block.deformation[2], [[0.5, 0.8]])


def test_undeformed_block_is_a_prism():
    group = wallpaper.group("p4")
    block = escher_block(group, {}, height=3.0)
    assert block.deformed_edges == frozenset()
    np.testing.assert_allclose(block.mesh.bounds, [[0, 0, 0], [0.5, 0.5, 3]])
    assert block.volume == pytest.approx(0.75)


@pytest.mark.parametrize("group_name,deformation,match", [
    ("p4", {4: [(0.1, 0.1)]}, "edge 4 does not exist: the fundamental domain of p4 has edges 0..3"),
    ("p4", {"0": [(0.1, 0.1)]}, "edge '0' does not exist"),
    ("p4", {0: [(0.25, float("nan"))]}, "edge 0: intermediate points must be finite"),
    ("p4", {0: [0.25, 0.1]}, r"edge 0: intermediate points must be a sequence of \(x, y\) pairs"),
    ("p4", {0: [(0.25, 0.1)], 3: [(0.1, 0.25)]}, "edges 0 and 3 are paired by the rotation"),
    ("p4m", {0: [(0.25, 0.05)]}, "edge 0 lies on a mirror of p4m"),
    ("p4", {0: [(0.0, 0.0)]}, "edge 0: an intermediate point coincides with a vertex"),
    ("p4", {0: [(0.2, 0.1), (0.2, 0.1)]}, "edge 0: an intermediate point coincides"),
    ("p1", {0: [(0.9, 0.5)], 1: [(0.5, 0.5)]}, "self-intersecting: the paths of edges 0 and 1 cross"),
    ("p4", {0: [(0.25, -0.6)]}, "F' turned inside out|self-intersecting"),
    ("p4", [(0.1, 0.1)], "deformation must map edge indices to point lists"),
])
def test_bad_deformations_are_rejected_naming_the_edge(group_name, deformation, match):
    kwargs = {"gamma": 90} if group_name == "p1" else {}
    with pytest.raises(DeformationError, match=match):
        escher_block(wallpaper.group(group_name, **kwargs), deformation)


def test_self_intersecting_interpolation_is_rejected_although_both_caps_are_simple():
    group = wallpaper.group("p1")
    deformation = {0: [(0.544, -0.223)], 1: [(0.869, 0.328), (2.127, 0.404)]}
    with pytest.raises(DeformationError, match=r"intersect itself at height 0\.8\d\d x h: the sides over edges 1 and 3"):
        escher_block(group, deformation)
    # both F and F' are simple polygons: only intermediate slices cross themselves
    corners = np.asarray(group.fundamental_domain().exterior.coords)[:-1]
    full = escher._equivariant_deformation(group, deformation, 1e-12)
    top = shapely.Polygon(escher._top_ring(corners, full, 1e-12, "p1"))
    assert top.is_valid and group.fundamental_domain().is_valid


def test_consistent_points_on_both_partners_are_accepted():
    group = wallpaper.group("p4")
    block = escher_block(group, {0: [(0.25, 0.1)]})
    again = escher_block(group, {0: [(0.25, 0.1)], 3: block.deformation[3]})
    np.testing.assert_allclose(again.mesh.vertices, block.mesh.vertices)
    # a mirror edge may carry points on its own line (an undeformed path)
    assert escher_block(wallpaper.group("p4m"), {0: [(0.25, 0.0)]}).mesh.is_watertight


@pytest.mark.parametrize("bad", [0, -1, float("inf"), "tall"])
def test_bad_height_and_group(bad):
    with pytest.raises(DeformationError, match="height"):
        escher_block(wallpaper.group("p4"), {}, height=bad)
    with pytest.raises(InterlockError, match="WallpaperGroup"):
        escher_block("p4", {})


@given(
    name=st.sampled_from(ROTATION_GROUPS),
    seed=st.integers(0, 10_000),
    scale=st.floats(1e-3, 1e3),
    angle=st.floats(0, 2 * math.pi),
)
@settings(max_examples=25, deadline=None)
def test_blocks_scale_with_the_lattice_and_the_points(name, seed, scale, angle):
    rng = np.random.default_rng(seed)
    unit = wallpaper.group(name)
    deformation = random_deformation(unit, rng)
    try:
        block = escher_block(unit, deformation)
    except DeformationError:
        return  # an invalid random draw: rejection is tested elsewhere
    big = escher_block(wallpaper.group(name, a=scale), {e: scale * p for e, p in deformation.items()}, height=scale)
    assert big.volume == pytest.approx(scale**3 * block.volume, rel=1e-9)
    np.testing.assert_allclose(big.mesh.vertices, scale * block.mesh.vertices, rtol=1e-9, atol=1e-12 * scale)
    # a rigid motion of a block changes none of its intrinsic measures
    motion = trimesh.transformations.rotation_matrix(angle, [0.3, -0.5, 0.8])
    moved = block.mesh.copy().apply_transform(motion)
    assert moved.volume == pytest.approx(block.volume, rel=1e-9)
    assert moved.area == pytest.approx(block.mesh.area, rel=1e-9)
