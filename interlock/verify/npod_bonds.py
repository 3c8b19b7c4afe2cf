"""Deprecated: moved to :mod:`interlock.verify.npod.bonds`; this path is removed in interlock 0.3."""

from interlock.deprecation import moved

#: The public names of the old module, now in :mod:`interlock.verify.npod.bonds`.
NAMES = ("BOND_TOL", "BondConditions", "BondSearch", "COLLINEAR_RTOL", "DEGENERATE_TOL", "ProjectionBond",
         "REFINE_EVALUATIONS", "SEARCH_SAMPLES", "SEARCH_STARTS", "SIMILARITY_TOL", "bond_conditions",
         "projection_bonds")

__getattr__ = moved(__name__, dict.fromkeys(NAMES, "interlock.verify.npod.bonds"))
