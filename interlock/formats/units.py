"""Units and up-axes of files: the names interlock knows, and assemblies converted between them.

An :class:`~interlock.blocks.Assembly` carries its length unit (``assembly.unit``: ``"mm"``, ``"m"``, ``"in"``,
..., or None for a model without one).  Readers set it from what a file states (``.3dm``'s model unit system,
3MF's ``unit``, glTF's metres, interlock's own header); writers state it, and convert coordinates only where the
format fixes the unit (glTF: metres).  A size never changes silently: :func:`converted` keeps every size,
:func:`scaled` changes them on request only.
"""

from __future__ import annotations

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.formats.common import GLTF_TO_Z_UP, FormatError

__all__ = ["UNITS", "UP_AXES", "unit_name", "converted", "scaled", "turned", "up_axis", "with_unit", "METRES"]

#: The units interlock knows, by their short name: metres per unit.
METRES = {"um": 1e-6, "mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}
#: The short names of :data:`METRES`, smallest first.
UNITS = tuple(METRES)
#: The up-axes a file without a convention of its own may be written with (``up=``).
UP_AXES = ("z", "y")
# other spellings of the units: 3MF's, Rhino's, and common words
_SPELLINGS = {"micron": "um", "microns": "um", "micrometer": "um", "micrometre": "um", "micrometers": "um",
              "micrometres": "um", "millimeter": "mm", "millimetre": "mm", "millimeters": "mm", "millimetres": "mm",
              "centimeter": "cm", "centimetre": "cm", "centimeters": "cm", "centimetres": "cm", "meter": "m",
              "metre": "m", "meters": "m", "metres": "m", "inch": "in", "inches": "in", "foot": "ft", "feet": "ft",
              "µm": "um"}


def unit_name(unit) -> str | None:
    """The short name of ``unit`` (:data:`UNITS`), from any usual spelling; None stays None.

    >>> unit_name("Millimeters"), unit_name("inch"), unit_name(None)
    ('mm', 'in', None)
    """
    if unit is None:
        return None
    if isinstance(unit, str):
        word = unit.strip().lower()
        word = _SPELLINGS.get(word, word)
        if word in METRES:
            return word
    raise FormatError(f"unknown unit {unit!r}; use one of {', '.join(UNITS)} (or None for a model without unit)")


def up_axis(up, suffix: str = "") -> str:
    """``up`` checked: ``"z"`` or ``"y"`` (:data:`UP_AXES`)."""
    if isinstance(up, str) and up.strip().lower() in UP_AXES:
        return up.strip().lower()
    raise FormatError(f"up must be 'z' or 'y'{f' for {suffix} files' if suffix else ''}, got {up!r}")


def scaled(assembly: Assembly, factor: float) -> Assembly:
    """The assembly with every coordinate multiplied by ``factor`` (its unit kept): sizes change by ``factor``.

    >>> from interlock.blocks import presets
    >>> float(scaled(presets.cube_grid(), 2.0).volumes[0])
    8.0
    """
    if isinstance(factor, bool) or not np.isfinite(factor) or not factor > 0:
        raise FormatError(f"a scale must be a finite number > 0, got {factor!r}")
    factor = float(factor)
    if factor == 1.0:
        return assembly
    meshes = [mesh.copy() for mesh in assembly.meshes]
    for mesh in meshes:
        mesh.vertices = np.asarray(mesh.vertices) * factor
    transforms = assembly.transforms.copy()
    transforms[:, :3, 3] *= factor
    lattice = None if assembly.lattice is None else np.asarray(assembly.lattice) * factor
    return Assembly(meshes, assembly.types, transforms, assembly.labels, assembly.frame, lattice,
                    getattr(assembly, "_boundary", None), assembly.info)


def converted(assembly: Assembly, unit) -> Assembly:
    """The assembly in ``unit``, every size kept: coordinates converted from its unit; an assembly without
    unit is declared in ``unit`` (coordinates unchanged).

    >>> from interlock.blocks import presets
    >>> cm = converted(with_unit(presets.cube_grid(), "m"), "cm")
    >>> cm.unit, round(float(cm.volumes[0]))  # a cube of 1 m is 1,000,000 cm^3
    ('cm', 1000000)
    """
    unit = unit_name(unit)
    if unit is None or assembly.unit == unit:
        return assembly
    result = assembly if assembly.unit is None else scaled(assembly, METRES[assembly.unit] / METRES[unit])
    return with_unit(result, unit)


def with_unit(assembly: Assembly, unit) -> Assembly:
    """The same blocks stated in ``unit`` (no coordinate changes)."""
    unit = unit_name(unit)
    info = {key: value for key, value in assembly.info.items() if key != "unit"}
    if unit is not None:
        info["unit"] = unit
    return Assembly(assembly.meshes, assembly.types, assembly.transforms, assembly.labels, assembly.frame,
                    assembly.lattice, getattr(assembly, "_boundary", None), info)


def turned(assembly: Assembly, up: str) -> Assembly:
    """The assembly turned from interlock's +Z up to ``up`` (``"y"``: by the inverse of
    :data:`~interlock.formats.common.GLTF_TO_Z_UP`, exact); ``"z"`` gives it back."""
    if up == "z":
        return assembly
    transforms = GLTF_TO_Z_UP.T @ assembly.transforms
    return Assembly(assembly.meshes, assembly.types, transforms, assembly.labels, assembly.frame, None, None,
                    assembly.info)
