"""Reading mesh files: the blocks a file holds (by stored index, by object, or by body) and the frame it stores."""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import re
import warnings
import zipfile
from dataclasses import dataclass, field
from xml.etree import ElementTree
from pathlib import Path

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from interlock.blocks.repair import (closed_groups, group_meshes, split_t_junctions, triangulate_polygons,
                                     unmatched_edges)
from interlock.blocks.labels import label_from_text
from interlock.errors import AssemblyError

__all__ = ["MeshFile", "read_mesh_file", "file_header", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA",
           "FIXED_DATA", "FIXED_WORD", "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE", "OBJ_LABEL",
           "OBJ_INFO", "LABELS_KEY", "INFO_KEY", "GLTF_TO_Z_UP",
           "GLTF_SUFFIXES"]

#: How an exported file says that it holds interlock blocks, and how many: the start of a binary STL's
#: 80-byte header, a PLY or OBJ comment, GLB scene extras, 3MF model metadata (see :func:`file_header`).
HEADER_MARKER = b"interlock blocks="
#: One triangle of a binary STL: normal, three vertices, and the 2-byte attribute holding the block index.
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("block", "<u2")])
#: Name of the per-triangle block index in PLY (face property), VTU and XDMF (cell data) files.
BLOCK_DATA = "block"
#: Name of the per-triangle frame flag (1: the triangle's block is fixed) in PLY, VTU and XDMF files.
FIXED_DATA = "fixed"
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
#: OBJ comment lines of :func:`~interlock.gallery.export.export`: after an ``o`` line, the block's label as the
#: JSON pair ``[kind, text]`` of :func:`~interlock.blocks.labels.label_text`; in the header, ``Assembly.info``
#: as JSON (:func:`~interlock.blocks.info.plain`).
OBJ_LABEL, OBJ_INFO = "# interlock label ", "# interlock info "
#: GLB scene extras and 3MF model metadata of :func:`~interlock.gallery.export.export`: the labels, as
#: ``{block name: [kind, text]}``, and ``Assembly.info`` as JSON.
LABELS_KEY, INFO_KEY = "interlock_labels", "interlock_info"
#: glTF 2.0 says +Y is up; interlock's gravity is along -Z.  This rotation turns glTF coordinates into
#: interlock's, ``(x, y, z) -> (x, -z, y)``: reading applies it to every node, writing its inverse (transpose),
#: so a file written and read back has the same coordinates to the last bit (the entries are 0 and +-1).
GLTF_TO_Z_UP = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
#: The suffixes of glTF files, read and written +Y up (:data:`GLTF_TO_Z_UP`).
GLTF_SUFFIXES = (".glb", ".gltf")
# The formats read by meshio (:func:`_meshio_triangles`).
_MESHIO_SUFFIXES = (".vtu", ".xdmf")
# an ASCII STL vertex line with a coordinate NaN or infinite (as Python and trimesh parse them)
_NOT_FINITE_VERTEX = re.compile(rb"(?im)^[ \t]*vertex[ \t][^\n]*?(?<![\w.])[-+]?(?:nan|inf(?:inity)?)\b")
_HEADER = re.compile(re.escape(HEADER_MARKER.decode()) + r"(\d+)(?: fixed=(\d+))?(?: triangles=(\d+))?")


def file_header(blocks: int, fixed: int | None = None, triangles: int | None = None) -> str:
    """The text by which an exported file announces its blocks, fixed blocks and (OBJ) triangles.

    Loading checks a file against it: a file with fewer blocks or triangles
    than announced is cut short.

    Examples
    --------
    >>> file_header(27, 3)
    'interlock blocks=27 fixed=3'
    >>> _announced(file_header(27, 3, triangles=972))
    (27, 3, 972)
    """
    text = HEADER_MARKER.decode() + str(blocks)
    if fixed is not None:
        text += f" fixed={fixed}"
    if triangles is not None:
        text += f" triangles={triangles}"
    return text


@dataclass(frozen=True)
class MeshFile:
    """The blocks of a mesh file: names and meshes (file coordinates) in file order, and the stored frame.

    ``frame`` lists the indices of the blocks that the file marks fixed, or is
    None when the file stores no frame.  ``announced`` is the number of
    blocks that the file says it holds (its :func:`file_header`, or its
    block indices), or None if it does not say.  ``labels`` maps block names
    to the labels the file stores for them (OBJ, GLB and 3MF files of
    :func:`~interlock.gallery.export.export`; :mod:`~interlock.blocks.labels`),
    and ``info`` is the ``Assembly.info`` it stores (plain values), or None.
    """

    names: tuple[str, ...]
    meshes: tuple[trimesh.Trimesh, ...]
    frame: tuple[int, ...] | None = None
    announced: int | None = None
    labels: dict = field(default_factory=dict)
    info: dict | None = None


