"""Assemblies from COMPAS assembly JSON (compas_assembly / compas_cra), read without COMPAS."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh

from interlock import deprecation
from interlock.errors import AssemblyError

__all__ = ["read_compas", "UPSTREAM_SUPPORTS", "COMPAS_DTYPES"]

#: Node keys that the upstream compas_cra examples fix, by file stem, for the sample files that mark no
#: block ``is_support`` (``data/compas_cra/README.md``): the wedges, ``A``, ``H`` and the bridge stand on
#: blocks 0 and 1; the cubes, shelves, snake, concave and curved models on block 0; the armadillo on its
#: first course (33 blocks, as marked in upstream's solved copy).
UPSTREAM_SUPPORTS: dict[str, tuple[int, ...]] = {
    **{stem: (0, 1) for stem in ("type-a", "type-b", "type-c", "type-d", "A", "H", "bridge")},
    **{stem: (0,) for stem in ("cubes", "shelf", "shelf-s1", "shelf-s2", "shelf-s3", "shelf-stable", "snake",
                               "concave-long", "concave-short", "curve-3-blocks", "cube-curve-short",
                               "cube-curve-tall")},
    "armadillo": (*range(0, 8), *range(79, 89), *range(217, 228), *range(328, 332)),
}

#: ``dtype`` values of the assembly types this reader understands.
COMPAS_DTYPES = ("compas_assembly.datastructures/Assembly", "compas_cra.datastructures/CRA_Assembly")


def read_compas(path, supports=None) -> tuple[list[trimesh.Trimesh], list[int], list[int], dict]:
    """The blocks of a COMPAS assembly JSON file: ``(meshes, labels, frame, info)``, as :func:`load_compas` uses them.

    See :func:`~interlock.blocks.assembly.load_compas` for the format and the
    meaning of ``supports``; ``frame`` holds block indices (positions in
    increasing node-key order), ``labels`` the node keys.
    """
    path = Path(path)
    nodes, dtype = _nodes(path)
    keys = sorted(nodes, key=_node_key)
    meshes = [_block_mesh(path, key, nodes[key]) for key in keys]
    labels = [_node_key(key) for key in keys]
    frame_keys, origin = _support_keys(path, nodes, keys, labels, supports)
    index_of = {label: k for k, label in enumerate(labels)}
    unknown = [key for key in frame_keys if key not in index_of]
    if unknown:
        raise AssemblyError(f"support keys {unknown} are not nodes of {path.name}; its node keys are "
                            f"{labels[0]}..{labels[-1]}")
    frame = sorted(index_of[key] for key in frame_keys)
    info = {"source": [str(path)], "format": "compas", "dtype": dtype, "supports_from": origin}
    return meshes, labels, frame, info


def _nodes(path: Path) -> tuple[dict, str]:
    """The graph's node dict and the top-level dtype; clear errors for anything else."""
    if not path.is_file():
        raise AssemblyError(f"COMPAS file {path} does not exist")
    try:
        document = json.loads(path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise AssemblyError(f"{path} is not JSON ({error})") from None
    dtype = document.get("dtype", "") if isinstance(document, dict) else ""
    data = document.get("data") if isinstance(document, dict) else None
    graph = data.get("graph") if isinstance(data, dict) else None
    graph = graph.get("data", graph) if isinstance(graph, dict) else None
    nodes = graph.get("node") if isinstance(graph, dict) else None
    if not isinstance(nodes, dict) or (dtype and dtype not in COMPAS_DTYPES):
        raise AssemblyError(f"{path} is not a COMPAS assembly: expected a JSON object with dtype one of "
                            f"{COMPAS_DTYPES} and data.graph.data.node, got dtype {dtype!r}")
    if not nodes:
        raise AssemblyError(f"{path} is a COMPAS assembly without blocks")
    return nodes, dtype


def _node_key(key):
    """Graph keys are strings in JSON; integer keys come back as int."""
    try:
        return int(key)
    except ValueError:
        return key


def _support_keys(path: Path, nodes: dict, keys, labels, supports) -> tuple[list, str]:
    if supports is not None:
        if isinstance(supports, (str, bytes)) or not hasattr(supports, "__iter__"):
            raise AssemblyError(f"supports must be an iterable of node keys, got {supports!r}")
        return list(supports), "argument"
    marked = [label for key, label in zip(keys, labels) if nodes[key].get("is_support")]
    if marked:
        return marked, "file"
    if path.stem in UPSTREAM_SUPPORTS:
        return list(UPSTREAM_SUPPORTS[path.stem]), "upstream examples"
    return [], "none"


def _block_mesh(path: Path, key, node) -> trimesh.Trimesh:
    """The node's block as a closed triangle mesh (orientation fixed by :class:`Assembly`)."""
    block = node.get("block") if isinstance(node, dict) else None
    mesh = block.get("data", block) if isinstance(block, dict) else None
    if not isinstance(mesh, dict) or not isinstance(mesh.get("vertex"), dict) or not isinstance(mesh.get("face"), dict):
        raise AssemblyError(f"node {key} of {path.name} has no block mesh (block.data.vertex and block.data.face)")
    default = {"x": 0.0, "y": 0.0, "z": 0.0, **mesh.get("default_vertex_attributes", {})}
    vkeys = list(mesh["vertex"])
    index = {str(k): n for n, k in enumerate(vkeys)}
    try:
        vertices = np.array([[float({**default, **mesh["vertex"][k]}[axis]) for axis in "xyz"] for k in vkeys])
        polygons = [[index[str(v)] for v in face] for face in mesh["face"].values()]
    except (KeyError, TypeError, ValueError) as error:
        raise AssemblyError(f"block {key} of {path.name}: malformed vertex or face ({error!r})") from None
    triangles = [tri for polygon in polygons for tri in _triangulate(vertices, polygon)]
    if not triangles:
        raise AssemblyError(f"block {key} of {path.name} has no faces")
    result = trimesh.Trimesh(vertices, np.array(triangles), process=False)
    result.merge_vertices()
    if not _closed(result.faces):
        raise AssemblyError(f"block {key} of {path.name} is not a closed mesh (some edges border one face only)")
    return result


def _closed(faces: np.ndarray) -> bool:
    """Every undirected edge is shared by an even, nonzero number of triangles."""
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts % 2 == 0))


