"""Tangent cones of closed meshes at their corners and edges, and the admissible normals where two of them touch."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

__all__ = ["Features", "features", "mesh_features", "admissible_normals", "CONE_ANGLE"]

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
    return mesh_features([mesh], [facets])[0]


def mesh_features(meshes, facets_list) -> list:
    """The :class:`Features` of several merged meshes and their facets at once (one pass of array operations).

    >>> import trimesh
    >>> from interlock.verify.facets import facets as find_facets, merged
    >>> boxes = [merged(trimesh.creation.box()), merged(trimesh.creation.box(bounds=[[0, 0, 0], [2, 1, 1]]))]
    >>> [len(f.corners) for f in mesh_features(boxes, [find_facets(b) for b in boxes])]
    [8, 8]
    """
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


# --- private helpers --------------------------------------------------------------------------------


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


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=1)[:, None]
