"""The unit triangular lattice of lozenge tilings: coordinates, triangles, lozenges, and checks of integer input."""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral

import numpy as np

from interlock.errors import InterlockError

__all__ = ["Lozenge", "TilingError", "hexagon_triangles", "LATTICE_BASIS", "UP", "DOWN", "UP_OFFSETS",
           "LOZENGE_CORNERS", "COORD_BOUND", "hexagon_sizes", "as_integers", "as_lozenges", "as_region",
           "as_plane_partition", "up_cells", "cell_keys", "lookup", "gauss_reduced"]

#: Vertex ``p(i, j)`` of the unit triangular lattice is ``i * LATTICE_BASIS[0] + j * LATTICE_BASIS[1]``.
LATTICE_BASIS = np.array([[1.0, 0.0], [0.5, math.sqrt(3.0) / 2]])
#: Triangle kinds: up-triangle ``U(i, j) = p(i, j) p(i+1, j) p(i, j+1)``, down-triangle
#: ``D(i, j) = p(i+1, j) p(i, j+1) p(i+1, j+1)``.
UP, DOWN = 0, 1
#: A lozenge of orientation ``k`` is ``D(i, j)`` plus ``U((i, j) + UP_OFFSETS[k])``: the up-triangle across
#: the down-triangle's top edge (0), left edge (1) or right edge (2).  Seen as a stack of unit cubes,
#: orientation ``k`` is a face normal to the 3D axis ``k`` (x, y, z).
UP_OFFSETS = np.array([[0, 1], [0, 0], [1, 0]])
#: The four corners of a lozenge of each orientation, counter-clockwise, relative to ``p(i, j)``.
LOZENGE_CORNERS = np.array([[[1, 0], [1, 1], [0, 2], [0, 1]],
                            [[0, 0], [1, 0], [1, 1], [0, 1]],
                            [[1, 0], [2, 0], [1, 1], [0, 1]]])

#: Lattice coordinates must stay below this in absolute value (triangles are packed into int64 keys).
COORD_BOUND = 2**20


class TilingError(InterlockError):
    """Lozenges that overlap or leave gaps, or a plane partition or height function that is not valid."""


@dataclass(frozen=True, order=True)
class Lozenge:
    """One lozenge: the down-triangle ``D(i, j)`` and its neighbour across edge ``orientation``.

    >>> z = Lozenge(0, 0, 2)
    >>> z.down, z.up, str(z)
    ((0, 0), (1, 0), 'D(0, 0)+U(1, 0)')
    """

    i: int
    j: int
    orientation: int

    def __post_init__(self):
        for name in ("i", "j", "orientation"):
            object.__setattr__(self, name, int(getattr(self, name)))
        if self.orientation not in (0, 1, 2):
            raise TilingError(f"a lozenge's orientation must be 0, 1 or 2, got {self.orientation}")

    @property
    def down(self) -> tuple[int, int]:
        return (self.i, self.j)

    @property
    def up(self) -> tuple[int, int]:
        di, dj = UP_OFFSETS[self.orientation].tolist()
        return (self.i + di, self.j + dj)

    def __str__(self) -> str:
        return f"D{self.down}+U{self.up}"


def hexagon_triangles(a: int, b: int, c: int) -> np.ndarray:
    """The triangles ``(i, j, UP|DOWN)`` of the ``a x b x c`` hexagon, the shadow of the box ``[0,a]x[0,b]x[0,c]``.

    Its corners are ``p(a, 0), p(a-b, b), p(-b, b), p(-b, b-c), p(0, -c), p(a, -c)``:
    ``-b <= i <= a``, ``-c <= j <= b`` and ``-c <= i+j <= a``.  It has ``2 (ab + bc + ca)`` triangles.

    >>> len(hexagon_triangles(2, 2, 2))
    24
    """
    a, b, c = hexagon_sizes(a, b, c)
    i, j = np.mgrid[-b - 1:a + 1, -c - 1:b + 1].reshape(2, -1)
    out = []
    for kind, third in ((UP, 1), (DOWN, 2)):  # thrice the centroid: 3 (i, j) + third
        x, y = 3 * i + third, 3 * j + third
        inside = (-3 * b < x) & (x < 3 * a) & (-3 * c < y) & (y < 3 * b) & (-3 * c < x + y) & (x + y < 3 * a)
        out.append(np.column_stack([i[inside], j[inside], np.full(inside.sum(), kind)]))
    return np.concatenate(out)


# --- checks of input and integer keys -------------------------------------------------------------

