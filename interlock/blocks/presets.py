"""The example assemblies of the main paper (cube grids, tetrahedra layers, modified cubes, Versatile Blocks, Fig. 1),
and a block on pins that only second order shows interlocked."""

from __future__ import annotations

import math
from itertools import product
from numbers import Integral, Real

import numpy as np
import shapely
import trimesh

from interlock import wallpaper
from interlock.blocks.assembly import Assembly
from interlock.blocks.escher import Block, escher_block
from interlock.errors import InterlockError

__all__ = [
    "PresetError", "cube_grid", "cube_grid_cell", "interlocking_cubes", "interlocking_cubes_cell", "tetrahedra",
    "modified_cube", "modified_cube_assembly", "versatile_blocks", "fig1_p6_block", "block_on_pins",
    "CUBE_VERTICES", "CUBE_FACES", "INTERLOCKING_CUBES_TRANSLATIONS", "TETRAHEDRA_SYMMETRIES", "PYRAMID_HEIGHT",
    "VERSATILE_BLOCK_DATA", "VERSATILE_TO_PAPER", "FIG1_DEFORMATION",
]

#: The unit cube of main paper Ex. 3.5 as its ordered vertex list (vertex k is "k + 1" in the paper).
CUBE_VERTICES = ((0, 0, 1), (0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0), (1, 0, 0), (1, 0, 1))
#: Its six square faces, 0-based: the four side faces of Ex. 3.5 ([1,2,3,4], [1,2,7,8], [3,4,5,6],
#: [5,6,7,8] in the paper), then the bottom and the top.
CUBE_FACES = ((0, 1, 2, 3), (0, 1, 6, 7), (2, 3, 4, 5), (4, 5, 6, 7), (1, 2, 5, 6), (0, 3, 4, 7))
#: ``v1, v2`` of main paper Ex. 3.6: cube ``(i, j)`` is the side-2 cube moved by ``i v1 + j v2``.
INTERLOCKING_CUBES_TRANSLATIONS = ((1, 1, 2), (-1, 2, 1))
#: Side length of the cubes of Ex. 3.6 (the unit cube scaled so that all coordinates are integers).
INTERLOCKING_CUBE_SIDE = 2
#: The symmetries of Fig. 5 that :func:`tetrahedra` builds.
TETRAHEDRA_SYMMETRIES = ("p4", "p3", "p6")
#: Default height of the pyramids of :func:`modified_cube`, as a fraction of the cube's side.
PYRAMID_HEIGHT = 0.5
#: The Versatile Block as published with [2] (1-based faces, winding as published, not consistent).
VERSATILE_BLOCK_DATA = {
    "vertices": ((0, 0, 0), (2, 0, 0), (2, -2, 0), (0, -2, 0), (1, 1, 1), (2, 0, 1), (1, -1, 1), (0, -2, 1),
                 (-1, -1, 1)),
    "faces": ((1, 2, 4), (2, 3, 4), (5, 6, 7), (7, 8, 9), (5, 7, 9), (1, 9, 5), (5, 1, 2), (5, 6, 2), (6, 2, 7),
              (7, 2, 3), (7, 3, 4), (4, 8, 7), (4, 8, 9), (4, 9, 1)),
}
#: ``(x, y, z) -> ((x - y) / 2, (x + y) / 2, z)``: [2]'s assembly block (z times sqrt 2), turned by 45
#: degrees about the z-axis and scaled by 1 / sqrt 2, so that its face [1, 9, 5] is Ex. 3.7's triangle.
VERSATILE_TO_PAPER = ((0.5, -0.5, 0.0), (0.5, 0.5, 0.0), (0.0, 0.0, 1.0))
#: One intermediate point for edges 0 and 1 of the p6 fundamental domain (lattice a = 1); the
#: side pairings carry them to edges 3 and 2, so every edge is deformed (our choice, see fig1_p6_block).
FIG1_DEFORMATION = {0: ((0.25, -0.09),), 1: ((0.58, 0.16),)}

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


class PresetError(InterlockError):
    """Parameters of a preset outside the allowed range (the message says which values are allowed)."""


