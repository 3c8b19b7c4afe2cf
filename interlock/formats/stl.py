"""STL: binary files with the block index in each triangle's attribute bytes (written), and any STL (read).

interlock writes binary STL: the 80-byte header announces the blocks (:func:`~interlock.formats.common.file_header`,
with ``unit=`` and ``up=``), and each triangle's 2-byte attribute holds its block's index, its top bit
(:data:`~interlock.formats.common.STL_FIXED_BIT`) set for the frame's blocks.  STL has no unit and no up-axis of
its own; slicers take it as millimetres, +Z up.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.blocks.repair import group_meshes
from interlock.files import atomic_write
from interlock.formats.bodies import indexed_blocks
from interlock.formats.common import (HEADER_MARKER, STL_FIXED_BIT, STL_MAX_FRAMED, STL_RECORD, FormatError, MeshFile,
                                      face_blocks, file_header, fixed_flags, header_counts, header_words,
                                      world_triangles)

__all__ = ["read_stl", "write_stl", "STL_MAX_BLOCKS"]

#: The most blocks an STL file can tell apart: block indices in the triangles' 2-byte attribute.  Up to
#: :data:`~interlock.formats.common.STL_MAX_FRAMED` blocks the top bit of the attribute carries the frame; beyond,
#: the indices take all 16 bits and the file stores no frame.
STL_MAX_BLOCKS = int(np.iinfo(np.uint16).max)
# the three numbers of an ASCII STL vertex line
_VERTEX = re.compile(rb"(?im)^[ \t]*vertex[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)")


def read_stl(path: Path) -> MeshFile | None:
    """The blocks of an STL file: by stored index, one body (plain binary), or None for ASCII STL (which the
    scene reader reads, one block per ``solid``), after checking it whole and finite.

    A marked file (:data:`~interlock.formats.common.HEADER_MARKER`) must be exactly as long as its header says.
    A plain binary STL is read as well when its reading is unambiguous (:func:`_plain_binary_stl`).
    """
    whole = path.read_bytes()
    header, count, data = whole[:80], int.from_bytes(whole[80:84], "little"), memoryview(whole)[84:]
    if header.startswith(HEADER_MARKER):
        found = indexed_blocks(path, _marked_stl(path, header, count, data))
        words = header_words(header)
        return MeshFile(found.names, found.meshes, found.frame, found.announced, unit=words.get("unit"),
                        up=words.get("up", "z"))
    records = _plain_binary_stl(path, whole, count, data)
    if records is None:
        return None
    vertices = records["vertices"].reshape(-1, 3).astype(float)
    _check_finite_triangles(path, vertices)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    return MeshFile((path.name,), tuple(group_meshes(vertices, faces, np.zeros(len(faces), dtype=int))))


def write_stl(assembly: Assembly, path: Path, up: str = "z") -> None:
    """Binary STL: every block's world triangles, the block index (and frame bit) in the attribute bytes."""
    vertices, faces, _, face_start = world_triangles(assembly)
    records = np.zeros(len(faces), dtype=STL_RECORD)
    triangles = vertices[faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    with np.errstate(all="ignore"):
        records["normal"] = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    records["vertices"] = triangles
    blocks = face_blocks(face_start)
    if len(assembly) <= STL_MAX_FRAMED:
        records["block"] = blocks | np.where(fixed_flags(assembly)[blocks], STL_FIXED_BIT, 0)
        header = file_header(len(assembly), len(assembly.frame), unit=assembly.unit, up=up).encode()
    elif len(assembly) <= STL_MAX_BLOCKS:  # the block indices take every bit: no frame
        records["block"] = blocks
        header = file_header(len(assembly), unit=assembly.unit, up=up).encode()
    else:
        header = b"interlock: too many blocks to index in the triangle attributes"
    with atomic_write(path) as temporary, open(temporary, "wb") as file:
        file.write(header.ljust(80, b" ")[:80])
        file.write(np.uint32(len(records)).tobytes())
        file.write(records.tobytes())


def _marked_stl(path: Path, header: bytes, count: int, data):
    """Vertices, faces, block and fixed flag per face, the header of a marked binary STL, no labels, no info."""
    announced = header_counts(header)
    if announced is None:
        raise FormatError(f"{path} says it holds interlock blocks but not how many ({header[:40]!r})")
    if len(data) != count * STL_RECORD.itemsize:
        raise FormatError(f"{path} is cut short or padded: its header announces {count} triangles "
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

    Besides a complete file (84 bytes, then 50 per announced triangle) two variants that exporters write are
    read, as their reading is unambiguous: fewer than 50 bytes after the last triangle (padding), and a header
    count of 0 with whole triangles after it (a writer that never filled in the count).  More bytes than
    announced, by a triangle or more, could be triangles the count misses: refused, as is a file shorter than
    announced.
    """
    size, record = len(data), STL_RECORD.itemsize
    if count and 0 <= size - count * record < record:
        return np.frombuffer(data, dtype=STL_RECORD, count=count)
    if not count and size and not size % record:
        return np.frombuffer(data, dtype=STL_RECORD)
    if whole[:80].lstrip().lower().startswith(b"solid") and _check_ascii_stl(path, whole):
        return None
    raise FormatError(f"{path} is not a complete STL: as a binary STL its header announces {count:,} triangles "
                      f"({count * record:,} bytes after the header), it holds {size:,} bytes; "
                      "it is cut short or damaged (and not ASCII STL either)")


def _check_ascii_stl(path: Path, text: bytes) -> bool:
    """Whether ``text`` is an ASCII STL; an error if it is one cut short or with a coordinate that is not a finite
    number (``nan``, ``inf``, or one too large for a double such as ``1e400``), naming its line.

    ASCII STL is read as UTF-8 text whose keywords may be in any case; its last line starts with ``endsolid``,
    and only blank lines, spaces and NUL or end-of-file (Ctrl-Z) bytes may follow it.
    """
    body = text.rstrip(b" \t\r\n\0\x1a")
    try:
        body.decode("utf-8")
    except UnicodeDecodeError:
        return False
    if not body[body.rfind(b"\n") + 1:].lstrip().lower().startswith(b"endsolid"):
        raise FormatError(f"{path} is cut short: an ASCII STL ends with 'endsolid', this one does not")
    numbers = _VERTEX.findall(body)
    try:
        values = np.array(numbers, dtype=bytes).astype(float).reshape(-1, 3)
    except ValueError:  # a word that is no number: trimesh's reader says what it makes of it
        return True
    bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
    if bad.size:
        match = next(m for k, m in enumerate(_VERTEX.finditer(body)) if k == bad[0])
        number = body.count(b"\n", 0, match.start()) + 1
        line = match.group(0).decode().strip()
        raise FormatError(f"{path} line {number}: a vertex coordinate is not a finite number: {line[:60]!r} (NaN, "
                          "infinite, or beyond the largest double, 1.8e308)")
    return True


def _check_finite_triangles(path: Path, vertices: np.ndarray) -> None:
    """An error naming the first triangle of a binary STL with a coordinate that is NaN or infinite."""
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        k = int(bad[0]) // 3
        raise FormatError(f"{path} triangle {k + 1}: a vertex coordinate is not a finite number: "
                          f"{vertices[bad[0]].tolist()}")
