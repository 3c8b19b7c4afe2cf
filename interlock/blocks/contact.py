"""A contact between two blocks: the polygon where their faces meet, its normal and plane."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely

from interlock.errors import InterlockError

__all__ = ["Contact", "ContactError", "plane_bases", "CONTACT_KINDS"]

#: The contact types of the main paper's Remark 3.11 that the contact search finds (edge-face contacts are
#: segments whose ends are vertex-face or edge-edge contacts).
CONTACT_KINDS = ("face", "vertex-face", "edge-edge", "vertex-edge", "vertex-vertex")


class ContactError(InterlockError):
    """Input that a contact cannot be made of (not an assembly, bad tolerances, bad points)."""


@dataclass(frozen=True, eq=False)
class Contact:
    """One face-to-face contact polygon between blocks ``i < j`` (one row group of Def. 3.3).

    Attributes
    ----------
    i, j : int
        The blocks in contact, ``i < j``.
    normal : array (3,)
        Unit normal pointing from block ``i`` towards block ``j`` (block ``i``'s
        outward facet normal).
    vertices : array (k, 3)
        The overlap polygon on block ``i``'s facet plane (with ``gap > 0``: on
        the parallel plane halfway to block ``j``'s facet, see :func:`contacts`):
        the exterior ring (counter-clockwise about ``normal``, no closing
        repeat), then each hole ring.  Every vertex gives rows of the
        interlocking matrix.
    area : float
        Area of the polygon.
    facet_i, facet_j : int
        Indices of the touching facets in :func:`facets` of each block.
    polygon : shapely.Polygon
        The polygon in 2D plane coordinates: ``origin + x * basis[0] + y * basis[1]``.
    origin : array (3,)
        A point of the plane (the centroid of block ``i``'s facet, moved halfway
        to block ``j``'s facet when ``gap > 0``).
    basis : array (2, 3)
        Orthonormal in-plane vectors with ``basis[0] x basis[1] = normal``.
    deviation : float
        How far the blocks' real faces stray from the modelled common plane
        over this contact: the flatness of either facet (:attr:`Facets.flatness`);
        a gap between them is its :attr:`separation`, never a bend.  Zero up
        to rounding for faces that really are coplanar.
    planar : bool
        Both facets are planar up to rounding (:attr:`Facets.planar`).  When
        False, the tolerances merged triangles bent by a small angle into one
        facet: the real contact has several planes, so it may block a sliding
        motion that the modelled one allows.  A gap does not make a contact
        non-planar: two parallel planar faces a gap apart block no sliding
        either (see :func:`contacts`).
    separation : float
        The gap this contact bridges: zero for faces that touch (coplanar
        within ``rtol``, and always when ``gap = 0``); for a contact found only
        thanks to ``gap > 0``, the largest distance from block ``j``'s facet
        plane of the overlap's vertices on block ``i``'s facet plane (at most
        ``(rtol + gap) * scale``).  In the local model (default search), the
        largest gap between the two faces over the contact, when beyond
        their coordinates' last place: a gap within the tolerance is a
        contact whose play a verdict reports.
    tolerance : float or None
        How far the real faces may be from the modelled contact (a length):
        the rounding of the two blocks' coordinates
        (:mod:`interlock.verify.precision`) plus, for faces bent within the
        tolerances, twice their bend.  None for contacts given by hand
        (:meth:`at_points`): the verdict reads it off the blocks.
    kind : str
        The contact type of Remark 3.11 (:data:`CONTACT_KINDS`): ``"face"``
        (a polygon of positive area), ``"vertex-face"``, ``"edge-edge"``
        (two edges crossing, not parallel), ``"vertex-edge"`` or
        ``"vertex-vertex"``; a point contact has one vertex, the contact
        point, and zero area.
    normals : array (k, 3) or None
        None when the contact admits one normal (``normal``): each vertex
        gives one row of the interlocking matrix.  Otherwise the generators
        of the cone of admissible normals (degenerate vertex-edge,
        vertex-vertex and parallel-edge touches): non-penetration to first
        order says only that *some* normal of the cone separates, which is
        no linear row (docs/interlocking.md, "Contacts of every type").
    """

    i: int
    j: int
    normal: np.ndarray
    vertices: np.ndarray
    area: float
    facet_i: int
    facet_j: int
    polygon: shapely.Polygon = field(repr=False)
    origin: np.ndarray = field(repr=False)
    basis: np.ndarray = field(repr=False)
    deviation: float = 0.0
    planar: bool = True
    separation: float = 0.0
    tolerance: float | None = None
    kind: str = "face"
    normals: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def at_points(cls, i: int, j: int, normal, points) -> Contact:
        """A point or line contact given by hand: block ``j``'s points ``points`` on block ``i``'s face.

        :func:`contacts` finds face-to-face contacts only (Remark 3.11); a
        corner or an edge of block ``j`` resting on a face of block ``i``
        (outward unit ``normal``, towards ``j``) gives one row of the
        interlocking matrix per point, and the gap function of
        :mod:`interlock.verify.second_order` (an n-pod leg, ``docs/npod.md``).

        >>> c = Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0], [1, 0, 0]])
        >>> len(c.vertices), c.area
        (2, 0.0)
        """
        if not (isinstance(i, (int, np.integer)) and isinstance(j, (int, np.integer)) and 0 <= i < j):
            raise ContactError(f"a contact needs block indices 0 <= i < j, got {i!r}, {j!r}")
        n = np.asarray(normal, dtype=float).reshape(-1)
        vertices = np.asarray(points, dtype=float).reshape(-1, 3) if np.size(points) else np.zeros((0, 3))
        if n.shape != (3,) or not np.isfinite(n).all() or not np.linalg.norm(n) > 0:
            raise ContactError(f"normal must be a non-zero finite 3D vector, got {normal!r}")
        if not len(vertices) or not np.isfinite(vertices).all():
            raise ContactError("points must be one or more finite 3D points, shape (k, 3)")
        n = n / np.linalg.norm(n)
        basis = plane_bases(n[None])[0]
        origin = vertices.mean(axis=0)
        for array in (n, vertices, origin, basis):
            array.setflags(write=False)
        return cls(int(i), int(j), n, vertices, 0.0, -1, -1, shapely.Polygon(), origin, basis)

    @property
    def ring_sizes(self) -> tuple[int, ...]:
        """Vertex counts of the exterior ring and of each hole, in the order of :attr:`vertices`."""
        if self.polygon.is_empty:  # a point or line contact (:meth:`at_points`)
            return (len(self.vertices),)
        rings = [self.polygon.exterior, *self.polygon.interiors]
        return tuple(len(ring.coords) - 1 for ring in rings)

    def __str__(self) -> str:
        n = ", ".join(f"{x:.3g}" for x in self.normal)
        if self.kind != "face":
            p = ", ".join(f"{x:.6g}" for x in self.vertices[0])
            cone = f", a cone of {len(self.normals)} normals" if self.normals is not None else ""
            return f"{self.kind} contact {self.i}-{self.j} at ({p}), normal ({n}){cone}"
        holes = len(self.ring_sizes) - 1
        extra = f" with {holes} hole(s)" if holes else ""
        bent = "" if self.planar else f", faces bent by up to {self.deviation:.3g} (planar only within tolerance)"
        apart = f", across a gap of up to {self.separation:.3g}" if self.separation else ""
        return (f"contact {self.i}-{self.j}: {len(self.vertices)} vertices{extra}, area {self.area:.6g}, "
                f"normal ({n}), facets {self.facet_i}/{self.facet_j}{bent}{apart}")

    def to_dict(self) -> dict:
        """JSON-serialisable form; ``ring_sizes`` splits ``vertices`` into exterior and holes."""
        return {"i": self.i, "j": self.j, "normal": self.normal.tolist(), "vertices": self.vertices.tolist(),
                "ring_sizes": list(self.ring_sizes), "area": self.area, "facet_i": self.facet_i,
                "facet_j": self.facet_j, "origin": self.origin.tolist(), "basis": self.basis.tolist(),
                "deviation": self.deviation, "planar": self.planar, "separation": self.separation,
                **({} if self.kind == "face" else {"kind": self.kind}),
                **({} if self.normals is None else {"normals": self.normals.tolist()})}

    @classmethod
    def from_dict(cls, data: dict) -> Contact:
        """The contact :meth:`to_dict` describes (as read back from a file).

        The arrays come back exactly; the plane polygon is rebuilt from the
        vertices in the plane's coordinates (to rounding).  A point or line
        contact (:meth:`at_points`: zero area, one ring) has no polygon.

        >>> c = Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0], [1, 0, 0]])
        >>> back = Contact.from_dict(c.to_dict())
        >>> back.to_dict() == c.to_dict()
        True
        """
        try:
            arrays = [np.array(data[key], dtype=float) for key in ("normal", "vertices", "origin", "basis")]
            sizes = [int(k) for k in data["ring_sizes"]]
            i, j, area = int(data["i"]), int(data["j"]), float(data["area"])
            facets = int(data["facet_i"]), int(data["facet_j"])
            extra = float(data["deviation"]), bool(data["planar"]), float(data["separation"])
            kind = str(data.get("kind", "face"))
            normals = None if data.get("normals") is None else np.array(data["normals"], dtype=float).reshape(-1, 3)
        except (KeyError, TypeError, ValueError) as error:
            raise ContactError(f"not a stored contact (as Contact.to_dict writes it): {error}") from None
        normal, vertices, origin, basis = arrays
        if (normal.shape != (3,) or vertices.ndim != 2 or vertices.shape[1:] != (3,) or origin.shape != (3,)
                or basis.shape != (2, 3) or sum(sizes) != len(vertices) or not 0 <= i < j):
            raise ContactError(f"a stored contact {i}-{j} has arrays of the wrong shapes or ring sizes {sizes}")
        polygon = shapely.Polygon()
        if area > 0 or len(sizes) > 1:
            rings = np.split((vertices - origin) @ basis.T, np.cumsum(sizes)[:-1])
            polygon = shapely.Polygon(rings[0], rings[1:])
        if kind not in CONTACT_KINDS:
            raise ContactError(f"a stored contact {i}-{j} has an unknown kind {kind!r}")
        for array in arrays + ([] if normals is None else [normals]):
            array.setflags(write=False)
        return cls(i, j, normal, vertices, area, *facets, polygon, origin, basis, *extra, kind=kind, normals=normals)


def plane_bases(normals):
    """Orthonormal (u, v) per unit normal n with u x v = n."""
    axis = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    u = np.cross(normals, axis)
    u /= np.linalg.norm(u, axis=1)[:, None]
    return np.stack([u, np.cross(normals, u)], axis=1)

