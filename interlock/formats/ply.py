"""PLY: binary files with the block index, frame flag and class colour per vertex (written), and any PLY (read).

interlock's PLY holds one mesh whose vertices are not shared between blocks, so each vertex carries its
block's index (``block``), frame flag (``fixed``) and colour (``red green blue alpha``), and the face element
holds only ``vertex_indices``: the layout every PLY reader takes (meshio, plyfile, trimesh, Blender, MeshLab;
meshio misreads scalar face properties after the list).  Comments announce the blocks (``comment interlock
blocks=N fixed=K``, with ``unit=`` and ``up=``), the labels and ``Assembly.info`` (JSON).  Files of earlier
versions, with ``block`` and ``fixed`` as face properties, are read too.  A plain (ASCII) PLY is checked against
the counts its header announces.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain
from interlock.files import atomic_write
from interlock.formats.bodies import indexed_blocks
from interlock.formats.common import (BLOCK_DATA, FIXED_DATA, HEADER_MARKER, INFO_KEY, LABELS_KEY, PALETTE,
                                      FormatError, MeshFile, classes, file_header, fixed_flags, header_counts,
                                      header_words, json_value, label_pairs, one_line_json, stored_meaning,
                                      world_triangles)

__all__ = ["read_ply", "write_ply", "check_ascii_counts"]


def read_ply(path: Path) -> MeshFile | None:
    """The blocks of a PLY file marked ``interlock blocks=N`` (by their stored index); None for another PLY
    (read as one mesh and split into bodies), after checking an ASCII one against its announced counts."""
    with open(path, "rb") as file:
        start = file.read(4096)
        header = _ply_header(file, start)
        check_ascii_counts(path, file, header)
        marker = re.search(rb"^comment (" + re.escape(HEADER_MARKER) + rb".*)$", header, re.MULTILINE)
        if marker is None:
            return None
        file.seek(0)
        loaded = trimesh.exchange.ply.load_ply(file)
    labels, info = stored_meaning({key.decode(): json_value(value) for key, value in re.findall(
        rb"^comment (" + LABELS_KEY.encode() + b"|" + INFO_KEY.encode() + rb") (.*)$", header, re.MULTILINE)})
    announced = header_counts(marker.group(1))
    if announced is None:
        raise FormatError(f"{path} says it holds interlock blocks but not how many ({marker.group(1)[:40]!r})")
    raw = loaded["metadata"]["_ply_raw"]
    faces = np.asarray(loaded["faces"])
    block, fixed = _per_face(path, raw, faces)
    found = indexed_blocks(path, (loaded["vertices"], faces, block, fixed, announced, labels, info))
    words = header_words(marker.group(1))
    return MeshFile(found.names, found.meshes, found.frame, found.announced, found.labels, found.info,
                    unit=words.get("unit"), up=words.get("up", "z"))


def write_ply(assembly: Assembly, path: Path, up: str = "z") -> None:
    """Binary PLY, one mesh: per vertex its block, frame flag and class colour; labels and info as comments."""
    vertices, faces, vertex_start, _ = world_triangles(assembly)
    values, _ = classes(assembly)
    vertex_block = np.repeat(np.arange(len(assembly)), np.diff(vertex_start))
    colours = PALETTE[values % len(PALETTE)][vertex_block]
    records = np.zeros(len(vertices), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), (BLOCK_DATA, "<i4"),
                                             (FIXED_DATA, "u1"), ("red", "u1"), ("green", "u1"), ("blue", "u1"),
                                             ("alpha", "u1")])
    for k, axis in enumerate("xyz"):
        records[axis] = vertices[:, k]
    records[BLOCK_DATA] = vertex_block
    records[FIXED_DATA] = fixed_flags(assembly)[vertex_block]
    for k, channel in enumerate(("red", "green", "blue", "alpha")):
        records[channel] = colours[:, k]
    face_records = np.zeros(len(faces), dtype=[("count", "u1"), ("vertex_indices", "<i4", 3)])
    face_records["count"] = 3
    face_records["vertex_indices"] = faces
    header = "\n".join([
        "ply", "format binary_little_endian 1.0",
        f"comment {file_header(len(assembly), len(assembly.frame), unit=assembly.unit, up=up)}",
        f"comment {LABELS_KEY} {one_line_json(label_pairs(assembly))}",
        f"comment {INFO_KEY} {one_line_json(plain(assembly.info))}",
        f"element vertex {len(vertices)}", "property double x", "property double y", "property double z",
        f"property int {BLOCK_DATA}", f"property uchar {FIXED_DATA}",
        "property uchar red", "property uchar green", "property uchar blue", "property uchar alpha",
        f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header", ""])
    with atomic_write(path) as temporary, open(temporary, "wb") as file:
        file.write(header.encode("ascii"))
        file.write(records.tobytes())
        file.write(face_records.tobytes())


def check_ascii_counts(path: Path, file, header: bytes) -> None:
    """An error unless an ASCII PLY holds the vertices and faces its header announces (``element vertex N``,
    ``element face M``): one line each, then nothing but blank lines.  Binary PLY is checked by its reader."""
    if not re.search(rb"^format ascii", header, re.MULTILINE):
        return
    elements = [(name.decode(), int(count)) for name, count in
                re.findall(rb"^element (\S+) (\d+)", header, re.MULTILINE)]
    file.seek(len(header) + len(b"end_header"))
    lines = [line for line in file.read().split(b"\n")[1:] if line.strip()]
    announced = sum(count for _, count in elements)
    if len(lines) < announced:
        held, rest = [], len(lines)
        for name, count in elements:
            held.append(f"{min(count, rest):,} of {count:,} {_plural(name, count)}")
            rest = max(rest - count, 0)
        raise FormatError(f"{path} is cut short: its header announces " + ", ".join(
            f"{count:,} {_plural(name, count)}" for name, count in elements) + "; it holds " + ", ".join(held))
    if len(lines) > announced:
        raise FormatError(f"{path} holds {len(lines) - announced:,} lines more than its header announces "
                          f"({announced:,} element lines); the header or the data is damaged")


def _plural(name: str, count: int) -> str:
    return name if count == 1 else {"vertex": "vertices"}.get(name, name + "s")


def _per_face(path: Path, raw: dict, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The block index and frame flag of every face: from the vertices (this version) or the faces (earlier)."""
    for element, per_vertex in (("vertex", True), ("face", False)):
        data = raw.get(element, {}).get("data")
        names = (data.dtype.names if isinstance(data, np.ndarray) else tuple(data or ())) or ()
        if BLOCK_DATA in names:
            block = np.asarray(data[BLOCK_DATA]).ravel()
            fixed = np.asarray(data[FIXED_DATA]).ravel() if FIXED_DATA in names else None
            if per_vertex:
                first = faces[:, 0] if len(faces) else np.zeros(0, dtype=int)
                return block[first], None if fixed is None else fixed[first]
            return block, fixed
    raise FormatError(f"{path} says it holds interlock blocks but has no vertex or face property {BLOCK_DATA!r}")


def _ply_header(file, start: bytes) -> bytes:
    """A PLY file's header, up to ``end_header``, from its first bytes ``start`` on (its JSON comments may make
    it long)."""
    header = start
    while b"end_header" not in header:
        chunk = file.read(1 << 20)
        if not chunk:
            break
        header += chunk
    return header.split(b"end_header", 1)[0]
