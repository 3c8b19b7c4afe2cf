"""Pictures, pages and the gallery of generated and verified assemblies (files are :func:`interlock.write`'s).

- :func:`render`: a PNG of a block, an assembly (also exploded) or a 2D tiling.
- :func:`write_view`: an interactive, offline 3D view of an assembly and its verdicts (one HTML file).
- :func:`build`: the gallery of :func:`entries`, each verified, written and drawn, with ``index.html``.
- :func:`exploded`: an assembly with its blocks moved apart, to write or draw.

Writing files moved to :mod:`interlock.formats` (:func:`interlock.write`); ``export`` and ``FORMATS`` here are
deprecated aliases, removed in interlock 0.3.  Each name is imported on first use
(:func:`interlock.lazy_exports`).
"""

from interlock import deprecation, lazy_exports

__all__ = ["render", "build", "entries", "Gallery", "as_assembly", "block_classes", "block_colours", "exploded",
           "write_view"]

# where each exported name lives; export is the deprecated alias of interlock.write (it warns when called)
_HOMES = {
    **dict.fromkeys(["as_assembly", "block_classes", "block_colours", "exploded"], "interlock.gallery.appearance"),
    **dict.fromkeys(["Gallery", "build", "entries"], "interlock.gallery.builder"),
    "export": "interlock.gallery.export",
    "render": "interlock.gallery.render",
    "write_view": "interlock.gallery.view.page",
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES,
                                    fallback=deprecation.moved(__name__, {"FORMATS": "interlock.formats.readwrite"}))
