"""Input checks: self-intersections in bounded memory, overlaps judged against a length tolerance."""

import tracemalloc

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock.blocks import Assembly
from interlock.errors import InterlockError
from interlock.verify import validate as module
from interlock.verify.validate import OverlapError, self_intersections


def _prism_file(folder, n):
    """An n-gon prism as an OBJ file with two n-gon caps (triangulated on reading) and n quadrilateral sides."""
    t = 2 * np.pi * np.arange(n) / n
    rows = [f"v {np.cos(a):.12f} {np.sin(a):.12f} {z}" for z in (0, 1) for a in t]
    rows.append("f " + " ".join(str(i + 1) for i in reversed(range(n))))
    rows.append("f " + " ".join(str(n + i + 1) for i in range(n)))
    rows += [f"f {i + 1} {(i + 1) % n + 1} {n + (i + 1) % n + 1} {n + i + 1}" for i in range(n)]
    path = folder / f"prism{n}.obj"
    path.write_text("\n".join(rows) + "\n")
    return path


def _all_pairs(mesh):
    """The crossing pairs by testing every pair of triangles (the definition, without a broad phase)."""
    vertices = module._unit_box(np.asarray(mesh.vertices, dtype=float))
    triangles, faces = vertices[mesh.faces], np.asarray(mesh.faces)
    a, b = np.triu_indices(len(faces), 1)
    apart = ~(faces[a][:, :, None] == faces[b][:, None, :]).any(axis=(1, 2))
    a, b = a[apart], b[apart]
    atol = module.CROSSING_RTOL * float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    crossing = module._edges_cross(triangles[a], triangles[b], atol) | module._edges_cross(triangles[b], triangles[a], atol)
    return np.column_stack([a[crossing], b[crossing]])


def _shape(kind, size, sections):
    return [trimesh.creation.box(extents=[size, 0.7 * size, 1.3 * size]), trimesh.creation.icosphere(1, size),
            trimesh.creation.cylinder(size, 2 * size, sections=sections),
            trimesh.creation.cone(size, size, sections=sections)][kind]


@settings(max_examples=30)
@given(st.lists(st.tuples(st.integers(0, 3), st.floats(0.2, 1.5), st.integers(3, 40), st.integers(0, 2**32 - 1)),
                min_size=1, max_size=3),
       st.floats(-120, 120))
def test_self_intersections_are_the_crossing_pairs_among_all_pairs(shapes, exponent):
    # the broad phase (tree, shared-vertex skips, plane sides) drops no pair that the definition counts,
    # at any scale: coordinates of 1e-120 ... 1e120 give the same pairs
    parts = []
    for kind, size, sections, seed in shapes:
        motion = trimesh.transformations.random_rotation_matrix(np.random.default_rng(seed).random(3))
        motion[:3, 3] = np.random.default_rng(seed).uniform(-1, 1, 3)
        parts.append(_shape(kind, size, sections).apply_transform(motion))
    mesh = trimesh.util.concatenate(parts)
    mesh.vertices *= 10.0**exponent
    found = self_intersections(mesh)
    expected = _all_pairs(mesh)
    assert found.tolist() == sorted(expected.tolist())
    if len(parts) == 1:
        assert len(found) == 0


def test_triangles_that_cross_are_found_and_shared_corners_are_not():
    cube = trimesh.creation.box()
    shifted = trimesh.util.concatenate([cube, cube.copy().apply_translation([0.5, 0.3, 0.2])])
    assert len(self_intersections(shifted)) > 0
    fan = trimesh.creation.cylinder(1.0, 1.0, sections=500)  # 500 long triangles meeting at each cap's centre
    assert len(self_intersections(fan)) == 0


@pytest.mark.parametrize("n", [2000, 8000])
def test_long_triangles_are_checked_in_bounded_memory(tmp_path, n):
    # issue 40: an n-gon prism (two caps of long triangles) took 2.4 GB at n = 2,000 and 9.4 GB at 4,000
    # (a k-d tree query with the longest triangle as the radius pairs every cap triangle with the whole cap)
    assembly = Assembly.load(_prism_file(tmp_path, n))
    tracemalloc.start()
    try:
        module.validate(assembly)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 300e6, f"validate of a {n}-gon prism peaked at {peak / 1e6:.0f} MB"


def _fan_prism(n):
    """An n-gon prism whose caps are fans from one corner (as CAD exports triangulate them): long slivers."""
    t = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(t), np.sin(t)])
    vertices = np.vstack([np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.ones(n)])])
    k = np.arange(1, n - 1)
    i, j = np.arange(n), (np.arange(n) + 1) % n
    faces = np.vstack([np.column_stack([np.zeros(n - 2, dtype=int), k + 1, k]), np.column_stack([np.full(n - 2, n), n + k, n + k + 1]),
                       np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i])])
    return trimesh.Trimesh(vertices, faces, process=False)


