"""Layers of tetrahedra with wallpaper symmetry p4, p3 or p6, built from half-spaces (main paper Fig. 5)."""

from __future__ import annotations

import math

import numpy as np
import shapely
import trimesh

from interlock import wallpaper
from interlock.blocks.assembly import Assembly
from interlock.blocks.presets.common import PresetError, finite, outward

__all__ = ["tetrahedra", "TETRAHEDRA_SYMMETRIES"]

#: The symmetries of Fig. 5 that :func:`tetrahedra` builds.
TETRAHEDRA_SYMMETRIES = ("p4", "p3", "p6")

_SQRT3 = math.sqrt(3.0)
# Tetrahedra of Fig. 5 (lattice a = 1, layer 0 <= z <= 1): the block's mid-height section (a
# counter-clockwise quadrilateral of the plane tiling) and, per edge of it, the slope of the face through
# it (horizontal shift outwards per unit of height; negative: the face leans inwards going up).
_TETRAHEDRA = {
    "p4": (((0.0, 0.0), (0.5, -0.5), (1.0, 0.0), (0.5, 0.5)), (-math.sqrt(0.5), math.sqrt(0.5)) * 2),
    "p3": (((0.0, 0.0), (0.5, _SQRT3 / 6), (0.0, _SQRT3 / 3), (-0.5, _SQRT3 / 6)), (-1 / 3, 2 / 3, -2 / 3, 1 / 3)),
    "p6": (((0.0, 0.0), (0.5, -_SQRT3 / 6), (1.0, 0.0), (0.5, _SQRT3 / 6)), (-0.5, 0.5, -0.5, 0.5)),
}
_TETRAHEDRA_FIGURES = {"p4": "Main paper Fig. 5a", "p3": "Main paper Fig. 5b", "p6": "Main paper Fig. 5c"}
_LAYER_HEIGHT = 1.0
# Two tiles whose centres agree to this many decimals (relative to the lattice) are the same block.
_DECIMALS = 6
# Distance (relative to the lattice) within which an edge midpoint lies on another tile.
_TOUCH_RTOL = 1e-7


def tetrahedra(symmetry: str = "p4", radius: float = 1.5, center=(0.0, 0.0), frame="figure") -> Assembly:
    """A layer of tetrahedra with wallpaper symmetry, framed as in Fig. 5a-c.

    Built by intersecting half-spaces as in [3]: a plane tiling by
    quadrilaterals lies at mid-height ``z = 1/2`` of the layer ``0 <= z <= 1``;
    through each edge of the tiling goes a plane, tilted so that around each
    tile the faces lean alternately inwards and outwards going up; a block is
    the intersection of its tile's four half-spaces, a tetrahedron with one
    horizontal edge at ``z = 0``, one at ``z = 1`` and its tile as mid-height
    section.  Neighbours share the plane through their common edge: they
    touch face to face (in half of each face) and never overlap.

    - ``"p4"`` (Fig. 5a): square tiling with vertices at the 4-fold centres of
      p4 (lattice 1), slopes ``1 / sqrt 2``: regular tetrahedra of edge
      ``sqrt 2``, two per cell, centred on the 2-fold centres.
    - ``"p6"`` (Fig. 5c): rhombille tiling (rhombi of side ``1 / sqrt 3``
      between neighbouring 6-fold centres), slopes ``1 / 2``: tetrahedra with
      four edges ``2 / sqrt 3`` and two opposite edges ``sqrt 2``, three per cell.
    - ``"p3"`` (Fig. 5b): the p3 fundamental domain (a rhombus of the same
      tiling) with slopes ``1/3`` on edges 0, 3 and ``2/3`` on edges 1, 2,
      which the side pairings of p3 allow but those of p6 forbid: skew
      tetrahedra (no 2-fold axis), three per cell.

    The paper gives no coordinates for Fig. 5: the tilings, the slopes for p3
    and p6 and the height 1 are our choices.  Such a layer cannot fill its
    slab: a block's volume is 2/3 of its tile's area times the height, and
    voids remain towards ``z = 0`` and ``z = 1`` (top and bottom are edges).

    Parameters
    ----------
    symmetry : {"p4", "p3", "p6"}
    radius : float
        Blocks whose mid-height section meets the closed disc of this radius
        about ``center`` (in lattice units; >= 0) are kept.
    center : (float, float)
        Centre of the disc (default: the origin, a 4-, 3- or 6-fold centre).
    frame : "figure", "boundary", None or iterable of int
        The fixed blocks.  ``"figure"`` (default): the paper's frame.  For
        p4 that is Fig. 5a's red frame, a p4-symmetric one: the tetrahedra
        of one orientation class (whose lower edge runs along x) and the
        outer ring; the layer then interlocks.  For p3 and p6, whose figures
        show no frame, the outer tetrahedra, as the paper suggests (to first
        order the inner ones then slide: ``check`` says "not infinitesimally
        interlocked").  ``"boundary"``: the outer ring only; None: no frame.

    Returns
    -------
    Assembly
        One shared tetrahedron mesh, transforms ``group.to_3d(g)``, labels the
        group elements ``g`` (one per block, ordered by distance of the tile
        from ``center``); boundary: the blocks with a neighbour across an
        edge of their tile missing from the patch; the frame chosen by ``frame``.

    Raises
    ------
    PresetError
        Unknown ``symmetry`` or ``frame``, ``radius`` negative or not finite.

    Examples
    --------
    >>> layer = tetrahedra("p4", radius=1.0)
    >>> len(layer), len(layer.boundary()), len(layer.frame), round(float(layer.volumes[0]), 12)
    (16, 12, 14, 0.333333333333)
    >>> len(tetrahedra("p4", radius=1.0, frame="boundary").frame)
    12
    """
    if not isinstance(symmetry, str) or symmetry not in _TETRAHEDRA:
        raise PresetError(f"unknown symmetry {symmetry!r} for the tetrahedra of Fig. 5; choose one of "
                          f"{', '.join(TETRAHEDRA_SYMMETRIES)}")
    radius = finite(radius, "radius")
    if radius < 0:
        raise PresetError(f"radius must be >= 0, got {radius}")
    center = np.asarray(center, dtype=float)
    if center.shape != (2,) or not np.all(np.isfinite(center)):
        raise PresetError(f"center must be a finite point (x, y), got {center.tolist()}")
    group = wallpaper.group(symmetry)
    quad, slopes = (np.array(x) for x in _TETRAHEDRA[symmetry])
    tile = shapely.Polygon(quad)
    lo_x, lo_y, hi_x, hi_y = shapely.MultiPolygon([tile, group.fundamental_domain()]).bounds
    reach = math.hypot(hi_x - lo_x, hi_y - lo_y)  # g(F) lies within this of g(tile)
    scale = math.sqrt(group.cell_area)
    kept: dict[tuple, tuple] = {}
    for g in group.elements_within(radius + reach, center):
        m = group.matrix(g)
        placed = shapely.Polygon(quad @ m[:2, :2].T + m[:2, 2])
        distance = placed.distance(shapely.Point(center))
        key = tuple(np.round(np.asarray(placed.centroid.coords[0]) / scale, _DECIMALS) + 0.0)
        if distance <= radius + _TOUCH_RTOL * scale and key not in kept:
            kept[key] = (distance, key, g, placed)
    order = sorted(kept.values(), key=lambda item: (round(item[0] / scale, _DECIMALS), item[1]))
    tiles = [item[3] for item in order]
    ring = _open_tiles(tiles, _TOUCH_RTOL * scale)
    mesh = _tetrahedron(quad, slopes, _LAYER_HEIGHT)
    layer = Assembly([mesh], np.zeros(len(order), dtype=int), [group.to_3d(item[2]) for item in order],
                     labels=[item[2] for item in order], boundary=ring,
                     info={"preset": "tetrahedra", "figure": _TETRAHEDRA_FIGURES[symmetry], "group": symmetry,
                           "radius": radius, "height": _LAYER_HEIGHT, "slopes": slopes.tolist(),
                           "frame": frame if isinstance(frame, str) or frame is None else "given"})
    return layer.with_frame(_chosen_frame(layer, group, frame))


