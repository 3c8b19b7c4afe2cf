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


def test_huge_coordinates_are_refused_with_a_clear_error():
    # issue 40: coordinates of 1e200 made cKDTree.query_pairs raise a bare ValueError about "p too large"
    boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1)]
    for box in boxes:
        box.vertices *= 1e200
    with np.errstate(all="ignore"):
        assembly = Assembly.from_meshes(boxes)
    with pytest.raises(InterlockError, match=r"coordinates up to 2e\+200: beyond 1e\+100 .*\(scale it down\)"):
        module.validate(assembly)
    far = trimesh.creation.box()
    far.vertices *= 1e300  # one mesh alone is checked at any finite size
    assert len(self_intersections(far)) == 0
    broken = trimesh.creation.box()
    broken.vertices[0] = np.inf
    with pytest.raises(OverlapError, match="non-finite"):
        self_intersections(broken)
