"""Planar facets of a triangle mesh: coplanar triangles grouped into the polygons a contact is made of."""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np
import shapely
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from interlock.blocks.assembly import Assembly
from interlock.blocks.contact import ContactError, plane_bases
from interlock.blocks.repair import merge_vertices

__all__ = ["Facets", "FacetTable", "facets", "merged", "clean_polygons", "check_tolerance", "DEFAULT_CONTACT_RTOL",
           "DEFAULT_ANGLE_TOL", "PLANAR_ULPS", "NOISE_FACTOR", "NOISE_ANGLE", "NOISE_TAIL", "NOISE_PAIRS",
           "NOISE_BALANCE", "TINY"]

#: Distance tolerance relative to the model size: two planes closer than this
#: coincide, a gap narrower than this is a contact, an overlap thinner than this
#: is an edge touch, and facet outlines are simplified within it.  Mesh files
#: from CAD tools are often accurate to a few 1e-6 only (TopoLite's ``ania``).
DEFAULT_CONTACT_RTOL = 1e-5
#: Angle tolerance (radians): normals within it are parallel (facets) or
#: opposite (contacts).  Rotated pieces in files may be off by ~4e-5 rad (``ania``).
DEFAULT_ANGLE_TOL = 1e-4

#: A facet is planar when every vertex of its triangles lies within this many units in the last place (of
#: the mesh's largest coordinate) of its plane, i.e. within rounding; farther means the tolerances grouped
#: triangles that are not coplanar (a face bent by less than ``angle_tol``).  A bend of 1e-14 on a unit
#: block is about 25 such units; rounding leaves well under one.
PLANAR_ULPS = 8

#: A mesh whose nearly parallel neighbouring triangles stray from each other's planes by up to ``s`` (vertex
#: noise) groups its facets within this many times ``s``: a facet of several noisy triangles strays from its
#: fitted plane by up to about twice the largest pairwise stray.
NOISE_FACTOR = 4.0

#: Vertex noise larger than the angle tolerance shows as neighbouring triangles within this angle (radians) of
#: each other that stray from each other's planes: the median stray of all such pairs of a mesh, times
#: :data:`NOISE_TAIL`, is its noise.  A designed fold is one pair among many exactly coplanar ones and leaves the
#: median at 0; noise moves every vertex.  (Gaussian noise of 1e-5 of a TopoLite shell tilts its triangles,
#: 0.05 across, by up to 3e-3.)
NOISE_ANGLE = 1e-2
#: The largest of a few thousand strays is about this many times their median (a half-normal's 99.9th
#: percentile is 4.9 times its median).
NOISE_TAIL = 5.0
#: A mesh reads noise from its population of strays only with at least this many nearly coplanar pairs ...
NOISE_PAIRS = 8
#: ... and with at least this share of them creased each way (noise is as often concave as convex; a finely
#: tessellated sphere creases one way only).
NOISE_BALANCE = 0.25

