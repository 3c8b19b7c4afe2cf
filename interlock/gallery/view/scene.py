"""What the viewer draws, as JSON: one mesh per kind of block, a placement per block, the motion and the forces."""

from __future__ import annotations

import base64
import math

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.blocks.classes import block_classes
from interlock.errors import GalleryError
from interlock.gallery.appearance import PALETTE, as_assembly
from interlock.gallery.view.collapse import collapse_twists
from interlock.gallery.view.words import details, plain_sentence
from interlock.verify.contacts import contacts as find_contacts
from interlock.verify.motion import twist_exponential

__all__ = ["scene", "MOTION_STEPS", "FIRST_ORDER_REACH", "TURN_REACH", "FRAME_COLOUR", "MOVING_COLOUR",
           "SCENE_VERSION", "CLASS_WORDS", "MOTION_START", "shared_geometry", "SHARE_RTOL"]

#: The format of the scene the page's script reads; raised when its keys change.
SCENE_VERSION = 1
#: Placements of the moving blocks stored along a motion; the page interpolates between them.
MOTION_STEPS = 32
#: A first-order motion (or a collapse mechanism) is drawn until some vertex has moved this many block sizes: the
#: twist names a direction, not a distance, so the picture shows a block's worth of it.
FIRST_ORDER_REACH = 0.8
#: ... or until some block has turned this many radians, whichever comes first.
TURN_REACH = math.pi / 6
#: Meshes share a geometry when their vertices, less their mean, agree within this share of the mesh's size
#: (float32 files round at 6e-8 of a coordinate; a difference of 1e-6 of a block is not seen).
SHARE_RTOL = 1e-6
#: How the legend names the classes of :func:`~interlock.blocks.classes.block_classes`.
CLASS_WORDS = {"coset": "coset", "orientation": "lozenge orientation", "cell block": "cell block",
               "type": "block shape"}
#: Where the motion's slider starts: part of the way, so that a still picture shows which blocks move and how.
MOTION_START = 0.4
#: The frame's colour: muted grey, apart from the palette of the classes.
FRAME_COLOUR = "#a8a8a8"
#: The moving blocks' colour: crimson, apart from the palette of the classes.
MOVING_COLOUR = "#dc143c"


