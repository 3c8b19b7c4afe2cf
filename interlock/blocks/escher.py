"""Blocks from deformed fundamental domains: the Escher trick (main paper Sec. 1, Fig. 1, 12-13).

The edges of a fundamental domain F are deformed into piecewise-linear paths,
equivariantly (an edge and its partner carry images of the same points), giving
a second fundamental domain F'.  The block is the solid between F at z = 0 and
F' at z = height, its sides triangulated as in Fig. 13.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import shapely
import trimesh

from interlock.errors import InterlockError
from interlock.wallpaper import WallpaperGroup

__all__ = ["Block", "DeformationError", "escher_block", "DEFORMATION_RTOL"]

#: Points closer than this (relative to sqrt(cell area)) are the same point.
DEFORMATION_RTOL = 1e-9
#: Slice segments cross only where every orientation area exceeds this times the cell area.
CROSSING_RTOL = 1e-12


class DeformationError(InterlockError):
    """A deformation that does not give a valid block; the message names the edge."""


@dataclass(frozen=True, eq=False)
class Block:
    """A block between a fundamental domain F (bottom, z = 0) and its deformation F' (top).

    Attributes
    ----------
    mesh : trimesh.Trimesh
        Watertight, outward-oriented; volume ``bottom.area * height``.
    bottom, top : shapely.Polygon
        F and F' (counter-clockwise, Cartesian).
    group : WallpaperGroup
    deformation : mapping edge -> (m, 2) array
        The intermediate points of every edge, partners included (read-only).
    height : float
    """

    mesh: trimesh.Trimesh
    bottom: shapely.Polygon
    top: shapely.Polygon
    group: WallpaperGroup
    deformation: Mapping[int, np.ndarray]
    height: float

    @property
    def deformed_edges(self) -> frozenset[int]:
        """Edges of F carrying at least one intermediate point."""
        return frozenset(e for e, points in self.deformation.items() if len(points))

    @property
    def volume(self) -> float:
        return float(self.mesh.volume)

    def __str__(self) -> str:
        return (f"{self.group.name} block: {len(self.deformed_edges)} of {len(self.group.side_pairings())} "
                f"edges deformed, height {self.height:g}, volume {self.volume:.6g}")


def escher_block(group: WallpaperGroup, deformation: Mapping, height: float = 1.0, *,
                 rtol: float = DEFORMATION_RTOL) -> Block:
    """The block interpolating F and its equivariant deformation F' (main paper Sec. 1, Fig. 13).

    Parameters
    ----------
    group : WallpaperGroup
        The group; F is ``group.fundamental_domain()``, edge ``i`` from vertex
        ``i`` to vertex ``i + 1``.
    deformation : mapping int -> sequence of (x, y)
        Intermediate points per edge, Cartesian, in order from vertex ``i`` to
        vertex ``i + 1``.  The partner edge ``f`` of a deformed edge ``e``
        receives ``g_e^-1`` of the points (``g_e`` from
        :meth:`~interlock.wallpaper.WallpaperGroup.side_pairings`), so give
        one edge of each pair, or both consistently.
    height : float
        The block's height ``h > 0``.
    rtol : float
        Tolerance for coinciding points, relative to ``sqrt(cell area)``.

    Returns
    -------
    Block

    Raises
    ------
    DeformationError
        Naming the edge: an edge index that does not exist, non-finite points,
        points that conflict with the images given for the partner edge, a
        mirror (self-paired) edge deformed asymmetrically, points that coincide
        with each other or a vertex, or a deformation that makes F' (or a
        slice between F and F') self-intersecting.

    Notes
    -----
    Side triangulation (Fig. 13, generalised): for the edge ``v1 v2`` with top
    path ``v1', p1', ..., pm', v2'`` and apex ``pj'`` with ``j = ceil(m / 2)``,
    the triangles are ``(v1, p(k-1)', pk')`` for ``k <= j`` (with
    ``p0' = v1'``), ``(v1, v2, pj')`` and ``(v2, pk', p(k+1)')`` for
    ``k >= j`` (with ``p(m+1)' = v2'``).  For ``m = 1`` these are exactly the
    triangles ``v1 v2 p'``, ``v1 v1' p'``, ``v2 v2' p'`` of Fig. 13.  The
    partner edge's triangles are the images of these, so neighbouring blocks
    meet face to face.  The horizontal slices of the block are checked to be
    simple at every height, exactly (not by sampling): F and F' may both be
    simple while an intermediate slice is not.

    Examples
    --------
    >>> from interlock import wallpaper
    >>> g = wallpaper.group("p4")
    >>> block = escher_block(g, {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]})
    >>> sorted(block.deformed_edges), block.mesh.is_watertight, round(block.volume, 12)
    ([0, 1, 2, 3], True, 0.25)
    """
    if not isinstance(group, WallpaperGroup):
        raise DeformationError(f"group must be a WallpaperGroup (see interlock.wallpaper.group), "
                               f"got {type(group).__name__}")
    height = _positive(height, "height")
    if not (isinstance(rtol, (int, float)) and math.isfinite(rtol) and rtol >= 0):
        raise DeformationError(f"rtol must be a finite number >= 0, got {rtol!r}")
    tol = rtol * math.sqrt(group.cell_area)
    full = _equivariant_deformation(group, deformation, tol)
    corners = np.asarray(group.fundamental_domain().exterior.coords)[:-1]
    top_ring = _top_ring(corners, full, tol, group.name)
    _check_slices(corners, full, group.name, CROSSING_RTOL * group.cell_area)
    mesh = _mesh(group, corners, full, top_ring, height)
    return Block(
        mesh=mesh,
        bottom=group.fundamental_domain(),
        top=shapely.Polygon(top_ring),
        group=group,
        deformation=MappingProxyType(full),
        height=height,
    )


# --- deformation ------------------------------------------------------------------


def _equivariant_deformation(group, deformation, tol) -> dict[int, np.ndarray]:
    """Every edge's points, partners filled in through the side pairings."""
    if not isinstance(deformation, Mapping):
        raise DeformationError(
            f"deformation must map edge indices to point lists, e.g. {{0: [(0.3, 0.1)]}}; "
            f"got {type(deformation).__name__}"
        )
    pairings = group.side_pairings()
    count = len(pairings)
    given = {}
    for key, points in deformation.items():
        if isinstance(key, (bool, np.bool_)) or not isinstance(key, (int, np.integer)) or not 0 <= key < count:
            raise DeformationError(f"edge {key!r} does not exist: the fundamental domain of {group.name} "
                                   f"has edges 0..{count - 1}")
        try:
            pts = np.array(points, dtype=float) if len(points) else np.empty((0, 2))
        except (TypeError, ValueError):  # strings, ragged lists, objects without a length
            raise DeformationError(f"edge {key}: intermediate points must be a sequence of (x, y) number pairs, "
                                   f"e.g. [(0.3, 0.1)]; got {points!r}") from None
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise DeformationError(f"edge {key}: intermediate points must be a sequence of (x, y) pairs, "
                                   f"got shape {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise DeformationError(f"edge {key}: intermediate points must be finite, got {pts.tolist()}")
        given[int(key)] = pts
    full = {e: np.empty((0, 2)) for e in range(count)}
    for e, pts in given.items():
        pairing = pairings[e]
        images = _partner_points(group, pairing, pts)
        f = pairing.partner
        if f == e and not _same_points(images, pts, tol):
            raise DeformationError(
                f"edge {e} lies on a mirror of {group.name} and is paired with itself by the reflection "
                f"{pairing.element}; its intermediate points must be mirror-symmetric (on the edge's line), "
                f"got {pts.tolist()}"
            )
        if f != e and f in given and not _same_points(images, given[f], tol):
            raise DeformationError(
                f"edges {e} and {f} are paired by the {pairing.kind} {pairing.element}: the points of edge {f} "
                f"must be the images of those of edge {e}, i.e. {np.round(images, 12).tolist()}, "
                f"but {given[f].tolist()} were given; give points for one edge of the pair only"
            )
        full[e], full[f] = pts, images
    for array in full.values():
        array.setflags(write=False)
    return full


def _partner_points(group, pairing, points) -> np.ndarray:
    """``g_e^-1`` of the points of edge e, ordered along the partner edge."""
    m = group.matrix(pairing.element.inverse())
    images = points @ m[:2, :2].T + m[:2, 2]
    return images if _keeps_direction(group, pairing) else images[::-1]


def _keeps_direction(group, pairing) -> bool:
    """Whether ``g_e`` maps the partner's first vertex to edge e's first vertex."""
    V = group.domain_vertices
    return pairing.element.apply_exact(V[pairing.partner]) == V[pairing.edge]


def _same_points(a, b, tol) -> bool:
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= tol))


