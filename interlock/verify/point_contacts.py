"""Vertex and edge contacts between blocks (main paper Remark 3.11): vertex-face, edge-edge, vertex-edge, vertex-vertex."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.optimize import nnls
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
    """The corners and feature edges of one closed mesh, in its own frame.

    A *corner* is a vertex where three or more facets meet; a *feature edge*
    is a mesh edge between two different facets (triangulation diagonals
    inside a facet are none).  ``corner_normals[k]`` are the outward normals
    of the facets at corner ``corners[k]``; ``edge_normals[e]`` those of the
    two facets at edge ``e``.  Only convex corners and edges (every feature
    edge at a corner convex; an edge whose dihedral angle is below pi) take
    part in point contacts: at a reflex edge or a saddle the local solid is
    no convex cone, and no contact is made of it (a contact left out only
    weakens the model, never makes a motion look blocked).
    """

    vertices: np.ndarray
    corners: np.ndarray
    corner_normals: tuple
    corner_convex: np.ndarray
    edges: np.ndarray
    edge_normals: np.ndarray
    edge_convex: np.ndarray
    is_corner: np.ndarray


def features(mesh, facets) -> Features:
    """The :class:`Features` of a merged mesh and its :class:`~interlock.verify.facets.Facets`.

    >>> import trimesh
    >>> from interlock.verify.facets import facets as find_facets, merged
    >>> box = merged(trimesh.creation.box())
    >>> f = features(box, find_facets(box))
    >>> len(f.corners), len(f.edges), bool(f.corner_convex.all() and f.edge_convex.all())
    (8, 12, True)
    """
    faces = np.asarray(mesh.faces)
    label = np.full(len(faces), -1)
    for f, members in enumerate(facets.faces):
        label[members] = f
    vertices = np.asarray(mesh.vertices, dtype=float)
    adjacency = np.asarray(mesh.face_adjacency).reshape(-1, 2)
    shared = np.asarray(mesh.face_adjacency_edges).reshape(-1, 2)
    unshared = np.asarray(mesh.face_adjacency_unshared).reshape(-1, 2)
    la, lb = label[adjacency[:, 0]], label[adjacency[:, 1]]
    feature = (la >= 0) & (lb >= 0) & (la != lb)
    la, lb, shared, unshared = la[feature], lb[feature], shared[feature], unshared[feature]
    normals = np.asarray(facets.normals)
    edge_normals = np.stack([normals[la], normals[lb]], axis=1)
    # convex: the other facet's far vertex lies below this facet's plane
    far = np.einsum("ki,ki->k", normals[la], vertices[unshared[:, 1]] - vertices[shared[:, 0]])
    edge_convex = far < 0
    # corners: three or more facets at a vertex
    used = label >= 0
    pairs = np.unique(np.column_stack([faces[used].ravel(), np.repeat(label[used], 3)]), axis=0)
    count = np.bincount(pairs[:, 0], minlength=len(vertices))
    is_corner = count >= 3
    corners = np.flatnonzero(is_corner)
    starts = np.searchsorted(pairs[:, 0], corners)
    corner_normals = tuple(normals[pairs[s:s + c, 1]] for s, c in zip(starts, count[corners]))
    reflex_at = np.zeros(len(vertices), dtype=bool)
    reflex_at[shared[~edge_convex].ravel()] = True
    for array in (vertices, corners, edge_normals, edge_convex, is_corner):
        array.setflags(write=False)
    return Features(vertices, corners, corner_normals, ~reflex_at[corners], shared, edge_normals, edge_convex,
                    is_corner)


def admissible_normals(outward_i, outward_j, angle: float = CONE_ANGLE) -> np.ndarray:
    """The cone of admissible normals where convex features of blocks ``i`` and ``j`` touch, as generators.

    ``outward_i`` are the outward normals of block ``i``'s facets at the
    contact point (one for a face, two for an edge, three or more for a
    corner), ``outward_j`` block ``j``'s.  A plane with normal ``n`` (from
    ``i`` towards ``j``) separates the two local cones exactly when ``n`` is
    in the polar cone of ``i``'s, ``cone(outward_i)``, and in the dual of
    ``j``'s, ``cone(-outward_j)``; the admissible normals are their
    intersection.  Returns one unit row when the intersection is one ray
    (within ``angle``), its extreme rays when it is wider, and no row when it
    is empty (the blocks press into each other there).

    >>> admissible_normals([[1, 0, 0]], [[-1, 0, 0]]).tolist()        # a face on a face
    [[1.0, 0.0, 0.0]]
    >>> len(admissible_normals([[1, 0, 0], [0, 1, 0]], [[-1, 0, 0], [0, -1, 0]]))  # diagonal cubes' edges
    2
    """
    G = _unit(np.asarray(outward_i, dtype=float).reshape(-1, 3))
    H = _unit(-np.asarray(outward_j, dtype=float).reshape(-1, 3))
    candidates = [G, H]
    planes_g = _face_planes(G)
    planes_h = _face_planes(H)
    if len(planes_g) and len(planes_h):
        meet = np.cross(planes_g[:, None], planes_h[None]).reshape(-1, 3)
        meet = meet[np.linalg.norm(meet, axis=1) > 1e-12]
        if len(meet):
            meet = _unit(meet)
            candidates += [meet, -meet]
    rays = np.vstack(candidates)
    tol = np.sin(angle)
    inside = np.array([_in_cone(G, r, tol) and _in_cone(H, r, tol) for r in rays], dtype=bool)
    rays = rays[inside]
    if not len(rays):
        return np.zeros((0, 3))
    mean = rays.sum(axis=0)
    if np.linalg.norm(mean) > 1e-12:
        mean /= np.linalg.norm(mean)
        if np.all(np.linalg.norm(np.cross(rays, mean), axis=1) <= tol) and np.all(rays @ mean > 0):
            return mean[None]
    # distinct rays only
    kept = []
    for r in rays:
        if all(np.linalg.norm(r - k) > tol for k in kept):
            kept.append(r)
    return np.array(kept)


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
    """
    by_pair = {}
    for c in faces:
        by_pair.setdefault((c.i, c.j), []).append(c)
    found = []
    cache = {}
    for i, j in np.asarray(pairs, dtype=int).reshape(-1, 2).tolist():
        a, b = _placed(table, i, cache), _placed(table, j, cache)
        if a is None or b is None:
            continue
        tol = float(tolerances.search[i] + tolerances.search[j])
        rounding = float(max(tolerances.rounding[i], tolerances.rounding[j]))
        coincide = float(max(tolerances.coincide[i], tolerances.coincide[j]))
        angle = max(float(tolerances.angle), CONE_ANGLE)
        contacts = _pair_points(table, i, j, a, b, tol, angle)
        pair_faces = by_pair.get((i, j), ())
        kept = []
        for kind, point, normals, gap, facet_i, facet_j in contacts:
            if implied_by_faces(point, pair_faces, tol):
                continue
            if any(k[0] == kind and np.linalg.norm(k[1] - point) <= tol for k in kept):
                continue  # the same touch found twice (collinear edge pieces, both corners' sides)
            kept.append((kind, point, normals, gap, facet_i, facet_j))
        for kind, point, normals, gap, facet_i, facet_j in kept:
            found.append(_contact(i, j, kind, point, normals, gap, facet_i, facet_j, rounding, coincide))
    return tuple(found)


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
    corner_normals: tuple
    edges: np.ndarray  # convex feature edges (vertex index pairs)
    edge_normals: np.ndarray
    is_corner: np.ndarray


