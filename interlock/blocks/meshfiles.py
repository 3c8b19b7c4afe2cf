"""Reading mesh files: the blocks a file holds (by stored index, by object, or by body) and the frame it stores."""

from __future__ import annotations

import contextlib
import io
import os
import re
import warnings
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import trimesh

from interlock.blocks.meshformat import (BLOCK_DATA, FIXED_DATA, FIXED_WORD, GLTF_SUFFIXES, GLTF_TO_Z_UP, HEADER_MARKER,
                                         INFO_KEY, LABELS_KEY, OBJ_INFO, OBJ_LABEL, OBJ_SECOND_LINE, STL_FIXED_BIT,
                                         STL_MAX_FRAMED, STL_RECORD, MeshFile, header_counts, file_header, flagged_name,
                                         json_value, named_frame, stored_meaning, touching_bodies)
from interlock.blocks.objfile import obj_file
from interlock.blocks.repair import group_meshes, split_t_junctions, unmatched_edges, unrepeated
from interlock.errors import AssemblyError

# The format's names live in interlock.blocks.meshformat; they are also importable from here, where readers and
# writers have always found them.
__all__ = ["MeshFile", "read_mesh_file", "readgroup_meshes", "file_header", "HEADER_MARKER", "STL_RECORD",
           "BLOCK_DATA", "FIXED_DATA", "FIXED_WORD", "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE",
           "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY", "INFO_KEY", "GLTF_TO_Z_UP", "GLTF_SUFFIXES"]

# an ASCII STL vertex line with a coordinate NaN or infinite (as Python and trimesh parse them)
_NOT_FINITE_VERTEX = re.compile(rb"(?im)^[ \t]*vertex[ \t][^\n]*?(?<![\w.])[-+]?(?:nan|inf(?:inity)?)\b")


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
    reader = {".obj": obj_file, ".stl": _stl_file, ".ply": _indexed_file, ".vtu": _indexed_file,
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
    if path.stat().st_size == 0:
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
    if len(unmatched_edges(mesh.faces)):  # repeated triangles would make a body look like two that touch
        faces = unrepeated(mesh.faces)
        mesh = trimesh.Trimesh(mesh.vertices, split_t_junctions(mesh.vertices, faces), process=False)
    parts = mesh.split(only_watertight=False)
    if len(parts) <= 1:
        return found
    if not all(part.is_watertight for part in parts):
        raise AssemblyError(touching_bodies(path))
    frame = None if found.frame is None else tuple(range(len(parts))) if found.frame else ()
    return MeshFile(tuple(f"body{k}" for k in range(len(parts))), tuple(parts), frame)


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


def _natural_key(name: str) -> tuple:
    """Sort key reading runs of digits as numbers: ``block_9`` before ``block_10``."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", name))


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
    vertices, faces, blocks, fixed, announced, labels, info = triangles
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
    return MeshFile(names, tuple(group_meshes(vertices, faces, blocks)), frame, len(indices), labels, info), True


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
    """Vertices, faces, block and fixed flag per face, the header of a binary STL with :data:`HEADER_MARKER`, and
    (as for PLY) its labels and info: none, an STL has no room for them."""
    announced = header_counts(header)
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
        return vertices, faces, records["block"], None, announced, {}, None
    return (vertices, faces, records["block"] & (STL_FIXED_BIT - 1), records["block"] >= STL_FIXED_BIT, announced, {},
            None)


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
    """Vertices, faces, block and fixed flag per face, the header, and the labels (by block name) and info of
    the JSON comments :data:`LABELS_KEY` and :data:`INFO_KEY`, of a marked PLY; None without the comment."""
    with open(path, "rb") as file:
        start = file.read(4096)
        marker = re.search(rb"^comment (" + re.escape(HEADER_MARKER) + rb".*)$", start.split(b"end_header", 1)[0],
                           re.MULTILINE)
        if marker is None:
            return None
        header = _ply_header(file, start)
        file.seek(0)
        loaded = trimesh.exchange.ply.load_ply(file)
    labels, info = stored_meaning({key.decode(): json_value(value) for key, value in re.findall(
        rb"^comment (" + LABELS_KEY.encode() + b"|" + INFO_KEY.encode() + rb") (.*)$", header, re.MULTILINE)})
    announced = header_counts(marker.group(1))
    if announced is None:
        raise AssemblyError(f"{path} says it holds interlock blocks but not how many ({marker.group(1)[:40]!r})")
    properties = loaded["metadata"]["_ply_raw"]["face"]["data"]  # every face property as read, by name
    names = (properties.dtype.names if isinstance(properties, np.ndarray) else tuple(properties)) or ()
    if BLOCK_DATA not in names:
        raise AssemblyError(f"{path} says it holds interlock blocks but has no face property {BLOCK_DATA!r}")
    fixed = properties[FIXED_DATA] if FIXED_DATA in names else None
    return loaded["vertices"], loaded["faces"], properties[BLOCK_DATA], fixed, announced, labels, info


def _ply_header(file, start: bytes) -> bytes:
    """A PLY file's header, up to ``end_header``, from its first bytes ``start`` on (read on from ``file``: its
    JSON comments may make it long)."""
    header = start
    while b"end_header" not in header:
        chunk = file.read(1 << 20)
        if not chunk:
            break
        header += chunk
    return header.split(b"end_header", 1)[0]


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
    return mesh.points[:, :3], faces, blocks, fixed, None, {}, None


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
            nodes.append((*flagged_name(str(node)), transform, mesh))
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
    frame = named_frame(path, [node[1] for node in nodes], announced)
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
            return next(filter(None, (header_counts(package.open(name).read(4096)) for name in models)), None)
    text = scene.metadata.get("interlock") if isinstance(scene.metadata, dict) else None
    return header_counts(text) if isinstance(text, str) else None


def _scene_meaning(path: Path, scene) -> tuple[dict, dict | None]:
    """The labels (by block name) and the info that a GLB (scene extras) or 3MF (model metadata) file stores
    (:func:`~interlock.blocks.meshformat.stored_meaning`)."""
    if path.suffix.lower() == ".3mf":
        stored = {}
        with zipfile.ZipFile(path) as package:
            for name in (n for n in package.namelist() if n.lower().endswith(".model")):
                for event, element in ElementTree.iterparse(package.open(name), events=("start", "end")):
                    tag = element.tag.rpartition("}")[2]
                    if tag == "resources":  # the model's metadata come before its resources
                        break
                    if event == "end" and tag == "metadata" and element.get("name", "").startswith("interlock:"):
                        stored[element.get("name").partition(":")[2]] = json_value(element.text)
    else:
        stored = scene.metadata if isinstance(scene.metadata, dict) else {}
    return stored_meaning(stored)


