"""The paper's example assemblies: coordinates, counts, contacts and non-overlap (Ex. 3.5-3.7, Fig. 1, 4-7, 9-11)."""

import math
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest
import shapely
import trimesh

from interlock import InterlockError, wallpaper
from interlock.blocks import patch, presets
from interlock.blocks.contact import Contact
from interlock.blocks.presets import (
    CUBE_VERTICES,
    TETRAHEDRA_SYMMETRIES,
    PresetError,
    block_on_pins,
    cube_grid,
    cube_grid_cell,
    fig1_p6_block,
    interlocking_cubes,
    interlocking_cubes_cell,
    modified_cube,
    modified_cube_assembly,
    tetrahedra,
    versatile_blocks,
)
from interlock.verify.contacts import contacts

#: Intersections of touching blocks must be empty up to this fraction of a block's volume.
OVERLAP_RTOL = 1e-9
#: manifold3d leaves ~3e-8 of relative volume between faces that share a plane in general position
#: (the rotated tetrahedra), so convex blocks are tested exactly instead: a separating axis, within this.
PLANE_TOL = 1e-12
#: Snapping grid for the shapely overlays of mid-height sections.
GRID = 1e-9
#: A finite step that must (or must not) create an overlap.
STEP = 0.3
#: Relative overlap volume that is clearly a collision, not round-off.
COLLISION = 1e-3

# A^T of main paper Ex. 3.5: one column (-(p x n), -n) per vertex p of the middle cube's contact squares.
EXAMPLE_3_5_AT = [
    [0, 0, 0, 0, 1, 0, 0, 1, 0, -1, 0, -1, 0, 0, 0, 0],
    [1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, -1, 0, 0, -1],
    [0, 0, -1, -1, 0, 0, -1, -1, 0, 0, 1, 1, 1, 1, 0, 0],
    [1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, -1, -1, -1, -1],
    [0, 0, 0, 0, -1, -1, -1, -1, 1, 1, 1, 1, 0, 0, 0, 0],
    [0] * 16,
]
# A^T of main paper Ex. 3.6 (the middle cube moved by v1 + v2 = (0, 3, 3)).
EXAMPLE_3_6_AT = [
    [-3, -3, -4, -4, 4, 4, 5, 5, 0, 0, 0, 0, 0, 0, 0, 0, 4, 4, 3, 3, -5, -5, -4, -4],
    [0, 0, 0, 0, 0, 0, 0, 0, 3, 3, 4, 4, -4, -4, -5, -5, 0, -1, -1, 0, 1, 2, 2, 1],
    [1, 2, 2, 1, 0, -1, -1, 0, -5, -4, -4, -5, 4, 3, 3, 4, 0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0],
    [1, 1, 1, 1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, -1, -1, -1, -1],
]
EX_3_6_CUBE = [(0, 0, 2), (0, 0, 0), (0, 2, 0), (0, 2, 2), (2, 2, 2), (2, 2, 0), (2, 0, 0), (2, 0, 2)]
V1, V2 = np.array([1, 1, 2]), np.array([-1, 2, 1])
AXES = {(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)}


# --- Ex. 3.5, Fig. 4a, 9: the cube grid ------------------------------------------------------


def test_example_3_5_middle_cube_is_the_papers_vertex_list():
    grid = cube_grid()
    middle = grid.labels.index((1, 1))
    np.testing.assert_array_equal(grid.mesh(middle).vertices, CUBE_VERTICES)
    assert CUBE_VERTICES == ((0, 0, 1), (0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0), (1, 0, 0), (1, 0, 1))
    shifts = {tuple(t[:3, 3].astype(int)) for t in grid.transforms}
    assert shifts == {(x, y, 0) for x in (-1, 0, 1) for y in (-1, 0, 1)}
    assert np.all(grid.transforms[:, :3, :3] == np.eye(3))


