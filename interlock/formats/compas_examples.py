"""The upstream compas_cra examples: which blocks they fix, and how a file is recognised as one of them."""

from __future__ import annotations

import hashlib

import numpy as np

__all__ = ["UPSTREAM_SUPPORTS", "UPSTREAM_FINGERPRINTS", "FINGERPRINT_ROUNDING", "fingerprint"]

#: Node keys that the upstream compas_cra examples fix, by file stem, for the sample files that mark no
#: block ``is_support`` (``data/compas_cra/README.md``): the wedges, ``A``, ``H`` and the bridge stand on
#: blocks 0 and 1; the cubes, shelves, snake, concave and curved models on block 0; the armadillo on its
#: first course (33 blocks, as marked in upstream's solved copy).  :func:`~interlock.formats.compas.read_compas` applies them only
#: to a file that is that example (:data:`UPSTREAM_FINGERPRINTS`), whatever its name.
UPSTREAM_SUPPORTS: dict[str, tuple[int, ...]] = {
    **{stem: (0, 1) for stem in ("type-a", "type-b", "type-c", "type-d", "A", "H", "bridge")},
    **{stem: (0,) for stem in ("cubes", "shelf", "shelf-s1", "shelf-s2", "shelf-s3", "shelf-stable", "snake",
                               "concave-long", "concave-short", "curve-3-blocks", "cube-curve-short",
                               "cube-curve-tall")},
    "armadillo": (*range(0, 8), *range(79, 89), *range(217, 228), *range(328, 332)),
}
#: What makes a file one of the upstream examples, by file stem: its node count and the
#: :func:`fingerprint` of its node keys and blocks, as measured on the files of ``data/compas_cra``
#: (all twenty differ).  A file under an example's name with other blocks is not that example.
UPSTREAM_FINGERPRINTS: dict[str, tuple[int, str]] = {
    "A": (3, "69bba7aa1fa381d1"), "H": (3, "3cebb28044f4acab"), "armadillo": (399, "b34b69f5b470d0f7"),
    "bridge": (16, "4d64c747df3d45f1"), "concave-long": (2, "bb6fb4c22a150867"),
    "concave-short": (2, "79295c03e2d881ef"), "cube-curve-short": (2, "77f5f1166f7ded73"),
    "cube-curve-tall": (2, "ecefb15f9a1b8043"), "cubes": (3, "00ceb66e8dc2b924"),
    "curve-3-blocks": (3, "209da09655a5f454"), "shelf-s1": (13, "3466dab42887f7f7"),
    "shelf-s2": (12, "969a8b5ff5caf226"), "shelf-s3": (12, "4789c54f6f490328"),
    "shelf-stable": (9, "b7d0e72c931ae5a7"), "shelf": (11, "eb64ca084a987934"), "snake": (4, "12d7ff010ea99d00"),
    "type-a": (3, "796265e35ade0b50"), "type-b": (3, "ac7f1c6dd561f391"), "type-c": (3, "423895b3546c3f99"),
    "type-d": (3, "0705510e9eff12b9"),
}
#: :func:`fingerprint` rounds vertex coordinates to this fraction of the model size (its largest bounding-box
#: extent, rounded up to a power of ten): a copy re-saved by COMPAS (same floats, or noise of 1e-16) keeps the
#: fingerprint, moving a vertex of a metre-sized model by a micrometre or more changes it.
FINGERPRINT_ROUNDING = 1e-6


def fingerprint(keys, meshes, rounding: float = FINGERPRINT_ROUNDING) -> str:
    """A digest of an assembly's node keys and blocks, the same for the same file however it is named.

    Each block's distinct used vertices, rounded to ``rounding`` times the
    model size (its largest bounding-box extent, rounded up to a power of ten),
    are hashed (SHA-256, first 16 hex digits) with the block's node key in the
    given order.  :func:`~interlock.formats.compas.read_compas` compares it with :data:`UPSTREAM_FINGERPRINTS`.

    Parameters
    ----------
    keys : sequence
        The node keys, one per block.
    meshes : sequence of trimesh.Trimesh
        The blocks in world coordinates.
    rounding : float

    Returns
    -------
    str

    Examples
    --------
    >>> import trimesh
    >>> cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    >>> moved = cube.copy()
    >>> _ = moved.apply_translation([0, 0, 1e-3])
    >>> digest = fingerprint([0], [cube])
    >>> [digest == fingerprint(keys, blocks) for keys, blocks in [([0], [cube.copy()]), ([0], [moved]), ([1], [cube])]]
    [True, False, False]
    """
    used = [np.asarray(mesh.vertices)[np.unique(mesh.faces)] for mesh in meshes]
    size = float(np.ptp(np.vstack(used), axis=0).max()) if used else 0.0
    quantum = rounding * 10.0 ** np.ceil(np.log10(size)) if size > 0 else rounding
    digest = hashlib.sha256()
    for key, points in zip(keys, used):
        digest.update(f"{key}:".encode())
        digest.update(np.unique(np.rint(points / quantum).astype("<i8"), axis=0).tobytes())
    return digest.hexdigest()[:16]
