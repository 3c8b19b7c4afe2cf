"""The RhomBlock and its assemblies on lozenge tilings (main paper Sec. 4.4, Thm. 4.9, Fig. 2-3)."""

import math
from itertools import product

import numpy as np
import pytest
import shapely
import trimesh

from interlock import InterlockError
from interlock.blocks.assembly import Assembly
from interlock.blocks.lozenge import (
    LATTICE_BASIS,
    UP_OFFSETS,
    Lozenge,
    LozengeTiling,
    TilingError,
    random_hexagon,
    staircase,
)
from interlock.blocks.rhomblock import (
    RHOMBLOCK_FACES,
    RHOMBLOCK_HEIGHT,
    RHOMBLOCK_VERTICES,
    rhomblock,
    rhomblock_assembly,
    rhomblock_transforms,
)
from interlock.verify import check
from interlock.verify.contacts import contacts
from interlock.verify.validate import overlaps

SQRT3 = math.sqrt(3)
#: Coordinates and areas agree to this.
TOL = 1e-9
#: manifold3d's union of face-sharing solids loses slivers of ~1e-7 relative volume.
UNION_RTOL = 1e-6
#: Decimals for comparing point sets.
DECIMALS = 9
#: Snapping grid for shapely unions (GEOS can drop a whole polygon that shares edges with 1e-16 noise).
GRID = 1e-9
#: Relative area error of a union snapped to that grid.
GRID_RTOL = 1e-7
#: A small step off a face.
STEP = 1e-4
HEXAGONS = [(4, 4, 4, 1), (3, 5, 2, 2), (2, 6, 3, 3)]  # a, b, c, seed


def _points(array):
    return {tuple(p) for p in np.round(np.asarray(array), DECIMALS).tolist()}


def _centroid(cells, up):
    """Centroids of up-triangles U(i, j) or down-triangles D(i, j) in the plane."""
    return (np.asarray(cells) + (1 / 3 if up else 2 / 3)) @ LATTICE_BASIS


def _cell(i, j, up):
    """The fixed hexagon about U(i, j) (or D(i, j)): its corners and the centres of its three neighbours."""
    if up:
        corners, neighbours = [(i, j), (i + 1, j), (i, j + 1)], np.array([(i, j)]) - UP_OFFSETS
    else:
        corners, neighbours = [(i + 1, j), (i, j + 1), (i + 1, j + 1)], np.array([(i, j)]) + UP_OFFSETS
    points = np.vstack([np.array(corners) @ LATTICE_BASIS, _centroid(neighbours, not up)])
    return shapely.MultiPoint(points).convex_hull


def _tops(assembly):
    """The top face of every block: the convex hull of its vertices at the block's greatest height."""
    world = np.einsum("nij,vj->nvi", assembly.transforms[:, :3, :3], assembly.meshes[0].vertices)
    world += assembly.transforms[:, None, :3, 3]
    tops = []
    for points in world:
        high = points[np.abs(points[:, 2] - points[:, 2].max()) < TOL]
        tops.append(shapely.MultiPoint(high[:, :2]).convex_hull)
    return tops, world


def _largest_overlap(polygons):
    """The largest area common to two of the polygons."""
    left, right = shapely.STRtree(polygons).query(polygons, predicate="intersects")
    keep = left < right
    common = shapely.intersection(np.array(polygons)[left[keep]], np.array(polygons)[right[keep]])
    return float(shapely.area(common).max(initial=0.0))


def _wrong_variant_1(tiling):
    """Blocks about the up-triangles turned only by thirds (no half turn): the tops do not tile."""
    loz = tiling.lozenges
    angle = loz[:, 2] * 2 * math.pi / 3
    out = np.tile(np.eye(4), (len(loz), 1, 1))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = np.cos(angle), -np.sin(angle), np.sin(angle), np.cos(angle)
    centre = _centroid(loz[:, :2] + UP_OFFSETS[loz[:, 2]], up=True)
    out[:, :2, 3] = centre - np.einsum("nij,j->ni", out[:, :2, :2], [0.5, -SQRT3 / 6])
    return Assembly([rhomblock()], np.zeros(len(loz), dtype=int), out)


# --- the block (Sec. 4.4, Fig. 2) ------------------------------------------------------------------------------

def test_rhomblock_has_the_papers_coordinates_and_faces():
    block = rhomblock()
    h = math.sqrt(2 / 3)
    paper = [(0, 0, 0), (0.5, SQRT3 / 2, 0), (1, 0, 0), (0.5, -SQRT3 / 2, 0), (0, 0, h), (0.5, SQRT3 / 6, h), (1, 0, h),
             (1, -SQRT3 / 3, h), (0.5, -SQRT3 / 2, h), (0, -SQRT3 / 3, h)]
    assert np.allclose(block.vertices, paper, rtol=0, atol=TOL) and np.allclose(RHOMBLOCK_VERTICES, block.vertices)
    assert RHOMBLOCK_HEIGHT == h
    assert len(RHOMBLOCK_FACES) == 16
    assert {frozenset(f) for f in (block.faces + 1).tolist()} == {frozenset(f) for f in RHOMBLOCK_FACES}
    assert block.is_watertight and block.is_winding_consistent
    assert block.volume == pytest.approx(1 / math.sqrt(2), abs=TOL)
    normals, centres = block.face_normals, block.triangles_center
    # outward: a point just off each face along its normal is outside the solid, one just behind it inside
    assert not block.contains(centres + STEP * normals).any()
    assert block.contains(centres - STEP * normals).all()


