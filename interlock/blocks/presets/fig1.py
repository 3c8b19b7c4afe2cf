"""The p6 block of main paper Fig. 1: the Escher trick on the p6 fundamental domain."""

from __future__ import annotations

from interlock import wallpaper
from interlock.blocks.escher import Block, escher_block
from interlock.blocks.presets.common import positive

__all__ = ["fig1_p6_block", "FIG1_DEFORMATION"]

#: One intermediate point for edges 0 and 1 of the p6 fundamental domain (lattice a = 1); the
#: side pairings carry them to edges 3 and 2, so every edge is deformed (our choice, see fig1_p6_block).
FIG1_DEFORMATION = {0: ((0.25, -0.09),), 1: ((0.58, 0.16),)}


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
    height = positive(height, "height")
    return escher_block(wallpaper.group("p6"), FIG1_DEFORMATION, height)
