"""Deprecated: writing files moved to :mod:`interlock.formats` (:func:`interlock.write`); the gallery keeps
pictures and pages.  ``export`` and the old names here are removed in interlock 0.3."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from interlock import deprecation
from interlock.formats import write
from interlock.formats.common import exploded_factor
from interlock.gallery import appearance

__all__ = ["export"]


def export(obj, path, exploded=0.0, progress=None) -> Path:
    """Deprecated alias of :func:`interlock.write` (after :func:`~interlock.gallery.appearance.exploded` for
    ``exploded > 0``), removed in interlock 0.3.

    Callers inside interlock not yet moved to ``interlock.write`` are not warned.
    """
    caller = sys._getframe(1).f_globals.get("__name__", "")
    if not caller.startswith("interlock."):
        warnings.warn("interlock.gallery.export moved to interlock.write (interlock.formats.write); the old path is "
                      f"removed in interlock {deprecation.REMOVED_IN}", DeprecationWarning, stacklevel=2)
    factor = exploded_factor(exploded)
    assembly = appearance.as_assembly(obj)
    return write(appearance.exploded(assembly, factor) if factor else assembly, path, progress=progress)


__getattr__ = deprecation.moved(__name__, {
    **dict.fromkeys(["FORMATS", "LABELLED_FORMATS"], "interlock.formats.readwrite"),
    "STL_MAX_BLOCKS": "interlock.formats.stl"})
