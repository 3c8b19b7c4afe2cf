"""Conforming triangle meshes from what files hold: merged vertices, triangulated polygons, split T-junctions."""

from __future__ import annotations

import numpy as np
import shapely
import trimesh
from scipy.spatial import cKDTree

__all__ = ["merge_vertices", "triangulate_polygons", "unmatched_edges", "split_t_junctions", "unrepeated",
           "consistently_wound", "group_meshes", "closed_groups", "MERGE_RTOL", "TJUNCTION_RTOL"]

#: Vertices closer than this (relative to the extent of all vertices, per coordinate) are one vertex.
#: About what trimesh merges (1e-8 absolute) on unit-sized models, but relative, so that a model in
#: nanometres merges as one in metres; float32 files write one point the same way every time, so
#: coincident vertices differ by far less.
MERGE_RTOL = 1e-8
#: A vertex within this distance (relative to the mesh's bounding-box diagonal) of the inside of a
#: triangle edge lies on it (a T-junction).  Float32 files round coordinates by up to 6e-8 of the model
#: size; 1e-6 leaves a margin of 15 over that and stays ten times below the contact tolerance
#: (``interlock.verify.facets.DEFAULT_CONTACT_RTOL``, 1e-5).
TJUNCTION_RTOL = 1e-6
# Splitting rounds: each round halves the run of T vertices on one edge of every triangle, so 64 rounds
# split far more vertices per edge than any file holds.
_MAX_ROUNDS = 64


def merge_vertices(vertices, faces, rtol: float = MERGE_RTOL, groups=None) -> tuple[np.ndarray, np.ndarray]:
    """One vertex per point: vertices that round to the same point within ``rtol`` become one.

    Coordinates are rounded to a grid of ``rtol`` times the largest extent of
    ``vertices``; vertices in one grid cell merge.  Vertices that no face
    uses are dropped.  With ``groups`` (one integer per vertex), vertices of
    different groups never merge, and the result lists the vertices sorted by
    group, so each group's vertices are one contiguous run.

    Parameters
    ----------
    vertices : array (n, 3)
    faces : array (m, 3) of int
    rtol : float
        Grid step relative to the model's extent (:data:`MERGE_RTOL`).
    groups : array (n,) of int, optional
        Vertices of different groups stay apart (blocks of one file).

    Returns
    -------
    vertices : array (k, 3)
        The merged vertices (the first of each cell), sorted by group.
    faces : array (m, 3) of int
        The faces on the merged vertices, in the same order.

    Examples
    --------
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1e-12, 0, 0], [5, 5, 5]])
    >>> merged, f = merge_vertices(v, [[0, 1, 2], [3, 2, 1]])
    >>> len(merged), f.tolist()
    (3, [[0, 1, 2], [0, 2, 1]])
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    used, faces = np.unique(faces.ravel(), return_inverse=True)
    points = vertices[used]
    if not len(points):
        return points, faces.reshape(-1, 3)
    step = rtol * (float(np.ptp(points, axis=0).max()) or 1.0)
    keys = np.round((points - points.min(axis=0)) / step).astype(np.int64)
    group = np.zeros(len(points), dtype=np.int64) if groups is None else np.asarray(groups, dtype=np.int64)[used]
    keys = np.column_stack([group, keys])
    order = np.lexsort(keys.T[::-1])  # stable: the first of each cell is its first appearance
    new = np.ones(len(order), dtype=bool)
    new[1:] = (keys[order[1:]] != keys[order[:-1]]).any(axis=1)
    cell = np.empty(len(order), dtype=np.int64)
    cell[order] = np.cumsum(new) - 1
    first = order[new]
    by_appearance = np.lexsort((first, group[first]))  # by group, then in order of first appearance
    rank = np.empty_like(by_appearance)
    rank[by_appearance] = np.arange(len(by_appearance))
    return points[first[by_appearance]], rank[cell][faces].reshape(-1, 3)


def triangulate_polygons(vertices, indices, counts) -> tuple[np.ndarray, np.ndarray]:
    """Triangles covering each polygonal face exactly, oriented like the face.

    A fan from the first corner (what most readers do) covers more than a
    non-convex face and folds over itself; here triangles stay inside the
    face: quadrilaterals are cut along the diagonal inside them, larger
    polygons get a constrained Delaunay triangulation (shapely) in the plane
    that the face projects onto best.  A face that is not a simple polygon
    in that plane falls back to the fan.

    Parameters
    ----------
    vertices : array (n, 3)
    indices : array of int
        The corners of every face, face after face.
    counts : array of int
        The number of corners of each face (at least 3).

    Returns
    -------
    faces : array (m, 3) of int
        ``counts - 2`` triangles per face, face after face.
    polygon : array (m,) of int
        The face each triangle comes from.

    Examples
    --------
    An L-shaped hexagon, whose fan from corner 0 would cover the missing square:

    >>> square = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]
    >>> faces, polygon = triangulate_polygons(square, [1, 2, 3, 4, 5, 0], [6])
    >>> t = np.asarray(square, dtype=float)[faces]
    >>> float(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])[:, 2].sum() / 2), polygon.tolist()
    (3.0, [0, 0, 0, 0])
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    indices = np.asarray(indices, dtype=np.int64).ravel()
    counts = np.asarray(counts, dtype=np.int64).ravel()
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    pieces = []  # (faces, polygon) per kind of face
    for kind, triangulate in ((counts == 3, _triangles), (counts == 4, _quadrilaterals), (counts > 4, _polygons)):
        polygon = np.flatnonzero(kind)
        if polygon.size:
            faces, own = triangulate(vertices, indices, starts[polygon], counts[polygon])
            pieces.append((faces, polygon[own]))
    if not pieces:
        return np.empty((0, 3), dtype=np.int64), np.empty(0, dtype=np.int64)
    faces = np.vstack([f for f, _ in pieces])
    polygon = np.concatenate([p for _, p in pieces])
    order = np.argsort(polygon, kind="stable")
    return faces[order], polygon[order]