#: Floor for tolerances of zero (relative; keeps the spatial index's metric finite).
TINY = 1e-15


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
    ``grouping`` is the distance within which triangles were grouped: the
    tolerance asked for, or :data:`NOISE_FACTOR` times the noise the mesh
    shows where that is larger.
    """

    normals: np.ndarray
    origins: np.ndarray
    bases: np.ndarray
    polygons: np.ndarray
    faces: tuple[np.ndarray, ...]
    flatness: np.ndarray
    planar: np.ndarray
    grouping: float = 0.0

    def __len__(self) -> int:
        return len(self.normals)

    @property
    def areas(self) -> np.ndarray:
        return shapely.area(self.polygons)


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
    mesh = merged(mesh)
    atol = DEFAULT_CONTACT_RTOL * mesh.scale if atol is None else check_tolerance("atol", atol)
    return _facets(mesh, atol, check_tolerance("angle_tol", angle_tol))


def check_tolerance(name, value) -> float:
    """``value`` as a float when it is a finite number >= 0 (a tolerance); ContactError otherwise."""
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or value < 0:
        raise ContactError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


class FacetTable:
    """The facets of every block (or of the blocks ``needed``) in world coordinates, concatenated block after block.

    Blocks that are not needed have no facets in the table.
    """

    def __init__(self, assembly: Assembly, atol, angle_tol: float, needed=None):
        types = assembly.types
        wanted = np.ones(len(types), dtype=bool)
        if needed is not None:
            wanted = np.zeros(len(types), dtype=bool)
            wanted[np.asarray(needed, dtype=int)] = True
        needed_types = np.unique(types[wanted]).tolist()
        atol = np.broadcast_to(np.asarray(atol, dtype=float), (len(assembly.meshes),))
        meshes = [merged(assembly.meshes[t]) for t in needed_types]
        found = _facets_of(meshes, atol[needed_types], angle_tol) if needed_types else []
        per_type = dict(zip(needed_types, found))
        #: per needed mesh type: its merged mesh and its Facets (in the mesh's own frame), for the features of
        #: point contacts (:mod:`interlock.verify.point_contacts`)
        self.per_type, self.merged = per_type, dict(zip(needed_types, meshes))
        self.types, self.transforms = types, assembly.transforms
        counts = np.array([len(per_type[t]) if w else 0 for t, w in zip(types, wanted)], dtype=int)
        self.start = np.concatenate([[0], np.cumsum(counts)])
        total = self.start[-1]
        self.block = np.repeat(np.arange(len(types)), counts)
        self.local = np.arange(total) - self.start[self.block]
        self.normals, self.origins = np.empty((total, 3)), np.empty((total, 3))
        self.bases, self.polygons = np.empty((total, 2, 3)), np.empty(total, dtype=object)
        self.flatness, self.planar = np.empty(total), np.empty(total, dtype=bool)
        self.grouping = np.empty(total)  # the distance within which each facet's triangles were grouped
        rot, shift = assembly.transforms[:, :3, :3], assembly.transforms[:, :3, 3]
        mirrored = assembly.mirrored
        for t, f in per_type.items():
            for mirror in (False, True):
                blocks = np.flatnonzero((types == t) & (mirrored == mirror) & wanted)
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
                    polygons = clean_polygons(shapely.transform(polygons, lambda xy: xy * [1.0, -1.0]), 0.0)
                self.bases[rows] = bases
                self.polygons[rows] = np.tile(polygons, len(blocks))
                self.flatness[rows] = np.tile(f.flatness, len(blocks))
                self.planar[rows] = np.tile(f.planar, len(blocks))
                self.grouping[rows] = f.grouping


def merged(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A copy of ``mesh`` with coincident vertices merged on a grid relative to its size (any scale).

    trimesh's own merge rounds to an absolute 1e-8, which fuses every vertex of
    a model 1e-8 across and overflows on one 1e12 across
    (:func:`~interlock.blocks.repair.merge_vertices` instead).
    """
    vertices, faces = merge_vertices(mesh.vertices, mesh.faces)
    return trimesh.Trimesh(vertices, faces, process=False)


# --- private helpers --------------------------------------------------------------------------------


def _facets(mesh: trimesh.Trimesh, atol: float, angle_tol: float) -> Facets:
    return _facets_of([mesh], atol, angle_tol)[0]


