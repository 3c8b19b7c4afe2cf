"""Deprecated: the markers of interlock's files moved to :mod:`interlock.formats.common`; the old path is removed in
interlock 0.3.
"""

from interlock import deprecation

__all__: list[str] = []

_NAMES = ["MeshFile", "file_header", "header_counts", "flagged_name", "named_frame", "touching_bodies", "json_value",
          "is_label_pair", "stored_meaning", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA", "FIXED_DATA", "FIXED_WORD",
          "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE", "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY", "INFO_KEY",
          "GLTF_TO_Z_UP", "GLTF_SUFFIXES"]

__getattr__ = deprecation.moved(__name__, dict.fromkeys(_NAMES, "interlock.formats.common"))