def unmatched_edges(faces) -> np.ndarray:
    """The directed edges of a closed, consistently oriented surface all have a partner; these do not.

    A surface is closed and consistently oriented when every directed edge
    ``(a, b)`` of its triangles occurs as often as ``(b, a)``: then each side
    of every edge is covered once from each side, also where four triangles
    meet (voxel parts).  Returns the distinct directed edges for which this
    fails, shape ``(k, 2)``.

    Examples
    --------
    >>> tetrahedron = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    >>> unmatched_edges(tetrahedron).shape, unmatched_edges(tetrahedron[:3]).tolist()
    ((0, 2), [[0, 2], [2, 3], [3, 0]])
    """
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if not len(faces):
        return np.empty((0, 2), dtype=np.int64)
    n = int(faces.max()) + 1
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    codes, counts = np.unique(directed[:, 0] * n + directed[:, 1], return_counts=True)
    reverse = (codes % n) * n + codes // n
    at = np.minimum(np.searchsorted(codes, reverse), len(codes) - 1)
    reverse_counts = np.where(codes[at] == reverse, counts[at], 0)
    bad = codes[counts != reverse_counts]
    return np.column_stack([bad // n, bad % n])


def unrepeated(faces) -> np.ndarray:
    """The triangles ``faces``, each that occurs more than once (the same corners in the same cyclic order) kept
    once, in the order of first occurrence.  A triangle and its reverse are two triangles.

    Examples
    --------
    >>> unrepeated([[0, 1, 2], [1, 2, 0], [0, 2, 1], [2, 3, 4]]).tolist()
    [[0, 1, 2], [0, 2, 1], [2, 3, 4]]
    """
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    # each triangle from its smallest corner on, in its own cyclic order
    turned = faces[np.arange(len(faces))[:, None], (np.argmin(faces, axis=1)[:, None] + np.arange(3)) % 3]
    _, first = np.unique(turned, axis=0, return_index=True)
    return faces[np.sort(first)]


def consistently_wound(vertices, faces) -> np.ndarray | None:
    """The faces of one surface with repeated triangles dropped and the winding made consistent, if that closes
    it (:func:`unmatched_edges` finds none); else None.

    CAD and scanning tools write closed surfaces with some triangles twice, or
    wound the other way round.  Neither changes the solid: a repeated triangle
    (the same corners in the same cyclic order) is kept once, and the winding
    is made to agree across every edge of two triangles, from a breadth-first
    walk over the surface (``trimesh.repair.fix_winding``).  Which way round
    the whole surface then is, is left to the caller (its signed volume).  A
    surface of several shells (a hollow block) is not repaired: which way each
    shell faces decides the solid.  A triangle and its reverse both present (a
    sheet of no thickness) are kept as they are.

    Examples
    --------
    >>> tetrahedron = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    >>> corners = np.eye(4, 3)
    >>> flipped = np.vstack([tetrahedron[:3], tetrahedron[3, ::-1], tetrahedron[:1]])  # one flipped, one twice
    >>> unmatched_edges(flipped).size > 0, unmatched_edges(consistently_wound(corners, flipped)).size
    (True, 0)
    """
    mesh = trimesh.Trimesh(np.asarray(vertices, dtype=float), unrepeated(faces), process=False)
    if mesh.body_count != 1:  # shells of one block (a hollow one): which way each faces is not for us to guess
        return None
    trimesh.repair.fix_winding(mesh)
    wound = np.asarray(mesh.faces, dtype=np.int64)
    return wound if not unmatched_edges(wound).size else None


def split_t_junctions(vertices, faces, rtol: float = TJUNCTION_RTOL, groups=None) -> np.ndarray:
    """The faces with every unmatched edge split at the vertices that lie on it.

    A closed surface from a CAD or mesh tool may have T-junctions: a vertex of
    some triangles lies inside an edge of another, so that edge finds no
    partner (:func:`unmatched_edges`) although no gap is there.  Each
    unmatched edge is split at the vertices within ``rtol`` times the mesh's
    bounding-box diagonal of its inside, and the triangles along it are cut
    accordingly (a triangle ``(u, v, w)`` with ``m`` on ``uv`` becomes
    ``(u, m, w)`` and ``(m, v, w)``), so the surface itself is unchanged and
    its triangulation conforms.  A surface with a real hole or a flipped
    triangle keeps unmatched edges.

    Parameters
    ----------
    vertices : array (n, 3)
    faces : array (m, 3) of int
    rtol : float
        Distance from an edge, relative to the mesh size, within which a
        vertex lies on it (:data:`TJUNCTION_RTOL`).
    groups : array (n,) of int, optional
        For many meshes at once: the mesh of each vertex.  An edge is split
        only at vertices of its own mesh, and each mesh's size is its own.

    Returns
    -------
    array (m', 3) of int
        The new faces on the same vertices; ``faces`` itself if no edge is unmatched.

    Examples
    --------
    A unit square face of a box split into two triangles on one side and
    three (with a vertex in the middle of an edge) on the other:

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0, 0]])
    >>> top, bottom = [[0, 1, 2], [0, 2, 3]], [[4, 0, 3], [4, 3, 2], [4, 2, 1]]
    >>> faces = np.array(top + bottom)
    >>> len(unmatched_edges(faces)), len(unmatched_edges(split_t_junctions(v, faces)))
    (3, 0)

    Notes
    -----
    The vertices of unmatched edges go into a k-d tree; each unmatched edge
    asks it for the vertices near its midpoint, which costs
    :math:`O(k \\log k)` for ``k`` unmatched edges.  Triangles are then cut
    in rounds, all at once with numpy, each round at the middle one of the
    vertices left on one edge of every triangle.  No Python loop runs per
    edge or per mesh: 10,000 meshes with T-junctions cost about as much as
    one mesh of all their triangles.
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    open_edges = unmatched_edges(faces)
    if not len(open_edges):
        return faces
    group = np.zeros(len(vertices), dtype=np.int64) if groups is None else np.asarray(groups, dtype=np.int64)
    table = _split_table(vertices, np.unique(np.sort(open_edges, axis=1), axis=0), group,
                         rtol * _group_sizes(vertices, faces, group))
    if table is None:
        return faces
    for _ in range(_MAX_ROUNDS):
        faces, cut = _cut_once(faces, *table)
        if not cut:
            break
    return faces


def group_meshes(vertices, faces, face_group) -> list[trimesh.Trimesh]:
    """One mesh per group of faces, in group order, each on its own merged vertices.

    Vertices are merged within each group only (:func:`merge_vertices`), all
    groups at once, so blocks that touch stay apart.

    Examples
    --------
    Two unit cubes side by side, as one triangle soup, one group per cube:

    >>> cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1)]
    >>> soup = np.vstack([c.triangles.reshape(-1, 3) for c in cubes])
    >>> meshes = group_meshes(soup, np.arange(len(soup)).reshape(-1, 3), np.repeat([0, 1], 12))
    >>> [(len(m.vertices), m.is_watertight, round(float(m.volume), 9)) for m in meshes]
    [(8, True, 1.0), (8, True, 1.0)]
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    order = np.argsort(face_group, kind="stable")
    faces, face_group = faces[order], np.asarray(face_group)[order]
    corners = vertices[faces.ravel()]
    merged, local = merge_vertices(corners, np.arange(len(corners)).reshape(-1, 3), groups=np.repeat(face_group, 3))
    _, face_start = np.unique(face_group, return_index=True)
    face_end = np.append(face_start[1:], len(faces))
    vertex_start = local[face_start].min(axis=1)  # vertices come group after group, in order of first use
    vertex_end = np.append(vertex_start[1:], len(merged))
    return [trimesh.Trimesh(merged[v0:v1], local[f0:f1] - v0, process=False)
            for f0, f1, v0, v1 in zip(face_start, face_end, vertex_start, vertex_end)]