def _placed(table, block: int, cache: dict):
    """Block ``block``'s convex features in world coordinates (cached per call, features per mesh type)."""
    if block in cache:
        return cache[block]
    t = int(table.types[block])
    if t not in table.per_type:
        cache[block] = None
        return None
    if ("type", t) not in cache:
        cache[("type", t)] = features(table.merged[t], table.per_type[t])
    feats = cache[("type", t)]
    rotation, shift = table.transforms[block, :3, :3], table.transforms[block, :3, 3]
    vertices = feats.vertices @ rotation.T + shift
    convex = feats.corner_convex
    corners = feats.corners[convex]
    normals = tuple(n @ rotation.T for n, ok in zip(feats.corner_normals, convex) if ok)
    edges = feats.edges[feats.edge_convex]
    edge_normals = feats.edge_normals[feats.edge_convex] @ rotation.T
    placed = _Placed(block, vertices, corners, vertices[corners], normals, edges, edge_normals, feats.is_corner)
    cache[block] = placed
    return placed


def _pair_points(table, i, j, a: _Placed, b: _Placed, tol: float, angle: float):
    """(kind, point, normals, gap, facet_i, facet_j) of every touch of features of blocks i (a) and j (b)."""
    out = []
    # vertex-face: corners of one block strictly inside a facet of the other
    for corner_block, face_block, sign in ((b, a, 1.0), (a, b, -1.0)):
        out += _vertex_face(table, corner_block, face_block, sign, tol, angle, i)
    # edge-edge, not parallel, crossing at interior points
    out += _edge_edge(a, b, tol, angle)
    # vertex-edge and vertex-vertex: the cone of admissible normals
    out += _vertex_edge(a, b, tol, angle, 1.0)
    out += _vertex_edge(b, a, tol, angle, -1.0)
    out += _vertex_vertex(a, b, tol, angle)
    return out


