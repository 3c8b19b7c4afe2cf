"""Interfaces for statics: contacts between faces that meet only approximately, with tolerances per block pair.

Real structures are modelled with faces that do not quite meet: the CRA paper's
Armadillo vault approximates ruled surfaces by planes, so neighbouring blocks
face each other across small gaps and tilts.  :func:`~interlock.verify.contacts.contacts`
with its defaults finds only faces that touch (what the kinematic verifier
needs); :func:`interfaces` finds the faces that *face* each other, with a rule
relative to each pair's own size.  It is the default contact model of
:func:`~interlock.verify.statics.rbe` and :func:`~interlock.verify.statics.cra`
(``docs/statics.md``, "Interfaces"); :func:`compas_interfaces` reads the
interfaces a COMPAS file stores instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely

from interlock.blocks.assembly import Assembly
from interlock.blocks.contact import Contact, plane_bases
from interlock.errors import InterlockError
from interlock.formats.common import FormatError
from interlock.formats.compas import read_json_document
from interlock.verify.contacts import DEFAULT_CONTACT_RTOL
from interlock.verify.contacts import contacts as find_contacts
from interlock.verify.validate import OverlapError, pair_overlaps, refuse_overlaps_without_contact

__all__ = ["Interfaces", "interfaces", "thickness", "compas_interfaces", "plain_geometry", "statics_contacts",
           "refuse_deep_overlaps", "DEFAULT_GAP_THICKNESS", "DEFAULT_AREA_THICKNESS", "CONTACT_MODELS"]

#: Largest gap between two facing faces, as a fraction of the thinner block's thickness (:func:`thickness`).
#: The armadillo's 1,043 touching pairs (1,014 with a free block, as upstream's interfaces with tmax = 0.05)
#: need up to 0.22 of it (measured: the per-pair smallest separation over the thinner block's thickness:
#: median 0.013, 99 % 0.14, largest 0.22); a quarter finds them all.
DEFAULT_GAP_THICKNESS = 0.25
#: Smallest interface area, as a fraction of the square of the thinner block's thickness (upstream's
#: amin = 1e-4 on the armadillo is 0.003-0.025 of it; the smallest interface found there is 0.013 of it).
DEFAULT_AREA_THICKNESS = 1e-3
#: Values of ``contacts`` that :func:`statics_contacts` understands besides a sequence of contacts.
CONTACT_MODELS = ("interfaces", "exact")


class InterfaceError(InterlockError):
    """Input that interfaces cannot be found or read from (not an assembly, bad tolerances, bad file)."""


@dataclass(frozen=True, eq=False)
class Interfaces:
    """The outcome of :func:`interfaces`: the contacts and the rule that found them.

    Attributes
    ----------
    contacts : tuple of Contact
        As :func:`~interlock.verify.contacts.contacts` returns them (sorted by ``(i, j, facet_i, facet_j)``);
        a contact across a gap lies on the mid-plane and records its ``separation``.
    thickness : ndarray (n,)
        Each block's thickness (:func:`thickness`), in model units.
    gap, angle, area : float
        The rule: per pair ``(i, j)`` with ``t = min(thickness[i], thickness[j])``, faces at most
        ``gap * t`` apart (beyond ``rtol``), tilted by at most ``angle`` radians (``2 * gap``), with an
        overlap of area above ``area * t**2``.
    rtol : float
        The contact search's distance tolerance, relative to the model size.
    """

    contacts: tuple = field(repr=False)
    thickness: np.ndarray = field(repr=False)
    gap: float
    angle: float
    area: float
    rtol: float

    @property
    def separations(self) -> np.ndarray:
        """Per contact, the gap it bridges over the thinner block's thickness."""
        t = np.array([min(self.thickness[c.i], self.thickness[c.j]) for c in self.contacts])
        return np.array([c.separation for c in self.contacts]) / np.maximum(t, 1e-300)

    def describe(self) -> str:
        """The rule in words (for results and the CLI)."""
        return (f"interfaces: faces within {self.gap:g} of the thinner block's thickness, "
                f"tilted <= {self.angle:g} rad")

    def __str__(self) -> str:
        pairs = len({(c.i, c.j) for c in self.contacts})
        bridged = int(np.count_nonzero([c.separation > 0 for c in self.contacts]))
        return f"{len(self.contacts)} contacts between {pairs} block pairs ({bridged} across a gap); {self.describe()}"

    def to_dict(self) -> dict:
        """The rule and its measured extent (JSON)."""
        seps = self.separations
        return {"model": "interfaces", "gap_thickness": self.gap, "angle": self.angle, "area_thickness": self.area,
                "rtol": self.rtol, "contacts": len(self.contacts),
                "pairs": len({(c.i, c.j) for c in self.contacts}),
                "largest_separation_thickness": float(seps.max()) if len(seps) else 0.0,
                "thickness_range": [float(self.thickness.min()), float(self.thickness.max())]
                if len(self.thickness) else []}


