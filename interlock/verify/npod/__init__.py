"""n-pods: rigid bodies held by legs of fixed length, their mobility, self-motions and bonds (bond theory paper).

>>> from interlock.verify.npod import npod, mobility
>>> tripod = npod([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
...               pose=([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 2]))
>>> mobility(tripod).mobility
3
"""

from interlock.verify.npod.bonds import (BOND_TOL, COLLINEAR_RTOL, DEGENERATE_TOL, REFINE_EVALUATIONS, SEARCH_SAMPLES,
                                         SEARCH_STARTS, SIMILARITY_TOL, BondConditions, BondSearch, ProjectionBond,
                                         bond_conditions, projection_bonds)
from interlock.verify.npod.continuation import (ARC_LENGTH, MAX_STEPS, MIN_STEP, NEWTON_ITERATIONS, RESIDUAL_TOL, STEP,
                                                SelfMotion, self_motion)
from interlock.verify.npod.mobility import (POSE_RTOL, RANK_RTOL, Mobility, NPod, NPodError, leg_rows, mobility, npod,
                                            pose_arrays)

__all__ = ["NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "pose_arrays", "SelfMotion", "self_motion",
           "BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds",
           "RANK_RTOL", "POSE_RTOL", "STEP", "ARC_LENGTH", "MIN_STEP", "RESIDUAL_TOL", "NEWTON_ITERATIONS", "MAX_STEPS",
           "COLLINEAR_RTOL", "BOND_TOL", "DEGENERATE_TOL", "SIMILARITY_TOL", "SEARCH_SAMPLES", "SEARCH_STARTS",
           "REFINE_EVALUATIONS"]
