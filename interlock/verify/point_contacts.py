"""Point contacts of blocks (main paper Remark 3.11): vertex-face, edge-edge, vertex-edge, vertex-vertex."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.spatial import cKDTree

from interlock.blocks.contact import Contact, plane_bases

__all__ = ["Features", "features", "point_contacts", "admissible_normals", "implied_by_faces", "contact_kinds",
           "POINT_KINDS",
           "LINEAR_KINDS", "CONE_ANGLE"]

#: The kinds a point contact can have (a point of zero area; see :data:`~interlock.blocks.contact.CONTACT_KINDS`).
POINT_KINDS = ("vertex-face", "edge-edge", "vertex-edge", "vertex-vertex")
#: Kinds whose contacts always admit exactly one normal: one row each (Remark 3.11).
LINEAR_KINDS = ("face", "vertex-face", "edge-edge")
#: Normals within this angle (radians) are one normal when the cone of admissible normals is computed: a cone
#: thinner than it is one row, a generator this far outside a cone is still in it.  The contact search's default
#: angle tolerance (1e-4 rad), which faces that meet use.
CONE_ANGLE = 1e-4


@dataclass(frozen=True, eq=False)
class Features:
    """The corners and feature edges of one closed mesh, in its own frame, with their tangent cones.

    A *corner* is a vertex where three or more facets meet; a *feature edge*
    is a mesh edge between two different facets (triangulation diagonals
    inside a facet are none).  The solid near a point of it is a cone, given
    by generators (unit *rays*): at corner ``corners[k]`` the directions of
    its feature edges (``corner_rays[k]``); along edge ``e`` its direction
    both ways and, in each of its two facets, the direction away from the
    edge (``edge_rays[e]``, four rows).  Only convex corners and edges
    (every feature edge at a corner convex; an edge whose dihedral angle is
    below pi) take part in point contacts: at a reflex edge or a saddle the
    local solid is no convex cone, and no contact is made of it (a contact
    left out only weakens the model, never makes a motion look blocked).
    """

    vertices: np.ndarray
    corners: np.ndarray
    corner_rays: tuple
    corner_convex: np.ndarray
    edges: np.ndarray
    edge_rays: np.ndarray
    edge_convex: np.ndarray
    is_corner: np.ndarray


def features(mesh, facets) -> Features:
    """The :class:`Features` of a merged mesh and its :class:`~interlock.verify.facets.Facets`.

    >>> import trimesh
    >>> from interlock.verify.facets import facets as find_facets, merged
    >>> box = merged(trimesh.creation.box())
    >>> f = features(box, find_facets(box))
    >>> len(f.corners), len(f.edges), [len(r) for r in f.corner_rays][:3], f.edge_rays.shape
    (8, 12, [3, 3, 3], (12, 4, 3))
    """
    return _features_of([mesh], [facets])[0]


def _features_of(meshes, facets_list) -> list:
    """The :class:`Features` of several merged meshes at once (one pass of array operations over all of them)."""
    import trimesh

    vertex_counts = np.array([len(m.vertices) for m in meshes])
    face_counts = np.array([len(m.faces) for m in meshes])
    facet_counts = np.array([len(f.normals) for f in facets_list])
    vertex_start, facet_start = np.r_[0, np.cumsum(vertex_counts)], np.r_[0, np.cumsum(facet_counts)]
    face_start = np.r_[0, np.cumsum(face_counts)]
    vertices = np.vstack([np.asarray(m.vertices, dtype=float) for m in meshes]).reshape(-1, 3)
    faces = np.vstack([np.asarray(m.faces) + o for m, o in zip(meshes, vertex_start)]).reshape(-1, 3)
    label = np.full(len(faces), -1)
    for k, f in enumerate(facets_list):
        for facet, members in enumerate(f.faces):
            label[face_start[k] + np.asarray(members, dtype=int)] = facet_start[k] + facet
    normals = np.vstack([np.asarray(f.normals) for f in facets_list]).reshape(-1, 3)
    whole = trimesh.Trimesh(vertices, faces, process=False)
    adjacency = np.asarray(whole.face_adjacency).reshape(-1, 2)
    shared = np.asarray(whole.face_adjacency_edges).reshape(-1, 2)
    unshared = np.asarray(whole.face_adjacency_unshared).reshape(-1, 2)
    la, lb = label[adjacency[:, 0]], label[adjacency[:, 1]]
    feature = (la >= 0) & (lb >= 0) & (la != lb)
    la, lb, shared, unshared = la[feature], lb[feature], shared[feature], unshared[feature]
    # convex: the other facet's far vertex lies below this facet's plane
    far = np.einsum("ki,ki->k", normals[la], vertices[unshared[:, 1]] - vertices[shared[:, 0]])
    edge_convex = far < 0
    direction = vertices[shared[:, 1]] - vertices[shared[:, 0]]
    direction = direction / np.maximum(np.linalg.norm(direction, axis=1), 1e-300)[:, None]
    inward = []  # in each facet, the direction away from the edge: perpendicular to it, below the other facet
    for mine, other in ((normals[la], normals[lb]), (normals[lb], normals[la])):
        d = _cross(direction, mine)
        d = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
        inward.append(np.where((np.einsum("ki,ki->k", d, other) > 0)[:, None], -d, d))
    edge_rays = np.stack([direction, -direction, inward[0], inward[1]], axis=1)
    # corners: three or more facets at a vertex; their rays: the directions of their feature edges
    used = label >= 0
    pairs = np.unique(np.column_stack([faces[used].ravel(), np.repeat(label[used], 3)]), axis=0)
    is_corner = np.bincount(pairs[:, 0], minlength=len(vertices)) >= 3
    ends = np.concatenate([shared[:, 0], shared[:, 1]])
    rays = np.concatenate([direction, -direction])
    order = np.argsort(ends, kind="stable")
    ends, rays = ends[order], rays[order]
    reflex_at = np.zeros(len(vertices), dtype=bool)
    reflex_at[shared[~edge_convex].ravel()] = True
    edge_mesh = np.searchsorted(vertex_start, shared[:, 0], side="right") - 1
    out = []
    for k in range(len(meshes)):
        lo, hi = vertex_start[k], vertex_start[k + 1]
        corners = np.flatnonzero(is_corner[lo:hi])
        first, last = np.searchsorted(ends, corners + lo), np.searchsorted(ends, corners + lo, side="right")
        mine = edge_mesh == k
        arrays = [vertices[lo:hi].copy(), corners, edge_rays[mine], edge_convex[mine], is_corner[lo:hi].copy()]
        for array in arrays:
            array.setflags(write=False)
        out.append(Features(arrays[0], corners, tuple(rays[a:b] for a, b in zip(first, last)),
                            ~reflex_at[corners + lo], shared[mine] - lo, arrays[2], arrays[3], arrays[4]))
    return out


def admissible_normals(rays_i, rays_j, angle: float = CONE_ANGLE) -> np.ndarray:
    """The cone of admissible normals where convex features of blocks ``i`` and ``j`` touch, as generators.

    ``rays_i`` generate block ``i``'s solid near the contact point (its
    tangent cone ``K_i``: the directions of a corner's edges; an edge's
    direction both ways and the directions into its two faces; a face's
    plane both ways and the inward normal), ``rays_j`` block ``j``'s.  A plane
    with normal ``n`` (from ``i`` towards ``j``) separates the two cones
    exactly when ``n . d <= 0`` for every ray ``d`` of ``K_i`` and
    ``n . d >= 0`` for every ray of ``K_j``: the admissible normals are the
    polyhedral cone these inequalities cut out.  Its extreme rays lie where
    two of its planes meet.  Returns one unit row when the cone is one ray
    (within ``angle``), its extreme rays when it is wider, and no row when it
    is only zero (the blocks press into each other there).

    >>> x, y, z = np.eye(3)
    >>> corner = [-x, -y, -z]                     # the corner (1, 1, 1) of the unit cube, edges towards the origin
    >>> admissible_normals(corner, [x, -y, -z]).round(12).tolist()   # a cube beside it, corner on corner: faces meet
    [[1.0, 0.0, 0.0]]
    >>> len(admissible_normals(corner, [x, y, -z]))   # the diagonal cube of the grid: a cone of normals
    2
    >>> len(admissible_normals(corner, [x, y, z]))    # corner on corner, tip to tip: a cone with 3 edges
    3
    """
    A = np.vstack([_unit(np.asarray(rays_i, dtype=float).reshape(-1, 3)),
                   -_unit(np.asarray(rays_j, dtype=float).reshape(-1, 3))])
    a, b = _PAIRS[len(A)] if len(A) < len(_PAIRS) else np.triu_indices(len(A), 1)
    candidates = _cross(A[a], A[b])
    size = np.linalg.norm(candidates, axis=1)
    candidates = candidates[size > 1e-9] / size[size > 1e-9, None]
    candidates = np.vstack([candidates, -candidates])
    tol = np.sin(angle)
    rays = candidates[(candidates @ A.T <= tol).all(axis=1)]
    if not len(rays):
        return np.zeros((0, 3))
    mean = rays.sum(axis=0)
    if np.linalg.norm(mean) > 1e-9:
        mean /= np.linalg.norm(mean)
        if np.all(np.linalg.norm(_cross(rays, mean[None]), axis=1) <= tol) and np.all(rays @ mean > 0):
            return mean[None]
    return _distinct(rays, tol)


def implied_by_faces(point: np.ndarray, faces, tol: float) -> bool:
    """True when ``point`` lies within ``tol`` of one of the face contacts ``faces`` (of the same pair).

    The rows of a face contact at its polygon's vertices imply the row at
    every point of the polygon (the constraint is affine in the point), and
    the face's normal is admissible wherever the faces meet: a point contact
    there adds nothing.
    """
    for c in faces:
        offset = point - c.origin
        if abs(offset @ c.normal) > tol:
            continue
        xy = shapely.Point(offset @ np.asarray(c.basis).T)
        if c.polygon.distance(xy) <= tol:
            return True
    return False


def point_contacts(table, pairs, tolerances, faces=()) -> tuple[Contact, ...]:
    """The vertex and edge contacts of the block pairs ``pairs`` (Remark 3.11).

    ``table`` is the contact search's :class:`~interlock.verify.facets.FacetTable`
    and ``tolerances`` its per-block tolerances (``search``: the distance within
    which a block's features touch another's; ``rounding``; ``coincide``).
    Two features touch when they are within the sum of their blocks' search
    distances; a point within that distance of a face contact of the same
    pair (``faces``) is implied by it and left out.

    Returns contacts of kind ``"vertex-face"`` (a corner strictly inside a
    face: the face's normal), ``"edge-edge"`` (two feature edges crossing at
    interior points, not parallel: the normal ``e_i x e_j``), and
    ``"vertex-edge"`` / ``"vertex-vertex"`` (the cone of admissible normals,
    :func:`admissible_normals`; one normal when the cone is one ray).
    Each has one vertex, the contact point, and zero area.  For a
    vertex-face contact ``facet_i`` (or ``facet_j``) names the face's facet,
    the other is -1: the vertex belongs to the other block.

    Notes
    -----
    All features of all blocks of the pairs are searched at once: k-d trees
    over corners, edge midpoints and facet centres (grouped by size within a
    factor 4), exact distances vectorised, then the implied points dropped;
    only the few touches left have their cones computed one by one.  The
    cost is ``O(V log V)`` in the number of features plus the touches.
    """
    pairs = np.unique(np.sort(np.asarray(pairs, dtype=int).reshape(-1, 2), axis=1), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    if not len(pairs):
        return ()
    count = int(pairs.max()) + 1
    keys = pairs[:, 0] * count + pairs[:, 1]
    blocks = np.unique(pairs)
    types = sorted({int(table.types[b]) for b in blocks} & set(table.per_type))
    cache = dict(zip(types, _features_of([table.merged[t] for t in types], [table.per_type[t] for t in types])))
    placed = [p for p in (_placed(table, int(b), cache) for b in blocks) if p is not None]
    if not placed:
        return ()
    every = _Everything(placed)
    search = np.asarray(tolerances.search, dtype=float)
    reach = 2.0 * float(search[np.unique(pairs)].max())
    angle = max(float(tolerances.angle), CONE_ANGLE)

    def paired(a, b):  # the candidate pairs among blocks a, b (either order)
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return (a != b) & np.isin(lo * count + hi, keys)

    found = []  # (i, j, kind, point, normals or None, rays_i, rays_j, gap, facet_i, facet_j)
    found += _vertex_vertex(every, search, reach, paired)
    found += _vertex_edge(every, search, reach, paired)
    found += _edge_edge(every, search, reach, paired, angle)
    found += _vertex_face(table, every, search, reach, paired, count, keys)
    if not found:
        return ()
    found = _unimplied(found, faces, search)
    kept, made = {}, []
    for i, j, kind, point, normals, rays_i, rays_j, gap, facet_i, facet_j in found:
        tol = float(search[i] + search[j])
        if any(np.linalg.norm(q - point) <= tol for q in kept.get((i, j, kind), ())):
            continue  # the same touch found twice (collinear edge pieces, both blocks' sides)
        if normals is None:
            normals = admissible_normals(rays_i, rays_j, angle)
        elif not _separates(normals[0], rays_i, rays_j, angle):
            normals = np.zeros((0, 3))
        if not len(normals):  # the local solids reach through each other: no contact of this kind
            continue
        kept.setdefault((i, j, kind), []).append(point)
        made.append((i, j, kind, point, normals, gap, facet_i, facet_j))
    if not made:
        return ()
    representative = np.array([m[4].sum(axis=0) for m in made])
    representative /= np.linalg.norm(representative, axis=1)[:, None]
    bases = plane_bases(representative)
    rounding, coincide = np.asarray(tolerances.rounding, float), np.asarray(tolerances.coincide, float)
    return tuple(_contact(*m, representative[k], bases[k], float(max(rounding[m[0]], rounding[m[1]])),
                          float(max(coincide[m[0]], coincide[m[1]])))
                 for k, m in enumerate(made))


def contact_kinds(found) -> dict:
    """How many contacts of each kind ``found`` holds; a cone of normals counts as ``"<kind> (cone)"``.

    >>> from interlock.blocks import presets
    >>> from interlock.verify.contacts import contacts
    >>> contact_kinds(contacts(presets.cube_grid(), kinds="all"))
    {'face': 12, 'vertex-vertex (cone)': 16}
    """
    counts = {}
    for c in found:
        key = c.kind if c.normals is None else f"{c.kind} (cone)"
        counts[key] = counts.get(key, 0) + 1
    return dict(sorted(counts.items(), key=lambda item: (_KIND_ORDER.index(item[0].split(" ")[0]), item[0])))


_KIND_ORDER = ("face",) + POINT_KINDS


# --- private helpers --------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _Placed:
    """A block's features in world coordinates."""

    block: int
    vertices: np.ndarray
    corners: np.ndarray  # corner vertex indices, convex ones only
    corner_points: np.ndarray
    corner_rays: tuple
    edges: np.ndarray  # convex feature edges (vertex index pairs)
    edge_rays: np.ndarray
    is_corner: np.ndarray


