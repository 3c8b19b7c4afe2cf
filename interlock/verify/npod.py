"""n-pods: first-order mobility, the bond conditions of Gallet–Nawratil–Schicho (seed 003) and self-motions."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import scipy.optimize

from interlock.errors import InterlockError

__all__ = ["NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "BondConditions", "bond_conditions",
           "ProjectionBond", "BondSearch", "projection_bonds", "SelfMotion", "self_motion",
           "RANK_RTOL", "POSE_RTOL", "COLLINEAR_RTOL", "BOND_TOL", "DEGENERATE_TOL", "SIMILARITY_TOL",
           "SEARCH_SAMPLES", "SEARCH_STARTS", "REFINE_EVALUATIONS", "STEP", "ARC_LENGTH", "MIN_STEP", "RESIDUAL_TOL",
           "NEWTON_ITERATIONS", "MAX_STEPS"]

#: A singular value of the (scaled, unit) leg rows at most ``RANK_RTOL * sigma_max`` counts as zero.
RANK_RTOL = 1e-9
#: A pose is on the n-pod when every ``| |M p_i + y - P_i|^2 - d_i^2 |`` is at most this times ``scale^2``;
#: also the tolerance of ``M^T M = I`` for a float rotation.
POSE_RTOL = 1e-9
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
#: Continuation: first (and largest) pseudo-arclength step, in scaled units (see :func:`self_motion`).
STEP = 0.05
#: Continuation: the arc length to reach in each direction, in scaled units.
ARC_LENGTH = 1.0
#: Continuation: a step that must shrink below this means the curve does not go on.
MIN_STEP = 1e-3
#: Continuation: Newton has converged when every scaled leg equation and the step equation is below this.
RESIDUAL_TOL = 1e-11
#: Continuation: Newton (Gauss–Newton) iterations per step before the step is halved.
NEWTON_ITERATIONS = 12
#: Continuation: at most this many accepted steps per direction.
MAX_STEPS = 2000


class NPodError(InterlockError):
    """Bad n-pod input: shapes, counts, non-finite numbers, lengths, a pose that is not a rotation or not on the pod."""


@dataclass(frozen=True, eq=False)
class NPod:
    """An n-pod ``((p_1..p_n), (P_1..P_n), (d_1..d_n))``: leg ``i`` keeps ``|sigma(p_i) - P_i| = d_i`` (seed 003, eq. (1)).

    ``base`` holds the fixed points ``P_i``, ``platform`` the points ``p_i`` in the platform frame; both are
    tuples of 3-tuples of :class:`~fractions.Fraction` when ``exact`` (every input number was an int or a
    Fraction) and of floats otherwise.  ``squared_lengths`` are ``d_i^2`` (exact when the data are).
    ``pose`` is the pose ``(M, y)`` the lengths were taken from, if any.  Build with :func:`npod`.
    """

    base: tuple
    platform: tuple
    squared_lengths: tuple
    exact: bool
    pose: tuple | None = None

    def __len__(self) -> int:
        return len(self.base)

    def __str__(self) -> str:
        return f"{len(self)}-pod ({'exact rational' if self.exact else 'floating-point'} data)"

    def to_dict(self) -> dict:
        """JSON-serialisable: numbers as strings when exact ("1/2"), floats otherwise."""
        num = str if self.exact else float
        rows = lambda points: [[num(c) for c in point] for point in points]  # noqa: E731
        pose = None if self.pose is None else {"M": rows(self.pose[0]), "y": [num(c) for c in self.pose[1]]}
        return {"legs": len(self), "exact": self.exact, "base": rows(self.base), "platform": rows(self.platform),
                "squared_lengths": [num(d) for d in self.squared_lengths], "pose": pose}


def npod(base, platform, lengths=None, *, squared_lengths=None, pose=None, exact: bool | None = None) -> NPod:
    """An n-pod from base points, platform points and leg lengths (given, or taken from a pose).

    Give exactly one of ``lengths`` (``d_i > 0``), ``squared_lengths`` (``d_i^2``; exact for rational data
    whose lengths are irrational) or ``pose = (M, y)``, a rotation ``M`` and translation ``y`` giving
    ``d_i^2 = |M p_i + y - P_i|^2``.

    Parameters
    ----------
    base, platform : array-like (n, 3)
        ``P_i`` (fixed) and ``p_i`` (platform frame), ``n >= 1``.
    lengths, squared_lengths : array-like (n,), optional
    pose : (M, y), optional
    exact : bool, optional
        None (default): exact (Fractions) iff every number given is an int or a Fraction.  True converts floats
        to the Fractions of their binary values; False uses floats throughout.

    Raises
    ------
    NPodError
        Wrong shapes, fewer than one leg, count mismatch, non-finite or non-real numbers, lengths that are
        negative or zero (a leg of length 0 is a spherical joint, not a leg), a pose that is not a rotation.

    Examples
    --------
    >>> pod = npod([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
    ...            pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2]))
    >>> str(pod), pod.squared_lengths
    ('3-pod (exact rational data)', (Fraction(4, 1), Fraction(4, 1), Fraction(4, 1)))
    """
    given = [name for name, value in (("lengths", lengths), ("squared_lengths", squared_lengths), ("pose", pose))
             if value is not None]
    if len(given) != 1:
        raise NPodError(f"give exactly one of lengths, squared_lengths or pose (got {given or 'none'})")
    P, base_exact = _numbers(base, "base", (None, 3))
    p, platform_exact = _numbers(platform, "platform", (None, 3))
    if len(P) < 1:
        raise NPodError("an n-pod needs at least one leg: base and platform have shape (n, 3) with n >= 1, got n = 0")
    if len(P) != len(p):
        raise NPodError(f"base has {len(P)} points but platform has {len(p)}: one base and one platform point per leg")
    parsed_pose, pose_exact = (None, True) if pose is None else _pose(pose)
    if lengths is not None:
        values, lengths_exact = _numbers(lengths, "lengths", (len(P),))
    elif squared_lengths is not None:
        values, lengths_exact = _numbers(squared_lengths, "squared_lengths", (len(P),))
    else:
        values, lengths_exact = None, True
    if exact is None:
        exact = base_exact and platform_exact and pose_exact and lengths_exact
    cast = Fraction if exact else float
    P = tuple(tuple(cast(c) for c in point) for point in P)
    p = tuple(tuple(cast(c) for c in point) for point in p)
    if parsed_pose is not None:
        parsed_pose = (tuple(tuple(cast(c) for c in row) for row in parsed_pose[0]), tuple(cast(c) for c in parsed_pose[1]))
        _check_rotation(parsed_pose[0], exact)
        squared = tuple(_squared_leg(parsed_pose, pi, Pi) for pi, Pi in zip(p, P))
    else:
        values = tuple(cast(v) for v in values)
        if any(v < 0 for v in values):
            raise NPodError(f"{given[0]} must be positive, got {[float(v) for v in values]}")
        squared = values if squared_lengths is not None else tuple(v * v for v in values)
    if any(d == 0 for d in squared):
        legs = [i for i, d in enumerate(squared) if d == 0]
        raise NPodError(f"legs {legs} have length 0: a leg of length 0 is a spherical joint, not a leg; "
                        "model it by three legs of positive length meeting at the point")
    return NPod(P, p, squared, bool(exact), parsed_pose)


def leg_rows(pod: NPod, pose=None) -> np.ndarray:
    """The leg rows ``(P_i x x_i, x_i - P_i)``, ``x_i = M p_i + y``, at a pose: shape (n, 6), world units.

    Row ``i`` is the Plücker vector (moment ``P_i x u_i = x_i x u_i``, direction ``u_i = x_i - P_i``) of the
    leg's line, paired with a spatial twist ``(omega, v)`` (point velocities ``omega x x + v``) so that
    ``row_i . (omega, v) = d/dt |x_i - P_i|^2 / 2``.  ``pose`` defaults to ``pod.pose``.

    Examples
    --------
    >>> pod = npod([(0, 0, 0)], [(0, 0, 0)], pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [1, 0, 0]))
    >>> leg_rows(pod).tolist()
    [[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]]
    """
    M, y = _pose_arrays(pod, pose)
    P = np.array(pod.base, dtype=float)
    x = np.array(pod.platform, dtype=float) @ M.T + y
    return np.hstack([np.cross(P, x), x - P])


@dataclass(frozen=True, eq=False)
class Mobility:
    """The answer of :func:`mobility`: the first-order motions of the platform at one pose.

    ``mobility = 6 - rank`` of the leg rows; ``kernel`` (mobility, 6) spans the infinitesimal motions as world
    twists ``(omega, v)`` (point velocities ``omega x x + v``), each of unit norm.  ``rank`` is the float rank
    with ``rank_rtol``; ``exact_rank`` the rank over the rationals when the pod and the pose are exact and the
    pose satisfies the leg equations exactly (then ``mobility`` uses it), else None.
    ``singular_values`` are those of the scaled unit rows, divided by the largest.
    """

    mobility: int
    rank: int
    exact_rank: int | None
    legs: int
    kernel: np.ndarray
    singular_values: tuple
    tolerances: dict = field(default_factory=dict)

    def __str__(self) -> str:
        how = "exact rank" if self.exact_rank is not None else f"float rank, rank_rtol {self.tolerances['rank_rtol']:g}"
        plural = "s" if self.mobility > 1 else ""
        word = ("infinitesimally rigid" if self.mobility == 0 else
                f"infinitesimally mobile ({self.mobility} first-order motion{plural})")
        return f"{word}: {self.legs} legs, rank {6 - self.mobility} ({how})"

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {"mobility": self.mobility, "rank": self.rank, "exact_rank": self.exact_rank, "legs": self.legs,
                "kernel": self.kernel.tolist(), "singular_values": list(self.singular_values),
                "tolerances": dict(self.tolerances)}


def mobility(pod: NPod, pose=None, *, rank_rtol: float = RANK_RTOL, pose_rtol: float = POSE_RTOL) -> Mobility:
    """Infinitesimal mobility ``6 - rank`` of the leg rows at a pose, with its kernel.

    The rank is that of the rows ``(x_i' x e_i, e_i)``, ``e_i = u_i / |u_i|`` the unit leg directions and
    ``x_i' = (x_i - c) / s`` the platform anchors about the base centroid ``c``, scaled by the model size ``s``
    (:func:`leg_rows` up to row scaling and a change of twist coordinates, so the same rank): this makes the
    singular values invariant under rigid motions and scaling.  The criterion is the classical one at a pose
    (seed 003, before Cor. 3.17, ref. [9]); Cor. 3.17 gives pose-independent conditions (:func:`bond_conditions`).

    Parameters
    ----------
    pod : NPod
    pose : (M, y), optional
        Defaults to ``pod.pose``; must satisfy the leg equations within ``pose_rtol * s^2``.
    rank_rtol : float
        Singular values at most ``rank_rtol * sigma_max`` count as zero.

    Examples
    --------
    >>> tripod = npod([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
    ...               pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2]))
    >>> m = mobility(tripod)
    >>> m.mobility, m.exact_rank
    (3, 3)
    """
    M, y = _pose_arrays(pod, pose)
    frame = _Scaled(pod, M, y)
    frame.check_on_pod(M, frame.scaled_y(y), pose_rtol)
    rows = frame.rows(M, frame.scaled_y(y), unit=True)
    _, sigma, vt = np.linalg.svd(rows)
    sigma = np.concatenate([sigma, np.zeros(6 - len(sigma))])
    top = sigma[0] if sigma[0] > 0 else 1.0
    rank = int(np.sum(sigma > rank_rtol * top))
    kernel = np.array([frame.world_twist(t) for t in vt[rank:]]).reshape(-1, 6)
    kernel /= np.maximum(np.linalg.norm(kernel, axis=1, keepdims=True), 1e-300)
    exact_rank = _exact_rank(pod, pose if pose is not None else pod.pose)
    return Mobility(6 - (rank if exact_rank is None else exact_rank), rank, exact_rank, len(pod), kernel,
                    tuple(abs(float(s / top)) for s in sigma), {"rank_rtol": rank_rtol, "pose_rtol": pose_rtol})


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
    :func:`self_motion` tests a pose).

    Examples
    --------
    >>> from fractions import Fraction as F
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


@dataclass(frozen=True, eq=False)
class SelfMotion:
    """The answer of :func:`self_motion`: numerical evidence for or against a self-motion through a pose.

    ``found`` is True ("self-motion found": the leg equations hold to ``residual_tol`` along a curve of the
    requested arc length, steps never below ``min_step``), False (infinitesimally rigid, or the curve along
    the 1-dimensional kernel does not go on: Newton fails at steps shrinking below ``min_step`` in both
    directions) or None (kernel dimension >= 2: not followed).  ``poses`` (world ``(M, y)``) run from the end
    of the backward branch through the start pose to the end of the forward one; ``reached`` is the arc
    length reached in each direction (scaled units), ``max_residual`` the largest scaled leg residual at an
    accepted pose, ``max_angle`` / ``max_translation`` the largest rotation angle (rad) / translation (world
    units) from the start pose.  None of this is a proof: it is floating-point evidence with the tolerances given.
    """

    found: bool | None
    status: str
    kernel_dimension: int
    reached: tuple
    steps: tuple
    smallest_step: float
    max_residual: float
    max_angle: float
    max_translation: float
    poses: tuple
    tolerances: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return f"{self.status} (kernel dimension {self.kernel_dimension}, reached {list(self.reached)})"

    def to_dict(self) -> dict:
        return {"found": self.found, "status": self.status, "kernel_dimension": self.kernel_dimension,
                "reached": list(self.reached), "steps": list(self.steps), "smallest_step": self.smallest_step,
                "max_residual": self.max_residual, "max_angle": self.max_angle,
                "max_translation": self.max_translation,
                "poses": [{"M": M.tolist(), "y": y.tolist()} for M, y in self.poses],
                "tolerances": dict(self.tolerances)}


def self_motion(pod: NPod, pose=None, *, step: float = STEP, arc_length: float = ARC_LENGTH,
                min_step: float = MIN_STEP, residual_tol: float = RESIDUAL_TOL, rank_rtol: float = RANK_RTOL,
                pose_rtol: float = POSE_RTOL, newton_iterations: int = NEWTON_ITERATIONS,
                max_steps: int = MAX_STEPS) -> SelfMotion:
    """Follow the solution curve of ``{|M p_i + y - P_i|^2 = d_i^2}`` in SE(3) through a pose, both ways.

    Coordinates are scaled: ``x' = (x - c) / s`` (``c`` the base centroid, ``s`` the model size), so leg
    equations are ``f_i = |M p_i' + y' - P_i'|^2 - d_i'^2`` with ``d' = d / s``.  A pose ``g = (M, y')`` is
    embedded as ``z(g) = (M, y')`` in ``R^12``; arc length is measured there.  A spatial twist ``xi = (omega, v)``
    moves ``g`` to ``(exp[omega] M, exp[omega] y' + v)``, whose derivative at ``xi = 0`` is ``2 x`` the scaled
    leg rows (:func:`leg_rows`).  Pseudo-arclength continuation: the tangent ``t`` solves ``[J; T_prev Z] t =
    (0, 1)`` (``Z`` maps twists to ``R^12``); the predictor moves by ``h t`` (``|Z t| = 1``); Gauss–Newton
    (least squares, re-linearised at each iterate) solves ``f(g) = 0``, ``T . (z(g) - z_k) = h``.  A step whose
    Newton iteration does not bring every equation below ``residual_tol`` in ``newton_iterations`` is halved;
    below ``min_step`` the branch stops ("stalled").

    At a pose that is infinitesimally mobile but finitely rigid (e.g. a rank-deficient pose of an
    overconstrained pod), the equations along the kernel fail at second order: Gauss–Newton converges to a
    least-squares point with residual ``~ h^2``, the step halves until it is below ``min_step`` and the branch
    stalls; only a real curve keeps residuals at ``residual_tol`` with steps that do not shrink.

    Parameters
    ----------
    pod : NPod
    pose : (M, y), optional
        Defaults to ``pod.pose``.
    step, arc_length, min_step : float
        Largest step, arc length to reach per direction, smallest step (scaled ``R^12`` units).
    residual_tol : float
        Newton has converged when all scaled equations are at most this.
    rank_rtol : float
        For the kernel dimension at the pose (:func:`mobility`).

    Not covered: a curve that is singular at the pose (a cusp, or branches crossing with a 1-dimensional kernel)
    can be missed; a kernel of dimension >= 2 is not explored; "found" means a curve to the tolerances, not an
    exact proof; "no self-motion" is evidence of finite rigidity, not a proof.

    Examples
    --------
    >>> tripod = npod([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
    ...               pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2]))
    >>> five = npod([(0, 0, 0), (3, 0, 0), (0, 3, 0), (3, 3, 1), (1, 2, 2)],
    ...             [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 1)],
    ...             pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2]))
    >>> motion = self_motion(five)   # a pentapod at a regular pose moves
    >>> motion.found, motion.reached, motion.max_residual < 1e-11
    (True, (1.0, 1.0), True)
    """
    tolerances = {"step": step, "arc_length": arc_length, "min_step": min_step, "residual_tol": residual_tol,
                  "rank_rtol": rank_rtol, "pose_rtol": pose_rtol, "newton_iterations": newton_iterations}
    first = mobility(pod, pose, rank_rtol=rank_rtol, pose_rtol=pose_rtol)
    M0, y0 = _pose_arrays(pod, pose)
    frame = _Scaled(pod, M0, y0)
    start = (M0, frame.scaled_y(y0))
    dimension = first.mobility
    if dimension != 1 or first.rank != 6 - dimension:
        found = False if dimension == 0 else None
        how = "exact" if first.exact_rank is not None else f"float, rank_rtol {rank_rtol:g}"
        status = (f"infinitesimally rigid at the pose (rank 6, {how}): no self-motion through it"
                  if dimension == 0 and first.rank == 6 else
                  f"inconclusive: the float rank {first.rank} and the exact rank {first.exact_rank} differ"
                  if first.rank != 6 - dimension else
                  f"inconclusive: {dimension} first-order motions; continuation follows a 1-dimensional kernel only")
        return SelfMotion(found, status, dimension, (0.0, 0.0), (0, 0), 0.0, 0.0, 0.0, 0.0,
                          ((M0, np.asarray(y0, float)),), tolerances)
    J = frame.rows(*start, unit=False)
    kernel = np.linalg.svd(J)[2][-1]
    tangent = _ambient(*start) @ kernel
    tangent /= np.linalg.norm(tangent)
    branches = [_follow(frame, start, sign * tangent, step, arc_length, min_step, residual_tol,
                        newton_iterations, max_steps) for sign in (1.0, -1.0)]
    path = branches[1]["poses"][::-1] + [start] + branches[0]["poses"]
    reached = tuple(b["reached"] for b in branches)
    complete = [b["reason"] == "reached" for b in branches]
    residual = max(float(np.max(np.abs(frame.residual(*g)))) for g in path)
    angles = [float(np.arccos(np.clip((np.trace(M @ M0.T) - 1) / 2, -1, 1))) for M, _ in path]
    moves = [float(np.linalg.norm(y - start[1])) * frame.size for _, y in path]
    moving = max(angles) + max(moves) / frame.size > 0.1 * arc_length
    smallest = min(b["smallest"] for b in branches)
    reasons = [b["reason"] for b in branches]
    if any(complete) and moving:
        found, status = True, (f"self-motion found: curve followed to arc length {arc_length:g} "
                               f"(residual <= {residual:.1e}, steps >= {smallest:.2g}; numerical evidence)")
    elif any(complete):
        found, status = None, "inconclusive: the continuation reached its arc length without the pose moving"
    elif "max_steps" in reasons:
        found, status = None, f"inconclusive: max_steps {max_steps} reached before arc length {arc_length:g}"
    else:
        found, status = False, ("no self-motion found: infinitesimally mobile (kernel dimension 1) but Newton fails "
                                f"at steps below min_step {min_step:g} in both directions "
                                "(numerical evidence of finite rigidity)")
    world = tuple((M, frame.world_y(y)) for M, y in path)
    return SelfMotion(found, status, 1, reached, tuple(b["steps"] for b in branches), smallest, residual,
                      max(angles), max(moves), world, tolerances)


# --- private helpers -------------------------------------------------------------------------------------------


class _Scaled:
    """Scaled coordinates about the base centroid: ``x' = (x - c) / s``, invariant under rigid motions and scaling."""

    def __init__(self, pod: NPod, M, y):
        self.base = np.array(pod.base, dtype=float)
        self.centre = self.base.mean(axis=0)
        platform = np.array(pod.platform, dtype=float)
        anchors = platform @ M.T + y
        squared = np.array([float(d) for d in pod.squared_lengths])
        self.size = float(max(np.abs(self.base - self.centre).max(), np.abs(anchors - self.centre).max(),
                              np.sqrt(squared.max())))
        self.P = (self.base - self.centre) / self.size
        self.p = platform / self.size
        self.d2 = squared / self.size ** 2

    def scaled_y(self, y):
        return (np.asarray(y, float) - self.centre) / self.size

    def world_y(self, y):
        return np.asarray(y) * self.size + self.centre

    def world_twist(self, t):
        omega, v = t[:3], t[3:]
        return np.concatenate([omega, self.size * v - np.cross(omega, self.centre)])

    def residual(self, M, y):
        u = self.p @ M.T + y - self.P
        return np.einsum("ij,ij->i", u, u) - self.d2

    def rows(self, M, y, unit: bool):
        x = self.p @ M.T + y
        u = x - self.P
        if unit:
            u = u / np.linalg.norm(u, axis=1, keepdims=True)
        return np.hstack([np.cross(x, u), u])

    def check_on_pod(self, M, y, pose_rtol):
        worst = float(np.max(np.abs(self.residual(M, y))))
        if worst > pose_rtol:
            raise NPodError(f"the pose is not on the n-pod: a squared leg length is off by {worst:.2e} (scaled), "
                            f"more than pose_rtol {pose_rtol:g}; pass a pose that satisfies |M p_i + y - P_i| = d_i")