def scene(obj, verdict=None, stability=None, *, title: str | None = None, contacts=None,
          frame_words: str | None = None) -> dict:
    """The viewer's scene of an assembly, with the verdict of :func:`~interlock.verify.check` and a stability result.

    Parameters
    ----------
    obj : Assembly, Block or trimesh.Trimesh
    verdict : Verdict, optional
        Its frame is the one drawn (else the assembly's); the moving blocks
        are highlighted and the motion stored: the finite motion shown
        (``order=2``), else the first-order twist.
    stability : StabilityResult or CRAResult, optional
        Contact forces (resultant per contact at its centre of pressure) when
        stable; when unstable, the collapse mechanism of
        :func:`~interlock.gallery.view.collapse.collapse_twists` as the motion
        (unless the verdict already has one).
    title : str, optional
    contacts : sequence of Contact, optional
        Used for each block's list of contacts; default: with a verdict, the
        face contacts of :func:`~interlock.verify.contacts` (as the verdict
        found them), else the blocks whose boxes touch
        (:attr:`Assembly.neighbours <interlock.blocks.Assembly.neighbours>`).
    frame_words : str, optional
        How the plain sentence names the frame (e.g. "the outer ring").

    Returns
    -------
    dict
        JSON-ready; arrays are base64 little-endian float32 or uint32.
        World coordinates are shifted so that the assembly's box is centred
        at the origin (``offset`` is the shift), so float32 keeps the detail of
        an assembly far from the origin.

    Examples
    --------
    >>> from interlock.blocks import presets
    >>> from interlock.verify import check
    >>> s = scene(presets.cube_grid(), check(presets.cube_grid()))
    >>> s["blocks"]["count"], s["blocks"]["frame"], s["motion"]["moving"], s["motion"]["kind"]
    (9, [0, 1, 2, 3, 5, 6, 7, 8], [4], 'first-order')
    >>> s["sentence"]
    'With the outer ring (8 blocks) fixed, block 4 can start to move straight up: no contact stops it at first order.'
    """
    assembly = as_assembly(obj)
    if len(assembly) == 0:
        raise GalleryError("the assembly has no blocks: there is nothing to view")
    frame = tuple(int(b) for b in (verdict.frame if verdict is not None else assembly.frame))
    _check_matches(assembly, verdict, stability, frame)
    if contacts is None and verdict is not None:
        contacts = find_contacts(assembly)
    bounds = assembly.bounds
    low, high = bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)
    offset = (low + high) / 2
    shift = np.eye(4)
    shift[:3, 3] = -offset
    geometries, types, local = shared_geometry(assembly)
    placements = shift @ local
    classes, kind = block_classes(assembly)
    if kind == "type" and classes.max() >= len(PALETTE):  # shapes of their own (an arch's voussoirs): one colour
        classes, kind = np.zeros_like(classes), "blocks"
    names = [f"{CLASS_WORDS.get(kind, kind)} {k}" for k in range(int(classes.max()) + 1)] if kind != "blocks" \
        else ["blocks"]
    motion = _motion(assembly, verdict, stability, shift, local)
    return {
        "version": SCENE_VERSION,
        "title": title or str(assembly.info.get("name") or f"{len(assembly)} blocks"),
        "sentence": plain_sentence(assembly, verdict, stability, frame_words=frame_words),
        "details": details(verdict, stability),
        "offset": [float(v) for v in offset],
        "size": float(np.linalg.norm(high - low)) or 1.0,
        "block_size": float(assembly.block_size),
        "up": [0.0, 0.0, 1.0],
        "geometries": [{"position": _floats(v), "index": _uints(f)} for v, f in geometries],
        "blocks": {
            "count": len(assembly),
            "type": [int(t) for t in types],
            "matrix": _floats(placements.transpose(0, 2, 1)),  # column-major, as three.js's Matrix4.fromArray
            "class": [int(c) for c in classes],
            "label": [_label(label, k) for k, label in enumerate(assembly.labels)],
            "volume": [float(f"{v:.6g}") for v in assembly.volumes],
            "frame": list(frame),
            **_neighbour_lists(assembly, contacts),
        },
        "classes": {"kind": kind, "names": names,
                    "colours": ["#%02x%02x%02x" % tuple(PALETTE[k % len(PALETTE)][:3]) for k in range(len(names))]},
        "frame_colour": FRAME_COLOUR,
        "moving_colour": MOVING_COLOUR,
        "motion": motion,
        "forces": _forces(assembly, stability, shift),
    }


def shared_geometry(assembly: Assembly) -> tuple[list, np.ndarray, np.ndarray]:
    """One geometry per set of meshes that are translates of one another, and each block's placement of it.

    A file read back (STL, OBJ, GLB, ...) gives every block a mesh of its own,
    in world coordinates; congruent blocks placed by translations (RhomBlocks of
    one orientation, Escher blocks of one coset) then share a geometry again:
    meshes with the same faces whose vertices, less their mean, agree within
    :data:`SHARE_RTOL` of the mesh's size.  Returns ``(geometries, types,
    placements)``: ``(vertices, faces)`` per geometry (vertices about their
    mean), the geometry of each block, and its (n, 4, 4) world placement.

    >>> from interlock.blocks import Assembly, presets
    >>> grid = presets.cube_grid()
    >>> loose = Assembly.from_meshes(grid.world_meshes())  # nine meshes, as a file gives them
    >>> geometries, types, placements = shared_geometry(loose)
    >>> len(loose.meshes), len(geometries), types.tolist()
    (9, 1, [0, 0, 0, 0, 0, 0, 0, 0, 0])
    """
    groups, geometries, of_mesh, centres = {}, [], [], []
    for mesh in assembly.meshes:
        vertices = np.asarray(mesh.vertices, dtype=float)
        centre = vertices.mean(axis=0) if len(vertices) else np.zeros(3)
        about = vertices - centre
        size = float(np.abs(about).max(initial=0.0)) or 1.0
        key = (np.asarray(mesh.faces).tobytes(), np.round(about / (SHARE_RTOL * size)).astype(np.int64).tobytes())
        if key not in groups:
            groups[key] = len(geometries)
            geometries.append((about, np.asarray(mesh.faces)))
        of_mesh.append(groups[key])
        centres.append(centre)
    move = np.tile(np.eye(4), (len(centres), 1, 1))
    move[:, :3, 3] = centres
    types = np.asarray(of_mesh, dtype=int)[assembly.types]
    return geometries, types, assembly.transforms @ move[assembly.types]


