"""Deprecated: moved to :mod:`interlock.verify.statics.cra_local`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.statics.cra_local`.
NAMES = ("ACTIVE_TOL", "last_resort", "least_friction", "polish", "realise", "realise_least_friction",
         "settled_motion", "snap", "verify_local")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.statics.cra_local"))
