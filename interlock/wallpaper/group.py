"""Wallpaper groups with a lattice: elements, fundamental domain, side pairings, orbits."""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property

import numpy as np
import shapely

from interlock.errors import GroupError, InterlockError
from interlock.wallpaper.elements import GroupElement, Vector, parse_symop
from interlock.wallpaper.lattice import LatticeParameters, conventional_basis, lattice_parameters
from interlock.wallpaper.tables import GROUPS, TABLES, GroupTable

__all__ = ["WallpaperGroup", "SidePairing", "group", "MAX_ELEMENTS"]

#: Relative tolerance (of the disc radius) for "tile meets the disc" in ``elements_within``.
MEETS_RTOL = 1e-9
#: The most candidate tiles :meth:`WallpaperGroup.elements_within` tests unless its ``max_elements`` says
#: more, counted before any is made: each candidate costs about 1 KB (a group element of fractions, its tile),
#: so the default is about 10 GB at most, a hundred times the candidates of the largest patch the block
#: generators make by default (``interlock.blocks.limits.MAX_BLOCKS``).  ``p4`` within a radius of 1e6 would
#: be 1.6e13 candidates (a 29 TiB array of translations alone).
MAX_ELEMENTS = 10_000_000

# Columns: the primitive basis vectors in conventional coordinates of a centred cell.
_CENTRED_TO_PRIMITIVE = ((Fraction(1, 2), Fraction(1, 2)), (Fraction(-1, 2), Fraction(1, 2)))
_IDENTITY = ((Fraction(1), Fraction(0)), (Fraction(0), Fraction(1)))


@dataclass(frozen=True)
class SidePairing:
    """The element ``g`` glueing edge ``edge`` of F to the tile across it.

    ``F`` and ``g(F)`` meet along edge ``edge`` (their interiors are disjoint)
    and ``g`` maps edge ``partner`` of F onto edge ``edge``.  The pairing is an
    involution: the pairing of ``partner`` is ``g.inverse()``, back to
    ``edge``.  An edge on a mirror line is paired with itself by the reflection.
    """

    edge: int
    partner: int
    element: GroupElement

    @property
    def kind(self) -> str:
        """'translation', 'rotation', 'reflection' or 'glide reflection'."""
        return self.element.kind

    @property
    def self_paired(self) -> bool:
        return self.edge == self.partner


def group(name: str, a: float = 1.0, b: float | None = None, gamma: float | None = None) -> WallpaperGroup:
    """The wallpaper group ``name`` acting on the plane with the given lattice.

    Parameters
    ----------
    name : str
        One of :data:`interlock.wallpaper.GROUPS` (short international symbols,
        e.g. ``"p4g"``, ``"p31m"``).
    a, b : float
        Lengths of the conventional cell edges; ``b`` defaults to ``a``.  For
        ``cm`` and ``cmm`` they are the edges of the centred rectangular cell,
        and :attr:`WallpaperGroup.lattice` is the primitive basis
        ``((a/2, -b/2), (a/2, b/2))``.
    gamma : float
        Angle between the cell edges in degrees.  Defaults: 90 (rectangular,
        square), 120 (hexagonal), 75 (oblique: p1, p2).

    Raises
    ------
    GroupError
        Unknown group name.
    LatticeError
        Parameters outside the crystal system (p4 with gamma = 100, a
        negative length, NaN, gamma = 0).

    Examples
    --------
    >>> g = group("p4", a=2.0)
    >>> g.point_group_order, round(g.fundamental_domain().area, 12)
    (4, 1.0)
    """
    if not isinstance(name, str) or name not in TABLES:
        raise GroupError(f"unknown wallpaper group {name!r}; choose one of: {' '.join(GROUPS)}")
    table = TABLES[name]
    return WallpaperGroup(table, lattice_parameters(name, table.crystal_system, a, b, gamma))


