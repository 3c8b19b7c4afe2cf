"""A semicircular masonry arch of voussoirs on two supports (the CRA paper's "arch thick", Table 1)."""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError

__all__ = ["ArchError", "semicircular_arch", "MAX_THICKNESS_RATIO"]

#: ``thickness_ratio`` must stay below this: at ``t / r = 2`` the intrados radius ``r - t / 2`` is zero.
MAX_THICKNESS_RATIO = 2.0


class ArchError(InterlockError):
    """Arch parameters outside the allowed range (the message says which values are allowed)."""


def semicircular_arch(voussoirs: int = 36, thickness_ratio: float = 0.15, radius: float = 1.0,
                      depth: float | None = None, supports: bool = True,
                      support_height: float | None = None) -> Assembly:
    """A semicircular arch of ``voussoirs`` prismatic voussoirs with radial joints, on two supports.

    The arch lies in the xz-plane, its centre at the origin, springings on
    ``z = 0``, extruded along y over ``-depth / 2 <= y <= depth / 2``.  With
    thickness ``t = thickness_ratio * radius`` and ``n = voussoirs``, the joints
    are at the angles ``theta_k = pi (1 - k / n)``, ``k = 0 .. n`` (left springing
    to right springing), and voussoir ``k`` is the convex prism on the eight corners

        ``(rho cos theta, y, rho sin theta)``,  ``rho in {r - t/2, r + t/2}``,
        ``theta in {theta_k, theta_{k+1}}``,  ``y in {-depth/2, depth/2}``:

    the annular sector between the intrados and extrados circles (radii
    ``r -+ t/2``; ``radius`` is the centreline radius) with its arcs replaced by
    chords, so that every face is planar.  Its volume is

        ``V = r t depth sin(pi / n)``,

    the sector's ``r t depth pi / n`` times ``sin(pi/n) / (pi/n)`` (0.99873 for
    36 voussoirs).  Joints are radial: neighbours share one ``t x depth``
    rectangle.  The supports are boxes of height ``support_height`` under the
    springings whose top faces are exactly the springing joints
    (``r - t/2 <= |x| <= r + t/2``, ``z = 0``), so the arch rests on horizontal
    beds where it can slide.

    This is the "arch thick" model of the CRA paper (Kao et al., Table 1 and
    Remark 1): ``t / r = 0.150``, 36 voussoirs, 2 fixed supports.  Its tilting
    test in the arch's plane (about the y-axis) fails at 8.2 degrees with a
    friction angle of 43 degrees and at 3.0 degrees with 21.8 degrees
    (Remark 1; RBE, CRA, 3DEC and the analytic solution agree).

    Parameters
    ----------
    voussoirs : int
        Number of voussoirs ``n``, an integer >= 1 (the paper's 36).
    thickness_ratio : float
        ``t / r``, in ``(0, 2)`` (the paper's 0.15).
    radius : float
        Centreline radius ``r`` > 0.
    depth : float, optional
        Extent along y, > 0; default ``t`` (square voussoir sections).  It does
        not change the in-plane tilting test.
    supports : bool
        Add the two support boxes (blocks ``n`` left and ``n + 1`` right) as the
        frame.  Without them the frame is the two end voussoirs ``0`` and ``n - 1``
        (the upstream compas_cra convention).
    support_height : float, optional
        Height of the support boxes, > 0; default ``t``.

    Returns
    -------
    Assembly
        One mesh per block (voussoirs from left to right, then the left and the
        right support), labels ``("voussoir", k)`` and ``("support", "left" | "right")``,
        the frame as above, and the parameters in ``info``.

    Raises
    ------
    ArchError
        ``voussoirs`` not an integer >= 1; ``thickness_ratio`` not in ``(0, 2)``;
        ``radius``, ``depth`` or ``support_height`` not finite and > 0;
        ``supports`` not a bool.

    See Also
    --------
    interlock.verify.statics.critical_tilt : the tilting test of Table 1.

    Notes
    -----
    ``O(n)``: one convex hull of eight points per voussoir.  Shared joint
    corners are computed from the same angle, so neighbouring voussoirs meet in
    bit-identical rectangles.

    Examples
    --------
    >>> arch = semicircular_arch()
    >>> len(arch), arch.frame, arch.labels[0], arch.labels[-1]
    (38, (36, 37), ('voussoir', 0), ('support', 'right'))
    >>> r, t, d = 1.0, 0.15, 0.15
    >>> bool(np.isclose(arch.volumes[0], r * t * d * math.sin(math.pi / 36)))
    True
    >>> arch.mesh(36).bounds.round(3).tolist()
    [[-1.075, -0.075, -0.15], [-0.925, 0.075, 0.0]]
    """
    n = _count(voussoirs, "voussoirs")
    ratio = _finite(thickness_ratio, "thickness_ratio")
    if not 0.0 < ratio < MAX_THICKNESS_RATIO:
        raise ArchError(f"thickness_ratio t/r must be in (0, {MAX_THICKNESS_RATIO:g}) so that the intrados "
                        f"radius r - t/2 is positive, got {ratio}")
    r = _positive(radius, "radius")
    t = ratio * r
    depth = t if depth is None else _positive(depth, "depth")
    support_height = t if support_height is None else _positive(support_height, "support_height")
    if not isinstance(supports, (bool, np.bool_)):
        raise ArchError(f"supports must be True or False, got {supports!r}")

    inner, outer, half = r - t / 2.0, r + t / 2.0, depth / 2.0
    angles = math.pi * (1.0 - np.arange(n + 1) / n)
    meshes = [_voussoir(angles[k], angles[k + 1], inner, outer, half) for k in range(n)]
    labels = [("voussoir", k) for k in range(n)]
    if supports:
        meshes += [trimesh.creation.box(bounds=[[lo, -half, -support_height], [hi, half, 0.0]])
                   for lo, hi in ((-outer, -inner), (inner, outer))]
        labels += [("support", "left"), ("support", "right")]
        frame = (n, n + 1)
    else:
        frame = (0, n - 1)
    info = {"preset": "semicircular_arch", "figure": "CRA paper Table 1, Remark 1 (arch thick)",
            "voussoirs": n, "thickness_ratio": ratio, "radius": r, "thickness": t, "depth": depth,
            "supports": bool(supports), "support_height": support_height if supports else None}
    return Assembly.from_meshes(meshes, frame=frame, labels=labels, info=info)


def _voussoir(start: float, end: float, inner: float, outer: float, half: float) -> trimesh.Trimesh:
    """The convex prism between the joint angles ``start`` and ``end`` (radians), radii ``inner``, ``outer``."""
    corners = np.array([(rho * math.cos(theta), y, rho * math.sin(theta))
                        for theta in (start, end) for rho in (inner, outer) for y in (-half, half)])
    return trimesh.convex.convex_hull(corners)


def _count(value, name) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 1:
        raise ArchError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _finite(value, name) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real) or not math.isfinite(value):
        raise ArchError(f"{name} must be a finite real number, got {value!r}")
    return float(value)


def _positive(value, name) -> float:
    value = _finite(value, name)
    if value <= 0:
        raise ArchError(f"{name} must be > 0, got {value}")
    return value