def _follow(frame, start, tangent, step, arc_length, min_step, residual_tol, iterations, max_steps) -> dict:
    g, previous, travelled, h = start, tangent, 0.0, step
    poses, smallest = [], step
    while arc_length - travelled > 1e-12 * arc_length and len(poses) < max_steps:
        Z = _ambient(*g)
        J = frame.rows(*g, unit=False)
        t = np.linalg.lstsq(np.vstack([J, previous @ Z]), np.r_[np.zeros(len(J)), 1.0], rcond=None)[0]
        t /= np.linalg.norm(Z @ t)
        T = Z @ t
        h = min(h, arc_length - travelled)
        while True:
            moved, used = _correct(frame, g, t, T, h, residual_tol, iterations)
            if moved is not None:
                break
            h /= 2
            if h < min_step:
                return {"poses": poses, "reached": travelled, "steps": len(poses), "smallest": h, "reason": "stalled"}
        smallest = min(smallest, h)
        g, previous, travelled = moved, T, (arc_length if h >= arc_length - travelled else travelled + h)
        poses.append(g)
        h = min(step, 2 * h) if used <= 4 else h
    reason = "reached" if arc_length - travelled <= 1e-12 * arc_length else "max_steps"
    travelled = arc_length if reason == "reached" else travelled
    return {"poses": poses, "reached": travelled, "steps": len(poses), "smallest": smallest, "reason": reason}


