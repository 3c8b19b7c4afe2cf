"""n-pods (seed 003): input, leg rows and first-order mobility at a pose.

Self-motions by continuation are in :mod:`interlock.verify.npod.continuation`.

The pose-independent bond checks of Cor. 3.17 (collinearity/butterfly conditions, projection bonds) are in
:mod:`interlock.verify.npod.bonds`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from interlock.errors import InterlockError

__all__ = ["NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "pose_arrays", "ScaledFrame", "RANK_RTOL",
           "POSE_RTOL"]

#: A singular value of the (scaled, unit) leg rows at most ``RANK_RTOL * sigma_max`` counts as zero.
RANK_RTOL = 1e-9
#: A pose is on the n-pod when every ``| |M p_i + y - P_i|^2 - d_i^2 |`` is at most this times ``scale^2``;
#: also the tolerance of ``M^T M = I`` for a float rotation.
POSE_RTOL = 1e-9


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
    M, y = pose_arrays(pod, pose)
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
    (:func:`~interlock.verify.npod.bonds.bond_conditions`).

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
    M, y = pose_arrays(pod, pose)
    frame = ScaledFrame(pod, M, y)
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


class ScaledFrame:
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


def pose_arrays(pod: NPod, pose):
    """The float ``(M, y)`` of ``pose``, or of the pod's own pose when ``pose`` is None (NPodError if neither)."""
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