def read_mesh_file(path, split: bool = True) -> MeshFile:
    r"""The blocks and the frame of a mesh file.

    Stored block indices win (STL, PLY, VTU, XDMF from
    :func:`~interlock.gallery.export.export`), then the file's objects (OBJ
    ``o``, or ``g`` groups in a file without ``o``, GLB nodes, 3MF items), then, for OBJ, the
    bodies that share vertex indices or else runs of ``v`` lines.  The frame is read from where
    :func:`~interlock.gallery.export.export` writes it: the STL attribute bit
    :data:`STL_FIXED_BIT`, the PLY, VTU and XDMF triangle data
    :data:`FIXED_DATA`, object, node and item names ending in
    :data:`FIXED_WORD`.  glTF files (``.glb``, ``.gltf``) are +Y up, as the glTF
    specification says; their coordinates are turned to interlock's +Z up
    (:data:`GLTF_TO_Z_UP`).  Warnings of the readers are silenced: a file is
    read, or an :class:`AssemblyError` says in one line why not.

    Parameters
    ----------
    path : str or Path
    split : bool
        Split a file holding one object into its connected bodies.  Without,
        the file is to be one block, so a file announcing several is refused.

    Returns
    -------
    MeshFile

    Raises
    ------
    AssemblyError
        For a missing, empty or unreadable file, one with fewer blocks, fixed blocks
        or triangles than it announces (cut short), coordinates that are not finite
        numbers, or touching bodies in one plain file (or welded in one OBJ object).

    Examples
    --------
    >>> import tempfile
    >>> def tetrahedron(name, x):
    ...     corners = "".join(f"v {x + a} {b} {c}\n" for a, b, c in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)])
    ...     return f"o {name}\n{corners}f -4 -2 -3\nf -4 -3 -1\nf -3 -2 -1\nf -4 -1 -2\n"
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "two.obj"
    ...     _ = path.write_text(tetrahedron("left", 0) + tetrahedron("right fixed", 2))
    ...     found = read_mesh_file(path)
    >>> found.names, found.frame, [round(float(m.volume), 6) for m in found.meshes]
    (('left', 'right'), (1,), [0.166667, 0.166667])
    """
    path = _mesh_path(path)
    reader = {".obj": _obj_file, ".stl": _stl_file, ".ply": _indexed_file, ".vtu": _indexed_file,
              ".xdmf": _indexed_file}.get(path.suffix.lower(), _scene_file)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        found = _read(path, reader, split)
    return found


def _read(path: Path, reader, split: bool) -> MeshFile:
    """The blocks of the file ``path`` by ``reader``, checked (:func:`read_mesh_file`)."""
    try:
        found, separated = reader(path)
        if found is None:  # a plain STL or PLY file
            found, separated = _scene_file(path)
    except AssemblyError:
        raise
    except Exception as error:  # the readers raise many types for unreadable files
        raise AssemblyError(f"cannot read {path} as a mesh ({type(error).__name__}: {error})") from None
    if not found.meshes:
        raise AssemblyError(f"{path} holds no triangle mesh")
    if not all(np.isfinite(mesh.vertices).all() for mesh in found.meshes):
        raise AssemblyError(f"{path} has vertex coordinates that are not finite numbers (NaN or infinity)")
    if found.announced is not None and found.announced != len(found.meshes):
        raise AssemblyError(f"{path} is cut short or damaged: it announces {found.announced} blocks, "
                            f"it holds {len(found.meshes)}")
    if not split and len(found.meshes) > 1 and found.announced is not None:
        raise AssemblyError(f"{path} holds {len(found.meshes)} blocks, which would merge into one in a list of "
                            f"one file per block; load it on its own: Assembly.load({str(path)!r})")
    if split and not separated and len(found.meshes) == 1:
        found = _splitgroup_meshes(path, found)
    return found


