"""The RhomBlock and its two assemblies on every lozenge tiling (main paper Sec. 4.4, Thm. 4.9, Fig. 2-3)."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.lozenge import LATTICE_BASIS, UP_OFFSETS, LozengeTiling, TilingError

__all__ = ["rhomblock", "rhomblock_assembly", "rhomblock_transforms", "RHOMBLOCK_VERTICES", "RHOMBLOCK_FACES",
           "RHOMBLOCK_HEIGHT", "RHOMBLOCK_VOLUME", "VARIANTS"]

_SQRT3 = math.sqrt(3.0)
#: Height of the RhomBlock for unit edge length: sqrt(2/3).
RHOMBLOCK_HEIGHT = math.sqrt(2.0 / 3.0)
#: The ten vertices v1..v10 of main paper Sec. 4.4 (vertex k is "k + 1" in the paper).  The bottom
#: v1..v4 is the lozenge D(0, -1) + U(0, 0); the top v5..v10 is the hexagon about the down-triangle's
#: centre (1/2, -sqrt(3)/6) with corners at its vertices and at the centres of its three up-neighbours.
RHOMBLOCK_VERTICES = np.array([
    (0.0, 0.0, 0.0), (0.5, _SQRT3 / 2, 0.0), (1.0, 0.0, 0.0), (0.5, -_SQRT3 / 2, 0.0),
    (0.0, 0.0, RHOMBLOCK_HEIGHT), (0.5, _SQRT3 / 6, RHOMBLOCK_HEIGHT), (1.0, 0.0, RHOMBLOCK_HEIGHT),
    (1.0, -_SQRT3 / 3, RHOMBLOCK_HEIGHT), (0.5, -_SQRT3 / 2, RHOMBLOCK_HEIGHT), (0.0, -_SQRT3 / 3, RHOMBLOCK_HEIGHT),
])
RHOMBLOCK_VERTICES.setflags(write=False)
#: The 16 triangles as printed in Sec. 4.4 (1-based; the winding is not consistent, see :func:`rhomblock`).
RHOMBLOCK_FACES = ((1, 2, 3), (1, 3, 4), (1, 5, 6), (1, 2, 6), (2, 3, 6), (3, 6, 7), (3, 7, 8), (3, 4, 8), (4, 8, 9),
                   (4, 9, 10), (1, 4, 10), (1, 5, 10), (5, 6, 7), (5, 9, 10), (7, 8, 9), (5, 7, 9))
#: Volume for unit edge length: 1 / sqrt(2).
RHOMBLOCK_VOLUME = 1.0 / math.sqrt(2.0)
#: The two assemblies of Thm. 4.9: 0 places each block about its lozenge's down-triangle, 1 about its up-triangle.
VARIANTS = (0, 1)

# The centre of the reference block's down-triangle D(0, -1), about which variant 0 turns it.
_REFERENCE_CENTRE = np.array([0.5, -_SQRT3 / 6])
# Third of a full turn: a lozenge of orientation k is the reference one turned by k thirds.
_THIRD_TURN = 2 * math.pi / 3


def rhomblock() -> trimesh.Trimesh:
    """The RhomBlock of main paper Sec. 4.4 (Fig. 2), for unit edge length, oriented outward.

    The paper's coordinates and faces (:data:`RHOMBLOCK_VERTICES`, :data:`RHOMBLOCK_FACES`); the
    printed faces have inconsistent winding, so they are re-oriented consistently and outward.
    The bottom is the lozenge ``D(0, -1) + U(0, 0)`` of :mod:`~interlock.blocks.lozenge` (area
    ``sqrt(3) / 2``); the top, at height ``sqrt(2/3)``, is the hexagon of the same area about the
    down-triangle's centre, which is invariant under turns by a third about that centre.  The block
    is symmetric under the mirror ``x -> 1 - x`` (it swaps v1 and v3, v5 and v7, v8 and v10).

    Returns
    -------
    trimesh.Trimesh
        A new closed mesh of 10 vertices and 16 triangles (12 planar facets), volume ``1 / sqrt(2)``.

    Examples
    --------
    >>> block = rhomblock()
    >>> block.is_watertight, len(block.faces), round(float(block.volume) * math.sqrt(2), 12)
    (True, 16, 1.0)
    """
    mesh = trimesh.Trimesh(np.array(RHOMBLOCK_VERTICES), np.array(RHOMBLOCK_FACES) - 1, process=False)
    trimesh.repair.fix_winding(mesh)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def rhomblock_transforms(tiling: LozengeTiling, variant: int = 0) -> np.ndarray:
    """The placement of the RhomBlock on each lozenge of a tiling, shape (n, 4, 4).

    Variant 0 turns the reference block (on ``D(0, -1) + U(0, 0)``) by ``k`` thirds about the centre
    of its down-triangle (orientation ``k``) and moves that centre to the lozenge's down-triangle.
    Variant 1 exchanges the roles of up and down triangles: a half turn about the centre of the
    reference lozenge first swaps its two triangles, then the block is turned by ``k`` thirds about
    the up-triangle's centre and moved to the lozenge's up-triangle.  The block is symmetric under
    ``x -> 1 - x``, so that half turn is also the mirror image across the lozenge's short diagonal:
    the mirrored and the turned placements are the same solid, and no mirror-image blocks are needed.
    The top is a regular hexagon: after the half turn it is the hexagon about the up-triangle's
    centre, with corners at the up-triangle's vertices and at the centres of its down-neighbours.

    >>> from interlock.blocks.lozenge import Lozenge
    >>> t = LozengeTiling([Lozenge(0, -1, 0)])
    >>> np.allclose(rhomblock_transforms(t, 0)[0], np.eye(4))
    True
    """
    if variant not in VARIANTS:
        raise TilingError(f"variant must be 0 (blocks about down-triangles) or 1 (about up-triangles), got {variant!r}")
    loz = tiling.lozenges
    cells = loz[:, :2] + (UP_OFFSETS[loz[:, 2]] if variant else 0)
    centre = (cells + (1 / 3 if variant else 2 / 3)) @ LATTICE_BASIS  # centroid of U(i, j) or D(i, j)
    angle = loz[:, 2] * _THIRD_TURN + variant * math.pi
    cos, sin = np.cos(angle), np.sin(angle)
    out = np.tile(np.eye(4), (len(loz), 1, 1))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = cos, -sin, sin, cos
    out[:, :2, 3] = centre - np.einsum("nij,j->ni", out[:, :2, :2], _REFERENCE_CENTRE)
    return _snap(out)


def rhomblock_assembly(tiling: LozengeTiling, variant: int = 0, frame=None) -> Assembly:
    """The RhomBlock assembly of a lozenge tiling (main paper Thm. 4.9, Fig. 3).

    Every lozenge tiling contains each down-triangle (and each up-triangle) in exactly one lozenge,
    so the tops of variant 0 are the fixed hexagonal tiling by hexagons about the down-triangles'
    centres, and the tops of variant 1 the one about the up-triangles' centres; the bottoms are the
    lozenges.  Thm. 4.9: for every tiling of the plane both assemblies are interlocking.

    Parameters
    ----------
    tiling : LozengeTiling
        A finite tiling (a patch) or a periodic one (a periodic cell).
    variant : {0, 1}
        0: blocks about the down-triangles; 1: about the up-triangles (see :func:`rhomblock_transforms`).
    frame : None, "boundary" or iterable of int
        The fixed blocks: none, the outer ring (the blocks whose lozenge meets the outline along an
        edge or at a corner, :meth:`~interlock.blocks.lozenge.LozengeTiling.boundary`), or indices.

    Returns
    -------
    Assembly
        One shared mesh, one transform per lozenge, labels the :class:`~interlock.blocks.lozenge.Lozenge`
        objects (position and orientation).  A finite tiling gives ``boundary()`` = the outer ring;
        a periodic tiling gives a periodic cell with ``lattice`` its two periods (``z = 0``).

    Raises
    ------
    TilingError
        If ``tiling`` is not a :class:`~interlock.blocks.lozenge.LozengeTiling` or ``variant`` is not 0 or 1.

    Examples
    --------
    >>> from interlock.blocks.lozenge import random_hexagon, staircase
    >>> a = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0), variant=1, frame="boundary")
    >>> len(a), len(a.frame), round(float(a.volumes.sum()) * math.sqrt(2), 9)
    (27, 16, 27.0)
    >>> rhomblock_assembly(staircase((1, 1, 1))).lattice.round(6).tolist()
    [[1.5, 0.866025, 0.0], [0.0, -1.732051, 0.0]]
    """
    if not isinstance(tiling, LozengeTiling):
        raise TilingError(f"rhomblock_assembly needs a LozengeTiling, got {type(tiling).__name__}")
    if not len(tiling):
        raise TilingError("the tiling has no lozenges, so there is nothing to place RhomBlocks on "
                          "(a hexagon needs two sides > 0: it has a b + b c + c a lozenges)")
    transforms = rhomblock_transforms(tiling, variant)
    info = {"block": "RhomBlock", "variant": int(variant), "lozenges": len(tiling),
            "orientation_counts": list(tiling.orientation_counts)}
    labels = list(tiling)
    if tiling.is_periodic:
        lattice = np.zeros((2, 3))
        lattice[:, :2] = tiling.periods @ LATTICE_BASIS
        assembly = Assembly([rhomblock()], np.zeros(len(tiling), dtype=int), transforms, labels,
                            lattice=_snap(lattice), info={**info, "periods": tiling.periods.tolist()})
    else:
        assembly = Assembly([rhomblock()], np.zeros(len(tiling), dtype=int), transforms, labels,
                            boundary=tiling.boundary(), info=info)
    if frame is None:
        return assembly
    if isinstance(frame, str):
        if frame != "boundary":
            raise TilingError(f"frame must be None, 'boundary' or a list of block indices, got {frame!r}")
        frame = assembly.boundary()
    return assembly.with_frame(frame)


# --- private helpers ------------------------------------------------------------------------------------

def _snap(values: np.ndarray) -> np.ndarray:
    """Entries below machine epsilon set to exact zeros (turns by thirds leave entries like 1e-16)."""
    values = np.array(values, dtype=float)
    values[np.abs(values) < np.finfo(float).eps] = 0.0
    return values