def _correct(frame, g, t, T, h, residual_tol, iterations):
    """Gauss–Newton for ``f(g') = 0, T . (z(g') - z(g)) = h`` from the predictor ``g + h t``; None if it fails."""
    z0 = _embed(*g)
    current = _move(g, h * t)
    for iteration in range(iterations + 1):
        F = np.r_[frame.residual(*current), T @ (_embed(*current) - z0) - h]
        if np.max(np.abs(F)) <= residual_tol:
            return current, iteration
        if iteration == iterations:
            break
        A = np.vstack([2 * frame.rows(*current, unit=False), T @ _ambient(*current)])
        delta = np.linalg.lstsq(A, -F, rcond=None)[0]
        if np.linalg.norm(delta) > 2 * h:  # a jump away from the predictor: not this curve
            return None, iteration
        current = _move(current, delta)
    return None, iterations


def _hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _expm_so3(w):
    angle = float(np.linalg.norm(w))
    K = _hat(w)
    if angle < 1e-8:
        return np.eye(3) + K + K @ K / 2
    return np.eye(3) + math.sin(angle) / angle * K + (1 - math.cos(angle)) / angle ** 2 * K @ K


def _move(g, xi):
    M, y = g
    E = _expm_so3(xi[:3])
    return E @ M, E @ y + xi[3:]