def closed_groups(vertices, faces, face_group, rtol: float = TJUNCTION_RTOL) -> tuple | None:
    """``(vertices, faces, face_group)`` with T-junctions split, if every group of faces is closed on its own.

    Vertices are merged within each group (:func:`merge_vertices`); a group
    with unmatched edges gets them split (:func:`split_t_junctions`, all
    groups at once).  Returns None if some group stays open: then the groups
    are not separate closed bodies.

    Examples
    --------
    >>> cube = trimesh.creation.box()
    >>> closed_groups(cube.vertices, cube.faces, np.zeros(12, dtype=int)) is not None
    True
    >>> closed_groups(cube.vertices, cube.faces, np.repeat([0, 1], 6)) is None  # two open halves
    True
    """
    corners = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=np.int64).ravel()]
    group = np.repeat(face_group, 3)
    merged, local = merge_vertices(corners, np.arange(len(corners)).reshape(-1, 3), groups=group)
    vertex_group = np.zeros(len(merged), dtype=np.int64)
    vertex_group[local.ravel()] = group
    open_faces = np.isin(face_group, vertex_group[unmatched_edges(local)[:, 0]])
    if not open_faces.any():
        return merged, local, np.asarray(face_group)
    split = split_t_junctions(merged, local[open_faces], rtol, groups=vertex_group)
    if len(unmatched_edges(split)):
        return None
    local = np.vstack([local[~open_faces], split])
    return merged, local, vertex_group[local[:, 0]]


