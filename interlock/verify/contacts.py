"""Face-to-face contacts between the blocks of an assembly (main paper Def. 3.3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import shapely
from scipy.spatial import cKDTree

from interlock.blocks.assembly import NEIGHBOUR_RTOL, Assembly
from interlock.blocks.contact import CONTACT_KINDS, Contact, ContactError
from interlock.verify.facets import (DEFAULT_ANGLE_TOL, DEFAULT_CONTACT_RTOL, PLANAR_ULPS, TINY, Facets, FacetTable,
                                     check_tolerance, clean_polygons, facets)
from interlock.verify.point_contacts import point_contacts
from interlock.verify.precision import (BEND_FACTOR, COMPUTED_ULPS, PRECISION_FACTOR, block_precision,
                                       coordinate_precision)

__all__ = [
    "Contact",
    "ContactError",
    "CONTACT_KINDS",
    "CONTACT_MODELS",
    "Facets",
    "contacts",
    "model_contacts",
    "GIVEN_CONTACTS",
    "facets",
    "DEFAULT_CONTACT_RTOL",
    "DEFAULT_ANGLE_TOL",
    "DEFAULT_AREA_RTOL",
    "DEFAULT_GAP_RTOL",
    "PLANAR_ULPS",
    "SEARCH_RTOL",
    "MAX_TILT",
    "PRESS_RTOL",
    "search_distances",
    "block_noise",
    "NOISE_CONTACTS",
    "NOISE_SHARE",
    "NOISE_SPREAD",
]

#: Contact polygons of area at most this times the model size squared are dropped.
DEFAULT_AREA_RTOL = 1e-10
#: Gap tolerance relative to the model size: facets whose planes are at most this far apart (beyond ``rtol``)
#: are in contact, across the gap.  Zero: only faces that really touch (within ``rtol``) are contacts.
DEFAULT_GAP_RTOL = 0.0
#: Overlaps are computed on a precision grid of this times the model size (GEOS snap rounding):
#: in plain floating point, GEOS can return a whole square as the overlap of two squares that only
#: share an edge with 1e-16 noise.
OVERLAY_GRID_RTOL = 1e-13
#: The local model finds faces within this fraction of their blocks' size as touching, even where the input's
#: rounding is finer (float64 geometry computed by a CAD tool or a generator strays by far more than its last
#: place).  A gap this narrow is a contact with play (docs/interlocking.md); 1e-6 of a block is open.
SEARCH_RTOL = 1e-9
#: A facet's angle tolerance grows with its distance tolerance over its diameter (a small facet rounded as
#: coarsely as a large one tilts more), up to this many radians.
MAX_TILT = 0.05
#: Facing faces that cross or press into each other (rotated pieces of a file accurate to a few 1e-6 rad, CAD
#: faces a hair into their neighbours) are in contact while they disagree by at most this much of the contact's
#: diameter.  TopoLite's ``ania`` pieces cross by 4.6e-6 of their contact; a block grown by 2e-4 (1e-4 into its
#: neighbours) overlaps them and is refused.
PRESS_RTOL = 1e-5
#: A block's noise is read (:func:`block_noise`) from at least this many contacts: fewer would take a designed
#: fold of one or two faces for noise.
NOISE_CONTACTS = 4
#: The share of a block's contacts that must be bent by at least its noise (:func:`block_noise`): a p1 block with
#: a fold of 1e-10 on two of its four faces reads no noise, a noisy mesh bends nearly all.
NOISE_SHARE = 2.0 / 3.0
#: A bend up to this many times the sum of its blocks' noise is noise: single bends spread above the level two
#: thirds of the contacts reach (the TopoLite cube with Gaussian vertex noise of 1e-9: up to 4.3 times it, 2.1 to
#: 3.7 times it for 95 % of the contacts, over six seeds).  Only a block whose contacts are nearly all bent has a
#: noise at all, so exact or designed geometry (noise 0) is not affected.  The default search looks this far
#: for the faces of a noisy block (:func:`contacts`).
NOISE_SPREAD = 5.0
#: What a contact search finds: ``"faces"`` (face-to-face contacts only, Def. 3.3) or ``"all"`` (also the
#: vertex-face, edge-edge, vertex-edge and vertex-vertex contacts of Remark 3.11).
CONTACT_MODELS = ("faces", "all")
#: Instanced pairs of one kind (:meth:`Assembly.pair_kinds`) share one contact computation; that path is
#: taken when kinds are at most this share of the pairs.
KIND_SHARE = 0.5


def contacts(assembly: Assembly, rtol: float | None = None, angle_tol: float = DEFAULT_ANGLE_TOL,
             area_rtol: float = DEFAULT_AREA_RTOL, involving=None,
             gap: float = DEFAULT_GAP_RTOL, precision=None, budget=None, kinds: str = "faces",
             noise_spread: float = NOISE_SPREAD) -> tuple[Contact, ...]:
    """All face-to-face contacts between the blocks of an assembly (with ``kinds="all"``: contacts of every type).

    Two blocks are in contact where a facet of one and a facet of the other
    lie in a common plane with opposite outward normals and overlap in a region
    of positive area.  Each connected part of such an overlap is one
    :class:`Contact`; its vertices and normal give the rows of the
    infinitesimal interlocking matrix (main paper Def. 3.3).  Only
    face-to-face contacts are found: blocks touching along an edge or at a
    corner give none (Remark 3.11).

    With ``gap > 0``, facets with opposite normals whose planes are up to
    ``gap * scale`` apart (on either side: a slight overlap of the blocks
    counts as well) are in contact too, as in compas_assembly's interface
    detection (``tmax``): the contact is the overlap of the two facets
    projected onto a common plane, which models blocks that a file leaves
    slightly apart (rounded or independently modelled faces) and curved
    interfaces whose two triangulations do not match, which come out as many
    small planar contacts (the CRA paper's Fig. 5).

    Parameters
    ----------
    assembly : Assembly
        The blocks (closed triangle meshes; polygonal faces may be triangulated).
    rtol : float, optional
        Default None: tolerances follow each contact (docs/interlocking.md,
        "Tolerances that follow the contact").  Each block's distance
        tolerance is :data:`~interlock.verify.precision.PRECISION_FACTOR`
        times the rounding of its coordinates
        (:func:`~interlock.verify.precision.block_precision`: float32 at
        ``|x|`` rounds by ``2^-24 |x|``), at least :data:`SEARCH_RTOL` times
        its size, plus the bend its faces show; nothing depends on the rest
        of the scene.  Two facets coincide when their planes are within their
        tolerances; a gap wider is open, a narrower one is a contact with its
        :attr:`~Contact.separation`; overlaps thinner than the tolerance
        (twice the area over the perimeter) are edge touches and dropped;
        outlines are simplified within it.  A number: one distance tolerance
        ``rtol * assembly.scale`` for every block (the model of interlock
        0.2, e.g. ``DEFAULT_CONTACT_RTOL`` = 1e-5, which compas_cra's
        interfaces use; also the default when ``gap > 0``).
    angle_tol : float, optional
        Angle tolerance in radians (default ``DEFAULT_ANGLE_TOL`` = 1e-4) for
        opposite normals and for grouping triangles into facets.
    area_rtol : float, optional
        Overlaps of area at most ``area_rtol * scale**2`` are dropped (default
        ``DEFAULT_AREA_RTOL`` = 1e-10).
    involving : iterable of int, optional
        Only contacts of which at least one block is among these (default: all).
    precision : Precision, optional
        The blocks' rounding (default: read off the coordinates by
        :func:`~interlock.verify.precision.block_precision`).
    kinds : {"faces", "all"}
        ``"faces"`` (default): face-to-face contacts only.  ``"all"``: also
        the vertex-face, edge-edge, vertex-edge and vertex-vertex contacts of
        Remark 3.11 (:func:`~interlock.verify.point_contacts.point_contacts`),
        within the same per-pair distance tolerance; those a face contact of
        the same pair implies are left out.
    noise_spread : float, optional
        Local model only: the pairs of a block whose contacts show vertex
        noise (:func:`block_noise`) are searched again within this many times
        the noise of their two blocks (default :data:`NOISE_SPREAD` = 5),
        since noise tilts a small contact's triangles beyond what rounding
        allows.  A larger value finds the faces a noisy file leaves a little
        apart (what :func:`~interlock.verify.check` asks a motion to respect).
    budget : Budget, optional
        A time budget (:mod:`interlock.verify.budget`), checked between blocks
        of the facet matching and before the overlaps: TimeLimitReached
        ("contacts") when spent.
    gap : float, optional
        Gap tolerance relative to ``assembly.scale`` (default
        ``DEFAULT_GAP_RTOL`` = 0: only touching faces).  Facets with opposite
        normals (within ``angle_tol``) whose centroids lie within
        ``(rtol + gap) * scale`` of each other's planes, and whose overlap stays
        within that distance of block ``j``'s facet plane, are in contact.
        compas_cra's armadillo uses the absolute ``tmax = 0.05`` and
        ``amin = 1e-4`` on a model of scale 20.41, i.e. ``gap = 0.05 / scale``
        (about 2.45e-3) and ``area_rtol = 1e-4 / scale**2`` (about 2.4e-7).
        Upstream tests no angle, only that the vertices of one face lie within
        ``tmax`` of the other's plane (which lets faces of size ``L`` tilt by up
        to about ``2 tmax / L``): the armadillo's facing faces are up to 0.16
        rad apart, curved interfaces' facing triangles similarly, so pass a
        larger ``angle_tol`` (0.2 there) to pair faces as loosely.  Facets are
        still grouped within ``rtol``: the triangles of a polygon that is not
        flat stay apart and give one contact each.

    Returns
    -------
    tuple of Contact
        Sorted by ``(i, j, facet_i, facet_j)``.

    Raises
    ------
    ContactError
        If ``assembly`` is not an :class:`~interlock.blocks.Assembly` or a
        tolerance (``gap`` included) is negative, not finite or not a number
        (or ``angle_tol >= pi / 2``).

    See Also
    --------
    facets : the planar facets of one mesh, which ``facet_i`` and ``facet_j`` index.

    Notes
    -----
    Candidate pairs are the edges of ``assembly.neighbours`` (a spatial index on
    bounding boxes; :meth:`~Assembly.neighbour_graph` with ``rtol`` when it is
    larger), never all pairs.  Facets are computed once per block type and
    moved rigidly (mirror images included).  Per candidate pair, facets with
    opposite normals in coincident planes are matched through a k-d tree on
    (normal, plane offset), so the cost is ``O((F_i + F_j) log F)`` plus the
    matches, not ``O(F_i F_j)``.  Block ``j``'s facet is mapped into the 2D
    frame of block ``i``'s facet and all matched pairs are intersected at once
    with shapely (non-convex facets, holes and multi-part overlaps are
    handled).  Contact vertices lie on block ``i``'s facet plane.

    A contact found across a gap (``gap > 0``) is the overlap of the two
    facets projected orthogonally onto block ``i``'s facet plane, then moved
    along its normal halfway to block ``j``'s facet (the mid-plane, parallel to
    block ``i``'s facet); with ``gap > 0`` every contact is placed so, which
    moves touching ones by at most ``rtol * scale / 2``.  Its ``separation``
    and ``deviation`` record how far apart the faces were; ``planar`` keeps its
    meaning (both facets planar up to rounding), since a gap only makes the
    model stricter than the real blocks: a motion the model admits (a "not
    interlocked" verdict of :func:`~interlock.verify.check`) keeps faces that
    are really apart apart, whereas "interlocked" holds for the blocks with
    their gaps closed.  With ``gap = 0`` the results are exactly those
    without the parameter.

    Examples
    --------
    >>> import trimesh
    >>> cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)]
    >>> found = contacts(Assembly.from_meshes(cubes))
    >>> [(c.i, c.j, round(c.area, 9), c.normal.round(9).tolist()) for c in found]
    [(0, 1, 1.0, [1.0, 0.0, 0.0]), (1, 2, 1.0, [1.0, 0.0, 0.0])]
    >>> print(found[0])
    contact 0-1: 4 vertices, area 1, normal (1, 0, 0), facets 5/0
    """
    if not isinstance(assembly, Assembly):
        raise ContactError(f"contacts() needs an interlock Assembly, got {type(assembly).__name__}; "
                           "build one with Assembly.from_meshes or interlock.read")
    rtol = None if rtol is None else check_tolerance("rtol", rtol)
    angle_tol = check_tolerance("angle_tol", angle_tol)
    area_rtol = check_tolerance("area_rtol", area_rtol)
    gap = check_tolerance("gap", gap)
    noise_spread = check_tolerance("noise_spread", noise_spread)
    if angle_tol >= math.pi / 2:
        raise ContactError(f"angle_tol must be below pi/2 radians, got {angle_tol}")
    if kinds not in CONTACT_MODELS:
        raise ContactError(f"kinds must be one of {', '.join(map(repr, CONTACT_MODELS))}, got {kinds!r}")
    if len(assembly) < 2:
        return ()
    local = _tolerances(assembly, rtol, angle_tol, area_rtol, gap, precision)
    found = _search(assembly, _candidate_pairs(assembly, local.search + local.gap, involving), local, budget, kinds)
    if rtol is None and gap == 0:
        found = _with_noisy_faces(assembly, found, local, noise_spread, involving, budget, kinds)
    return found


def _candidate_pairs(assembly: Assembly, reach: np.ndarray, involving=None) -> np.ndarray:
    """Pairs ``(i, j)``, ``i < j``, of blocks whose boxes come within ``reach`` (per block) of each other, of which
    at least one is among ``involving`` (all when None)."""
    lean = assembly.local_padding(NEIGHBOUR_RTOL)
    graph = assembly.neighbours if np.all(reach <= lean) else assembly.neighbour_graph(pad=reach + lean)
    pairs = np.array(sorted((min(u, v), max(u, v)) for u, v in graph.edges if u != v), dtype=int).reshape(-1, 2)
    if involving is not None:
        pairs = pairs[np.isin(pairs, assembly.block_indices(involving, "involving")).any(axis=1)]
    return pairs


def _with_noisy_faces(assembly: Assembly, found, local: _Tolerances, spread: float, involving, budget,
                      kinds) -> tuple[Contact, ...]:
    """``found``, with the pairs of noisy blocks searched again within ``spread`` times their noise.

    Vertex noise tilts a contact's few triangles by about the noise over their size, beyond the angle a face
    rounded only by its coordinates may tilt: a small contact of a noisy block is missed, and the blocks seem
    free to move through it (TopoLite's shell with noise of 1e-5: one part's 0.07-wide contact with the frame).
    The noise its other contacts show (:func:`block_noise`) is how far its faces may lie from where they were.
    """
    noise = spread * block_noise(found)
    noise = np.pad(noise, (0, len(assembly) - len(noise)))
    if not noise.any():
        return found
    widened = replace(local, search=np.maximum(local.search, noise))
    pairs = _candidate_pairs(assembly, widened.search, involving)
    noisy = (noise[pairs] > 0).any(axis=1)
    again = _pair_contacts(assembly, pairs[noisy], widened, budget, kinds) if noisy.any() else ()
    kept = [c for c in found if not (noise[c.i] > 0 or noise[c.j] > 0)]
    return tuple(sorted(kept + list(again), key=_order))


def _search(assembly: Assembly, pairs: np.ndarray, local: _Tolerances, budget, kinds) -> tuple[Contact, ...]:
    """The contacts of the candidate ``pairs`` under ``local``; instanced pairs of one kind computed once."""
    if not len(pairs):
        return ()
    model = kinds
    kinds, kind_of, relative = assembly.pair_kinds(pairs)
    if len(kinds) > KIND_SHARE * len(pairs):
        return _pair_contacts(assembly, pairs, local, budget, model)
    # instanced blocks: one computation per kind of pair, on a stand-in of two blocks, moved to every pair; each
    # stand-in block takes the coarsest tolerance of the blocks it stands for
    i, j = pairs[kinds].T
    relative = relative[kinds]
    stand_in = Assembly(assembly.meshes, np.column_stack([assembly.types[i], assembly.types[j]]).ravel(),
                        np.stack([np.broadcast_to(np.eye(4), relative.shape), relative], axis=1).reshape(-1, 4, 4))
    widest = [np.zeros(2 * len(kinds)) for _ in range(4)]
    for k, values in enumerate((local.search, local.rounding, local.area, local.coincide)):
        np.maximum.at(widest[k], 2 * kind_of, values[pairs[:, 0]])
        np.maximum.at(widest[k], 2 * kind_of + 1, values[pairs[:, 1]])
    stand_in_tolerances = _Tolerances(*widest, local.grouping, local.angle, local.gap, local.tilt)
    computed = _pair_contacts(stand_in, np.arange(2 * len(kinds)).reshape(-1, 2), stand_in_tolerances, budget,
                              model)
    by_kind = {}
    for contact in computed:
        by_kind.setdefault(contact.i // 2, []).append(contact)
    found = [_moved(contact, int(a), int(b), assembly.transforms[a], assembly.mirrored[a])
             for (a, b), k in zip(pairs, kind_of) for contact in by_kind.get(int(k), ())]
    return tuple(sorted(found, key=_order))


def _order(contact: Contact):
    """Sort key: pair, faces before point contacts (by kind), facets, then the point."""
    return (contact.i, contact.j, CONTACT_KINDS.index(contact.kind), contact.facet_i, contact.facet_j,
            tuple(contact.vertices[0]) if contact.kind != "face" else ())


def search_distances(assembly: Assembly, precision=None) -> np.ndarray:
    """Per block, the distance within which the default search takes its faces as touching another's.

    :data:`~interlock.verify.precision.PRECISION_FACTOR` times the rounding
    of its coordinates, at least :data:`SEARCH_RTOL` times its size.

    >>> import trimesh
    >>> far = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1e9)]
    >>> near, distant = search_distances(Assembly.from_meshes(far))  # each block its own: its size, its coordinates
    >>> float(near), bool(1e-5 < distant < 1e-4)
    (1.7320508075688772e-09, True)
    """
    precision = block_precision(assembly) if precision is None else precision
    return np.maximum(PRECISION_FACTOR * np.asarray(precision.delta, dtype=float), SEARCH_RTOL * assembly.block_sizes)


def block_noise(found) -> np.ndarray:
    """Per block (indexed up to the largest in ``found``): the bend that :data:`NOISE_SHARE` of its contacts' faces
    reach, a length.

    A noisy mesh bends nearly every face of several triangles by about its noise, and leaves single triangles
    planar however noisy it is: the :attr:`~interlock.blocks.contact.Contact.deviation` that two thirds of a
    block's contacts reach reads that noise.  A bend only some faces show (a fold of a designed face) is geometry,
    not noise, and reads 0.  Fewer than :data:`NOISE_CONTACTS` contacts read no noise (0).

    Examples
    --------
    >>> from types import SimpleNamespace as Found
    >>> found = [Found(i=0, j=k, deviation=d) for k, d in ((1, 1e-9), (2, 2e-9), (3, 3e-9), (4, 1e-7))]
    >>> block_noise(found).tolist()  # block 0 reads its noise; the others have one contact each
    [2e-09, 0.0, 0.0, 0.0, 0.0]
    >>> folded = [Found(i=0, j=k, deviation=d) for k, d in ((1, 0.0), (2, 1e-10), (3, 1e-10), (4, 0.0))]
    >>> block_noise(folded).tolist()[0]  # two folded faces of four: geometry
    0.0
    """
    blocks = 1 + max((max(c.i, c.j) for c in found), default=-1)
    bends = [[] for _ in range(blocks)]
    for c in found:
        bends[c.i].append(c.deviation)
        bends[c.j].append(c.deviation)
    return np.array([float(np.sort(b)[int(len(b) * (1.0 - NOISE_SHARE))]) if len(b) >= NOISE_CONTACTS else 0.0
                     for b in bends])


def _tolerances(assembly, rtol, angle_tol, area_rtol, gap, precision) -> "_Tolerances":
    """The search's tolerances for :func:`contacts` (arguments as there, already checked)."""
    scale = assembly.scale
    if rtol is None and gap > 0:  # interfaces across gaps are compas_assembly's model: relative to the model size
        rtol = DEFAULT_CONTACT_RTOL
    if rtol is None:  # the local model: each block's rounding and size, nothing of the scene
        precision = block_precision(assembly) if precision is None else precision
        # the margin's rounding is what the numbers show; the allowance for computed geometry widens the search only
        read = precision.delta if precision.read is None else precision.read
        rounding = PRECISION_FACTOR * np.asarray(read, dtype=float)
        search = search_distances(assembly, precision)
        by_type = (precision.by_type if precision.by_type is not None
                   else [coordinate_precision(m.vertices)[0] for m in assembly.meshes])
        grouping = np.array([max(PRECISION_FACTOR * d, SEARCH_RTOL * m.scale)
                             for d, m in zip(by_type, assembly.meshes)])
        area_size = assembly.block_sizes
    else:  # one tolerance relative to the model size, as asked
        rounding = search = np.full(len(assembly), rtol * scale)
        grouping = np.full(len(assembly.meshes), rtol * scale)
        area_size = np.full(len(assembly), scale)
    # faces closer than the last places computed float64 strays by, at the block's own coordinates, coincide
    coincide = COMPUTED_ULPS * np.finfo(float).eps * np.abs(assembly.bounds).max(axis=(1, 2))
    return _Tolerances(search, rounding, area_rtol * area_size**2, coincide, grouping, angle_tol, gap * scale,
                       rtol is None)