def test_rhomblock_bottom_is_a_lozenge_and_top_the_hexagon_about_its_down_triangle():
    block = rhomblock()
    bottom = block.vertices[block.vertices[:, 2] == 0][:, :2]
    top = block.vertices[block.vertices[:, 2] == RHOMBLOCK_HEIGHT][:, :2]
    lozenge = Lozenge(0, -1, 0)
    assert _points(bottom) == _points((np.array([[0, 0], [1, 0], [0, 1], [1, -1]])) @ LATTICE_BASIS)
    assert lozenge.down == (0, -1) and lozenge.up == (0, 0)
    assert _points(top) == _points(shapely.get_coordinates(_cell(0, -1, up=False)))
    assert shapely.MultiPoint(bottom).convex_hull.area == pytest.approx(SQRT3 / 2)
    assert shapely.MultiPoint(top).convex_hull.area == pytest.approx(SQRT3 / 2)
    # the top is invariant under turns by a third about the down-triangle's centre
    centre = _centroid([(0, -1)], up=False)[0]
    turn = np.array([[-0.5, -SQRT3 / 2], [SQRT3 / 2, -0.5]])
    assert _points((top - centre) @ turn.T + centre) == _points(top)


def test_variant_1_half_turn_is_the_mirror_image_across_the_shared_edge():
    """The block is symmetric under x -> 1 - x, so mirroring it across its lozenge's diagonal is a half turn."""
    block = rhomblock()
    mirror = block.copy().apply_transform(np.diag([1.0, -1.0, 1.0, 1.0]))
    half_turn = block.copy().apply_transform(rhomblock_transforms(LozengeTiling([(0, -1, 0)]), variant=1)[0])
    assert {frozenset(_points(t)) for t in mirror.triangles} == {frozenset(_points(t)) for t in half_turn.triangles}
    assert not np.allclose(half_turn.vertices, block.vertices)


# --- assemblies (Thm. 4.9, Fig. 3) --------------------------------------------------------------------------------

@pytest.mark.parametrize("variant", [0, 1])
@pytest.mark.parametrize("a, b, c, seed", HEXAGONS)
def test_blocks_do_not_overlap_and_fill_their_volume(a, b, c, seed, variant):
    tiling = random_hexagon(a, b, c, seed=seed)
    assembly = rhomblock_assembly(tiling, variant)
    assert len(assembly) == len(tiling) == a * b + b * c + c * a
    assert assembly.labels == tuple(tiling)
    assert assembly.volumes.sum() == pytest.approx(len(tiling) / math.sqrt(2), rel=TOL)
    assert overlaps(assembly) == []
    union = trimesh.boolean.union(assembly.world_meshes(), engine="manifold")
    assert union.volume == pytest.approx(len(tiling) / math.sqrt(2), rel=UNION_RTOL)


def test_overlap_check_catches_a_wrong_placement():
    """Turning the blocks of variant 1 by thirds only (no half turn) makes them collide: the check has teeth.

    The tops still tile (the top is a regular hexagon), but the bottoms are no longer the lozenges.
    """
    tiling = random_hexagon(3, 3, 3, seed=0)
    wrong = _wrong_variant_1(tiling)
    assert len(overlaps(wrong)) > 0
    tops, world = _tops(wrong)
    assert _largest_overlap(tops) < TOL
    bottoms = [_points(points[points[:, 2] == 0][:, :2]) for points in world]
    assert all(b != _points(p) for b, p in zip(bottoms, tiling.polygons()))


@pytest.mark.parametrize("variant", [0, 1])
@pytest.mark.parametrize("a, b, c, seed", HEXAGONS)
def test_tops_tile_the_hexagonal_pattern_and_bottoms_are_the_lozenges(a, b, c, seed, variant):
    tiling = random_hexagon(a, b, c, seed=seed)
    tops, world = _tops(rhomblock_assembly(tiling, variant))
    loz = tiling.lozenges
    cells = loz[:, :2] + (UP_OFFSETS[loz[:, 2]] if variant else 0)  # each block's up- (or down-) triangle
    for top, (i, j) in zip(tops, cells.tolist()):
        assert _points(shapely.get_coordinates(top)) == _points(shapely.get_coordinates(_cell(i, j, up=variant)))
    assert _largest_overlap(tops) < TOL
    union = shapely.union_all(tops, grid_size=GRID)
    assert union.area == pytest.approx(len(tiling) * SQRT3 / 2, rel=GRID_RTOL)
    kind = 0 if variant else 1  # all up- (down-) triangles of the region, each once
    region = {tuple(t) for t in tiling.triangles().tolist() if t[2] == kind}
    assert {(i, j, kind) for i, j in cells.tolist()} == region and len(region) == len(tiling)
    expected = shapely.union_all([_cell(i, j, up=variant) for i, j, _ in region], grid_size=GRID)
    assert shapely.symmetric_difference(union, expected, grid_size=GRID).area < GRID_RTOL * union.area
    for points, polygon in zip(world, tiling.polygons()):
        assert _points(points[points[:, 2] == 0][:, :2]) == _points(polygon)