def _triangulate(vertices: np.ndarray, polygon: list[int]) -> list[tuple[int, int, int]]:
    """Triangles of one planar polygon (vertex indices, orientation kept): a fan if convex, else ear clipping."""
    polygon = [v for k, v in enumerate(polygon) if v != polygon[k - 1]]
    if len(polygon) < 3:
        return []
    if len(polygon) == 3:
        return [tuple(polygon)]
    points = vertices[polygon]
    normal = np.cross(points - points.mean(axis=0), np.roll(points, -1, axis=0) - points.mean(axis=0)).sum(axis=0)
    if not np.linalg.norm(normal) > 0:
        return []
    u = np.cross(normal, np.eye(3)[np.argmin(np.abs(normal))])
    u /= np.linalg.norm(u)
    v = np.cross(normal / np.linalg.norm(normal), u)
    flat = np.column_stack([points @ u, points @ v])  # counter-clockwise when the polygon is
    edge = np.roll(flat, -1, axis=0) - flat
    following = np.roll(edge, -1, axis=0)
    turns = edge[:, 0] * following[:, 1] - edge[:, 1] * following[:, 0]
    if np.all(turns >= -1e-12 * np.abs(flat).max() ** 2):
        return [(polygon[0], polygon[k], polygon[k + 1]) for k in range(1, len(polygon) - 1)]
    return [tuple(polygon[k] for k in tri) for tri in _ear_clip(flat)]


def _ear_clip(flat: np.ndarray) -> list[tuple[int, int, int]]:
    """Ear clipping of a simple counter-clockwise polygon (O(k^2); faces are small)."""
    remaining = list(range(len(flat)))
    triangles = []
    while len(remaining) > 3:
        for k in range(len(remaining)):
            a, b, c = remaining[k - 1], remaining[k], remaining[(k + 1) % len(remaining)]
            if _cross(flat[a], flat[b], flat[c]) <= 0:
                continue
            others = [p for p in remaining if p not in (a, b, c)]
            if not any(_inside(flat[p], flat[a], flat[b], flat[c]) for p in others):
                triangles.append((a, b, c))
                remaining.pop(k)
                break
        else:  # degenerate outline: fall back to a fan over what is left
            break
    triangles += [(remaining[0], remaining[k], remaining[k + 1]) for k in range(1, len(remaining) - 1)]
    return triangles


def _cross(a, b, c) -> float:
    return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _inside(p, a, b, c) -> bool:
    return _cross(a, b, p) >= 0 and _cross(b, c, p) >= 0 and _cross(c, a, p) >= 0


# Deprecated: load_compas builds an Assembly, so it lives with the type (interlock.blocks.load_compas).
__getattr__ = deprecation.moved(__name__, {"load_compas": "interlock.blocks.assembly"})
