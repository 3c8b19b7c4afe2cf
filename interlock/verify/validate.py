"""Input checks before a verdict: blocks must be solids and must not overlap."""

from __future__ import annotations

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError

__all__ = ["OverlapError", "overlaps", "validate", "OVERLAP_RTOL"]

#: Two blocks overlap when their common volume exceeds this fraction of the smaller one; it matches
#: the contacts' angular tolerance (a face tilted by 1e-4 rad overlaps its neighbour in a wedge of ~1e-4 x volume).
OVERLAP_RTOL = 1e-4
_KEY_DECIMALS = 9


class OverlapError(InterlockError):
    """Blocks that interpenetrate, or a block that is not a valid solid."""


def overlaps(assembly: Assembly, rtol: float = OVERLAP_RTOL) -> list[tuple[int, int, float]]:
    """Pairs of neighbouring blocks whose intersection volume exceeds ``rtol`` of the smaller block.

    Intersections are exact-predicate booleans of manifold3d (float64 meshes).
    Candidate pairs come from ``assembly.neighbours``; a pair's overlap depends
    only on the two block types and their relative transform, so each kind of
    pair is computed once (a patch of one block type has only a few kinds).

    >>> import trimesh
    >>> boxes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 0.5)]
    >>> overlaps(Assembly.from_meshes(boxes))
    [(0, 1, 0.5)]
    """
    import manifold3d

    solids = [_solid(manifold3d, mesh, k) for k, mesh in enumerate(assembly.meshes)]
    inverse = np.linalg.inv(assembly.transforms)
    cache: dict[tuple, float] = {}
    found = []
    for i, j in sorted(assembly.neighbours.edges):
        relative = inverse[i] @ assembly.transforms[j]
        key = (int(assembly.types[i]), int(assembly.types[j]),
               tuple(np.round(relative / assembly.scale, _KEY_DECIMALS).ravel() + 0.0))
        if key not in cache:
            other = solids[assembly.types[j]].transform(relative[:3, :])
            cache[key] = float((solids[assembly.types[i]] ^ other).volume())
        volume = cache[key]
        if volume > rtol * min(assembly.volumes[i], assembly.volumes[j]):
            found.append((int(i), int(j), volume))
    return found


def validate(assembly: Assembly, rtol: float = OVERLAP_RTOL) -> None:
    """Raise :class:`OverlapError` naming the blocks if any two of them overlap."""
    found = overlaps(assembly, rtol)
    if found:
        i, j, volume = max(found, key=lambda item: item[2])
        more = f" ({len(found) - 1} more overlapping pairs)" if len(found) > 1 else ""
        raise OverlapError(
            f"blocks {i} ({assembly.labels[i]}) and {j} ({assembly.labels[j]}) overlap in a volume of {volume:.3g} "
            f"(more than {rtol:g} of the smaller block){more}; blocks of an assembly may only touch"
        )


def _solid(manifold3d, mesh, k):
    solid = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.asarray(mesh.vertices, dtype=np.float64),
                                                  tri_verts=np.asarray(mesh.faces, dtype=np.uint64)))
    status = solid.status()
    if status != manifold3d.Error.NoError:
        raise OverlapError(f"mesh {k} is not a valid solid for manifold3d ({status.name}); "
                           "blocks must be closed, consistently oriented and free of self-intersections")
    return solid
