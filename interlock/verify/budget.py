"""Time budgets: one wall-clock limit per call, shared by all of its stages.

A verdict that never comes is worse than "inconclusive".  A call that takes
``time_limit`` starts one :class:`Budget`; every stage asks it how much time is
left (``remaining``), hands that to its solvers (Clarabel's and HiGHS'
``time_limit``), and calls :meth:`Budget.check` between steps.  When the time
is out, :class:`TimeLimitReached` carries the stage's name up to the caller,
which answers "inconclusive: time limit reached in <stage>".  The clock only
ever turns an answer into "inconclusive"; it never chooses between routes, so
verdicts do not depend on the machine's speed.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from numbers import Real

from interlock.errors import InterlockError

__all__ = ["Budget", "TimeLimitReached", "time_limit_value"]


class TimeLimitReached(Exception):
    """The budget ran out during ``stage`` (control flow inside a call, never seen by its caller)."""

    def __init__(self, stage: str):
        super().__init__(f"time limit reached in {stage}")
        self.stage = stage


def time_limit_value(value, name: str = "time_limit") -> float:
    """``value`` as seconds: a number > 0, ``inf`` or None (no limit); InterlockError otherwise.

    >>> time_limit_value(None), time_limit_value(2)
    (inf, 2.0)
    """
    if value is None:
        return math.inf
    if isinstance(value, bool) or not isinstance(value, Real) or math.isnan(value) or value <= 0:
        raise InterlockError(f"{name} must be a number of seconds > 0 (or None for no limit), got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Budget:
    """A wall-clock limit of ``limit`` seconds counted from ``started`` (``time.perf_counter``).

    >>> budget = Budget.start(None)
    >>> budget.remaining() == float("inf"), budget.solver_limit() is None
    (True, True)
    >>> budget.check("rank")  # no limit: never raises
    """

    limit: float = math.inf
    started: float = field(default_factory=time.perf_counter)

    @classmethod
    def start(cls, time_limit=None) -> "Budget":
        """A budget of ``time_limit`` seconds from now (None: unlimited); the value is validated."""
        return cls(time_limit_value(time_limit))

    def remaining(self) -> float:
        """Seconds left (``inf`` without a limit; may be negative once spent)."""
        return self.limit - (time.perf_counter() - self.started)

    def solver_limit(self) -> float | None:
        """The time left as a solver's ``time_limit`` option (at least a millisecond), or None without a limit."""
        return None if math.isinf(self.limit) else max(self.remaining(), 1e-3)

    def check(self, stage: str) -> None:
        """Raise :class:`TimeLimitReached` naming ``stage`` when no time is left."""
        if self.remaining() <= 0:
            raise TimeLimitReached(stage)