def test_example_3_5_counts_and_frame():
    grid = cube_grid()
    assert len(grid) == 9 and len(grid.meshes) == 1
    assert grid.frame == grid.boundary() == tuple(k for k in range(9) if k != 4)
    assert grid.meshes[0].is_watertight
    np.testing.assert_allclose(grid.volumes, 1.0)
    assert grid.info["preset"] == "cube_grid" and "Ex. 3.5" in grid.info["figure"]


def test_example_3_5_contacts_give_the_papers_matrix():
    grid = cube_grid()
    found = contacts(grid)
    assert len(found) == 12  # the 12 shared squares of a 3 x 3 grid; diagonal cubes touch in edges only
    middle = [c for c in found if 4 in (c.i, c.j)]
    assert len(middle) == 4  # the middle cube has exactly 4 contact faces
    assert {tuple(_outward_normal(c, 4).round(12)) for c in middle} == {(-1, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0)}
    assert all(c.area == pytest.approx(1.0) for c in middle)
    assert _rows(middle, 4) == _columns(EXAMPLE_3_5_AT)
    # the kernel element (0,0,0,0,0,1) of Ex. 3.5: every row is orthogonal to a vertical translation
    assert all(row[5] == 0 for row in _rows(middle, 4))


def test_cube_grid_other_sizes():
    grid = cube_grid(rows=4, cols=5, size=0.5)
    assert len(grid) == 20 and len(grid.frame) == 14
    np.testing.assert_allclose(grid.volumes, 0.125)
    lo, hi = grid.bounds[:, 0].min(axis=0), grid.bounds[:, 1].max(axis=0)
    np.testing.assert_allclose(hi - lo, [2.5, 2.0, 0.5])
    assert len(contacts(grid)) == 4 * 4 + 3 * 5  # shared squares along x and along y
    assert cube_grid(rows=2, cols=3).frame == tuple(range(6))  # no inner cube
    _assert_no_overlaps(grid)


def test_cube_grid_cell_repeats_to_the_grid():
    cell = cube_grid_cell(size=2.0)
    assert len(cell) == 1 and cell.info["preset"] == "cube_grid_cell"
    np.testing.assert_array_equal(cell.lattice, [[2, 0, 0], [0, 2, 0]])
    grid = cube_grid(size=2.0)
    for t in grid.transforms:  # every cube of the grid is the cell moved by a lattice vector
        coefficients = np.linalg.lstsq(cell.lattice.T, t[:3, 3], rcond=None)[0]
        np.testing.assert_allclose(coefficients, np.round(coefficients), atol=1e-12)


# --- Ex. 3.6, Fig. 4b, 10: the interlocking cube layer ---------------------------------------


def test_example_3_6_cube_coordinates_and_translations():
    layer = interlocking_cubes()
    np.testing.assert_array_equal(layer.meshes[0].vertices, EX_3_6_CUBE)
    assert len(layer) == 9 and layer.frame == (0, 1, 2, 3, 5, 6, 7, 8)
    for (i, j), t in zip(layer.labels, layer.transforms):
        np.testing.assert_array_equal(t[:3, 3], i * V1 + j * V2)
    middle = layer.labels.index((1, 1))
    np.testing.assert_array_equal(layer.mesh(middle).bounds, [[0, 3, 3], [2, 5, 5]])
    np.testing.assert_allclose(layer.volumes, 8.0)


def test_example_3_6_middle_cube_contacts_are_fig_10b():
    layer = interlocking_cubes()
    middle = [c for c in contacts(layer) if 4 in (c.i, c.j)]
    assert len(middle) == 6  # one unit square on each face of the middle cube
    assert {tuple(_outward_normal(c, 4).round(12)) for c in middle} == AXES
    assert all(c.area == pytest.approx(1.0) for c in middle)
    assert _rows(middle, 4) == _columns(EXAMPLE_3_6_AT)
    _assert_no_overlaps(layer)