def _placed(table, block: int, cache: dict):
    """Block ``block``'s convex features in world coordinates (features cached per mesh type)."""
    t = int(table.types[block])
    if t not in cache:
        return None
    feats = cache[t]
    rotation, shift = table.transforms[block, :3, :3], table.transforms[block, :3, 3]
    vertices = feats.vertices @ rotation.T + shift
    convex = feats.corner_convex
    corners = feats.corners[convex]
    rays = tuple(r @ rotation.T for r, ok in zip(feats.corner_rays, convex) if ok)
    edges = feats.edges[feats.edge_convex]
    edge_rays = feats.edge_rays[feats.edge_convex] @ rotation.T
    return _Placed(block, vertices, corners, vertices[corners], rays, edges, edge_rays, feats.is_corner)


class _Everything:
    """The convex corners and feature edges of several placed blocks, concatenated."""

    def __init__(self, placed):
        self.corner_points = np.vstack([p.corner_points for p in placed]).reshape(-1, 3)
        self.corner_block = np.concatenate([np.full(len(p.corners), p.block) for p in placed])
        self.corner_rays = [r for p in placed for r in p.corner_rays]
        self.edge_p = np.vstack([p.vertices[p.edges[:, 0]] for p in placed]).reshape(-1, 3)
        self.edge_q = np.vstack([p.vertices[p.edges[:, 1]] for p in placed]).reshape(-1, 3)
        self.edge_block = np.concatenate([np.full(len(p.edges), p.block) for p in placed])
        self.edge_rays = np.vstack([p.edge_rays for p in placed]).reshape(-1, 4, 3)
        # whether each end of an edge is a corner (a touch there is no edge touch)
        self.end_corner = np.vstack([p.is_corner[p.edges] for p in placed]).reshape(-1, 2)
        self.mid = (self.edge_p + self.edge_q) / 2
        self.half = np.linalg.norm(self.edge_q - self.edge_p, axis=1) / 2


