"""Lozenge tilings: plane partitions, height functions, uniform random and periodic tilings (main paper Sec. 4.4)."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from numbers import Integral

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order

from interlock.blocks.cftp import uniform_plane_partition
from interlock.blocks.limits import MAX_BLOCKS, check_block_count
from interlock.blocks.trilattice import (DOWN, LATTICE_BASIS, LOZENGE_CORNERS, UP, UP_OFFSETS, Lozenge, TilingError,
                                         as_integers, as_lozenges, as_plane_partition, as_region, cell_keys,
                                         gauss_reduced, hexagon_sizes, hexagon_triangles, lookup, up_cells)

__all__ = ["Lozenge", "LozengeTiling", "TilingError", "hexagon_triangles", "random_hexagon", "staircase",
           "LATTICE_BASIS", "UP", "DOWN", "UP_OFFSETS", "LOZENGE_CORNERS"]


# Edges of each triangle kind as (start, end) offsets from p(i, j) in the positive directions
# u = p(1, 0), v = p(-1, 1), w = p(0, -1); edge k of either triangle is the diagonal of orientation k.
_EDGES = {UP: np.array([[[0, 0], [1, 0]], [[1, 0], [0, 1]], [[0, 1], [0, 0]]]),
          DOWN: np.array([[[0, 1], [1, 1]], [[1, 0], [0, 1]], [[1, 1], [1, 0]]])}
# The six triangles (i, j, kind) around the vertex p(0, 0).
_AROUND = np.array([[0, 0, UP], [-1, 0, UP], [0, -1, UP], [-1, 0, DOWN], [0, -1, DOWN], [-1, -1, DOWN]])
# Height change along a positive direction: on a tile edge, across a lozenge (its short diagonal).
_RISE, _DROP = 1, -2
# D-triangle offset of a cube face normal to axis k from its corner p(i, j) (see from_plane_partition).
_FACE_SHIFT = np.array([[-1, -1], [0, -1], [-1, 0]])


@dataclass(frozen=True, eq=False)
class LozengeTiling:
    """Lozenges of the unit triangular lattice that do not overlap (main paper Sec. 4.4, Fig. 3b).

    A finite tiling tiles the union of its lozenges (:meth:`from_lozenges` also checks a given
    region for gaps).  A periodic tiling is the patch ``lozenges`` repeated by the integer
    combinations of ``periods``; it must cover every class of triangles modulo the periods once.

    Attributes
    ----------
    lozenges : array (n, 3) of int
        Rows ``(i, j, orientation)`` (see :class:`Lozenge`), sorted.
    periods : array (2, 2) of int or None
        Period vectors in lattice coordinates, or None for a finite tiling.

    Examples
    --------
    >>> t = LozengeTiling.from_plane_partition([[1, 0], [0, 0]], c=1)
    >>> print(t)
    finite lozenge tiling: 8 lozenges (2/2/4 by orientation)
    >>> t.to_plane_partition().tolist()
    [[1, 0], [0, 0]]
    """

    lozenges: np.ndarray
    periods: np.ndarray | None = None

    def __post_init__(self):
        lozenges = as_lozenges(self.lozenges)
        lozenges = lozenges[np.lexsort(lozenges.T[::-1])]
        lozenges.setflags(write=False)
        object.__setattr__(self, "lozenges", lozenges)
        if self.periods is not None:
            periods = as_integers(self.periods, "periods")
            if periods.shape != (2, 2) or round(np.linalg.det(periods)) == 0:
                raise TilingError("periods must be two linearly independent integer vectors (lattice coordinates), "
                                  f"got {periods.tolist()}")
            periods.setflags(write=False)
            object.__setattr__(self, "periods", periods)
        for kind, cells in ((DOWN, lozenges[:, :2]), (UP, up_cells(lozenges))):
            keys = cell_keys(self._reduce(cells), kind)
            order = np.argsort(keys, kind="stable")
            twice = np.flatnonzero(np.diff(keys[order]) == 0)
            if twice.size:
                a, b = order[twice[0]], order[twice[0] + 1]
                raise TilingError(f"lozenges overlap: {Lozenge(*lozenges[a])} and {Lozenge(*lozenges[b])} both cover "
                                  f"{'UD'[kind]}{tuple(cells[a].tolist())}{' (modulo the periods)' * self.is_periodic}"
                                  "; each triangle may lie in one lozenge only")
        if self.is_periodic and len(lozenges) != self.cell_size:
            raise TilingError(f"a periodic tiling with periods {self.periods.tolist()} needs exactly {self.cell_size} "
                              f"lozenges per period (one per class of down-triangles), got {len(lozenges)}: "
                              f"{'gaps' if len(lozenges) < self.cell_size else 'overlaps'}")

    # --- constructors -------------------------------------------------------------------------------
    @classmethod
    def from_lozenges(cls, lozenges, region=None) -> LozengeTiling:
        """A finite tiling, checked to cover ``region`` (rows ``(i, j, UP|DOWN)``) without gaps.

        >>> LozengeTiling.from_lozenges([(0, 0, 1)], region=[(0, 0, UP), (0, 0, DOWN), (1, 0, UP)])
        ... # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        interlock.blocks.trilattice.TilingError: the lozenges leave 1 triangle(s) of the region uncovered, ...
        """
        tiling = cls(lozenges)
        if region is not None:
            region, tri = as_region(region), tiling.triangles()
            want, have = cell_keys(region[:, :2], region[:, 2]), cell_keys(tri[:, :2], tri[:, 2])
            for message, rows, missing in (("the lozenges leave {} triangle(s) of the region uncovered", region,
                                            ~np.isin(want, have)),
                                           ("{} triangle(s) of the lozenges lie outside the region", tri,
                                            ~np.isin(have, want))):
                if missing.any():
                    i, j, kind = rows[missing][0].tolist()
                    raise TilingError(f"{message.format(missing.sum())}, e.g. {'UD'[kind]}({i}, {j}); a tiling must "
                                      "cover its region exactly")
        return tiling

    @classmethod
    def periodic(cls, lozenges, periods) -> LozengeTiling:
        """The doubly periodic tiling: the patch ``lozenges`` repeated by ``periods`` (lattice coordinates).

        >>> print(LozengeTiling.periodic([(0, 0, 2)], periods=[(1, 0), (0, 1)]))
        periodic lozenge tiling: 1 lozenges (0/0/1 by orientation), periods [[1, 0], [0, 1]]
        """
        if periods is None:
            raise TilingError("a periodic tiling needs two period vectors")
        return cls(lozenges, periods)

    @classmethod
    def from_plane_partition(cls, partition, c: int) -> LozengeTiling:
        """The tiling of the ``a x b x c`` hexagon seen as the cube stack ``partition`` (faces -> lozenges).

        ``partition[x][y]`` cubes stand on cell ``(x, y)`` of an ``a x b`` floor; entries are
        non-increasing along rows and columns and at most ``c``.  The cube corner ``(x, y, z)`` projects
        to ``p(x - y, y - z)``; a visible face normal to axis ``k`` becomes a lozenge of orientation ``k``.

        >>> len(LozengeTiling.from_plane_partition(np.zeros((2, 3), int), c=4))
        26
        """
        pp = as_plane_partition(partition, c)
        a, b = pp.shape
        x, y = np.indices((a, b)).reshape(2, -1)
        corners = [np.stack([x, y, pp.ravel()], axis=1)]  # the top faces
        stack = pp[:, :, None] > np.arange(c)  # cube (x, y, z) present
        for axis in (0, 1):  # walls facing +x at (X, y, z), facing +y at (x, Y, z): X, Y the first free place
            first = stack.sum(axis=axis)
            along, z = np.indices(first.shape).reshape(2, -1)
            corners.append(np.stack([first.ravel(), along, z] if axis == 0 else [along, first.ravel(), z], axis=1))
        faces = [np.column_stack([cube[:, 0] - cube[:, 1], cube[:, 1] - cube[:, 2]]) + _FACE_SHIFT[k]
                 for k, cube in zip((2, 0, 1), corners)]
        orientation = np.repeat([2, 0, 1], [len(f) for f in faces])
        return cls.from_lozenges(np.column_stack([np.concatenate(faces), orientation]), hexagon_triangles(a, b, c))

    @classmethod
    def from_height_function(cls, heights: Mapping) -> LozengeTiling:
        """The tiling of the triangles whose corners all carry a height (inverse of :meth:`height_function`).

        Along each lattice edge, in the directions ``u = p(1, 0)``, ``v = p(-1, 1)``, ``w = p(0, -1)``,
        the height rises by 1 on a tile edge and drops by 2 across a lozenge (its short diagonal).

        >>> t = LozengeTiling.from_plane_partition([[2, 1], [1, 0]], c=2)
        >>> LozengeTiling.from_height_function(t.height_function()).to_plane_partition().tolist()
        [[2, 1], [1, 0]]
        """
        if not isinstance(heights, Mapping) or not heights:
            raise TilingError("a height function is a non-empty mapping {(i, j): height} over lattice vertices")
        points = as_integers(list(heights.keys()), "height function vertices").reshape(-1, 2)
        values = as_integers(list(heights.values()), "heights").reshape(-1)
        order = np.argsort(cell_keys(points, 0))
        cells = np.unique(np.concatenate([points - off for off in ((0, 0), (1, 0), (0, 1), (1, 1))]), axis=0)
        region, drop = [], []
        for kind in (UP, DOWN):
            ends = cells[:, None, None, :] + _EDGES[kind]  # (cells, 3 edges, 2 ends, 2)
            idx, found = lookup(cell_keys(points, 0), order, cell_keys(ends.reshape(-1, 2), 0))
            inside = found.reshape(-1, 6).all(axis=1)
            rise = np.diff(values[idx].reshape(-1, 3, 2), axis=2)[inside, :, 0]
            bad = np.argwhere(~np.isin(rise, (_RISE, _DROP)))
            if bad.size:
                (t, e), edge = bad[0], ends[inside][bad[0][0], bad[0][1]].tolist()
                raise TilingError(f"the heights change by {rise[t, e]} from {tuple(edge[0])} to {tuple(edge[1])}; "
                                  f"along a lattice edge (directions u, v, w) the height must change by +{_RISE} "
                                  f"(tile edge) or {_DROP} (across a lozenge)")
            region.append(np.column_stack([cells[inside], np.full(inside.sum(), kind)]))
            drop.append(np.argmax(rise == _DROP, axis=1))  # exactly one edge of a triangle drops
        lozenges = np.column_stack([region[DOWN][:, :2], drop[DOWN]])
        across = np.concatenate([region[UP][:, :2] - UP_OFFSETS[drop[UP]], up_cells(lozenges)])
        kinds = np.repeat([DOWN, UP], [len(drop[UP]), len(lozenges)])
        region = np.concatenate(region)
        outside = ~np.isin(cell_keys(across, kinds), cell_keys(region[:, :2], region[:, 2]))
        if outside.any():
            raise TilingError(f"the heights drop by {-_DROP} across the region's boundary at "
                              f"{'UD'[kinds[outside][0]]}{tuple(across[outside][0].tolist())}; boundary edges must be "
                              f"tile edges (height +{_RISE} along u, v, w)")
        return cls.from_lozenges(lozenges, region)

    # --- views -----------------------------------------------------------------------------------------
    @property
    def is_periodic(self) -> bool:
        return self.periods is not None

    @property
    def cell_size(self) -> int:
        """Lozenges per period (``|det periods|``), or the number of lozenges of a finite tiling."""
        return abs(round(np.linalg.det(self.periods))) if self.is_periodic else len(self.lozenges)

    @property
    def orientation_counts(self) -> tuple[int, int, int]:
        return tuple(np.bincount(self.lozenges[:, 2], minlength=3).tolist())

    def __len__(self) -> int:
        return len(self.lozenges)

    def __iter__(self) -> Iterator[Lozenge]:
        return (Lozenge(*row) for row in self.lozenges.tolist())

    def __str__(self) -> str:
        counts = "/".join(map(str, self.orientation_counts))
        kind, extra = ("periodic", f", periods {self.periods.tolist()}") if self.is_periodic else ("finite", "")
        return f"{kind} lozenge tiling: {len(self)} lozenges ({counts} by orientation){extra}"

    def to_dict(self) -> dict:
        return {"lozenges": self.lozenges.tolist(), "periods": self.periods.tolist() if self.is_periodic else None}

    def polygons(self) -> np.ndarray:
        """The corners of every lozenge in the plane, counter-clockwise, shape (n, 4, 2)."""
        return (LOZENGE_CORNERS[self.lozenges[:, 2]] + self.lozenges[:, None, :2]) @ LATTICE_BASIS

    def triangles(self) -> np.ndarray:
        """The covered triangles, rows ``(i, j, UP|DOWN)``: the lozenges' down-triangles, then their up-triangles."""
        return np.concatenate([np.column_stack([self.lozenges[:, :2], np.full(len(self), DOWN)]),
                               np.column_stack([up_cells(self.lozenges), np.full(len(self), UP)])])

    def adjacency(self) -> np.ndarray:
        """Pairs ``(p, q)``, ``p <= q``, of lozenges sharing an edge (modulo the periods), shape (m, 2)."""
        loz = self.lozenges
        others = np.array([[m for m in range(3) if m != k] for k in range(3)])[loz[:, 2]]  # (n, 2)
        cells = np.concatenate([loz[:, None, :2] + UP_OFFSETS[others], up_cells(loz)[:, None] - UP_OFFSETS[others]], 1)
        keys = self._triangle_keys()  # the down-triangles of lozenges 0..n-1, then their up-triangles
        idx, found = lookup(keys, np.argsort(keys), cell_keys(self._reduce(cells), np.array([UP, UP, DOWN, DOWN])))
        pairs = np.stack([np.repeat(np.arange(len(loz)), 4), idx % max(len(loz), 1)], axis=1)[found.ravel()]
        return np.unique(np.sort(pairs, axis=1), axis=0).reshape(-1, 2)

    def boundary(self) -> tuple[int, ...]:
        """Indices of the lozenges that meet the region's boundary, along an edge or at a corner: the outer ring.

        A RhomBlock's top reaches past its lozenge's corners, so blocks also touch across a shared
        corner; a patch is held by the blocks that would touch the missing outside (Cor. 4.8).  A
        periodic tiling has no boundary.

        >>> len(random_hexagon(3, 3, 3, seed=0).boundary())
        16
        """
        if self.is_periodic:
            return ()
        keys = np.sort(self._triangle_keys())
        corners = LOZENGE_CORNERS[self.lozenges[:, 2]] + self.lozenges[:, None, :2]  # (n, 4, 2)
        around = corners[:, :, None, :] + _AROUND[:, :2]
        _, found = lookup(keys, np.arange(len(keys)), cell_keys(around, _AROUND[:, 2]))
        return tuple(np.flatnonzero(~found.reshape(len(self), -1).all(axis=1)).tolist())

    # --- height functions and plane partitions ------------------------------------------------------
    def height_function(self) -> dict[tuple[int, int], int]:
        """Heights on the vertices of a finite tiling's region (rise 1 along tile edges, drop 2 across lozenges).

        Normalised so that at the vertex with the largest ``(i, j)`` the height is ``i - j``; for the
        ``a x b x c`` hexagon that is the corner ``p(a, 0)``, and every vertex's height is ``x + y + z``
        of its cube corner.  The region must be connected; around a hole the heights must close up.

        >>> LozengeTiling.from_plane_partition([[0]], c=1).height_function()[(0, 0)]
        0
        """
        if self.is_periodic:
            raise TilingError("height functions are defined for finite tilings; a periodic tiling's height grows "
                              "linearly along its periods")
        loz, tri = self.lozenges, self.triangles()
        ends = np.concatenate([tri[tri[:, 2] == k, None, None, :2] + _EDGES[k] for k in (DOWN, UP)])
        rise = np.full((len(tri), 3), _RISE)
        rise[np.arange(len(tri)), np.tile(loz[:, 2], 2)] = _DROP  # a lozenge's diagonal is edge k of both triangles
        rise = rise.ravel()
        points, inverse = np.unique(ends.reshape(-1, 2), axis=0, return_inverse=True)
        a, b = inverse.reshape(-1, 2).T
        n = len(points)
        root = n - 1  # np.unique sorts: the largest (i, j)
        order, parent = breadth_first_order(coo_matrix((np.ones(a.size), (a, b)), shape=(n, n)), root, directed=False)
        if len(order) < n:
            raise TilingError("height functions need a connected region; this tiling falls apart into pieces")
        steps = np.concatenate([a * n + b, b * n + a])  # the rise along each edge, both ways
        idx, _ = lookup(steps, np.argsort(steps), parent[order[1:]] * n + order[1:])
        total, up = np.zeros(n, dtype=np.int64), parent.copy()
        total[order[1:]], up[root] = np.concatenate([rise, -rise])[idx], root
        while np.any(up != root):  # pointer jumping; total[v] is the rise from up[v] to v
            total, up = total + total[up], up[up]
        h = total + points[root, 0] - points[root, 1]
        if np.any(h[b] - h[a] != rise):
            raise TilingError("the heights do not close up around a hole of the region; height functions need a "
                              "simply connected region (or no height change around each hole)")
        return dict(zip(map(tuple, points.tolist()), h.tolist()))

    def to_plane_partition(self) -> np.ndarray:
        """The plane partition (cube stack) of a tiling of the ``a x b x c`` hexagon, shape ``(a, b)``.

        The hexagon is the one of :func:`hexagon_triangles`; ``a, b, c`` are read off the region.

        >>> random_hexagon(2, 3, 1, seed=0).to_plane_partition().shape
        (2, 3)
        """
        if self.is_periodic or not len(self):
            raise TilingError("only a finite, non-empty tiling of an a x b x c hexagon has a plane partition")
        ij = (LOZENGE_CORNERS[self.lozenges[:, 2]] + self.lozenges[:, None, :2]).reshape(-1, 2)
        a, b, c = int(ij[:, 0].max()), int(-ij[:, 0].min()), int(-ij[:, 1].min())
        hexagon = hexagon_triangles(a, b, c)
        if not np.array_equal(np.sort(self._triangle_keys()), np.sort(cell_keys(hexagon[:, :2], hexagon[:, 2]))):
            raise TilingError("the tiling's region is not an a x b x c hexagon of hexagon_triangles(a, b, c) "
                              f"(its extent suggests a, b, c = {a}, {b}, {c}); only those are plane partitions")
        heights = self.height_function()
        top = self.lozenges[self.lozenges[:, 2] == 2]
        i, j = top[:, 0] + 1, top[:, 1]  # the corner p(x - y, y - z) of a top face
        h = np.array([heights[k] for k in zip(i.tolist(), j.tolist())], dtype=np.int64)  # x + y + z
        pp = np.zeros((a, b), dtype=np.int64)
        pp[(h + 2 * i + j) // 3, (h - i + j) // 3] = (h - i - 2 * j) // 3
        return pp

    # --- internals -------------------------------------------------------------------------------------
    def _reduce(self, cells: np.ndarray) -> np.ndarray:
        """Lattice points (or triangle indices) reduced modulo the periods to canonical representatives."""
        if not self.is_periodic:
            return cells
        p = self.periods
        det = int(round(np.linalg.det(p)))
        adjugate = np.array([[p[1, 1], -p[0, 1]], [-p[1, 0], p[0, 0]]], dtype=np.int64) * np.sign(det)
        return cells - ((cells @ adjugate) // abs(det)) @ p

    def _triangle_keys(self) -> np.ndarray:
        tri = self.triangles()
        return cell_keys(self._reduce(tri[:, :2]), tri[:, 2])


def random_hexagon(a: int, b: int, c: int, seed, *, max_blocks: int = MAX_BLOCKS, progress=None) -> LozengeTiling:
    """A uniformly random lozenge tiling of the ``a x b x c`` hexagon, by coupling from the past.

    Parameters
    ----------
    a, b, c : int
        The hexagon (non-negative); the tiling has ``ab + bc + ca`` lozenges.
    seed : int, numpy.random.Generator or SeedSequence
        The source of randomness (``numpy.random.default_rng(seed)``); an int must be >= 0.
    max_blocks : int
        Refuse a hexagon of more lozenges than this, before sampling
        (:data:`~interlock.blocks.limits.MAX_BLOCKS`).
    progress : callable, optional
        Called as ``progress(sweeps)`` as coupling from the past runs (for a progress bar).

    Returns
    -------
    LozengeTiling
        A sample from the uniform distribution on the ``a x b x c`` hexagon's tilings.

    Notes
    -----
    Propp-Wilson on plane partitions (:meth:`LozengeTiling.from_plane_partition`).  The heat-bath
    chain that redraws one entry uniformly among the values its four neighbours allow is monotone
    for the entrywise order (with the same uniform, a higher neighbourhood never gives a lower
    value), and a checkerboard half-sweep redraws all entries of one parity ``x + y`` at once, as
    they do not constrain each other.  Two chains, from the empty and the full box, run from time
    ``-T`` to 0 with the same uniforms; ``T`` doubles (reusing the uniforms of the later epochs)
    until they meet.  A sweep is a few numpy operations on the ``a x b`` array; ``T`` grows like
    the square of the side (heights relax diffusively): for ``40 x 40 x 40`` typically ``T = 4096``,
    some 8,000 sweeps in all, well under two seconds.

    Examples
    --------
    >>> t = random_hexagon(10, 10, 10, seed=0)
    >>> len(t), t.orientation_counts
    (300, (100, 100, 100))
    """
    a, b, c = hexagon_sizes(a, b, c)
    check_block_count(a * b + b * c + c * a, f"a {a} x {b} x {c} hexagon", max_blocks)
    if isinstance(seed, (bool, np.bool_)) or (isinstance(seed, Integral) and seed < 0):
        raise TilingError(f"seed must be an integer >= 0 (or a numpy Generator or SeedSequence), got {seed!r}")
    try:
        rng = np.random.default_rng(seed)
    except (TypeError, ValueError) as error:
        raise TilingError(f"seed must be an integer >= 0 (or a numpy Generator or SeedSequence), got {seed!r}: "
                          f"{error}") from None
    return LozengeTiling.from_plane_partition(uniform_plane_partition(a, b, c, rng, progress), c)


def staircase(counts) -> LozengeTiling:
    """The periodic tiling of the stepped plane with normal ``n = counts``: a staircase.

    ``counts = (n0, n1, n2)`` (non-negative integers, not all zero) gives, per period, ``n_k / gcd``
    lozenges of orientation ``k``: one non-zero count is the tiling by one orientation, two are a
    staircase with two orientations (steps of ``n0`` and ``n1``), three one with all three
    (``(1, 1, 1)``: the tumbling-blocks tiling).  The lozenges are the faces facing ``+x, +y, +z``
    of the cubes below the plane ``n . (x, y, z) = 0``: a face normal to axis ``k`` has its corner
    ``v`` at ``0 <= n . v < n_k``.

    >>> print(staircase((1, 1, 1)))
    periodic lozenge tiling: 3 lozenges (1/1/1 by orientation), periods [[1, 1], [1, -2]]
    """
    n = as_integers(counts, "staircase counts").reshape(-1)
    if n.size != 3 or n.min() < 0 or n.max() == 0:
        raise TilingError(f"staircase needs three non-negative integers, not all zero, got {np.ravel(counts).tolist()}")
    n = n // math.gcd(*n.tolist())
    total = int(n.sum())
    # p(i, j) lifts to (z + i + j, z + j, z), where n . v = form . (i, j) + total z; the periods are
    # {(i, j): form . (i, j) = 0 mod total}, with Hermite basis (step, 0), (offset, rise)
    form = np.array([n[0], n[0] + n[1]])
    step = total // math.gcd(int(n[0]), total)
    rise, offset = next((j, i) for j in range(1, total + 1) for i in range(step) if (form @ (i, j)) % total == 0)
    corners = np.mgrid[0:step, 0:rise].reshape(2, -1).T  # one vertex per class modulo the periods
    value = (corners @ form) % total
    faces = [np.column_stack([corners[value < n[k]] + _FACE_SHIFT[k], np.full((value < n[k]).sum(), k)])
             for k in range(3)]
    return LozengeTiling(np.concatenate(faces), gauss_reduced(np.array([step, 0]), np.array([offset, rise])))
