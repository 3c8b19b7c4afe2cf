"""The exception hierarchy: every error raised on bad input is an ``InterlockError``."""

__all__ = ["InterlockError", "GroupError", "LatticeError", "AssemblyError", "GalleryError"]


class InterlockError(ValueError):
    """Root of all errors that ``interlock`` raises on bad input.

    It is a ``ValueError``, so callers that already catch ``ValueError`` keep
    working.  Messages say what was wrong and what would be right.
    """


class GroupError(InterlockError):
    """An unknown wallpaper group or an element that is not in the group."""


class LatticeError(InterlockError):
    """Lattice parameters that are not allowed for the group's crystal system."""


class AssemblyError(InterlockError):
    """Meshes, transforms, labels, a frame or a file that do not form an assembly."""


class GalleryError(InterlockError):
    """Something that cannot be exported, drawn or written: an unknown format, a bad path, a wrong object."""
