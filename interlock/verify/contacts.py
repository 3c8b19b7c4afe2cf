"""Face-to-face contacts between the blocks of an assembly (main paper Def. 3.3)."""

from __future__ import annotations


import math
from dataclasses import dataclass, field, replace
from numbers import Real

import numpy as np
import shapely
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from interlock.blocks.assembly import NEIGHBOUR_RTOL, Assembly
from interlock.errors import InterlockError

__all__ = [
    "Contact",
    "ContactError",
    "Facets",
    "contacts",
    "facets",
    "DEFAULT_CONTACT_RTOL",
    "DEFAULT_ANGLE_TOL",
    "DEFAULT_AREA_RTOL",
    "DEFAULT_GAP_RTOL",
    "PLANAR_ULPS",
]

#: Distance tolerance relative to the model size: two planes closer than this
#: coincide, a gap narrower than this is a contact, an overlap thinner than this
#: is an edge touch, and facet outlines are simplified within it.  Mesh files
#: from CAD tools are often accurate to a few 1e-6 only (TopoLite's ``ania``).
DEFAULT_CONTACT_RTOL = 1e-5
#: Angle tolerance (radians): normals within it are parallel (facets) or
#: opposite (contacts).  Rotated pieces in files may be off by ~4e-5 rad (``ania``).
DEFAULT_ANGLE_TOL = 1e-4
#: Contact polygons of area at most this times the model size squared are dropped.
DEFAULT_AREA_RTOL = 1e-10
#: Gap tolerance relative to the model size: facets whose planes are at most this far apart (beyond ``rtol``)
#: are in contact, across the gap.  Zero: only faces that really touch (within ``rtol``) are contacts.
DEFAULT_GAP_RTOL = 0.0
#: Overlaps are computed on a precision grid of this times the model size (GEOS snap rounding):
#: in plain floating point, GEOS can return a whole square as the overlap of two squares that only
#: share an edge with 1e-16 noise.
OVERLAY_GRID_RTOL = 1e-13
#: Instanced pairs of one kind (:meth:`Assembly.pair_kinds`) share one contact computation; that path is
#: taken when kinds are at most this share of the pairs.
KIND_SHARE = 0.5

#: A facet is planar when every vertex of its triangles lies within this many units in the last place (of
#: the mesh's largest coordinate) of its plane, i.e. within rounding; farther means the tolerances grouped
#: triangles that are not coplanar (a face bent by less than ``angle_tol``).  A bend of 1e-14 on a unit
#: block is about 25 such units; rounding leaves well under one.
PLANAR_ULPS = 8

# Floor for tolerances of zero in the spatial index (relative; keeps its metric finite).
_TINY = 1e-15


class ContactError(InterlockError):
    """Input that :func:`contacts` cannot work with (not an assembly, bad tolerances)."""