def _mesh_path(path) -> Path:
    """``path`` as a Path to an existing file; an :class:`AssemblyError` that says what it is otherwise."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise AssemblyError(f"a mesh file is given by its path (str or path-like), got {type(path).__name__}")
    path = Path(os.fsdecode(path))
    if path.is_dir():
        raise AssemblyError(f"{path} is a folder, not a mesh file; give the files in it, e.g. {path}/*.obj")
    if not path.exists():
        raise AssemblyError(f"mesh file {path} does not exist")
    if not path.is_file():
        raise AssemblyError(f"{path} is not a regular file (a pipe, socket or device); save the mesh to a file "
                            "and give that")
    if path.stat().st_size == 0 and path.suffix.lower() not in _MESHIO_SUFFIXES:  # meshio's reader says so itself
        raise AssemblyError(f"{path} is empty (0 bytes): it holds no mesh")
    return path


def readgroup_meshes(path, split: bool = True) -> list[tuple[str, trimesh.Trimesh]]:
    """(name, mesh in file coordinates) for every block of a mesh file, in file order (:func:`read_mesh_file`)."""
    found = read_mesh_file(path, split)
    return list(zip(found.names, found.meshes))


# --- bodies --------------------------------------------------------------------
def _splitgroup_meshes(path: Path, found: MeshFile) -> MeshFile:
    """A file's one body split into its connected bodies (sharing an edge, T-junctions split first).

    Bodies that touch share edges of more than two triangles and fall apart
    into open pieces; a single STL or PLY file cannot tell them apart.
    """
    mesh = found.meshes[0]
    if len(unmatched_edges(mesh.faces)):
        mesh = trimesh.Trimesh(mesh.vertices, split_t_junctions(mesh.vertices, mesh.faces), process=False)
    parts = mesh.split(only_watertight=False)
    if len(parts) <= 1:
        return found
    if not all(part.is_watertight for part in parts):
        raise AssemblyError(_touching(path))
    frame = None if found.frame is None else tuple(range(len(parts))) if found.frame else ()
    return MeshFile(tuple(f"body{k}" for k in range(len(parts))), tuple(parts), frame)


def _touching(path: Path) -> str:
    """The error for bodies that touch in a file that cannot tell them apart."""
    if path.suffix.lower() == ".obj":
        return (f"{path} holds several bodies that touch and share vertices (welded), which an OBJ file without "
                "objects cannot separate; give each block its own object ('o') or group ('g'), or export with "
                "vertices not welded (merged) across blocks")
    return (f"{path} holds several bodies that touch, which a single {path.suffix} file cannot separate; give one "
            "file per block, or an OBJ file with one object ('o') or group ('g') per block")


def _frame(path: Path, face_block, face_fixed, announced_fixed) -> tuple[int, ...]:
    """Positions (in sorted block order) of the blocks whose triangles are all marked fixed."""
    blocks, position = np.unique(face_block, return_inverse=True)
    marked = np.zeros(len(blocks), dtype=int)
    np.add.at(marked, position.ravel(), np.asarray(face_fixed, dtype=bool).astype(int))
    total = np.bincount(position.ravel(), minlength=len(blocks))
    mixed = np.flatnonzero((marked > 0) & (marked < total))
    if mixed.size:
        raise AssemblyError(f"{path} marks only some triangles of block {blocks[mixed[0]]} as fixed; a block is "
                            "fixed or not as a whole")
    frame = tuple(np.flatnonzero(marked > 0).tolist())
    if announced_fixed is not None and announced_fixed != len(frame):
        raise AssemblyError(f"{path} is cut short or damaged: it announces {announced_fixed} fixed blocks, "
                            f"its triangles mark {len(frame)}")
    return frame


def _flagged_name(name: str) -> tuple[str, bool]:
    """``'block_0007 fixed'`` -> ``('block_0007', True)``; other names unchanged."""
    stem, _, last = name.strip().rpartition(" ")
    return (stem.rstrip(), True) if stem and last.lower() == FIXED_WORD else (name.strip(), False)


def _natural_key(name: str) -> tuple:
    """Sort key reading runs of digits as numbers: ``block_9`` before ``block_10``."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", name))


def _announced(text) -> tuple[int, int | None, int | None] | None:
    """(blocks, fixed, triangles) from a :func:`file_header` in ``text``; None without one."""
    if isinstance(text, bytes):
        text = text.decode("ascii", errors="replace")
    match = _HEADER.search(text or "")
    if match is None:
        return None
    return tuple(None if group is None else int(group) for group in match.groups())


