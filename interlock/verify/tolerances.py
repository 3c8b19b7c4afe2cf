"""How far each contact may be from the input's faces: the tolerances a verdict of :func:`~interlock.verify.check`
uses, read off each contact and its blocks, never off the scene (docs/interlocking.md, "Tolerances that follow the
contact")."""

from __future__ import annotations

import math

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.verify.contacts import NOISE_CONTACTS, NOISE_SHARE, NOISE_SPREAD, block_noise
from interlock.verify.matrix import InterlockingMatrix
from interlock.verify.precision import PRECISION_FACTOR, Precision

__all__ = ["contact_tolerances", "block_depths", "block_noise", "coarseness", "too_coarse", "tolerance_source",
           "coarsest", "COARSE_RATIO", "UNDECIDABLE_RATIO", "NOISE_CONTACTS", "NOISE_SHARE", "NOISE_SPREAD"]

#: An input whose tolerance reaches this share of a contact's or a block's size is coarse: its first-order answers
#: stand only where something beyond first order confirms them (a margin above 1, a finite motion shown); the
#: 4-digit bunny's faces are bent by 0.0036 on contacts 0.06 across.
COARSE_RATIO = 0.01
#: An input whose rounding (times the precision factor) reaches this share of a free block's size (or of a
#: neighbour's) is not checked at all: rounding that coarse moves faces apart and lets blocks out that the design
#: holds (the GeoCombSurfX patches written with 4 digits at coordinates up to 150, 3 % of a block: block 0 comes
#: out of the file, not of the design), and float32 coordinates 1e6 model sizes from the origin leave no contact.
UNDECIDABLE_RATIO = 0.02


def coarseness(assembly: Assembly, frame, precision: Precision) -> tuple[float, int | None]:
    """``(ratio, block)``: the largest rounding (times :data:`~interlock.verify.precision.PRECISION_FACTOR`) of a
    free block, or of a neighbour of one, against its size, and that block (``(0.0, None)`` without free blocks)."""
    fixed = set(assembly.block_indices(assembly.frame if frame is None else frame))
    free = [b for b in range(len(assembly)) if b not in fixed]
    graph = assembly.neighbours
    near = sorted(set(free).union(*(graph[b] for b in free)))
    if not near:
        return 0.0, None
    near = np.asarray(near)
    ratio = PRECISION_FACTOR * precision.delta[near] / assembly.block_sizes[near]
    return float(ratio.max()), int(near[np.argmax(ratio)])


def too_coarse(assembly: Assembly, frame, precision: Precision, ratio: float = UNDECIDABLE_RATIO) -> str | None:
    """Why the input is too coarse to decide, or None: a free block, or a neighbour of one, whose coordinates'
    rounding (times :data:`~interlock.verify.precision.PRECISION_FACTOR`) reaches ``ratio`` of its size
    (:func:`coarseness`).

    Float32 coordinates 1e6 model sizes from the origin round a unit cube's corners by 0.06: no contact survives,
    and any verdict would be about geometry the file does not hold.
    """
    largest, worst = coarseness(assembly, frame, precision)
    if worst is None or largest < ratio:
        return None
    remedy = ("move the model near the origin or store it in float64" if "float" in precision.source[worst]
              else "write its coordinates with more digits")
    return (f"the file's precision {PRECISION_FACTOR * precision.delta[worst]:.2g} "
            f"({precision.source[worst]} at coordinates up to {np.abs(assembly.bounds[worst]).max():.3g}) is coarser "
            f"than its blocks: block {worst} is {assembly.block_sizes[worst]:.3g} across; {remedy}")


def contact_tolerances(found, precision: Precision, tolerance=None, bends: bool = True) -> np.ndarray:
    """One length per contact: how far the real faces may be from the modelled contact.

    ``tolerance`` given: that length for every contact.  Otherwise each
    contact's own :attr:`~interlock.verify.contacts.Contact.tolerance` (the
    rounding of its two blocks, plus twice the bend of faces bent within the
    tolerances), or, for contacts given by hand, the rounding of its blocks
    (:meth:`~interlock.verify.precision.Precision.contact_tolerance`); and at
    least :data:`NOISE_SPREAD` times the sum of its blocks' noise
    (:func:`block_noise`: a noisy mesh shows its noise only on faces of
    several triangles).
    ``bends=False``: the rounding alone (what the numbers show, without the allowance for computed geometry:
    :meth:`~interlock.verify.precision.Precision.contact_tolerance`).
    """
    if tolerance is not None:
        return np.full(len(found), float(tolerance))
    rounding = np.array([precision.contact_tolerance(c.i, c.j) for c in found], dtype=float)
    if len(found):  # vertex noise of either block moves the contact: the sum of the blocks' noise, and its spread
        noise = NOISE_SPREAD * block_noise(found)
        rounding = np.maximum(rounding, np.array([noise[c.i] + noise[c.j] for c in found]))
    if not bends:
        return rounding
    own = np.array([np.nan if c.tolerance is None else c.tolerance for c in found], dtype=float)
    return np.where(np.isnan(own), rounding, np.maximum(own, rounding))


def block_depths(found, precision: Precision, blocks: int, tolerance=None) -> np.ndarray:
    """Per block, how far its faces may lie from where the input puts them: half of what a contact of two such
    blocks is allowed without bends (:func:`contact_tolerances` with ``bends=False``), so that two blocks together
    may reach that far into each other.

    The rounding its numbers show (:data:`~interlock.verify.precision.PRECISION_FACTOR` times ``precision.read``)
    plus :data:`NOISE_SPREAD` times its vertex noise (:func:`block_noise`); half of ``tolerance`` when one is given.
    Never a face's bend: a designed fold blocks a slide for real, however small.

    Examples
    --------
    >>> from types import SimpleNamespace as Found
    >>> rounding = np.array([1e-7, 1e-7, 0.0])
    >>> rounded = Precision(rounding, ("float32", "float32", "grid"), read=rounding)
    >>> block_depths([Found(i=0, j=1, deviation=0.0)], rounded, 3).tolist()
    [2e-07, 2e-07, 0.0]
    """
    if tolerance is not None:
        return np.full(blocks, 0.5 * float(tolerance))
    delta = precision.delta if precision.read is None else precision.read
    depths = 0.5 * PRECISION_FACTOR * np.asarray(delta, dtype=float)[:blocks].copy()
    if len(found):
        noise = block_noise(found)
        depths[:len(noise)] += NOISE_SPREAD * noise[:blocks]
    return depths


def tolerance_source(found, A: InterlockingMatrix, precision: Precision) -> str:
    """Where the tolerances of the contacts of free blocks came from, in words ("float32 input; faces bent ...")."""
    free = set(A.free.tolist())
    moving = [c for c in found if c.i in free or c.j in free]
    source = precision.describe(sorted({b for c in moving for b in (c.i, c.j)}))
    bends = [c.deviation for c in moving if not c.planar and c.deviation > precision.contact_tolerance(c.i, c.j)]
    return source + (f"; faces bent by up to {max(bends):.2g}" if bends else "")


def coarsest(found, A: InterlockingMatrix, limits: np.ndarray):
    """``(tolerance, size)`` of the contact of a free block whose tolerance is largest against its size (the square
    root of its area), or None when no contact has an area."""
    free = set(A.free.tolist())
    ratios = [(t / math.sqrt(c.area), t, math.sqrt(c.area)) for c, t in zip(found, limits)
              if (c.i in free or c.j in free) and c.area > 0]
    return max(ratios)[1:] if ratios else None