def _vertex_vertex(every: _Everything, search, reach, paired):
    """Corners of two blocks within their search distances."""
    points, block = every.corner_points, every.corner_block
    hits = _near(points, np.zeros(len(points)), points, np.zeros(len(points)), reach)
    a, b = hits.T if len(hits) else (np.zeros(0, int), np.zeros(0, int))
    ok = (block[a] < block[b]) & paired(block[a], block[b])
    a, b = a[ok], b[ok]
    gap = np.linalg.norm(points[b] - points[a], axis=1)
    ok = gap <= search[block[a]] + search[block[b]]
    return [(int(block[x]), int(block[y]), "vertex-vertex", (points[x] + points[y]) / 2, None,
             every.corner_rays[x], every.corner_rays[y], float(g), -1, -1)
            for x, y, g in zip(a[ok], b[ok], gap[ok])]


def _vertex_edge(every: _Everything, search, reach, paired):
    """Corners of one block on the interior of a convex feature edge of another."""
    points, block = every.corner_points, every.corner_block
    hits = _near(every.mid, every.half, points, np.zeros(len(points)), reach)
    if not len(hits):
        return []
    e, c = hits.T
    ok = paired(every.edge_block[e], block[c])
    e, c = e[ok], c[ok]
    u = every.edge_q[e] - every.edge_p[e]
    s = np.einsum("ki,ki->k", points[c] - every.edge_p[e], u) / np.einsum("ki,ki->k", u, u)
    on = every.edge_p[e] + np.clip(s, 0, 1)[:, None] * u
    gap = np.linalg.norm(points[c] - on, axis=1)
    tol = search[every.edge_block[e]] + search[block[c]]
    length = 2 * every.half[e]
    # interior: farther than the tolerance from an end of the edge that is a corner
    near_p = every.end_corner[e, 0] & (s * length <= tol)
    near_q = every.end_corner[e, 1] & ((1 - s) * length <= tol)
    ok = (s >= 0) & (s <= 1) & (gap <= tol) & ~near_p & ~near_q
    out = []
    for x, y, p, g in zip(e[ok], c[ok], on[ok], gap[ok]):
        edge_block, corner_block = int(every.edge_block[x]), int(block[y])
        point = (p + points[y]) / 2
        if edge_block < corner_block:
            out.append((edge_block, corner_block, "vertex-edge", point, None, every.edge_rays[x],
                        every.corner_rays[y], float(g), -1, -1))
        else:
            out.append((corner_block, edge_block, "vertex-edge", point, None, every.corner_rays[y],
                        every.edge_rays[x], float(g), -1, -1))
    return out


