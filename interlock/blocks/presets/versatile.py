"""The pair of Versatile Blocks of main paper Ex. 3.7 (Fig. 11), from the block published with [2]."""

from __future__ import annotations

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.blocks.presets.common import outward, turn

__all__ = ["versatile_blocks", "VERSATILE_BLOCK_DATA", "VERSATILE_TO_PAPER"]

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
    mesh = outward(np.array(VERSATILE_BLOCK_DATA["vertices"], dtype=float) @ np.array(VERSATILE_TO_PAPER).T,
                   np.array(VERSATILE_BLOCK_DATA["faces"]) - 1)
    return Assembly([mesh], [0, 0], [turn(2), np.eye(4)], labels=["left", "right"], frame=[0], boundary=[0, 1],
                    info={"preset": "versatile_blocks", "figure": "Main paper Ex. 3.7, Fig. 11"})
