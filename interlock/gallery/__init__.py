"""Exports, pictures and the gallery of generated and verified assemblies.

- :func:`export`: a block, an assembly or a mesh to STL, OBJ, PLY, GLB, 3MF, VTU or XDMF.
- :func:`render`: a PNG of a block, an assembly (also exploded) or a 2D tiling.
- :func:`write_view`: an interactive, offline 3D view of an assembly and its verdicts (one HTML file).
- :func:`build`: the gallery of :func:`entries`, each verified, exported and drawn, with ``index.html``.

Each name is imported on first use (:func:`interlock.lazy_exports`): exporting does not load matplotlib.
"""

from interlock import lazy_exports

__all__ = ["export", "render", "build", "entries", "Gallery", "FORMATS", "as_assembly", "block_classes",
           "block_colours", "exploded", "write_view"]

# where each exported name lives
_HOMES = {
    **dict.fromkeys(["as_assembly", "block_classes", "block_colours", "exploded"], "interlock.gallery.appearance"),
    **dict.fromkeys(["Gallery", "build", "entries"], "interlock.gallery.builder"),
    **dict.fromkeys(["FORMATS", "export"], "interlock.gallery.export"),
    "render": "interlock.gallery.render",
    "write_view": "interlock.gallery.view.page",
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
