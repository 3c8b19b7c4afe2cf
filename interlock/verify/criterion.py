"""Criterion 4.3 of the main paper, decided exactly through the subgroup of deformed side pairings."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from interlock.blocks.escher import DEFORMATION_RTOL, Block
from interlock.errors import InterlockError
from interlock.wallpaper import GroupElement, WallpaperGroup

__all__ = ["CriterionResult", "criterion_4_3", "MAX_FINITE_ORDER", "UNION_RTOL", "ROUNDING_ULPS"]

#: Finite subgroups of a plane crystallographic group have at most 12 elements (p6m's point group).
MAX_FINITE_ORDER = 12
#: The unions of h(F) and h(F') agree when their symmetric difference is below this times the cell area.
UNION_RTOL = 1e-9
#: Offsets of an intermediate point from its edge's line up to this many units in the last place are rounding.
ROUNDING_ULPS = 8


@dataclass(frozen=True)
class CriterionResult:
    """Whether Criterion 4.3 holds, with the finite witness ``H`` when it does not.

    Attributes
    ----------
    holds : bool or None
        True when no finite set of tiles is bounded by undeformed edges only;
        None when that depends on ``uncertain_edges``.
    group : str
    deformed_edges : tuple of int
    generators : tuple of GroupElement
        The side pairings ``g_e`` of the deformed edges.
    witness : tuple of GroupElement or None
        When the criterion fails: the finite subgroup ``H = S``, identity first.
    union_difference : float or None
        For a block that fails: the area of the symmetric difference of
        ``U h(F)`` and ``U h(F')`` over ``h`` in ``H`` (about 0: the blocks of
        ``H`` can be lifted together).
    uncertain_edges : tuple of int
        Edges whose intermediate points are off the edge's line by more than
        rounding but not more than the generator's tolerance: floating point
        cannot say whether they are deformed.
    """

    holds: bool | None
    group: str
    deformed_edges: tuple[int, ...]
    generators: tuple[GroupElement, ...]
    witness: tuple[GroupElement, ...] | None = None
    union_difference: float | None = None
    uncertain_edges: tuple[int, ...] = ()

    def __str__(self) -> str:
        if self.holds is None:
            return (f"Criterion 4.3 is inconclusive for {self.group}: it holds if edges {list(self.uncertain_edges)} "
                    "count as deformed and fails if not, and their points lie within the tolerance of the edge")
        if self.holds:
            return f"Criterion 4.3 holds for {self.group} with deformed edges {list(self.deformed_edges)}"
        return (f"Criterion 4.3 fails for {self.group} with deformed edges {list(self.deformed_edges)}: the "
                f"{len(self.witness)} blocks of H = {{{', '.join(map(str, self.witness))}}} can be lifted together")

    def to_dict(self) -> dict:
        return {
            "holds": self.holds,
            "group": self.group,
            "deformed_edges": list(self.deformed_edges),
            "generators": [str(g) for g in self.generators],
            "witness": None if self.witness is None else [str(h) for h in self.witness],
            "union_difference": self.union_difference,
            "uncertain_edges": list(self.uncertain_edges),
        }


def criterion_4_3(block_or_group, deformed_edges=None) -> CriterionResult:
    """Decide Criterion 4.3 (main paper Sec. 4) for an Escher block, or a group and its deformed edges.

    The criterion asks that no finite set ``H`` of group elements has
    ``H(F) = H(F')``.  The tiles reachable from ``F`` across deformed edges
    are ``S(F)`` with ``S = <g_e : e deformed>`` (``g(F)`` and ``g g_e(F)``
    meet along ``g(e)``), so a finite union of tiles bounded by undeformed
    edges only exists iff ``S`` is finite (docs/criterion.md, "From unions of tiles
    to a subgroup").  Finite subgroups of a wallpaper group have order at most 12,
    so a closure of ``S`` that passes 12 elements proves the criterion; a
    closed ``S`` is the witness ``H``.  Exact arithmetic throughout.

    Parameters
    ----------
    block_or_group : Block or WallpaperGroup
    deformed_edges : iterable of int, optional
        With a group: the deformed edges of its fundamental domain (partners
        are added).  With a block: the edges with an intermediate point off
        the edge's line by more than the generator's tolerance
        (:data:`~interlock.blocks.escher.DEFORMATION_RTOL`); points on the
        edge leave ``F'`` equal to ``F`` there.

    Returns
    -------
    CriterionResult
        For a failing block, also the geometric check ``U h(F) = U h(F')``.

    Examples
    --------
    >>> from interlock import wallpaper
    >>> p6 = wallpaper.group("p6")
    >>> criterion_4_3(p6, [0]).holds, len(criterion_4_3(p6, [0]).witness)  # only the 6-fold pair: a hexagon
    (False, 6)
    >>> criterion_4_3(p6, [0, 1]).holds
    True
    """
    if isinstance(block_or_group, Block):
        block, group = block_or_group, block_or_group.group
        if deformed_edges is not None:
            raise InterlockError("give deformed_edges only with a group; a block knows its deformed edges")
        edges, uncertain = _geometrically_deformed(block)
        if uncertain and _decide(group, edges | uncertain) != _decide(group, edges):
            return CriterionResult(None, group.name, tuple(sorted(edges)), (), uncertain_edges=tuple(sorted(uncertain)))
    elif isinstance(block_or_group, WallpaperGroup):
        block, group = None, block_or_group
        edges = _edges(group, deformed_edges)
    else:
        raise InterlockError(f"criterion_4_3 needs an Escher Block or a WallpaperGroup, got {type(block_or_group).__name__}")
    pairings = group.side_pairings()
    edges |= {pairings[e].partner for e in edges}
    generators = tuple(dict.fromkeys(pairings[e].element for e in sorted(edges)))
    closure = _closure(group.identity, generators)
    if closure is None:
        return CriterionResult(True, group.name, tuple(sorted(edges)), generators)
    difference = None
    if block is not None:
        bottoms = shapely.union_all(group.tiles(closure))
        tops = shapely.union_all(_images(group, block.top, closure))
        difference = float(shapely.symmetric_difference(bottoms, tops).area)
        if difference > UNION_RTOL * group.cell_area:
            raise AssertionError(f"{group.name}: the witness H does not satisfy H(F) = H(F') (difference {difference})")
    return CriterionResult(False, group.name, tuple(sorted(edges)), generators, closure, difference)


def _decide(group, edges) -> bool:
    """Whether Criterion 4.3 holds with these deformed edges (partners added)."""
    pairings = group.side_pairings()
    edges = edges | {pairings[e].partner for e in edges}
    return _closure(group.identity, tuple(dict.fromkeys(pairings[e].element for e in sorted(edges)))) is None


def _closure(identity, generators):
    """The subgroup generated by ``generators`` (identity first), or None when it passes MAX_FINITE_ORDER."""
    elements = [identity]
    seen = {identity}
    frontier = [identity]
    while frontier:
        new = []
        for g in frontier:
            for s in generators:
                for h in (g @ s, g @ s.inverse()):
                    if h not in seen:
                        seen.add(h)
                        elements.append(h)
                        new.append(h)
                        if len(elements) > MAX_FINITE_ORDER:
                            return None
        frontier = new
    return tuple(elements)


def _geometrically_deformed(block) -> tuple[set[int], set[int]]:
    """Edges with an intermediate point off the edge's line, and edges whose points are off it only within tolerance.

    A point farther than the generator's tolerance deforms its edge; one
    within rounding (:data:`ROUNDING_ULPS`) lies on the line; in between,
    floating point cannot tell.
    """
    group = block.group
    corners = shapely.get_coordinates(group.fundamental_domain().exterior)[:-1]
    tol = DEFORMATION_RTOL * group.cell_area ** 0.5
    rounding = ROUNDING_ULPS * np.finfo(float).eps * float(np.abs(corners).max())
    deformed, uncertain = set(), set()
    for e, points in block.deformation.items():
        if len(points):
            p, q = corners[e], corners[(e + 1) % len(corners)]
            direction = (q - p) / ((q - p) @ (q - p)) ** 0.5
            offset = float(np.abs((points - p) @ [-direction[1], direction[0]]).max())
            if offset > tol:
                deformed.add(int(e))
            elif offset > rounding:
                uncertain.add(int(e))
    return deformed, uncertain - deformed


def _images(group, polygon, elements):
    coords = shapely.get_coordinates(polygon)
    out = []
    for g in elements:
        m = group.matrix(g)
        out.append(shapely.Polygon(coords @ m[:2, :2].T + m[:2, 2]))
    return out


def _edges(group, deformed_edges) -> set[int]:
    count = len(group.side_pairings())
    edges = set()
    for e in [] if deformed_edges is None else deformed_edges:
        if isinstance(e, bool) or not isinstance(e, int) or not 0 <= e < count:
            raise InterlockError(f"edge {e!r} does not exist: the fundamental domain of {group.name} has edges "
                                 f"0..{count - 1}")
        edges.add(e)
    return edges
