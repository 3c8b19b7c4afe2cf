"""Wavefront OBJ: one object per block (written); one block per object, else per group, else per body (read).

Rhino, 3ds Max, Maya and Blender write OBJ files in different ways: objects (``o``), groups (``g``) over one
pool of welded vertices, one object holding a selection of bodies.  :func:`read_obj` finds the blocks in each;
the labels and ``Assembly.info`` that :func:`write_obj` writes as comments
(:data:`~interlock.formats.common.OBJ_LABEL`, :data:`~interlock.formats.common.OBJ_INFO`) come back with them.
OBJ has no unit and no up-axis: interlock writes +Z up unless asked for ``up="y"`` (Blender's importer and
three.js take +Y up) and states both in its header comment, ``# interlock blocks=N fixed=K triangles=T unit=mm
up=y``; the materials (one per class, ``coset_1``, ...) go into an ``.mtl`` file beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain
from interlock.blocks.labels import label_from_text
from interlock.blocks.repair import closed_groups, group_meshes, triangulate_polygons
from interlock.files import atomic_write, write_atomically
from interlock.formats.common import (OBJ_INFO, OBJ_LABEL, OBJ_SECOND_LINE, PALETTE, FormatError, MeshFile,
                                      block_name, class_name, classes, file_header, flagged_name, header_counts,
                                      header_words, is_label_pair, json_value, label_pairs, named_frame,
                                      one_line_json, touching_bodies, world_triangles)

__all__ = ["read_obj", "write_obj"]


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
    words: dict  # unit and up of the header


def read_obj(path: Path) -> MeshFile:
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
    into its bodies across edges of two triangles (:func:`~interlock.formats.bodies.split_bodies`).
    Sets of faces whose bodies touch at welded vertices are split the same way
    (:func:`_welded_bodies`); bodies that cannot be split into closed surfaces are an error.
    """
    obj = _parse_obj(path)
    faces, polygon = triangulate_polygons(obj.vertices, obj.corners, obj.counts)
    if not len(faces):
        raise FormatError(f"{path} holds no faces ('f' lines), only {len(obj.vertices)} vertices: no block to "
                            "read; a block is a closed surface of faces")
    blocks, _, triangles = obj.announced or (None, None, None)
    face_object, object_names = obj.polygon_object[polygon], obj.object_names
    by_group = len(object_names) == 1 and _closed_groups_apart(obj.vertices, faces, obj.polygon_group[polygon])
    if by_group:
        face_object, object_names = obj.polygon_group[polygon], obj.group_names
    objects = np.unique(face_object)
    if triangles is not None and triangles != len(faces):
        raise FormatError(f"{path} is cut short or damaged: it announces {blocks} blocks of {triangles} "
                            f"triangles in all, it holds {len(objects)} objects of {len(faces)} triangles")
    names, fixed = zip(*(flagged_name(object_names[k]) for k in objects.tolist()))
    labels = {} if by_group else {name: label_from_text(*obj.object_labels[k])  # the objects' OBJ_LABEL lines
                                  for name, k in zip(names, objects.tolist()) if k in obj.object_labels}
    if len(objects) > 1:  # one block per object, in file order
        meshes = group_meshes(obj.vertices, faces, np.searchsorted(objects, face_object))
        return MeshFile(names, tuple(meshes), named_frame(path, fixed, obj.announced), blocks, labels, obj.info,
                        **obj.words)
    closed, _ = _separate(obj.vertices, faces, obj.vertex_run)
    frame = named_frame(path, fixed, obj.announced)
    if closed is not None:
        closed = _welded_bodies(path, *closed)
    if closed is None:
        mesh = group_meshes(obj.vertices, faces, np.zeros(len(faces), dtype=int))[0]
        name = names[0] if names and names[0] else "body0"
        labels = {name: labels[names[0]]} if names[0] in labels else {}
        return MeshFile((name,), (mesh,), frame, blocks, labels, obj.info, **obj.words)
    meshes = group_meshes(*closed)
    frame = None if frame is None else tuple(range(len(meshes))) if frame else ()  # bodies of one object
    return MeshFile(tuple(f"body{k}" for k in range(len(meshes))), tuple(meshes), frame, blocks, **obj.words)


def _closed_groups_apart(vertices, faces, face_group) -> bool:
    """Whether the faces fall into several groups (OBJ ``g``) that are each a closed surface."""
    groups = np.unique(face_group, return_inverse=True)[1].ravel()
    return groups.max(initial=0) > 0 and closed_groups(vertices, faces, groups) is not None