def _edge_edge(every: _Everything, search, reach, paired, angle):
    """Convex feature edges of two blocks crossing (not parallel) at interior points."""
    hits = _near(every.mid, every.half, every.mid, every.half, reach)
    if not len(hits):
        return []
    a, b = hits.T
    ok = (every.edge_block[a] < every.edge_block[b]) & paired(every.edge_block[a], every.edge_block[b])
    a, b = a[ok], b[ok]
    pa, pb = every.edge_p[a], every.edge_p[b]
    u, w = every.edge_q[a] - pa, every.edge_q[b] - pb
    cross = np.cross(u, w)
    size = np.linalg.norm(cross, axis=1)
    lu, lw = 2 * every.half[a], 2 * every.half[b]
    tol = search[every.edge_block[a]] + search[every.edge_block[b]]
    # not parallel: the angle between the edges is above the angle tolerance, and so large that moving their ends
    # by the tolerance turns e_i x e_j by at most CONE_ANGLE (tol / (l sin theta) <= CONE_ANGLE); crossings at
    # smaller angles are no edge-edge contact (fewer rows: never a motion wrongly blocked)
    shortest = np.maximum(np.minimum(lu, lw), 1e-300)
    transverse = size > np.maximum(np.sin(angle), tol / (CONE_ANGLE * shortest)) * lu * lw
    a, b, pa, pb, u, w, cross, size, lu, lw, tol = (x[transverse] for x in (a, b, pa, pb, u, w, cross, size, lu, lw,
                                                                            tol))
    d = pb - pa
    uu, ww, uw = lu ** 2, lw ** 2, np.einsum("ki,ki->k", u, w)
    du, dw = np.einsum("ki,ki->k", d, u), np.einsum("ki,ki->k", d, w)
    det = uu * ww - uw ** 2
    s = (du * ww - dw * uw) / det
    t = (du * uw - dw * uu) / det
    on_a, on_b = pa + s[:, None] * u, pb + t[:, None] * w
    n = cross / size[:, None]
    gap_signed = np.einsum("ki,ki->k", on_b - on_a, n)
    near = ((every.end_corner[a, 0] & (s * lu <= tol)) | (every.end_corner[a, 1] & ((1 - s) * lu <= tol))
            | (every.end_corner[b, 0] & (t * lw <= tol)) | (every.end_corner[b, 1] & ((1 - t) * lw <= tol)))
    ok = (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1) & (np.abs(gap_signed) <= tol) & ~near
    out = []
    for k in np.flatnonzero(ok):
        normal = n[k] if n[k] @ every.edge_rays[a[k], 2:].sum(axis=0) <= 0 else -n[k]
        out.append((int(every.edge_block[a[k]]), int(every.edge_block[b[k]]), "edge-edge",
                    (on_a[k] + on_b[k]) / 2, normal[None], every.edge_rays[a[k]], every.edge_rays[b[k]],
                    float((on_b[k] - on_a[k]) @ normal), -1, -1))
    return out