# --- polygons ---------------------------------------------------------------------
def _triangles(vertices, indices, starts, counts):
    return indices[starts[:, None] + np.arange(3)], np.arange(len(starts))


def _quadrilaterals(vertices, indices, starts, counts):
    """Each quadrilateral cut along the diagonal 0-2 when it lies inside, else along 1-3."""
    quad = indices[starts[:, None] + np.arange(4)]
    p = vertices[quad]
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])  # the quadrilateral's area vector (twice)
    first = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), normal)
    second = np.einsum("ij,ij->i", np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]), normal)
    along_02 = (first >= 0) & (second >= 0)
    cut = np.where(along_02[:, None, None], quad[:, [[0, 1, 2], [0, 2, 3]]], quad[:, [[1, 2, 3], [1, 3, 0]]])
    return cut.reshape(-1, 3), np.repeat(np.arange(len(quad)), 2)


def _polygons(vertices, indices, starts, counts):
    """Constrained Delaunay triangles of each polygon in its best projection plane; a fan where that fails."""
    corner = np.repeat(starts, counts) + _ranks(counts)
    polygon_of = np.repeat(np.arange(len(counts)), counts)
    points = vertices[indices[corner]]
    following = vertices[indices[np.repeat(starts, counts) + (_ranks(counts) + 1) % np.repeat(counts, counts)]]
    normal = np.add.reduceat(np.cross(points, following), np.concatenate([[0], np.cumsum(counts)[:-1]]))
    drop = np.abs(normal).argmax(axis=1)
    axes = (drop[:, None] + [1, 2]) % 3  # keeps the orientation: the 2D area has the sign of normal[drop]
    flat = np.take_along_axis(points, axes[polygon_of], axis=1)
    rings = shapely.linearrings(flat, indices=polygon_of)
    shapes = shapely.polygons(rings)
    ok = shapely.is_valid(shapes) & (shapely.area(shapes) > 0)
    faces, owner = _fans(indices, starts, counts)
    if not ok.any():
        return faces, owner
    cdt, cdt_owner, done = _delaunay(flat, polygon_of, shapes, np.flatnonzero(ok), indices[corner], counts)
    # the triangulation's triangles turn either way; turn each like its polygon (fans stay as they are)
    t = vertices[cdt]
    turn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])[np.arange(len(cdt)), drop[cdt_owner]]
    flip = turn * normal[cdt_owner, drop[cdt_owner]] < 0
    cdt[flip] = cdt[flip][:, ::-1]
    fan = np.ones(len(counts), dtype=bool)
    fan[done] = False
    return np.vstack([faces[fan[owner]], cdt]), np.concatenate([owner[fan[owner]], cdt_owner])