def _facets_of(meshes, atol, angle_tol: float) -> list[Facets]:
    """The facets of several meshes at once: one pass of array operations over all their triangles.

    The meshes share no vertex, so no facet spans two of them; facets are
    numbered per mesh by their lowest triangle index.  ``atol`` is one
    distance, or one per mesh; a mesh whose triangles within ``angle_tol``
    (at most :data:`DEFAULT_ANGLE_TOL`) of each other stray farther from each other's planes (vertex noise) is
    grouped within :data:`NOISE_FACTOR` times that stray instead.
    """
    atol = np.broadcast_to(np.asarray(atol, dtype=float), (len(meshes),)).copy()
    vertex_counts = np.array([len(m.vertices) for m in meshes])
    face_counts = np.array([len(m.faces) for m in meshes])
    face_start = np.r_[0, np.cumsum(face_counts)]
    owner = np.repeat(np.arange(len(meshes)), face_counts)
    vertices = np.vstack([m.vertices for m in meshes]).reshape(-1, 3)
    faces = np.vstack([m.faces for m in meshes]).reshape(-1, 3) + np.repeat(np.r_[0, np.cumsum(vertex_counts)][:-1],
                                                                            face_counts)[:, None]
    whole = trimesh.Trimesh(vertices, faces, process=False)
    scales = np.array([max(m.scale, TINY) for m in meshes])
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    twice_area = np.linalg.norm(cross, axis=1)
    good = twice_area > np.finfo(float).eps * scales[owner] ** 2
    normal = np.zeros_like(cross)
    normal[good] = cross[good] / twice_area[good, None]

    # coplanar neighbours: normals agree, or the smaller face's far vertex is on the larger's plane
    adj = whole.face_adjacency
    adj = adj[good[adj].all(axis=1)] if len(adj) else adj.reshape(0, 2)
    keep = np.zeros(len(adj), dtype=bool)
    if len(adj):
        a, b = adj[:, 0], adj[:, 1]
        angle = 2 * np.arcsin(np.clip(np.linalg.norm(normal[a] - normal[b], axis=1) / 2, 0, 1))
        big_first = twice_area[a] >= twice_area[b]
        big, small = np.where(big_first, a, b), np.where(big_first, b, a)
        unshared = _unshared_vertex(faces[small], faces[big])
        stray = np.einsum("ij,ij->i", normal[big], vertices[unshared] - tri[big, 0])  # > 0: a concave crease
        far = np.abs(stray)
        same_side = np.einsum("ij,ij->i", normal[a], normal[b]) > 0
        # noise: neighbours whose normals agree within the default angle but whose far vertex strays from the plane
        nearly = same_side & (angle <= min(angle_tol, DEFAULT_ANGLE_TOL))
        noise = np.zeros(len(meshes))
        np.maximum.at(noise, owner[a[nearly]], far[nearly])
        # stronger noise tilts small triangles beyond that angle: read it off the strays of the whole population
        candidates = same_side & (angle <= NOISE_ANGLE)
        noise = np.maximum(noise, NOISE_TAIL * _noise_per(owner[a[candidates]], stray[candidates], len(meshes)))
        atol = np.maximum(atol, NOISE_FACTOR * noise)
        keep = same_side & ((angle <= angle_tol) | (far <= atol[owner[a]]))
    n_faces = len(faces)
    graph = coo_matrix((np.ones(keep.sum()), (adj[keep, 0], adj[keep, 1])), shape=(n_faces, n_faces))
    _, label = connected_components(graph, directed=False)

    # groups that are not flat fall apart into single triangles
    _, label = np.unique(label, return_inverse=True)
    nrm, org = _planes(label, cross, tri, good)
    dist = np.abs(np.einsum("fvi,fi->fv", tri - org[label][:, None], nrm[label])).max(axis=1)
    bent = np.zeros(label.max() + 1, dtype=bool)
    np.logical_or.at(bent, label[good], dist[good] > atol[owner[good]])
    split = bent[label]
    label = np.where(split, label.max() + 1 + np.arange(n_faces), label)
    label[~good] = -1
    # number facets by their lowest triangle index (so mesh after mesh)
    used = np.flatnonzero(good)
    _, first, label_g = np.unique(label[used], return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(used[first], kind="stable"), kind="stable")
    label = np.full(n_faces, -1)
    label[used] = order[label_g]
    n_facets = len(first)
    facet_owner = owner[np.sort(used[first])]
    per_mesh = np.bincount(facet_owner, minlength=len(meshes))
    if np.any(per_mesh == 0):
        raise ContactError("the mesh has no triangle of positive area")
    nrm, org = _planes(label[used], cross[used], tri[used], np.ones(len(used), dtype=bool))
    bases = plane_bases(nrm)

    # facet outlines: union of the projected triangles
    lab = label[used]
    flat = np.einsum("fvi,fai->fva", tri[used] - org[lab][:, None], bases[lab])
    triangles = shapely.polygons(flat)
    members = np.argsort(lab, kind="stable")
    groups = np.split(members, np.cumsum(np.bincount(lab, minlength=n_facets))[:-1])
    facet_owner_sorted = owner[np.sort(used[first])]
    polygons = clean_polygons(_unions(triangles, lab, n_facets), atol[facet_owner_sorted])
    # how far the grouped triangles really are from their common plane: rounding, or a bend within tolerance
    offsets = np.abs(np.einsum("fvi,fi->fv", tri[used] - org[lab][:, None], nrm[lab])).max(axis=1)
    flatness = np.zeros(n_facets)
    np.maximum.at(flatness, lab, offsets)
    magnitude = np.array([float(np.abs(m.vertices).max(initial=0.0)) or 1.0 for m in meshes])
    planar = flatness <= PLANAR_ULPS * np.finfo(float).eps * magnitude[facet_owner]
    triangles_of = [used[g] - face_start[facet_owner[f]] for f, g in enumerate(groups)]
    out, start = [], 0
    for k, count in enumerate(per_mesh.tolist()):
        part = slice(start, start + count)
        arrays = [nrm[part].copy(), org[part].copy(), bases[part].copy(), polygons[part].copy(),
                  flatness[part].copy(), planar[part].copy()]
        for array in arrays:
            array.setflags(write=False)
        n_, o_, b_, p_, f_, pl_ = arrays
        out.append(Facets(n_, o_, b_, p_, tuple(triangles_of[part]), f_, pl_, float(atol[k])))
        start += count
    return out