@pytest.mark.parametrize("variant", [0, 1])
def test_neighbouring_blocks_touch_face_to_face(variant):
    tiling = random_hexagon(4, 3, 5, seed=4)
    assembly = rhomblock_assembly(tiling, variant)
    found = contacts(assembly)
    touching = {(c.i, c.j) for c in found}
    assert {tuple(p) for p in tiling.adjacency().tolist()} <= touching
    assert all(c.area > TOL for c in found)
    assert len(touching) > len(tiling.adjacency())  # blocks also touch across a shared corner of their lozenges


@pytest.mark.parametrize("variant", [0, 1])
@pytest.mark.parametrize("a, b, c, seed", [(3, 3, 3, 2), (4, 4, 4, 5), (5, 3, 4, 1)])
def test_theorem_4_9_patches_interlock_with_their_outer_ring_fixed(a, b, c, seed, variant):
    tiling = random_hexagon(a, b, c, seed=seed)
    assembly = rhomblock_assembly(tiling, variant, frame="boundary")
    assert assembly.frame == assembly.boundary() == tiling.boundary()
    assert check(assembly).interlocked is True


def test_fixing_only_the_blocks_with_an_edge_on_the_outline_is_not_enough():
    """A block whose lozenge meets the outline at a corner only escapes outwards; the ring must include it."""
    tiling = random_hexagon(3, 3, 3, seed=2)
    pairs = tiling.adjacency()
    degree = np.bincount(pairs.ravel(), minlength=len(tiling))
    edge_ring = np.flatnonzero(degree < 4).tolist()
    assert set(edge_ring) < set(tiling.boundary())
    verdict = check(rhomblock_assembly(tiling, 0, frame=edge_ring))
    assert verdict.interlocked is False
    assert set(verdict.moving) <= set(tiling.boundary()) - set(edge_ring)


@pytest.mark.parametrize("variant", [0, 1])
@pytest.mark.parametrize("counts", [(1, 0, 0), (1, 1, 0), (2, 0, 1), (1, 1, 1), (1, 2, 3)])
def test_periodic_tilings_give_periodic_cells(counts, variant):
    tiling = staircase(counts)
    cell = rhomblock_assembly(tiling, variant)
    assert cell.lattice is not None and len(cell) == tiling.cell_size
    assert np.allclose(cell.lattice[:, :2], tiling.periods @ LATTICE_BASIS) and not cell.lattice[:, 2].any()
    cell_area = abs(np.linalg.det(cell.lattice[:, :2]))
    assert cell_area == pytest.approx(len(cell) * SQRT3 / 2)
    # the cell repeated over a 3 x 3 window: no overlaps, tops tile
    shifts = [m * cell.lattice[0] + n * cell.lattice[1] for m, n in product(range(-1, 2), repeat=2)]
    transforms = np.concatenate([cell.transforms + np.pad(s[:, None], ((0, 1), (3, 0))) for s in shifts])
    window = Assembly(cell.meshes, np.zeros(len(transforms), dtype=int), transforms)
    assert overlaps(window) == []
    tops, _ = _tops(window)
    assert _largest_overlap(tops) < TOL
    assert shapely.union_all(tops, grid_size=GRID).area == pytest.approx(9 * cell_area, rel=GRID_RTOL)


def test_large_hexagon_builds():
    tiling = random_hexagon(20, 20, 20, seed=0)
    assembly = rhomblock_assembly(tiling, 1)
    assert len(assembly) == 1200 and len(assembly.boundary()) == len(tiling.boundary()) > 0
    assert assembly.info["variant"] == 1 and assembly.info["orientation_counts"] == [400, 400, 400]


def test_invalid_arguments_are_rejected():
    tiling = random_hexagon(2, 2, 2, seed=0)
    with pytest.raises(TilingError, match="variant must be 0 .* or 1"):
        rhomblock_assembly(tiling, 2)
    with pytest.raises(TilingError, match="needs a LozengeTiling"):
        rhomblock_assembly([(0, 0, 0)])
    with pytest.raises(InterlockError, match="frame must be None, 'boundary' or a list"):
        rhomblock_assembly(tiling, 0, frame="outer")