def thickness(assembly: Assembly, budget=None) -> np.ndarray:
    """Each block's thickness: the least width of its convex hull over the hull's face normals (model units).

    Exact for boxes and prisms (the distance between the closest parallel
    faces); for other shapes an upper bound of the least width, attained on a
    face of the hull.  Computed once per block type (rigid motions and mirror
    images keep widths).  ``budget`` (:class:`~interlock.verify.budget.Budget`) is checked between block
    types (TimeLimitReached, "the contacts"): a file read as one mesh per block has as many types as blocks,
    and their hulls took 0.7 s on a 300-block hexagon.

    >>> import trimesh
    >>> slab = trimesh.creation.box(extents=[4, 2, 0.5])
    >>> thickness(Assembly.from_meshes([slab])).tolist()
    [0.5]
    """
    if not isinstance(assembly, Assembly):
        raise InterfaceError(f"expected an interlock Assembly, got {type(assembly).__name__}")
    per_type = np.empty(len(assembly.meshes))
    for t, mesh in enumerate(assembly.meshes):
        if budget is not None:
            budget.check("the contacts")
        hull = mesh.convex_hull
        heights = hull.vertices @ hull.face_normals.T
        per_type[t] = float((heights.max(axis=0) - heights.min(axis=0)).min())
    return per_type[assembly.types]


def interfaces(assembly: Assembly, gap: float = DEFAULT_GAP_THICKNESS, area: float = DEFAULT_AREA_THICKNESS,
               rtol: float = DEFAULT_CONTACT_RTOL, involving=None, budget=None) -> Interfaces:
    """Contacts between faces that face each other across small gaps and tilts, relative to each pair's thickness.

    For blocks ``i < j`` with ``t = min(thickness_i, thickness_j)``
    (:func:`thickness`), a facet of ``i`` and a facet of ``j`` with opposite
    normals, tilted by at most ``2 gap`` radians, are an interface where their
    overlap (projected onto ``i``'s facet plane) lies everywhere within
    ``rtol * L + gap * t`` of ``j``'s facet plane and has area above
    ``area * t**2``.  The angle is the tilt at which a face as wide as the
    pair's thickness departs by the gap at its edges; wider faces are held to
    less by the distance test, as compas_assembly's ``tmax`` holds them
    (vertices within ``tmax`` of the other plane).  The contact is placed on the
    mid-plane (see :func:`~interlock.verify.contacts.contacts` with ``gap``).

    This is a model of interfaces for statics: faces apart by less than a
    quarter of a block's thickness are taken to meet, as in a real structure
    whose joints are filled or whose blocks settle onto each other.  The
    kinematic verifier :func:`~interlock.verify.check` keeps exact contacts.

    Parameters
    ----------
    assembly : Assembly
    gap : float
        Largest gap as a fraction of the pair's thickness (default :data:`DEFAULT_GAP_THICKNESS`), ``>= 0``,
        below ``pi / 4`` (the angle ``2 gap`` must stay below ``pi / 2``).
    area : float
        Smallest area as a fraction of the pair's thickness squared (default :data:`DEFAULT_AREA_THICKNESS`).
    rtol : float
        :func:`~interlock.verify.contacts.contacts`' distance tolerance (relative to the model size).
    involving : iterable of int, optional
        Only interfaces of which at least one block is among these.

    Returns
    -------
    Interfaces

    Raises
    ------
    InterfaceError
        Not an assembly, or a tolerance negative, not finite or too large.

    Notes
    -----
    One call of :func:`~interlock.verify.contacts.contacts` with the largest
    pair's tolerances (``gap = max gap * t / L``, ``angle_tol = 2 gap``,
    ``area_rtol = min area * t**2 / L**2``), then each contact is kept if it
    meets its own pair's: the search is monotone in its tolerances and a
    contact's ``separation`` is exactly the distance it tests, so this equals
    one call per pair with that pair's tolerances
    (``tests/verify/test_interfaces.py`` checks it pair by pair).  A pair
    whose faces touch (found by the exact search) and bridge no gap keeps
    its exact contacts: the wide search's angle also groups triangles into
    facets, so a face bent by less than it falls apart into triangles (the
    same union in more polygons: 37 contacts of the bridge would become 65).

    Examples
    --------
    Two slabs 0.5 thick, 0.05 apart: no contact, but an interface.

    >>> import trimesh
    >>> from interlock.verify import contacts
    >>> slabs = [trimesh.creation.box(bounds=[[0, 0, z], [2, 2, z + 0.5]]) for z in (0, 0.55)]
    >>> pair = Assembly.from_meshes(slabs)
    >>> len(contacts(pair)), len(interfaces(pair).contacts), round(interfaces(pair).contacts[0].separation, 9)
    (0, 1, 0.05)
    """
    if not isinstance(assembly, Assembly):
        raise InterfaceError(f"expected an interlock Assembly, got {type(assembly).__name__}")
    gap, area, rtol = (_tolerance(name, value) for name, value in (("gap", gap), ("area", area), ("rtol", rtol)))
    if not gap < math.pi / 4:
        raise InterfaceError(f"gap must be below pi / 4 of the thickness (the tilt 2 gap < pi / 2), got {gap}")
    widths = thickness(assembly, budget)
    angle = 2.0 * gap
    empty = Interfaces((), widths, gap, angle, area, rtol)
    if len(assembly) < 2:
        return empty
    length = assembly.scale
    found = find_contacts(assembly, rtol=rtol, angle_tol=max(angle, 1e-12), gap=gap * float(widths.max()) / length,
                          area_rtol=area * float(widths.min()) ** 2 / length ** 2, involving=involving, budget=budget)
    kept = {}
    for c in found:
        t = min(widths[c.i], widths[c.j])
        if c.separation <= rtol * length + gap * t and c.area > area * t * t:
            kept.setdefault((c.i, c.j), []).append(c)
    # pairs whose faces only touch keep their exact contacts: the wide search groups triangles within its
    # larger angle, so a face bent by less than it falls apart into triangles (the same union, more polygons;
    # the bridge: 37 contacts -> 65)
    touching = {}
    for c in find_contacts(assembly, rtol=rtol, involving=involving, budget=budget):
        t = min(widths[c.i], widths[c.j])
        if c.area > area * t * t:
            touching.setdefault((c.i, c.j), []).append(c)
    for pair, exact in touching.items():
        if all(c.separation == 0.0 for c in kept.get(pair, ())):
            kept[pair] = exact
    chosen = [c for pair in sorted(kept) for c in kept[pair]]
    return Interfaces(tuple(sorted(chosen, key=lambda c: (c.i, c.j, c.facet_i, c.facet_j))), widths, gap, angle,
                      area, rtol)


