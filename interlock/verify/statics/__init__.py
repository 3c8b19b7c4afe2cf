"""Stability under self-weight: rigid-block equilibrium (RBE), coupled rigid-block analysis (CRA), the tilt test.

The contact model (interfaces of faces that meet approximately) is in
:mod:`~interlock.verify.statics.interfaces` (``interfaces(assembly)``; the module keeps its name, so
the function is not re-exported here); the shared equilibrium problem is in
:mod:`~interlock.verify.statics.equilibrium`;
the theory, with the CRA paper's numbering, is in ``docs/statics.md``.

>>> import trimesh
>>> from interlock.blocks import Assembly
>>> from interlock.verify.statics import rbe
>>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
>>> rbe(Assembly.from_meshes(cubes, frame=[0]), mu=0.5).stable
True
"""

from interlock import lazy_exports

# where each exported name lives; each is imported on first use (:func:`interlock.lazy_exports`), so RBE does not
# load CRA's modules
_HOMES = {
    **dict.fromkeys(["DEFAULT_FORCE_BOUND", "DEFAULT_MIN_SLIDE", "DEFAULT_SECTORS", "REFINED_SECTORS", "CRAResult",
                     "cra"], "interlock.verify.statics.cra"),
    **dict.fromkeys(["CONES", "DEFAULT_EPS", "DEFAULT_ETA", "DEFAULT_SIDES", "FRICTION_RTOL", "StabilityError",
                     "StabilityResult"], "interlock.verify.statics.equilibrium"),
    **dict.fromkeys(["DEFAULT_AREA_THICKNESS", "DEFAULT_GAP_THICKNESS", "Interfaces", "compas_interfaces",
                     "thickness"], "interlock.verify.statics.interfaces"),
    "rbe": "interlock.verify.statics.rbe",
    **dict.fromkeys(["DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL", "TILT_AXES", "TiltScan", "critical_tilt", "tilt_scan",
                     "tilted_gravity"], "interlock.verify.statics.tilt"),
}

__all__ = ["rbe", "StabilityResult", "StabilityError", "cra", "CRAResult", "critical_tilt", "tilt_scan", "TiltScan",
           "tilted_gravity",
           "TILT_AXES", "CONES", "DEFAULT_SIDES", "DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL", "DEFAULT_EPS", "DEFAULT_ETA",
           "DEFAULT_SECTORS", "DEFAULT_FORCE_BOUND", "DEFAULT_MIN_SLIDE", "REFINED_SECTORS", "FRICTION_RTOL",
           "Interfaces", "compas_interfaces", "thickness", "DEFAULT_GAP_THICKNESS", "DEFAULT_AREA_THICKNESS"]

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
