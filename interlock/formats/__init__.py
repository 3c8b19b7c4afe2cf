"""Files of assemblies: one module per format, each holding its reader and writer, and one way in and out.

- :func:`read`: an :class:`~interlock.blocks.Assembly` from a file (or a list of files), by its suffix;
- :func:`write`: an assembly (a block, a mesh) to a file, by its suffix.

The formats: :mod:`~interlock.formats.stl`, :mod:`~interlock.formats.obj`, :mod:`~interlock.formats.ply`,
:mod:`~interlock.formats.gltf` (``.glb``), :mod:`~interlock.formats.threemf` (``.3mf``),
:mod:`~interlock.formats.vtu` (``.vtu``, ``.xdmf``), :mod:`~interlock.formats.rhino` (``.3dm``),
:mod:`~interlock.formats.compas` (COMPAS assembly ``.json``); other mesh formats trimesh reads (``.off``, ...)
through :mod:`~interlock.formats.scene`.  Units and up-axes: :mod:`~interlock.formats.units`; what each format
keeps: ``docs/formats.md``.  Each name is imported on first use (:func:`interlock.lazy_exports`).

>>> import tempfile
>>> from pathlib import Path
>>> from interlock.blocks import presets
>>> from interlock.formats import read, write
>>> with tempfile.TemporaryDirectory() as folder:
...     back = read(write(presets.cube_grid(), Path(folder) / "grid.glb", unit="mm"))
>>> len(back), back.unit, back.info["frame_from"]
(9, 'mm', 'file')
"""

from interlock import lazy_exports

__all__ = ["read", "write", "read_mesh_file", "writable_target", "FORMATS", "READ_FORMATS", "LABELLED_FORMATS",
           "UP_CONVENTIONS", "FormatError", "MeshFile", "UNITS", "converted", "scaled", "unit_name"]

# where each exported name lives
_HOMES = {
    **dict.fromkeys(["read", "write", "read_mesh_file", "writable_target", "FORMATS", "READ_FORMATS",
                     "LABELLED_FORMATS", "UP_CONVENTIONS"], "interlock.formats.readwrite"),
    **dict.fromkeys(["FormatError", "MeshFile"], "interlock.formats.common"),
    **dict.fromkeys(["UNITS", "converted", "scaled", "unit_name"], "interlock.formats.units"),
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