def _vertex_face(table, corner_block: _Placed, face_block: _Placed, sign, tol, angle, i):
    """Corners of ``corner_block`` within ``tol`` of a facet of ``face_block``, strictly inside it."""
    if not len(corner_block.corners):
        return []
    block = face_block.block
    facets = np.arange(table.start[block], table.start[block + 1])
    if not len(facets):
        return []
    normals, origins = table.normals[facets], table.origins[facets]
    box = shapely.bounds(table.polygons[facets])
    radius = np.hypot(np.maximum(np.abs(box[:, 0]), np.abs(box[:, 2])), np.maximum(np.abs(box[:, 1]), np.abs(box[:, 3])))
    points = corner_block.corner_points
    hits = _near(origins, radius, points, np.zeros(len(points)), tol)
    out = []
    for f, k in hits:
        g = facets[f]
        offset = points[k] - origins[f]
        distance = float(offset @ normals[f])
        if abs(distance) > tol:
            continue
        xy = shapely.Point(offset @ table.bases[g].T)
        polygon = table.polygons[g]
        if not polygon.contains(xy) or polygon.boundary.distance(xy) <= tol:
            continue
        n = normals[f]
        cone = admissible_normals(n, corner_block.corner_normals[k], angle)
        if len(cone) != 1:  # the corner's solid reaches through the face: they press into each other
            continue
        local = int(table.local[g])
        facet_i, facet_j = (local, -1) if sign > 0 else (-1, local)
        out.append(("vertex-face", points[k] - 0.5 * distance * n, sign * n[None], distance, facet_i, facet_j))
    return out


def _edge_edge(a: _Placed, b: _Placed, tol, angle):
    """Convex feature edges of a and b crossing (not parallel) at interior points within ``tol``."""
    if not len(a.edges) or not len(b.edges):
        return []
    pa, qa = a.vertices[a.edges[:, 0]], a.vertices[a.edges[:, 1]]
    pb, qb = b.vertices[b.edges[:, 0]], b.vertices[b.edges[:, 1]]
    ca, cb = (pa + qa) / 2, (pb + qb) / 2
    ra, rb = np.linalg.norm(qa - pa, axis=1) / 2, np.linalg.norm(qb - pb, axis=1) / 2
    hits = _near(ca, ra, cb, rb, tol)
    if not len(hits):
        return []
    ea, eb = hits[:, 0], hits[:, 1]
    u, w = qa[ea] - pa[ea], qb[eb] - pb[eb]
    cross = np.cross(u, w)
    length = np.linalg.norm(cross, axis=1)
    lu, lw = np.linalg.norm(u, axis=1), np.linalg.norm(w, axis=1)
    # not parallel: the lines part by more than the tolerance over the shorter edge
    transverse = length > np.maximum(np.sin(angle), tol / np.minimum(lu, lw)) * lu * lw
    out = []
    for k in np.flatnonzero(transverse):
        x, y = ea[k], eb[k]
        d = pb[y] - pa[x]
        uu, ww, uw = u[k] @ u[k], w[k] @ w[k], u[k] @ w[k]
        det = uu * ww - uw * uw
        s = ((d @ u[k]) * ww - (d @ w[k]) * uw) / det
        t = ((d @ u[k]) * uw - (d @ w[k]) * uu) / det
        if not (0.0 <= s <= 1.0 and 0.0 <= t <= 1.0):
            continue
        on_a, on_b = pa[x] + s * u[k], pb[y] + t * w[k]
        if np.linalg.norm(on_b - on_a) > tol:
            continue
        if _near_corner(a, a.edges[x], on_a, tol) or _near_corner(b, b.edges[y], on_b, tol):
            continue  # at a corner: a vertex-edge or vertex-vertex touch
        n = cross[k] / length[k]
        if n @ a.edge_normals[x].sum(axis=0) < 0:
            n = -n
        # the plane of the two edges separates the two wedges: n in cone(a's normals), -n in cone(b's)
        tol_angle = np.sin(angle)
        if not (_in_cone(a.edge_normals[x], n, tol_angle) and _in_cone(b.edge_normals[y], -n, tol_angle)):
            continue
        out.append(("edge-edge", (on_a + on_b) / 2, n[None], float((on_b - on_a) @ n), -1, -1))
    return out


