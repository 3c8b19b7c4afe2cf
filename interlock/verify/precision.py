"""The input's precision, read where the coordinates are: one length per block, never one per scene.

A file rounds each coordinate by what its format keeps: float32 (STL, GLB,
PLY, Rhino's OBJ) by half a unit in the last place, ``2^-24 |x|``, so a block
far from the origin is as imprecise as its coordinates are large; text files
by their last printed digit, either a fixed number of decimals (``%.6f``) or of
significant digits (``%.4g``).  Geometry computed in float64 (generated
assemblies, or a transform applied to a mesh) carries a few dozen units in the
last place of its coordinates.  Noise beyond any of these shows in the faces
themselves: triangles of one planar face that are not coplanar.

:func:`block_precision` gives, per block, the rounding ``delta`` of its
coordinates (a length, in model units) and where it came from.  The contact
search (:func:`~interlock.verify.contacts.contacts`) turns it, with each face's
own size and bend, into one tolerance per contact
(docs/interlocking.md, "Tolerances that follow the contact").  Nothing here
depends on the size of the scene: a block far away changes no other block's
precision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["Precision", "coordinate_precision", "block_precision", "GRID_BITS", "DECIMAL_MIN_DIGITS",
           "DECIMAL_FULL_SHARE", "DECIMAL_MIN_VALUES", "DECIMAL_ULPS", "COMPUTED_ULPS", "PRECISION_FACTOR",
           "BEND_FACTOR"]

#: Coordinates that are all multiples of a power of two with at most this many significant bits lie on a
#: grid (voxel puzzles, generated lattices): they are exact, whatever type they were stored in.
GRID_BITS = 20
#: Text rounded to fewer significant digits than this is a designer's round values (0.25, 1.5), not rounding.
DECIMAL_MIN_DIGITS = 4
#: A decimal quantum counts as the file's rounding only if at least this share of the distinct numbers use its
#: last digit (numbers cut to that digit, not round values that happen to be multiples of it) ...
DECIMAL_FULL_SHARE = 0.5
#: ... and there are at least this many distinct nonzero numbers (a box at x = 1.001 is not a rounded file) ...
DECIMAL_MIN_VALUES = 8
#: ... each within this many units in the last place of a whole number of quanta (parsing a decimal rounds by half
#: a unit, dividing by the quantum by another).
DECIMAL_ULPS = 8
#: Float64 geometry that was computed (transforms, constructions) is taken as accurate to this many units in
#: the last place of its coordinates: a few dozen operations, each rounding by half a unit.
COMPUTED_ULPS = 64
#: Faces bent within the tolerances (their triangles not coplanar) count this many times their bend as
#: tolerance: the modelled plane is a fit, and the real faces lie up to the bend on either side of it.
BEND_FACTOR = 2.0
#: A contact's tolerance is this many times the mean rounding of its two blocks: a vertex rounded by
#: ``delta`` per coordinate moves by up to ``sqrt(3) delta``, and both faces carry their own rounding.
PRECISION_FACTOR = 4.0

_EPS64 = 2.0**-53
_EPS32 = 2.0**-24


@dataclass(frozen=True)
class Precision:
    """Per block: ``delta[b]``, the rounding of block ``b``'s coordinates (a length), and its ``source``.

    ``source[b]`` is one of "grid", "float32", "decimals 1e-06" (a fixed
    quantum), "6 significant digits", "float64" (read from a file) or
    "computed float64" (placed by a transform).  ``read[b]`` is the rounding
    the numbers alone show (for float64, one unit in the last place), before
    the allowance of :data:`COMPUTED_ULPS` for computed geometry.
    ``by_type[t]`` is the rounding of mesh ``t`` in its own coordinates.
    """

    delta: np.ndarray
    source: tuple[str, ...]
    read: np.ndarray | None = None
    by_type: np.ndarray | None = None

    def contact_tolerance(self, i: int, j: int, read: bool = True) -> float:
        """:data:`PRECISION_FACTOR` times the mean rounding of blocks ``i`` and ``j``.

        ``read=True`` (default): the rounding the numbers show (``read``), without the allowance for computed
        float64 geometry, which only widens the contact search: a face bent beyond it is bent as far as the
        input can tell, and the margin is measured against it.  ``read=False``: ``delta``.
        """
        delta = self.delta if not read or self.read is None else self.read
        return PRECISION_FACTOR * 0.5 * float(delta[i] + delta[j])

    def widened(self, tolerance: float) -> "Precision":
        """The precision of blocks whose faces the caller says are only within ``tolerance`` of the model: each
        rounding at least ``tolerance / PRECISION_FACTOR`` (so a contact's tolerance is at least ``tolerance``),
        its source "given tolerance" where that is coarser than the numbers.

        >>> Precision(np.array([1e-9, 1e-3]), ("float32", "4 significant digits")).widened(4e-6).source
        ('given tolerance', '4 significant digits')
        """
        floor = float(tolerance) / PRECISION_FACTOR
        coarser = np.asarray(self.delta, dtype=float) < floor
        read = None if self.read is None else np.maximum(self.read, floor)
        source = tuple("given tolerance" if c else s for c, s in zip(coarser, self.source))
        return replace(self, delta=np.maximum(self.delta, floor), source=source, read=read)

    def describe(self, blocks=None) -> str:
        """The sources of the given blocks (default all), most common first, e.g. ``"float32 input"``."""
        chosen = [self.source[b] for b in (range(len(self.source)) if blocks is None else blocks)]
        kinds, counts = np.unique(chosen, return_counts=True) if chosen else ([], [])
        ordered = [str(k) for _, k in sorted(zip(-np.asarray(counts), kinds))]
        return " and ".join(ordered) + " input" if ordered else "no input"


def coordinate_precision(values) -> tuple[float, str]:
    """``(delta, source)``: how finely one body's coordinates were rounded (a length), read off the numbers.

    In this order: all on a coarse dyadic grid (at most :data:`GRID_BITS`
    significant bits): "grid", ``delta = 2^-53 max|x|``; all exactly float32:
    ``delta = 2^-24 max|x|``; all cut to a decimal quantum ``q`` (at least
    :data:`DECIMAL_MIN_DIGITS` significant digits of ``max|x|``, the last digit
    mostly used, at least :data:`DECIMAL_MIN_VALUES` distinct values):
    ``delta = q / 2``; all cut to ``k >= 4`` significant digits:
    ``delta = 10^(e - k + 1) / 2`` with ``e`` the decimal exponent of
    ``max|x|``; else "float64", ``delta = 2^-53 max|x|``.  ``max|x|`` is taken
    over this body only: a body far from the origin is rounded coarsely.

    Examples
    --------
    >>> coordinate_precision([0.0625, 1.5, 2.0])[1]
    'grid'
    >>> delta, source = coordinate_precision(np.float32([1000.1, 1000.3, 999.7]).astype(float))
    >>> source, bool(delta < 1e-4)
    ('float32', True)
    >>> coordinate_precision([0.123456, 1.100003, 2.000001, 0.5, 0.654321, 0.700007, 1.234567, 0.000012])
    (5e-07, 'decimals 1e-06')
    >>> coordinate_precision([0.1235, 12.34, 0.004567, 1.111, 2.222, 3.333, 4.444, 0.5556])
    (0.005, '4 significant digits')
    >>> coordinate_precision([0.2, 0.4, 0.1])[1]  # round values are exact, not rounded
    'float64'
    >>> coordinate_precision(np.arange(1, 3, 0.0625) + 1e-12 * np.sin(np.arange(32)))[1]  # sixteenths moved by 1e-12
    'float64'
    """
    x = np.asarray(values, dtype=float).ravel()
    x = np.unique(x[np.isfinite(x)])
    top = float(np.abs(x).max(initial=0.0)) or 1.0
    mantissa = np.frexp(x)[0] * 2.0**GRID_BITS  # an integer exactly when at most GRID_BITS bits are used
    if np.all(mantissa == np.round(mantissa)):
        return top * _EPS64, "grid"
    if np.all(x.astype(np.float32).astype(float) == x):
        return top * _EPS32, "float32"
    exponent = math.floor(math.log10(top))
    nonzero = x[x != 0]
    if len(nonzero) < DECIMAL_MIN_VALUES:
        return top * _EPS64, "float64"
    found = []
    for digits in range(DECIMAL_MIN_DIGITS, 16):  # a fixed quantum 10^(e - digits + 1) for every number
        quantum = 10.0 ** (exponent - digits + 1)
        if _cut_to(x, quantum) is not None and np.mean(_cut_to(x, quantum) % 10 != 0) >= DECIMAL_FULL_SHARE:
            found.append((0.5 * quantum, f"decimals {quantum:.0e}"))
            break
    exponents = np.floor(np.log10(np.abs(nonzero)))
    for digits in range(DECIMAL_MIN_DIGITS, 16):  # k significant digits: each number its own quantum
        with np.errstate(all="ignore"):  # quanta below the smallest float64 are no rounding anyone wrote
            units = nonzero / 10.0 ** (exponents - digits + 1)
        if (np.all(np.isfinite(units)) and _whole(units)
                and np.mean(np.round(units) % 10 != 0) >= DECIMAL_FULL_SHARE):
            found.append((0.5 * 10.0 ** (exponent - digits + 1), f"{digits} significant digits"))
            break
    if found:  # %.6g numbers below 10 are also multiples of 1e-5: the largest ones were cut coarser
        return max(found)
    return top * _EPS64, "float64"


def block_precision(assembly) -> Precision:
    """The rounding of each block's coordinates (:class:`Precision`), read off the meshes and their placement.

    A block whose transform is the identity (a file's blocks) has the
    :func:`coordinate_precision` of its mesh.  A block placed by another
    transform was computed: :data:`COMPUTED_ULPS` units in the last place of
    its largest world coordinate, or its mesh's own rounding if coarser.

    Examples
    --------
    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> near = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    >>> far = trimesh.creation.box(bounds=[[1e5, 0, 0], [1e5 + 1, 1, 1]])
    >>> p = block_precision(Assembly.from_meshes([near, far]))
    >>> p.source, bool(p.delta[0] < 1e-15)
    (('grid', 'grid'), True)
    """
    per_type = [coordinate_precision(mesh.vertices) for mesh in assembly.meshes]
    delta = np.array([per_type[t][0] for t in assembly.types], dtype=float)
    source = [per_type[t][1] for t in assembly.types]
    read = delta.copy()
    # placed by a transform, or read as float64 from a file: computed geometry, a few dozen units in the last place
    placed = ~np.all(np.isclose(assembly.transforms, np.eye(4), rtol=0.0, atol=0.0), axis=(1, 2))
    placed |= np.array([s == "float64" for s in source])
    if placed.any():
        bounds = assembly.bounds[placed]
        largest = np.abs(bounds).max(axis=(1, 2))
        computed = COMPUTED_ULPS * _EPS64 * largest
        delta[placed] = np.maximum(delta[placed], computed)
        read[placed] = np.maximum(read[placed], _EPS64 * largest)
        for b in np.flatnonzero(placed):
            if source[b] in ("grid", "float64"):
                source[b] = "computed float64"
    return Precision(delta, tuple(source), read, np.array([d for d, _ in per_type], dtype=float))


def _cut_to(x: np.ndarray, quantum: float):
    """The numbers as integer multiples of ``quantum`` if they all are (within float64 noise), else None."""
    with np.errstate(all="ignore"):
        units = x / quantum
    rounded = np.round(units)
    if (np.all(np.isfinite(units)) and _whole(units)
            and np.abs(rounded).max(initial=0.0) < 2.0**52):
        return rounded
    return None


def _whole(units: np.ndarray) -> bool:
    """Whether numbers divided by a quantum are whole numbers up to the rounding of parsing and dividing: a few units
    in the last place of each (a grid model with noise of 1e-12 is not cut to 1e-4, though 0.0625 is 625 of them)."""
    return bool(np.all(np.abs(units - np.round(units)) <= DECIMAL_ULPS * _EPS64 * np.maximum(np.abs(units), 1.0)))