def statics_contacts(assembly: Assembly, contacts=None, budget=None) -> tuple[tuple, dict]:
    """The contacts RBE and CRA use, and how they were found (for the result's ``parameters["contacts"]``).

    ``contacts`` is ``None`` or ``"interfaces"`` (:func:`interfaces` with its
    defaults), ``"exact"`` (:func:`~interlock.verify.contacts.contacts` with
    its defaults: faces that touch), an :class:`Interfaces`, or a sequence of
    :class:`~interlock.blocks.contact.Contact` (given; e.g. :func:`compas_interfaces`).
    Blocks that overlap deeper than the interface rule allows are refused (:func:`refuse_deep_overlaps`), and
    with interfaces also blocks that overlap deeper than the exact contacts' tolerance without an interface
    between them (:func:`~interlock.verify.validate.refuse_overlaps_without_contact`).  The search and the overlap
    test run under ``budget`` (TimeLimitReached, "the contacts").
    """
    if contacts is None or (isinstance(contacts, str) and contacts == "interfaces"):
        contacts = interfaces(assembly, budget=budget)
    found, model = _statics_contacts(assembly, contacts, budget)
    if budget is not None:
        budget.check("the contacts")
    overlapping = pair_overlaps(assembly)
    if budget is not None:
        budget.check("the contacts")
    if isinstance(contacts, Interfaces):  # the rule meets faces across overlaps, so an overlap must be one
        refuse_deep_overlaps(assembly, contacts.gap, contacts.thickness, overlapping)
        refuse_overlaps_without_contact(assembly, overlapping, found, DEFAULT_CONTACT_RTOL * assembly.scale)
    else:  # exact or given contacts: the user's model of what touches; only interpenetration is refused
        refuse_deep_overlaps(assembly, found=overlapping)
    return found, model