@pytest.mark.parametrize("turned", [False, True])
def test_caps_of_long_slivers_are_not_paired_with_every_side(monkeypatch, turned):
    # each sliver's box holds a whole arc of the sides: a box test pairs them quadratically (a 20,000-gon took
    # 144 s); nodes lying in one plane are dropped against boxes on one side of it, in the principal axes
    prism = _fan_prism(1000)
    if turned:
        prism.apply_transform(trimesh.transformations.random_rotation_matrix(np.random.default_rng(0).random(3)))
    paired = []
    candidates = module._candidate_pairs

    def counted(*args):
        for a, b in candidates(*args):
            paired.append(len(a))
            yield a, b

    monkeypatch.setattr(module, "_candidate_pairs", counted)
    assert len(self_intersections(prism)) == 0 and prism.is_volume
    assert sum(paired) < 10 * len(prism.faces)


def test_huge_coordinates_are_refused_with_a_clear_error():
    # issue 40: coordinates of 1e200 made cKDTree.query_pairs raise a bare ValueError about "p too large"
    boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1)]
    for box in boxes:
        box.vertices *= 1e200
    refused = r"block 1 reaches 2\.45e\+200 from the origin: beyond 1e\+100 .*\(scale it down\)"
    with pytest.raises(InterlockError, match=refused):
        Assembly.from_meshes(boxes)
    far = trimesh.creation.box()
    far.vertices *= 1e300  # one mesh alone is checked at any finite size
    assert len(self_intersections(far)) == 0
    broken = trimesh.creation.box()
    broken.vertices[0] = np.inf
    with pytest.raises(OverlapError, match="non-finite"):
        self_intersections(broken)


