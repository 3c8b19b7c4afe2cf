"""Files of scene nodes read through trimesh: one block per node (GLB, 3MF), or per body (OFF, other formats)."""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.repair import group_meshes
from interlock.formats.bodies import natural_key
from interlock.formats.common import MeshFile, flagged_name, header_counts, named_frame

__all__ = ["read_scene", "quiet_trimesh"]


@contextlib.contextmanager
def quiet_trimesh():
    """trimesh's log messages kept off stderr (``id 7 included but not defined!``): the readers say in one
    error what is wrong with a file."""
    logger = logging.getLogger("trimesh")
    disabled = logger.disabled
    logger.disabled = True
    try:
        yield
    finally:
        logger.disabled = disabled


def read_scene(path: Path, up: np.ndarray | None = None, header: str | None = None, stored=None,
               unit: str | None = None, scene: trimesh.Scene | None = None) -> MeshFile:
    """One block per scene node with a triangle mesh, node transform applied, named by the node.

    Nodes sort by name (digits as numbers); a name ending in :data:`~interlock.formats.common.FIXED_WORD` puts
    its block in the frame.  ``up`` turns the file's coordinates to +Z up (glTF's +Y up); ``header`` is the
    file's :func:`~interlock.formats.common.file_header` text, ``stored`` its ``(labels, info)`` and ``unit``
    the unit it states, as the format's module found them; ``scene`` the file as trimesh loaded it, if loaded.
    """
    if scene is None:
        with quiet_trimesh():
            scene = trimesh.load_scene(path)
    up = np.eye(4) if up is None else up
    nodes = []
    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[node]
        mesh = scene.geometry[geometry]
        if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces):
            nodes.append((*flagged_name(str(node)), transform, mesh))
    if len(nodes) > 1:
        nodes.sort(key=lambda node: natural_key(node[0]))
    placed = []
    for _, _, transform, mesh in nodes:
        transform = up @ transform  # exact for glTF: the rows of ``transform`` permuted, one negated
        vertices = trimesh.transform_points(mesh.vertices, transform)
        if _float32(mesh.vertices) and not np.array_equal(transform, np.eye(4)):
            # a shared float32 mesh placed by a node: the positions are known to float32 (what a viewer computes),
            # and stored so, the precision they show is read as it is (in float64 they would read as exact, and
            # contacts a float32 step apart would be lost)
            vertices = vertices.astype(np.float32).astype(float)
        faces = mesh.faces[:, ::-1] if np.linalg.det(transform[:3, :3]) < 0 else mesh.faces  # a reflection
        placed.append((vertices, faces))
    if not placed:
        return MeshFile((), ())
    announced = header_counts(header) if header else None
    labels, info = stored if stored is not None else ({}, None)
    frame = named_frame(path, [node[1] for node in nodes], announced)
    offsets = np.cumsum([0] + [len(v) for v, _ in placed])
    meshes = group_meshes(np.vstack([v for v, _ in placed]), np.vstack([f + o for (_, f), o in zip(placed, offsets)]),
                          np.repeat(np.arange(len(placed)), [len(f) for _, f in placed]))
    count = None if announced is None else announced[0]
    return MeshFile(tuple(node[0] for node in nodes), tuple(meshes), frame, count, labels, info, unit)


def _float32(values) -> bool:
    """Whether every number is a float32 (as glTF and 3MF readers hand them over in float64)."""
    values = np.asarray(values, dtype=float)
    with np.errstate(over="ignore"):
        return bool(values.size) and bool(np.array_equal(values.astype(np.float32).astype(float), values))