def test_example_3_6_midsection_is_a_regular_hexagon():
    # "the midsection of each cube ... is given by a hexagon" (Sec. 3, Fig. 4b)
    layer = interlocking_cubes()
    normal = np.cross(V1, V2)
    section = layer.mesh(4).section(plane_origin=layer.centroids[4], plane_normal=normal)
    planar, _ = section.to_2D()
    hexagon = planar.polygons_full[0].simplify(GRID)  # drop the points where triangle edges cross
    ring = np.asarray(hexagon.exterior.coords)[:-1]
    assert len(ring) == 6
    sides = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1)
    np.testing.assert_allclose(sides, math.sqrt(2))
    assert hexagon.area == pytest.approx(3 * math.sqrt(3))  # regular hexagon of side sqrt 2


def test_interlocking_cubes_cell_and_other_sizes():
    cell = interlocking_cubes_cell()
    np.testing.assert_array_equal(cell.lattice, [V1, V2])
    np.testing.assert_array_equal(cell.meshes[0].vertices, EX_3_6_CUBE)
    big = interlocking_cubes(rows=4, cols=5)
    assert len(big) == 20 and len(big.frame) == 14
    inner = [k for k in range(20) if k not in big.frame]
    counts = Counter(k for c in contacts(big) for k in (c.i, c.j))
    assert all(counts[k] == 6 for k in inner)


# --- Fig. 5: tetrahedra -------------------------------------------------------------------------


@pytest.fixture(scope="module", params=TETRAHEDRA_SYMMETRIES)
def layer(request):
    return tetrahedra(request.param)


def test_fig_5_tetrahedra_shape(layer):
    mesh = layer.meshes[0]
    assert len(layer.meshes) == 1 and mesh.is_watertight and len(mesh.vertices) == 4
    edges = np.linalg.norm(mesh.vertices[:, None] - mesh.vertices[None], axis=-1)[np.triu_indices(4, 1)]
    if layer.info["group"] == "p4":  # Fig. 5a: regular, edge sqrt 2
        np.testing.assert_allclose(edges, math.sqrt(2))
    else:  # Fig. 5b, c: non-regular
        assert np.ptp(edges) > 0.1
    # one horizontal edge at z = 0 and one at z = 1
    assert sorted(mesh.vertices[:, 2].round(12)) == [0, 0, 1, 1]


def test_fig_5_mid_sections_tile_the_disc_and_fill_two_thirds(layer):
    sections = [_mid_section(layer.mesh(k)) for k in range(len(layer))]
    areas = shapely.area(sections)
    np.testing.assert_allclose(areas, areas[0], rtol=1e-9)
    union = shapely.unary_union(shapely.set_precision(sections, GRID))  # GEOS mis-overlays 1e-17 noise
    assert union.area == pytest.approx(areas.sum(), rel=1e-7)  # no two sections overlap
    disc = shapely.Point(0, 0).buffer(layer.info["radius"], quad_segs=64)
    assert disc.difference(union).area <= 1e-9 * disc.area  # the kept sections cover the disc
    # tetrahedron between two opposite edges: volume = 2/3 mid-section area x height
    np.testing.assert_allclose(layer.volumes, 2 / 3 * areas * layer.info["height"], rtol=1e-9)
    group = wallpaper.group(layer.info["group"])
    blocks_per_cell = group.cell_area / areas[0]
    assert blocks_per_cell == pytest.approx({"p4": 2, "p3": 3, "p6": 3}[group.name])


def test_fig_5_symmetry(layer):
    group = wallpaper.group(layer.info["group"])
    blocks = _vertex_sets(layer.world_meshes(), np.eye(3))
    for r in group.coset_representatives():  # the point group about the origin maps the patch to itself
        assert _vertex_sets(layer.world_meshes(), r) == blocks
    # p4 and p6 blocks sit on 2-fold centres and have a 2-fold axis; the p3 block is skew (else p6)
    block = layer.meshes[0]
    half_turn = _rotation(math.pi)
    half_turn[:2, 2] = 2 * block.vertices[:, :2].mean(axis=0)
    assert (_vertex_sets([block], half_turn) == _vertex_sets([block], np.eye(3))) == (group.name != "p3")