def _retriangulated(mesh, rng):
    """The same solid on other triangles: points inside triangles, edges split, triangles cut in four (leaving
    T-junctions for the reader to split), about one change for every two triangles."""
    vertices, faces = [np.asarray(v, dtype=float) for v in mesh.vertices], [tuple(f) for f in mesh.faces]
    for _ in range(max(1, len(faces) // 2)):
        k = int(rng.integers(len(faces)))
        a, b, c = faces[k]
        kind = rng.integers(3)
        if kind == 0:
            w = rng.dirichlet([1, 1, 1])
            vertices.append(w[0] * vertices[a] + w[1] * vertices[b] + w[2] * vertices[c])
            m = len(vertices) - 1
            faces[k] = (a, b, m)
            faces += [(b, c, m), (c, a, m)]
        elif kind == 1:
            s = rng.uniform(0.2, 0.8)
            vertices.append((1 - s) * vertices[a] + s * vertices[b])
            m = len(vertices) - 1
            for q, (x, y, z) in enumerate(list(faces)):
                for p0, p1, p2 in ((x, y, z), (y, z, x), (z, x, y)):
                    if {p0, p1} == {a, b}:
                        faces[q] = (p0, m, p2)
                        faces.append((m, p1, p2))
                        break
        else:
            vertices += [(vertices[a] + vertices[b]) / 2, (vertices[b] + vertices[c]) / 2, (vertices[c] + vertices[a]) / 2]
            ab, bc, ca = len(vertices) - 3, len(vertices) - 2, len(vertices) - 1
            faces[k] = (a, ab, ca)
            faces += [(ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return np.array(vertices), np.array(faces)


def _obj(path, pieces):
    rows, base = [], 1
    for k, (vertices, faces) in enumerate(pieces):
        rows.append(f"o part_{k}")
        rows += ["v %.17g %.17g %.17g" % tuple(v) for v in vertices]
        rows += ["f %d %d %d" % tuple(f + base) for f in faces]
        base += len(vertices)
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def bunny(reference_data):
    paths = sorted((reference_data / "topolite" / "bunny").glob("part_*.obj"), key=lambda p: int(p.stem[5:]))
    return Assembly.load(paths)


def test_a_retriangulated_bunny_touches_within_the_input_precision(bunny, tmp_path):
    # issue 35: re-triangulating the bunny's parts (faces where they were) was refused as "overlap" in most copies:
    # manifold3d's volumes err by ~1 % on blocks whose edges are shared by four triangles
    meshes = [bunny.mesh(i) for i in range(len(bunny))]
    for seed in range(4):
        rng = np.random.default_rng(seed)
        copy = Assembly.load(_obj(tmp_path / f"copy{seed}.obj", [_retriangulated(m, rng) for m in meshes]))
        found = module.validate(copy, depth=1e-9 * copy.scale)
        assert all(o.depth <= 1e-9 * copy.scale for o in found if o.depth is not None)


def test_a_real_overlap_is_refused_within_the_input_precision(bunny):
    meshes = [bunny.mesh(i) for i in range(len(bunny))]
    neighbour = min(bunny.neighbours[10])
    towards = bunny.centroids[neighbour] - bunny.centroids[10]
    meshes[10].apply_translation(1e-3 * towards / np.linalg.norm(towards))  # 1e-3 into a neighbour
    moved = Assembly.from_meshes(meshes)
    with pytest.raises(OverlapError, match=r"overlap: the surface of one reaches .* inside the other .* deeper than "
                                           r"the tolerance"):
        module.validate(moved, depth=1e-9 * moved.scale)
    with pytest.raises(OverlapError, match=r"deeper than the tolerance"):  # one length per block
        module.validate(moved, depth=np.full(len(moved), 1e-9 * moved.scale))


def test_a_block_grown_below_the_volume_rule_passes_with_its_measured_depth(bunny):
    # 2e-4 of the part's size: a common volume far below the volume rule, left to the contacts to judge
    # (refuse_overlaps_without_contact), now with the depth measured rather than the boolean's mean depth
    meshes = [bunny.mesh(i) for i in range(len(bunny))]
    centre = meshes[10].centroid.copy()
    meshes[10].apply_translation(-centre).apply_scale(1.0002).apply_translation(centre)
    grown = Assembly.from_meshes(meshes)
    found = module.validate(grown, depth=1e-9 * grown.scale)
    deepest = max((o for o in found if 10 in (o.i, o.j)), key=lambda o: o.deepness)
    assert deepest.depth is not None and deepest.depth > 1e-5
    with pytest.raises(OverlapError, match="without a face of one lying on a face of the other"):
        module.refuse_overlaps_without_contact(grown, found, [], 1e-9 * grown.scale)


@settings(max_examples=25)
@given(st.floats(0.0, 0.1), st.integers(0, 2**32 - 1), st.floats(-3, 3))
def test_penetration_of_a_box_moved_into_another_is_the_move(offset, seed, exponent):
    # between parallel faces the signed depths add up to the move, at any placement and scale (where the move is
    # thinner than the boxes' other sides, so the two moved faces are the nearest ones)
    size = 10.0**exponent
    motion = trimesh.transformations.random_rotation_matrix(np.random.default_rng(seed).random(3))
    motion[:3, 3] = np.random.default_rng(seed).uniform(-5, 5, 3) * size
    first = trimesh.creation.box(bounds=np.array([[0, 0, 0], [1, 1, 1]]) * size).apply_transform(motion)
    second = trimesh.creation.box(bounds=np.array([[1 - offset, 0.2, 0.1], [2, 0.9, 0.7]]) * size)
    second.apply_transform(motion)
    assert module.penetration(first, second) == pytest.approx(offset * size, abs=1e-9 * size)


def test_depth_must_be_a_length_or_one_per_block():
    boxes = Assembly.from_meshes([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1)])
    for bad in (float("nan"), -1.0, float("inf"), [0.1], [0.1, 0.1, 0.1], "1e-6"):
        with pytest.raises(OverlapError, match=r"depth must be a finite length >= 0, or one per block \(2 of them\)"):
            module.validate(boxes, depth=bad)
    assert module.validate(boxes, depth=[0.0, 1e-9]) == []


@pytest.mark.parametrize("offset", [0.0, 1e-3])
def test_a_mirrored_neighbour_is_measured_in_its_own_frame(offset):
    # block 1 is block 0 mirrored about the plane x = 1 - offset / 2: it reaches offset into block 0
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    mirror[0, 3] = 2.0 - offset
    pair = Assembly([trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])], [0, 0], [np.eye(4), mirror])
    found = module.validate(pair, depth=2e-3)
    assert [o.depth for o in found if o.depth is not None] == ([pytest.approx(offset, abs=1e-12)] if offset else [])
    if offset:
        with pytest.raises(OverlapError, match="reaches 0.001 inside the other"):
            module.validate(pair, depth=5e-4)


def test_a_crossing_within_the_rounding_is_the_files_not_the_solids():
    """TopoLite's SphereA80 shell written with 6 significant digits (coordinates up to 27 cut to 1e-3): block 14's
    slivers fold through a neighbouring triangle by up to 7e-4, within the rounding of 5e-4 per coordinate.  Without a
    depth that is a self-intersection; with the input's precision as depth it passes, and the shell is decided as
    its original (not interlocked)."""
    from benchmarks.real_files import perturbed
    from interlock import check

    rounded = perturbed("TI SphereA80_Hex_T40.0", 0, "6 digits")
    with pytest.raises(OverlapError, match="block 14 .* intersects itself"):
        module.validate(rounded)
    with pytest.raises(OverlapError, match="cross by more than 5e-05"):
        module.validate(rounded, depth=1e-4)
    assert module.validate(rounded, depth=2e-3) is not None  # a pair may reach 2e-3, a block 1e-3 into itself
    assert check(rounded).interlocked is False