def cube_grid(rows: int = 3, cols: int = 3, size: float = 1.0) -> Assembly:
    """Cubes translated on a square grid; the outer ones form the frame (Ex. 3.5, Fig. 4a and 9).

    The cube in the middle is the convex hull of the ordered list of Ex. 3.5,
    ``[(0,0,1), (0,0,0), (0,1,0), (0,1,1), (1,1,1), (1,1,0), (1,0,0), (1,0,1)]``
    (times ``size``); cube ``(i, j)`` is it moved by
    ``(j - (cols - 1) // 2, i - (rows - 1) // 2, 0) * size``, i.e. "by translations
    in the directions (1,0,0) and (0,1,0)".  Neighbours touch in whole squares,
    so the middle cube can slide out along ``(0, 0, 1)``.

    Parameters
    ----------
    rows, cols : int
        Cubes along y and along x (each >= 1); 3 x 3 is the paper's.
    size : float
        Side length (> 0).

    Returns
    -------
    Assembly
        One shared cube mesh (its vertices in the order of Ex. 3.5), labels
        ``(i, j)`` row by row, frame and boundary the outer ring.

    Raises
    ------
    PresetError
        ``rows`` or ``cols`` not an integer >= 1, ``size`` not finite and > 0.

    See Also
    --------
    cube_grid_cell : the periodic cell of the infinite grid.

    Examples
    --------
    >>> grid = cube_grid()
    >>> len(grid), len(grid.frame), grid.mesh(4).vertices.astype(int).tolist()[:3]
    (9, 8, [[0, 0, 1], [0, 0, 0], [0, 1, 0]])
    """
    rows, cols, size = _count(rows, "rows"), _count(cols, "cols"), _positive(size, "size")
    labels, ring = _grid(rows, cols)
    shifts = [((j - (cols - 1) // 2) * size, (i - (rows - 1) // 2) * size, 0.0) for i, j in labels]
    return Assembly([_cube(size)], np.zeros(len(labels), dtype=int), [_translation(s) for s in shifts],
                    labels=labels, frame=ring, boundary=ring,
                    info={"preset": "cube_grid", "figure": "Main paper Ex. 3.5, Fig. 4a, 9", "size": size})


def cube_grid_cell(size: float = 1.0) -> Assembly:
    """The periodic cell of the infinite cube grid: one cube, lattice ``(size,0,0), (0,size,0)`` (Ex. 3.5, Fig. 4a).

    Examples
    --------
    >>> cell = cube_grid_cell(2.0)
    >>> len(cell), cell.lattice.tolist()
    (1, [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    """
    size = _positive(size, "size")
    return Assembly([_cube(size)], [0], [np.eye(4)], labels=[(0, 0)], lattice=[[size, 0, 0], [0, size, 0]],
                    info={"preset": "cube_grid_cell", "figure": "Main paper Ex. 3.5, Fig. 4a", "size": size})


def interlocking_cubes(rows: int = 3, cols: int = 3) -> Assembly:
    """The tilted layer of cubes of Ex. 3.6 (Fig. 4b, 10); the outer ring is the frame.

    The cube has side 2 and the integer coordinates of Ex. 3.6 (axis-parallel,
    Fig. 10c): ``[(0,0,2), (0,0,0), (0,2,0), (0,2,2), (2,2,2), (2,2,0), (2,0,0),
    (2,0,2)]``.  Cube ``(i, j)`` is it moved by ``i v1 + j v2`` with
    ``v1 = (1, 1, 2)``, ``v2 = (-1, 2, 1)``, ``0 <= i < rows``, ``0 <= j < cols``;
    the layer is perpendicular to ``v1 x v2 = 3 (-1, -1, 1)``, so its midsections
    are hexagons (Fig. 4b).  For 3 x 3 the middle cube is ``(1, 1)``, moved by
    ``(0, 3, 3)``: it touches its six neighbours in one unit square on each of
    its faces (Fig. 10b).

    Parameters
    ----------
    rows, cols : int
        Copies along ``v1`` and along ``v2`` (each >= 1).

    Returns
    -------
    Assembly
        One shared cube mesh, labels ``(i, j)``, frame and boundary the outer ring.

    Raises
    ------
    PresetError
        ``rows`` or ``cols`` not an integer >= 1.

    Examples
    --------
    >>> layer = interlocking_cubes()
    >>> layer.labels[4], layer.transforms[4, :3, 3].tolist(), layer.frame
    ((1, 1), [0.0, 3.0, 3.0], (0, 1, 2, 3, 5, 6, 7, 8))
    """
    rows, cols = _count(rows, "rows"), _count(cols, "cols")
    v1, v2 = np.array(INTERLOCKING_CUBES_TRANSLATIONS, dtype=float)
    labels, ring = _grid(rows, cols)
    return Assembly([_cube(INTERLOCKING_CUBE_SIDE)], np.zeros(len(labels), dtype=int),
                    [_translation(i * v1 + j * v2) for i, j in labels], labels=labels, frame=ring, boundary=ring,
                    info={"preset": "interlocking_cubes", "figure": "Main paper Ex. 3.6, Fig. 4b, 10"})


def interlocking_cubes_cell() -> Assembly:
    """The periodic cell of Ex. 3.6: one side-2 cube with lattice ``v1 = (1,1,2)``, ``v2 = (-1,2,1)`` (Fig. 10).

    Examples
    --------
    >>> interlocking_cubes_cell().lattice.astype(int).tolist()
    [[1, 1, 2], [-1, 2, 1]]
    """
    return Assembly([_cube(INTERLOCKING_CUBE_SIDE)], [0], [np.eye(4)], labels=[(0, 0)],
                    lattice=INTERLOCKING_CUBES_TRANSLATIONS,
                    info={"preset": "interlocking_cubes_cell", "figure": "Main paper Ex. 3.6, Fig. 10"})


def tetrahedra(symmetry: str = "p4", radius: float = 1.5, center=(0.0, 0.0)) -> Assembly:
    """A layer of tetrahedra with wallpaper symmetry, framed by its outer ring (Fig. 5a-c).

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

    Returns
    -------
    Assembly
        One shared tetrahedron mesh, transforms ``group.to_3d(g)``, labels the
        group elements ``g`` (one per block, ordered by distance of the tile
        from ``center``); frame and boundary: the blocks with a neighbour
        across an edge of their tile missing from the patch.

    Raises
    ------
    PresetError
        Unknown ``symmetry``, ``radius`` negative or not finite.

    Examples
    --------
    >>> layer = tetrahedra("p4", radius=1.0)
    >>> len(layer), len(layer.frame), round(float(layer.volumes[0]), 12)
    (16, 12, 0.333333333333)
    """
    if not isinstance(symmetry, str) or symmetry not in _TETRAHEDRA:
        raise PresetError(f"unknown symmetry {symmetry!r} for the tetrahedra of Fig. 5; choose one of "
                          f"{', '.join(TETRAHEDRA_SYMMETRIES)}")
    radius = _finite(radius, "radius")
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
    return Assembly([mesh], np.zeros(len(order), dtype=int), [group.to_3d(item[2]) for item in order],
                    labels=[item[2] for item in order], frame=ring, boundary=ring,
                    info={"preset": "tetrahedra", "figure": _TETRAHEDRA_FIGURES[symmetry], "group": symmetry,
                          "radius": radius, "height": _LAYER_HEIGHT, "slopes": slopes.tolist()})


def modified_cube(size: float = 1.0, pyramid_height: float | None = None) -> trimesh.Trimesh:
    """The cube ``[0, size]^3`` with a pyramid added on one side and removed from another (Fig. 6a).

    The square pyramid over the face ``x = size`` with apex
    ``(size + h, size / 2, size / 2)`` is added, and the same pyramid, pointing
    inwards from the face ``y = size`` (apex ``(size / 2, size - h, size / 2)``),
    is removed; the volume stays ``size**3``.  The paper gives neither the sides
    nor ``h``: the two sides are adjacent (so that four copies turned about the
    vertical edge ``x = y = size`` lock into each other, Fig. 6b and 7) and
    ``h`` defaults to ``PYRAMID_HEIGHT * size`` (apex of the hole at the centre).

    Parameters
    ----------
    size : float
        Side of the cube (> 0).
    pyramid_height : float, optional
        ``h``, with ``0 < h < size``.

    Returns
    -------
    trimesh.Trimesh
        Watertight, outward oriented, 10 vertices and 16 triangles.

    Raises
    ------
    PresetError
        ``size`` not > 0, ``h`` outside ``(0, size)``.

    Examples
    --------
    >>> block = modified_cube()
    >>> block.is_watertight, round(float(block.volume), 12), block.bounds.tolist()
    (True, 1.0, [[0.0, 0.0, 0.0], [1.5, 1.0, 1.0]])
    """
    size = _positive(size, "size")
    h = PYRAMID_HEIGHT * size if pyramid_height is None else _finite(pyramid_height, "pyramid_height")
    if not 0 < h < size:
        raise PresetError(f"pyramid_height must lie strictly between 0 and the cube's side {size}, got {h}")
    corners = np.array(CUBE_VERTICES, dtype=float) * size
    half = size / 2
    apexes = [(size + h, half, half), (half, size - h, half)]
    vertices = np.vstack([corners, apexes])
    added, removed = 8, 9
    faces = [f for k in (0, 1, 4, 5) for f in _split(CUBE_FACES[k])]  # x = 0, y = 0, bottom, top: flat
    faces += _fan(CUBE_FACES[3], added) + _fan(CUBE_FACES[2], removed)  # x = size: pyramid; y = size: hole
    return _outward(vertices, faces)


def modified_cube_assembly(rows: int = 4, cols: int = 4, size: float = 1.0,
                           pyramid_height: float | None = None) -> Assembly:
    """Modified cubes on a square grid, locked in groups of four (Fig. 7); the outer ring is the frame.

    Cell ``(i, j)`` is ``[j, j + 1] x [i, i + 1] x [0, 1]`` (times ``size``).
    The four cells around a point with even coordinates hold copies of
    :func:`modified_cube` turned by 0, 90, 180, 270 degrees about that
    vertical axis (Fig. 6b): each pyramid sits in the hole of the next block
    of the group; neighbouring groups touch in flat squares only.  In the
    default 4 x 4 the middle four form one group: together they move by
    ``x -> x + (0, 0, t)`` unhindered, although each alone is held (Fig. 7c).

    Parameters
    ----------
    rows, cols : int
        Cells along y and along x (each >= 1).
    size, pyramid_height : float
        As in :func:`modified_cube`.

    Returns
    -------
    Assembly
        One shared mesh, labels ``(i, j)`` row by row, frame and boundary the outer ring.

    Raises
    ------
    PresetError
        As in :func:`modified_cube`; ``rows`` or ``cols`` not an integer >= 1.

    Examples
    --------
    >>> a = modified_cube_assembly()
    >>> len(a), [a.labels[k] for k in range(len(a)) if k not in a.frame]
    (16, [(1, 1), (1, 2), (2, 1), (2, 2)])
    """
    rows, cols = _count(rows, "rows"), _count(cols, "cols")
    mesh = modified_cube(size, pyramid_height)
    labels, ring = _grid(rows, cols)
    transforms = []
    for i, j in labels:
        cx, cy = j + j % 2, i + i % 2  # the group's axis: the cell corner with even coordinates
        turns = {(True, True): 0, (False, True): 1, (False, False): 2, (True, False): 3}[(j < cx, i < cy)]
        transforms.append(_translation((cx * size, cy * size, 0)) @ _turn(turns) @ _translation((-size, -size, 0)))
    return Assembly([mesh], np.zeros(len(labels), dtype=int), transforms, labels=labels, frame=ring, boundary=ring,
                    info={"preset": "modified_cube_assembly", "figure": "Main paper Fig. 6, 7", "size": size})


def versatile_blocks() -> Assembly:
    """Two Versatile Blocks sharing the contact triangle of Ex. 3.7 (Fig. 11); the left (red) one is the frame.

    [2]'s block (``VERSATILE_BLOCK_DATA``) mapped by ``VERSATILE_TO_PAPER``
    has the integer vertices ``(0,0,0), (1,1,0), (2,0,0), (1,-1,0), (0,1,1),
    (1,1,1), (1,0,1), (1,-1,1), (0,-1,1)`` (a diamond at ``z = 0``, a pentagon
    at ``z = 1``); its face [1, 9, 5] is the triangle ``(0,0,0), (0,-1,1),
    (0,1,1)`` of Ex. 3.7, with the block on the side ``x >= 0``: the right
    (blue) block.  The left (red) block is its half turn about the z-axis,
    which maps the triangle onto itself; the contact is exactly that triangle
    (area 1, normal ``(1, 0, 0)`` from left to right).  The paper does not
    say how Fig. 11 places the blocks beyond the triangle; this placement
    also lets the motion ``gamma`` of Ex. 3.7 run without collision.

    Returns
    -------
    Assembly
        Block 0 the left (frame), block 1 the right; one shared mesh.

    Examples
    --------
    >>> pair = versatile_blocks()
    >>> pair.frame, pair.labels, round(float(pair.volumes[1]), 12)
    ((0,), ('left', 'right'), 2.0)
    """
    mesh = _outward(np.array(VERSATILE_BLOCK_DATA["vertices"], dtype=float) @ np.array(VERSATILE_TO_PAPER).T,
                    np.array(VERSATILE_BLOCK_DATA["faces"]) - 1)
    return Assembly([mesh], [0, 0], [_turn(2), np.eye(4)], labels=["left", "right"], frame=[0], boundary=[0, 1],
                    info={"preset": "versatile_blocks", "figure": "Main paper Ex. 3.7, Fig. 11"})


def block_on_pins(h: float = 1.0, c: float = 2.0):
    """A block held by fixed pins that touch it along lines and at points: interlocked only at second order.

    The block (0) is a prism along ``y`` (``|y| <= 1``) with a V-shaped
    valley on top whose faces have outward normals ``(+-1, 0, h)`` and pass
    through ``(-+1, 0, 0)``, so their normals there meet at ``O = (0, 0, h)``.
    Wedge pins (fixed) touch the valley faces along ``x = -+1, z = 0``, the
    bottom face ``z = -c`` along ``x = 0``, and the end faces ``y = -+1`` at
    ``(+-1/2, -+1, -c/2)``.  The only first-order motion is the turn about
    the line through ``O`` along ``y``; the stressed second-order form on it
    is ``2 lambda (1 - h c) / sqrt(1 + h^2)``, so the block is interlocked
    (second order) exactly when ``h c > 1`` (which is also when the valley
    stays above the bottom face).

    :func:`~interlock.verify.contacts.contacts` finds face-to-face contacts
    only, so the pins' contacts are returned beside the assembly, made by
    :meth:`~interlock.verify.contacts.Contact.at_points`: pass them to
    :func:`~interlock.verify.check` as ``contacts=``.

    Returns
    -------
    (Assembly, tuple of Contact)
        Block 0 free, pins 1..7 the frame; the ten point-on-face contact rows.

    Examples
    --------
    >>> cup, pins = block_on_pins(h=1.0, c=2.0)
    >>> len(cup), cup.frame, sum(len(c.vertices) for c in pins)
    (8, (1, 2, 3, 4, 5, 6, 7), 10)
    """
    from interlock.verify.contacts import Contact  # verify builds on blocks: import it only here

    h, c = _positive(h, "h"), _positive(c, "c")
    if not h * c > 1:
        raise PresetError(f"the valley must stay above the bottom face: h c > 1, got h = {h:g}, c = {c:g}")
    top = 0.5 / h
    section = shapely.Polygon([(-2, -c), (2, -c), (2, top), (1.5, top), (0, -1 / h), (-1.5, top), (-2, top)])
    prism = trimesh.creation.extrude_polygon(section, 2.0)
    prism.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
    prism.apply_translation([0, 1, 0])
    a = math.hypot(1, h)

    def wedge(tip, direction, side, axis=(0, 1, 0), half=0.5):
        tip, d, s, ax = (np.asarray(v, dtype=float) for v in (tip, direction, side, axis))
        corners = [tip, tip + 0.3 * (d + s), tip + 0.3 * (d - s)]
        return trimesh.convex.convex_hull(np.array([x + e * half * ax for x in corners for e in (-1, 1)]))

    left, right, down = np.array([1, 0, h]) / a, np.array([-1, 0, h]) / a, np.array([0.0, 0, -1])
    pins = [wedge((-1, 0, 0), left, np.array([h, 0, -1]) / (2 * a)),
            wedge((1, 0, 0), right, np.array([h, 0, 1]) / (2 * a)), wedge((0, 0, -c), down, (0.5, 0, 0))]
    found = [Contact.at_points(0, 1, left, [[-1, -0.5, 0], [-1, 0.5, 0]]),
             Contact.at_points(0, 2, right, [[1, -0.5, 0], [1, 0.5, 0]]),
             Contact.at_points(0, 3, down, [[0, -0.5, -c], [0, 0.5, -c]])]
    for x in (-0.5, 0.5):
        for y in (-1, 1):
            point, out = np.array([x, y, -c / 2]), np.array([0, y, 0.0])
            pins.append(wedge(point, out, (0.1, 0, 0), axis=(0, 0, 1), half=0.05))
            found.append(Contact.at_points(0, len(pins), out, [point]))
    assembly = Assembly.from_meshes([prism, *pins], frame=range(1, len(pins) + 1),
                                    labels=["block"] + [f"pin {k}" for k in range(1, len(pins) + 1)])
    return assembly, tuple(found)


def fig1_p6_block(height: float = 1.0) -> Block:
    """The p6 block of Fig. 1: the Escher trick on the p6 fundamental domain, every edge deformed.

    F (lattice a = 1) is the kite ``(0, 0), (1/2, 0), (1/2, sqrt(3)/6),
    (1/4, sqrt(3)/4)``; the 6-fold rotation pairs edges 0 and 3, the 3-fold
    one edges 1 and 2.  The paper gives no coordinates for Fig. 1: we choose
    one intermediate point per edge pair (``FIG1_DEFORMATION``), ``(0.25,
    -0.09)`` pushing edge 0 outwards and ``(0.58, 0.16)`` edge 1; the pairings
    move edges 3 and 2 with them (Fig. 1a), so every edge is deformed and
    Criterion 4.3 holds.  The block interpolates F at ``z = 0`` and F' at
    ``z = height`` (Fig. 1c); :func:`~interlock.blocks.patch` gives the assembly (Fig. 1d).

    Parameters
    ----------
    height : float
        Height of the block (> 0).

    Returns
    -------
    Block

    Examples
    --------
    >>> from interlock.blocks import patch
    >>> block = fig1_p6_block()
    >>> sorted(block.deformed_edges), len(patch(block, 1.0))
    ([0, 1, 2, 3], 31)
    """
    height = _positive(height, "height")
    return escher_block(wallpaper.group("p6"), FIG1_DEFORMATION, height)


# --- helpers -----------------------------------------------------------------------------


def _count(value, name) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 1:
        raise PresetError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _finite(value, name) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real) or not math.isfinite(value):
        raise PresetError(f"{name} must be a finite real number, got {value!r}")
    return float(value)


def _positive(value, name) -> float:
    value = _finite(value, name)
    if value <= 0:
        raise PresetError(f"{name} must be > 0, got {value}")
    return value


def _grid(rows, cols):
    """Labels ``(i, j)`` row by row and the indices of the outer ring."""
    labels = list(product(range(rows), range(cols)))
    return labels, [k for k, (i, j) in enumerate(labels) if i in (0, rows - 1) or j in (0, cols - 1)]


def _translation(shift) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = shift
    return out


def _turn(quarters: int) -> np.ndarray:
    """Rotation by ``quarters`` * 90 degrees about the z-axis, with exact entries."""
    c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[quarters % 4]
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    return out


def _split(quad) -> list:
    return [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]


def _fan(quad, apex) -> list:
    return [(quad[k], quad[(k + 1) % 4], apex) for k in range(4)]


def _outward(vertices, faces) -> trimesh.Trimesh:
    """A closed mesh with consistent, outward winding, vertices kept in the given order."""
    mesh = trimesh.Trimesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=int), process=False)
    trimesh.repair.fix_winding(mesh)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _cube(side) -> trimesh.Trimesh:
    return _outward(np.array(CUBE_VERTICES, dtype=float) * side, [f for q in CUBE_FACES for f in _split(q)])


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
    return _outward(vertices, [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])


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