def test_fig_5_contacts_and_frame(layer):
    found = contacts(layer)
    counts = Counter(k for c in found for k in (c.i, c.j))
    # every block touches the four neighbours across its tile's edges in one tilted face each
    ring = layer.boundary()
    assert set(ring) == {k for k in range(len(layer)) if counts[k] < 4}
    assert 0 < len(ring) < len(layer) and set(ring) <= set(layer.frame)
    assert all(counts[k] == 4 for k in range(len(layer)) if k not in ring)
    assert all(0 < abs(c.normal[2]) < 1 for c in found)
    face_areas = {round(a, 9) for a in layer.meshes[0].area_faces}
    assert all(round(2 * c.area, 9) in face_areas for c in found)  # each contact is half a face
    if layer.info["group"] == "p4":
        assert all(c.area == pytest.approx(math.sqrt(3) / 4) for c in found)


def test_fig_5_no_overlaps(layer):
    meshes = layer.world_meshes()
    for i, j in layer.neighbours.edges:
        assert _separated(meshes[i], meshes[j]), (i, j)
    moved = meshes[0].copy().apply_translation((STEP / 6, STEP / 6, 0))  # the test can fail
    assert not all(_separated(moved, meshes[j]) for j in layer.neighbours[0])


# --- Fig. 6, 7: modified cubes -------------------------------------------------------------------


def test_fig_6_modified_cube():
    block = modified_cube()
    assert block.is_watertight and block.is_winding_consistent and block.volume == pytest.approx(1.0)
    assert len(block.vertices) == 10 and len(block.faces) == 16
    assert block.contains([[1.2, 0.5, 0.5]])[0]  # inside the added pyramid on x = 1
    assert not block.contains([[0.5, 0.8, 0.5]])[0]  # inside the pyramid removed from y = 1
    other = modified_cube(size=2.0, pyramid_height=0.3)
    assert other.volume == pytest.approx(8.0) and other.bounds[1, 0] == pytest.approx(2.3)


def test_fig_7_groups_of_four_move_together():
    a = modified_cube_assembly()
    assert len(a) == 16 and len(a.frame) == 12
    group = [k for k in range(16) if k not in a.frame]
    assert [a.labels[k] for k in group] == [(1, 1), (1, 2), (2, 1), (2, 2)]
    _assert_no_overlaps(a)
    found = contacts(a)
    counts = Counter(k for c in found for k in (c.i, c.j))
    assert all(counts[k] == 10 for k in group)  # 4 pyramid triangles, 4 hole triangles, 2 flat squares
    to_frame = [c for c in found if (c.i in group) != (c.j in group)]
    inside = [c for c in found if c.i in group and c.j in group]
    assert to_frame and all(abs(c.normal[2]) < 1e-12 for c in to_frame)  # flat: (0,0,t) slides
    for k in group:  # but each block alone is held from above and below by the pyramids
        z = [_outward_normal(c, k)[2] for c in inside if k in (c.i, c.j)]
        assert min(z) < 0 < max(z)
    meshes = a.world_meshes()
    lifted = [meshes[k].copy().apply_translation((0, 0, STEP)) for k in group]
    for m in lifted:  # the four together: no collision with the frame (Fig. 7c)
        assert all(_overlap(m, meshes[f]) <= OVERLAP_RTOL for f in a.frame)
    alone = lifted[0]  # one alone: collides with its group
    assert max(_overlap(alone, meshes[k]) for k in group[1:]) > COLLISION


# --- Ex. 3.7, Fig. 11: Versatile Blocks -------------------------------------------------------------