def _noise_per(owner: np.ndarray, strays: np.ndarray, count: int) -> np.ndarray:
    """Per mesh ``0 .. count - 1``: the median size of its signed ``strays`` (the lower one of an even number), where
    they look like noise: at least :data:`NOISE_PAIRS` of them, and at least :data:`NOISE_BALANCE` of them on
    either side.  A tessellated convex or concave surface creases one way only and reads 0.

    >>> _noise_per(np.array([0] * 8 + [1] * 8), np.array([1, -2, 3, -4, 5, -6, 7, -8] + [-1.0] * 8), 2).tolist()
    [4.0, 0.0]
    """
    sizes = np.bincount(owner, minlength=count)
    above = np.bincount(owner, weights=strays > 0, minlength=count)
    below = np.bincount(owner, weights=strays < 0, minlength=count)
    values = np.abs(strays)
    order = np.lexsort((values, owner))
    starts = np.r_[0, np.cumsum(sizes)[:-1]]
    middle = np.minimum(starts + np.maximum(sizes - 1, 0) // 2, max(len(values) - 1, 0))
    median = values[order][middle] if len(values) else np.zeros(count)
    balanced = np.minimum(above, below) >= NOISE_BALANCE * np.maximum(sizes, 1)
    return np.where((sizes >= NOISE_PAIRS) & balanced, median, 0.0)


def _unions(pieces: np.ndarray, group: np.ndarray, count: int) -> np.ndarray:
    """The union of the ``pieces`` of each group ``0 .. count - 1``: one vectorised call per group size class.

    A facet's triangles are edge-matched and do not overlap (a coverage), so
    GEOS' coverage union, far cheaper than the general one, is tried first.
    Groups are padded with None to a common length (powers of two, so that
    a few large facets do not pad all the others) and reduced along that axis.
    """
    order = np.argsort(group, kind="stable")
    sizes = np.bincount(group, minlength=count)
    starts = np.r_[0, np.cumsum(sizes)][:-1]
    out = np.empty(count, dtype=object)
    single = sizes == 1
    out[single] = pieces[order[starts[single]]]
    width = np.maximum(1, 2 ** np.ceil(np.log2(np.maximum(sizes, 1)))).astype(int)
    for size in np.unique(width[~single]).tolist():
        rows = np.flatnonzero((width == size) & ~single)
        table = np.full((len(rows), size), None, dtype=object)
        column = np.arange(size)
        inside = column[None, :] < sizes[rows, None]
        table[inside] = pieces[order[(starts[rows, None] + column[None, :])[inside]]]
        try:
            unions = shapely.coverage_union_all(table, axis=1)
        except shapely.errors.GEOSException:  # a facet of this size class is not edge-matched (T-junctions)
            unions = shapely.union_all(table, axis=1)
        # a coverage union assumes edge-matched pieces that do not overlap; where the result shows otherwise
        # (invalid, area lost to overlaps, or more than one polygon), the general union is taken instead
        areas = np.where(inside, shapely.area(np.where(inside, table, shapely.Polygon())), 0.0).sum(axis=1)
        suspect = (~shapely.is_valid(unions) | (shapely.get_type_id(unions) != shapely.GeometryType.POLYGON)
                   | (np.abs(shapely.area(unions) - areas) > 1e-9 * np.maximum(areas, TINY)))
        if suspect.any():
            unions[suspect] = shapely.union_all(table[suspect], axis=1)
        out[rows] = unions
    return out


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


def clean_polygons(polygons, atol):
    """Drop near-duplicate and near-collinear vertices anywhere in each ring; exteriors counter-clockwise.

    ``atol`` is one distance, or one per polygon.  A vertex closer than ``atol`` to the segment joining its two neighbours is
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
    atol = np.broadcast_to(np.asarray(atol, dtype=float), (len(polygons),))  # one distance, or one per polygon
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
        near = (distance <= atol[polygon_of[ring_of]]) & (length > 3)
        # in a run of removable vertices remove the most collinear first (a corner beside a spurious
        # vertex from nearly parallel edges is farther from its neighbours' segment than the spurious one)
        remove = near & ~(near[prev] & (distance[prev] < distance)) & ~(near[nxt] & (distance[nxt] <= distance))
        if not remove.any():
            break
        coords, ring_of = coords[~remove], ring_of[~remove]
    counts = np.bincount(ring_of, minlength=len(rings))
    first_ring = np.r_[0, np.cumsum(np.bincount(polygon_of, minlength=len(polygons)))][:-1]  # rings come per polygon
    exterior_ok = np.zeros(len(polygons), dtype=bool)
    has_rings = first_ring < len(rings)
    exterior_ok[has_rings] = counts[first_ring[has_rings]] >= 3
    kept = (counts >= 3) & exterior_ok[polygon_of]  # rings of fewer than 3 vertices are dropped (holes) or void
    out = np.array([shapely.Polygon()] * len(polygons), dtype=object)
    if kept.any():
        on_kept = kept[ring_of]
        _, ring_index = np.unique(ring_of[on_kept], return_inverse=True)
        built = shapely.linearrings(coords[on_kept], indices=ring_index)
        shapely.polygons(built, indices=polygon_of[kept], out=out)
    return shapely.orient_polygons(shapely.normalize(out))

