"""A layer of the tetrahedral-octahedral honeycomb: tetrahedra and octahedra between two planes, framed by its ring."""

from __future__ import annotations

import math

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from interlock.blocks.assembly import Assembly
from interlock.blocks.presets.common import PresetError, finite, outward

__all__ = ["honeycomb_layer", "HONEYCOMB_HEIGHT"]

#: The layer's height for edges of length 1: the distance of two opposite faces of the regular octahedron.
HONEYCOMB_HEIGHT = math.sqrt(2.0 / 3.0)
# Centroids of blocks sharing a face are this far apart (tetrahedron to octahedron, edge 1): sqrt(6)/12 +
# sqrt(6)/6 = sqrt(6)/4; neighbours are found within this, plus a margin far below the next distance.
_FACE_NEIGHBOURS = math.sqrt(6.0) / 4.0 * (1 + 1e-6)
_FACES_OF = {0: 3, 1: 3, 2: 6}  # face neighbours inside the layer: up tetrahedron, down tetrahedron, octahedron


def honeycomb_layer(radius: float = 1.5, frame="boundary") -> Assembly:
    """One layer of the tetrahedral-octahedral honeycomb between the planes ``z = 0`` and ``z = sqrt(2/3)``.

    The alternated cubic honeycomb cut along its triangular planes: the
    bottom plane holds a triangular lattice of edge 1 (``a1 = (1, 0)``,
    ``a2 = (1/2, sqrt 3 / 2)``), the top plane the same lattice shifted by
    ``(a1 + a2) / 3``.  Per lattice cell there are three blocks: a regular
    tetrahedron standing on a bottom triangle with its apex in the top plane
    (type 0), one hanging from a top triangle with its apex in the bottom
    plane (type 1), and a regular octahedron between a bottom and a top
    triangle (type 2).  Every tetrahedron shares its three slanted faces with
    octahedra; two tetrahedra touch only along edges and at corners, which
    is why the face-to-face model of Def. 3.3 leaves this layer sliding
    (main paper Remark 3.11) and the contacts of every type hold it.

    Parameters
    ----------
    radius : float
        Blocks whose centroid lies within this distance (edge lengths) of
        the origin's vertical are kept (>= 0).
    frame : "boundary", None or iterable of int
        The fixed blocks: ``"boundary"`` (default), the blocks with fewer
        face neighbours in the patch than inside the layer; None: none.

    Returns
    -------
    Assembly
        Three meshes (types 0, 1, 2 as above) placed by translations; labels
        ``(kind, i, j)`` with ``kind`` one of ``"up"``, ``"down"``,
        ``"octahedron"`` and ``(i, j)`` the lattice cell.

    Raises
    ------
    PresetError
        ``radius`` negative or not finite, or an unknown ``frame``.

    Examples
    --------
    >>> layer = honeycomb_layer(radius=2.0)
    >>> len(layer), [int(k) for k in np.bincount(layer.types)], len(layer.frame)
    (43, [12, 19, 12], 24)
    """
    radius = finite(radius, "radius")
    if radius < 0:
        raise PresetError(f"radius must be >= 0, got {radius}")
    a1, a2 = np.array([1.0, 0.0, 0.0]), np.array([0.5, math.sqrt(3) / 2, 0.0])
    up = np.array([0.0, 0.0, HONEYCOMB_HEIGHT])
    shift = (a1 + a2) / 3 + up  # the top lattice
    meshes = [
        outward(np.array([np.zeros(3), a1, a2, (a1 + a2) / 3 + up]), [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)]),
        outward(np.array([a1 + shift, a1 + a2 + shift, a2 + shift, a1 + a2]),
                [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)]),
        _octahedron(np.array([a1, a1 + a2, a2]), np.array([shift, a1 + shift, a2 + shift])),
    ]
    reach = int(math.ceil(radius / (math.sqrt(3) / 2))) + 2
    centroids = [np.asarray(m.vertices).mean(axis=0) for m in meshes]
    kinds = ("up", "down", "octahedron")
    labels, types, offsets = [], [], []
    for i in range(-reach, reach + 1):
        for j in range(-reach, reach + 1):
            offset = i * a1 + j * a2
            for t in range(3):
                centre = centroids[t] + offset
                if math.hypot(centre[0], centre[1]) <= radius + 1e-9:
                    labels.append((kinds[t], i, j))
                    types.append(t)
                    offsets.append(offset)
    order = sorted(range(len(labels)), key=lambda k: (round(float(np.hypot(*(centroids[types[k]] + offsets[k])[:2])),
                                                            9), labels[k]))
    labels, types, offsets = [labels[k] for k in order], [types[k] for k in order], [offsets[k] for k in order]
    transforms = np.tile(np.eye(4), (len(types), 1, 1))
    transforms[:, :3, 3] = offsets
    centres = np.array([centroids[t] for t in types]) + np.array(offsets).reshape(-1, 3)
    pairs = cKDTree(centres).query_pairs(_FACE_NEIGHBOURS, output_type="ndarray") if len(types) else np.zeros((0, 2))
    degree = np.bincount(np.asarray(pairs, dtype=int).ravel(), minlength=len(types))
    ring = [k for k, t in enumerate(types) if degree[k] < _FACES_OF[t]]
    if frame == "boundary":
        fixed = ring
    elif frame is None:
        fixed = []
    elif isinstance(frame, str):
        raise PresetError(f"frame must be 'boundary', None or block indices, got {frame!r}")
    else:
        fixed = list(frame)
    layer = Assembly(meshes, types, transforms, labels=labels, boundary=ring,
                     info={"preset": "honeycomb_layer", "radius": radius, "height": HONEYCOMB_HEIGHT,
                           "frame": frame if isinstance(frame, str) or frame is None else "given"})
    return layer.with_frame(fixed)


def _octahedron(bottom: np.ndarray, top: np.ndarray) -> trimesh.Trimesh:
    """The octahedron between a triangle ``bottom`` and the triangle ``top`` turned by 180 degrees above it."""
    hull = trimesh.convex.convex_hull(np.vstack([bottom, top]))
    return trimesh.Trimesh(hull.vertices, hull.faces, process=False)