def _vertex_face(table, every: _Everything, search, reach, paired, count, keys):
    """Corners of one block strictly inside a facet of another (farther than the tolerance from its boundary)."""
    points, block = every.corner_points, every.corner_block
    blocks = np.unique(block)
    facets = np.concatenate([np.arange(table.start[b], table.start[b + 1]) for b in blocks]).astype(int)
    if not len(facets) or not len(points):
        return []
    box = shapely.bounds(table.polygons[facets])
    radius = np.hypot(np.maximum(np.abs(box[:, 0]), np.abs(box[:, 2])),
                      np.maximum(np.abs(box[:, 1]), np.abs(box[:, 3])))
    hits = _near(table.origins[facets], radius, points, np.zeros(len(points)), reach)
    if not len(hits):
        return []
    f, c = hits.T
    g = facets[f]
    face_block = table.block[g]
    ok = paired(face_block, block[c])
    g, c, face_block = g[ok], c[ok], face_block[ok]
    offset = points[c] - table.origins[g]
    distance = np.einsum("ki,ki->k", offset, table.normals[g])
    tol = search[face_block] + search[block[c]]
    ok = np.abs(distance) <= tol
    g, c, face_block, offset, distance, tol = g[ok], c[ok], face_block[ok], offset[ok], distance[ok], tol[ok]
    xy = shapely.points(np.einsum("ki,kai->ka", offset, table.bases[g]))
    polygons = table.polygons[g]
    inside = shapely.contains(polygons, xy) & (shapely.distance(shapely.boundary(polygons), xy) > tol)
    out = []
    for k in np.flatnonzero(inside):
        n = table.normals[g[k]]
        point = points[c[k]] - 0.5 * distance[k] * n
        corner_block, fb, local = int(block[c[k]]), int(face_block[k]), int(table.local[g[k]])
        u, v = table.bases[g[k]]
        face_rays = np.array([u, -u, v, -v, -n])  # the half-space below the face
        if fb < corner_block:  # the face is block i's, pointing to j
            out.append((fb, corner_block, "vertex-face", point, n[None], face_rays, every.corner_rays[c[k]],
                        float(distance[k]), local, -1))
        else:
            out.append((corner_block, fb, "vertex-face", point, -n[None], every.corner_rays[c[k]], face_rays,
                        float(distance[k]), -1, local))
    return out


