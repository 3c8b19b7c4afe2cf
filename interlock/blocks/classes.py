"""The class of each block of an assembly: what the gallery colours by and Rhino files layer by."""

from __future__ import annotations

import numpy as np

from interlock.blocks.trilattice import Lozenge
from interlock.wallpaper.elements import GroupElement

__all__ = ["block_classes", "classes_of_labels"]

_IDENTITY = ((1, 0), (0, 1))


def block_classes(assembly) -> tuple[np.ndarray, str]:
    """One small integer per block, and what it means.

    - RhomBlocks (labels are lozenges): the lozenge's orientation 0, 1, 2 ("orientation").
    - Escher blocks (labels are group elements ``g``): the coset ``gT`` of the
      translation subgroup, i.e. the linear part of ``g``; the identity's is 0,
      the others follow in sorted order ("coset").
    - Patches of a periodic cell (labels ``(a, b, i)``, :func:`~interlock.blocks.cell_patch`): the
      class of the cell's block ``i`` by the rules above, else ``i`` itself ("cell block").
    - Anything else: the block's mesh type ("type").

    >>> from interlock.blocks import presets
    >>> classes, kind = block_classes(presets.cube_grid())
    >>> kind, sorted(set(classes.tolist()))
    ('type', [0])
    """
    return classes_of_labels(assembly.labels, assembly.types, assembly.info)


def classes_of_labels(labels, types, info=None) -> tuple[np.ndarray, str]:
    """:func:`block_classes` from the labels, mesh types and ``info`` (``cell_labels``) of an assembly.

    >>> classes_of_labels((None, None), [0, 1])
    (array([0, 1]), 'type')
    """
    labels = tuple(labels)
    if labels and all(isinstance(label, Lozenge) for label in labels):
        return np.array([label.orientation for label in labels], dtype=int), "orientation"
    if labels and all(isinstance(label, GroupElement) for label in labels):
        linear = [label.linear for label in labels]
        order = {part: k for k, part in enumerate(sorted(set(linear), key=lambda p: (p != _IDENTITY, p)))}
        return np.array([order[part] for part in linear], dtype=int), "coset"
    if labels and all(_is_cell_label(label) for label in labels):
        within = np.array([label[2] for label in labels], dtype=int)
        cell_labels = (info or {}).get("cell_labels")
        if cell_labels is not None and len(cell_labels) > within.max():
            classes, kind = classes_of_labels(tuple(cell_labels), np.zeros(len(cell_labels), dtype=int))
            if kind != "type":
                return classes[within], kind
        return within, "cell block"
    return np.asarray(types, dtype=int).copy(), "type"


def _is_cell_label(label) -> bool:
    return isinstance(label, tuple) and len(label) == 3 and all(isinstance(v, (int, np.integer)) for v in label)