def test_example_3_7_versatile_blocks_share_the_papers_triangle():
    pair = versatile_blocks()
    assert pair.frame == (0,) and len(pair.meshes) == 1 and pair.meshes[0].is_watertight
    assert not pair.mirrored.any()  # two copies, not mirror images
    right = {tuple(v) for v in pair.mesh(1).vertices}
    assert right == {(0, 0, 0), (1, 1, 0), (2, 0, 0), (1, -1, 0), (0, 1, 1), (1, 1, 1), (1, 0, 1), (1, -1, 1), (0, -1, 1)}
    assert pair.volumes[0] == pytest.approx(pair.volumes[1])
    (contact,) = contacts(pair)
    assert (contact.i, contact.j) == (0, 1)
    np.testing.assert_allclose(contact.normal, [1, 0, 0], atol=1e-12)  # towards the right block
    assert {tuple(p) for p in contact.vertices.round(12) + 0.0} == {(0, 0, 0), (0, -1, 1), (0, 1, 1)}
    assert contact.area == pytest.approx(1.0)
    # Ex. 3.7: (p x n, n) . gamma'(0) >= 0 at the three points, = 0 at (0, -1, 1) and (0, 1, 1)
    velocity = np.array([0, -1, 0, 1, 0, 2])  # as printed; d/dt of gamma's translation at 0 is (1, 0, 1)
    t = 1e-6  # the printed z-entry 2 is a misprint: differentiate gamma(t) itself
    assert (math.cos(t) * (t - 1) + 1 - 0) / t == pytest.approx(1, abs=1e-5)
    values = {tuple(np.round(p, 9) + 0.0): np.r_[np.cross(p, contact.normal), contact.normal] @ velocity
              for p in contact.vertices}
    assert values[(0, -1, 1)] == pytest.approx(0) and values[(0, 1, 1)] == pytest.approx(0)
    assert values[(0, 0, 0)] > 0
    derived = velocity - [0, 0, 0, 0, 0, 1]  # the true gamma'(0) satisfies the same (in)equalities
    assert [np.r_[np.cross(p, contact.normal), contact.normal] @ derived for p in contact.vertices] == \
        pytest.approx([values[tuple(np.round(p, 9) + 0.0)] for p in contact.vertices])


@pytest.mark.parametrize("t", [0.25, 0.5, 1.0])
def test_example_3_7_gamma_moves_the_right_block_without_collision(t):
    pair = versatile_blocks()
    c, s = math.cos(t), math.sin(t)
    gamma = np.array([[c, 0, -s, -s * (t - 1)], [0, 1, 0, 0], [s, 0, c, c * (t - 1) + 1], [0, 0, 0, 1]])
    assert _overlap(pair.mesh(0), pair.mesh(1).apply_transform(gamma)) <= OVERLAP_RTOL
    pushed = pair.mesh(1).apply_translation((-t / 4, 0, 0))  # the test can fail
    assert _overlap(pair.mesh(0), pushed) > COLLISION


# --- Fig. 1: the p6 block -----------------------------------------------------------------------------


def test_fig_1_p6_block_deforms_every_edge_once():
    block = fig1_p6_block(height=2.0)
    assert block.group.name == "p6" and block.deformed_edges == {0, 1, 2, 3}
    assert all(len(points) == 1 for points in block.deformation.values())
    assert block.mesh.is_watertight and block.mesh.bounds[1, 2] == pytest.approx(2.0)
    assert block.volume == pytest.approx(block.bottom.area * 2.0)
    p = patch(block, 0.5)
    _assert_no_overlaps(p)
    assert Counter(k for c in contacts(p) for k in (c.i, c.j))[0] >= 6


