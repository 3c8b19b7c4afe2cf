"""VTK unstructured grids (``.vtu``) and XDMF (``.xdmf``, inline XML data) through meshio: triangles with cell
data ``block``, ``class``, ``mirrored`` and ``fixed``.

A comment at the top of the XML (``<!-- interlock blocks=N fixed=K unit=mm -->``) announces the blocks, so a
file cut short is found, and states the unit and up-axis, which neither format has.  Reading gives the blocks
back by their ``block`` data, with ``class`` and ``mirrored`` into ``Assembly.info["classes"]`` and
``info["mirrored"]`` (the colours and 3dm layers of a later export follow them).  pyvista's reader fails on
static XDMF files (a pyvista bug); ParaView and meshio read them, and pyvista reads the ``.vtu``.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.files import atomic_write
from interlock.formats.bodies import indexed_blocks
from interlock.formats.common import (BLOCK_DATA, CLASS_DATA, FIXED_DATA, MIRRORED_DATA, FormatError, MeshFile,
                                      classes, face_blocks, file_header, fixed_flags, header_counts, header_words,
                                      world_triangles)

__all__ = ["read_vtu", "write_vtu"]


def read_vtu(path: Path) -> MeshFile:
    """The blocks of a VTU or XDMF file by their cell data ``block`` (required), with frame, classes and unit."""
    import meshio  # here, not above: it takes a tenth of a second to import, and few files need it

    with open(path, "rb") as file:
        start = file.read(4096)
    announced = header_counts(start)
    words = header_words(start)
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            mesh = meshio.read(path)
    except SystemExit:  # meshio ends the program on some unreadable files: here it must not
        raise FormatError(f"cannot read {path} as {path.suffix[1:].upper()}: the file is empty, cut short or "
                          "damaged") from None
    kept = [k for k, cells in enumerate(mesh.cells) if cells.type == "triangle"]
    if BLOCK_DATA not in mesh.cell_data or not kept:
        raise FormatError(f"{path} has no triangles with cell data {BLOCK_DATA!r} telling the blocks apart; "
                          "write it with interlock.write, or give one mesh file per block")

    def data(name):
        if name not in mesh.cell_data:
            return None
        return np.concatenate([np.ravel(mesh.cell_data[name][k]) for k in kept])

    faces = np.vstack([mesh.cells[k].data for k in kept])
    blocks = data(BLOCK_DATA).astype(np.int64)
    fixed = None if FIXED_DATA not in mesh.cell_data else data(FIXED_DATA) != 0
    found = indexed_blocks(path, (mesh.points[:, :3], faces, blocks, fixed, announced, {}, None))
    extra = {}
    order = np.unique(blocks, return_index=True)[1]  # the first triangle of each block, blocks in order
    for name, key in ((CLASS_DATA, "classes"), (MIRRORED_DATA, "mirrored")):
        values = data(name)
        if values is not None:
            extra[key] = [int(v) if key == "classes" else bool(v) for v in values[order].tolist()]
    if "classes" in extra and isinstance(words.get("classes"), str):
        extra["class_kind"] = words["classes"].replace("_", " ")
    return MeshFile(found.names, found.meshes, found.frame, found.announced, unit=words.get("unit"), extra=extra,
                    up=words.get("up", "z"))


def write_vtu(assembly: Assembly, path: Path, up: str = "z") -> None:
    """VTU (binary, compressed) or XDMF (XML data): the triangles with cell data block, class, mirrored, fixed."""
    import meshio

    vertices, faces, _, face_start = world_triangles(assembly)
    blocks = face_blocks(face_start)
    values, kind = classes(assembly)
    cell_data = {BLOCK_DATA: [blocks], CLASS_DATA: [values[blocks].astype(np.int64)],
                 MIRRORED_DATA: [assembly.mirrored[blocks].astype(np.int64)],
                 FIXED_DATA: [fixed_flags(assembly)[blocks].astype(np.int64)]}
    mesh = meshio.Mesh(vertices, [("triangle", faces)], cell_data=cell_data)
    header = file_header(len(assembly), len(assembly.frame), unit=assembly.unit, up=up)
    header += f" classes={kind.replace(' ', '_')}"
    with atomic_write(path) as temporary:
        if path.suffix.lower() == ".xdmf":
            meshio.write(temporary, mesh, file_format="xdmf", data_format="XML")
        else:
            meshio.write(temporary, mesh, file_format="vtu")
        text = temporary.read_bytes()
        declaration = text.index(b"?>") + 2 if text.startswith(b"<?xml") else 0
        temporary.write_bytes(text[:declaration] + f"\n<!-- {header} -->".encode() + text[declaration:])