def _unimplied(found, faces, search):
    """The touches of ``found`` that lie farther than their tolerance from every face contact of their pair.

    The tolerance is the pair's search distance, or the face contact's own where that is larger (its
    :attr:`~interlock.blocks.contact.Contact.tolerance`, its bend and gap): a face bent within the tolerances
    is modelled as one plane, and the corners of its halves are that face's, not contacts of their own."""
    by_pair = {}
    for k, c in enumerate(faces):
        by_pair.setdefault((c.i, c.j), []).append(k)
    tests_t, tests_f = [], []
    for t, item in enumerate(found):
        for k in by_pair.get((item[0], item[1]), ()):
            tests_t.append(t)
            tests_f.append(k)
    if not tests_t:
        return found
    tests_t, tests_f = np.array(tests_t), np.array(tests_f)
    points = np.array([item[3] for item in found])[tests_t]
    tol = np.array([search[item[0]] + search[item[1]] for item in found])[tests_t]
    # a face contact stands for its faces within its own tolerance (a bend it merged, a gap it bridges)
    tol = np.maximum(tol, np.array([max(faces[k].tolerance or 0.0, faces[k].deviation + faces[k].separation)
                                    for k in tests_f]))
    origins = np.array([faces[k].origin for k in tests_f])
    normals = np.array([faces[k].normal for k in tests_f])
    bases = np.array([faces[k].basis for k in tests_f])
    polygons = np.array([faces[k].polygon for k in tests_f], dtype=object)
    offset = points - origins
    xy = shapely.points(np.einsum("ki,kai->ka", offset, bases))
    near = (np.abs(np.einsum("ki,ki->k", offset, normals)) <= tol) & (shapely.distance(polygons, xy) <= tol)
    implied = np.zeros(len(found), dtype=bool)
    implied[tests_t[near]] = True
    return [item for item, gone in zip(found, implied) if not gone]