# --- bad input -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("call, words", [
    (lambda: cube_grid(rows=0), "rows must be an integer >= 1"),
    (lambda: cube_grid(cols=2.5), "cols must be an integer >= 1"),
    (lambda: cube_grid(rows=True), "rows must be an integer >= 1"),
    (lambda: cube_grid(size=0), "size must be > 0"),
    (lambda: cube_grid_cell(size=float("nan")), "size must be a finite real number"),
    (lambda: interlocking_cubes(cols=-1), "cols must be an integer >= 1"),
    (lambda: tetrahedra("p5"), "unknown symmetry 'p5' for the tetrahedra of Fig. 5; choose one of p4, p3, p6"),
    (lambda: tetrahedra("p4", radius=-1), "radius must be >= 0"),
    (lambda: tetrahedra("p6", radius=math.inf), "radius must be a finite real number"),
    (lambda: tetrahedra("p3", center=(0, 0, 0)), "center must be a finite point"),
    (lambda: modified_cube(pyramid_height=1.0), "pyramid_height must lie strictly between 0 and the cube's side"),
    (lambda: modified_cube(size=-1), "size must be > 0"),
    (lambda: modified_cube_assembly(rows=0), "rows must be an integer >= 1"),
    (lambda: fig1_p6_block(height=0), "height must be > 0"),
    (lambda: block_on_pins(h=0), "h must be > 0"),
    (lambda: block_on_pins(h=1.0, c=0.5), "the valley must stay above the bottom face: h c > 1"),
])
def test_bad_input_is_rejected_with_a_clear_message(call, words):
    with pytest.raises(PresetError, match=words.replace(".", r"\.").replace("(", r"\(")) as error:
        call()
    assert isinstance(error.value, InterlockError) and isinstance(error.value, ValueError)


# --- the package ---------------------------------------------------------------------------------------


def test_every_public_name_is_exported_from_the_package():
    assert len(set(presets.__all__)) == len(presets.__all__)
    for name in presets.__all__:
        value = getattr(presets, name)
        assert not isinstance(value, type(presets)), name  # a function, not a submodule of the same name
        assert getattr(value, "__module__", "interlock.blocks.presets").startswith("interlock.blocks.presets"), name