def _fans(indices, starts, counts):
    """Fan triangles ``(0, k, k + 1)`` of every polygon."""
    owner = np.repeat(np.arange(len(counts)), counts - 2)
    k = _ranks(counts - 2) + 1
    base = starts[owner]
    return np.column_stack([indices[base], indices[base + k], indices[base + k + 1]]), owner


def _delaunay(flat, polygon_of, shapes, chosen, corner_indices, counts):
    """Triangles of the chosen polygons as vertex indices; polygons whose triangles do not map back are left out."""
    parts, which = shapely.get_parts(shapely.constrained_delaunay_triangles(shapes[chosen]), return_index=True)
    owner = chosen[which]
    corners = shapely.get_coordinates(shapely.get_exterior_ring(parts)).reshape(-1, 4, 2)[:, :3]
    # find every triangle corner among its polygon's corners: the same (polygon, x, y), bit for bit
    keys = np.vstack([np.column_stack([polygon_of, _bits(flat)]),
                      np.column_stack([np.repeat(owner, 3), _bits(corners.reshape(-1, 2))])])
    _, first, key = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    key = key.ravel()
    mine, theirs = key[:len(polygon_of)], key[len(polygon_of):]
    found = first[theirs] < len(polygon_of)  # the first row with this key is a polygon corner
    repeated = np.bincount(mine, minlength=len(first)) > 1  # one point twice in a polygon: ambiguous
    good = np.ones(len(counts), dtype=bool)
    np.logical_and.at(good, owner, (found & ~repeated[theirs]).reshape(-1, 3).all(axis=1))
    good[chosen] &= np.bincount(owner, minlength=len(counts))[chosen] == counts[chosen] - 2
    done = chosen[good[chosen]]
    keep = good[owner]
    faces = corner_indices[np.minimum(first[theirs], len(polygon_of) - 1)].reshape(-1, 3)
    return faces[keep], owner[keep], done


def _bits(xy: np.ndarray) -> np.ndarray:
    """Coordinates as integers with the same bits (``-0.0`` as ``0.0``), for exact matching."""
    return (np.ascontiguousarray(xy, dtype=float) + 0.0).view(np.int64)


def _ranks(counts) -> np.ndarray:
    """0, 1, ..., c - 1 for every count c, concatenated."""
    counts = np.asarray(counts, dtype=np.int64)
    return np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)


