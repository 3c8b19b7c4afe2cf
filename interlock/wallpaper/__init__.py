"""The 17 plane crystallographic (wallpaper) groups that assemblies are generated from.

>>> from interlock import wallpaper
>>> g = wallpaper.group("p6")
>>> g.point_group_order, len(g.side_pairings())
(6, 4)
"""

from interlock.wallpaper.elements import GroupElement, parse_symop
from interlock.wallpaper.group import SidePairing, WallpaperGroup, group
from interlock.wallpaper.tables import GROUPS

__all__ = ["GROUPS", "group", "WallpaperGroup", "GroupElement", "SidePairing", "parse_symop"]