def _statics_contacts(assembly: Assembly, contacts, budget=None) -> tuple[tuple, dict]:
    if isinstance(contacts, Interfaces):
        return contacts.contacts, contacts.to_dict()
    if isinstance(contacts, str):
        if contacts != "exact":
            raise InterfaceError(f"contacts must be one of {CONTACT_MODELS}, Interfaces or a sequence of Contact, "
                                 f"got {contacts!r}")
        found = find_contacts(assembly, budget=budget)
        return found, {"model": "exact", "contacts": len(found)}
    found = tuple(contacts)
    if not all(isinstance(c, Contact) for c in found):
        raise InterfaceError("contacts must be Contact objects (interlock.verify.contacts or compas_interfaces)")
    return found, {"model": "given", "contacts": len(found)}


def refuse_deep_overlaps(assembly: Assembly, gap: float = DEFAULT_GAP_THICKNESS, widths=None, found=None) -> None:
    """Raise :class:`~interlock.verify.validate.OverlapError` when two blocks overlap deeper (mean depth, see
    :class:`~interlock.verify.validate.Overlap`) than ``gap`` times the thinner one's thickness (``widths``:
    :func:`thickness`, and ``found``: :func:`~interlock.verify.validate.pair_overlaps`, computed when not given).

    The interface rule lets faces meet across gaps *and overlaps* up to that depth (the armadillo's blocks
    overlap up to 0.01 deep, 1.4 % of a block); deeper, the blocks interpenetrate (a block duplicated in
    place, a wedge pushed through its neighbour) and RBE would balance geometry the file does not describe.

    >>> import trimesh
    >>> boxes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 0.25)]
    >>> try:
    ...     refuse_deep_overlaps(Assembly.from_meshes(boxes))
    ... except OverlapError as error:
    ...     print(str(error)[:70])
    blocks 0 (0) and 1 (1) overlap 0.3 deep, more than 0.25 of the thinner
    """
    found = pair_overlaps(assembly) if found is None else found
    if not found:
        return
    widths = thickness(assembly) if widths is None else widths
    deep = [o for o in found if o.thickness > gap * min(widths[o.i], widths[o.j])]
    if deep:
        o = max(deep, key=lambda item: item.thickness / min(widths[item.i], widths[item.j]))
        more = f" ({len(deep) - 1} more such pairs)" if len(deep) > 1 else ""
        raise OverlapError(
            f"blocks {o.i} ({assembly.labels[o.i]}) and {o.j} ({assembly.labels[o.j]}) overlap {o.thickness:.3g} deep, "
            f"more than {gap:g} of the thinner one's thickness ({min(widths[o.i], widths[o.j]):.3g}): they "
            f"interpenetrate{more}; blocks may only touch or meet across small gaps and overlaps")


def compas_interfaces(path, assembly: Assembly) -> tuple[Contact, ...]:
    """The interfaces a COMPAS assembly JSON file stores, as contacts of ``assembly`` (loaded from that file).

    compas_assembly and compas_cra store an edge ``(u, v)`` of the block graph
    with a list ``interfaces`` (or one ``interface``) of
    ``compas_assembly.datastructures/Interface`` objects: a ``frame``
    (``point``, ``xaxis``, ``yaxis``) and the polygon's ``points``.  The
    frame's ``zaxis = xaxis x yaxis`` points from ``u`` to ``v`` (upstream's
    ``A_eq`` puts the force on ``v``, its negative on ``u``), so the contact
    is ``(i, j) = (u, v)`` with normal ``zaxis`` when ``u`` comes first, else
    ``(v, u)`` with ``-zaxis`` and the axes swapped.  Blocks are matched by
    node key: ``assembly.info["node_keys"]`` when the file names its nodes
    (labels differ from keys), else ``assembly.labels``, as
    :func:`~interlock.formats.compas.load_compas` sets them.  Vertices are ordered counter-clockwise about the normal;
    ``deviation`` is their largest distance from the frame's plane.

    Parameters
    ----------
    path : str or Path
        A COMPAS assembly JSON file (``compas_assembly...Assembly`` or ``compas_cra...CRA_Assembly``).
    assembly : Assembly
        The same file's blocks, e.g. ``interlock.read(path)``.

    Returns
    -------
    tuple of Contact
        Sorted by ``(i, j)``; empty if the file stores no interfaces (most of compas_cra's samples store
        none: ``curve-3-blocks``, ``cube-curve-short``, ``cube-curve-tall`` and ``concave-short`` do).

    Raises
    ------
    InterfaceError
        The file is missing or not COMPAS JSON, an edge names a node that is not a block, or an interface
        has fewer than three points or no frame.
    """
    path = Path(path)
    try:
        document = read_json_document(path, "COMPAS file")
    except FormatError as error:
        raise InterfaceError(str(error)) from None
    try:
        graph = document["data"]["graph"]
        graph = graph.get("data", graph)
        edges = graph.get("edge", {})
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
        raise InterfaceError(f"{path} is not a readable COMPAS assembly JSON file ({error})") from None
    keys = assembly.info.get("node_keys") if isinstance(assembly.info, dict) else None
    keys = keys if isinstance(keys, (list, tuple)) and len(keys) == len(assembly) else assembly.labels
    index = {str(key): k for k, key in enumerate(keys)}  # node keys (labels when a file names its nodes)
    found = []
    for u, neighbours in edges.items():
        for v, attributes in (neighbours or {}).items():
            if not isinstance(attributes, dict):
                continue
            stored = attributes.get("interfaces") or []
            if attributes.get("interface"):
                stored = [*stored, attributes["interface"]]
            for item in stored:
                if str(u) not in index or str(v) not in index:
                    raise InterfaceError(f"{path.name}: edge ({u}, {v}) names a node that is not a block")
                found.append(_compas_contact(path, item, index[str(u)], index[str(v)]))
    return tuple(sorted(found, key=lambda c: (c.i, c.j)))


