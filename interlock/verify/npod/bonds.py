"""Bond checks for n-pods (seed 003, Cor. 3.17): collinearity/butterfly conditions and projection bonds.

The n-pod itself (:func:`~interlock.verify.npod.npod`), its mobility and self-motions are in
:mod:`interlock.verify.npod`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from interlock.verify.npod.mobility import NPod

__all__ = ["BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds",
           "COLLINEAR_RTOL", "BOND_TOL", "DEGENERATE_TOL", "SIMILARITY_TOL", "SEARCH_SAMPLES", "SEARCH_STARTS",
           "REFINE_EVALUATIONS"]

#: Float anchors are collinear when each lies within ``COLLINEAR_RTOL * scale`` of one line.
COLLINEAR_RTOL = 1e-9
#: A projection bond is accepted when the smallest singular value of its (row-normalised) Möbius system is below this.
BOND_TOL = 1e-9
#: ... and its map is not degenerate: ``|alpha delta - beta gamma|`` of the unit coefficient vector exceeds this.
DEGENERATE_TOL = 1e-6
#: A Möbius map with ``|gamma| <= SIMILARITY_TOL`` (unit coefficients, normalised points) is a similarity.
SIMILARITY_TOL = 1e-7
#: Directions per hemisphere sampled for (L, R) by :func:`projection_bonds` (R over the sphere: twice as many).
SEARCH_SAMPLES = 60
#: The best this many samples are refined by least squares.
SEARCH_STARTS = 24
#: Function evaluations per least-squares refinement of a start.
REFINE_EVALUATIONS = 60


@dataclass(frozen=True)
class BondConditions:
    """The collinearity and butterfly conditions of Cor. 3.17 (ii) (bonds of Cor. 3.16 and Cor. 3.14).

    ``platform_collinear``: all ``p_i`` on one line; ``base_collinear``: all ``P_i`` on one line (Cor. 3.16).
    ``butterflies``: leg splits ``(S, T)`` (0-based leg indices) with ``p_S`` collinear and ``P_T`` collinear,
    both non-empty, ``T`` all legs whose base point lies on its line (Cor. 3.14); listed only when neither
    collinearity case holds (which implies such splits trivially).  ``exact``: decided in rational arithmetic;
    otherwise with ``collinear_rtol`` (``method`` says which).
    """

    platform_collinear: bool
    base_collinear: bool
    butterflies: tuple
    exact: bool
    method: str
    tolerances: dict = field(default_factory=dict)

    @property
    def cases(self) -> tuple[str, ...]:
        """The conditions that hold: "platform collinear", "base collinear", "butterfly"."""
        return tuple(name for name, holds in (("platform collinear", self.platform_collinear),
                                              ("base collinear", self.base_collinear),
                                              ("butterfly", bool(self.butterflies))) if holds)

    def __str__(self) -> str:
        if not self.cases:
            return f"no collinearity or butterfly condition ({self.method})"
        splits = "; ".join(f"platform {list(s)} / base {list(t)}" for s, t in self.butterflies)
        return f"{', '.join(self.cases)}{': ' + splits if splits else ''} ({self.method})"

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {"cases": list(self.cases), "platform_collinear": self.platform_collinear,
                "base_collinear": self.base_collinear,
                "butterflies": [[list(s), list(t)] for s, t in self.butterflies],
                "exact": self.exact, "method": self.method, "tolerances": dict(self.tolerances)}


def bond_conditions(pod: NPod, *, collinear_rtol: float = COLLINEAR_RTOL) -> BondConditions:
    """Check the pose-independent conditions (ii) of Cor. 3.17: collinear anchors and butterflies.

    By Cor. 3.16 the pod has a collinearity bond iff all platform points or all base points are collinear; by
    Cor. 3.14 a butterfly bond iff, up to a permutation of the legs, ``p_1..p_m`` are collinear and
    ``P_{m+1}..P_n`` are collinear.  If the pod is mobile, (ii) or the projection condition (i)
    (:func:`projection_bonds`) holds (Cor. 3.17); neither is sufficient.

    Exact data are decided exactly (cross products of Fractions vanish); float data with points within
    ``collinear_rtol * scale`` of a line (``scale`` the largest distance of the set's points from their centroid).

    Notes
    -----
    Butterfly splits come from the lines through two distinct base points: ``T`` = legs whose base point is on
    the line, ``S`` = the rest, kept if ``p_S`` is collinear.  Every split with ``|T| >= 2`` distinct base points
    is contained in one of these (collinearity passes to subsets), and a ``T`` of coincident points is contained
    in one unless all base points coincide (then the base is collinear).  ``O(n^3)`` collinearity tests.

    Examples
    --------
    >>> from interlock.verify.npod import npod
    >>> I = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> pod = npod([(0, 2, -1), (1, -2, -1), (-1, 0, -2), (-2, 0, 0), (1, 0, 0), (3, 0, 0)],
    ...            [(-1, 0, 0), (0, 0, 0), (1, 0, 0), (0, 1, 1), (1, -1, 2), (-1, 2, 0)], pose=(I, [0, 0, 0]))
    >>> bond_conditions(pod).butterflies
    (((0, 1, 2), (3, 4, 5)),)
    """
    tol = None if pod.exact else collinear_rtol
    platform_scale, base_scale = _spread(pod.platform), _spread(pod.base)
    platform_collinear = _collinear(pod.platform, range(len(pod)), tol, platform_scale)
    base_collinear = _collinear(pod.base, range(len(pod)), tol, base_scale)
    splits = []
    if not (platform_collinear or base_collinear):
        seen = set()
        for i in range(len(pod)):
            for j in range(i + 1, len(pod)):
                if _same_point(pod.base[i], pod.base[j], tol, base_scale):
                    continue
                T = tuple(k for k in range(len(pod)) if _collinear(pod.base, (i, j, k), tol, base_scale))
                S = tuple(k for k in range(len(pod)) if k not in T)
                if T not in seen and S and _collinear(pod.platform, S, tol, platform_scale):
                    splits.append((S, T))
                seen.add(T)
    method = "exact (rational arithmetic)" if pod.exact else f"floating point, collinear_rtol {collinear_rtol:g}"
    return BondConditions(platform_collinear, base_collinear, tuple(sorted(splits)), pod.exact, method,
                          {} if pod.exact else {"collinear_rtol": collinear_rtol})


@dataclass(frozen=True, eq=False)
class ProjectionBond:
    """A pair ``(L, R)`` of Cor. 3.12: ``pi_R(P_i) = kappa(pi_L(p_i))`` for a Möbius map ``kappa``.

    ``kind`` is "inversion" (``gamma != 0``) or "similarity" (``gamma = 0``) of
    ``kappa(q) = (alpha q + beta) / (gamma q + delta)`` in the complex coordinates of :func:`projection_bonds`
    (``coefficients``, for the centred, RMS-scaled projections); ``residual`` the smallest singular value of the
    row-normalised system.
    """

    kind: str
    left: np.ndarray
    right: np.ndarray
    coefficients: tuple
    residual: float

    def to_dict(self) -> dict:
        return {"kind": self.kind, "left": self.left.tolist(), "right": self.right.tolist(),
                "coefficients": [[c.real, c.imag] for c in self.coefficients], "residual": self.residual}


@dataclass(frozen=True, eq=False)
class BondSearch:
    """The answer of :func:`projection_bonds`: numerical evidence for condition (i) of Cor. 3.17."""

    bonds: tuple
    samples: int
    starts: int
    tolerances: dict = field(default_factory=dict)
    searched: bool = True

    @property
    def found(self) -> bool | None:
        """True if a pair was found, False if none was, None if not searched (``n <= 3``)."""
        return bool(self.bonds) if self.searched else None

    def __str__(self) -> str:
        if not self.searched:
            return ("not searched: with n <= 3 legs a Möbius map takes any three projections to any three, "
                    "so generic (L, R) satisfy Cor. 3.12")
        if not self.bonds:
            return (f"no inversion/similarity projection pair found ({self.samples} sampled pairs, {self.starts} "
                    "refined; numerical search, not a proof of absence)")
        kinds = ", ".join(sorted({b.kind for b in self.bonds}))
        worst = max(b.residual for b in self.bonds)
        return f"{len(self.bonds)} projection pair(s) (L, R) found: {kinds} (residual <= {worst:.1e}, numerical)"

    def to_dict(self) -> dict:
        return {"found": self.found, "searched": self.searched, "bonds": [b.to_dict() for b in self.bonds],
                "samples": self.samples, "starts": self.starts, "tolerances": dict(self.tolerances)}


def projection_bonds(pod: NPod, *, samples: int = SEARCH_SAMPLES, starts: int = SEARCH_STARTS,
                     bond_tol: float = BOND_TOL, degenerate_tol: float = DEGENERATE_TOL,
                     similarity_tol: float = SIMILARITY_TOL) -> BondSearch:
    """Search numerically for inversion/similarity bonds: condition (i) of Cor. 3.17 (Thm. 3.10, Cor. 3.12).

    By Cor. 3.12 the pod has an inversion/similarity bond with left and right vectors ``L, R`` in ``S^2`` iff
    the orthogonal projections ``q_i = pi_L(p_i)`` and ``Q_i = pi_R(P_i)`` differ by an inversion or a
    similarity; Thm. 3.10's normal forms are ``q Q = r / 2`` and ``Q = -gamma q`` (``q = a + i b``), so in
    general ``Q_i = (alpha q_i + beta) / (gamma q_i + delta)`` with ``alpha delta - beta gamma != 0``, an
    inversion when ``gamma != 0`` and a similarity when ``gamma = 0``.  Here ``pi_e(p) = p.e1 + i p.e2`` with
    ``(e1, e2, e)`` a positive orthonormal frame, the same rule for ``L`` and ``R``; ``pi_{-e}`` is the
    conjugate, so an anti-holomorphic map (a reflection in a circle) appears with ``-R``, and ``(L, R)`` and
    ``(-L, -R)`` give conjugate conditions: one of the two is listed, with ``L`` in the upper hemisphere.

    The condition is that the complex ``n x 4`` matrix with rows ``(q_i Q_i, Q_i, -q_i, -1)`` has a kernel
    vector ``(alpha, beta, gamma, delta)`` with non-zero determinant.  The search samples ``L`` on a hemisphere
    and ``R`` on the sphere (Fibonacci points), takes the ``starts`` pairs of smallest singular value (at most
    one per neighbourhood of about two sample spacings), refines each by Levenberg–Marquardt in ``(L, R, kernel vector)`` and keeps those with residual at most ``bond_tol``
    and ``|alpha delta - beta gamma| > degenerate_tol`` (degenerate kernels are the collinear/butterfly cases,
    :func:`bond_conditions`).  Points are centred and RMS-scaled in each plane first (Möbius maps contain the
    similarities), so the result is invariant under rigid motions and scaling.

    With ``n <= 3`` legs generic pairs qualify and nothing is searched (``found`` is None).

    Not covered: this is a local multi-start search, so "none found" is evidence, not a proof that no ``(L, R)``
    exists, and the bonds found need not be all of them; bonds are not certified exactly; positive-dimensional families of pairs (``n <= 4``, or Thm. 3.19 (a)
    for mobility >= 2) are returned as the sample of points the search converged to, not described; whether
    a found bond comes from a real self-motion is not decided (condition (i) is necessary, not sufficient:
    :func:`~interlock.verify.npod.self_motion` tests a pose).

    Examples
    --------
    >>> from fractions import Fraction as F
    >>> from interlock.verify.npod import npod
    >>> p = [(2, 0, 0), (0, 1, 1), (1, 1, 0), (-1, 2, 1), (3, -1, 2), (-2, -2, -1)]
    >>> P = [(F(1, 2), 0, 0), (0, 1, 1), (F(1, 2), F(1, 2), 0), (F(-1, 5), F(2, 5), 1),
    ...      (F(3, 10), F(-1, 10), 2), (F(-1, 4), F(-1, 4), -1)]
    >>> search = projection_bonds(npod(P, p, pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2])))
    >>> [(b.kind, (b.left.round(6) + 0.0).tolist(), (b.right.round(6) + 0.0).tolist()) for b in search.bonds]
    [('inversion', [0.0, 0.0, 1.0], [0.0, 0.0, -1.0])]
    """
    tolerances = {"bond_tol": bond_tol, "degenerate_tol": degenerate_tol, "similarity_tol": similarity_tol}
    if len(pod) <= 3:
        return BondSearch((), 0, 0, tolerances, searched=False)
    p, P = np.array(pod.platform, dtype=float), np.array(pod.base, dtype=float)
    lefts, rights = _fibonacci(samples, hemisphere=True), _fibonacci(2 * samples, hemisphere=False)
    q = _normalised_projection(p, lefts)                 # (a, n)
    Q = _normalised_projection(P, rights)                # (b, n)
    systems = _mobius_rows(q[:, None, :], Q[None, :, :])  # (a, b, n, 4)
    smallest = np.linalg.svd(systems, compute_uv=False)[..., -1]
    spacing = 2.0 * math.sqrt(2 * math.pi / len(lefts))  # about two sample spacings on the sphere
    chosen = []
    for index in np.argsort(smallest, axis=None)[:50 * starts]:  # best samples, at most one per neighbourhood
        a, b = np.unravel_index(index, smallest.shape)
        if not any(np.linalg.norm(lefts[a] - lefts[c]) < spacing and np.linalg.norm(rights[b] - rights[d]) < spacing
                   for c, d in chosen):
            chosen.append((a, b))
        if len(chosen) == starts:
            break
    found = []
    for a, b in chosen:
        bond = _refine_bond(p, P, lefts[a], rights[b], bond_tol, degenerate_tol, similarity_tol)
        if bond is not None and not any(_same_pair(bond, other) for other in found):
            found.append(bond)
    found.sort(key=lambda b: (b.kind, b.residual))
    return BondSearch(tuple(found), len(lefts) * len(rights), len(chosen), tolerances)


# --- private helpers -------------------------------------------------------------------------------------------


def _fibonacci(count: int, hemisphere: bool) -> np.ndarray:
    """``count`` nearly uniform unit vectors on the sphere, or on the hemisphere ``z >= 0``."""
    k = np.arange(count) + 0.5
    z = 1 - k / count if hemisphere else 1 - 2 * k / count
    phi = k * math.pi * (3 - math.sqrt(5))
    r = np.sqrt(1 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _frame_of(e):
    """``(e1, e2)`` with ``(e1, e2, e)`` a positive orthonormal frame, e of shape (..., 3)."""
    helper = np.where(np.abs(e[..., :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    e1 = np.cross(helper, e)
    e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    return e1, np.cross(e, e1)


def _normalised_projection(points, directions) -> np.ndarray:
    """``pi_e(points)`` as complex numbers, centred and scaled to RMS 1 (all zero if they coincide): (m, n)."""
    e1, e2 = _frame_of(directions)
    q = points @ e1.T + 1j * (points @ e2.T)  # (n, m)
    q = (q - q.mean(axis=0)).T
    rms = np.sqrt(np.mean(np.abs(q) ** 2, axis=-1, keepdims=True))
    return np.where(rms > 1e-12, q / np.where(rms > 1e-12, rms, 1.0), 0.0)


def _projection(points, e):
    """:func:`_normalised_projection` for one direction (the fast path of the refinement)."""
    x, y, z = e
    e1 = np.array([0.0, z, -y]) if abs(x) < 0.9 else np.array([-z, 0.0, x])  # (1,0,0) x e or (0,1,0) x e
    e1 /= math.sqrt(e1 @ e1)
    e2 = np.array([y * e1[2] - z * e1[1], z * e1[0] - x * e1[2], x * e1[1] - y * e1[0]])
    q = points @ e1 + 1j * (points @ e2)
    q = q - q.mean()
    rms = math.sqrt(float((q.real ** 2 + q.imag ** 2).mean()))
    return q / rms if rms > 1e-12 else np.zeros_like(q)


def _mobius_rows(q, Q):
    """Row-normalised rows ``(q Q, Q, -q, -1)``: a kernel vector is ``(alpha, beta, gamma, delta)``."""
    q, Q = np.broadcast_arrays(q, Q)
    rows = np.stack([q * Q, Q, -q, -np.ones_like(q)], axis=-1)
    return rows / np.linalg.norm(rows, axis=-1, keepdims=True)


def _refine_bond(p, P, left, right, bond_tol, degenerate_tol, similarity_tol):
    bl, br = np.array(_frame_of(left)), np.array(_frame_of(right))

    def unpack(x):
        L = left + x[0] * bl[0] + x[1] * bl[1]
        R = right + x[2] * br[0] + x[3] * br[1]
        return L / np.linalg.norm(L), R / np.linalg.norm(R)

    def system(x):
        L, R = unpack(x)
        q, Q = _projection(p, L), _projection(P, R)
        rows = np.column_stack([q * Q, Q, -q, -np.ones(len(q))])
        return rows / np.sqrt((rows.real ** 2 + rows.imag ** 2).sum(axis=1))[:, None]

    kernel = np.linalg.svd(system(np.zeros(4)))[2][-1].conj()
    gauge = int(np.argmax(np.abs(kernel)))
    kernel = kernel / kernel[gauge]
    free = [k for k in range(4) if k != gauge]

    def residuals(x):
        k = np.ones(4, complex)
        k[free] = x[4:7] + 1j * x[7:10]
        r = system(x) @ k / np.linalg.norm(k)
        return np.r_[r.real, r.imag]

    x0 = np.r_[np.zeros(4), kernel[free].real, kernel[free].imag]
    method = "lm" if 2 * len(p) >= len(x0) else "trf"  # LM needs at least as many residuals as unknowns
    x = scipy.optimize.least_squares(residuals, x0, method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15,
                                     max_nfev=REFINE_EVALUATIONS).x
    A = system(x)
    _, sigma, vt = np.linalg.svd(A)
    residual = float(sigma[-1])
    alpha, beta, gamma, delta = vt[-1].conj()
    if residual > bond_tol or abs(alpha * delta - beta * gamma) <= degenerate_tol:
        return None
    L, R = unpack(x)
    if L[2] < 0 or (L[2] == 0 and (L[1] < 0 or (L[1] == 0 and L[0] < 0))):
        L, R = -L, -R
    kind = "similarity" if abs(gamma) <= similarity_tol else "inversion"
    return ProjectionBond(kind, L, R, (complex(alpha), complex(beta), complex(gamma), complex(delta)), residual)


def _same_pair(a: ProjectionBond, b: ProjectionBond) -> bool:
    return np.linalg.norm(a.left - b.left) < 1e-6 and np.linalg.norm(a.right - b.right) < 1e-6


def _spread(points) -> float:
    array = np.array(points, dtype=float)
    return float(np.abs(array - array.mean(axis=0)).max()) if len(array) else 0.0


def _same_point(a, b, tol, scale) -> bool:
    if tol is None:
        return a == b
    return float(np.linalg.norm(np.subtract(a, b, dtype=float))) <= tol * scale


def _collinear(points, indices, tol, scale) -> bool:
    """Whether ``points[indices]`` lie on one line: exactly (tol None) or within ``tol * scale``."""
    chosen = [points[i] for i in indices]
    if len(chosen) <= 2:
        return True
    if tol is None:
        a = chosen[0]
        b = next((c for c in chosen if c != a), None)
        if b is None:
            return True
        e = [b[k] - a[k] for k in range(3)]
        for c in chosen:
            w = [c[k] - a[k] for k in range(3)]
            if (w[1] * e[2] - w[2] * e[1], w[2] * e[0] - w[0] * e[2], w[0] * e[1] - w[1] * e[0]) != (0, 0, 0):
                return False
        return True
    array = np.array(chosen, dtype=float)
    a = array[0]
    far = np.linalg.norm(array - a, axis=1)
    if far.max() <= tol * scale:
        return True
    e = (array[np.argmax(far)] - a) / far.max()
    w = array - a
    off = w - np.outer(w @ e, e)
    return bool(np.linalg.norm(off, axis=1).max() <= tol * scale)
