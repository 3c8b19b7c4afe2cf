"""How blocks look: which belong together, their colours, and exploded positions."""

from __future__ import annotations

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.classes import block_classes
from interlock.blocks.escher import Block
from interlock.errors import GalleryError

__all__ = ["as_assembly", "block_classes", "block_colours", "exploded", "exploded_factor", "PALETTE"]

#: RGBA colours (uint8) for block classes 0, 1, 2, ... (cycled): colour-blind-safe (Okabe-Ito), opaque.
PALETTE = np.array([[0, 114, 178, 255], [230, 159, 0, 255], [0, 158, 115, 255], [204, 121, 167, 255],
                    [86, 180, 233, 255], [213, 94, 0, 255], [240, 228, 66, 255], [120, 120, 120, 255]],
                   dtype=np.uint8)


def as_assembly(obj) -> Assembly:
    """A block, a mesh or an assembly as an :class:`~interlock.blocks.Assembly`.

    >>> from interlock.blocks import presets
    >>> len(as_assembly(presets.cube_grid().mesh(0)))
    1
    """
    if isinstance(obj, Assembly):
        return obj
    if isinstance(obj, Block):
        return Assembly.from_meshes([obj.mesh], info={"group": obj.group.name})
    if isinstance(obj, trimesh.Trimesh):
        return Assembly.from_meshes([obj])
    raise GalleryError(f"expected a Block, an Assembly or a trimesh.Trimesh, got {type(obj).__name__}")


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
