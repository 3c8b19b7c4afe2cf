"""Self-motions of an n-pod by pseudo-arclength continuation: numerical evidence, not proof (bond theory paper)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from interlock.verify.npod.mobility import POSE_RTOL, RANK_RTOL, NPod, ScaledFrame, mobility, pose_arrays

__all__ = ["SelfMotion", "self_motion", "STEP", "ARC_LENGTH", "MIN_STEP", "RESIDUAL_TOL", "NEWTON_ITERATIONS",
           "MAX_STEPS"]

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
    >>> from interlock.verify.npod import npod
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
    M0, y0 = pose_arrays(pod, pose)
    frame = ScaledFrame(pod, M0, y0)
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
