"""Deprecated: moved to :mod:`interlock.verify.statics.cra_compas`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.statics.cra_compas`.
NAMES = ("MISSING_MESSAGE", "UPSTREAM_VERSION", "upstream_motion", "upstream_solution")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.statics.cra_compas"))
