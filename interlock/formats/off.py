"""OFF (Object File Format, Geomview, MeshLab): one mesh whose blocks share no vertex; read and written here.

OFF has no objects, no unit and no up-axis.  interlock writes each block's vertices on their own, so the blocks
are the sets of faces that share vertex indices (a block per set, in order), and comments carry the rest:
``# interlock blocks=N fixed=K unit=U up=A`` (the header), ``# interlock fixed 0 3 7`` (the frame), and the
labels and ``Assembly.info`` as JSON.  Faces carry no colour, so meshio, trimesh and MeshLab all read the file
(meshio refuses face colours).  Reading checks the file
against the vertex and face counts its count line announces.  A foreign OFF is read the same way: its sets of
faces sharing vertex indices, each a closed surface, else its connected bodies.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain
from interlock.blocks.repair import closed_groups, group_meshes, triangulate_polygons
from interlock.files import atomic_write
from interlock.formats.common import (INFO_KEY, LABELS_KEY, FormatError, MeshFile, block_name, file_header,
                                      header_counts, header_words, json_value, label_pairs, one_line_json,
                                      stored_meaning, world_triangles)

__all__ = ["read_off", "write_off", "FRAME_COMMENT"]

#: The comment that lists the frame's blocks: ``# interlock fixed 0 3 7``.
FRAME_COMMENT = "# interlock fixed"


def read_off(path: Path) -> MeshFile:
    """The blocks of an OFF file: the sets of faces that share vertex indices (interlock's files and others whose
    blocks each have their vertices), with the frame, labels, info, unit and up-axis of interlock's comments."""
    lines = path.read_text(errors="replace").splitlines()
    comments = [line.strip() for line in lines if line.lstrip().startswith("#")]
    header = next((c for c in comments if header_counts(c)), None)
    words = header_words(header) if header else {}
    stored = {key: json_value(value) for key, value in
              (re.match(r"# interlock (\S+) (.*)", c).groups() for c in comments
               if re.match(rf"# interlock ({LABELS_KEY}|{INFO_KEY}) ", c))}
    labels, info = stored_meaning(stored)
    fixed = next((c[len(FRAME_COMMENT):].split() for c in comments if c.startswith(FRAME_COMMENT)), None)
    rows = [(number, line.split("#", 1)[0].split()) for number, line in enumerate(lines, 1)]
    rows = [(number, words_) for number, words_ in rows if words_]
    if not rows or not re.fullmatch(r"C?N?OFF", rows[0][1][0]):
        raise FormatError(f"{path} is not an OFF file: it does not start with 'OFF'")
    if len(rows[0][1]) > 1:  # "OFF V F E" on one line
        count_row, counts, data = rows[0], rows[0][1][1:], rows[1:]
    else:
        count_row = rows[1] if len(rows) > 1 else (rows[0][0] + 1, [])
        counts, data = count_row[1], rows[2:]
    try:
        n_vertices, n_faces = int(counts[0]), int(counts[1])
    except (IndexError, ValueError):
        raise FormatError(f"{path} line {count_row[0]}: the count line 'VERTICES FACES EDGES' is missing or "
                          "malformed") from None
    if len(data) < n_vertices + n_faces:
        held_vertices = min(len(data), n_vertices)
        raise FormatError(f"{path} is cut short: its count line announces {n_vertices:,} vertices and "
                          f"{n_faces:,} faces; it holds {held_vertices:,} vertices and "
                          f"{max(len(data) - n_vertices, 0):,} faces")
    try:
        vertices = np.array([row[:3] for _, row in data[:n_vertices]], dtype=float).reshape(-1, 3)
    except ValueError:
        raise FormatError(f"{path}: a vertex line does not hold three numbers") from None
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        number, row = data[int(bad[0])]
        raise FormatError(f"{path} line {number}: a vertex coordinate is not a finite number: {' '.join(row)!r}")
    polygons = []
    for number, row in data[n_vertices:n_vertices + n_faces]:
        try:
            size = int(row[0])
            corners = [int(v) for v in row[1:size + 1]]
        except (ValueError, IndexError):
            raise FormatError(f"{path} line {number}: a face line is malformed: {' '.join(row)[:60]!r}") from None
        if size < 3 or len(corners) != size or min(corners) < 0 or max(corners) >= n_vertices:
            raise FormatError(f"{path} line {number}: a face needs 3 or more vertex indices in 0..{n_vertices - 1}, "
                              f"got {' '.join(row)[:60]!r}")
        polygons.append(corners)
    faces, _ = triangulate_polygons(vertices, [v for p in polygons for v in p], [len(p) for p in polygons])
    if not len(faces):
        raise FormatError(f"{path} holds no faces: no block to read")
    groups = _shared_vertex_sets(vertices, faces)
    announced = header_counts(header) if header else None
    if groups.max() > 0 and (announced is not None or closed_groups(vertices, faces, groups) is not None):
        meshes = group_meshes(vertices, faces, groups)
    else:
        meshes = group_meshes(vertices, faces, np.zeros(len(faces), dtype=int))
    names = tuple(f"block_{k:04d}" for k in range(len(meshes)))
    frame = None
    if announced is not None or fixed is not None:
        frame = tuple(sorted(int(k) for k in fixed or () if k.isdecimal() and int(k) < len(meshes)))
        if announced is not None and announced[1] is not None and announced[1] != len(frame):
            raise FormatError(f"{path} is cut short or damaged: it announces {announced[1]} fixed blocks, its "
                              f"comment lists {len(frame)}")
    return MeshFile(names, tuple(meshes), frame, None if announced is None else announced[0], labels, info,
                    words.get("unit"), up=words.get("up", "z"))


def write_off(assembly: Assembly, path: Path, up: str = "z") -> None:
    """OFF: every block's vertices on their own, interlock's comments."""
    vertices, faces, _, _ = world_triangles(assembly)
    lines = ["OFF", f"# {file_header(len(assembly), len(assembly.frame), unit=assembly.unit, up=up)}"]
    if assembly.frame:
        lines.append(f"{FRAME_COMMENT} {' '.join(map(str, assembly.frame))}")
    lines += [f"# interlock {LABELS_KEY} {one_line_json(label_pairs(assembly))}",
              f"# interlock {INFO_KEY} {one_line_json(plain(assembly.info))}",
              f"# one block per set of faces sharing vertices, in order ({block_name(0)}, ...)",
              f"{len(vertices)} {len(faces)} 0"]
    with atomic_write(path) as temporary, open(temporary, "w") as file:
        file.write("\n".join(lines) + "\n")
        file.write("%r %r %r\n" * len(vertices) % tuple(vertices.ravel().tolist()))
        file.write("3 %d %d %d\n" * len(faces) % tuple(faces.ravel().tolist()))


def _shared_vertex_sets(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each face's set of faces connected through shared vertex indices, numbered by first appearance."""
    graph = coo_matrix((np.ones(2 * len(faces)), (faces[:, [0, 1]].ravel(), faces[:, [1, 2]].ravel())),
                       shape=(len(vertices), len(vertices)))
    component = connected_components(graph, directed=False)[1][faces[:, 0]]
    _, first, inverse = np.unique(component, return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first))  # numbered in the order the sets first appear
    return order[inverse.ravel()]