def _separates(normal, rays_i, rays_j, angle) -> bool:
    """Whether ``normal`` (from i to j) is admissible: ``n . d <= 0`` on i's rays and ``>= 0`` on j's (within angle)."""
    tol = np.sin(angle)
    return bool(np.all(np.asarray(rays_i) @ normal <= tol) and np.all(np.asarray(rays_j) @ normal >= -tol))


def _distinct(rays, tol: float = 1e-9) -> np.ndarray:
    """The rows of ``rays`` without repeats (within ``tol``; the first of each)."""
    rays = np.asarray(rays, dtype=float).reshape(-1, 3)
    close = np.linalg.norm(rays[:, None] - rays[None], axis=2) <= tol
    return rays[~np.triu(close, 1).any(axis=0)]


def _cross(a, b) -> np.ndarray:
    """Row-wise cross products (numpy's cross costs more than the products for a few rows)."""
    return np.column_stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]])


#: Index pairs of the upper triangle for up to 31 rows (the planes of a cone of admissible normals).
_PAIRS = [np.triu_indices(k, 1) for k in range(32)]


def _contact(i, j, kind, point, normals, gap, facet_i, facet_j, normal, basis, rounding, coincide) -> Contact:
    """A point contact of blocks i < j at ``point`` (one admissible normal, or a cone of them)."""
    normals = np.asarray(normals, dtype=float).reshape(-1, 3)
    vertices = np.asarray(point, dtype=float).reshape(1, 3).copy()
    origin = vertices[0].copy()
    cone = None if len(normals) == 1 else normals.copy()
    for array in (normal, vertices, origin, basis) + (() if cone is None else (cone,)):
        array.setflags(write=False)
    separation = float(gap) if gap > coincide else 0.0
    return Contact(int(i), int(j), normal, vertices, 0.0, int(facet_i), int(facet_j), shapely.Polygon(), origin,
                   basis, 0.0, True, separation, float(rounding), kind=kind, normals=cone)


def _near(centres_a, radii_a, centres_b, radii_b, tol) -> np.ndarray:
    """Index pairs (a, b) of balls within ``tol`` of each other, through k-d trees per size class."""
    centres_a, centres_b = np.asarray(centres_a, float).reshape(-1, 3), np.asarray(centres_b, float).reshape(-1, 3)
    if not len(centres_a) or not len(centres_b):
        return np.zeros((0, 2), dtype=int)
    classes_a, classes_b = _size_classes(radii_a), _size_classes(radii_b)
    trees_b = [cKDTree(centres_b[members]) for members in classes_b]
    out = []
    for members_a in classes_a:
        tree = cKDTree(centres_a[members_a])
        top_a = float(radii_a[members_a].max())
        for members_b, tree_b in zip(classes_b, trees_b):
            reach = top_a + float(radii_b[members_b].max()) + tol
            hits = tree.sparse_distance_matrix(tree_b, reach, output_type="ndarray")
            if not len(hits):
                continue
            ia, ib = members_a[hits["i"]], members_b[hits["j"]]
            close = hits["v"] <= radii_a[ia] + radii_b[ib] + tol
            out.append(np.column_stack([ia[close], ib[close]]))
    return np.vstack(out) if out else np.zeros((0, 2), dtype=int)


def _size_classes(radii) -> list:
    """Indices grouped by radius, each class within a factor 4 (points are one class)."""
    radii = np.asarray(radii, dtype=float)
    level = np.where(radii > 0, np.floor(np.log(np.maximum(radii, 1e-300)) / np.log(4.0)), -np.inf)
    return [np.flatnonzero(level == v) for v in np.unique(level)]


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=1)[:, None]