@dataclass(frozen=True)
class _Tolerances:
    """The contact search's tolerances: per block the search distance, the rounding, the smallest area kept and
    the distance below which faces coincide (no gap); per mesh type the facet grouping distance; the angle, the
    absolute gap, and whether each facet's angle tolerance grows with its distance tolerance (the local model)."""

    search: np.ndarray
    rounding: np.ndarray
    area: np.ndarray
    coincide: np.ndarray
    grouping: np.ndarray
    angle: float
    gap: float
    tilt: bool = True


#: ``Assembly.info`` key of contacts given with an assembly (point and line contacts that the face search cannot
#: find, e.g. :func:`~interlock.blocks.presets.block_on_pins`): a tuple of :class:`Contact`.
GIVEN_CONTACTS = "contacts"


def model_contacts(assembly: Assembly, given=None, precision=None, budget=None,
                   kinds: str = "all") -> tuple[Contact, ...]:
    """The contacts a verdict uses: ``given`` if not None, else those the assembly carries, else :func:`contacts`.

    ``kinds`` is the search's model (:data:`CONTACT_MODELS`): ``"all"``
    (default) finds contacts of every type, ``"faces"`` face-to-face ones only.

    An assembly carries contacts in ``assembly.info[GIVEN_CONTACTS]`` when
    some of its contacts are not face to face (Remark 3.11), as
    :func:`~interlock.blocks.presets.block_on_pins` does.

    >>> from interlock.blocks import presets
    >>> len(model_contacts(presets.block_on_pins())), len(model_contacts(presets.cube_grid(), kinds="faces"))
    (7, 12)
    """
    if given is not None:
        return tuple(given)
    carried = assembly.info.get(GIVEN_CONTACTS) if isinstance(assembly.info, dict) else None
    if carried is not None:
        if not all(isinstance(c, Contact) for c in carried):
            raise ContactError(f"assembly.info[{GIVEN_CONTACTS!r}] must hold Contact objects")
        return tuple(carried)
    return contacts(assembly, precision=precision, budget=budget, kinds=kinds)


