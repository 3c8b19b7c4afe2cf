"""The 17 plane groups as data, in the conventional settings of the International Tables.

For each group: its crystal system, its coordinate triplets (one per coset of
the translation subgroup, conventional cell), whether the conventional cell is
centred, and a fundamental domain in conventional fractional coordinates.

The domains are the Tables' asymmetric units with every rotation centre on
their boundary inserted as a vertex, and with edges split where the tiling by
the domain would otherwise not be edge-to-edge (e.g. pg, where the glide maps
half an edge onto the other half).  Vertices are counter-clockwise and edge
``i`` runs from vertex ``i`` to vertex ``i + 1``.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["GROUPS", "GroupTable", "TABLES", "SPACE_GROUP_NUMBERS"]


@dataclass(frozen=True)
class GroupTable:
    name: str
    crystal_system: str  # 'oblique', 'rectangular', 'centred rectangular', 'square', 'hexagonal'
    operations: tuple[str, ...]  # coset representatives, conventional cell
    domain: tuple[tuple[str, str], ...]  # vertices, conventional fractional coordinates
    centred: bool = False


_P4 = ("x,y", "-x,-y", "-y,x", "y,-x")
_P3 = ("x,y", "-y,x-y", "-x+y,-x")
_P6 = _P3 + ("-x,-y", "y,-x+y", "x-y,x")

_ROWS = [
    GroupTable("p1", "oblique", ("x,y",), (("0", "0"), ("1", "0"), ("1", "1"), ("0", "1"))),
    GroupTable(
        "p2", "oblique", ("x,y", "-x,-y"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("1/2", "1"), ("0", "1"), ("0", "1/2")),
    ),
    GroupTable("pm", "rectangular", ("x,y", "-x,y"), (("0", "0"), ("1/2", "0"), ("1/2", "1"), ("0", "1"))),
    GroupTable(
        "pg", "rectangular", ("x,y", "-x,y+1/2"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("1/2", "1"), ("0", "1"), ("0", "1/2")),
    ),
    GroupTable(
        "cm", "centred rectangular", ("x,y", "-x,y"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("0", "1/2")), centred=True,
    ),
    GroupTable(
        "pmm", "rectangular", ("x,y", "-x,-y", "-x,y", "x,-y"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("0", "1/2")),
    ),
    GroupTable(
        "pmg", "rectangular", ("x,y", "-x,-y", "-x+1/2,y", "x+1/2,-y"),
        (("0", "0"), ("1/4", "0"), ("1/4", "1"), ("0", "1"), ("0", "1/2")),
    ),
    GroupTable(
        "pgg", "rectangular", ("x,y", "-x,-y", "-x+1/2,y+1/2", "x+1/2,-y+1/2"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("0", "1/2")),
    ),
    GroupTable(
        "cmm", "centred rectangular", ("x,y", "-x,-y", "-x,y", "x,-y"),
        (("0", "0"), ("1/4", "0"), ("1/4", "1/4"), ("1/4", "1/2"), ("0", "1/2")), centred=True,
    ),
    GroupTable("p4", "square", _P4, (("0", "0"), ("1/2", "0"), ("1/2", "1/2"), ("0", "1/2"))),
    GroupTable(
        "p4m", "square", _P4 + ("-x,y", "x,-y", "y,x", "-y,-x"),
        (("0", "0"), ("1/2", "0"), ("1/2", "1/2")),
    ),
    GroupTable(
        "p4g", "square", _P4 + ("-x+1/2,y+1/2", "x+1/2,-y+1/2", "y+1/2,x+1/2", "-y+1/2,-x+1/2"),
        (("0", "0"), ("1/2", "0"), ("0", "1/2")),
    ),
    GroupTable("p3", "hexagonal", _P3, (("0", "0"), ("2/3", "1/3"), ("1/3", "2/3"), ("-1/3", "1/3"))),
    GroupTable(
        "p3m1", "hexagonal", _P3 + ("-y,-x", "-x+y,y", "x,x-y"),
        (("0", "0"), ("2/3", "1/3"), ("1/3", "2/3")),
    ),
    GroupTable(
        "p31m", "hexagonal", _P3 + ("y,x", "x-y,-y", "-x,-x+y"),
        (("0", "0"), ("1", "0"), ("2/3", "1/3")),
    ),
    GroupTable("p6", "hexagonal", _P6, (("0", "0"), ("1/2", "0"), ("2/3", "1/3"), ("1/2", "1/2"))),
    GroupTable(
        "p6m", "hexagonal", _P6 + ("-y,-x", "-x+y,y", "x,x-y", "y,x", "x-y,-y", "-x,-x+y"),
        (("0", "0"), ("1/2", "0"), ("2/3", "1/3")),
    ),
]

TABLES: dict[str, GroupTable] = {row.name: row for row in _ROWS}

#: The 17 short names, in the order of the International Tables.
GROUPS: tuple[str, ...] = tuple(TABLES)

#: Space-group numbers of the layer ``G x Z`` (G acting on x, y; z periodic), as spglib reports them.
SPACE_GROUP_NUMBERS: dict[str, int] = {
    "p1": 1, "p2": 3, "pm": 6, "pg": 7, "cm": 8, "pmm": 25, "pmg": 28, "pgg": 32, "cmm": 35,
    "p4": 75, "p4m": 99, "p4g": 100, "p3": 143, "p3m1": 156, "p31m": 157, "p6": 168, "p6m": 183,
}
