"""COMPAS assembly JSON (compas_assembly / compas_cra), read and written without COMPAS."""

from __future__ import annotations

import json
import uuid
from pathlib import Path

import numpy as np
import trimesh

from interlock import deprecation
from interlock.blocks.info import plain, restored
from interlock.errors import AssemblyError
from interlock.files import unwritable, write_atomically

__all__ = ["read_compas", "write_compas", "UPSTREAM_SUPPORTS", "COMPAS_DTYPES", "BLOCK_DTYPE", "GRAPH_DTYPE",
           "INFO_ATTRIBUTE"]

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
#: ``dtype`` of a block (a COMPAS mesh) and of the assembly's graph in files :func:`write_compas` writes.
BLOCK_DTYPE = "compas_assembly.datastructures/Block"
GRAPH_DTYPE = "compas.datastructures/Graph"
#: The assembly attribute holding ``Assembly.info`` (as JSON text) in files :func:`write_compas` writes.
INFO_ATTRIBUTE = "interlock"
# Node attributes that compas_assembly's Assembly declares (its defaults), plus the block's centroid.
_NODE_DEFAULTS = {"x": 0.0, "y": 0.0, "z": 0.0, "block": None, "is_support": False, "section": None,
                  "mesh_size": None, "displacement": [0, 0, 0, 0, 0, 0], "name": None, "label": None}


def read_compas(path, supports=None, progress=None) -> tuple[list[trimesh.Trimesh], list[int], list[int], dict]:
    """The blocks of a COMPAS assembly JSON file: ``(meshes, labels, frame, info)``, as :func:`load_compas` uses them.

    See :func:`~interlock.blocks.assembly.load_compas` for the format and the
    meaning of ``supports``; ``frame`` holds block indices (positions in
    increasing node-key order), ``labels`` the node keys.
    """
    path = Path(path)
    nodes, dtype, stored = _nodes(path)  # stored: the info of a file of write_compas, else None
    keys = sorted(nodes, key=_node_key)
    meshes = []
    for k, key in enumerate(keys):
        if progress is not None:
            progress(k, len(keys))
        meshes.append(_block_mesh(path, key, nodes[key]))
    labels = [_node_key(key) for key in keys]
    frame_keys, origin = _support_keys(path, nodes, keys, labels, supports, ours=stored is not None)
    index_of = {label: k for k, label in enumerate(labels)}
    unknown = [key for key in frame_keys if key not in index_of]
    if unknown:
        raise AssemblyError(f"support keys {unknown} are not nodes of {path.name}; its node keys are "
                            f"{labels[0]}..{labels[-1]}")
    frame = sorted(index_of[key] for key in frame_keys)
    info = {**restored(stored or {}), "source": [str(path)], "format": "compas", "dtype": dtype,
            "supports_from": origin}
    names = [nodes[key].get("name") for key in keys]
    if any(isinstance(name, str) for name in names):
        info["names"] = names
    return meshes, labels, frame, info


def write_compas(assembly, path, progress=None) -> Path:
    """Write an assembly as COMPAS assembly JSON, the schema :func:`read_compas` reads.

    The file is what ``compas.json_dump`` writes for a
    ``compas_assembly.datastructures.Assembly`` (compas 2, compas_assembly 0.7,
    the assemblies compas_cra 0.8 solves): one graph node per block, keyed by
    the block index, holding

    - ``block``: the block as a COMPAS mesh in world coordinates, outward faces;
      coplanar triangles that meet along edges are merged into one polygon face
      (so interfaces come out as whole polygons), vertices written exactly;
    - ``is_support``: whether the block is in the frame;
    - ``name`` (``block_0007``), ``label`` (the label as text) and ``x, y, z``
      (the block's centroid).

    ``Assembly.info`` is kept in the assembly attribute :data:`INFO_ATTRIBUTE`
    as a JSON text (numbers, text and lists as such, other values as text; a
    text, because COMPAS would take a nested ``dtype`` key for an object).  The graph has no
    edges: interfaces are for COMPAS to find (``compas_assembly.algorithms.assembly_interfaces``).
    The file is written under a temporary name beside ``path`` and moved into place.

    Parameters
    ----------
    assembly : Assembly
    path : str or path-like

    Returns
    -------
    pathlib.Path

    Raises
    ------
    AssemblyError
        If the assembly has no blocks or the file cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import load_compas, presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_compas(write_compas(grid, Path(folder) / "grid.json"))
    >>> len(back), back.frame == grid.frame, back.info["names"][:2], back.info["preset"]
    (9, True, ['block_0000', 'block_0001'], 'cube_grid')
    """
    path = Path(path)
    if not len(assembly):
        raise AssemblyError(f"nothing to write to {path.name}: the assembly has no blocks")
    fixed = set(assembly.frame)
    nodes = {}
    for i in range(len(assembly)):
        if progress is not None:
            progress(i, len(assembly))
        mesh = assembly.mesh(i)
        x, y, z = (float(c) for c in assembly.centroids[i])
        nodes[str(i)] = {"block": {"dtype": BLOCK_DTYPE, "data": _mesh_data(mesh, i),
                                   "guid": str(uuid.uuid5(uuid.NAMESPACE_OID, f"interlock block {i}"))},
                         "is_support": i in fixed, "name": f"block_{i:04d}", "label": str(assembly.labels[i]),
                         "x": x, "y": y, "z": z}
    graph = {"attributes": {}, "default_node_attributes": _NODE_DEFAULTS,
             "default_edge_attributes": {"interfaces": None}, "node": nodes, "edge": {key: {} for key in nodes},
             "max_node": len(assembly) - 1}
    document = {"dtype": COMPAS_DTYPES[0],
                "data": {"attributes": {"name": "Assembly", INFO_ATTRIBUTE: json.dumps(plain(assembly.info))},
                         "graph": {"dtype": GRAPH_DTYPE, "data": graph}}}
    _write_atomically(json.dumps(document, allow_nan=False), path)
    return path