def _pair_contacts(assembly, pairs, tolerances: _Tolerances, budget=None, kinds="faces") -> tuple[Contact, ...]:
    """Contacts of the given block pairs under the per-block ``tolerances`` (``budget`` checked between steps)."""
    table = FacetTable(assembly, tolerances.grouping, tolerances.angle, needed=np.unique(pairs))
    if budget is not None:
        budget.check("contacts")
    gi, gj, atol = _matches(table, pairs, tolerances, budget)
    if budget is not None:
        budget.check("contacts")
    faces = _overlaps(table, gi, gj, atol, tolerances)
    if kinds == "faces":
        return faces
    if budget is not None:
        budget.check("contacts")
    return faces + point_contacts(table, pairs, tolerances, faces)


def _moved(contact: Contact, i: int, j: int, transform: np.ndarray, mirrored: bool) -> Contact:
    """A contact computed with block i at the origin, placed for blocks i, j (block i moved by ``transform``)."""
    rotation, shift = transform[:3, :3], transform[:3, 3]
    basis, origin = contact.basis @ rotation.T, rotation @ contact.origin + shift
    polygon, vertices = contact.polygon, contact.vertices @ rotation.T + shift
    if contact.kind != "face":  # a point: no polygon to reflect; the cone of normals turns with the blocks
        if mirrored:
            basis = basis * np.array([[1.0], [-1.0]])
        arrays = [rotation @ contact.normal, vertices, origin, basis]
        if contact.normals is not None:
            arrays.append(contact.normals @ rotation.T)
        for array in arrays:
            array.setflags(write=False)
        return replace(contact, i=i, j=j, normal=arrays[0], vertices=vertices, origin=origin, basis=basis,
                       normals=arrays[4] if contact.normals is not None else None)
    if mirrored:  # keep u x v = n and counter-clockwise rings: flip v and the polygon's y
        basis = basis * np.array([[1.0], [-1.0]])
        polygon = shapely.orient_polygons(shapely.transform(polygon, lambda xy: xy * [1.0, -1.0]))
        xy, ring = shapely.get_coordinates(shapely.get_rings(polygon), return_index=True)
        xy = xy[np.r_[ring[1:] == ring[:-1], False]]  # without each ring's closing repeat
        vertices = origin + xy @ basis
    arrays = [rotation @ contact.normal, vertices, origin, basis]
    for array in arrays:
        array.setflags(write=False)
    normal, vertices, origin, basis = arrays
    return replace(contact, i=i, j=j, normal=normal, vertices=vertices, origin=origin, basis=basis, polygon=polygon)


