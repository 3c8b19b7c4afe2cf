"""Deprecated: Rhino ``.3dm`` files moved to :mod:`interlock.formats.rhino`; the old path is removed in interlock 0.3.
"""

from interlock import deprecation

__all__: list[str] = []

_NAMES = ["write_3dm", "read_3dm_blocks", "RhinoError", "FRAME_LAYER", "MARKER_KEY", "INFO_KEY", "MISSING_MESSAGE",
          "RHINO_VERSION", "LAYER_COLOURS"]

__getattr__ = deprecation.moved(__name__, dict.fromkeys(_NAMES, "interlock.formats.rhino"))