def _embed(M, y):
    return np.r_[M.ravel(), y]


def _ambient(M, y):
    """``Z`` (12 x 6): the velocity of ``z(g) = (M, y)`` under the spatial twist ``(omega, v)``."""
    Z = np.zeros((12, 6))
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        K = _hat(e)
        Z[:9, k] = (K @ M).ravel()
        Z[9:, k] = K @ y
        Z[9 + k, 3 + k] = 1.0
    return Z


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


def _numbers(values, name: str, shape: tuple):
    """Nested numbers of the given shape (None: any length >= 0) and whether all are ints/Fractions."""
    try:
        array = np.array(values, dtype=object)
    except ValueError as error:
        raise NPodError(f"{name} must be a rectangular array of shape {_shape_text(shape)}: {error}") from None
    if array.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, array.shape)):
        if not (array.size == 0 and shape[0] is None):
            raise NPodError(f"{name} must have shape {_shape_text(shape)}, got {array.shape}")
        return [], True
    exact = True
    for value in array.flat:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise NPodError(f"{name} must hold real numbers (int, Fraction or float), got {value!r}")
        if not isinstance(value, numbers.Rational):
            exact = False
            if not math.isfinite(float(value)):
                raise NPodError(f"{name} must be finite, got {value!r}")
    return array.tolist(), exact


