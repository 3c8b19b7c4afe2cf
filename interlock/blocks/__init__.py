"""Blocks from deformed fundamental domains, RhomBlocks, and assemblies of them.

Each name is imported on first use (:func:`interlock.lazy_exports`).

>>> from interlock import wallpaper
>>> from interlock.blocks import escher_block, patch
>>> X = escher_block(wallpaper.group("p6"), {0: [(0.25, 0.08)], 1: [(0.55, 0.15)]})
>>> len(patch(X, 1.0))
31
"""

from interlock import lazy_exports

__all__ = ["Assembly", "AssemblyError", "Block", "DeformationError", "escher_block", "patch", "periodic_cell",
           "cell_patch", "cell_reach",
           "presets", "Lozenge", "LozengeTiling", "TilingError", "random_hexagon", "staircase", "rhomblock",
           "rhomblock_assembly", "semicircular_arch"]

# where each exported name lives (presets is a subpackage); load_3dm and load_compas are deprecated aliases
# (files moved to interlock.formats: interlock.read), importable until interlock 0.3 but not in __all__
_HOMES = {
    "semicircular_arch": "interlock.blocks.arch",
    **dict.fromkeys(["Assembly", "AssemblyError", "load_3dm", "load_compas"], "interlock.blocks.assembly"),
    **dict.fromkeys(["Block", "DeformationError", "escher_block"], "interlock.blocks.escher"),
    **dict.fromkeys(["Lozenge", "LozengeTiling", "TilingError", "random_hexagon", "staircase"],
                    "interlock.blocks.lozenge"),
    **dict.fromkeys(["cell_patch", "cell_reach", "patch", "periodic_cell"], "interlock.blocks.orbits"),
    **dict.fromkeys(["rhomblock", "rhomblock_assembly"], "interlock.blocks.rhomblock"),
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
