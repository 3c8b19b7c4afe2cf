"""Cube assemblies of the main paper: cube grid (Ex. 3.5), interlocking cubes (Ex. 3.6), modified cubes (Fig. 6, 7)."""

from __future__ import annotations

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.presets.common import (PresetError, count, fan, finite, grid, outward, positive, split,
                                             translation, turn)

__all__ = ["cube_grid", "cube_grid_cell", "interlocking_cubes", "interlocking_cubes_cell", "modified_cube",
           "modified_cube_assembly", "CUBE_VERTICES", "CUBE_FACES", "INTERLOCKING_CUBES_TRANSLATIONS",
           "INTERLOCKING_CUBE_SIDE", "PYRAMID_HEIGHT"]

#: The unit cube of main paper Ex. 3.5 as its ordered vertex list (vertex k is "k + 1" in the paper).
CUBE_VERTICES = ((0, 0, 1), (0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0), (1, 0, 0), (1, 0, 1))
#: Its six square faces, 0-based: the four side faces of Ex. 3.5 ([1,2,3,4], [1,2,7,8], [3,4,5,6],
#: [5,6,7,8] in the paper), then the bottom and the top.
CUBE_FACES = ((0, 1, 2, 3), (0, 1, 6, 7), (2, 3, 4, 5), (4, 5, 6, 7), (1, 2, 5, 6), (0, 3, 4, 7))
#: ``v1, v2`` of main paper Ex. 3.6: cube ``(i, j)`` is the side-2 cube moved by ``i v1 + j v2``.
INTERLOCKING_CUBES_TRANSLATIONS = ((1, 1, 2), (-1, 2, 1))
#: Side length of the cubes of Ex. 3.6 (the unit cube scaled so that all coordinates are integers).
INTERLOCKING_CUBE_SIDE = 2
#: Default height of the pyramids of :func:`modified_cube`, as a fraction of the cube's side.
PYRAMID_HEIGHT = 0.5


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
    rows, cols, size = count(rows, "rows"), count(cols, "cols"), positive(size, "size")
    labels, ring = grid(rows, cols)
    shifts = [((j - (cols - 1) // 2) * size, (i - (rows - 1) // 2) * size, 0.0) for i, j in labels]
    return Assembly([_cube(size)], np.zeros(len(labels), dtype=int), [translation(s) for s in shifts],
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
    size = positive(size, "size")
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
    rows, cols = count(rows, "rows"), count(cols, "cols")
    v1, v2 = np.array(INTERLOCKING_CUBES_TRANSLATIONS, dtype=float)
    labels, ring = grid(rows, cols)
    return Assembly([_cube(INTERLOCKING_CUBE_SIDE)], np.zeros(len(labels), dtype=int),
                    [translation(i * v1 + j * v2) for i, j in labels], labels=labels, frame=ring, boundary=ring,
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
    size = positive(size, "size")
    h = PYRAMID_HEIGHT * size if pyramid_height is None else finite(pyramid_height, "pyramid_height")
    if not 0 < h < size:
        raise PresetError(f"pyramid_height must lie strictly between 0 and the cube's side {size}, got {h}")
    corners = np.array(CUBE_VERTICES, dtype=float) * size
    half = size / 2
    apexes = [(size + h, half, half), (half, size - h, half)]
    vertices = np.vstack([corners, apexes])
    added, removed = 8, 9
    faces = [f for k in (0, 1, 4, 5) for f in split(CUBE_FACES[k])]  # x = 0, y = 0, bottom, top: flat
    faces += fan(CUBE_FACES[3], added) + fan(CUBE_FACES[2], removed)  # x = size: pyramid; y = size: hole
    return outward(vertices, faces)


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
    rows, cols = count(rows, "rows"), count(cols, "cols")
    mesh = modified_cube(size, pyramid_height)
    labels, ring = grid(rows, cols)
    transforms = []
    for i, j in labels:
        cx, cy = j + j % 2, i + i % 2  # the group's axis: the cell corner with even coordinates
        turns = {(True, True): 0, (False, True): 1, (False, False): 2, (True, False): 3}[(j < cx, i < cy)]
        transforms.append(translation((cx * size, cy * size, 0)) @ turn(turns) @ translation((-size, -size, 0)))
    return Assembly([mesh], np.zeros(len(labels), dtype=int), transforms, labels=labels, frame=ring, boundary=ring,
                    info={"preset": "modified_cube_assembly", "figure": "Main paper Fig. 6, 7", "size": size})


def _cube(side) -> trimesh.Trimesh:
    """The cube ``[0, side]^3`` with the vertices of ``CUBE_VERTICES`` in their order."""
    return outward(np.array(CUBE_VERTICES, dtype=float) * side, [f for q in CUBE_FACES for f in split(q)])
