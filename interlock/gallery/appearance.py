"""How blocks look: which belong together, their colours, and exploded positions."""

from __future__ import annotations

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.blocks.classes import block_classes
from interlock.errors import GalleryError
from interlock.formats.common import PALETTE, as_assembly  # the files' palette and block/mesh/assembly rule

__all__ = ["as_assembly", "block_classes", "block_colours", "exploded", "exploded_factor", "PALETTE"]


def block_colours(assembly: Assembly) -> np.ndarray:
    """RGBA (uint8) per block from :data:`PALETTE` by :func:`block_classes`, shape (n, 4).

    >>> from interlock.blocks import presets
    >>> block_colours(presets.cube_grid()).shape
    (9, 4)
    """
    classes, _ = block_classes(assembly)
    return PALETTE[classes % len(PALETTE)]


def exploded(assembly: Assembly, factor: float) -> Assembly:
    """Every block moved away from the assembly's centre: ``c_i -> c_i + factor (c_i - c)``.

    ``c_i`` is block ``i``'s centroid and ``c`` the mean of the centroids;
    ``factor = 0`` gives the assembly back.  Frame, labels and lattice are kept.

    >>> from interlock.blocks import presets
    >>> a = presets.cube_grid()
    >>> float(exploded(a, 0.5).bounds.max() - a.bounds.max())
    0.5
    """
    factor = exploded_factor(factor)
    if factor == 0 or len(assembly) == 0:
        return assembly
    centroids = assembly.centroids
    transforms = assembly.transforms.copy()
    transforms[:, :3, 3] += factor * (centroids - centroids.mean(axis=0))
    return Assembly(assembly.meshes, assembly.types, transforms, assembly.labels, assembly.frame,
                    assembly.lattice, None, {**assembly.info, "exploded": factor})


def exploded_factor(value) -> float:
    """``value`` as an exploded-view factor: a finite number >= 0, else a :class:`GalleryError`.

    >>> exploded_factor(0.5)
    0.5
    """
    try:
        factor = float(value)
    except (TypeError, ValueError):
        raise GalleryError(f"exploded must be a number >= 0, got {value!r}") from None
    if not (np.isfinite(factor) and factor >= 0):
        raise GalleryError(f"exploded must be a finite factor >= 0, got {factor}")
    return factor
