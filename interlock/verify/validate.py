"""Input checks before a verdict: blocks must be solids and must not overlap."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from interlock.blocks.assembly import MAX_COORDINATE, Assembly
from interlock.errors import AssemblyError, InterlockError

__all__ = ["manifold_solid", "OverlapError", "Overlap", "pair_overlaps", "overlaps", "overlaps_without_contact",
           "refuse_overlaps_without_contact", "self_intersections", "validate", "OVERLAP_RTOL", "CROSSING_RTOL",
           "SEPARATED_RTOL", "MAX_COORDINATE", "LEAF_TRIANGLES", "PAIR_CHUNK", "penetration", "PENETRATION_SAMPLES",
           "DEPTH_CHUNK"]

#: Two blocks overlap when their common volume exceeds this fraction of the smaller one; it matches
#: the contacts' angular tolerance (a face tilted by 1e-4 rad overlaps its neighbour in a wedge of ~1e-4 x volume).
OVERLAP_RTOL = 1e-4
#: An edge crosses a triangle only if it passes this far (relative to the mesh size) inside both.
CROSSING_RTOL = 1e-9
#: A triangle is on one side of another's plane when its corners are this far (relative to the mesh size)
#: beyond it: far above the rounding of the signed distances (1e-16), far below :data:`CROSSING_RTOL`.
SEPARATED_RTOL = 1e-12
#: Triangles in a leaf of the self-intersection test's bounding-volume tree.  Measured on n-gon prisms and
#: cylinders (n = 2,000 ... 20,000) and the bunny's parts: 4 visits twice the node pairs, 16 tests twice the
#: triangle pairs; 8 is the fastest of the three.
LEAF_TRIANGLES = 8
#: Candidate pairs of triangles tested at once: the self-intersection test's memory is about 1 kB per pair
#: (the narrow phase's temporaries), so about 130 MB whatever the mesh.
PAIR_CHUNK = 1 << 17
#: Where :func:`penetration` looks on each triangle of the common solid (barycentric weights): the corners,
#: the centre, and halfway from the centre to each corner.
PENETRATION_SAMPLES = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1 / 3, 1 / 3, 1 / 3],
                                [2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])
#: Points times triangles measured at once by :func:`penetration` (about 0.5 kB each: ~30 MB).
DEPTH_CHUNK = 1 << 16


class OverlapError(InterlockError):
    """Blocks that interpenetrate, or a block that is not a valid solid."""


@dataclass(frozen=True)
class Overlap:
    """The common volume of two neighbouring blocks ``i`` and ``j``.

    ``thickness = 2 volume / area`` (``area``: the surface of the common solid) is its mean depth: ``d`` for
    a thin slab of depth ``d`` between parallel faces, about a third of the depth for a block's edge pressed
    into a face.  Both come from the boolean, which can be wrong on meshes whose edges are shared by more than
    two triangles; ``depth``, when measured (:func:`validate` with ``depth``), is the robust
    :func:`penetration` of the two blocks, and None otherwise.
    """

    i: int
    j: int
    volume: float
    thickness: float
    depth: float | None = None

    @property
    def deepness(self) -> float:
        """How deep the two blocks reach into each other: ``depth`` when measured, else ``thickness``."""
        return self.thickness if self.depth is None else self.depth


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
    return [o for o in found if o.deepness > distance and (min(o.i, o.j), max(o.i, o.j)) not in touching]


def self_intersections(mesh, rtol: float = CROSSING_RTOL) -> np.ndarray:
    """Pairs of triangles of one mesh that cross each other (sharing no vertex), shape (k, 2).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Any triangle mesh with finite coordinates.
    rtol : float
        An edge counts as crossing a triangle only if it passes this far
        (relative to the mesh size) inside both (:data:`CROSSING_RTOL`).

    Returns
    -------
    numpy.ndarray of int, shape (k, 2)
        The crossing pairs ``(a, b)``, ``a < b``, in increasing order.

    Raises
    ------
    OverlapError
        When a coordinate is not finite.

    Notes
    -----
    Broad phase: a bounding-volume tree over the triangles (sorted along a
    Morton curve of their centres, :data:`LEAF_TRIANGLES` to a leaf), traversed
    against itself.  Each node keeps the vertices that all its triangles share,
    so two nodes whose triangles all meet at one vertex (a fan of long
    triangles around a cap's centre) are skipped whole: their pairs share a
    vertex and never count; and its plane, when all its triangles lie in one
    (within :data:`SEPARATED_RTOL`), so it is skipped against a node whose
    box lies on one side of that plane (a cap of slivers against the sides
    it stands on; the tree is built in the mesh's principal axes, where such
    caps lie across an axis).  Such a pair could only cross by less than
    :data:`SEPARATED_RTOL`, far below :data:`CROSSING_RTOL`.  Node pairs are expanded at most
    :data:`PAIR_CHUNK` at a time, so memory stays bounded whatever the mesh.
    Narrow phase: every edge of one triangle against the other
    (Moller-Trumbore), counted only when it passes strictly inside both, so
    triangles that merely touch along an edge or at a corner do not count.
    Coplanar overlaps are not detected.  The mesh is moved to the origin and
    scaled by a power of two first, so no product overflows however large the
    coordinates.

    The work grows with the number of pairs of triangles whose boxes overlap
    and which share no vertex (about linear for meshes of solids, also with
    long triangles); before, a k-d tree query with the longest triangle as the
    radius made it quadratic.

    Examples
    --------
    >>> import trimesh
    >>> len(self_intersections(trimesh.creation.box()))
    0
    >>> two = trimesh.util.concatenate([trimesh.creation.box(), trimesh.creation.box().apply_translation([0.5, 0.3, 0.2])])
    >>> len(self_intersections(two)) > 0
    True
    """
    vertices = np.asarray(mesh.vertices, dtype=float)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if len(faces) < 2:
        return np.empty((0, 2), dtype=int)
    if not np.isfinite(vertices).all():
        raise OverlapError("the mesh has non-finite vertex coordinates; every coordinate must be a finite number")
    vertices = _unit_box(vertices)
    triangles = vertices[faces]
    size = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))) or 1.0
    atol = rtol * size
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    offset = np.einsum("ij,ij->i", normal, triangles[:, 0])
    slack = SEPARATED_RTOL * size * np.linalg.norm(normal, axis=1)
    # the tree in the mesh's principal axes, where a prism's or a cylinder's caps lie across an axis
    centred = vertices - vertices.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2] if len(vertices) > 2 else np.eye(3)
    found = [np.empty((0, 2), dtype=np.int64)]
    for a, b in _candidate_pairs(faces, (centred @ axes.T)[faces], SEPARATED_RTOL * size):
        # a triangle wholly on one side of the other's plane crosses nothing of it, nor the other way round
        side_b = np.einsum("kij,kj->ki", triangles[b], normal[a]) - offset[a][:, None]
        side_a = np.einsum("kij,kj->ki", triangles[a], normal[b]) - offset[b][:, None]
        apart = ((side_b > slack[a][:, None]).all(axis=1) | (side_b < -slack[a][:, None]).all(axis=1)
                 | (side_a > slack[b][:, None]).all(axis=1) | (side_a < -slack[b][:, None]).all(axis=1))
        a, b = a[~apart], b[~apart]
        crossing = _edges_cross(triangles[a], triangles[b], atol) | _edges_cross(triangles[b], triangles[a], atol)
        found.append(np.column_stack([np.minimum(a, b), np.maximum(a, b)])[crossing])
    pairs = np.concatenate(found)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))].astype(int)


def validate(assembly: Assembly, rtol: float = OVERLAP_RTOL, depth=None, fixed=()) -> list[Overlap]:
    """Refuse blocks that cross themselves or overlap; return the smaller overlaps that pass.

    Parameters
    ----------
    assembly : Assembly
    rtol : float
        Two blocks overlap when the boolean finds a common volume above this
        fraction of the smaller one (:data:`OVERLAP_RTOL`).
    depth : float or sequence of float, optional
        A length tolerance for overlaps: how deep two blocks may reach into
        each other and still touch (the input's precision, a contact
        tolerance).  One length for every pair, or one per block, and then a
        pair may reach the sum of its two blocks' (each surface may lie its
        own length from where it should), and a block's triangles may cross
        each other by its own share (a rounded file folds a sliver through
        its neighbour by its rounding).  Every pair whose common volume
        exceeds ``rtol`` or whose mean depth (``Overlap.thickness``) exceeds
        its length is then measured by :func:`penetration`, and a volume
        above ``rtol`` is refused only when that depth exceeds the length: a
        block re-triangulated without moving its faces (where the boolean is
        wrong) touches its neighbours; a block moved 1e-3 into one overlaps.
        Smaller volumes pass, with their measured depth, for
        :func:`refuse_overlaps_without_contact` to judge once the contacts
        are known (a block grown by 2e-4 into its neighbours).  None (the
        default): the volume alone decides.
    fixed : sequence of int, optional
        Blocks held fixed (a verdict's frame): two of them may overlap, as
        their contact is no row of the interlocking matrix (a noisy file's
        boundary blocks); such pairs are returned as passed, never refused.

    Returns
    -------
    list of Overlap
        Every pair with a common volume that passed (for
        :func:`overlaps_without_contact` once the contacts are known); with
        ``depth``, those whose boolean volume or thickness exceeds the
        tolerance carry their measured ``depth``.

    Raises
    ------
    OverlapError
        Naming the block that crosses itself, or the two blocks that overlap;
        also for a ``depth`` that is not a finite length >= 0 (or one per block).
    AssemblyError
        For coordinates beyond :data:`MAX_COORDINATE`.

    Examples
    --------
    >>> import trimesh
    >>> boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 0.999)]
    >>> try:
    ...     validate(Assembly.from_meshes(boxes))
    ... except OverlapError as error:
    ...     print(str(error)[:56])
    blocks 0 (0) and 1 (1) overlap in a volume of 0.001 (mor
    >>> [round(o.depth, 6) for o in validate(Assembly.from_meshes(boxes), depth=0.002)]
    [0.001]
    """
    allowed = _allowances(assembly, depth)
    reach = np.abs(assembly.bounds).max(axis=(1, 2)) if len(assembly) else np.zeros(0)
    if (reach > MAX_COORDINATE).any():
        k = int(np.argmax(reach))
        raise AssemblyError(f"block {k} ({assembly.labels[k]}) has coordinates up to {reach[k]:.3g}: beyond "
                            f"{MAX_COORDINATE:g} volumes and overlaps overflow float64; give the model in other units "
                            "(scale it down) or nearer the origin")
    for k, mesh in enumerate(assembly.meshes):
        block = int(np.flatnonzero(assembly.types == k)[0]) if (assembly.types == k).any() else k
        # a rounded file may fold a sliver of a block through a neighbouring triangle by its rounding: that deep
        # (the block's own share of what a pair may reach), a crossing is the file's, not the solid's
        own = 0.5 * allowed(block, block) if allowed is not None and block < len(assembly) else 0.0
        size = float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices, dtype=float), axis=0))) if len(mesh.vertices) \
            else 0.0
        crossing = self_intersections(mesh, max(CROSSING_RTOL, own / size) if size > 0 else CROSSING_RTOL)
        if len(crossing):
            beyond = f" by more than {own:.3g}" if own > CROSSING_RTOL * size else ""
            raise OverlapError(f"block {block} ({assembly.labels[block]}) intersects itself: {len(crossing)} pairs of "
                               f"its triangles cross{beyond} (e.g. faces {crossing[0].tolist()}); blocks must be "
                               f"simple solids")
    held = np.zeros(len(assembly), dtype=bool)
    held[np.asarray(assembly.block_indices(fixed), dtype=int)] = True
    every = pair_overlaps(assembly)
    if allowed is not None:
        every = _measured(assembly, every, rtol, allowed)
    judged = [o for o in every if not (held[o.i] and held[o.j])]
    if allowed is not None:
        deep = [o for o in judged if o.depth is not None and o.depth > allowed(o.i, o.j)
                and o.volume > rtol * min(assembly.volumes[o.i], assembly.volumes[o.j])]
        if deep:
            o = max(deep, key=lambda item: item.depth / allowed(item.i, item.j))
            more = f" ({len(deep) - 1} more overlapping pairs)" if len(deep) > 1 else ""
            raise OverlapError(
                f"blocks {o.i} ({assembly.labels[o.i]}) and {o.j} ({assembly.labels[o.j]}) overlap: the surface of "
                f"one reaches {o.depth:.3g} inside the other (a common volume of {o.volume:.3g}), deeper than the "
                f"tolerance {allowed(o.i, o.j):.3g}{more}; blocks of an assembly may only touch")
        return every
    found = overlaps(assembly, rtol, judged)
    if found:
        i, j, volume = max(found, key=lambda item: item[2])
        more = f" ({len(found) - 1} more overlapping pairs)" if len(found) > 1 else ""
        raise OverlapError(
            f"blocks {i} ({assembly.labels[i]}) and {j} ({assembly.labels[j]}) overlap in a volume of {volume:.3g} "
            f"(more than {rtol:g} of the smaller block){more}; blocks of an assembly may only touch"
        )
    return every


def penetration(first, second, common=None) -> float:
    """How deep the surface of either of two solids reaches inside the other (both in one frame).

    The largest ``s1(p) + s2(p)`` over points ``p``, where ``s`` is the
    signed distance to a solid's surface (positive inside): ``d`` for a block
    moved ``d`` into its neighbour or a face pushed ``d`` in (between two
    parallel faces the sum is the same everywhere), the length of a spike
    stuck into the other block.  For solids whose interiors are disjoint the
    sum is at most 0 at *every* point (the segment from a point inside one to
    the nearest point of the other leaves the first on the way), so blocks
    that only touch, however they are triangulated, measure 0.

    Parameters
    ----------
    first, second : trimesh.Trimesh
        Closed, consistently oriented meshes.
    common : manifold3d.Manifold, optional
        Their common solid, when the caller has it already (a finite motion's
        overlap test); computed otherwise.

    Returns
    -------
    float
        The penetration, 0 when the solids are apart.

    Notes
    -----
    The common solid (a manifold3d boolean) only says where to look: points
    on each of its triangles (:data:`PENETRATION_SAMPLES`) are measured
    against the two meshes themselves, inside or out by the winding number
    and how far by the distance to the nearest triangle.  A boolean that is
    wrong (as on meshes whose edges are shared by four triangles, where
    manifold3d's volumes err by about 1 %) can only offer bad points, and no
    point makes touching blocks overlap; a real overlap is measured as deep
    as the deepest sampled point.  Cost: the sampled points times the
    triangles for the winding numbers (in chunks of :data:`DEPTH_CHUNK`),
    and for the distances only the triangles near each point (a k-d tree).

    Examples
    --------
    >>> import trimesh
    >>> cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    >>> pushed = trimesh.creation.box(bounds=[[0.999, 0.2, 0.2], [2, 0.8, 0.8]])
    >>> round(penetration(cube, pushed), 9)
    0.001
    >>> penetration(cube, trimesh.creation.box(bounds=[[1, 0, 0], [2, 1, 1]])) < 1e-12  # touching
    True
    """
    if common is None:
        import manifold3d

        common = manifold_solid(manifold3d, first, 0) ^ manifold_solid(manifold3d, second, 1)
    return _penetration(first, second, common)


def refuse_overlaps_without_contact(assembly: Assembly, found, contacts, distance: float) -> None:
    """Raise :class:`OverlapError` for the deepest of :func:`overlaps_without_contact`, if any."""
    loose = overlaps_without_contact(found, contacts, distance)
    if loose:
        o = max(loose, key=lambda item: item.deepness)
        more = f" ({len(loose) - 1} more such pairs)" if len(loose) > 1 else ""
        raise OverlapError(
            f"blocks {o.i} ({assembly.labels[o.i]}) and {o.j} ({assembly.labels[o.j]}) overlap {o.deepness:.3g} deep "
            f"(a volume of {o.volume:.3g}) without a face of one lying on a face of the other: deeper than the "
            f"contact tolerance {distance:.3g}, so they are neither apart nor touching{more}; move them apart or "
            "onto each other's faces"
        )


def _allowances(assembly: Assembly, depth):
    """``depth`` checked, as a function of a pair ``(i, j)``: the depth it may reach (None for None)."""
    if depth is None:
        return None
    values = np.asarray(depth, dtype=float) if not isinstance(depth, (str, bytes)) else np.array(np.nan)
    if values.ndim > 1 or (values.ndim == 1 and len(values) != len(assembly)) or not np.isfinite(values).all() \
            or (values < 0).any():
        raise OverlapError(f"depth must be a finite length >= 0, or one per block ({len(assembly)} of them), "
                           f"or None; got {depth!r}")
    if values.ndim == 0:
        return lambda i, j: float(values)
    return lambda i, j: float(values[i] + values[j])


def _measured(assembly: Assembly, found, rtol, allowed) -> list[Overlap]:
    """``found`` with the :func:`penetration` of every pair whose boolean volume or thickness is too large."""
    import manifold3d

    doubtful = [k for k, o in enumerate(found) if o.thickness > allowed(o.i, o.j)
                or o.volume > rtol * min(assembly.volumes[o.i], assembly.volumes[o.j])]
    if not doubtful:
        return list(found)
    pairs = np.array([(found[k].i, found[k].j) for k in doubtful], dtype=int)
    first, kind_of, relative = assembly.pair_kinds(pairs)
    depths = []
    for r in first:
        i, j = pairs[r]
        mine, other = assembly.meshes[assembly.types[i]], assembly.meshes[assembly.types[j]].copy()
        other.apply_transform(relative[r])  # trimesh keeps a mirrored mesh's winding outward
        common = manifold_solid(manifold3d, mine, i) ^ manifold_solid(manifold3d, other, j)
        depths.append(_penetration(mine, other, common))
    out = list(found)
    for k, kind in zip(doubtful, kind_of):
        out[k] = dataclasses.replace(found[k], depth=depths[kind])
    return out


def _penetration(first, second, common) -> float:
    mesh = common.to_mesh()
    vertices, faces = np.asarray(mesh.vert_properties, dtype=float)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64)
    if not len(faces):
        return 0.0
    points = np.unique(np.einsum("sk,tkj->tsj", PENETRATION_SAMPLES, vertices[faces]).reshape(-1, 3), axis=0)
    # measured in the unit box of the two (moved, and scaled by a power of two): no overflow at any size
    both = np.vstack([first.vertices, second.vertices, points])
    lo, hi = both.min(axis=0), both.max(axis=0)
    exponent = math.frexp(float(np.max(hi / 2 - lo / 2)) or 1.0)[1]
    centre = np.ldexp(lo / 2 + hi / 2, -exponent)
    inside = [np.ldexp(np.asarray(m.vertices, dtype=float), -exponent)[np.asarray(m.faces)] - centre
              for m in (first, second)]
    points = np.ldexp(points, -exponent) - centre
    deepest = max(0.0, float((_signed_depths(inside[0], points) + _signed_depths(inside[1], points)).max()))
    return math.ldexp(deepest, exponent)


def _signed_depths(triangles, points) -> np.ndarray:
    """The distance from each point to the closed surface of ``triangles``: positive inside, negative outside."""
    distance = _distances(points, triangles)
    return np.where(_inside(points, triangles), distance, -distance)


def _inside(points, triangles) -> np.ndarray:
    """Whether each point is inside the closed surface: its winding number (solid angles over 4 pi) above 1/2."""
    out = np.empty(len(points), dtype=bool)
    corners = [triangles[:, k].T for k in range(3)]  # (3 coordinates, triangles) per corner
    step = max(1, DEPTH_CHUNK // len(triangles))
    for start in range(0, len(points), step):
        p = points[start:start + step, :, None]
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = ([c[j][None] - p[:, j] for j in range(3)] for c in corners)
        l0, l1, l2 = (np.sqrt(x * x + y * y + z * z) for x, y, z in ((x0, y0, z0), (x1, y1, z1), (x2, y2, z2)))
        det = x0 * (y1 * z2 - z1 * y2) + y0 * (z1 * x2 - x1 * z2) + z0 * (x1 * y2 - y1 * x2)
        below = (l0 * l1 * l2 + (x0 * x1 + y0 * y1 + z0 * z1) * l2 + (x1 * x2 + y1 * y2 + z1 * z2) * l0
                 + (x2 * x0 + y2 * y0 + z2 * z0) * l1)
        out[start:start + step] = np.abs(np.arctan2(det, below).sum(axis=1)) > np.pi  # |winding| > 1/2
    return out


def _distances(points, triangles) -> np.ndarray:
    """The distance from each point to the nearest of ``triangles``: exact, from the triangles near it.

    A k-d tree on the triangles' centres gives an upper bound (the nearest few), then every triangle whose
    centre lies within that bound plus the farthest corner from its centre.
    """
    import scipy.spatial

    centres = triangles.mean(axis=1)
    reach = float(np.linalg.norm(triangles - centres[:, None], axis=2).max())
    tree = scipy.spatial.cKDTree(centres)
    few = min(8, len(triangles))
    near = tree.query(points, k=few)[1].reshape(len(points), few)
    rows = np.repeat(np.arange(len(points)), few)
    best = _point_triangle(points[rows], triangles[near.ravel()]).reshape(len(points), few).min(axis=1)
    within = tree.query_ball_point(points, best + reach)
    rows = np.repeat(np.arange(len(points)), [len(w) for w in within])
    columns = np.fromiter((t for w in within for t in w), dtype=np.int64, count=len(rows))
    for start in range(0, len(rows), DEPTH_CHUNK):
        r, c = rows[start:start + DEPTH_CHUNK], columns[start:start + DEPTH_CHUNK]
        np.minimum.at(best, r, _point_triangle(points[r], triangles[c]))
    return best


def _point_triangle(points, triangles) -> np.ndarray:
    """The distance from each point to the matching triangle (Ericson's regions: the face, an edge or a corner)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    square = np.einsum("ij,ij->i", normal, normal)
    within = square > 0
    for u, v in ((a, b), (b, c), (c, a)):
        within &= np.einsum("ij,ij->i", np.cross(v - u, points - u), normal) >= 0
    best = np.where(within, np.einsum("ij,ij->i", points - a, normal) ** 2 / np.where(within, square, 1.0), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        edge = v - u
        along = np.clip(np.einsum("ij,ij->i", points - u, edge) / np.maximum(np.einsum("ij,ij->i", edge, edge), 1e-300),
                        0.0, 1.0)
        gap = points - u - along[:, None] * edge
        best = np.minimum(best, np.einsum("ij,ij->i", gap, gap))
    return np.sqrt(best)


def _unit_box(vertices) -> np.ndarray:
    """``vertices`` moved and scaled by a power of two into [-1, 1]^3, without overflow at any finite size."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    half = float(np.max(hi / 2 - lo / 2))
    exponent = math.frexp(half)[1] if half > 0 else 0
    return np.ldexp(vertices, -exponent) - np.ldexp(lo / 2 + hi / 2, -exponent)


def _morton(points) -> np.ndarray:
    """Morton (Z-order) codes of ``points`` in their bounding box, 21 bits per axis."""
    lo = points.min(axis=0)
    span = points.max(axis=0) - lo
    q = ((points - lo) / np.where(span > 0, span, 1.0) * (2**21 - 1)).astype(np.uint64)
    code = np.zeros(len(points), dtype=np.uint64)
    for axis in range(3):
        x = q[:, axis]
        for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                            (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
            x = (x | (x << np.uint64(shift))) & np.uint64(mask)
        code |= x << np.uint64(axis)
    return code


def _candidate_pairs(faces, triangles, slack):
    """Chunks ``(a, b)`` of pairs of triangles whose boxes overlap and which share no vertex.

    A complete binary tree over the triangles in Morton order (node ``k``'s children are ``2k``, ``2k + 1``;
    the leaves, :data:`LEAF_TRIANGLES` slots each, are ``leaves ... 2 leaves - 1``), traversed against itself
    level by level.  Node pairs are dropped when their boxes are apart, when their triangles all share a
    vertex, or when one node's triangles lie in one plane (within ``slack``) and the other's box on one side
    of it (the caps of a prism against its sides).
    """
    n, width = len(faces), LEAF_TRIANGLES
    lo, hi = triangles.min(axis=1), triangles.max(axis=1)
    leaves = 1 << max(0, math.ceil(math.log2(-(-n // width))))
    order = np.full(leaves * width, -1, dtype=np.int64)
    order[:n] = np.argsort(_morton((lo + hi) / 2), kind="stable")
    slots = order.reshape(leaves, width)
    real = slots >= 0
    slot_lo = np.where(real[..., None], lo[slots], np.inf)
    slot_hi = np.where(real[..., None], hi[slots], -np.inf)
    box_lo = np.full((2 * leaves, 3), np.inf)
    box_hi = np.full((2 * leaves, 3), -np.inf)
    box_lo[leaves:] = slot_lo.min(axis=1)
    box_hi[leaves:] = slot_hi.max(axis=1)
    count = np.zeros(2 * leaves, dtype=np.int64)
    count[leaves:] = real.sum(axis=1)
    plane, flat = _node_planes(triangles, order, slack)
    # the vertices every triangle of a node has (-1: none): those of the leaf's first triangle, then intersected
    corners = faces[slots]
    first = corners[:, 0, :]
    everywhere = ((corners[:, :, :, None] == first[:, None, None, :]).any(axis=2) | ~real[..., None]).all(axis=1)
    common = np.full((2 * leaves, 3), -1, dtype=np.int64)
    common[leaves:] = np.where(everywhere & real[:, :1], first, -1)
    level = leaves // 2
    while level:
        ids = np.arange(level, 2 * level)
        left, right = 2 * ids, 2 * ids + 1
        box_lo[ids] = np.minimum(box_lo[left], box_lo[right])
        box_hi[ids] = np.maximum(box_hi[left], box_hi[right])
        count[ids] = count[left] + count[right]
        cl, cr = common[left], common[right]
        both = np.where((cl[:, :, None] == cr[:, None, :]).any(axis=2) & (cl >= 0), cl, -1)
        common[ids] = np.where((count[right] == 0)[:, None], cl, np.where((count[left] == 0)[:, None], cr, both))
        level //= 2
    upper = np.triu(np.ones((width, width), dtype=bool), 1)
    nodes = PAIR_CHUNK // (width * width)
    stack = [(np.ones(1, dtype=np.int64), np.ones(1, dtype=np.int64))]
    while stack:
        a, b = stack.pop()
        if len(a) > nodes:
            stack += [(a[nodes:], b[nodes:]), (a[:nodes], b[:nodes])]
            continue
        same = a == b
        apart = np.any((box_lo[a] > box_hi[b]) | (box_lo[b] > box_hi[a]), axis=1)
        fan = ((common[a][:, :, None] == common[b][:, None, :]) & (common[a] >= 0)[:, :, None]).any(axis=(1, 2))
        keep = np.where(same, count[a] > 1, ~apart & ~fan)
        other = keep & ~same
        other[other] = ~(_beside(plane, flat, box_lo, box_hi, a[other], b[other], slack)
                         | _beside(plane, flat, box_lo, box_hi, b[other], a[other], slack))
        keep &= same | other
        a, b, same = a[keep], b[keep], same[keep]
        if not len(a):
            continue
        if a[0] < leaves:  # every pair of a chunk is on one level: descend to the children
            x, z, y = a[same], a[~same], b[~same]  # (x, x) and (z, y)
            stack.append((np.concatenate([2 * x, 2 * x + 1, 2 * x, 2 * z, 2 * z, 2 * z + 1, 2 * z + 1]),
                          np.concatenate([2 * x, 2 * x + 1, 2 * x + 1, 2 * y, 2 * y + 1, 2 * y, 2 * y + 1])))
            continue
        la, ha, lb, hb = slot_lo[a - leaves], slot_hi[a - leaves], slot_lo[b - leaves], slot_hi[b - leaves]
        ok = np.all((la[:, :, None] <= hb[:, None]) & (lb[:, None] <= ha[:, :, None]), axis=3)
        ok[same] &= upper  # a leaf against itself: each pair once
        k, s, t = np.nonzero(ok)
        p, q = slots[a[k] - leaves, s], slots[b[k] - leaves, t]
        ok = ~(faces[p][:, :, None] == faces[q][:, None, :]).any(axis=(1, 2))
        if ok.any():
            yield p[ok], q[ok]


def _node_planes(triangles, order, slack):
    """Per node of the tree over ``order`` (the heap numbering of :func:`_candidate_pairs`): the unit normal and
    offset of the plane of its first triangle, and whether all its triangles lie within ``slack`` of it."""
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0, length, 1.0)[:, None]
    nodes = 2 * (len(order) // LEAF_TRIANGLES)
    plane = np.zeros((nodes, 4))
    flat = np.zeros(nodes, dtype=bool)
    count, span = nodes // 2, LEAF_TRIANGLES
    while count:
        members = order.reshape(count, span)
        head = members[:, 0]
        u = unit[head]
        d = np.einsum("ij,ij->i", u, triangles[head, 0])
        points = triangles[members]  # (nodes, span, 3 corners, 3)
        off = np.abs(np.einsum("nscj,nj->nsc", points, u) - d[:, None, None]).max(axis=2)
        ids = np.arange(count, 2 * count)
        plane[ids, :3], plane[ids, 3] = u, d
        flat[ids] = (head >= 0) & (length[head] > 0) & np.where(members >= 0, off <= slack, True).all(axis=1)
        count, span = count // 2, span * 2
    return plane, flat


def _beside(plane, flat, box_lo, box_hi, a, b, slack) -> np.ndarray:
    """Whether node ``a``'s triangles lie in one plane and node ``b``'s box on one side of it (``slack`` over)."""
    out = flat[a].copy()
    a, b = a[out], b[out]
    centre = (box_lo[b] + box_hi[b]) / 2
    reach = np.einsum("ij,ij->i", np.abs(plane[a, :3]), (box_hi[b] - box_lo[b]) / 2)
    middle = np.einsum("ij,ij->i", plane[a, :3], centre) - plane[a, 3]
    out[out] = (middle - reach >= -slack) | (middle + reach <= slack)
    return out


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
