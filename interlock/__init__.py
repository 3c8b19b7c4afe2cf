"""interlock: interlocking assemblies of rigid blocks.

Generate assemblies with crystallographic symmetry (``interlock.wallpaper``,
``interlock.blocks``), export them (``interlock.gallery``) and prove or
disprove that they interlock (``interlock.verify``).

>>> import interlock
>>> interlock.wallpaper.group("p6").point_group_order
6
"""

__version__ = "0.1.0"

from interlock import wallpaper
from interlock.errors import GalleryError, GroupError, InterlockError, LatticeError

__all__ = ["InterlockError", "GroupError", "LatticeError", "GalleryError", "wallpaper", "__version__"]