def test_block_on_pins_makes_block_contacts_without_importing_verify():
    cup = block_on_pins()
    assert all(isinstance(c, Contact) for c in cup.info["contacts"]) and len(cup) == 8
    code = ("import sys; from interlock.blocks import presets; presets.block_on_pins(); "
            "print(sorted(m for m in sys.modules if m.startswith('interlock.verify')))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"  # blocks do not build on verify


# --- helpers -------------------------------------------------------------------------------------------


def _outward_normal(contact, k):
    """The contact normal pointing out of block ``k``."""
    return contact.normal if contact.i == k else -contact.normal


def _rows(found, k):
    """Rows (-(p x n), -n) of block ``k`` (Def. 3.3 with n the outer normal of k), as a sorted list."""
    rows = []
    for c in found:
        n = _outward_normal(c, k)
        rows += [tuple(np.round(np.r_[-np.cross(p, n), -n], 9) + 0.0) for p in c.vertices]
    return sorted(rows)


def _columns(matrix_t):
    return sorted(tuple(float(x) for x in column) for column in zip(*matrix_t))


def _overlap(a, b):
    """Intersection volume relative to the smaller block."""
    with np.errstate(invalid="ignore", divide="ignore"):  # empty intersections have no centre of mass
        common = trimesh.boolean.intersection([a, b], engine="manifold")
        return common.volume / min(a.volume, b.volume)


def _assert_no_overlaps(assembly):
    meshes = assembly.world_meshes()
    for i, j in assembly.neighbours.edges:
        assert _overlap(meshes[i], meshes[j]) <= OVERLAP_RTOL, (i, j)


def _separated(a, b):
    """Whether two convex meshes have disjoint interiors: a separating axis exists (face normals, edge crosses)."""
    crosses = np.cross(_edge_vectors(a)[:, None], _edge_vectors(b)[None]).reshape(-1, 3)
    axes = np.vstack([a.face_normals, b.face_normals, crosses])
    axes = axes[np.linalg.norm(axes, axis=1) > PLANE_TOL]
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    pa, pb = a.vertices @ axes.T, b.vertices @ axes.T
    gap = np.maximum(pb.min(axis=0) - pa.max(axis=0), pa.min(axis=0) - pb.max(axis=0))
    return bool(gap.max() >= -PLANE_TOL)


def _mid_section(mesh):
    section = mesh.section(plane_origin=(0, 0, 0.5), plane_normal=(0, 0, 1))
    return shapely.Polygon(section.discrete[0][:, :2])


def _rotation(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _vertex_sets(meshes, plane_map):
    """Blocks as sets of rounded vertices after the plane affine map ``plane_map`` (3x3, acting on x, y)."""
    out = set()
    for mesh in meshes:
        xy = mesh.vertices[:, :2] @ plane_map[:2, :2].T + plane_map[:2, 2]
        out.add(frozenset(map(tuple, np.round(np.c_[xy, mesh.vertices[:, 2]], 6) + 0.0)))
    return out


def _edge_vectors(mesh):
    return np.diff(mesh.vertices[mesh.edges_unique], axis=1)[:, 0]


def test_fig_5a_default_frame_is_the_red_p4_frame_and_interlocks():
    from interlock.verify import check

    layer = tetrahedra("p4", radius=1.5)
    along_x = {k for k in range(len(layer)) if abs(layer.transforms[k][0, 0]) > 0.5}
    assert set(layer.frame) == along_x | set(layer.boundary())
    assert check(layer).interlocked is True
    assert tetrahedra("p4", radius=1.5, frame="boundary").frame == layer.boundary()
    assert tetrahedra("p6", radius=1.0).frame == tetrahedra("p6", radius=1.0).boundary()  # no frame drawn
    with pytest.raises(PresetError, match="frame must be 'figure', 'boundary'"):
        tetrahedra("p4", frame="red")


# --- the tetrahedral-octahedral honeycomb layer -----------------------------------------------------------


@pytest.mark.parametrize("radius", [1.0, 2.0])
def test_honeycomb_layer_is_the_tet_oct_honeycomb_between_two_planes(radius):
    layer = presets.honeycomb_layer(radius)
    assert set(layer.types.tolist()) == {0, 1, 2}  # tetrahedra standing up, hanging down, and octahedra
    volumes = [float(m.volume) for m in layer.meshes]
    assert volumes[0] == pytest.approx(math.sqrt(2) / 12) and volumes[1] == pytest.approx(math.sqrt(2) / 12)
    assert volumes[2] == pytest.approx(math.sqrt(2) / 3)  # the regular octahedron of edge 1: four tetrahedra
    for mesh in layer.meshes:
        assert mesh.is_watertight and mesh.volume > 0
        lengths = np.linalg.norm(_edge_vectors(mesh), axis=1)
        assert np.allclose(lengths, 1.0)  # regular solids of edge 1
    z = np.concatenate([m.vertices[:, 2] for m in layer.world_meshes()])
    assert z.min() == pytest.approx(0.0, abs=1e-12) and z.max() == pytest.approx(presets.HONEYCOMB_HEIGHT)
    meshes = layer.world_meshes()
    for i, j in layer.neighbours.edges:
        assert _separated(meshes[i], meshes[j]), (i, j)
    # inside the layer every tetrahedron shares its three slanted faces with octahedra, every octahedron six
    found = contacts(layer)
    degree = Counter(k for c in found for k in (c.i, c.j))
    inner = [k for k in range(len(layer)) if k not in layer.frame]
    assert all(degree[k] == (6 if layer.types[k] == 2 else 3) for k in inner)
    assert set(layer.frame) == set(layer.boundary())


def test_honeycomb_layer_frame_and_bad_input():
    assert presets.honeycomb_layer(1.0, frame=None).frame == ()
    assert presets.honeycomb_layer(1.0, frame=[0]).frame == (0,)
    with pytest.raises(PresetError, match="radius must be >= 0"):
        presets.honeycomb_layer(-1)
    with pytest.raises(PresetError, match="frame must be 'boundary'"):
        presets.honeycomb_layer(1.0, frame="ring")