class WallpaperGroup:
    """A plane crystallographic group with a concrete lattice.

    Elements are exact :class:`GroupElement` objects in lattice coordinates of
    the primitive basis (the rows of :attr:`lattice`), so the translation
    subgroup is exactly ``Z^2`` and every element is ``t_n r_i`` for one coset
    representative ``r_i`` and one integer vector ``n``.  Geometry (matrices,
    tiles) is in Cartesian coordinates.

    Build one with :func:`group`.
    """

    def __init__(self, table: GroupTable, parameters: LatticeParameters):
        self.name = table.name
        self.crystal_system = table.crystal_system
        self.parameters = parameters
        P = _CENTRED_TO_PRIMITIVE if table.centred else _IDENTITY
        P_inv = _inverse_2x2(P)
        conventional = conventional_basis(parameters)
        lattice = np.array([[float(P[0][i]), float(P[1][i])] for i in range(2)]) @ conventional
        lattice.setflags(write=False)
        #: 2x2, rows are the primitive basis vectors in Cartesian coordinates.
        self.lattice = lattice
        self.cosets: tuple[GroupElement, ...] = tuple(
            _change_basis(parse_symop(op), P, P_inv) for op in table.operations
        )
        self.domain_vertices: tuple[Vector, ...] = tuple(
            _mul_vec(P_inv, (Fraction(x), Fraction(y))) for x, y in table.domain
        )
        self._coset_of_linear = {g.linear: i for i, g in enumerate(self.cosets)}
        to_cartesian = np.eye(3)
        to_cartesian[:2, :2] = lattice.T
        self._to_cartesian = to_cartesian
        self._to_lattice = np.linalg.inv(to_cartesian)

    # --- basic data ----------------------------------------------------------
    @property
    def point_group_order(self) -> int:
        """``|G / T|``: the number of cosets of the translation subgroup (blocks per cell)."""
        return len(self.cosets)

    @property
    def cell_area(self) -> float:
        """Area of the primitive cell."""
        return float(abs(np.linalg.det(self.lattice)))

    def __repr__(self) -> str:
        p = self.parameters
        return f"group({self.name!r}, a={p.a:g}, b={p.b:g}, gamma={p.gamma:g})"

    def __eq__(self, other) -> bool:
        return isinstance(other, WallpaperGroup) and (self.name, self.parameters) == (other.name, other.parameters)

    def __hash__(self) -> int:
        return hash((self.name, self.parameters))

    # --- elements ------------------------------------------------------------
    @property
    def identity(self) -> GroupElement:
        return self.cosets[0]

    def decompose(self, g: GroupElement) -> tuple[int, tuple[int, int]]:
        """``(i, n)`` with ``g = t_n r_i``; raises :class:`GroupError` if g is not in the group."""
        i = self._coset_of_linear.get(g.linear)
        if i is not None:
            n = tuple(g.translation[k] - self.cosets[i].translation[k] for k in range(2))
            if all(x.denominator == 1 for x in map(Fraction, n)):
                return i, (int(n[0]), int(n[1]))
        raise GroupError(f"{g} (lattice coordinates) is not an element of {self.name}")

    def contains(self, g: GroupElement) -> bool:
        try:
            self.decompose(g)
        except GroupError:
            return False
        return True

    def element(self, coset: int, shift=(0, 0)) -> GroupElement:
        """``t_shift r_coset``."""
        if not 0 <= coset < len(self.cosets):
            raise GroupError(f"{self.name} has cosets 0..{len(self.cosets) - 1}, not {coset}")
        return self.cosets[coset].shifted(shift)

    def matrix(self, g) -> np.ndarray:
        """The 3x3 affine matrix of ``g`` in Cartesian coordinates."""
        if isinstance(g, GroupElement):
            return self._to_cartesian @ g.affine() @ self._to_lattice
        if isinstance(g, (str, bytes)):
            raise InterlockError(f"expected a GroupElement or a finite 3x3 affine matrix, got the text {g!r}; "
                                 "read a symmetry operation with interlock.wallpaper.parse_symop (lattice "
                                 "coordinates), or take one of the group's elements (group.cosets, group.element)")
        try:
            m = np.asarray(g, dtype=float)
        except (TypeError, ValueError):
            raise InterlockError(f"expected a GroupElement or a finite 3x3 affine matrix, got "
                                 f"{type(g).__name__} {g!r:.60}") from None
        if m.shape != (3, 3) or not np.all(np.isfinite(m)):
            raise InterlockError(f"expected a GroupElement or a finite 3x3 affine matrix, got shape {m.shape}")
        return m

    def matrices(self, elements) -> np.ndarray:
        """Cartesian 3x3 matrices of many elements, shape ``(n, 3, 3)``."""
        lattice_affine = np.array([g.affine() for g in elements]).reshape(-1, 3, 3)
        return self._to_cartesian @ lattice_affine @ self._to_lattice

    def coset_representatives(self) -> np.ndarray:
        """The ``point_group_order`` coset representatives as Cartesian 3x3 matrices.

        Representative 0 is the identity.
        """
        return self.matrices(self.cosets)

    def to_3d(self, g) -> np.ndarray:
        """The 4x4 matrix of ``g`` acting on ``(x, y)`` and fixing ``z``."""
        m = self.matrix(g)
        out = np.eye(4)
        out[:2, :2] = m[:2, :2]
        out[:2, 3] = m[:2, 2]
        return out

    def is_orientation_preserving(self, g) -> bool:
        """Whether ``g`` preserves orientation (no reflection or glide)."""
        if isinstance(g, GroupElement):
            return g.det == 1
        return bool(np.linalg.det(self.matrix(g)[:2, :2]) > 0)

    # --- geometry ------------------------------------------------------------
    def to_cartesian(self, points) -> np.ndarray:
        """Lattice coordinates (rows) to Cartesian."""
        return np.asarray(points, dtype=float) @ self.lattice

    def to_lattice(self, points) -> np.ndarray:
        """Cartesian coordinates (rows) to lattice coordinates."""
        return np.asarray(points, dtype=float) @ np.linalg.inv(self.lattice)

    def fundamental_domain(self) -> shapely.Polygon:
        """The fundamental domain F, counter-clockwise, in Cartesian coordinates.

        Every rotation centre on its boundary is a vertex; its area is
        ``cell_area / point_group_order``.  Edge ``i`` runs from vertex ``i``
        to vertex ``i + 1`` (these are the edge indices used by
        :meth:`side_pairings` and by block deformations).
        """
        return shapely.Polygon(self.to_cartesian([[float(x), float(y)] for x, y in self.domain_vertices]))

    @cached_property
    def _side_pairings(self) -> tuple[SidePairing, ...]:
        return tuple(self._pair_edge(e) for e in range(len(self.domain_vertices)))

    def side_pairings(self) -> tuple[SidePairing, ...]:
        """For each edge ``e`` of F: its partner edge and ``g_e`` with ``F ∩ g_e(F) ⊇ e``.

        ``g_e`` maps the partner edge onto ``e`` and the tile ``g_e(F)`` lies
        across ``e`` (docs/wallpaper.md; main paper Sec. 4.1).
        Computed exactly in lattice coordinates.

        >>> [(s.edge, s.partner, s.kind) for s in group("p4").side_pairings()]
        [(0, 3, 'rotation'), (1, 2, 'rotation'), (2, 1, 'rotation'), (3, 0, 'rotation')]
        """
        return self._side_pairings

    def tiles(self, elements) -> np.ndarray:
        """The tiles ``g(F)`` as an array of shapely polygons."""
        mats = self.matrices(elements)
        domain = np.asarray(self.fundamental_domain().exterior.coords)[:-1]
        coords = np.einsum("nij,vj->nvi", mats[:, :2, :2], domain) + mats[:, None, :2, 2]
        return shapely.polygons(coords)

    def elements_within(self, radius: float, center=None,
                        max_elements: int = MAX_ELEMENTS) -> tuple[GroupElement, ...]:
        """Every ``g`` whose tile ``g(F)`` meets the closed disc of ``radius`` about ``center``.

        ``center`` defaults to the centroid of F.  Elements come sorted by the
        distance of their tile from the centre (the identity first), ties
        broken by coset and translation, so the order is reproducible.

        Raises
        ------
        InterlockError
            A radius or centre that is not a finite number (point), or more
            candidate tiles than ``max_elements`` (default
            :data:`MAX_ELEMENTS`), counted before any is made.

        Notes
        -----
        For each coset the candidate translations come from a bounding circle
        of the tile, then shapely measures the exact distance of each
        candidate tile from the centre: ``O(k (r / a)^2)`` for k cosets.

        >>> len(group("p1", gamma=90).elements_within(0.4))
        1
        >>> group("p4").elements_within(1e6)  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        interlock.errors.InterlockError: p4: the tiles within radius 1e+06 are about 1.6e+13 candidates, more than ...
        """
        radius = _finite_number(radius, "radius")
        if isinstance(max_elements, bool) or not isinstance(max_elements, int) or max_elements < 1:
            raise InterlockError(f"max_elements must be an integer >= 1, got {max_elements!r}")
        if radius < 0:
            raise InterlockError(f"radius must be >= 0, got {radius}")
        domain = self.fundamental_domain()
        center = np.array(domain.centroid.coords[0]) if center is None else np.asarray(center, dtype=float)
        if center.shape != (2,) or not np.all(np.isfinite(center)):
            raise InterlockError(f"center must be a finite point (x, y), got {center!r}")
        candidates = []
        base_tiles = self.tiles(self.cosets)
        inverse_lattice = np.linalg.inv(self.lattice)
        windows = []
        for tile in base_tiles:
            corners = np.asarray(tile.exterior.coords)[:-1]
            mid = corners.mean(axis=0)
            reach = radius + np.linalg.norm(corners - mid, axis=1).max()
            # lattice coordinates of translations n with |mid + n L - center| <= reach
            with np.errstate(over="ignore", invalid="ignore"):
                n_center = (center - mid) @ inverse_lattice
                half = reach * np.linalg.norm(inverse_lattice, axis=0)
            windows.append((mid, reach, n_center, half))
        count = sum(math.prod(2 * float(h) + 3 for h in half) for _, _, _, half in windows)
        far = max(float(np.abs(n).max()) + float(h.max()) for _, _, n, h in windows)
        if not count <= max_elements:  # also NaN and inf
            raise InterlockError(f"{self.name}: the tiles within radius {radius:g} are about {count:.2g} candidates, "
                                 f"more than max_elements={max_elements:,} (about 1 KB each); give a smaller radius "
                                 "(in model units: the cell is "
                                 f"{math.sqrt(self.cell_area):.3g} across), or raise max_elements")
        if not far < 2.0**53:  # translations beyond 2**53 cells are not exact integers in float64
            raise InterlockError(f"{self.name}: the disc of radius {radius:g} about {center.tolist()} reaches "
                                 f"{far:.3g} cells from the origin, beyond 2**53, where float64 cannot tell one "
                                 "cell from the next; move the centre nearer the origin or shrink the radius")
        for i, (mid, reach, n_center, half) in enumerate(windows):
            ranges = [np.arange(math.floor(c - h), math.ceil(c + h) + 1) for c, h in zip(n_center, half)]
            shifts = np.stack(np.meshgrid(*ranges, indexing="ij"), axis=-1).reshape(-1, 2)
            near = np.linalg.norm(mid + shifts @ self.lattice - center, axis=1) <= reach * (1 + MEETS_RTOL)
            candidates.extend((i, tuple(int(v) for v in n)) for n in shifts[near])
        elements = [self.element(i, n) for i, n in candidates]
        distance = shapely.distance(self.tiles(elements), shapely.Point(center)) if elements else np.empty(0)
        keep = distance <= radius * (1 + MEETS_RTOL) + MEETS_RTOL * math.sqrt(self.cell_area)
        order = sorted(
            (round(float(d) / math.sqrt(self.cell_area), 9), c) for d, c, k in zip(distance, candidates, keep) if k
        )
        return tuple(self.element(i, n) for _, (i, n) in order)

    # --- internals -----------------------------------------------------------
    def _pair_edge(self, e: int) -> SidePairing:
        vertices = self.domain_vertices
        count = len(vertices)
        va, vb = vertices[e], vertices[(e + 1) % count]
        inside = (sum(v[0] for v in vertices) / count, sum(v[1] for v in vertices) / count)
        found = []
        for r in self.cosets:
            for f in range(count):
                wa, wb = r.apply_exact(vertices[f]), r.apply_exact(vertices[(f + 1) % count])
                for pa, pb in ((wa, wb), (wb, wa)):
                    shift = (va[0] - pa[0], va[1] - pa[1])
                    if shift != (vb[0] - pb[0], vb[1] - pb[1]) or any(Fraction(s).denominator != 1 for s in shift):
                        continue
                    g = r.shifted(shift)
                    q = g.apply_exact(inside)
                    if (vb[0] - va[0]) * (q[1] - va[1]) - (vb[1] - va[1]) * (q[0] - va[0]) < 0:
                        found.append(SidePairing(e, f, g))
        if len(found) != 1:  # a defect of the tables, not of user input
            raise AssertionError(f"{self.name}: edge {e} has {len(found)} tiles across it; the domain table is wrong")
        return found[0]


def _finite_number(value, name) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InterlockError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(value):
        raise InterlockError(f"{name} must be finite, got {value}")
    return value


def _inverse_2x2(m):
    (a, b), (c, d) = m
    det = a * d - b * c
    return ((d / det, -b / det), (-c / det, a / det))


def _mul_vec(m, v) -> Vector:
    return (m[0][0] * v[0] + m[0][1] * v[1], m[1][0] * v[0] + m[1][1] * v[1])


def _mul(m, n):
    return tuple(tuple(sum(m[i][k] * n[k][j] for k in range(2)) for j in range(2)) for i in range(2))


def _change_basis(g: GroupElement, P, P_inv) -> GroupElement:
    """Rewrite ``g`` from conventional to primitive lattice coordinates: ``P^-1 g P``."""
    linear = _mul(_mul(P_inv, g.linear), P)
    if any(Fraction(x).denominator != 1 for row in linear for x in row):
        raise AssertionError(f"{g} is not integral in the primitive basis")
    return GroupElement(
        tuple(tuple(int(x) for x in row) for row in linear), _mul_vec(P_inv, g.translation)
    )
