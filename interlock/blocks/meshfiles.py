"""Deprecated: reading mesh files moved to :mod:`interlock.formats` (:func:`interlock.read`); the old path is removed
in interlock 0.3.
"""

from interlock import deprecation

__all__: list[str] = []

_NAMES = ["MeshFile", "file_header", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA", "FIXED_DATA", "FIXED_WORD",
          "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE", "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY", "INFO_KEY",
          "GLTF_TO_Z_UP", "GLTF_SUFFIXES"]

__getattr__ = deprecation.moved(
    __name__, {"read_mesh_file": "interlock.formats", **dict.fromkeys(_NAMES, "interlock.formats.common")})
