"""What the formats share: the markers of interlock's files, :class:`MeshFile`, block names, classes and colours,
and the blocks' world triangles that the writers store.

Every writer announces its blocks with :func:`file_header` (``interlock blocks=N fixed=K``, and ``unit=`` and
``up=`` where they differ from the defaults), so that a file cut short is found and the unit and up-axis travel
with the file; every reader returns a :class:`MeshFile`.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from numbers import Real
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.classes import block_classes
from interlock.blocks.escher import Block
from interlock.blocks.labels import label_from_text, label_text
from interlock.errors import AssemblyError, GalleryError

__all__ = ["FormatError", "MeshFile", "file_header", "header_counts", "header_words", "flagged_name", "named_frame",
           "touching_bodies", "json_value", "is_label_pair", "stored_meaning", "as_assembly", "exploded_factor",
           "world_triangles", "face_blocks", "instanced_parts", "block_name", "fixed_flags", "label_pairs",
           "one_line_json", "classes", "class_name", "PALETTE", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA",
           "FIXED_DATA", "CLASS_DATA", "MIRRORED_DATA", "FIXED_WORD", "STL_FIXED_BIT", "STL_MAX_FRAMED",
           "OBJ_SECOND_LINE", "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY", "INFO_KEY", "GLTF_TO_Z_UP", "GLTF_SUFFIXES",
           "MAX_NESTING"]


class FormatError(AssemblyError, GalleryError):
    """A file that cannot be read as blocks, or an assembly that cannot be written to one.

    It is both an :class:`~interlock.errors.AssemblyError` (what reading raised before
    :mod:`interlock.formats`) and a :class:`~interlock.errors.GalleryError` (what exporting raised), so code
    that catches either keeps working.
    """


#: How an exported file says that it holds interlock blocks, and how many: the start of a binary STL's
#: 80-byte header, a PLY or OBJ comment, GLB scene extras, 3MF model metadata (see :func:`file_header`).
HEADER_MARKER = b"interlock blocks="
#: One triangle of a binary STL: normal, three vertices, and the 2-byte attribute holding the block index.
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("block", "<u2")])
#: Name of the block index in PLY (vertex or face property), VTU and XDMF (cell data) files.
BLOCK_DATA = "block"
#: Name of the frame flag (1: the block is fixed) in PLY, VTU and XDMF files.
FIXED_DATA = "fixed"
#: Names of each block's class (:func:`classes`) and mirror flag in VTU and XDMF cell data.
CLASS_DATA, MIRRORED_DATA = "class", "mirrored"
#: The last word of the name of a fixed block's object (OBJ ``o block_0007 fixed``), node (GLB) or item (3MF).
FIXED_WORD = "fixed"
#: In a binary STL whose header counts the fixed blocks (``fixed=K``), this bit of each triangle's attribute
#: marks the triangles of fixed blocks, and the 15 bits below it hold the block index.
STL_FIXED_BIT = 1 << 15
#: The most blocks a binary STL stores with their frame: block indices below :data:`STL_FIXED_BIT`.
STL_MAX_FRAMED = STL_FIXED_BIT
#: How the second line of an OBJ export starts (after its :func:`file_header`): a file with it and without a
#: readable header is damaged.
OBJ_SECOND_LINE = "# one object per block, named 'fixed' in the frame"
#: OBJ comment lines: after an ``o`` line, the block's label as the JSON pair ``[kind, text]`` of
#: :func:`~interlock.blocks.labels.label_text`; in the header, ``Assembly.info`` as JSON.
OBJ_LABEL, OBJ_INFO = "# interlock label ", "# interlock info "
#: GLB scene extras, 3MF model metadata and PLY comments: the labels, as ``{block name: [kind, text]}``, and
#: ``Assembly.info`` as JSON.
LABELS_KEY, INFO_KEY = "interlock_labels", "interlock_info"
#: glTF 2.0 says +Y is up; interlock's gravity is along -Z.  This rotation turns +Y-up coordinates into
#: interlock's, ``(x, y, z) -> (x, -z, y)``: reading applies it, writing its inverse (transpose), so a file written
#: and read back has the same coordinates to the last bit (the entries are 0 and +-1).  ``up="y"`` files of the
#: formats without a convention of their own (OBJ, STL, PLY, OFF, VTU, XDMF) use it too.
GLTF_TO_Z_UP = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
#: The suffixes of glTF files, read and written +Y up (:data:`GLTF_TO_Z_UP`).
GLTF_SUFFIXES = (".glb", ".gltf")
#: The deepest nesting of brackets a JSON text may have before it is refused unread: Python's parser recurses
#: once per level and ends in a RecursionError near 1,000 levels; COMPAS files nest about 10 deep.
MAX_NESTING = 200
#: RGBA colours (uint8) for block classes 0, 1, 2, ... (cycled): colour-blind-safe (Okabe-Ito), opaque.  The
#: gallery colours its pictures with the same palette.
PALETTE = np.array([[0, 114, 178, 255], [230, 159, 0, 255], [0, 158, 115, 255], [204, 121, 167, 255],
                    [86, 180, 233, 255], [213, 94, 0, 255], [240, 228, 66, 255], [120, 120, 120, 255]],
                   dtype=np.uint8)
_HEADER = re.compile(re.escape(HEADER_MARKER.decode()) + r"(\d+)(?: fixed=(\d+))?(?: triangles=(\d+))?")
_WORD = re.compile(r"\b(unit|up|classes)=([A-Za-z_]+)")


def file_header(blocks: int, fixed: int | None = None, triangles: int | None = None, unit: str | None = None,
                up: str = "z") -> str:
    """The text by which a file announces its blocks, fixed blocks, (OBJ) triangles, unit and up-axis.

    Reading checks a file against it: a file with fewer blocks or triangles than announced is cut short.

    Examples
    --------
    >>> file_header(27, 3)
    'interlock blocks=27 fixed=3'
    >>> header_counts(file_header(27, 3, triangles=972, unit="mm"))
    (27, 3, 972)
    >>> header_words(file_header(27, 3, unit="mm", up="y"))
    {'unit': 'mm', 'up': 'y'}
    """
    text = HEADER_MARKER.decode() + str(blocks)
    if fixed is not None:
        text += f" fixed={fixed}"
    if triangles is not None:
        text += f" triangles={triangles}"
    if unit is not None:
        text += f" unit={unit}"
    if up != "z":
        text += f" up={up}"
    return text


@dataclass(frozen=True)
class MeshFile:
    """The blocks of a file: names and meshes (file coordinates) in file order, and what the file stores.

    ``frame`` lists the indices of the blocks that the file marks fixed, or is None when the file stores no frame.
    ``announced`` is the number of blocks that the file says it holds, or None.  ``labels`` maps block names to
    the labels the file stores for them, ``info`` is the ``Assembly.info`` it stores (plain values) or None,
    ``unit`` the unit it states (None: none) and ``extra`` what else travels into ``Assembly.info`` (the classes
    of VTU and XDMF files, the names, layers and user text of ``.3dm`` files), and ``up`` the up-axis of the
    coordinates as read (``"y"``: :data:`GLTF_TO_Z_UP` turns them to interlock's +Z up).
    """

    names: tuple[str, ...]
    meshes: tuple[trimesh.Trimesh, ...]
    frame: tuple[int, ...] | None = None
    announced: int | None = None
    labels: dict = field(default_factory=dict)
    info: dict | None = None
    unit: str | None = None
    extra: dict = field(default_factory=dict)
    up: str = "z"


def header_counts(text) -> tuple[int, int | None, int | None] | None:
    """(blocks, fixed, triangles) from a :func:`file_header` in ``text``; None without one."""
    if isinstance(text, bytes):
        text = text.decode("ascii", errors="replace")
    match = _HEADER.search(text or "")
    if match is None:
        return None
    return tuple(None if group is None else int(group) for group in match.groups())


def header_words(text) -> dict[str, str]:
    """The ``unit=``, ``up=`` (and, VTU and XDMF, ``classes=``) words of a :func:`file_header` in ``text``."""
    if isinstance(text, bytes):
        text = text.decode("ascii", errors="replace")
    match = _HEADER.search(text or "")
    if match is None:
        return {}
    line = text[match.start():].split("\n", 1)[0]
    return {key: value for key, value in _WORD.findall(line)}


def flagged_name(name: str) -> tuple[str, bool]:
    """``'block_0007 fixed'`` -> ``('block_0007', True)``; other names unchanged."""
    stem, _, last = name.strip().rpartition(" ")
    return (stem.rstrip(), True) if stem and last.lower() == FIXED_WORD else (name.strip(), False)


def named_frame(path: Path, fixed, header) -> tuple[int, ...] | None:
    """The blocks whose names end in :data:`FIXED_WORD` (``fixed``: a flag per block); None if none does and
    the file has no header (``header``: what :func:`header_counts` found, or None)."""
    frame = tuple(k for k, flag in enumerate(fixed) if flag)
    if header is not None and header[1] is not None and header[1] != len(frame):
        raise FormatError(f"{path} is cut short or damaged: it announces {header[1]} fixed blocks, its "
                          f"names mark {len(frame)}")
    return frame if frame or header is not None else None


def touching_bodies(path: Path) -> str:
    """The error for bodies that touch in a file that cannot tell them apart."""
    if path.suffix.lower() == ".obj":
        return (f"{path} holds several bodies that touch and share vertices (welded), which an OBJ file without "
                "objects cannot separate; give each block its own object ('o') or group ('g'), or export with "
                "vertices not welded (merged) across blocks")
    return (f"{path} holds several bodies that touch, which a single {path.suffix} file cannot separate; give one "
            "file per block, or an OBJ file with one object ('o') or group ('g') per block")


def json_value(text):
    """The value of a JSON text; None for one that is not JSON (or nests deeper than :data:`MAX_NESTING`)."""
    text = text or ""
    if isinstance(text, (bytes, str)) and text.count("[" if isinstance(text, str) else b"[") + text.count(
            "{" if isinstance(text, str) else b"{") > MAX_NESTING and nesting(text) > MAX_NESTING:
        return None  # only a text with that many brackets can nest that deep
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        return None


def nesting(text) -> int:
    """How deep the brackets of a JSON text nest at most (brackets inside strings counted too: an upper bound).

    >>> nesting('{"a": [[1], 2]}'), nesting("[" * 5)
    (3, 5)
    """
    data = text.encode() if isinstance(text, str) else bytes(text)
    steps = np.frombuffer(data, dtype=np.uint8)
    change = np.isin(steps, (ord("["), ord("{"))).astype(np.int64) - np.isin(steps, (ord("]"), ord("}")))
    return int(np.cumsum(change).max(initial=0))


def stored_meaning(stored: dict) -> tuple[dict, dict | None]:
    """``({block name: label}, info)`` from what a GLB, 3MF or PLY file stores under :data:`LABELS_KEY` (a
    ``{block name: [kind, text]}`` dict) and :data:`INFO_KEY` (a dict).  What is not as the writers write it (a
    file edited by hand) is left out."""
    pairs, info = stored.get(LABELS_KEY), stored.get(INFO_KEY)
    labels = {name: label_from_text(*pair) for name, pair in pairs.items() if is_label_pair(pair)} \
        if isinstance(pairs, dict) else {}
    return labels, info if isinstance(info, dict) else None


def is_label_pair(value) -> bool:
    """Whether ``value`` is a ``[kind, text]`` pair of :func:`~interlock.blocks.labels.label_text`."""
    return isinstance(value, list) and len(value) == 2 and all(isinstance(v, str) for v in value)


# --- writing --------------------------------------------------------------------------------------
def as_assembly(obj) -> Assembly:
    """A block, a mesh or an assembly as an :class:`~interlock.blocks.Assembly`.

    >>> from interlock.blocks import presets
    >>> len(as_assembly(presets.cube_grid().mesh(0)))
    1
    """
    if isinstance(obj, Assembly):
        return obj
    if isinstance(obj, Block):
        return Assembly.from_meshes([obj.mesh], info={"group": obj.group.name})
    if isinstance(obj, trimesh.Trimesh):
        return Assembly.from_meshes([obj])
    raise FormatError(f"expected a Block, an Assembly or a trimesh.Trimesh, got {type(obj).__name__}")


def exploded_factor(exploded) -> float:
    """``exploded`` as a factor: a finite number >= 0, else a :class:`FormatError`."""
    if isinstance(exploded, bool) or not isinstance(exploded, Real) or not math.isfinite(exploded) or exploded < 0:
        raise FormatError(f"exploded must be a finite number >= 0 (0 keeps the blocks in place), got {exploded!r}")
    return float(exploded)


def world_triangles(assembly: Assembly) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every block's vertices and outward faces in world coordinates, blocks in order.

    Returns ``vertices (V, 3)``, ``faces (F, 3)`` (indices into ``vertices``) and the offsets
    ``vertex_start (n + 1,)``, ``face_start (n + 1,)``: block ``i`` owns
    ``vertices[vertex_start[i]:vertex_start[i + 1]]`` and likewise faces.  One ``einsum`` per block type.
    """
    n_vertices = np.array([len(m.vertices) for m in assembly.meshes], dtype=int)[assembly.types]
    n_faces = np.array([len(m.faces) for m in assembly.meshes], dtype=int)[assembly.types]
    vertex_start = np.concatenate([[0], np.cumsum(n_vertices)])
    face_start = np.concatenate([[0], np.cumsum(n_faces)])
    vertices = np.empty((vertex_start[-1], 3))
    faces = np.empty((face_start[-1], 3), dtype=np.int64)
    for t, mesh in enumerate(assembly.meshes):
        blocks = np.flatnonzero(assembly.types == t)
        if not blocks.size:
            continue
        placed = np.einsum("nij,vj->nvi", assembly.transforms[blocks, :3, :3], mesh.vertices)
        placed += assembly.transforms[blocks, None, :3, 3]
        vertices[vertex_start[blocks, None] + np.arange(len(mesh.vertices))] = placed
        own = mesh.faces[None] + vertex_start[blocks, None, None]
        mirrored = assembly.mirrored[blocks]
        own[mirrored] = own[mirrored][:, :, ::-1]  # a reflection turns the winding inside out
        faces[face_start[blocks, None] + np.arange(len(mesh.faces))] = own
    return vertices, faces, vertex_start, face_start


def face_blocks(face_start: np.ndarray) -> np.ndarray:
    """The block of every face, from the offsets of :func:`world_triangles`."""
    return np.repeat(np.arange(len(face_start) - 1), np.diff(face_start))


# Turns a mirror-image placement T into the proper one T @ _MIRROR of the mirrored mesh _MIRROR(mesh).
_MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


def instanced_parts(assembly: Assembly) -> tuple[list[trimesh.Trimesh], np.ndarray, np.ndarray, np.ndarray]:
    """Shared meshes for instancing (GLB, 3MF): one per block type, mirroring and class.

    Returns the part meshes (mirror images stored mirrored, outward), each part's class, each block's part and
    each block's placement of its part, a proper rigid motion.
    """
    values, _ = classes(assembly)
    mirrored = assembly.mirrored
    keys = np.column_stack([assembly.types, mirrored, values])
    unique, first, part_of = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    meshes = [assembly.meshes[t].copy().apply_transform(_MIRROR) if m else assembly.meshes[t]
              for t, m, _ in unique]
    placements = assembly.transforms.copy()
    placements[mirrored] = placements[mirrored] @ _MIRROR
    return meshes, values[first], part_of.ravel(), placements


def classes(assembly: Assembly) -> tuple[np.ndarray, str]:
    """Each block's class and what classes mean: those a file stored (``info["classes"]`` and
    ``info["class_kind"]``, read from VTU, XDMF and ``.3dm`` files) if they fit, else
    :func:`~interlock.blocks.classes.block_classes` (coset, orientation, cell block or mesh type)."""
    stored, kind = assembly.info.get("classes"), assembly.info.get("class_kind")
    if (isinstance(stored, (list, tuple)) and len(stored) == len(assembly) and isinstance(kind, str)
            and all(isinstance(c, (int, np.integer)) and not isinstance(c, bool) and c >= 0 for c in stored)):
        return np.asarray(stored, dtype=int), kind
    return block_classes(assembly)


def class_name(kind: str, value: int) -> str:
    """The one name of a class in every format: material (OBJ, GLB, 3MF) and layer (3dm), e.g. ``coset_1``.

    >>> class_name("cell block", 2)
    'cell_block_2'
    """
    return f"{kind.replace(' ', '_')}_{value}"


def block_name(i: int, fixed=()) -> str:
    """The name of block ``i`` in OBJ objects, GLB nodes and 3MF items: ``block_0007``, ``block_0007 fixed``."""
    return f"block_{i:04d} {FIXED_WORD}" if i in fixed else f"block_{i:04d}"


def fixed_flags(assembly: Assembly) -> np.ndarray:
    """Whether each block is in the frame."""
    fixed = np.zeros(len(assembly), dtype=bool)
    fixed[list(assembly.frame)] = True
    return fixed


def label_pairs(assembly: Assembly) -> dict[str, list[str]]:
    """``{block name: [kind, text]}`` (:func:`~interlock.blocks.labels.label_text`), the names without ``fixed``."""
    return {block_name(i): list(label_text(label)) for i, label in enumerate(assembly.labels)}


def one_line_json(value) -> str:
    """``value`` as one line of JSON (``Assembly.info`` through :func:`~interlock.blocks.info.plain`)."""
    return json.dumps(value, allow_nan=False, separators=(",", ":"))