# --- private helpers --------------------------------------------------------------------------------


def _facet_tolerances(table: FacetTable, tolerances: _Tolerances):
    """Per facet of the table: its distance tolerance (its block's search distance, its mesh's grouping distance,
    and its own bend), its tilt (the angle that distance tilts a facet of its diameter by; 0 outside the local
    model) and its diameter."""
    bend = np.where(table.planar, 0.0, table.flatness)
    distance = np.maximum(tolerances.search[table.block], table.grouping) + bend
    box = shapely.bounds(table.polygons).reshape(-1, 2, 2)
    diameter = np.nan_to_num(np.hypot(*(box[:, 1] - box[:, 0]).T), nan=0.0)  # an empty polygon has no extent
    if not tolerances.tilt:
        return distance, np.zeros(len(distance)), diameter
    return distance, np.minimum(2.0 * distance / np.maximum(diameter, TINY), MAX_TILT), diameter


def _matches(table: FacetTable, pairs, tolerances: _Tolerances, budget=None):
    """Global facet indices (gi, gj) of coplanar facets with opposite normals, blocks i < j, and their distance
    tolerances.

    Facets ``f`` of block ``i`` and ``g`` of block ``j`` match when their normals are opposite within the angle
    tolerance, or within the sum of their tilts (each may lean by its own, :func:`_facet_tolerances`), and each
    centroid lies within ``d_f + d_g`` (their distance tolerances) of the other's
    plane, plus what the angle between them adds over the distance of their centroids.  With a gap, facets up to
    ``gap`` farther apart match too (the overlap is tested later).
    """
    distance, tilt, diameter = _facet_tolerances(table, tolerances)
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    radius = math.sqrt(2) * (1 + 1e-9)
    gi, gj = [], []
    # one tree per block i, queried at once with the facets of all its partners j; offsets about block i's
    # facets' centre, so that nothing depends on where the scene lies
    for count, (i, partners) in enumerate(zip(*_grouped(pairs))):
        if budget is not None and count % 256 == 0:
            budget.check("contacts")
        facets_i = np.arange(table.start[i], table.start[i + 1])
        facets_j = np.concatenate([np.arange(table.start[j], table.start[j + 1]) for j in partners])
        if not len(facets_j) or not len(facets_i):
            continue
        both = np.r_[facets_i, facets_j]
        centre = table.origins[facets_i].mean(axis=0)
        reach = float(np.linalg.norm(table.origins[both] - centre, axis=1).max() + diameter[both].max())
        a = max(tolerances.angle, 2.0 * float(tilt[both].max()), TINY)
        t = max(float(distance[facets_i].max() + distance[facets_j].max()) + tolerances.gap
                + (2 * a + PRESS_RTOL) * reach,
                TINY * max(reach, TINY))
        # |n_i + n_j| <= a and |d_i + d_j| <= t for offsets d = n.(o - centre): within the ball of radius sqrt 2
        offsets = np.einsum("fi,fi->f", table.normals[both], table.origins[both] - centre)
        points = np.hstack([table.normals[both] / a, offsets[:, None] / t])
        hits = cKDTree(points[:len(facets_i)]).query_ball_point(-points[len(facets_i):], radius)
        sizes = np.fromiter(map(len, hits), dtype=int, count=len(hits))
        if sizes.sum():
            gi.append(facets_i[np.concatenate([h for h in hits if h]).astype(int)])
            gj.append(np.repeat(facets_j, sizes))
    if not gi:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0)
    gi, gj = np.concatenate(gi), np.concatenate(gj)
    ni, nj = table.normals[gi], table.normals[gj]
    angle = 2 * np.arcsin(np.clip(np.linalg.norm(ni + nj, axis=1) / 2, 0, 1))
    apart = table.origins[gj] - table.origins[gi]
    pair_distance = distance[gi] + distance[gj]
    slack = (pair_distance + tolerances.gap + PRESS_RTOL * np.minimum(diameter[gi], diameter[gj])
             + np.sin(angle) * (np.linalg.norm(apart, axis=1) + diameter[gi] + diameter[gj]))
    ok = ((angle <= np.maximum(tolerances.angle, tilt[gi] + tilt[gj]))
          & (np.abs(np.einsum("ki,ki->k", ni, apart)) <= slack) & (np.abs(np.einsum("ki,ki->k", nj, apart)) <= slack))
    return gi[ok], gj[ok], pair_distance[ok]