def _check_matches(assembly: Assembly, verdict, stability, frame) -> None:
    """A verdict or stability result of another assembly (other blocks) is refused, saying so."""
    n = len(assembly)
    motion = getattr(verdict, "motion", None)
    used = [*frame, *getattr(verdict, "moving", ())]
    if stability is not None:
        used += [b for c in stability.contacts for b in (c.i, c.j)] + list(stability.parameters.get("frame") or ())
    if (motion is not None and len(motion) != n) or any(not 0 <= int(b) < n for b in used):
        raise GalleryError(f"the verdict or stability result names blocks this assembly of {n} blocks does not have: "
                           "give the assembly it was computed for")


# --- the motion ---------------------------------------------------------------------------------


def _motion(assembly: Assembly, verdict, stability, shift, local) -> dict | None:
    """The moving blocks' placements along the motion to show, or None."""
    finite = getattr(verdict, "finite_motion", None)
    if finite is not None and getattr(finite, "shown", False) and finite.path is not None:
        last = finite.parameters[-1] if finite.parameters else finite.start
        steps = np.linspace(finite.start, last, MOTION_STEPS)
        moving = [int(b) for b in finite.moving]
        return _sampled(finite.path, steps, moving, shift, local, "finite",
                        f"the finite motion shown ({finite.ending}), from its start to its last step")
    if verdict is not None and verdict.motion is not None and verdict.moving and verdict.interlocked is not True:
        twists = np.asarray(verdict.motion, dtype=float)
        return _twist(assembly, twists, verdict.moving, shift, "first-order",
                      "the first-order motion (a direction the contacts allow; not shown to be a finite motion)")
    if stability is not None and stability.stable is False:
        twists = collapse_twists(assembly, stability)
        if twists is not None:
            moving = np.flatnonzero(np.abs(twists).max(axis=1) > 1e-9 * np.abs(twists).max())
            return _twist(assembly, twists, moving, shift, "collapse",
                          "a collapse mechanism: the blocks move so that every contact opens or slides within its "
                          "friction cone while their weight does work (why no forces can carry it)")
    return None


def _twist(assembly: Assembly, twists: np.ndarray, moving, shift, kind: str, caption: str) -> dict | None:
    """A twist per moving block, which the page follows by the SE(3) exponential (as
    :func:`~interlock.verify.motion.twist_exponential`) from 0 to ``end``: until a vertex has moved
    :data:`FIRST_ORDER_REACH` block sizes or a block turned :data:`TURN_REACH`.  Six numbers a block, however
    many blocks move (4,521 blocks of a hexagon read back from a file: 0.2 MB, not 12 MB of sampled placements)."""
    moving = [int(b) for b in moving]
    corners = assembly.bounds[moving]  # (m, 2, 3): the moving blocks' boxes bound their vertices' speeds
    reach = np.linalg.norm(corners[:, 1] - corners[:, 0], axis=1) / 2
    centres = assembly.centroids[moving]
    middle = corners.mean(axis=1)
    omega, t = twists[moving, :3], twists[moving, 3:]
    arm = np.linalg.norm(middle - centres, axis=1) + reach
    speed = float((np.linalg.norm(t, axis=1) + np.linalg.norm(omega, axis=1) * arm).max())
    turn = float(np.linalg.norm(omega, axis=1).max())
    if speed <= 0:
        return None
    end = FIRST_ORDER_REACH * assembly.block_size / speed
    if turn > 0:
        end = min(end, TURN_REACH / turn)
    return {"kind": kind, "caption": caption, "moving": moving, "start_at": MOTION_START, "end": float(end),
            "twists": _floats(twists[moving]), "centres": _floats(centres + shift[:3, 3])}