def _shape_text(shape) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _pose(pose):
    try:
        M, y = pose
    except (TypeError, ValueError):
        raise NPodError("pose must be a pair (M, y): a 3x3 rotation and a translation 3-vector") from None
    M, exact_M = _numbers(M, "pose rotation M", (3, 3))
    y, exact_y = _numbers(y, "pose translation y", (3,))
    return (M, y), exact_M and exact_y


def _check_rotation(M, exact: bool) -> None:
    product = [[sum(M[k][i] * M[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    det = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
           + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]))
    off = max(abs(product[i][j] - (i == j)) for i in range(3) for j in range(3))
    if (off != 0 or det != 1) if exact else (off > POSE_RTOL or det <= 0):
        how = "exactly" if exact else f"to {POSE_RTOL:g}"
        raise NPodError(f"pose rotation M must satisfy M^T M = I and det M = 1 ({how}); "
                        f"got max |M^T M - I| = {float(off):.3g}, det M = {float(det):.6g}")


def _squared_leg(pose, p, P):
    M, y = pose
    return sum((sum(M[r][c] * p[c] for c in range(3)) + y[r] - P[r]) ** 2 for r in range(3))


def _pose_arrays(pod: NPod, pose):
    if pose is None:
        if pod.pose is None:
            raise NPodError("no pose: pass pose=(M, y), or build the n-pod with npod(..., pose=(M, y))")
        parsed = pod.pose
    else:
        parsed, _ = _pose(pose)
    M, y = np.array(parsed[0], dtype=float), np.array(parsed[1], dtype=float)
    _check_rotation(M.tolist(), False)
    return M, y


def _exact_rank(pod: NPod, pose):
    """Rank over Q of the rows ``(x_i x u_i, u_i)`` if the pod and the pose are exact and the pose is on the pod."""
    if not pod.exact or pose is None:
        return None
    parsed, exact = _pose(pose)
    if not exact:
        return None
    M, y = [[Fraction(c) for c in row] for row in parsed[0]], [Fraction(c) for c in parsed[1]]
    try:
        _check_rotation(M, True)
    except NPodError:
        return None
    rows = []
    for p, P, d2 in zip(pod.platform, pod.base, pod.squared_lengths):
        x = [sum(M[r][c] * p[c] for c in range(3)) + y[r] for r in range(3)]
        u = [x[r] - P[r] for r in range(3)]
        if sum(c * c for c in u) != d2:
            return None
        rows.append([x[1] * u[2] - x[2] * u[1], x[2] * u[0] - x[0] * u[2], x[0] * u[1] - x[1] * u[0]] + u)
    rank = 0
    for column in range(6):
        pivot = next((r for r in range(rank, len(rows)) if rows[r][column] != 0), None)
        if pivot is None:
            continue
        rows[rank], rows[pivot] = rows[pivot], rows[rank]
        for r in range(rank + 1, len(rows)):
            factor = rows[r][column] / rows[rank][column]
            if factor:
                rows[r] = [a - factor * b for a, b in zip(rows[r], rows[rank])]
        rank += 1
    return rank


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