# --- T-junctions ------------------------------------------------------------------
def _group_sizes(vertices, faces, group) -> np.ndarray:
    """The bounding-box diagonal of each group's vertices that faces use (1 for a point or no vertex)."""
    used = np.unique(faces)
    count = int(group.max(initial=0)) + 1
    low, high = np.full((count, 3), np.inf), np.full((count, 3), -np.inf)
    np.minimum.at(low, group[used], vertices[used])
    np.maximum.at(high, group[used], vertices[used])
    size = np.linalg.norm(np.where(np.isfinite(high - low), high - low, 0.0), axis=1)
    return np.where(size > 0, size, 1.0)


def _split_table(vertices, segments, group, tol):
    """For every run of vertices along an unmatched edge: each sub-edge with vertices inside, and its middle one.

    ``tol`` is the distance tolerance of each group.  Returns the sorted codes
    ``a * n + b`` (``a < b``) of the sub-edges, the vertex to cut each at,
    and ``n``; None if no vertex lies inside any edge.
    """
    a, b = vertices[segments[:, 0]], vertices[segments[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    own_tol = tol[group[segments[:, 0]]]
    candidates = np.unique(segments)
    near = cKDTree(vertices[candidates]).query_ball_point((a + b) / 2, length / 2 + own_tol, return_sorted=False)
    segment = np.repeat(np.arange(len(segments)), np.fromiter(map(len, near), dtype=np.int64, count=len(near)))
    if not segment.size:
        return None
    point = candidates[np.concatenate([np.asarray(n, dtype=np.int64) for n in near if n])]
    unit = (b - a)[segment] / np.maximum(length[segment], np.finfo(float).tiny)[:, None]
    offset = vertices[point] - a[segment]
    along = np.einsum("ij,ij->i", offset, unit)
    off = np.linalg.norm(offset - along[:, None] * unit, axis=1)
    t = own_tol[segment]
    inside = (off <= t) & (along > t) & (along < length[segment] - t) & (group[point] == group[segments[segment, 0]])
    if not inside.any():
        return None
    segment, point, along = segment[inside], point[inside], along[inside]
    order = np.lexsort((along, segment))
    segment, point = segment[order], point[order]
    # runs: each split edge's first end, the vertices on it in order, its last end
    split, inner = np.unique(segment, return_counts=True)
    size = inner + 2
    start = np.cumsum(size) - size
    runs = np.empty(size.sum(), dtype=np.int64)
    runs[start], runs[start + size - 1] = segments[split, 0], segments[split, 1]
    runs[np.repeat(start, inner) + 1 + _ranks(inner)] = point
    # every pair (i, j) of a run with a vertex between them: the sub-edge and its middle vertex
    cell = _ranks(size ** 2)
    width, base = np.repeat(size, size ** 2), np.repeat(start, size ** 2)
    i, j = cell // width, cell % width
    keep = j >= i + 2
    i, j, base = i[keep], j[keep], base[keep]
    low, high = np.minimum(runs[base + i], runs[base + j]), np.maximum(runs[base + i], runs[base + j])
    codes, first = np.unique(low * len(vertices) + high, return_index=True)
    return codes, runs[base + (i + j) // 2][first], len(vertices)


def _cut_once(faces, codes, middles, n):
    """Cut every triangle that has a vertex inside one of its edges once, at the middle one; (faces, any cut)."""
    u, v = faces, faces[:, [1, 2, 0]]
    edge = np.minimum(u, v) * n + np.maximum(u, v)
    at = np.minimum(np.searchsorted(codes, edge), len(codes) - 1)
    middle = np.where(codes[at] == edge, middles[at], -1)
    middle[(middle[:, :, None] == faces[:, None, :]).any(axis=2)] = -1  # never cut at the triangle's own corner
    cut = (middle >= 0).any(axis=1)
    if not cut.any():
        return faces, False
    rows = np.flatnonzero(cut)
    k = (middle[rows] >= 0).argmax(axis=1)
    a, b, c = (faces[rows, (k + shift) % 3] for shift in range(3))
    m = middle[rows, k]
    new = np.vstack([np.column_stack([a, m, c]), np.column_stack([m, b, c])])
    return np.vstack([faces[~cut], new]), True