# --- files with a block index per triangle -------------------------------------
def _indexed_file(path: Path, triangles=None) -> tuple[MeshFile | None, bool]:
    """The blocks of a file that stores a block index per triangle; (None, False) if it does not.

    Binary STL with :data:`HEADER_MARKER` (the triangle attribute; its frame
    in :data:`STL_FIXED_BIT` when the header counts the fixed blocks), PLY
    with an ``interlock blocks=N`` comment (face properties :data:`BLOCK_DATA`
    and :data:`FIXED_DATA`), VTU and XDMF (cell data :data:`BLOCK_DATA`,
    required, and :data:`FIXED_DATA`).  Block ``k`` is named ``block_k``
    (four digits at least).  ``triangles``: what the format's reader gave, if read already.
    """
    if triangles is None:
        triangles = {".ply": _ply_triangles}.get(path.suffix.lower(), _meshio_triangles)(path)
    if triangles is None:
        return None, False
    vertices, faces, blocks, fixed, announced = triangles
    blocks = np.asarray(blocks).astype(np.int64).ravel()
    if len(blocks) != len(faces):
        raise AssemblyError(f"{path} gives {len(blocks)} block indices for {len(faces)} triangles")
    indices = np.unique(blocks)
    count, fixed_count = (None, None) if announced is None else announced[:2]
    if count is not None and not np.array_equal(indices, np.arange(count)):
        found = f"{indices[0]}..{indices[-1]}" if len(indices) else "none"
        raise AssemblyError(f"{path} announces {count} blocks 0..{count - 1} but its triangles carry "
                            f"{len(indices)} distinct block indices ({found})")
    frame = None if fixed is None else _frame(path, blocks, np.ravel(fixed), fixed_count)
    names = tuple(f"block_{index:04d}" for index in indices.tolist())
    return MeshFile(names, tuple(group_meshes(vertices, faces, blocks)), frame, len(indices)), True


# --- STL -------------------------------------------------------------------------
def _stl_file(path: Path) -> tuple[MeshFile | None, bool]:
    """The blocks of an STL file: by stored index (:func:`_indexed_file`), one body (plain binary), or
    (None, False) for ASCII STL, which trimesh reads with one block per ``solid``.

    A marked file (:data:`HEADER_MARKER`) must be exactly as long as its
    header says.  A plain binary STL is read as well when its reading is
    unambiguous (:func:`_plain_binary_stl`); an ASCII STL is checked whole and
    finite (:func:`_check_ascii_stl`).
    """
    whole = path.read_bytes()
    header, count, data = whole[:80], int.from_bytes(whole[80:84], "little"), memoryview(whole)[84:]
    if header.startswith(HEADER_MARKER):
        return _indexed_file(path, _marked_stl(path, header, count, data))
    records = _plain_binary_stl(path, whole, count, data)
    if records is None:
        return None, False
    vertices = records["vertices"].reshape(-1, 3).astype(float)
    _check_finite_triangles(path, vertices)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    return MeshFile((path.name,), tuple(group_meshes(vertices, faces, np.zeros(len(faces), dtype=int)))), False


def _marked_stl(path: Path, header: bytes, count: int, data):
    """Vertices, faces, block and fixed flag per face, and the header of a binary STL with :data:`HEADER_MARKER`."""
    announced = _announced(header)
    if announced is None:
        raise AssemblyError(f"{path} says it holds interlock blocks but not how many ({header[:40]!r})")
    if len(data) != count * STL_RECORD.itemsize:
        raise AssemblyError(f"{path} is cut short or padded: its header announces {count} triangles "
                            f"({count * STL_RECORD.itemsize} bytes), it holds {len(data)} bytes")
    records = np.frombuffer(data, dtype=STL_RECORD)
    vertices = records["vertices"].reshape(-1, 3).astype(float)
    _check_finite_triangles(path, vertices)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    if announced[1] is None:  # written before frames were stored: the attribute is the block index
        return vertices, faces, records["block"], None, announced
    return vertices, faces, records["block"] & (STL_FIXED_BIT - 1), records["block"] >= STL_FIXED_BIT, announced


def _plain_binary_stl(path: Path, whole: bytes, count: int, data):
    """The triangle records of a plain binary STL; None for ASCII STL; an error for a file cut short.

    Besides a complete file (84 bytes, then 50 per announced triangle) two
    variants that exporters write are read, as their reading is unambiguous:
    fewer than 50 bytes after the last triangle (padding: not a triangle), and
    a header count of 0 with whole triangles after it (a writer that never
    filled in the count; text never has the NUL bytes of a 0 count).  More
    bytes than announced, by a triangle or more, could be triangles the count
    misses: refused, as is a file shorter than announced.
    """
    size, record = len(data), STL_RECORD.itemsize
    if count and 0 <= size - count * record < record:
        return np.frombuffer(data, dtype=STL_RECORD, count=count)
    if not count and size and not size % record:
        return np.frombuffer(data, dtype=STL_RECORD)
    if whole[:80].lstrip().lower().startswith(b"solid") and _check_ascii_stl(path, whole):
        return None
    raise AssemblyError(f"{path} is not a complete STL: as a binary STL its header announces {count:,} triangles "
                        f"({count * record:,} bytes after the header), it holds {size:,} bytes; "
                        "it is cut short or damaged (and not ASCII STL either)")


