"""How far a verdict holds beyond the exact input: the input's precision, per-row tolerances and the margin.

A mesh file rounds its coordinates (float32 in every STL), so a face that is
planar in the designer's model arrives bent by about one unit in the last
place.  First order then sees blocking rows that no physical part has: a block
that slides out of the model may be "interlocked" in the file.  This module
makes the verdict carry that uncertainty (``docs/interlocking.md``, "Margin
and tolerance"):

- :func:`input_precision` reads the rounding of the coordinates off the data;
- :func:`row_tolerances` turns a length tolerance ``t`` into a bound
  ``eps_r`` on the change of each row of the interlocking matrix ``A``: a
  contact vertex moved by ``t`` moves the row by ``t / L``, a facet of size
  ``h`` tilted by ``t / h`` turns the normal part by that angle, so
  ``eps_r = (t / L) (1 + 2 L / h_r)`` (``L`` the length scale of ``A``);
- the *margin* ``rho = min over unit motions x of max_r (-(A x)_r / eps_r)``
  says how far, in tolerances, every unit motion (fastest block moving by one
  length scale) must push some contact vertex into its neighbour.  ``rho > 1``:
  every polyhedral assembly within the tolerance is interlocked to first order.
  ``rho <= 1``: some motion keeps every contact within the tolerance, and the
  verdict is "not interlocked within tolerance".

:func:`margin_lower_bound` proves a lower bound on ``rho`` from a positive
self-stress; :func:`tolerant_motion` finds a motion within the tolerance, an
upper bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize
import scipy.sparse as sp
import scipy.sparse.linalg

from interlock.files import json_float

__all__ = ["Margin", "assess", "rounding_tolerance", "input_precision", "row_tolerances", "margin_lower_bound",
           "tolerant_motion",
           "GRID_BITS", "DECIMAL_MIN_RTOL", "DECIMAL_MAX_RTOL", "DECIMAL_FULL_SHARE", "PRECISION_FACTOR",
           "MARGIN_CHUNK", "EXACT_RTOL", "TOLERANT_SHARE", "BEND_FACTOR"]

#: Coordinates that are all multiples of a power of two with at most this many significant bits lie on a
#: grid (voxel puzzles, generated lattices): they are taken as exact, whatever type they were stored in.
GRID_BITS = 20
#: Text formats round to decimals: coordinates that are all multiples of a power of ten ``q`` with
#: ``DECIMAL_MIN_RTOL <= q / max |x| <= DECIMAL_MAX_RTOL`` (at least four significant digits), whose last digit
#: is used by at least ``DECIMAL_FULL_SHARE`` of them (numbers cut to that digit, not a designer's round
#: values), are taken as rounded to ``q / 2``.  Coarser round values (0.25, 1.5) are exact, not rounding.
DECIMAL_MIN_RTOL = 1e-12
DECIMAL_MAX_RTOL = 1e-4
DECIMAL_FULL_SHARE = 0.5
#: The tolerance is this many times the rounding (a vertex moved by ``delta`` per coordinate moves by up to
#: ``sqrt(3) delta``; two faces in contact each carry their own rounding).
PRECISION_FACTOR = 4.0
#: Faces measurably bent (contact deviation from its plane) count this many times their bend as tolerance.
BEND_FACTOR = 2.0
#: Columns of ``(A^T A)^{-1}`` formed at a time by :func:`margin_lower_bound` (memory: rows x this).
MARGIN_CHUNK = 256
#: :func:`tolerant_motion` relaxes each row by this share of its tolerance.
TOLERANT_SHARE = 0.99
#: A tolerance at most this times the model size is far below the rank and LP tolerances of
#: :func:`~interlock.verify.check.check` (1e-6, 1e-7): the margin is not computed and the float verdict stands.
EXACT_RTOL = 1e-12


@dataclass(frozen=True)
class Margin:
    """Bounds on the margin ``rho`` of :mod:`interlock.verify.margin` (in tolerances) and what they rest on.

    ``lower`` is proved (from a positive stress and the smallest singular
    value); ``upper`` is attained by ``motion`` (a column vector of ``A``), or
    ``inf`` when no motion was tried.  ``tolerance`` is the length tolerance
    (model units) and ``source`` where it came from ("float32 input",
    "decimals input", "float64 input", "grid input", "faces bent by up to ..."
    or "given").
    """

    lower: float
    upper: float
    tolerance: float
    source: str
    motion: np.ndarray | None = None

    def __str__(self) -> str:
        upper = "" if math.isinf(self.upper) else f", at most {self.upper:.3g}"
        return (f"margin at least {self.lower:.3g}{upper} times the tolerance {self.tolerance:.3g} "
                f"({self.source})")

    def to_dict(self) -> dict:
        return {"lower": json_float(self.lower), "upper": json_float(self.upper), "tolerance": self.tolerance,
                "source": self.source}


def input_precision(vertices) -> tuple[float, str]:
    """``(delta, source)``: how finely the coordinates were rounded (a length), read off the numbers.

    In this order: all coordinates on a coarse dyadic grid (at most
    :data:`GRID_BITS` significant bits, e.g. multiples of 1/16): exact
    ("grid", ``delta`` the float64 rounding of the largest); all exactly
    float32 numbers: ``delta = 2^-24 max |x|`` ("float32", what STL files
    hold); all decimals cut to a quantum ``q`` of at least four significant
    digits (:data:`DECIMAL_MAX_RTOL`, the last digit mostly used):
    ``delta = q / 2`` ("decimals"); else ``delta = 2^-53 max |x|`` ("float64").

    Examples
    --------
    >>> import numpy as np
    >>> input_precision(np.array([[0.0625, 1.5, 2.0]]))[1]
    'grid'
    >>> delta, source = input_precision(np.float32(np.random.default_rng(0).random((9, 3))).astype(float))
    >>> source, delta < 6e-8
    ('float32', True)
    >>> input_precision(np.array([[0.123456, 1.100003, 2.000001]]))
    (5e-07, 'decimals')
    >>> input_precision(np.array([[0.2, 0.4, 0.1]]))[1]  # round values are exact, not rounded
    'float64'
    """
    x = np.asarray(vertices, dtype=float).ravel()
    x = x[np.isfinite(x)]
    top = float(np.abs(x).max(initial=0.0)) or 1.0
    mantissa = np.frexp(x)[0] * 2.0**GRID_BITS  # an integer exactly when at most GRID_BITS bits are used
    if np.all(mantissa == np.round(mantissa)):
        return top * 2.0**-53, "grid"
    if np.all(x.astype(np.float32).astype(float) == x):
        return top * 2.0**-24, "float32"
    for digits in range(-15, 31):  # the coarsest decimal quantum 10^-digits that the numbers are cut to
        quantum = 10.0**-digits
        if not DECIMAL_MIN_RTOL <= quantum / top <= DECIMAL_MAX_RTOL:
            continue
        units = np.round(x / quantum)
        if np.all(np.abs(x / quantum - units) <= 1e-4) and np.mean(units % 10 != 0) >= DECIMAL_FULL_SHARE:
            return 0.5 * quantum, "decimals"
    return top * 2.0**-53, "float64"


def row_tolerances(matrix, contacts, tolerance) -> np.ndarray:
    """``eps_r = (t / L) (1 + 2 L / h_r)`` per row of an :class:`~interlock.verify.matrix.InterlockingMatrix`.

    ``h_r`` is the square root of the area of the row's contact polygon (for a
    point or line contact, the model size): the facet that carries the
    normal is at least that large, so rounding by ``t`` tilts it by at most
    about ``t / h_r``.  ``tolerance`` is one length ``t``, or one per contact.
    """
    L = matrix.length_scale
    areas = np.array([c.area for c in contacts], dtype=float)
    sizes = np.where(areas > 0, np.sqrt(np.maximum(areas, 0.0)), L)
    t = np.asarray(tolerance, dtype=float)
    t = t[matrix.row_contact] if t.ndim else t
    return (t / L) * (1.0 + 2.0 * L / sizes[matrix.row_contact])


def margin_lower_bound(A: sp.csr_matrix, eps: np.ndarray, stress, chunk: int = MARGIN_CHUNK) -> float:
    """A lower bound on the margin ``rho`` from a positive stress ``w`` (``A^T w = 0``, ``w > 0``), by LP duality.

    ``rho > 1`` iff the polytope ``P = {x : A x >= -eps}`` lies inside the
    open unit box.  For each coordinate ``j`` and sign, any ``u >= 0`` with
    ``A^T u = -+e_j`` bounds ``+-x_j <= eps . u`` on ``P`` (weak duality).
    Take ``u0 = -+A (A^T A)^{-1} e_j`` and add the stress until it is
    nonnegative: ``u = u0 + tau w`` with ``tau = max(0, max_r -u0_r / w_r)``.
    Then every ``x`` in ``P`` has ``||x||_inf <= B = max_j (eps . u)``, and
    ``rho >= 1 / B``.  Needs full column rank; the inverse is one sparse LU,
    applied to ``chunk`` coordinates at a time.
    """
    w = np.asarray(stress, dtype=float)
    n = A.shape[1]
    gram = (A.T @ A).tocsc()
    lu = scipy.sparse.linalg.splu(gram)
    weighted = float(eps @ w)
    largest = 0.0
    for start in range(0, n, chunk):
        columns = np.arange(start, min(start + chunk, n))
        unit = np.zeros((n, len(columns)))
        unit[columns, np.arange(len(columns))] = 1.0
        u0 = -(A @ lu.solve(unit))
        for u in (u0, -u0):
            tau = np.maximum(0.0, (-u / w[:, None]).max(axis=0))
            largest = max(largest, float((eps @ u + tau * weighted).max(initial=0.0)))
    return math.inf if largest <= 0 else 1.0 / largest


def tolerant_motion(A: sp.csr_matrix, eps: np.ndarray, tol: float = 1e-9):
    """The motion LP with every row relaxed by its tolerance: ``max 1^T A x``, ``A x >= -eps``, ``|x| <= 1``.

    Returns ``(x, rho)`` where ``rho = max_r(-(A x)_r / eps_r) / ||x||_inf``
    (at most 1 when ``x`` reaches the box: a unit motion that keeps every
    contact within its tolerance), or ``(None, inf)`` when the LP fails.
    """
    objective = -np.asarray(A.sum(axis=0)).ravel()
    # rows relaxed by a little less than eps, so that HiGHS' feasibility tolerance cannot push a row past it
    result = scipy.optimize.linprog(objective, A_ub=-A, b_ub=TOLERANT_SHARE * eps, bounds=(-1.0, 1.0), method="highs",
                                    options={"primal_feasibility_tolerance": tol})
    if result.status != 0:
        return None, math.inf
    x = result.x
    size = float(np.abs(x).max(initial=0.0))
    if size == 0:
        return None, math.inf
    y = A @ x
    return x, float(max(0.0, float((-y / eps).max(initial=0.0))) / size)


def rounding_tolerance(assembly) -> tuple[float, str]:
    """``(t, source)``: :data:`PRECISION_FACTOR` times the :func:`input_precision` of the blocks' coordinates.

    Blocks placed by non-identity transforms (generated assemblies) count as
    float64: their placement was computed, not read from a file.
    """
    if not np.allclose(assembly.transforms, np.eye(4), rtol=0.0, atol=0.0):
        return PRECISION_FACTOR * assembly.scale * 2.0**-53, "float64 input"
    delta, source = input_precision(np.vstack([m.vertices for m in assembly.meshes]))
    return PRECISION_FACTOR * delta, f"{source} input"


def assess(matrix, contacts, scale: float, stress, tolerance: float, source: str) -> Margin:
    """The margin of an "interlocked" float verdict against the tolerance ``tolerance`` of its input.

    ``tolerance`` (a length) and its ``source`` are the caller's: the given
    one, or :func:`rounding_tolerance`; then :data:`BEND_FACTOR` times the
    largest :attr:`~interlock.blocks.contact.Contact.deviation` of a contact
    from its plane is used where that is larger (noisy or re-meshed input).
    Below :data:`EXACT_RTOL` of the model size ``scale`` nothing is computed
    (``lower = inf``).  Otherwise the lower bound of
    :func:`margin_lower_bound` and, when it does not exceed 1, the motion of
    :func:`tolerant_motion`.
    """
    if source != "given":
        bent = max((c.deviation for c in contacts), default=0.0)
        if BEND_FACTOR * bent > tolerance:  # the faces are measurably less exact than their rounding
            tolerance, source = BEND_FACTOR * bent, f"faces bent by up to {bent:.2g}"
    if tolerance <= EXACT_RTOL * scale or stress is None:
        return Margin(math.inf, math.inf, float(tolerance), source)
    eps = row_tolerances(matrix, contacts, tolerance)
    lower = margin_lower_bound(matrix.matrix, eps, stress)
    if lower > 1.0:
        return Margin(lower, math.inf, float(tolerance), source)
    motion, upper = tolerant_motion(matrix.matrix, eps)
    return Margin(lower, upper, float(tolerance), source, motion)
