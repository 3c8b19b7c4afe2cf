"""n-pods (seed 003): input, leg rows, first-order mobility at a pose and self-motions by continuation.

The pose-independent bond checks of Cor. 3.17 (collinearity/butterfly conditions, projection bonds) are in
:mod:`interlock.verify.npod_bonds`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from interlock.errors import InterlockError

__all__ = ["NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "SelfMotion", "self_motion",
           "RANK_RTOL", "POSE_RTOL", "STEP", "ARC_LENGTH", "MIN_STEP", "RESIDUAL_TOL", "NEWTON_ITERATIONS",
           "MAX_STEPS"]

#: A singular value of the (scaled, unit) leg rows at most ``RANK_RTOL * sigma_max`` counts as zero.
RANK_RTOL = 1e-9
#: A pose is on the n-pod when every ``| |M p_i + y - P_i|^2 - d_i^2 |`` is at most this times ``scale^2``;
#: also the tolerance of ``M^T M = I`` for a float rotation.
POSE_RTOL = 1e-9
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
    (seed 003, before Cor. 3.17, ref. [9]); Cor. 3.17 gives pose-independent conditions
    (:func:`~interlock.verify.npod_bonds.bond_conditions`).

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
