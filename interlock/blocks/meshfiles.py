"""Reading mesh files into named bodies: the blocks a file holds, by stored index, by object, or by body."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from interlock.errors import AssemblyError

__all__ = ["read_bodies", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA"]

#: How an exported file says that it stores a block index per triangle, and how many blocks: the start of
#: a binary STL's 80-byte header, or a PLY comment (``interlock blocks=12`` for 12 blocks).
HEADER_MARKER = b"interlock blocks="
#: One triangle of a binary STL: normal, three vertices, and the 2-byte attribute holding the block index.
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("block", "<u2")])
#: Name of the per-triangle block index in PLY (face property), VTU and XDMF (cell data) files.
BLOCK_DATA = "block"


def read_bodies(path: Path, split: bool = True) -> list[tuple[str, trimesh.Trimesh]]:
    """(name, mesh in file coordinates) for every block of a mesh file, in file order.

    Stored block indices win (:func:`_indexed_blocks`), then the file's objects.
    With ``split``, a file holding one object is split into its connected bodies;
    without, the file is to be one block, so several stored blocks are refused.
    """
    if not path.is_file():
        raise AssemblyError(f"mesh file {path} does not exist")
    try:
        blocks = _indexed_blocks(path)
        bodies = _scene_objects(path) if blocks is None else blocks
    except AssemblyError:
        raise
    except Exception as error:  # the readers raise many types for unreadable files
        raise AssemblyError(f"cannot read {path} as a mesh ({type(error).__name__}: {error})") from None
    if not bodies:
        raise AssemblyError(f"{path} holds no triangle mesh")
    if not split and blocks is not None and len(blocks) > 1:
        raise AssemblyError(f"{path} holds {len(blocks)} blocks, which would merge into one in a list of "
                            f"one file per block; load it on its own: Assembly.load({str(path)!r})")
    if split and blocks is None and len(bodies) == 1:
        parts = bodies[0][1].split(only_watertight=False)
        if len(parts) > 1:
            if not all(part.is_watertight for part in parts):
                raise AssemblyError(f"{path} holds several bodies that touch, which a single {path.suffix} file cannot "
                                    "separate; give one file per block, or an OBJ file with one object ('o') per block")
            bodies = [(f"body{k}", part) for k, part in enumerate(parts)]
    return bodies


def _scene_objects(path: Path) -> list[tuple[str, trimesh.Trimesh]]:
    """One mesh per object (OBJ ``o``) or scene node (GLB, 3MF), node transform applied, named by the node."""
    obj = path.suffix.lower() == ".obj"
    scene = trimesh.load_scene(path, **({"split_objects": True, "group_material": False} if obj else {}))
    bodies = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if isinstance(geometry, trimesh.Trimesh) and len(geometry.faces):
            body = geometry.copy().apply_transform(transform)  # a reflection also flips the faces
            body.merge_vertices(merge_tex=True, merge_norm=True)  # per-face normals must not split corners
            bodies.append((str(node), body))
    if obj and len(bodies) > 1:
        order = [line.split(maxsplit=1)[1].strip() for line in path.read_text(errors="replace").splitlines()
                 if line.startswith("o ") and len(line.split(maxsplit=1)) == 2]
        bodies.sort(key=lambda body: order.index(body[0]) if body[0] in order else len(order))
    elif len(bodies) > 1:
        bodies.sort(key=lambda body: _natural_key(body[0]))
    return bodies


def _natural_key(name: str) -> tuple:
    """Sort key reading runs of digits as numbers: ``block_9`` before ``block_10``."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", name))


def _indexed_blocks(path: Path) -> list[tuple[str, trimesh.Trimesh]] | None:
    """The blocks of a file that stores a block index per triangle; None if it does not.

    Binary STL with :data:`HEADER_MARKER` (the triangle attribute), PLY with an
    ``interlock blocks=N`` comment (the face property :data:`BLOCK_DATA`), VTU
    and XDMF (cell data :data:`BLOCK_DATA`, required).  Block ``k`` is named
    ``block_k`` (four digits at least).
    """
    reader = {".stl": _stl_triangles, ".ply": _ply_triangles, ".vtu": _meshio_triangles,
              ".xdmf": _meshio_triangles}.get(path.suffix.lower())
    triangles = None if reader is None else reader(path)
    return None if triangles is None else _split_by_block(path, *triangles)


