"""Deprecated: moved to :mod:`interlock.verify.statics`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.statics`.
NAMES = ("CONES", "DEFAULT_SIDES", "DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL", "StabilityError",
         "StabilityResult", "TILT_AXES", "critical_tilt", "rbe", "tilted_gravity")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.statics"))