def _check_ascii_stl(path: Path, text: bytes) -> bool:
    """Whether ``text`` is an ASCII STL; an error if it is one cut short or with coordinates that are not finite.

    ASCII STL is read as UTF-8 text (solid names need not be ASCII) whose
    keywords may be in any case (``SOLID``, ``ENDSOLID``, as trimesh reads
    them); its last line starts with ``endsolid``, and only blank lines,
    spaces and NUL or end-of-file (Ctrl-Z) bytes may follow it.
    """
    body = text.rstrip(b" \t\r\n\0\x1a")
    try:
        body.decode("utf-8")
    except UnicodeDecodeError:
        return False
    if not body[body.rfind(b"\n") + 1:].lstrip().lower().startswith(b"endsolid"):
        raise AssemblyError(f"{path} is cut short: an ASCII STL ends with 'endsolid', this one does not")
    lower = body.lower()
    bad = _NOT_FINITE_VERTEX.search(body) if b"nan" in lower or b"inf" in lower else None
    if bad is not None:
        number = body.count(b"\n", 0, bad.start()) + 1
        end = body.find(b"\n", bad.start())
        line = body[bad.start():end if end >= 0 else None].decode().strip()
        raise AssemblyError(f"{path} line {number}: a vertex coordinate is not a finite number: {line[:60]!r}")
    return True


def _check_finite_triangles(path: Path, vertices: np.ndarray) -> None:
    """An error naming the first triangle of a binary STL with a coordinate that is NaN or infinite."""
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        k = int(bad[0]) // 3
        raise AssemblyError(f"{path} triangle {k + 1}: a vertex coordinate is not a finite number: "
                            f"{vertices[bad[0]].tolist()}")


def _ply_triangles(path: Path):
    """Vertices, faces, block and fixed flag per face, and the header of a marked PLY; None without the comment."""
    with open(path, "rb") as file:
        header = file.read(4096).split(b"end_header", 1)[0]
        marker = re.search(rb"^comment (" + re.escape(HEADER_MARKER) + rb".*)$", header, re.MULTILINE)
        if marker is None:
            return None
        file.seek(0)
        loaded = trimesh.exchange.ply.load_ply(file)
    announced = _announced(marker.group(1))
    if announced is None:
        raise AssemblyError(f"{path} says it holds interlock blocks but not how many ({marker.group(1)[:40]!r})")
    properties = loaded["metadata"]["_ply_raw"]["face"]["data"]  # every face property as read, by name
    names = (properties.dtype.names if isinstance(properties, np.ndarray) else tuple(properties)) or ()
    if BLOCK_DATA not in names:
        raise AssemblyError(f"{path} says it holds interlock blocks but has no face property {BLOCK_DATA!r}")
    fixed = properties[FIXED_DATA] if FIXED_DATA in names else None
    return loaded["vertices"], loaded["faces"], properties[BLOCK_DATA], fixed, announced


def _meshio_triangles(path: Path):
    """Vertices, triangles, cell data :data:`BLOCK_DATA` and :data:`FIXED_DATA` of a VTU or XDMF file (meshio)."""
    import meshio  # here, not above: it takes a tenth of a second to import, and few files need it

    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            mesh = meshio.read(path)
    except SystemExit:  # meshio ends the program on some unreadable files: here it must not
        raise AssemblyError(f"cannot read {path} as {path.suffix[1:].upper()}: the file is empty, cut short or "
                            "damaged") from None
    kept = [k for k, cells in enumerate(mesh.cells) if cells.type == "triangle"]
    if BLOCK_DATA not in mesh.cell_data or not kept:
        raise AssemblyError(f"{path} has no triangles with cell data {BLOCK_DATA!r} telling the blocks apart; "
                            "write it with interlock.gallery.export, or give one mesh file per block")
    faces = np.vstack([mesh.cells[k].data for k in kept])
    blocks = np.concatenate([np.ravel(mesh.cell_data[BLOCK_DATA][k]) for k in kept])
    fixed = None
    if FIXED_DATA in mesh.cell_data:
        fixed = np.concatenate([np.ravel(mesh.cell_data[FIXED_DATA][k]) for k in kept]) != 0
    return mesh.points[:, :3], faces, blocks, fixed, None