def _compas_contact(path, item, a: int, b: int) -> Contact:
    data = item.get("data", item) if isinstance(item, dict) else None
    try:
        frame = plain_geometry(data["frame"])
        origin = np.asarray(frame["point"], dtype=float)
        x, y = np.asarray(frame["xaxis"], dtype=float), np.asarray(frame["yaxis"], dtype=float)
        points = np.asarray(plain_geometry(data["points"]), dtype=float).reshape(-1, 3)
    except (KeyError, TypeError, ValueError, AttributeError):
        raise InterfaceError(f"{path.name}: an interface of edge {a}-{b} has no frame or points") from None
    z = np.cross(x, y)
    if len(points) < 3 or not np.isfinite(points).all() or not np.linalg.norm(z) > 0:
        raise InterfaceError(f"{path.name}: an interface of edge {a}-{b} needs three or more finite points "
                             "and a frame")
    normal = z / np.linalg.norm(z)
    i, j = (a, b) if a < b else (b, a)
    if a > b:
        normal = -normal
    basis = plane_bases(normal[None])[0]
    xy = (points - origin) @ basis.T
    polygon = shapely.Polygon(xy)
    if polygon.exterior.is_ccw is False:
        points, xy = points[::-1], xy[::-1]
        polygon = shapely.Polygon(xy)
    deviation = float(np.abs((points - origin) @ normal).max())
    arrays = [normal, points.copy(), origin, basis]
    for array in arrays:
        array.setflags(write=False)
    return Contact(int(i), int(j), arrays[0], arrays[1], float(abs(polygon.area)), -1, -1, polygon, arrays[2],
                   arrays[3], deviation, True, 0.0)


def plain_geometry(value):
    """COMPAS geometry data as plain numbers and lists: COMPAS 2 stores a point, vector or frame as an object
    ``{"dtype": "compas.geometry/Point", "data": [x, y, z], "guid": ...}`` (a frame's ``data`` a dict of its
    ``point``, ``xaxis`` and ``yaxis``, each a list or again such an object); COMPAS 1 and compas_cra's older
    files store the plain lists.  Both read the same.

    >>> plain_geometry({"dtype": "compas.geometry/Frame", "data": {"point": {"dtype": "compas.geometry/Point",
    ...     "data": [0, 0, 1]}, "xaxis": [1, 0, 0], "yaxis": [0, 1, 0]}})
    {'point': [0, 0, 1], 'xaxis': [1, 0, 0], 'yaxis': [0, 1, 0]}
    >>> plain_geometry([{"dtype": "compas.geometry/Point", "data": [1, 2, 3]}, [4, 5, 6]])
    [[1, 2, 3], [4, 5, 6]]
    """
    if isinstance(value, dict) and "data" in value and ("dtype" in value or set(value) <= {"data", "guid", "name"}):
        return plain_geometry(value["data"])
    if isinstance(value, dict):
        return {key: plain_geometry(item) for key, item in value.items()}
    if isinstance(value, list):
        return [plain_geometry(item) for item in value]
    return value


def _tolerance(name, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not math.isfinite(value) or value < 0:
        raise InterfaceError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)