@dataclass(frozen=True, eq=False)
class Contact:
    """One face-to-face contact polygon between blocks ``i < j`` (one row group of Def. 3.3).

    Attributes
    ----------
    i, j : int
        The blocks in contact, ``i < j``.
    normal : array (3,)
        Unit normal pointing from block ``i`` towards block ``j`` (block ``i``'s
        outward facet normal).
    vertices : array (k, 3)
        The overlap polygon on block ``i``'s facet plane (with ``gap > 0``: on
        the parallel plane halfway to block ``j``'s facet, see :func:`contacts`):
        the exterior ring (counter-clockwise about ``normal``, no closing
        repeat), then each hole ring.  Every vertex gives rows of the
        interlocking matrix.
    area : float
        Area of the polygon.
    facet_i, facet_j : int
        Indices of the touching facets in :func:`facets` of each block.
    polygon : shapely.Polygon
        The polygon in 2D plane coordinates: ``origin + x * basis[0] + y * basis[1]``.
    origin : array (3,)
        A point of the plane (the centroid of block ``i``'s facet, moved halfway
        to block ``j``'s facet when ``gap > 0``).
    basis : array (2, 3)
        Orthonormal in-plane vectors with ``basis[0] x basis[1] = normal``.
    deviation : float
        How far the blocks' real faces stray from the modelled common plane
        over this contact: the flatness of either facet (:attr:`Facets.flatness`)
        plus the largest distance of a contact vertex from block ``j``'s facet
        plane (for a contact across a gap, its :attr:`separation`).  Zero up to
        rounding for faces that really are coplanar.
    planar : bool
        Both facets are planar up to rounding (:attr:`Facets.planar`).  When
        False, the tolerances merged triangles bent by a small angle into one
        facet: the real contact has several planes, so it may block a sliding
        motion that the modelled one allows.  A gap does not make a contact
        non-planar: two parallel planar faces a gap apart block no sliding
        either (see :func:`contacts`).
    separation : float
        The gap this contact bridges: zero for faces that touch (coplanar
        within ``rtol``, and always when ``gap = 0``); for a contact found only
        thanks to ``gap > 0``, the largest distance from block ``j``'s facet
        plane of the overlap's vertices on block ``i``'s facet plane (at most
        ``(rtol + gap) * scale``; also part of :attr:`deviation`).
    """

    i: int
    j: int
    normal: np.ndarray
    vertices: np.ndarray
    area: float
    facet_i: int
    facet_j: int
    polygon: shapely.Polygon = field(repr=False)
    origin: np.ndarray = field(repr=False)
    basis: np.ndarray = field(repr=False)
    deviation: float = 0.0
    planar: bool = True
    separation: float = 0.0

    @classmethod
    def at_points(cls, i: int, j: int, normal, points) -> Contact:
        """A point or line contact given by hand: block ``j``'s points ``points`` on block ``i``'s face.

        :func:`contacts` finds face-to-face contacts only (Remark 3.11); a
        corner or an edge of block ``j`` resting on a face of block ``i``
        (outward unit ``normal``, towards ``j``) gives one row of the
        interlocking matrix per point, and the gap function of
        :mod:`interlock.verify.second_order` (an n-pod leg, ``docs/npod.md``).

        >>> c = Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0], [1, 0, 0]])
        >>> len(c.vertices), c.area
        (2, 0.0)
        """
        if not (isinstance(i, (int, np.integer)) and isinstance(j, (int, np.integer)) and 0 <= i < j):
            raise ContactError(f"a contact needs block indices 0 <= i < j, got {i!r}, {j!r}")
        n = np.asarray(normal, dtype=float).reshape(-1)
        vertices = np.asarray(points, dtype=float).reshape(-1, 3) if np.size(points) else np.zeros((0, 3))
        if n.shape != (3,) or not np.isfinite(n).all() or not np.linalg.norm(n) > 0:
            raise ContactError(f"normal must be a non-zero finite 3D vector, got {normal!r}")
        if not len(vertices) or not np.isfinite(vertices).all():
            raise ContactError("points must be one or more finite 3D points, shape (k, 3)")
        n = n / np.linalg.norm(n)
        basis = _bases(n[None])[0]
        origin = vertices.mean(axis=0)
        for array in (n, vertices, origin, basis):
            array.setflags(write=False)
        return cls(int(i), int(j), n, vertices, 0.0, -1, -1, shapely.Polygon(), origin, basis)

    @property
    def ring_sizes(self) -> tuple[int, ...]:
        """Vertex counts of the exterior ring and of each hole, in the order of :attr:`vertices`."""
        if self.polygon.is_empty:  # a point or line contact (:meth:`at_points`)
            return (len(self.vertices),)
        rings = [self.polygon.exterior, *self.polygon.interiors]
        return tuple(len(ring.coords) - 1 for ring in rings)

    def __str__(self) -> str:
        n = ", ".join(f"{x:.3g}" for x in self.normal)
        holes = len(self.ring_sizes) - 1
        extra = f" with {holes} hole(s)" if holes else ""
        bent = "" if self.planar else f", faces bent by up to {self.deviation:.3g} (planar only within tolerance)"
        apart = f", across a gap of up to {self.separation:.3g}" if self.separation else ""
        return (f"contact {self.i}-{self.j}: {len(self.vertices)} vertices{extra}, area {self.area:.6g}, "
                f"normal ({n}), facets {self.facet_i}/{self.facet_j}{bent}{apart}")

    def to_dict(self) -> dict:
        """JSON-serialisable form; ``ring_sizes`` splits ``vertices`` into exterior and holes."""
        return {"i": self.i, "j": self.j, "normal": self.normal.tolist(), "vertices": self.vertices.tolist(),
                "ring_sizes": list(self.ring_sizes), "area": self.area, "facet_i": self.facet_i,
                "facet_j": self.facet_j, "origin": self.origin.tolist(), "basis": self.basis.tolist(),
                "deviation": self.deviation, "planar": self.planar, "separation": self.separation}


@dataclass(frozen=True, eq=False)
class Facets:
    """The planar facets of a triangle mesh: maximal edge-connected sets of coplanar triangles.

    Facet ``f`` is the polygon ``polygons[f]`` (2D, possibly non-convex, with
    holes) placed by ``origins[f] + x * bases[f, 0] + y * bases[f, 1]``; its
    outward normal is ``normals[f] = bases[f, 0] x bases[f, 1]``; ``faces[f]``
    lists its triangles.  Facets are ordered by their lowest triangle index.
    ``flatness[f]`` is the largest distance of a vertex of its triangles from
    its plane, and ``planar[f]`` says whether that is rounding only
    (:data:`PLANAR_ULPS`) rather than a bend the tolerances accepted.
    """

    normals: np.ndarray
    origins: np.ndarray
    bases: np.ndarray
    polygons: np.ndarray
    faces: tuple[np.ndarray, ...]
    flatness: np.ndarray
    planar: np.ndarray

    def __len__(self) -> int:
        return len(self.normals)

    @property
    def areas(self) -> np.ndarray:
        return shapely.area(self.polygons)


