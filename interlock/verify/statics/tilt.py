"""The tilting test of the CRA paper (Table 2): gravity turned about an axis, and the critical tilt angle."""

from __future__ import annotations

import math

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.verify.statics.cra import decider
from interlock.verify.statics.equilibrium import DEFAULT_SIDES, EquilibriumSystem, StabilityError, positive

__all__ = ["critical_tilt", "tilted_gravity", "TILT_AXES", "DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL"]

#: Named tilt axes of the CRA paper's Table 2: rotate-x, rotate-y, rotate-xy30 = (sqrt 3, 1, 0).
TILT_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "xy30": (math.sqrt(3.0), 1.0, 0.0)}
#: Coarse step (degrees) of the tilt scan before bisection, and the bisection tolerance (degrees).
DEFAULT_TILT_STEP = 5.0
DEFAULT_TILT_TOL = 0.1


def tilted_gravity(axis, angle: float, gravity=(0.0, 0.0, -1.0)) -> np.ndarray:
    """Gravity in the frame of an assembly turned counter-clockwise by ``angle`` degrees about ``axis``.

    Turning the assembly by ``R`` under fixed gravity ``g`` (the paper's tilting
    test, Table 2) is turning gravity by ``R^T``: ``R(axis, -angle) g``.

    Examples
    --------
    >>> tilted_gravity("x", 90).round(12).tolist()
    [0.0, -1.0, -0.0]
    """
    axis = _axis(axis)
    theta = -math.radians(float(angle))
    g = np.asarray(gravity, dtype=float)
    return (g * math.cos(theta) + np.cross(axis, g) * math.sin(theta)
            + axis * (axis @ g) * (1.0 - math.cos(theta)))


def critical_tilt(assembly: Assembly, axis, mu: float, method: str = "rbe", density: float = 1.0,
                  frame=None, cone: str = "paper", sides: int = DEFAULT_SIDES, step: float = DEFAULT_TILT_STEP,
                  tol: float = DEFAULT_TILT_TOL, contacts=None, cra_options=None, progress=None) -> float:
    """The smallest tilt angle (degrees, in [0, 180]) at which the assembly is no longer stable.

    The assembly is turned counter-clockwise about ``axis`` ("x", "y", "xy30" =
    ``(sqrt 3, 1, 0)`` as in the CRA paper's Table 2, or a horizontal or any
    3-vector) under gravity ``(0, 0, -1)`` (:func:`tilted_gravity`).  Angles are
    scanned in steps of ``step`` until the first unstable one, then bisected to
    ``tol``.  Returns 180 when every scanned angle up to 180 is stable (the
    paper's "180.0").  The contact system is built once; each angle is one LP.

    Parameters
    ----------
    method : {"rbe", "cra"}
        :func:`rbe` (one LP per angle) or :func:`~interlock.verify.statics.cra.cra`
        (coupled rigid-block analysis); an angle where CRA is "inconclusive"
        counts as not stable, so the CRA angle errs on the safe side.
    cra_options : dict, optional
        Keyword arguments for :func:`~interlock.verify.statics.cra.cra` (``eps``, ``eta``, ``sectors``,
        ``force_bound``, ``min_slide``, ``time_limit``).
    step, tol : float
        Scan step and bisection tolerance in degrees; a stable window narrower
        than ``step`` after the first unstable angle cannot be missed, but an
        unstable window narrower than ``step`` can.
    progress : callable, optional
        Called as ``progress(angle, stable)`` after each angle is decided (the CLI's progress bar).

    Other parameters are those of :func:`rbe`.

    Examples
    --------
    >>> import trimesh
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> stack = Assembly.from_meshes(cubes, frame=[0])
    >>> angle = critical_tilt(stack, "x", mu=0.5)
    >>> abs(angle - math.degrees(math.atan(0.5))) <= 0.1
    True
    """
    if method not in ("rbe", "cra"):
        raise StabilityError(f"method must be 'rbe' or 'cra', got {method!r}")
    if cra_options and method != "cra":
        raise StabilityError("cra_options apply to method='cra' only")
    step, tol = positive("step", step), positive("tol", tol)
    axis = _axis(axis)
    if method == "rbe":
        system = EquilibriumSystem.build(assembly, mu, density, frame, cone, sides, contacts)

        def decide(angle: float) -> bool:
            return system.feasible(tilted_gravity(axis, angle))
    else:
        stable_under = decider(assembly, mu, density=density, frame=frame, cone=cone, sides=sides,
                               contacts=contacts, **(cra_options or {}))

        def decide(angle: float) -> bool:
            return stable_under(tilted_gravity(axis, angle)) is True

    def stable(angle: float) -> bool:
        verdict = decide(angle)
        if progress is not None:
            progress(angle, verdict)
        return verdict

    if not stable(0.0):
        return 0.0
    low = 0.0
    while low < 180.0:
        high = min(low + step, 180.0)
        if not stable(high):
            break
        low = high
    else:
        return 180.0
    while high - low > tol:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if stable(middle) else (low, middle)
    return round(high, 10)


def _axis(axis) -> np.ndarray:
    if isinstance(axis, str):
        if axis not in TILT_AXES:
            raise StabilityError(f"tilt axis must be one of {tuple(TILT_AXES)} or a 3-vector, got {axis!r}")
        axis = TILT_AXES[axis]
    axis = np.asarray(axis, dtype=float)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.linalg.norm(axis) > 0:
        raise StabilityError(f"tilt axis must be a finite, non-zero 3-vector, got {axis.tolist()}")
    return axis / np.linalg.norm(axis)
