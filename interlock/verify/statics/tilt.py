"""The tilting test of the CRA paper (Table 2): gravity turned about an axis, and the critical tilt angle."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.verify.statics.cra import decider
from interlock.verify.statics.equilibrium import (DEFAULT_SIDES, Budget, EquilibriumSystem, StabilityError,
                                                  TimeLimitReached, json_float, positive)

__all__ = ["critical_tilt", "tilt_scan", "TiltScan", "tilted_gravity", "TILT_AXES", "DEFAULT_TILT_STEP",
           "DEFAULT_TILT_TOL"]

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


@dataclass(frozen=True)
class TiltScan:
    """The outcome of :func:`tilt_scan`: the critical tilt angle and how every scanned angle was decided.

    Attributes
    ----------
    angle : float
        The smallest angle (degrees) not proved stable: the critical tilt when every angle was decided (180
        when all were stable), otherwise the safe side of it.
    status : {"decided", "inconclusive"}
        "decided" when the bracket ``(stable_below, angle)`` has a stable and an unstable end; "inconclusive"
        when ``angle`` is an undecided angle (a solver did not decide, or the time limit was reached).
    stable_below : float
        The largest angle proved stable below ``angle`` (``angle`` itself when it is 0).
    undecided : tuple of (float, str)
        The angles no solver decided, with the reason; the scan went on past them.
    angles : tuple of (float, bool or None)
        Every angle tried, in order, with its verdict (``None``: undecided).
    parameters : dict
        ``method``, ``axis``, ``mu``, ``step``, ``tol``, ``time_limit``.
    seconds : float
    """

    angle: float
    status: str
    stable_below: float
    undecided: tuple
    angles: tuple = field(repr=False)
    parameters: dict = field(default_factory=dict)
    seconds: float = 0.0

    def __float__(self) -> float:
        return float(self.angle)

    def __str__(self) -> str:
        method = self.parameters.get("method", "rbe").upper()
        if self.status == "decided":
            words = ("stable up to 180 degrees" if self.angle >= 180 else
                     f"{self.angle:.1f} degrees")
            return f"{method} critical tilt: {words} ({len(self.angles)} angles, {self.seconds:.3g} s)"
        first, reason = self.undecided[-1]
        return (f"{method} critical tilt inconclusive: stable up to {self.stable_below:.1f} degrees, undecided at "
                f"{first:.2f} degrees ({reason}); {len(self.undecided)} undecided of {len(self.angles)} angles, "
                f"{self.seconds:.3g} s")

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {"angle": json_float(self.angle), "status": self.status, "stable_below": json_float(self.stable_below),
                "undecided": [[json_float(a), why] for a, why in self.undecided],
                "angles": [[json_float(a), verdict] for a, verdict in self.angles],
                "parameters": dict(self.parameters), "seconds": self.seconds}


def critical_tilt(assembly: Assembly, axis, mu: float, method: str = "rbe", density: float = 1.0,
                  frame=None, cone: str = "paper", sides: int = DEFAULT_SIDES, step: float = DEFAULT_TILT_STEP,
                  tol: float = DEFAULT_TILT_TOL, contacts=None, cra_options=None, progress=None,
                  time_limit=None) -> float:
    """The smallest tilt angle (degrees, in [0, 180]) at which the assembly is no longer stable.

    The assembly is turned counter-clockwise about ``axis`` ("x", "y", "xy30" =
    ``(sqrt 3, 1, 0)`` as in the CRA paper's Table 2, or a horizontal or any
    3-vector) under gravity ``(0, 0, -1)`` (:func:`tilted_gravity`).  Angles are
    scanned in steps of ``step`` until the first unstable one, then bisected to
    ``tol``.  Returns 180 when every scanned angle up to 180 is stable (the
    paper's "180.0").  The contact system is built once; each angle is one LP.
    This is ``float(tilt_scan(...))``: an angle that no solver decides counts as
    not stable (the safe side), and :func:`tilt_scan` says which and why.

    Parameters
    ----------
    method : {"rbe", "cra"}
        :func:`rbe` (one LP per angle) or :func:`~interlock.verify.statics.cra.cra`
        (coupled rigid-block analysis); an angle where CRA is "inconclusive"
        counts as not stable, so the CRA angle errs on the safe side.
    cra_options : dict, optional
        Keyword arguments for :func:`~interlock.verify.statics.cra.cra` (``eps``, ``eta``, ``sectors``,
        ``force_bound``, ``min_slide``, ``milp_nodes``, ``time_limit``: seconds per angle).
    step, tol : float
        Scan step and bisection tolerance in degrees; a stable window narrower
        than ``step`` after the first unstable angle cannot be missed, but an
        unstable window narrower than ``step`` can.
    progress : callable, optional
        Called as ``progress(angle, stable)`` after each angle is decided (``stable`` ``None``: undecided;
        the CLI's progress bar).
    time_limit : float, optional
        Seconds for the whole scan (default: no limit); the angle at which they run out is undecided.

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
    return float(tilt_scan(assembly, axis, mu, method=method, density=density, frame=frame, cone=cone, sides=sides,
                           step=step, tol=tol, contacts=contacts, cra_options=cra_options, progress=progress,
                           time_limit=time_limit))


def tilt_scan(assembly: Assembly, axis, mu: float, method: str = "rbe", density: float = 1.0, frame=None,
              cone: str = "paper", sides: int = DEFAULT_SIDES, step: float = DEFAULT_TILT_STEP,
              tol: float = DEFAULT_TILT_TOL, contacts=None, cra_options=None, progress=None,
              time_limit=None) -> TiltScan:
    """The tilt scan of :func:`critical_tilt`, with every angle's verdict and the undecided ones' reasons.

    An angle that no solver decides (RBE: Clarabel and HiGHS all stop undecided, e.g. curve-3-blocks about
    ``(1, -1, 0)`` at 48.75 degrees, where HiGHS' simplex ends in its status 15; CRA: "inconclusive") is
    recorded with the reason and counts as not stable, and the scan goes on below it.  The result is
    "inconclusive" when the angle it returns is such an undecided angle.  When ``time_limit`` runs out, the
    angle being decided is undecided ("time limit reached in ...") and the scan stops.  Parameters as for
    :func:`critical_tilt`.

    Examples
    --------
    >>> import trimesh
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> scan = tilt_scan(Assembly.from_meshes(cubes, frame=[0]), "x", mu=0.5)
    >>> scan.status, round(scan.angle, 1), scan.undecided
    ('decided', 26.6, ())
    """
    if method not in ("rbe", "cra"):
        raise StabilityError(f"method must be 'rbe' or 'cra', got {method!r}")
    if cra_options and method != "cra":
        raise StabilityError("cra_options apply to method='cra' only")
    step, tol = positive("step", step), positive("tol", tol)
    axis = _axis(axis)
    budget = Budget.start(time_limit)
    started = time.perf_counter()
    if method == "rbe":
        system = EquilibriumSystem.build(assembly, mu, density, frame, cone, sides, contacts, budget)

        def decide(angle: float):
            return system.feasible(tilted_gravity(axis, angle), budget)
    else:
        stable_under = decider(assembly, mu, density=density, frame=frame, cone=cone, sides=sides,
                               contacts=contacts, budget=budget, **(cra_options or {}))

        def decide(angle: float):
            result = stable_under(tilted_gravity(axis, angle), budget)
            return result.stable, result.message

    angles, undecided = [], []

    def stable(angle: float) -> bool:
        try:
            verdict, why = decide(angle)
        except TimeLimitReached as out:
            verdict, why = None, str(out)
        angles.append((angle, verdict))
        if verdict is None:
            undecided.append((angle, why))
        if progress is not None:
            progress(angle, verdict)
        return verdict is True

    def result(low: float, high: float) -> TiltScan:
        decided = dict(angles).get(high) is not None or high >= 180.0
        parameters = {"method": method, "axis": axis.tolist(), "mu": mu, "step": step, "tol": tol,
                      "time_limit": time_limit}
        return TiltScan(round(high, 10), "decided" if decided else "inconclusive", round(low, 10),
                        tuple(undecided), tuple(angles), parameters, time.perf_counter() - started)

    def out_of_time() -> bool:
        return bool(undecided) and undecided[-1][1].startswith("time limit")

    if not stable(0.0):
        return result(0.0, 0.0)
    low = 0.0
    while low < 180.0:
        high = min(low + step, 180.0)
        if not stable(high):
            break
        low = high
    else:
        return result(180.0, 180.0)
    while high - low > tol and not out_of_time():
        middle = 0.5 * (low + high)
        low, high = (middle, high) if stable(middle) else (low, middle)
    return result(low, high)


def _axis(axis) -> np.ndarray:
    if isinstance(axis, str):
        if axis not in TILT_AXES:
            raise StabilityError(f"tilt axis must be one of {tuple(TILT_AXES)} or a 3-vector, got {axis!r}")
        axis = TILT_AXES[axis]
    axis = np.asarray(axis, dtype=float)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.linalg.norm(axis) > 0:
        raise StabilityError(f"tilt axis must be a finite, non-zero 3-vector, got {axis.tolist()}")
    return axis / np.linalg.norm(axis)