def _grouped(pairs: np.ndarray):
    """Sorted pairs ``(i, j)`` as the distinct ``i`` and, for each, the array of its ``j``."""
    firsts, starts = np.unique(pairs[:, 0], return_index=True)
    return firsts.tolist(), np.split(pairs[:, 1], starts[1:])


def _overlaps(table: FacetTable, gi, gj, atol, tolerances: _Tolerances) -> tuple[Contact, ...]:
    """Intersect matched facets in block i's facet frame; one Contact per overlap part.

    ``atol`` is each pair's distance tolerance.  Parts whose vertices lie farther than it (plus the gap) from block
    j's facet plane are open, not contacts.  With a gap, the others are moved along block i's normal halfway to
    block j's facet plane (at the part's centroid).
    """
    if not len(gi):
        return ()
    gap = tolerances.gap
    bi, bj = table.bases[gi], table.bases[gj]
    linear = np.einsum("kar,kbr->kab", bi, bj)  # j's plane coordinates -> i's
    shift = np.einsum("kar,kr->ka", bi, table.origins[gj] - table.origins[gi])
    # shapely.set_coordinates works in place and facets are shared between blocks of a type: copy first
    moved = shapely.transform(table.polygons[gj], lambda coords: coords)
    xy, which = shapely.get_coordinates(moved, return_index=True)
    moved = shapely.set_coordinates(moved, np.einsum("kab,kb->ka", linear[which], xy) + shift[which])
    # coplanar facets far apart in their plane cannot overlap: skip them before the (costly) overlay
    box_i, box_j = shapely.bounds(table.polygons[gi]), shapely.bounds(moved)
    apart = np.any((box_i[:, 2:] <= box_j[:, :2] + atol[:, None]) | (box_j[:, 2:] <= box_i[:, :2] + atol[:, None]),
                   axis=1)
    gi, gj, moved, atol = gi[~apart], gj[~apart], moved[~apart], atol[~apart]
    # facets whose outlines do not even touch cannot overlap by more than the area tolerance; the predicate on
    # prepared outlines is far cheaper than the snapped overlay
    shapely.prepare(moved)
    touching = shapely.intersects(moved, table.polygons[gi])
    gi, gj, moved, atol = gi[touching], gj[touching], moved[touching], atol[touching]
    if not len(gi):
        return ()
    # snap rounding on a grid far below every facet's size (a power of two keeps dyadic coordinates exact): in
    # plain floating point GEOS can return a whole square as the overlap of two squares sharing an edge
    box = shapely.bounds(table.polygons[gi])
    extent = float(np.abs(box).max(initial=0.0)) or 1.0
    grid = 2.0 ** math.floor(math.log2(OVERLAY_GRID_RTOL * extent))
    overlap = shapely.intersection(table.polygons[gi], moved, grid_size=grid)
    parts, k = shapely.get_parts(overlap, return_index=True)
    polygonal = shapely.get_type_id(parts) == 3
    parts, k = clean_polygons(parts[polygonal], atol[k[polygonal]]), k[polygonal]
    polygonal = shapely.get_type_id(parts) == 3  # simplification may collapse slivers
    parts, k = parts[polygonal], k[polygonal]
    area, perimeter = shapely.area(parts), shapely.length(parts)
    block_i, block_j = table.block[gi[k]], table.block[gj[k]]
    smallest = np.minimum(tolerances.area[block_i], tolerances.area[block_j])
    keep = (area > smallest) & (2 * area > atol[k] * perimeter)
    parts, k, area, block_i, block_j = parts[keep], k[keep], area[keep], block_i[keep], block_j[keep]
    if not len(parts):
        return ()
    # 3D vertices: every ring without its closing repeat
    rings, ring_part = shapely.get_rings(parts, return_index=True)
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    last = np.r_[ring[1:] != ring[:-1], True]
    xy, ring = xy[~last], ring[~last]
    part = ring_part[ring]
    g = gi[k[part]]
    points = table.origins[g] + np.einsum("va,var->vr", xy, table.bases[g])
    per_part = np.split(points, np.cumsum(np.bincount(part, minlength=len(parts)))[:-1])
    facet_i, facet_j = table.local[gi[k]], table.local[gj[k]]
    order = np.lexsort((np.arange(len(parts)), facet_j, facet_i, block_j, block_i))
    if gap > 0:
        centroids = shapely.get_coordinates(shapely.centroid(parts))
    corners = shapely.bounds(parts).reshape(-1, 2, 2)
    press = np.maximum(atol[k], PRESS_RTOL * np.hypot(*(corners[:, 1] - corners[:, 0]).T))
    found = []
    for p in order:
        g_i, g_j = gi[k[p]], gj[k[p]]
        vertices, origin = per_part[p], table.origins[g_i].copy()
        distance = (vertices - table.origins[g_j]) @ table.normals[g_j]  # > 0: a gap, < 0: i presses into j
        apart, deepest = float(np.abs(distance).max()), float(-distance.min())
        # faces that cross (one presses into the other) within what a tilt of angle_tol over the contact allows
        # are pressed together: a contact whose faces disagree by their spread, never a gap
        pressed = gap == 0 and deepest > atol[k[p]] and apart <= press[p]
        if apart > atol[k[p]] + gap and not pressed:  # open: farther apart than the tolerance of these faces
            continue
        # coincidence up to the last places of the blocks' world coordinates; beyond it the faces are a gap apart
        coincide = max(tolerances.coincide[block_i[p]], tolerances.coincide[block_j[p]])
        separation = max(0.0, float(distance.max())) if apart > coincide and not pressed else 0.0
        if gap > 0:
            separation = apart if apart > atol[k[p]] else 0.0
            # to the mid-plane: halfway along n_i from block i's facet plane to block j's, at the centroid
            n_i, n_j = table.normals[g_i], table.normals[g_j]
            centre = origin + centroids[p] @ table.bases[g_i]
            shift = n_i * (0.5 * ((table.origins[g_j] - centre) @ n_j) / (n_i @ n_j))
            vertices, origin = vertices + shift, origin + shift
        arrays = [table.normals[g_i].copy(), vertices, origin, table.bases[g_i].copy()]
        for array in arrays:
            array.setflags(write=False)
        normal, vertices, origin, basis = arrays
        planar = bool(table.planar[g_i] and table.planar[g_j]) and not pressed
        deviation = float(table.flatness[g_i] + table.flatness[g_j]) + (float(np.ptp(distance)) if pressed else 0.0)
        rounding = max(tolerances.rounding[block_i[p]], tolerances.rounding[block_j[p]])
        tolerance = max(rounding, 0.0 if planar else BEND_FACTOR * deviation)
        found.append(Contact(int(block_i[p]), int(block_j[p]), normal, vertices, float(area[p]),
                             int(facet_i[p]), int(facet_j[p]), parts[p], origin, basis, deviation, planar,
                             separation, float(tolerance)))
    return tuple(found)