def contacts(assembly: Assembly, rtol: float = DEFAULT_CONTACT_RTOL, angle_tol: float = DEFAULT_ANGLE_TOL,
             area_rtol: float = DEFAULT_AREA_RTOL, involving=None,
             gap: float = DEFAULT_GAP_RTOL) -> tuple[Contact, ...]:
    """All face-to-face contacts between the blocks of an assembly.

    Two blocks are in contact where a facet of one and a facet of the other
    lie in a common plane with opposite outward normals and overlap in a region
    of positive area.  Each connected part of such an overlap is one
    :class:`Contact`; its vertices and normal give the rows of the
    infinitesimal interlocking matrix (main paper Def. 3.3).  Only
    face-to-face contacts are found: blocks touching along an edge or at a
    corner give none (Remark 3.11).

    With ``gap > 0``, facets with opposite normals whose planes are up to
    ``gap * scale`` apart (on either side: a slight overlap of the blocks
    counts as well) are in contact too, as in compas_assembly's interface
    detection (``tmax``): the contact is the overlap of the two facets
    projected onto a common plane, which models blocks that a file leaves
    slightly apart (rounded or independently modelled faces) and curved
    interfaces whose two triangulations do not match, which come out as many
    small planar contacts (the CRA paper's Fig. 5).

    Parameters
    ----------
    assembly : Assembly
        The blocks (closed triangle meshes; polygonal faces may be triangulated).
    rtol : float, optional
        Distance tolerance relative to ``assembly.scale`` (default
        ``DEFAULT_CONTACT_RTOL`` = 1e-5): facet planes whose offsets differ by at
        most ``rtol * scale`` coincide (so a gap that narrow still counts as a
        contact); overlaps thinner than it (twice the area over the perimeter)
        are edge touches and are dropped; outlines are simplified within it.
    angle_tol : float, optional
        Angle tolerance in radians (default ``DEFAULT_ANGLE_TOL`` = 1e-4) for
        opposite normals and for grouping triangles into facets.
    area_rtol : float, optional
        Overlaps of area at most ``area_rtol * scale**2`` are dropped (default
        ``DEFAULT_AREA_RTOL`` = 1e-10).
    involving : iterable of int, optional
        Only contacts of which at least one block is among these (default: all).
    gap : float, optional
        Gap tolerance relative to ``assembly.scale`` (default
        ``DEFAULT_GAP_RTOL`` = 0: only touching faces).  Facets with opposite
        normals (within ``angle_tol``) whose centroids lie within
        ``(rtol + gap) * scale`` of each other's planes, and whose overlap stays
        within that distance of block ``j``'s facet plane, are in contact.
        compas_cra's armadillo uses the absolute ``tmax = 0.05`` and
        ``amin = 1e-4`` on a model of scale 20.41, i.e. ``gap = 0.05 / scale``
        (about 2.45e-3) and ``area_rtol = 1e-4 / scale**2`` (about 2.4e-7).
        Upstream tests no angle, only that the vertices of one face lie within
        ``tmax`` of the other's plane (which lets faces of size ``L`` tilt by up
        to about ``2 tmax / L``): the armadillo's facing faces are up to 0.16
        rad apart, curved interfaces' facing triangles similarly, so pass a
        larger ``angle_tol`` (0.2 there) to pair faces as loosely.  Facets are
        still grouped within ``rtol``: the triangles of a polygon that is not
        flat stay apart and give one contact each.

    Returns
    -------
    tuple of Contact
        Sorted by ``(i, j, facet_i, facet_j)``.

    Raises
    ------
    ContactError
        If ``assembly`` is not an :class:`~interlock.blocks.Assembly` or a
        tolerance (``gap`` included) is negative, not finite or not a number
        (or ``angle_tol >= pi / 2``).

    See Also
    --------
    facets : the planar facets of one mesh, which ``facet_i`` and ``facet_j`` index.

    Notes
    -----
    Candidate pairs are the edges of ``assembly.neighbours`` (a spatial index on
    bounding boxes; :meth:`~Assembly.neighbour_graph` with ``rtol`` when it is
    larger), never all pairs.  Facets are computed once per block type and
    moved rigidly (mirror images included).  Per candidate pair, facets with
    opposite normals in coincident planes are matched through a k-d tree on
    (normal, plane offset), so the cost is ``O((F_i + F_j) log F)`` plus the
    matches, not ``O(F_i F_j)``.  Block ``j``'s facet is mapped into the 2D
    frame of block ``i``'s facet and all matched pairs are intersected at once
    with shapely (non-convex facets, holes and multi-part overlaps are
    handled).  Contact vertices lie on block ``i``'s facet plane.

    A contact found across a gap (``gap > 0``) is the overlap of the two
    facets projected orthogonally onto block ``i``'s facet plane, then moved
    along its normal halfway to block ``j``'s facet (the mid-plane, parallel to
    block ``i``'s facet); with ``gap > 0`` every contact is placed so, which
    moves touching ones by at most ``rtol * scale / 2``.  Its ``separation``
    and ``deviation`` record how far apart the faces were; ``planar`` keeps its
    meaning (both facets planar up to rounding), since a gap only makes the
    model stricter than the real blocks: a motion the model admits (a "not
    interlocked" verdict of :func:`~interlock.verify.check`) keeps faces that
    are really apart apart, whereas "interlocked" holds for the blocks with
    their gaps closed.  With ``gap = 0`` the results are exactly those
    without the parameter.

    Examples
    --------
    >>> cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)]
    >>> found = contacts(Assembly.from_meshes(cubes))
    >>> [(c.i, c.j, round(c.area, 9), c.normal.round(9).tolist()) for c in found]
    [(0, 1, 1.0, [1.0, 0.0, 0.0]), (1, 2, 1.0, [1.0, 0.0, 0.0])]
    >>> print(found[0])
    contact 0-1: 4 vertices, area 1, normal (1, 0, 0), facets 5/0
    """
    if not isinstance(assembly, Assembly):
        raise ContactError(f"contacts() needs an interlock Assembly, got {type(assembly).__name__}; "
                           "build one with Assembly.from_meshes or Assembly.load")
    rtol = _tolerance("rtol", rtol)
    angle_tol = _tolerance("angle_tol", angle_tol)
    area_rtol = _tolerance("area_rtol", area_rtol)
    gap = _tolerance("gap", gap)
    if angle_tol >= math.pi / 2:
        raise ContactError(f"angle_tol must be below pi/2 radians, got {angle_tol}")
    if len(assembly) < 2:
        return ()
    scale = assembly.scale
    graph = assembly.neighbours if rtol + gap <= NEIGHBOUR_RTOL else assembly.neighbour_graph(rtol + gap)
    pairs = np.array(sorted((min(u, v), max(u, v)) for u, v in graph.edges if u != v), dtype=int).reshape(-1, 2)
    if involving is not None:
        pairs = pairs[np.isin(pairs, assembly.block_indices(involving, "involving")).any(axis=1)]
    if not len(pairs):
        return ()
    kinds, kind_of, relative = assembly.pair_kinds(pairs)
    if len(kinds) > KIND_SHARE * len(pairs):
        return _pair_contacts(assembly, pairs, scale, rtol, angle_tol, area_rtol, gap)
    # instanced blocks: one computation per kind of pair, on a stand-in of two blocks, moved to every pair
    i, j = pairs[kinds].T
    relative = relative[kinds]
    stand_in = Assembly(assembly.meshes, np.column_stack([assembly.types[i], assembly.types[j]]).ravel(),
                        np.stack([np.broadcast_to(np.eye(4), relative.shape), relative], axis=1).reshape(-1, 4, 4))
    local = _pair_contacts(stand_in, np.arange(2 * len(kinds)).reshape(-1, 2), scale, rtol, angle_tol, area_rtol,
                           gap)
    by_kind = {}
    for contact in local:
        by_kind.setdefault(contact.i // 2, []).append(contact)
    found = [_moved(contact, int(a), int(b), assembly.transforms[a], assembly.mirrored[a])
             for (a, b), k in zip(pairs, kind_of) for contact in by_kind.get(int(k), ())]
    return tuple(sorted(found, key=lambda c: (c.i, c.j, c.facet_i, c.facet_j)))


def _pair_contacts(assembly, pairs, scale, rtol, angle_tol, area_rtol, gap=0.0) -> tuple[Contact, ...]:
    """Contacts of the given block pairs, tolerances relative to ``scale``."""
    table = _FacetTable(assembly, rtol * scale, angle_tol)
    gi, gj = _matches(table, pairs, (rtol + gap) * scale, angle_tol, scale, tilted=gap > 0)
    grid = 2.0 ** math.floor(math.log2(OVERLAY_GRID_RTOL * scale))  # a power of two keeps dyadic coordinates exact
    return _overlaps(table, gi, gj, rtol * scale, area_rtol * scale**2, grid, gap * scale)


def _moved(contact: Contact, i: int, j: int, transform: np.ndarray, mirrored: bool) -> Contact:
    """A contact computed with block i at the origin, placed for blocks i, j (block i moved by ``transform``)."""
    rotation, shift = transform[:3, :3], transform[:3, 3]
    basis, origin = contact.basis @ rotation.T, rotation @ contact.origin + shift
    polygon, vertices = contact.polygon, contact.vertices @ rotation.T + shift
    if mirrored:  # keep u x v = n and counter-clockwise rings: flip v and the polygon's y
        basis = basis * np.array([[1.0], [-1.0]])
        polygon = shapely.orient_polygons(shapely.transform(polygon, lambda xy: xy * [1.0, -1.0]))
        xy, ring = shapely.get_coordinates(shapely.get_rings(polygon), return_index=True)
        xy = xy[np.r_[ring[1:] == ring[:-1], False]]  # without each ring's closing repeat
        vertices = origin + xy @ basis
    arrays = [rotation @ contact.normal, vertices, origin, basis]
    for array in arrays:
        array.setflags(write=False)
    normal, vertices, origin, basis = arrays
    return replace(contact, i=i, j=j, normal=normal, vertices=vertices, origin=origin, basis=basis, polygon=polygon)


def facets(mesh: trimesh.Trimesh, atol: float | None = None, angle_tol: float = DEFAULT_ANGLE_TOL) -> Facets:
    """The planar facets of a triangle mesh (polygonal faces that a file format triangulated).

    Adjacent triangles (sharing an edge, after merging duplicate vertices)
    belong to one facet when their normals agree within ``angle_tol`` or the
    smaller one's far vertex lies within ``atol`` of the larger one's plane; a
    group that is not flat within ``atol`` (a finely tessellated curved
    surface) falls apart into its triangles.  A triangle in no group is a facet
    of its own.  Degenerate triangles are left out.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        An outward-oriented triangle mesh.
    atol : float, optional
        Distance tolerance; default ``DEFAULT_CONTACT_RTOL * mesh.scale``.
    angle_tol : float, optional
        Angle tolerance in radians.

    Returns
    -------
    Facets

    Examples
    --------
    >>> f = facets(trimesh.creation.box())
    >>> len(f), f.areas.round(12).tolist()
    (6, [1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    """
    if not isinstance(mesh, trimesh.Trimesh):
        raise ContactError(f"facets() needs a trimesh.Trimesh, got {type(mesh).__name__}")
    mesh = mesh.copy()
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    atol = DEFAULT_CONTACT_RTOL * mesh.scale if atol is None else _tolerance("atol", atol)
    return _facets(mesh, atol, _tolerance("angle_tol", angle_tol))


# --- private helpers ----------------------------------------------------------------------------


def _tolerance(name, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or value < 0:
        raise ContactError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def _facets(mesh: trimesh.Trimesh, atol: float, angle_tol: float) -> Facets:
    tri = mesh.triangles
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    twice_area = np.linalg.norm(cross, axis=1)
    good = twice_area > np.finfo(float).eps * max(mesh.scale, _TINY) ** 2
    normal = np.zeros_like(cross)
    normal[good] = cross[good] / twice_area[good, None]

    # coplanar neighbours: normals agree, or the smaller face's far vertex is on the larger's plane
    adj = mesh.face_adjacency
    adj = adj[good[adj].all(axis=1)] if len(adj) else adj.reshape(0, 2)
    keep = np.zeros(len(adj), dtype=bool)
    if len(adj):
        a, b = adj[:, 0], adj[:, 1]
        angle = 2 * np.arcsin(np.clip(np.linalg.norm(normal[a] - normal[b], axis=1) / 2, 0, 1))
        big_first = twice_area[a] >= twice_area[b]
        big, small = np.where(big_first, a, b), np.where(big_first, b, a)
        unshared = _unshared_vertex(mesh.faces[small], mesh.faces[big])
        far = np.abs(np.einsum("ij,ij->i", normal[big], mesh.vertices[unshared] - tri[big, 0]))
        same_side = np.einsum("ij,ij->i", normal[a], normal[b]) > 0
        keep = same_side & ((angle <= angle_tol) | (far <= atol))
    n_faces = len(mesh.faces)
    graph = coo_matrix((np.ones(keep.sum()), (adj[keep, 0], adj[keep, 1])), shape=(n_faces, n_faces))
    _, label = connected_components(graph, directed=False)

    # groups that are not flat fall apart into single triangles
    _, label = np.unique(label, return_inverse=True)
    nrm, org = _planes(label, cross, tri, good)
    dist = np.abs(np.einsum("fvi,fi->fv", tri - org[label][:, None], nrm[label])).max(axis=1)
    bent = np.zeros(label.max() + 1, dtype=bool)
    np.logical_or.at(bent, label[good], dist[good] > atol)
    split = bent[label]
    label = np.where(split, label.max() + 1 + np.arange(n_faces), label)
    label[~good] = -1
    # number facets by their lowest triangle index
    used = np.flatnonzero(good)
    _, first, label_g = np.unique(label[used], return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(used[first], kind="stable"), kind="stable")
    label = np.full(n_faces, -1)
    label[used] = order[label_g]
    n_facets = len(first)
    if n_facets == 0:
        raise ContactError("the mesh has no triangle of positive area")
    nrm, org = _planes(label[used], cross[used], tri[used], np.ones(len(used), dtype=bool))
    bases = _bases(nrm)

    # facet outlines: union of the projected triangles
    lab = label[used]
    flat = np.einsum("fvi,fai->fva", tri[used] - org[lab][:, None], bases[lab])
    triangles = shapely.polygons(flat)
    members = np.argsort(lab, kind="stable")
    groups = np.split(members, np.cumsum(np.bincount(lab, minlength=n_facets))[:-1])
    polygons = np.empty(n_facets, dtype=object)
    for f, group in enumerate(groups):
        polygons[f] = triangles[group[0]] if len(group) == 1 else shapely.union_all(triangles[group])
    polygons = _clean(polygons, atol)
    # how far the grouped triangles really are from their common plane: rounding, or a bend within tolerance
    offsets = np.abs(np.einsum("fvi,fi->fv", tri[used] - org[lab][:, None], nrm[lab])).max(axis=1)
    flatness = np.zeros(n_facets)
    np.maximum.at(flatness, lab, offsets)
    magnitude = float(np.abs(mesh.vertices).max(initial=0.0)) or 1.0
    planar = flatness <= PLANAR_ULPS * np.finfo(float).eps * magnitude
    for array in (nrm, org, bases, polygons, flatness, planar):
        array.setflags(write=False)
    return Facets(nrm, org, bases, polygons, tuple(used[g] for g in groups), flatness, planar)


def _unshared_vertex(faces_small, faces_big):
    """For each pair of adjacent faces, the vertex of the first not in the second."""
    not_shared = ~(faces_small[:, :, None] == faces_big[:, None, :]).any(axis=2)
    return faces_small[np.arange(len(faces_small)), not_shared.argmax(axis=1)]


def _planes(label, cross, tri, good):
    """Area-weighted unit normal and centroid per label."""
    count = label.max() + 1
    w = np.where(good, np.linalg.norm(cross, axis=1), 0.0)
    nrm = np.stack([np.bincount(label, cross[:, k] * good, count) for k in range(3)], axis=1)
    centres = tri.mean(axis=1)
    total = np.bincount(label, w, count)
    org = np.stack([np.bincount(label, centres[:, k] * w, count) for k in range(3)], axis=1)
    org /= np.where(total > 0, total, 1.0)[:, None]
    length = np.linalg.norm(nrm, axis=1)
    nrm /= np.where(length > 0, length, 1.0)[:, None]
    return nrm, org


def _bases(normals):
    """Orthonormal (u, v) per unit normal n with u x v = n."""
    axis = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    u = np.cross(normals, axis)
    u /= np.linalg.norm(u, axis=1)[:, None]
    return np.stack([u, np.cross(normals, u)], axis=1)


def _clean(polygons, atol):
    """Drop near-duplicate and near-collinear vertices anywhere in each ring; exteriors counter-clockwise.

    A vertex closer than ``atol`` to the segment joining its two neighbours is
    removed, repeatedly, for all rings at once (each pass removes, in every
    run of such vertices, those nearest to their neighbours' segment, then
    re-checks).  Douglas-Peucker
    simplification would keep each ring's start point, so a duplicate there
    would survive and add a redundant row to the interlocking matrix.
    """
    polygons = np.atleast_1d(polygons)
    rings, polygon_of = shapely.get_rings(polygons, return_index=True)
    coords, ring_of = shapely.get_coordinates(rings, return_index=True)
    if not len(coords):
        return np.array([shapely.Polygon()] * len(polygons), dtype=object)
    closing = np.r_[ring_of[1:] != ring_of[:-1], True]
    coords, ring_of = coords[~closing], ring_of[~closing]
    while len(coords):
        first = np.r_[0, np.flatnonzero(np.diff(ring_of)) + 1]
        length = np.diff(np.r_[first, len(coords)])
        first, length = np.repeat(first, length), np.repeat(length, length)
        position = np.arange(len(coords)) - first
        prev, nxt = first + (position - 1) % length, first + (position + 1) % length
        a, ac = coords[prev], coords[nxt] - coords[prev]
        squared = np.einsum("ij,ij->i", ac, ac)
        t = np.clip(np.einsum("ij,ij->i", coords - a, ac) / np.where(squared > 0, squared, 1.0), 0.0, 1.0)
        distance = np.hypot(*(coords - a - t[:, None] * ac).T)
        near = (distance <= atol) & (length > 3)
        # in a run of removable vertices remove the most collinear first (a corner beside a spurious
        # vertex from nearly parallel edges is farther from its neighbours' segment than the spurious one)
        remove = near & ~(near[prev] & (distance[prev] < distance)) & ~(near[nxt] & (distance[nxt] <= distance))
        if not remove.any():
            break
        coords, ring_of = coords[~remove], ring_of[~remove]
    counts = np.bincount(ring_of, minlength=len(rings))
    bounds = np.r_[0, np.cumsum(counts)]
    first_ring = np.r_[0, np.cumsum(np.bincount(polygon_of, minlength=len(polygons)))]  # rings come per polygon
    out = np.empty(len(polygons), dtype=object)
    for p in range(len(polygons)):
        members = range(first_ring[p], first_ring[p + 1])
        valid = [coords[bounds[k]:bounds[k + 1]] for k in members if counts[k] >= 3]
        exterior_ok = len(members) > 0 and counts[members[0]] >= 3
        out[p] = shapely.Polygon(valid[0], valid[1:]) if exterior_ok else shapely.Polygon()
    return shapely.orient_polygons(shapely.normalize(out))


class _FacetTable:
    """The facets of every block in world coordinates, concatenated block after block."""

    def __init__(self, assembly: Assembly, atol: float, angle_tol: float):
        types = assembly.types
        per_type = {}
        for t in np.unique(types):
            mesh = assembly.meshes[t].copy()
            mesh.merge_vertices(merge_tex=True, merge_norm=True)
            per_type[t] = _facets(mesh, atol, angle_tol)
        counts = np.array([len(per_type[t]) for t in types])
        self.start = np.concatenate([[0], np.cumsum(counts)])
        total = self.start[-1]
        self.block = np.repeat(np.arange(len(types)), counts)
        self.local = np.arange(total) - self.start[self.block]
        self.normals, self.origins = np.empty((total, 3)), np.empty((total, 3))
        self.bases, self.polygons = np.empty((total, 2, 3)), np.empty(total, dtype=object)
        self.flatness, self.planar = np.empty(total), np.empty(total, dtype=bool)
        rot, shift = assembly.transforms[:, :3, :3], assembly.transforms[:, :3, 3]
        mirrored = assembly.mirrored
        for t, f in per_type.items():
            for mirror in (False, True):
                blocks = np.flatnonzero((types == t) & (mirrored == mirror))
                if not len(blocks):
                    continue
                rows = (self.start[blocks][:, None] + np.arange(len(f))).ravel()
                r = rot[blocks]
                self.normals[rows] = np.einsum("bij,fj->bfi", r, f.normals).reshape(-1, 3)
                self.origins[rows] = (np.einsum("bij,fj->bfi", r, f.origins) + shift[blocks, None]).reshape(-1, 3)
                bases = np.einsum("bij,fkj->bfki", r, f.bases).reshape(-1, 2, 3)
                polygons = f.polygons
                if mirror:  # keep u x v = n: flip v, and y in the plane
                    bases[:, 1] *= -1
                    polygons = _clean(shapely.transform(polygons, lambda xy: xy * [1.0, -1.0]), 0.0)
                self.bases[rows] = bases
                self.polygons[rows] = np.tile(polygons, len(blocks))
                self.flatness[rows] = np.tile(f.flatness, len(blocks))
                self.planar[rows] = np.tile(f.planar, len(blocks))


def _matches(table: _FacetTable, pairs, atol, angle_tol, scale, tilted=False):
    """Global facet indices (gi, gj) of coplanar facets with opposite normals, blocks i < j.

    ``tilted``: the centroid of each facet may be farther from the other's plane than ``atol`` by what a tilt
    within ``angle_tol`` over the facets' radii adds (the overlap is tested later, for gap contacts).
    """
    lo, hi = table.origins.min(axis=0), table.origins.max(axis=0)
    centre = (lo + hi) / 2
    reach = max(scale, float(np.linalg.norm(hi - lo)))
    # |n_i + n_j| <= angle_tol and |d_i + d_j| <= atol + angle_tol * reach / 2 for offsets d = n.(o - centre)
    a = max(angle_tol, _TINY)
    t = max(atol + angle_tol * reach, _TINY * scale)
    offset = np.einsum("fi,fi->f", table.normals, table.origins - centre)
    points = np.hstack([table.normals / a, offset[:, None] / t])
    radius = math.sqrt(2) * (1 + 1e-9)
    trees, gi, gj = {}, [], []
    for i, j in pairs:
        si, sj = slice(table.start[i], table.start[i + 1]), slice(table.start[j], table.start[j + 1])
        if i not in trees:
            trees[i] = cKDTree(points[si])
        hits = trees[i].query_ball_point(-points[sj], radius)
        sizes = np.fromiter(map(len, hits), dtype=int, count=len(hits))
        if sizes.sum():
            gi.append(table.start[i] + np.concatenate([h for h in hits if h]).astype(int))
            gj.append(table.start[j] + np.repeat(np.arange(len(hits)), sizes))
    if not gi:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    gi, gj = np.concatenate(gi), np.concatenate(gj)
    ni, nj = table.normals[gi], table.normals[gj]
    angle = 2 * np.arcsin(np.clip(np.linalg.norm(ni + nj, axis=1) / 2, 0, 1))
    apart = table.origins[gj] - table.origins[gi]
    slack = atol
    if tilted:
        corners = np.abs(shapely.bounds(table.polygons)).reshape(-1, 2, 2).max(axis=1)
        radius = np.hypot(*corners.T)
        slack = atol + math.sin(angle_tol) * (radius[gi] + radius[gj])
    ok = ((angle <= angle_tol) & (np.abs(np.einsum("ki,ki->k", ni, apart)) <= slack)
          & (np.abs(np.einsum("ki,ki->k", nj, apart)) <= slack))
    return gi[ok], gj[ok]


def _overlaps(table: _FacetTable, gi, gj, atol, area_tol, grid, gap=0.0) -> tuple[Contact, ...]:
    """Intersect matched facets in block i's facet frame; one Contact per overlap part.

    With ``gap > 0`` (absolute), parts farther than ``atol + gap`` from block j's facet plane are dropped and
    the others are moved along block i's normal halfway to block j's facet plane (at the part's centroid).
    """
    if not len(gi):
        return ()
    bi, bj = table.bases[gi], table.bases[gj]
    linear = np.einsum("kar,kbr->kab", bi, bj)  # j's plane coordinates -> i's
    shift = np.einsum("kar,kr->ka", bi, table.origins[gj] - table.origins[gi])
    # shapely.set_coordinates works in place and facets are shared between blocks of a type: copy first
    moved = shapely.transform(table.polygons[gj], lambda coords: coords)
    xy, which = shapely.get_coordinates(moved, return_index=True)
    moved = shapely.set_coordinates(moved, np.einsum("kab,kb->ka", linear[which], xy) + shift[which])
    # coplanar facets far apart in their plane cannot overlap: skip them before the (costly) overlay
    box_i, box_j = shapely.bounds(table.polygons[gi]), shapely.bounds(moved)
    apart = np.any((box_i[:, 2:] <= box_j[:, :2] + atol) | (box_j[:, 2:] <= box_i[:, :2] + atol), axis=1)
    gi, gj, moved = gi[~apart], gj[~apart], moved[~apart]
    overlap = shapely.intersection(table.polygons[gi], moved, grid_size=grid)
    parts, k = shapely.get_parts(overlap, return_index=True)
    polygonal = shapely.get_type_id(parts) == 3
    parts, k = _clean(parts[polygonal], atol), k[polygonal]
    polygonal = shapely.get_type_id(parts) == 3  # simplification may collapse slivers
    parts, k = parts[polygonal], k[polygonal]
    area, perimeter = shapely.area(parts), shapely.length(parts)
    keep = (area > area_tol) & (2 * area > atol * perimeter)
    parts, k, area = parts[keep], k[keep], area[keep]
    if not len(parts):
        return ()
    # 3D vertices: every ring without its closing repeat
    rings, ring_part = shapely.get_rings(parts, return_index=True)
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    last = np.r_[ring[1:] != ring[:-1], True]
    xy, ring = xy[~last], ring[~last]
    part = ring_part[ring]
    g = gi[k[part]]
    points = table.origins[g] + np.einsum("va,var->vr", xy, table.bases[g])
    per_part = np.split(points, np.cumsum(np.bincount(part, minlength=len(parts)))[:-1])
    block_i, block_j = table.block[gi[k]], table.block[gj[k]]
    facet_i, facet_j = table.local[gi[k]], table.local[gj[k]]
    order = np.lexsort((np.arange(len(parts)), facet_j, facet_i, block_j, block_i))
    if gap > 0:
        centroids = shapely.get_coordinates(shapely.centroid(parts))
    found = []
    for p in order:
        g_i, g_j = gi[k[p]], gj[k[p]]
        vertices, origin = per_part[p], table.origins[g_i].copy()
        apart = float(np.abs((vertices - table.origins[g_j]) @ table.normals[g_j]).max())
        separation = 0.0
        if gap > 0:
            if apart > atol + gap:
                continue
            separation = apart if apart > atol else 0.0
            # to the mid-plane: halfway along n_i from block i's facet plane to block j's, at the centroid
            n_i, n_j = table.normals[g_i], table.normals[g_j]
            centre = origin + centroids[p] @ table.bases[g_i]
            shift = n_i * (0.5 * ((table.origins[g_j] - centre) @ n_j) / (n_i @ n_j))
            vertices, origin = vertices + shift, origin + shift
        arrays = [table.normals[g_i].copy(), vertices, origin, table.bases[g_i].copy()]
        for array in arrays:
            array.setflags(write=False)
        normal, vertices, origin, basis = arrays
        deviation = float(table.flatness[g_i] + table.flatness[g_j]) + apart
        found.append(Contact(int(block_i[p]), int(block_j[p]), normal, vertices, float(area[p]),
                             int(facet_i[p]), int(facet_j[p]), parts[p], origin, basis, deviation,
                             bool(table.planar[g_i] and table.planar[g_j]), separation))
    return tuple(found)