def _top_ring(corners, full, tol, name) -> np.ndarray:
    """F' as a ring of points; rejects repeated points and self-intersections."""
    pieces, owner = [], []
    for e, corner in enumerate(corners):
        pieces.append(corner[None])
        pieces.append(full[e])
        owner += [e] * (1 + len(full[e]))
    ring = np.vstack(pieces)
    steps = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1)
    if steps.min() <= tol:
        e = owner[int(np.argmin(steps))]
        raise DeformationError(f"edge {e}: an intermediate point coincides with a vertex or with the previous point; "
                               "points must be distinct and differ from the edge's end points")
    crossing = _first_crossing(ring, owner)
    if crossing is not None:
        raise DeformationError(f"the deformation makes F' self-intersecting: the paths of edges {crossing[0]} and "
                               f"{crossing[1]} cross (in {name}, after adding partner images); move their points")
    if not shapely.LinearRing(ring).is_simple:
        raise DeformationError("the deformation makes F' fold back on itself (a path doubles back along a line); "
                               "move the intermediate points off the edges' extensions")
    if shapely.Polygon(ring).area <= 0 or not shapely.LinearRing(ring).is_ccw:
        raise DeformationError("the deformed domain F' turned inside out; intermediate points must keep it "
                               "counter-clockwise")
    return ring