def _chosen_frame(layer: Assembly, group, frame) -> list[int]:
    """The blocks ``frame`` names (see :func:`tetrahedra`)."""
    if frame is None:
        return []
    if isinstance(frame, str):
        if frame == "boundary" or (frame == "figure" and group.name != "p4"):
            return list(layer.boundary())
        if frame == "figure":  # Fig. 5a, red: one orientation class (lower edge along x), and the ring
            along_x = [i for i, g in enumerate(layer.labels) if abs(group.matrix(g)[0, 0]) > 0.5]
            return sorted(set(along_x) | set(layer.boundary()))
        raise PresetError(f"frame must be 'figure', 'boundary', None or block indices, got {frame!r}")
    return list(frame)


def _tetrahedron(quad, slopes, height) -> trimesh.Trimesh:
    """The intersection of the four half-spaces through the edges of ``quad`` placed at ``z = height / 2``.

    Face ``k`` is the plane ``n_k . (x - q_k) = slopes[k] (z - height / 2)`` with
    ``n_k`` the outward unit normal of edge ``k``; vertex ``k`` is where the
    three planes other than ``k`` meet.
    """
    normals, offsets = [], []
    for k in range(4):
        a, b = quad[k], quad[(k + 1) % 4]
        n = np.array([b[1] - a[1], a[0] - b[0]]) / np.linalg.norm(b - a)
        normals.append([n[0], n[1], -slopes[k]])
        offsets.append(n @ a - slopes[k] * height / 2)
    normals, offsets = np.array(normals), np.array(offsets)
    vertices = np.array([np.linalg.solve(np.delete(normals, k, 0), np.delete(offsets, k)) for k in range(4)])
    return outward(vertices, [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])


def _open_tiles(tiles, tol) -> list[int]:
    """Indices of tiles with an edge not shared by another tile of the list."""
    tree = shapely.STRtree(tiles)
    out = []
    for k, tile in enumerate(tiles):
        ring = np.asarray(tile.exterior.coords)
        midpoints = shapely.points((ring[:-1] + ring[1:]) / 2)
        point_index, tile_index = tree.query(midpoints, predicate="dwithin", distance=tol)
        shared = {int(p) for p, t in zip(point_index, tile_index) if t != k}
        if len(shared) < len(midpoints):
            out.append(k)
    return out
