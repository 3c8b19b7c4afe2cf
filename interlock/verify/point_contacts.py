"""Point contacts of blocks (main paper Remark 3.11): vertex-face, edge-edge, vertex-edge, vertex-vertex."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.spatial import cKDTree

from interlock.blocks.contact import Contact, plane_bases
from interlock.verify.tangent_cones import CONE_ANGLE, admissible_normals, mesh_features

__all__ = ["point_contacts", "contact_kinds", "POINT_KINDS", "LINEAR_KINDS"]

#: The kinds a point contact can have (a point of zero area; see :data:`~interlock.blocks.contact.CONTACT_KINDS`).
POINT_KINDS = ("vertex-face", "edge-edge", "vertex-edge", "vertex-vertex")
#: Kinds whose contacts always admit exactly one normal: one row each (Remark 3.11).
LINEAR_KINDS = ("face", "vertex-face", "edge-edge")


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
    cache = dict(zip(types, mesh_features([table.merged[t] for t in types], [table.per_type[t] for t in types])))
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