def _stl_triangles(path: Path):
    """Vertices, faces, block per face and block count of a marked binary STL; None if unmarked."""
    with open(path, "rb") as file:
        header = file.read(80)
        if not header.startswith(HEADER_MARKER):
            return None
        count = int.from_bytes(file.read(4), "little")
        data = file.read()
    if len(data) != count * STL_RECORD.itemsize:
        raise AssemblyError(f"{path} is cut short or padded: its header announces {count} triangles "
                            f"({count * STL_RECORD.itemsize} bytes), it holds {len(data)} bytes")
    records = np.frombuffer(data, dtype=STL_RECORD)
    vertices = records["vertices"].reshape(-1, 3).astype(float)
    return vertices, np.arange(len(vertices)).reshape(-1, 3), records["block"], _block_count(header, path)


def _ply_triangles(path: Path):
    """Vertices, faces, block per face and block count of a PLY with an interlock comment; None without."""
    with open(path, "rb") as file:
        header = file.read(4096).split(b"end_header", 1)[0]
        marker = re.search(rb"^comment (" + re.escape(HEADER_MARKER) + rb".*)$", header, re.MULTILINE)
        if marker is None:
            return None
        file.seek(0)
        loaded = trimesh.exchange.ply.load_ply(file)
    properties = loaded["metadata"]["_ply_raw"]["face"]["data"]  # every face property as read, by name
    names = properties.dtype.names if isinstance(properties, np.ndarray) else tuple(properties)
    if BLOCK_DATA not in (names or ()):
        raise AssemblyError(f"{path} says it holds interlock blocks but has no face property {BLOCK_DATA!r}")
    return loaded["vertices"], loaded["faces"], properties[BLOCK_DATA], _block_count(marker.group(1), path)


def _meshio_triangles(path: Path):
    """Vertices, triangles and cell data :data:`BLOCK_DATA` of a VTU or XDMF file (meshio)."""
    import meshio  # here, not above: it takes a tenth of a second to import, and few files need it

    mesh = meshio.read(path)
    kept = [k for k, cells in enumerate(mesh.cells) if cells.type == "triangle"]
    if BLOCK_DATA not in mesh.cell_data or not kept:
        raise AssemblyError(f"{path} has no triangles with cell data {BLOCK_DATA!r} telling the blocks apart; "
                            "write it with interlock.gallery.export, or give one mesh file per block")
    faces = np.vstack([mesh.cells[k].data for k in kept])
    blocks = np.concatenate([np.ravel(mesh.cell_data[BLOCK_DATA][k]) for k in kept])
    return mesh.points[:, :3], faces, blocks, None


def _block_count(marker: bytes, path: Path) -> int:
    """N from ``interlock blocks=N``."""
    digits = re.match(rb"\d+", marker[len(HEADER_MARKER):])
    if digits is None:
        raise AssemblyError(f"{path} says it holds interlock blocks but not how many ({marker[:40]!r})")
    return int(digits.group())


def _split_by_block(path: Path, vertices, faces, blocks, count) -> list[tuple[str, trimesh.Trimesh]]:
    """One mesh per block index (merged vertices), in index order; ``count`` blocks if given."""
    blocks = np.asarray(blocks).astype(np.int64).ravel()
    if len(blocks) != len(faces):
        raise AssemblyError(f"{path} gives {len(blocks)} block indices for {len(faces)} triangles")
    order = np.argsort(blocks, kind="stable")
    indices, starts = np.unique(blocks[order], return_index=True)
    if count is not None and not np.array_equal(indices, np.arange(count)):
        found = f"{indices[0]}..{indices[-1]}" if len(indices) else "none"
        raise AssemblyError(f"{path} announces {count} blocks 0..{count - 1} but its triangles carry "
                            f"{len(indices)} distinct block indices ({found})")
    bodies = []
    for index, own in zip(indices.tolist(), np.split(order, starts[1:])):
        used, local = np.unique(faces[own], return_inverse=True)
        body = trimesh.Trimesh(vertices[used], local.reshape(-1, 3), process=False)
        body.merge_vertices()
        bodies.append((f"block_{index:04d}", body))
    return bodies