def _check_slices(corners, full, name, area_tol):
    """The block's horizontal slices must be simple polygons at every height.

    Slice vertices move linearly with the height ``t`` in (0, 1), so every
    orientation test between two slice segments is a quadratic in ``t``.  Two
    segments can only start or stop crossing at a root of one of these
    quadratics; testing for proper crossings at the midpoints between
    consecutive roots therefore decides the question for all heights.  A
    crossing counts when all four orientation areas exceed ``area_tol``
    (touching within rounding is not a crossing).
    """
    start, end, owner = _slice_vertices(corners, full)
    n = len(start)
    i, j = np.triu_indices(n, k=2)
    keep = (j - i) % n != n - 1  # the first and the last segment share a vertex
    i, j = i[keep], j[keep]
    if not i.size:
        return
    a0, a1 = start, end - start  # vertex k at height t is a0[k] + t * a1[k]
    p, q, r, s_ = i, (i + 1) % n, j, (j + 1) % n
    quadratics = np.concatenate([_orientation(a0, a1, p, q, r), _orientation(a0, a1, p, q, s_),
                                 _orientation(a0, a1, r, s_, p), _orientation(a0, a1, r, s_, q)])
    critical = np.unique(np.concatenate([[0.0, 1.0], _roots_in_unit_interval(quadratics)]))
    times = (critical[:-1] + critical[1:]) / 2
    for t in times:
        o = [np.polyval(c.T[::-1], t) for c in np.split(quadratics, 4)]
        clear = np.min(np.abs(o), axis=0) > area_tol
        crossing = (o[0] * o[1] < 0) & (o[2] * o[3] < 0) & clear
        if crossing.any():
            k = int(np.argmax(crossing))
            raise DeformationError(
                f"the block would intersect itself at height {t:.3f} x h: the sides over edges {owner[i[k]]} and "
                f"{owner[j[k]]} cross there ({name}); move their intermediate points"
            )


def _slice_vertices(corners, full):
    """Slice vertices at heights 0 and 1 (they move linearly between), and the edge owning each."""
    start, end, owner = [], [], []
    count = len(corners)
    for e, corner in enumerate(corners):
        nxt = corners[(e + 1) % count]
        pts = full[e]
        j = math.ceil(len(pts) / 2)
        rows = [(corner, corner)] + [(corner, p) for p in pts[:j]]
        rows += [(nxt, p) for p in pts[j - 1:]] if len(pts) else []
        start += [a for a, _ in rows]
        end += [b for _, b in rows]
        owner += [e] * len(rows)
    return np.asarray(start), np.asarray(end), owner


def _orientation(a0, a1, p, q, r):
    """Coefficients (c0, c1, c2) of cross(Q - P, R - P) as a polynomial in t."""
    u0, u1 = a0[q] - a0[p], a1[q] - a1[p]
    w0, w1 = a0[r] - a0[p], a1[r] - a1[p]
    cross = lambda x, y: x[:, 0] * y[:, 1] - x[:, 1] * y[:, 0]  # noqa: E731
    return np.column_stack([cross(u0, w0), cross(u0, w1) + cross(u1, w0), cross(u1, w1)])