def _welded_bodies(path: Path, vertices, faces, face_group) -> tuple:
    """Closed groups of faces, each split into its bodies: faces connected across edges of exactly two faces.

    A group of blocks that touch at welded (shared) vertices is closed (every
    edge has its opposite) but falls apart across the edges that more than
    two faces share; each piece must be closed, or the blocks cannot be told
    apart (an :class:`FormatError`).  Groups of one body come back as they are.
    """
    adjacency = trimesh.Trimesh(vertices, faces, process=False).face_adjacency
    body = trimesh.graph.connected_component_labels(adjacency, node_count=len(faces))
    if len(np.unique(body)) == len(np.unique(face_group)):
        return vertices, faces, face_group
    apart = closed_groups(vertices, faces, body)
    if apart is None:
        raise FormatError(touching_bodies(path))
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
    header = next((line for line in lines[:20] if not line.startswith(("v", "f")) and header_counts(line)), None)
    announced = header_counts(header) if header is not None else None
    words = header_words(header) if header is not None else {}
    if announced is None and any(line.startswith(OBJ_SECOND_LINE) for line in lines[:20]):
        raise FormatError(f"{path} was written by interlock but its header ('# interlock blocks=N ...') is "
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
                    raise ValueError("a vertex coordinate is not a finite number (NaN, infinite, or beyond the "
                                     "largest double, 1.8e308)")
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
            elif line.startswith(OBJ_LABEL) and is_label_pair(pair := json_value(line[len(OBJ_LABEL):])):
                object_labels[len(names) - 1] = pair
            elif line.startswith(OBJ_INFO) and isinstance(stored := json_value(line[len(OBJ_INFO):]), dict):
                info = stored
        except ValueError as error:
            if number == last:  # the file ends in the middle of this line
                break
            raise FormatError(f"{path} line {number + 1}: {error}: {line.strip()[:60]!r}") from None
    counts = np.array([len(p) for p in polygons], dtype=np.int64)
    corners = np.array([i for p in polygons for i in p], dtype=np.int64)
    before = np.repeat(np.array(seen, dtype=np.int64), counts)
    corners = np.where(corners < 0, before + corners, corners - 1)
    vertices = np.array(rows, dtype=float).reshape(-1, 3)
    bad = (corners < 0) | (corners >= len(vertices))
    if bad.any():
        raise FormatError(f"{path} has faces with vertex indices outside 1..{len(vertices)} "
                            f"(e.g. {corners[bad][0] + 1}); the file is cut short or damaged")
    return _Obj(vertices, corners, counts, np.array(objects, dtype=np.int64), tuple(names),
                np.array(runs, dtype=np.int64), announced, np.array(groups, dtype=np.int64), tuple(group_names),
                object_labels, info, {"unit": words.get("unit"), "up": words.get("up", "z")})


def write_obj(assembly: Assembly, path: Path, up: str = "z") -> None:
    """OBJ with one object per block (``o block_0007``, ``o block_0007 fixed``), its label in a comment, and
    the class materials in an ``.mtl`` file beside it (same stem)."""
    vertices, faces, vertex_start, face_start = world_triangles(assembly)
    values, kind = classes(assembly)
    materials = path.with_suffix(".mtl")
    used = np.unique(values)
    write_atomically(materials, "".join(
        f"newmtl {class_name(kind, c)}\nKd {r:.6f} {g:.6f} {b:.6f}\nd {a:.6f}\n\n"
        for c, (r, g, b, a) in ((c, PALETTE[c % len(PALETTE)] / 255) for c in used.tolist())))
    frame = set(assembly.frame)
    header = file_header(len(assembly), len(assembly.frame), len(faces), unit=assembly.unit, up=up)
    with atomic_write(path) as temporary, open(temporary, "w") as file:
        file.write(f"# {header}\n")
        file.write(f"{OBJ_SECOND_LINE}; materials by {kind}\n")
        file.write(f"{OBJ_INFO}{one_line_json(plain(assembly.info))}\n")
        file.write(f"mtllib {materials.name}\n")
        labels = label_pairs(assembly)
        for i in range(len(assembly)):
            block_vertices = vertices[vertex_start[i]:vertex_start[i + 1]]
            block_faces = faces[face_start[i]:face_start[i + 1]] + 1
            file.write(f"o {block_name(i, frame)}\n{OBJ_LABEL}{one_line_json(labels[block_name(i)])}\n"
                       f"usemtl {class_name(kind, int(values[i]))}\n")
            file.write("v %r %r %r\n" * len(block_vertices) % tuple(block_vertices.ravel().tolist()))
            file.write("f %d %d %d\n" * len(block_faces) % tuple(block_faces.ravel().tolist()))
