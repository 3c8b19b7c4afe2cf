"""Closed bodies of one triangle soup: touching solids told apart by pairing the half-edges of coincident edges."""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from interlock.blocks.repair import MERGE_RTOL, merge_vertices
from interlock.errors import InterlockError

__all__ = ["BodiesError", "closed_bodies", "ANGLE_TIE"]

#: Faces around an edge whose angles about it differ by at most this (radians) lie on one plane: two bodies
#: touching face to face.  Their order then follows the side each face's body lies on.
ANGLE_TIE = 1e-9


class BodiesError(InterlockError):
    """A triangle soup that cannot be split into closed, consistently oriented bodies (the reason says where)."""


def closed_bodies(vertices, faces, rtol: float = MERGE_RTOL) -> list[trimesh.Trimesh]:
    """Split a triangle soup holding several closed bodies that touch into those bodies.

    Bodies that touch share vertices, edges, even whole triangles, so
    connected components do not separate them.  Half-edges do: in a closed,
    consistently oriented body every half-edge ``u -> v`` has a twin
    ``v -> u``.  Where several bodies meet along one edge, the faces around
    it are ordered by their angle about the edge; each face's body lies on
    the side its normal points away from, so the face is paired with the
    next face on that side, which must run the edge the other way and turn
    its body's side back towards it.  Faces paired across every edge are one
    body.

    Parameters
    ----------
    vertices : array (n, 3)
    faces : array (m, 3) of int
        Triangles wound counter-clockwise seen from outside (outward
        normals), as mesh files ship closed bodies; a soup wound the other
        way throughout is turned first.
    rtol : float
        Vertices within ``rtol`` of the extent of the soup are one point
        (:func:`~interlock.blocks.repair.merge_vertices`).

    Returns
    -------
    list of trimesh.Trimesh
        The closed bodies, each consistently oriented outward, in the order
        of their first triangle.

    Raises
    ------
    BodiesError
        When the soup really cannot be separated, naming the edge: an edge
        with a triangle on one side only (an open surface), the two windings
        of an edge not balanced (faces turned against their body), faces
        around an edge that do not pair up (bodies whose insides overlap),
        or a body that comes out inside out.

    Examples
    --------
    Two cubes sharing a square face (written twice, once per cube):

    >>> a = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    >>> b = trimesh.creation.box(bounds=[[1, 0, 0], [2, 1, 1]])
    >>> soup = trimesh.util.concatenate([a, b])
    >>> welded = trimesh.Trimesh(soup.vertices, soup.faces)  # vertices merged, as an STL reader gives them
    >>> [(round(float(body.volume), 12), body.is_watertight) for body in closed_bodies(welded.vertices, welded.faces)]
    [(1.0, True), (1.0, True)]

    Notes
    -----
    After merging vertices, ``O(m log m)``: edges shared by two faces (the
    common case) pair at once; only edges of more faces are sorted by angle.
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if not len(faces):
        return []
    vertices, faces = merge_vertices(vertices, faces, rtol)
    tri = vertices[faces]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    faces = faces[area > np.finfo(float).eps * max(float(np.ptp(vertices, axis=0).max()), 1e-300) ** 2]
    if _signed_volume(vertices, faces) < 0:  # wound inward throughout: turn every face
        faces = faces[:, ::-1]
    partner = _partners(vertices, faces)
    count = len(faces)
    graph = coo_matrix((np.ones(len(partner)), (partner[:, 0], partner[:, 1])), shape=(count, count))
    parts, label = connected_components(graph, directed=False)
    first = np.full(parts, count)
    np.minimum.at(first, label, np.arange(count))
    bodies = []
    for rank, part in enumerate(np.argsort(first, kind="stable")):
        mine = faces[label == part]
        used, local = np.unique(mine, return_inverse=True)
        body = trimesh.Trimesh(vertices[used], local.reshape(-1, 3), process=False)
        if _signed_volume(body.vertices, body.faces) <= 0:
            raise BodiesError(f"body {rank} (triangles from {int(first[part])}) encloses no positive volume: it is "
                              "inside out, or flat")
        bodies.append(body)
    return bodies


def _partners(vertices, faces) -> np.ndarray:
    """Pairs (face, face) that share an edge and one body: across each edge, each face with its twin."""
    a = faces.ravel()
    b = np.roll(faces, -1, axis=1).ravel()
    third = np.roll(faces, -2, axis=1).ravel()
    owner = np.repeat(np.arange(len(faces)), 3)
    low, high = np.minimum(a, b), np.maximum(a, b)
    forward = a < b  # the half-edge runs low -> high
    key = low * len(vertices) + high
    order = np.argsort(key, kind="stable")
    key, low, high, forward, third, owner = (x[order] for x in (key, low, high, forward, third, owner))
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    sizes = np.diff(np.r_[starts, len(key)])
    ups = np.add.reduceat(forward.astype(int), starts)
    odd = np.flatnonzero(2 * ups != sizes)
    if len(odd):
        k = starts[odd[0]]
        edge = (vertices[low[k]], vertices[high[k]])
        if sizes[odd[0]] == 1:
            raise BodiesError(f"the surface is open: the edge {_point(edge[0])}-{_point(edge[1])} has a triangle "
                              f"on one side only ({int(np.sum(sizes[odd] == 1))} such edges); a body must be closed")
        raise BodiesError(f"the edge {_point(edge[0])}-{_point(edge[1])} is run {ups[odd[0]]} times one way and "
                          f"{sizes[odd[0]] - ups[odd[0]]} times the other ({len(odd)} such edges): triangles are "
                          "turned against their body, or a body is open there")
    pairs = [np.column_stack([owner[starts[sizes == 2]], owner[starts[sizes == 2] + 1]])]
    for k, size in zip(starts[sizes > 2], sizes[sizes > 2]):
        rows = slice(k, k + size)
        pairs.append(_around_edge(vertices, low[k], high[k], third[rows], forward[rows], owner[rows]))
    return np.vstack(pairs)


def _around_edge(vertices, u, v, third, forward, owner) -> np.ndarray:
    """Pair the faces around the edge u-v: each with the next face on the side its body lies on."""
    axis = vertices[v] - vertices[u]
    axis = axis / np.linalg.norm(axis)
    basis = np.linalg.svd(axis[None])[2][1:]  # two unit vectors perpendicular to the edge
    offset = vertices[third] - vertices[u]
    offset = offset - np.outer(offset @ axis, axis)
    angle = np.arctan2(offset @ basis[1], offset @ basis[0])
    # a face running the edge u -> v (forward) has its outward normal along axis x (its direction): its body lies
    # on the other side, turning counter-clockwise about the axis when (axis x d) . n < 0
    direction = offset / np.linalg.norm(offset, axis=1)[:, None]
    normal = np.cross(np.where(forward[:, None], 1.0, -1.0) * axis, direction)
    turn = np.cross(axis, direction)
    counter = np.einsum("ki,ki->k", turn, normal) < 0  # the body lies counter-clockwise from the face
    if np.linalg.det(np.vstack([basis[0], basis[1], axis])) < 0:
        counter = ~counter
    # faces in one plane: the one whose body lies clockwise first, so the empty wedge between them is outside
    tied = np.round(angle / ANGLE_TIE) * ANGLE_TIE
    order = np.lexsort((counter, tied))
    size = len(order)
    position = np.empty(size, dtype=int)
    position[order] = np.arange(size)
    mate = np.where(counter, order[(position + 1) % size], order[(position - 1) % size])
    if np.any(mate[mate] != np.arange(size)) or np.any(forward[mate] == forward):
        p, q = vertices[u], vertices[v]
        raise BodiesError(f"the {size} triangles at the edge {_point(p)}-{_point(q)} do not pair up into closed "
                          "bodies: the insides of bodies overlap there, or triangles are turned against them")
    keep = np.arange(size) < mate
    return np.column_stack([owner[keep], owner[mate[keep]]])


def _signed_volume(vertices, faces) -> float:
    tri = vertices[faces]
    return float(np.einsum("ki,ki->k", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def _point(p) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in p) + ")"