def hexagon_sizes(a, b, c) -> tuple[int, int, int]:
    """The hexagon sides ``a, b, c`` as ints, if each is an integer >= 0 (not a bool).

    Raises
    ------
    TilingError
        A side that is not.

    Examples
    --------
    >>> hexagon_sizes(2, 0, 3)
    (2, 0, 3)
    """
    for name, value in zip("abc", (a, b, c)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 0:
            raise TilingError(f"hexagon side {name} must be an integer >= 0, got {value!r}")
    return int(a), int(b), int(c)


def as_integers(values, what) -> np.ndarray:
    """``values`` as an int64 array, if they are integers (or integral floats) below ``COORD_BOUND``.

    Parameters
    ----------
    values : array_like
    what : str
        What the values are, for the error message.

    Raises
    ------
    TilingError
        Ragged input, non-integral values, or values too large for :func:`cell_keys`.

    Examples
    --------
    >>> as_integers([[1.0, -2.0]], "periods").tolist()
    [[1, -2]]
    """
    try:
        array = np.asarray(values)
    except ValueError:
        raise TilingError(f"{what} must be a rectangular array of integers") from None
    if array.size and not (np.issubdtype(array.dtype, np.integer) or (np.issubdtype(array.dtype, np.floating)
                                                                       and np.all(array == np.round(array)))):
        raise TilingError(f"{what} must be integers, got {array.dtype} values")
    if array.size and np.abs(array).max() >= COORD_BOUND:
        raise TilingError(f"{what} must stay below {COORD_BOUND} in absolute value")
    return array.astype(np.int64)


def as_lozenges(lozenges) -> np.ndarray:
    """Rows ``(i, j, orientation)`` as a new int64 array of shape (n, 3), from rows or :class:`Lozenge` objects.

    Raises
    ------
    TilingError
        Rows of the wrong length, or an orientation other than 0, 1, 2.

    Examples
    --------
    >>> as_lozenges([Lozenge(1, 2, 0), (0, 0, 2)]).tolist()
    [[1, 2, 0], [0, 0, 2]]
    """
    if not isinstance(lozenges, np.ndarray):
        lozenges = [(z.i, z.j, z.orientation) if isinstance(z, Lozenge) else z for z in lozenges]
    array = as_integers(lozenges, "lozenges")
    if array.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise TilingError(f"lozenges must be rows (i, j, orientation) or Lozenge objects, got shape {array.shape}")
    if not np.isin(array[:, 2], (0, 1, 2)).all():
        raise TilingError(f"a lozenge's orientation must be 0, 1 or 2, got {sorted(set(array[:, 2].tolist()))}")
    return array.copy()


def as_region(region) -> np.ndarray:
    """Triangles ``(i, j, UP|DOWN)`` as an int64 array of shape (n, 3).

    Raises
    ------
    TilingError
        Non-integral entries or a kind other than ``UP`` and ``DOWN``.
    """
    array = as_integers(region, "region").reshape(-1, 3)
    if not np.isin(array[:, 2], (UP, DOWN)).all():
        raise TilingError(f"region rows are (i, j, kind) with kind {UP} (up) or {DOWN} (down)")
    return array


def as_plane_partition(partition, c) -> np.ndarray:
    """``partition`` as an int64 ``a x b`` array, if it is a plane partition with entries at most ``c``.

    Raises
    ------
    TilingError
        ``c`` not an integer >= 0, ``partition`` not a matrix of integers in ``0..c``, or an entry
        larger than the one before it along its row or column.

    Examples
    --------
    >>> as_plane_partition([[2, 1], [1, 0]], c=2).tolist()
    [[2, 1], [1, 0]]
    """
    hexagon_sizes(0, 0, c)
    pp = as_integers(partition, "a plane partition")
    if pp.ndim != 2:
        raise TilingError(f"a plane partition is an a x b matrix of integers, got an array of shape {pp.shape}")
    if pp.size and (pp.min() < 0 or pp.max() > c):
        raise TilingError(f"plane partition entries must lie in 0..c = 0..{c}, got {pp.min()}..{pp.max()}")
    for axis, where in ((0, "down its column"), (1, "along its row")):
        rises = np.argwhere(np.diff(pp, axis=axis) > 0)
        if rises.size:
            r, s = rises[0].tolist()
            after = (r + 1, s) if axis == 0 else (r, s + 1)
            raise TilingError(f"plane partition entries must be non-increasing along rows and columns, but "
                              f"{pp[r, s]} at {(r, s)} is followed by {pp[after]} {where}")
    return pp


def up_cells(lozenges: np.ndarray) -> np.ndarray:
    """The ``(i, j)`` of each lozenge's up-triangle, for rows ``(i, j, orientation)``.

    Examples
    --------
    >>> up_cells(np.array([[0, 0, 0], [0, 0, 2]])).tolist()
    [[0, 1], [1, 0]]
    """
    return lozenges[:, :2] + UP_OFFSETS[lozenges[:, 2]]


def cell_keys(cells, kinds) -> np.ndarray:
    """One int64 per (i, j, kind) (``kinds`` broadcast against the cells' leading axes), flattened.

    Distinct triangles with coordinates below ``COORD_BOUND`` get distinct keys.
    """
    cells = np.asarray(cells, dtype=np.int64)
    kinds = np.broadcast_to(kinds, cells.shape[:-1])
    return (((cells[..., 0] + COORD_BOUND) * (4 * COORD_BOUND) + (cells[..., 1] + COORD_BOUND)) * 2 + kinds).ravel()


def lookup(keys, order, wanted) -> tuple[np.ndarray, np.ndarray]:
    """Index into ``keys`` (sorted by ``order``) of each wanted key, and whether it is there.

    Examples
    --------
    >>> keys = np.array([30, 10, 20])
    >>> [x.tolist() for x in lookup(keys, np.argsort(keys), np.array([20, 25]))]
    [[2, 0], [True, False]]
    """
    if not len(keys):
        return np.zeros(len(wanted), dtype=np.int64), np.zeros(len(wanted), dtype=bool)
    idx = order[np.minimum(np.searchsorted(keys[order], wanted), len(keys) - 1)]
    return idx, keys[idx] == wanted


def gauss_reduced(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A Lagrange-Gauss reduced basis of the lattice spanned by the integer vectors ``u, v``."""
    while True:
        if u @ u > v @ v:
            u, v = v, u
        k = int(round((u @ v) / (u @ u)))
        if k == 0:
            return np.array([u, v])
        v = v - k * u