# --- files with objects ----------------------------------------------------------
def _scene_file(path: Path) -> tuple[MeshFile, bool]:
    """One block per scene node (GLB, 3MF; also plain STL, PLY, ...), node transform applied, named by the node.

    Nodes sort by name (digits as numbers); a name ending in :data:`FIXED_WORD` puts its block in the frame.
    glTF (:data:`GLTF_SUFFIXES`) is +Y up: its nodes are turned +Z up by :data:`GLTF_TO_Z_UP`.
    """
    scene = trimesh.load_scene(path)
    up = GLTF_TO_Z_UP if path.suffix.lower() in GLTF_SUFFIXES else np.eye(4)
    nodes = []
    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[node]
        mesh = scene.geometry[geometry]
        if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces):
            nodes.append((*_flagged_name(str(node)), transform, mesh))
    if len(nodes) > 1:
        nodes.sort(key=lambda node: _natural_key(node[0]))
    placed = []
    for _, _, transform, mesh in nodes:
        transform = up @ transform  # exact: the rows of ``transform`` permuted, one negated
        vertices = trimesh.transform_points(mesh.vertices, transform)
        faces = mesh.faces[:, ::-1] if np.linalg.det(transform[:3, :3]) < 0 else mesh.faces  # a reflection
        placed.append((vertices, faces))
    if not placed:
        return MeshFile((), ()), False
    announced = _scene_header(path, scene)
    labels, info = _scene_meaning(path, scene)
    frame = _named_frame(path, [node[1] for node in nodes], announced)
    offsets = np.cumsum([0] + [len(v) for v, _ in placed])
    meshes = group_meshes(np.vstack([v for v, _ in placed]), np.vstack([f + o for (_, f), o in zip(placed, offsets)]),
                     np.repeat(np.arange(len(placed)), [len(f) for _, f in placed]))
    count = None if announced is None else announced[0]
    return MeshFile(tuple(node[0] for node in nodes), tuple(meshes), frame, count, labels, info), len(nodes) > 1


def _scene_header(path: Path, scene) -> tuple | None:
    """The :func:`file_header` of a GLB (scene extras) or 3MF (model metadata) file, if any."""
    if path.suffix.lower() == ".3mf":
        with zipfile.ZipFile(path) as package:
            models = [name for name in package.namelist() if name.lower().endswith(".model")]
            return next(filter(None, (_announced(package.open(name).read(4096)) for name in models)), None)
    text = scene.metadata.get("interlock") if isinstance(scene.metadata, dict) else None
    return _announced(text) if isinstance(text, str) else None


def _scene_meaning(path: Path, scene) -> tuple[dict, dict | None]:
    """The labels (by block name) and the info that a GLB (scene extras) or 3MF (model metadata) file stores.

    What is not as :func:`~interlock.gallery.export.export` writes it (a file edited by hand) is left out.
    """
    if path.suffix.lower() == ".3mf":
        stored = {}
        with zipfile.ZipFile(path) as package:
            for name in (n for n in package.namelist() if n.lower().endswith(".model")):
                for event, element in ElementTree.iterparse(package.open(name), events=("start", "end")):
                    tag = element.tag.rpartition("}")[2]
                    if tag == "resources":  # the model's metadata come before its resources
                        break
                    if event == "end" and tag == "metadata" and element.get("name", "").startswith("interlock:"):
                        stored[element.get("name").partition(":")[2]] = _json(element.text)
    else:
        stored = scene.metadata if isinstance(scene.metadata, dict) else {}
    pairs, info = stored.get(LABELS_KEY), stored.get(INFO_KEY)
    labels = {name: label_from_text(*pair) for name, pair in pairs.items() if _pair(pair)} \
        if isinstance(pairs, dict) else {}
    return labels, info if isinstance(info, dict) else None


def _json(text):
    """The value of a JSON text; None for one that is not JSON."""
    try:
        return json.loads(text or "")
    except ValueError:
        return None


def _pair(value) -> bool:
    """Whether ``value`` is a ``[kind, text]`` pair of :func:`~interlock.blocks.labels.label_text`."""
    return isinstance(value, list) and len(value) == 2 and all(isinstance(v, str) for v in value)


# --- OBJ -------------------------------------------------------------------------
@dataclass(frozen=True)
class _Obj:
    """The contents of an OBJ file: vertices, polygons (corners face after face), objects, groups, vertex runs."""

    vertices: np.ndarray
    corners: np.ndarray
    counts: np.ndarray
    polygon_object: np.ndarray
    object_names: tuple[str, ...]
    vertex_run: np.ndarray
    announced: tuple | None
    polygon_group: np.ndarray
    group_names: tuple[str, ...]
    object_labels: dict  # object index -> [kind, text], from OBJ_LABEL lines
    info: dict | None  # from the OBJ_INFO line


