"""Deprecated: OBJ files moved to :mod:`interlock.formats.obj` (``read_obj``, ``write_obj``); the old path is removed
in interlock 0.3.
"""

from interlock import deprecation

__all__: list[str] = []

__getattr__ = deprecation.moved(__name__, {})