def _vertex_edge(a: _Placed, b: _Placed, tol, angle, sign):
    """Corners of b on the interior of convex feature edges of a (``sign`` -1: a is block j)."""
    if not len(a.edges) or not len(b.corners):
        return []
    pa, qa = a.vertices[a.edges[:, 0]], a.vertices[a.edges[:, 1]]
    ca, ra = (pa + qa) / 2, np.linalg.norm(qa - pa, axis=1) / 2
    hits = _near(ca, ra, b.corner_points, np.zeros(len(b.corners)), tol)
    out = []
    for e, k in hits:
        u = qa[e] - pa[e]
        s = float((b.corner_points[k] - pa[e]) @ u / (u @ u))
        if not 0.0 <= s <= 1.0:
            continue
        on_a = pa[e] + s * u
        if np.linalg.norm(b.corner_points[k] - on_a) > tol or _near_corner(a, a.edges[e], on_a, tol):
            continue
        outward_a, outward_b = a.edge_normals[e], b.corner_normals[k]
        if sign < 0:
            outward_a, outward_b = outward_b, outward_a
        cone = admissible_normals(outward_a, outward_b, angle)
        if not len(cone):
            continue
        gap = float(np.linalg.norm(b.corner_points[k] - on_a))
        out.append(("vertex-edge", (on_a + b.corner_points[k]) / 2, cone, gap, -1, -1))
    return out


def _vertex_vertex(a: _Placed, b: _Placed, tol, angle):
    """Corners of a and b within ``tol`` of each other."""
    if not len(a.corners) or not len(b.corners):
        return []
    out = []
    for k, m in _near(a.corner_points, np.zeros(len(a.corners)), b.corner_points, np.zeros(len(b.corners)), tol):
        cone = admissible_normals(a.corner_normals[k], b.corner_normals[m], angle)
        if not len(cone):
            continue
        gap = float(np.linalg.norm(b.corner_points[m] - a.corner_points[k]))
        out.append(("vertex-vertex", (a.corner_points[k] + b.corner_points[m]) / 2, cone, gap, -1, -1))
    return out


def _near_corner(placed: _Placed, edge, point, tol) -> bool:
    """Whether ``point`` on ``edge`` lies within ``tol`` of an end of the edge that is a corner."""
    return any(placed.is_corner[v] and np.linalg.norm(placed.vertices[v] - point) <= tol for v in edge)


def _contact(i, j, kind, point, normals, gap, facet_i, facet_j, rounding, coincide) -> Contact:
    """A point contact of blocks i < j at ``point`` (one admissible normal, or a cone of them)."""
    normals = np.asarray(normals, dtype=float).reshape(-1, 3)
    normal = normals.sum(axis=0)
    normal = normal / np.linalg.norm(normal)
    vertices = np.asarray(point, dtype=float).reshape(1, 3).copy()
    origin = vertices[0].copy()
    basis = plane_bases(normal[None])[0]
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
    out = []
    for members_a in classes_a:
        tree = cKDTree(centres_a[members_a])
        top_a = float(radii_a[members_a].max())
        for members_b in classes_b:
            reach = top_a + float(radii_b[members_b].max()) + tol
            hits = tree.query_ball_point(centres_b[members_b], reach)
            sizes = np.fromiter(map(len, hits), dtype=int, count=len(hits))
            if not sizes.sum():
                continue
            ia = members_a[np.concatenate([h for h in hits if h]).astype(int)]
            ib = np.repeat(members_b, sizes)
            close = (np.linalg.norm(centres_a[ia] - centres_b[ib], axis=1) <= radii_a[ia] + radii_b[ib] + tol)
            out.append(np.column_stack([ia[close], ib[close]]))
    return np.vstack(out) if out else np.zeros((0, 2), dtype=int)


def _size_classes(radii) -> list:
    """Indices grouped by radius, each class within a factor 4 (points are one class)."""
    radii = np.asarray(radii, dtype=float)
    level = np.where(radii > 0, np.floor(np.log(np.maximum(radii, 1e-300)) / np.log(4.0)), -np.inf)
    return [np.flatnonzero(level == v) for v in np.unique(level)]


def _face_planes(generators: np.ndarray) -> np.ndarray:
    """Normals of the planes through pairs of generators (the 2D faces a cone's boundary may lie in)."""
    if len(generators) < 2:
        return np.zeros((0, 3))
    k = len(generators)
    a, b = np.triu_indices(k, 1)
    planes = np.cross(generators[a], generators[b])
    return planes[np.linalg.norm(planes, axis=1) > 1e-12]


def _in_cone(generators, ray, tol: float) -> bool:
    """Whether the unit ``ray`` lies in the cone of ``generators`` within ``tol`` (a residual, about an angle)."""
    generators = np.asarray(generators, dtype=float).reshape(-1, 3)
    _, residual = nnls(generators.T, np.asarray(ray, dtype=float))
    return residual <= tol


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=1)[:, None]