def _obj_file(path: Path) -> tuple[MeshFile, bool]:
    """The blocks of an OBJ file: its objects, else its groups, else its bodies by shared vertex indices, else by
    ``v`` runs.

    Polygons are triangulated inside their outline
    (:func:`~interlock.blocks.repair.triangulate_polygons`).  A file without
    ``o`` objects whose ``g`` groups are each a closed surface (Rhino, 3ds Max,
    Maya: one group per object, often over one pool of welded vertices) gives
    one block per group, like objects.  A file of one object whose faces fall
    into several sets that share no vertex index (Rhino's export of a
    selection) gives one block per set when each set is a closed surface
    (T-junctions allowed); else the same with the runs of ``v`` lines each
    followed by its faces (:func:`_separate`); else one body, which is split
    into its bodies across edges of two triangles (:func:`_splitgroup_meshes`).
    Sets of faces whose bodies touch at welded vertices are split the same way
    (:func:`_welded_bodies`); bodies that cannot be split into closed surfaces are an error.
    """
    obj = _parse_obj(path)
    faces, polygon = triangulate_polygons(obj.vertices, obj.corners, obj.counts)
    if not len(faces):
        raise AssemblyError(f"{path} holds no faces ('f' lines), only {len(obj.vertices)} vertices: no block to "
                            "read; a block is a closed surface of faces")
    blocks, _, triangles = obj.announced or (None, None, None)
    face_object, object_names = obj.polygon_object[polygon], obj.object_names
    if len(object_names) == 1 and _closed_groups_apart(obj.vertices, faces, obj.polygon_group[polygon]):
        face_object, object_names = obj.polygon_group[polygon], obj.group_names
    objects = np.unique(face_object)
    if triangles is not None and triangles != len(faces):
        raise AssemblyError(f"{path} is cut short or damaged: it announces {blocks} blocks of {triangles} "
                            f"triangles in all, it holds {len(objects)} objects of {len(faces)} triangles")
    names, fixed = zip(*(_flagged_name(object_names[k]) for k in objects.tolist()))
    if len(objects) > 1:  # one block per object, in file order
        meshes = group_meshes(obj.vertices, faces, np.searchsorted(objects, face_object))
        labels = {} if object_names is obj.group_names else {
            name: label_from_text(*obj.object_labels[k]) for name, k in zip(names, objects.tolist())
            if k in obj.object_labels}
        return MeshFile(names, tuple(meshes), _named_frame(path, fixed, obj.announced), blocks, labels, obj.info), True
    closed, separated = _separate(obj.vertices, faces, obj.vertex_run)
    frame = _named_frame(path, fixed, obj.announced)
    if closed is not None:
        closed = _welded_bodies(path, *closed)
    if closed is None:
        mesh = group_meshes(obj.vertices, faces, np.zeros(len(faces), dtype=int))[0]
        name = names[0] if names and names[0] else "body0"
        pair = obj.object_labels.get(int(objects[0])) if object_names is obj.object_names else None
        labels = {} if pair is None else {name: label_from_text(*pair)}
        return MeshFile((name,), (mesh,), frame, blocks, labels, obj.info), separated
    meshes = group_meshes(*closed)
    frame = None if frame is None else tuple(range(len(meshes))) if frame else ()  # bodies of one object
    return MeshFile(tuple(f"body{k}" for k in range(len(meshes))), tuple(meshes), frame, blocks), True


def _named_frame(path: Path, fixed, announced) -> tuple[int, ...] | None:
    """The blocks whose names end in :data:`FIXED_WORD`; None if none does and the file has no header."""
    frame = tuple(k for k, flag in enumerate(fixed) if flag)
    if announced is not None and announced[1] is not None and announced[1] != len(frame):
        raise AssemblyError(f"{path} is cut short or damaged: it announces {announced[1]} fixed blocks, its "
                            f"names mark {len(frame)}")
    return frame if frame or announced is not None else None


def _closed_groups_apart(vertices, faces, face_group) -> bool:
    """Whether the faces fall into several groups (OBJ ``g``) that are each a closed surface."""
    groups = np.unique(face_group, return_inverse=True)[1].ravel()
    return groups.max(initial=0) > 0 and closed_groups(vertices, faces, groups) is not None


def _welded_bodies(path: Path, vertices, faces, face_group) -> tuple:
    """Closed groups of faces, each split into its bodies: faces connected across edges of exactly two faces.

    A group of blocks that touch at welded (shared) vertices is closed (every
    edge has its opposite) but falls apart across the edges that more than
    two faces share; each piece must be closed, or the blocks cannot be told
    apart (an :class:`AssemblyError`).  Groups of one body come back as they are.
    """
    adjacency = trimesh.Trimesh(vertices, faces, process=False).face_adjacency
    body = trimesh.graph.connected_component_labels(adjacency, node_count=len(faces))
    if len(np.unique(body)) == len(np.unique(face_group)):
        return vertices, faces, face_group
    apart = closed_groups(vertices, faces, body)
    if apart is None:
        raise AssemblyError(_touching(path))
    return apart


