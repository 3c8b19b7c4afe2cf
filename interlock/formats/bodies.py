"""Telling the blocks of a file apart: by a stored block index per triangle, or by connected bodies."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.bodies import BodiesError, closed_bodies
from interlock.blocks.repair import group_meshes, split_t_junctions, unmatched_edges, unrepeated
from interlock.formats.common import FormatError, MeshFile, touching_bodies

__all__ = ["indexed_blocks", "split_bodies", "natural_key", "triangle_frame"]


def indexed_blocks(path: Path, triangles) -> MeshFile:
    """The blocks of a file that stores a block index per triangle (STL, PLY, VTU, XDMF of interlock).

    ``triangles`` is ``(vertices, faces, block per face, fixed flag per face or None, announced
    (blocks, fixed, triangles) or None, labels, info)`` as the format's reader found them.  Block ``k`` is named
    ``block_k`` (four digits at least).
    """
    vertices, faces, blocks, fixed, announced, labels, info = triangles
    blocks = np.asarray(blocks).astype(np.int64).ravel()
    if len(blocks) != len(faces):
        raise FormatError(f"{path} gives {len(blocks)} block indices for {len(faces)} triangles")
    indices = np.unique(blocks)
    count, fixed_count = (None, None) if announced is None else announced[:2]
    if count is not None and not np.array_equal(indices, np.arange(count)):
        found = f"{indices[0]}..{indices[-1]}" if len(indices) else "none"
        raise FormatError(f"{path} announces {count} blocks 0..{count - 1} but its triangles carry "
                          f"{len(indices)} distinct block indices ({found})")
    frame = None if fixed is None else triangle_frame(path, blocks, np.ravel(fixed), fixed_count)
    names = tuple(f"block_{index:04d}" for index in indices.tolist())
    return MeshFile(names, tuple(group_meshes(vertices, faces, blocks)), frame, len(indices), labels, info)


def triangle_frame(path: Path, face_block, face_fixed, announced_fixed) -> tuple[int, ...]:
    """Positions (in sorted block order) of the blocks whose triangles are all marked fixed."""
    blocks, position = np.unique(face_block, return_inverse=True)
    marked = np.zeros(len(blocks), dtype=int)
    np.add.at(marked, position.ravel(), np.asarray(face_fixed, dtype=bool).astype(int))
    total = np.bincount(position.ravel(), minlength=len(blocks))
    mixed = np.flatnonzero((marked > 0) & (marked < total))
    if mixed.size:
        raise FormatError(f"{path} marks only some triangles of block {blocks[mixed[0]]} as fixed; a block is "
                          "fixed or not as a whole")
    frame = tuple(np.flatnonzero(marked > 0).tolist())
    if announced_fixed is not None and announced_fixed != len(frame):
        raise FormatError(f"{path} is cut short or damaged: it announces {announced_fixed} fixed blocks, "
                          f"its triangles mark {len(frame)}")
    return frame


def split_bodies(path: Path, found: MeshFile) -> MeshFile:
    """A file's one body split into its connected bodies (sharing an edge, T-junctions split first).

    Bodies that touch share edges of more than two triangles: they are told apart by pairing the half-edges
    around each shared edge (:func:`~interlock.blocks.bodies.closed_bodies`); what cannot be paired into closed,
    consistently oriented bodies is an error that says why.
    """
    mesh = found.meshes[0]
    if len(unmatched_edges(mesh.faces)):  # repeated triangles would make a body look like two that touch
        faces = unrepeated(mesh.faces)
        mesh = trimesh.Trimesh(mesh.vertices, split_t_junctions(mesh.vertices, faces), process=False)
    parts = mesh.split(only_watertight=False)
    if not all(part.is_watertight for part in parts):  # bodies that touch share edges of more than two triangles
        try:
            parts = closed_bodies(mesh.vertices, mesh.faces)
        except BodiesError as error:
            if len(parts) <= 1:
                return found  # one open body: refused where blocks are checked, as before
            raise FormatError(f"{touching_bodies(path)}: {error}") from None
    if len(parts) <= 1:
        return found
    frame = None if found.frame is None else tuple(range(len(parts))) if found.frame else ()
    return MeshFile(tuple(f"body{k}" for k in range(len(parts))), tuple(parts), frame, unit=found.unit)


def natural_key(name: str) -> tuple:
    """Sort key reading runs of digits as numbers: ``block_9`` before ``block_10``."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", name))
