"""Collision checks along a finite motion: overlap volumes of moving blocks with the others, step by step."""

from __future__ import annotations

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.verify.validate import manifold_solid

__all__ = ["MotionOverlaps", "transform_offset", "IDENTITY_RTOL"]

#: A path's transform is the identity (a block does not move) when it differs from it by at most this (linear
#: part; translations relative to the model size); the check for rigid transforms uses the same tolerance.
IDENTITY_RTOL = 1e-9


class MotionOverlaps:
    """Overlap volumes of moving blocks with every block whose bounding box they meet, one step at a time.

    ``depth`` (one length per block, optional) lets a pair interfere: an
    overlap whose measured :func:`~interlock.verify.validate.penetration` is at
    most ``depth[i] + depth[j]`` is not counted (the blocks' faces lie within
    that much of where the input puts them); ``deepest`` keeps the deepest such
    interference met so far.
    """

    def __init__(self, assembly: Assembly, moving, gap: float, depth=None):
        import manifold3d

        self.manifold3d, self.assembly, self.gap = manifold3d, assembly, gap
        self.moving = np.asarray(moving, dtype=int)
        self.depth = None if depth is None else np.broadcast_to(np.asarray(depth, dtype=float), (len(assembly),))
        self.shapes, self.fixed_solids = {}, {}
        self.booleans = 0
        self.deepest = 0.0

    def _shape(self, t):
        if t not in self.shapes:
            self.shapes[t] = manifold_solid(self.manifold3d, self.assembly.meshes[t], t)
        return self.shapes[t]

    def _placed(self, b, T):
        return self._shape(int(self.assembly.types[b])).transform(T[:3, :])

    def __call__(self, M):
        """(volume, fraction, pair) of the worst overlap and whether the moving blocks are apart from the rest."""
        a = self.assembly
        transforms = M @ a.transforms
        bounds = a.bounds.copy()
        for b in self.moving:
            mesh = a.meshes[a.types[b]]
            world = mesh.vertices @ transforms[b, :3, :3].T + transforms[b, :3, 3]
            bounds[b] = world.min(axis=0), world.max(axis=0)
        moving, still = self.moving, np.ones(len(a), dtype=bool)
        still[moving] = False
        lo, hi = bounds[:, 0], bounds[:, 1]
        meets = np.all((lo[moving, None] <= hi[None] + self.gap) & (lo[None] <= hi[moving, None] + self.gap), axis=2)
        meets[np.arange(len(moving)), moving] = False
        worst, apart = (0.0, 0.0, None), bool(still.any())  # with nothing at rest there is nothing to leave
        done, solids = set(), {}
        for r, j in zip(*np.nonzero(meets)):
            i, j = int(moving[r]), int(j)
            together = not still[j] and transform_offset(M[i] - M[j] + np.eye(4), a.scale) <= IDENTITY_RTOL
            if (min(i, j), max(i, j)) in done or together:
                continue  # counted already, or two blocks moved as one: their overlap is that of the assembly given
            done.add((min(i, j), max(i, j)))
            for b in (i, j):
                if b not in solids:
                    solids[b] = self._placed(b, transforms[b]) if not still[b] else self._fixed(b)
            self.booleans += 1
            common = solids[i] ^ solids[j]
            volume = max(float(common.volume()), 0.0)
            fraction = volume / min(a.volumes[i], a.volumes[j])
            if fraction > 0 and self.depth is not None:
                reach = self._penetration(i, j, transforms, common)
                if reach <= self.depth[i] + self.depth[j]:
                    self.deepest = max(self.deepest, reach)
                    volume = fraction = 0.0
            if fraction > worst[1] or worst[2] is None:
                worst = (volume, fraction, (i, j))
            if still[j] and apart:
                apart = self._gap(solids[i], solids[j]) > self.gap
        return worst[0], worst[1], worst[2], apart

    def _penetration(self, i: int, j: int, transforms, common) -> float:
        from interlock.verify.validate import penetration

        a = self.assembly
        meshes = []
        for b in (i, j):
            mesh = a.meshes[a.types[b]]
            meshes.append(type(mesh)(mesh.vertices @ transforms[b, :3, :3].T + transforms[b, :3, 3], mesh.faces,
                                     process=False))
        return penetration(meshes[0], meshes[1], common)

    def _fixed(self, b):
        if b not in self.fixed_solids:
            self.fixed_solids[b] = self._placed(b, self.assembly.transforms[b])
        return self.fixed_solids[b]

    def _gap(self, one, other) -> float:
        min_gap = getattr(one, "min_gap", None)  # manifold3d >= 3
        return float(min_gap(other, 2 * self.gap)) if min_gap is not None and self.gap > 0 else 0.0


def transform_offset(T, size) -> np.ndarray:
    """How far each transform is from the identity: largest entry of ``T - I``, translations over ``size``."""
    return (np.abs(T - np.eye(4)) / np.array([1, 1, 1, size])).max(axis=(-2, -1))