def _separate(vertices, faces, vertex_run) -> tuple[tuple | None, bool]:
    """The blocks of one OBJ object: faces grouped by shared vertex indices, else by ``v`` runs.

    A grouping counts when it has several groups and each is a closed
    surface (:func:`~interlock.blocks.repair.closed_groups`).  Returns ``((vertices, faces, face groups),
    True)``, T-junctions split; or ``(None, False)`` when all faces share
    vertex indices (one body, to be split into bodies by edges) or neither grouping holds.
    """
    graph = coo_matrix((np.ones(2 * len(faces)), (faces[:, [0, 1]].ravel(), faces[:, [1, 2]].ravel())),
                       shape=(len(vertices), len(vertices)))
    component = connected_components(graph, directed=False)[1]
    by_index = np.unique(component[faces[:, 0]], return_inverse=True)[1].ravel()
    if by_index.max(initial=0) == 0:
        return None, False
    closed = closed_groups(vertices, faces, by_index)
    if closed is None and (vertex_run[faces] == vertex_run[faces[:, :1]]).all():
        by_run = np.unique(vertex_run[faces[:, 0]], return_inverse=True)[1].ravel()
        closed = closed_groups(vertices, faces, by_run) if by_run.max(initial=0) > 0 else None
    return closed, closed is not None


def _parse_obj(path: Path) -> _Obj:
    """Vertices, polygons, objects, groups and ``v`` runs of an OBJ file (``vt``, ``vn``, materials ignored).

    Each ``o`` line starts an object, each ``g`` line a group (named by the
    rest of the line).  A run of ``v`` lines starts at a ``v`` line that follows an ``f`` line.
    Negative indices count back from the last vertex so far.  A malformed
    last line is dropped (a file cut short); elsewhere it is an error.
    """
    lines = path.read_text(errors="replace").splitlines()
    # the header comment, also when damaged (a header that is not read would let a cut-short file pass)
    announced = next(filter(None, (_announced(line) for line in lines[:20] if not line.startswith(("v", "f")))),
                     None)
    if announced is None and any(line.startswith(OBJ_SECOND_LINE) for line in lines[:20]):
        raise AssemblyError(f"{path} was written by interlock but its header ('# interlock blocks=N ...') is "
                            "damaged, so it cannot tell whether it is whole; export it again")
    rows, polygons, seen, objects, runs, names, groups, group_names = [], [], [], [], [], [""], [], [""]
    object_labels, info = {}, None
    run, after_face = 0, False
    last = max((k for k, line in enumerate(lines) if line.strip()), default=-1)
    for number, line in enumerate(lines):
        parts = line.split()
        if not parts:
            continue
        tag = parts[0]
        try:
            if tag == "v":
                if len(parts) < 4:
                    raise ValueError("a vertex needs three coordinates")
                row = [float(x) for x in parts[1:4]]
                if not all(map(math.isfinite, row)):
                    raise ValueError("a vertex coordinate is not a finite number")
                rows.append(row)
                run += after_face
                after_face = False
                runs.append(run)
            elif tag == "f":
                corners = [int(token.partition("/")[0]) for token in parts[1:]]
                if len(corners) < 3:
                    raise ValueError("a face needs three corners")
                polygons.append(corners)
                seen.append(len(rows))
                objects.append(len(names) - 1)
                groups.append(len(group_names) - 1)
                after_face = True
            elif tag == "o":
                names.append(line.strip()[1:].strip())
            elif tag == "g":
                group_names.append(line.strip()[1:].strip())
            elif line.startswith(OBJ_LABEL) and _pair(pair := _json(line[len(OBJ_LABEL):])):
                object_labels[len(names) - 1] = pair
            elif line.startswith(OBJ_INFO) and isinstance(stored := _json(line[len(OBJ_INFO):]), dict):
                info = stored
        except ValueError as error:
            if number == last:  # the file ends in the middle of this line
                break
            raise AssemblyError(f"{path} line {number + 1}: {error}: {line.strip()[:60]!r}") from None
    counts = np.array([len(p) for p in polygons], dtype=np.int64)
    corners = np.array([i for p in polygons for i in p], dtype=np.int64)
    before = np.repeat(np.array(seen, dtype=np.int64), counts)
    corners = np.where(corners < 0, before + corners, corners - 1)
    vertices = np.array(rows, dtype=float).reshape(-1, 3)
    bad = (corners < 0) | (corners >= len(vertices))
    if bad.any():
        raise AssemblyError(f"{path} has faces with vertex indices outside 1..{len(vertices)} "
                            f"(e.g. {corners[bad][0] + 1}); the file is cut short or damaged")
    return _Obj(vertices, corners, counts, np.array(objects, dtype=np.int64), tuple(names),
                np.array(runs, dtype=np.int64), announced, np.array(groups, dtype=np.int64), tuple(group_names),
                object_labels, info)
