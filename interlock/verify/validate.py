"""Input checks before a verdict: blocks must be solids and must not overlap."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError

__all__ = ["manifold_solid", "OverlapError", "Overlap", "pair_overlaps", "overlaps", "overlaps_without_contact",
           "refuse_overlaps_without_contact", "self_intersections", "validate", "OVERLAP_RTOL", "CROSSING_RTOL"]

#: Two blocks overlap when their common volume exceeds this fraction of the smaller one; it matches
#: the contacts' angular tolerance (a face tilted by 1e-4 rad overlaps its neighbour in a wedge of ~1e-4 x volume).
OVERLAP_RTOL = 1e-4
#: An edge crosses a triangle only if it passes this far (relative to the mesh size) inside both.
CROSSING_RTOL = 1e-9


class OverlapError(InterlockError):
    """Blocks that interpenetrate, or a block that is not a valid solid."""


@dataclass(frozen=True)
class Overlap:
    """The common volume of two neighbouring blocks ``i`` and ``j``.

    ``thickness = 2 volume / area`` (``area``: the surface of the common solid) is its mean depth: ``d`` for
    a thin slab of depth ``d`` between parallel faces, about a third of the depth for a block's edge pressed
    into a face.
    """

    i: int
    j: int
    volume: float
    thickness: float


def pair_overlaps(assembly: Assembly) -> list[Overlap]:
    """Every pair of neighbouring blocks with a common volume, however small.

    Intersections are exact-predicate booleans of manifold3d (float64 meshes).
    Candidate pairs come from ``assembly.neighbours``; a pair's overlap depends
    only on the two block types and their relative transform, so each kind of
    pair is computed once (a patch of one block type has only a few kinds).

    >>> import trimesh
    >>> boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 0.999)]
    >>> [(o.i, o.j, round(o.volume, 9), round(o.thickness, 6)) for o in pair_overlaps(Assembly.from_meshes(boxes))]
    [(0, 1, 0.001, 0.000998)]
    """
    import manifold3d

    solids = [manifold_solid(manifold3d, mesh, k) for k, mesh in enumerate(assembly.meshes)]
    pairs = np.array(sorted(assembly.neighbours.edges), dtype=int).reshape(-1, 2)
    first, kind_of, relative = assembly.pair_kinds(pairs)
    of_kind = []
    for r in first:
        i, j = pairs[r]
        common = solids[assembly.types[i]] ^ solids[assembly.types[j]].transform(relative[r][:3, :])
        volume, area = float(common.volume()), float(common.surface_area())
        of_kind.append((volume, 2.0 * volume / area if area > 0 else 0.0))
    return [Overlap(int(i), int(j), *of_kind[kind]) for (i, j), kind in zip(pairs.tolist(), kind_of)
            if of_kind[kind][0] > 0]


def overlaps(assembly: Assembly, rtol: float = OVERLAP_RTOL, found=None) -> list[tuple[int, int, float]]:
    """Pairs of neighbouring blocks whose intersection volume exceeds ``rtol`` of the smaller block, as
    ``(i, j, volume)`` (from ``found``, the :func:`pair_overlaps` of the assembly, when given).

    >>> import trimesh
    >>> boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 0.5)]
    >>> overlaps(Assembly.from_meshes(boxes))
    [(0, 1, 0.5)]
    """
    found = pair_overlaps(assembly) if found is None else found
    return [(o.i, o.j, o.volume) for o in found
            if o.volume > rtol * min(assembly.volumes[o.i], assembly.volumes[o.j])]


def overlaps_without_contact(found, contacts, distance: float) -> list[Overlap]:
    """The overlaps among ``found`` deeper than ``distance`` (mean depth) between blocks with no contact.

    Two blocks may overlap by as much as the contact search's distance
    tolerance and still count as touching, and a common volume below
    :data:`OVERLAP_RTOL` passes :func:`validate`; but blocks that overlap
    deeper than the tolerance *without* a contact between them are neither
    apart nor touching, and any verdict on them would be a verdict on
    geometry the file does not describe (a centre block scaled by 1.0002
    pushes 2e-4 into its neighbours: no contact, a volume of 1e-4 of the
    block, and a wrong "not interlocked" before this check).
    """
    touching = {(min(c.i, c.j), max(c.i, c.j)) for c in contacts}
    return [o for o in found if o.thickness > distance and (min(o.i, o.j), max(o.i, o.j)) not in touching]


def self_intersections(mesh, rtol: float = CROSSING_RTOL) -> np.ndarray:
    """Pairs of triangles of one mesh that cross each other (sharing no vertex), shape (k, 2).

    Broad phase: a k-d tree on triangle centres, then bounding boxes; narrow
    phase: every edge of one triangle against the other (Moller-Trumbore),
    counted only when it passes strictly inside both, so triangles that merely
    touch along an edge or at a corner do not count.  Coplanar overlaps are
    not detected.

    >>> import trimesh
    >>> len(self_intersections(trimesh.creation.box()))
    0
    """
    import scipy.spatial

    triangles = np.asarray(mesh.triangles, dtype=float)
    faces = np.asarray(mesh.faces)
    if len(triangles) < 2:
        return np.empty((0, 2), dtype=int)
    size = float(np.linalg.norm(mesh.extents)) or 1.0
    lo, hi = triangles.min(axis=1), triangles.max(axis=1)
    reach = float(np.linalg.norm(hi - lo, axis=1).max())
    pairs = scipy.spatial.cKDTree(triangles.mean(axis=1)).query_pairs(reach, output_type="ndarray")
    if not len(pairs):
        return np.empty((0, 2), dtype=int)
    a, b = pairs.T
    boxes = np.all((lo[a] <= hi[b]) & (lo[b] <= hi[a]), axis=1)
    shared = (faces[a][:, :, None] == faces[b][:, None, :]).any(axis=(1, 2))
    a, b = a[boxes & ~shared], b[boxes & ~shared]
    crossing = _edges_cross(triangles[a], triangles[b], rtol * size) | _edges_cross(triangles[b], triangles[a], rtol * size)
    return np.column_stack([a[crossing], b[crossing]])


def validate(assembly: Assembly, rtol: float = OVERLAP_RTOL) -> list[Overlap]:
    """Raise :class:`OverlapError` naming the block if a mesh crosses itself or two blocks overlap; return the
    smaller overlaps that pass (for :func:`overlaps_without_contact` once the contacts are known)."""
    for k, mesh in enumerate(assembly.meshes):
        crossing = self_intersections(mesh)
        if len(crossing):
            block = int(np.flatnonzero(assembly.types == k)[0]) if (assembly.types == k).any() else k
            raise OverlapError(f"block {block} ({assembly.labels[block]}) intersects itself: {len(crossing)} pairs of "
                               f"its triangles cross (e.g. faces {crossing[0].tolist()}); blocks must be simple solids")
    every = pair_overlaps(assembly)
    found = overlaps(assembly, rtol, every)
    if found:
        i, j, volume = max(found, key=lambda item: item[2])
        more = f" ({len(found) - 1} more overlapping pairs)" if len(found) > 1 else ""
        raise OverlapError(
            f"blocks {i} ({assembly.labels[i]}) and {j} ({assembly.labels[j]}) overlap in a volume of {volume:.3g} "
            f"(more than {rtol:g} of the smaller block){more}; blocks of an assembly may only touch"
        )
    return every


def refuse_overlaps_without_contact(assembly: Assembly, found, contacts, distance: float) -> None:
    """Raise :class:`OverlapError` for the deepest of :func:`overlaps_without_contact`, if any."""
    loose = overlaps_without_contact(found, contacts, distance)
    if loose:
        o = max(loose, key=lambda item: item.thickness)
        more = f" ({len(loose) - 1} more such pairs)" if len(loose) > 1 else ""
        raise OverlapError(
            f"blocks {o.i} ({assembly.labels[o.i]}) and {o.j} ({assembly.labels[o.j]}) overlap {o.thickness:.3g} deep "
            f"(a volume of {o.volume:.3g}) without a face of one lying on a face of the other: deeper than the "
            f"contact tolerance {distance:.3g}, so they are neither apart nor touching{more}; move them apart or "
            "onto each other's faces"
        )


def _edges_cross(edges_of, triangles, atol) -> np.ndarray:
    """Whether some edge of each triangle in ``edges_of`` passes strictly through the matching triangle."""
    out = np.zeros(len(triangles), dtype=bool)
    if not len(triangles):
        return out
    p0, e1, e2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    scale = np.linalg.norm(np.cross(e1, e2), axis=1)  # twice the area: the natural unit of the determinants
    for k in range(3):
        start, direction = edges_of[:, k], edges_of[:, (k + 1) % 3] - edges_of[:, k]
        h = np.cross(direction, e2)
        det = np.einsum("ij,ij->i", e1, h)
        ok = np.abs(det) > 1e-12 * scale * np.linalg.norm(direction, axis=1)
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = start - p0
        u = np.einsum("ij,ij->i", s, h) * inv
        q = np.cross(s, e1)
        v = np.einsum("ij,ij->i", direction, q) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        length = np.linalg.norm(direction, axis=1)
        margin_t = atol / np.maximum(length, 1e-300)
        margin_uv = atol / np.maximum(np.sqrt(scale), 1e-300)
        out |= ok & (u > margin_uv) & (v > margin_uv) & (u + v < 1 - margin_uv) & (t > margin_t) & (t < 1 - margin_t)
    return out


def manifold_solid(manifold3d, mesh, k):
    """``mesh`` (block ``k``) as a ``manifold3d.Manifold``; OverlapError when it is not a valid solid."""
    solid = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.asarray(mesh.vertices, dtype=np.float64),
                                                  tri_verts=np.asarray(mesh.faces, dtype=np.uint64)))
    status = solid.status()
    if status != manifold3d.Error.NoError:
        raise OverlapError(f"mesh {k} is not a valid solid for manifold3d ({status.name}); "
                           "blocks must be closed, consistently oriented and free of self-intersections")
    return solid
