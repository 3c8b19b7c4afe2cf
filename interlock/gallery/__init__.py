"""Exports, pictures and the gallery of generated and verified assemblies.

- :func:`export`: a block, an assembly or a mesh to STL, OBJ, PLY, GLB, 3MF, VTU or XDMF.
- :func:`render`: a PNG of a block, an assembly (also exploded) or a 2D tiling.
- :func:`build`: the gallery of :func:`entries`, each verified, exported and drawn, with ``index.html``.
"""

from interlock.gallery.appearance import as_assembly, block_classes, block_colours, exploded
from interlock.gallery.builder import Gallery, build, entries
from interlock.gallery.export import FORMATS, export
from interlock.gallery.render import render

__all__ = ["export", "render", "build", "entries", "Gallery", "FORMATS", "as_assembly", "block_classes",
           "block_colours", "exploded"]
