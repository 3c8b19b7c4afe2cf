"""Deprecated: moved to :mod:`interlock.verify.statics.cra_ipopt`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.statics.cra_ipopt`.
NAMES = ("IPOPT_ITERATIONS", "MISSING_MESSAGE", "available", "local_solutions")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.statics.cra_ipopt"))