def _roots_in_unit_interval(coefficients):
    c0, c1, c2 = coefficients.T
    roots = []
    quadratic = np.abs(c2) > 1e-300
    disc = c1**2 - 4 * c2 * c0
    ok = quadratic & (disc >= 0)
    sq = np.sqrt(np.where(ok, disc, 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        roots += [((-c1 - sq) / (2 * c2))[ok], ((-c1 + sq) / (2 * c2))[ok]]
        linear = ~quadratic & (np.abs(c1) > 1e-300)
        roots.append((-c0 / c1)[linear])
    roots = np.concatenate(roots)
    return roots[(roots > 0) & (roots < 1)]


def _first_crossing(ring, owner):
    """Edges owning the first pair of non-adjacent ring segments that intersect, or None."""
    n = len(ring)
    segments = shapely.linestrings(np.stack([ring, np.roll(ring, -1, axis=0)], axis=1))
    left, right = shapely.STRtree(segments).query(segments, predicate="intersects")
    for a, b in zip(left.tolist(), right.tolist()):
        if a < b and (b - a) % n not in (1, n - 1):
            return owner[a], owner[b]
    return None


def _positive(value, name) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise DeformationError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise DeformationError(f"{name} must be a positive finite number, got {value}")
    return value


# --- mesh --------------------------------------------------------------------------


def _mesh(group, corners, full, top_ring, height) -> trimesh.Trimesh:
    n = len(corners)
    top_start = [n]
    for e in range(n - 1):
        top_start.append(top_start[-1] + 1 + len(full[e]))
    total_top = len(top_ring)

    def top_path(e):  # indices of v_e', points of e, v_{e+1}'
        first = top_start[e]
        return [first + k for k in range(1 + len(full[e]))] + [top_start[(e + 1) % n]]

    faces = []
    for pairing in group.side_pairings():
        e, f = pairing.edge, pairing.partner
        if f < e:
            continue  # drawn as the image of its partner's triangles
        side = _side_triangles(len(full[e]))
        faces += _localise(side, (e, (e + 1) % n), top_path(e))
        if f != e:
            keep = _keeps_direction(group, pairing)
            m = len(full[e])
            bottom = ((f, (f + 1) % n) if keep else ((f + 1) % n, f))
            path = top_path(f) if keep else top_path(f)[::-1]
            assert len(path) == m + 2
            faces += _localise(side, bottom, path)
    faces += _cap(corners, np.arange(n))
    faces += _cap(top_ring, np.arange(n, n + total_top))
    vertices = np.vstack([np.column_stack([corners, np.zeros(n)]),
                          np.column_stack([top_ring, np.full(total_top, height)])])
    mesh = trimesh.Trimesh(vertices, np.asarray(faces), process=False)
    trimesh.repair.fix_winding(mesh)
    trimesh.repair.fix_inversion(mesh)
    if not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0):
        raise AssertionError("escher block mesh is not a closed oriented surface")
    return mesh


def _side_triangles(m: int) -> list[tuple]:
    """Fig. 13 generalised, in local indices: ('b', 0|1) bottom ends, ('t', k) top path positions."""
    j = math.ceil(m / 2)
    tris = [(("b", 0), ("t", k), ("t", k + 1)) for k in range(j)]
    tris.append((("b", 0), ("b", 1), ("t", j)))
    tris += [(("b", 1), ("t", k), ("t", k + 1)) for k in range(j, m + 1)]
    return tris


def _localise(side, bottom, path):
    return [tuple(bottom[k] if kind == "b" else path[k] for kind, k in tri) for tri in side]


def _cap(ring, indices):
    """Triangles of a planar face (constrained Delaunay, no new vertices) as vertex indices."""
    triangles = shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(ring)))
    corners = shapely.get_coordinates(shapely.get_exterior_ring(triangles)).reshape(len(triangles), 4, 2)[:, :3]
    nearest = np.linalg.norm(corners[:, :, None, :] - ring[None, None], axis=-1).argmin(axis=-1)
    return [tuple(row) for row in np.asarray(indices)[nearest]]