def _mesh_data(mesh: trimesh.Trimesh, i: int) -> dict:
    """A COMPAS mesh's data: the used vertices, faces as polygons (coplanar triangles merged)."""
    polygons = _polygons(mesh)
    used = np.unique(np.concatenate([np.asarray(p) for p in polygons]))
    number = {int(v): k for k, v in enumerate(used.tolist())}
    vertex = {str(k): dict(zip("xyz", p)) for k, p in enumerate(mesh.vertices[used].tolist())}
    face = {str(f): [number[v] for v in polygon] for f, polygon in enumerate(polygons)}
    return {"attributes": {"name": f"block_{i:04d}", "node": i},
            "default_vertex_attributes": {"x": 0.0, "y": 0.0, "z": 0.0}, "default_edge_attributes": {},
            "default_face_attributes": {}, "vertex": vertex, "face": face,
            "facedata": {key: {} for key in face}, "edgedata": {}, "max_vertex": len(vertex) - 1,
            "max_face": len(face) - 1}


def _polygons(mesh: trimesh.Trimesh) -> list[list[int]]:
    """The faces of a closed triangle mesh, each set of coplanar triangles that meet along edges as one polygon.

    A set whose outline is not one loop (a face with a hole, or touching itself at a
    corner) stays triangles.  Polygon corners keep the vertices of the mesh, so
    neighbouring faces still share their edges.
    """
    faces = np.asarray(mesh.faces, dtype=np.int64)
    merged = np.zeros(len(faces), dtype=bool)
    polygons = []
    for facet in mesh.facets:
        loop = _outline(faces[facet])
        if loop is not None:
            polygons.append(loop)
            merged[facet] = True
    return polygons + faces[~merged].tolist()


def _outline(triangles: np.ndarray) -> list[int] | None:
    """The boundary of a patch of triangles as one loop of vertices, oriented like them; None unless it is one loop."""
    directed = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).tolist()
    inside = set(map(tuple, directed))
    following = {}
    for a, b in directed:
        if (b, a) in inside:
            continue
        if a in following:
            return None
        following[a] = b
    if not following:
        return None
    start = next(iter(following))
    loop, vertex = [start], following[start]
    while vertex != start and len(loop) <= len(following):
        loop.append(vertex)
        vertex = following.get(vertex, start)
    return loop if len(loop) == len(following) and vertex == start else None


def _write_atomically(text: str, path: Path):
    problem = unwritable(path, hint="ending in .json")
    if problem:
        raise AssemblyError(f"cannot write {path}: {problem}")
    try:
        write_atomically(path, text)
    except OSError as error:
        raise AssemblyError(f"cannot write {path}: {error.strerror or error}") from None


def _nodes(path: Path) -> tuple[dict, str, dict]:
    """The graph's node dict, the top-level dtype and the stored ``info`` (:data:`INFO_ATTRIBUTE`); clear errors."""
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
    attributes = data.get("attributes")
    stored = attributes.get(INFO_ATTRIBUTE) if isinstance(attributes, dict) else None
    try:
        stored = json.loads(stored) if isinstance(stored, str) else stored
    except json.JSONDecodeError:
        stored = None
    return nodes, dtype, dict(stored) if isinstance(stored, dict) else None


def _node_key(key):
    """Graph keys are strings in JSON; integer keys come back as int."""
    try:
        return int(key)
    except ValueError:
        return key


def _support_keys(path: Path, nodes: dict, keys, labels, supports, ours: bool = False) -> tuple[list, str]:
    """The support node keys and where they came from; a file of :func:`write_compas` (``ours``) states its frame."""
    if supports is not None:
        if isinstance(supports, (str, bytes)) or not hasattr(supports, "__iter__"):
            raise AssemblyError(f"supports must be an iterable of node keys, got {supports!r}")
        return list(supports), "argument"
    marked = [label for key, label in zip(keys, labels) if nodes[key].get("is_support")]
    if marked or ours:
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