def _sampled(path, steps, moving, shift, world, kind: str, caption: str) -> dict:
    """The moving blocks' placements at each step: ``shift @ path(s) @ world`` (``world``: the placements of the
    shared geometries; the world motion ``path(s)`` acts before the shift to the view's centre)."""
    matrices = np.stack([shift @ path(float(s))[moving] @ world[moving] for s in steps])
    return {"kind": kind, "caption": caption, "moving": moving, "start_at": MOTION_START, "steps": len(steps),
            "parameters": [float(f"{s:.6g}") for s in steps],
            "matrices": _floats(matrices.transpose(0, 1, 3, 2))}


# --- forces ---------------------------------------------------------------------------------------


def _forces(assembly: Assembly, stability, shift) -> dict | None:
    """Per contact that carries load: the resultant force on block ``j`` and its centre of pressure."""
    if stability is None or stability.stable is not True:
        return None
    forces = np.asarray(stability.forces, dtype=float)
    if not len(forces) or not np.isfinite(forces).all():
        return None
    found = stability.contacts
    which = np.asarray(stability.vertex_contact, dtype=int)
    axes = np.array([[c.normal, c.basis[0], c.basis[1]] for c in found])[which]  # (s, 3, 3)
    world = np.einsum("sk,skd->sd", forces, axes)
    resultants = np.zeros((len(found), 3))
    np.add.at(resultants, which, world)
    normal = np.zeros(len(found))
    np.add.at(normal, which, forces[:, 0])
    moments = np.zeros((len(found), 3))
    np.add.at(moments, which, forces[:, :1] * np.asarray(stability.points, dtype=float))
    loaded = normal > 1e-9 * max(float(normal.max(initial=0.0)), 1e-300)
    if not loaded.any():
        return None
    centres = moments[loaded] / normal[loaded, None]
    centres = centres + shift[:3, 3]
    pairs = [[int(c.i), int(c.j)] for c, keep in zip(found, loaded) if keep]
    magnitude = np.linalg.norm(resultants[loaded], axis=1)
    return {"count": int(loaded.sum()), "points": _floats(centres), "vectors": _floats(resultants[loaded]),
            "pairs": pairs, "largest": float(magnitude.max()),
            "caption": "arrows: the resultant contact force on the second block of each contact, at its centre of "
                       "pressure; length and colour by magnitude"}


# --- helpers --------------------------------------------------------------------------------------


def _neighbour_lists(assembly: Assembly, contacts) -> dict:
    """Each block's contacts as compressed rows: ``neighbours[start[k]:start[k + 1]]``."""
    if contacts is not None:
        pairs = np.array([(c.i, c.j) for c in contacts], dtype=int).reshape(-1, 2)
        source = "face contacts"
    else:
        pairs = np.array(list(assembly.neighbours.edges()), dtype=int).reshape(-1, 2)
        source = "touching boxes"
    both = np.vstack([pairs, pairs[:, ::-1]])
    both = np.unique(both, axis=0) if len(both) else both
    start = np.searchsorted(both[:, 0], np.arange(len(assembly) + 1)) if len(both) else np.zeros(len(assembly) + 1)
    return {"neighbour_start": [int(v) for v in start], "neighbours": [int(v) for v in both[:, 1]] if len(both) else [],
            "neighbour_source": source}


def _label(label, k: int) -> str:
    return f"block {k}" if label is None else str(label)


def _floats(values) -> str:
    array = np.ascontiguousarray(np.asarray(values, dtype=float), dtype="<f4")
    if not np.isfinite(array).all():
        raise GalleryError("the assembly has coordinates that are not finite numbers: there is nothing to draw")
    return base64.b64encode(array.tobytes()).decode("ascii")


def _uints(values) -> str:
    return base64.b64encode(np.ascontiguousarray(values, dtype="<u4").tobytes()).decode("ascii")
