"""Deprecated: moved to :mod:`interlock.verify.statics.cra`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.statics.cra`.
NAMES = ("CRAResult", "DEFAULT_EPS", "DEFAULT_ETA", "DEFAULT_FORCE_BOUND", "DEFAULT_MIN_SLIDE",
         "DEFAULT_SECTORS", "REFINED_SECTORS", "cra")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.statics.cra"))
