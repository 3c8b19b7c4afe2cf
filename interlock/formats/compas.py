"""COMPAS assembly JSON (compas_assembly / compas_cra), read and written without COMPAS.

COMPAS has no unit: ``assembly.unit`` travels in the assembly attribute :data:`INFO_ATTRIBUTE` with the rest of
``Assembly.info``.  COMPAS is +Z up.  A text nesting deeper than
:data:`~interlock.formats.common.MAX_NESTING` is refused before it is parsed.
"""

from __future__ import annotations

import json
import uuid
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain, restored
from interlock.blocks.labels import label_from_text, label_text
from interlock.files import unwritable, write_atomically
from interlock.formats.common import MAX_NESTING, FormatError, json_value, nesting
from interlock.formats.compas_examples import (FINGERPRINT_ROUNDING, UPSTREAM_FINGERPRINTS, UPSTREAM_SUPPORTS,
                                               fingerprint)

__all__ = ["read_compas", "load_compas", "write_compas", "read_json_document", "fingerprint", "UPSTREAM_SUPPORTS",
           "UPSTREAM_FINGERPRINTS",
           "FINGERPRINT_ROUNDING", "COMPAS_DTYPES", "BLOCK_DTYPE", "GRAPH_DTYPE", "INFO_ATTRIBUTE"]

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


def read_compas(path, supports=None, progress=None) -> tuple[list[trimesh.Trimesh], list, list[int], dict]:
    """The blocks of a COMPAS assembly JSON file: ``(meshes, labels, frame, info)``, as :func:`load_compas` uses them.

    See :func:`~interlock.blocks.assembly.load_compas` for the format and the
    meaning of ``supports``; ``frame`` holds block indices (positions in
    increasing node-key order).  ``labels`` are the node keys, except that a
    node with a ``label`` text (as :func:`write_compas` writes them) other than
    its key's text is labelled by that text, rebuilt as a group element, tuple,
    ... where the node has a ``label_type``; then ``info["node_keys"]`` lists
    the node keys.  Without ``supports`` and ``is_support`` marks, the frame is
    :data:`UPSTREAM_SUPPORTS` if the file is an upstream example (its node count
    and :func:`fingerprint` are in :data:`UPSTREAM_FINGERPRINTS`, whatever the
    file's name; ``info["upstream_example"]`` names it), else empty.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import Assembly
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> named = Assembly.from_meshes(cubes, frame=[0], labels=["base", "keystone"])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     meshes, labels, frame, info = read_compas(write_compas(named, Path(folder) / "two.json"))
    >>> labels, frame, info["node_keys"], info["supports_from"]
    (['base', 'keystone'], [0], [0, 1], 'file')
    """
    path = Path(path)
    nodes, dtype, stored = _nodes(path)  # stored: the info of a file of write_compas, else None
    keys = sorted(nodes, key=_node_key)
    meshes = []
    for k, key in enumerate(keys):
        if progress is not None:
            progress(k, len(keys))
        meshes.append(_block_mesh(path, key, nodes[key]))
    node_keys = [_node_key(key) for key in keys]
    labels = [_label(nodes[key], node_key) for key, node_key in zip(keys, node_keys)]
    frame_keys, origin, example = _support_keys(nodes, keys, node_keys, meshes, supports, ours=stored is not None)
    index_of = {node_key: k for k, node_key in enumerate(node_keys)}
    unknown = [key for key in frame_keys if key not in index_of]
    if unknown:
        raise FormatError(f"support keys {unknown} are not nodes of {path.name}; its node keys are "
                            f"{node_keys[0]}..{node_keys[-1]}")
    frame = sorted(index_of[key] for key in frame_keys)
    info = {**restored(stored or {}), "source": [str(path)], "format": "compas", "dtype": dtype,
            "supports_from": origin}
    info.pop("upstream_example", None)
    info.pop("node_keys", None)
    if example is not None:
        info["upstream_example"] = example
    if labels != node_keys:
        info["node_keys"] = node_keys
    names = [nodes[key].get("name") for key in keys]
    if any(isinstance(name, str) for name in names):
        info["names"] = names
    return meshes, labels, frame, info


def write_compas(assembly, path, progress=None) -> Path:
    """Write an assembly as COMPAS assembly JSON, the schema :func:`read_compas` reads.

    The file is what ``compas.json_dump`` writes for a
    ``compas_assembly.datastructures.Assembly`` (compas 2, compas_assembly 0.7,
    the assemblies compas_cra 0.8 solves): one graph node per block, in block
    order, keyed by

    - the block's label, if the labels are distinct integers >= 0 (the node
      keys of an assembly :func:`read_compas` read from a file whose nodes have
      no label texts, so its keys come back as they were);
    - else ``info["node_keys"]``, if that lists such integers, one per block
      (the keys of a file whose nodes have label texts);
    - else the block index.

    Each node holds

    - ``block``: the block as a COMPAS mesh in world coordinates, outward faces;
      coplanar triangles that meet along edges are merged into one polygon face
      (so interfaces come out as whole polygons), vertices written exactly;
    - ``is_support``: whether the block is in the frame;
    - ``name`` (the designer's, ``info["names"]``, else ``block_0007`` by block index), ``label`` and ``label_type``
      (the label as text and its kind, :func:`~interlock.blocks.labels.label_text`;
      :func:`read_compas` rebuilds the label from them unless the text is the
      node key's) and ``x, y, z`` (the block's centroid).

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
    FormatError
        If the assembly has no blocks or the file cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = load_compas(write_compas(grid, Path(folder) / "grid.json"))
    >>> len(back), back.frame == grid.frame, back.info["names"][:2], back.info["preset"], back.labels[:2]
    (9, True, ['block_0000', 'block_0001'], 'cube_grid', ((0, 0), (0, 1)))
    """
    path = Path(path)
    if not len(assembly):
        raise FormatError(f"nothing to write to {path.name}: the assembly has no blocks")
    fixed = set(assembly.frame)
    keys = _node_keys(assembly)
    names = assembly.info.get("names")  # the designer's names (read from a .3dm or a COMPAS file)
    if not (isinstance(names, (list, tuple)) and len(names) == len(assembly)):
        names = [None] * len(assembly)
    names = [name if isinstance(name, str) and name else None for name in names]
    nodes = {}
    for i, key in enumerate(keys):
        if progress is not None:
            progress(i, len(assembly))
        mesh = assembly.mesh(i)
        x, y, z = (float(c) for c in assembly.centroids[i])
        kind, text = label_text(assembly.labels[i])
        nodes[str(key)] = {"block": {"dtype": BLOCK_DTYPE, "data": _mesh_data(mesh, i, key),
                                     "guid": str(uuid.uuid5(uuid.NAMESPACE_OID, f"interlock block {i}"))},
                           "is_support": i in fixed, "name": names[i] or f"block_{i:04d}", "label": text,
                           "label_type": kind,
                           "x": x, "y": y, "z": z}
    graph = {"attributes": {}, "default_node_attributes": _NODE_DEFAULTS,
             "default_edge_attributes": {"interfaces": None}, "node": nodes, "edge": {key: {} for key in nodes},
             "max_node": max(keys)}
    document = {"dtype": COMPAS_DTYPES[0],
                "data": {"attributes": {"name": "Assembly", INFO_ATTRIBUTE: json.dumps(plain(assembly.info))},
                         "graph": {"dtype": GRAPH_DTYPE, "data": graph}}}
    _write_atomically(json.dumps(document, allow_nan=False), path)
    return path


def _node_keys(assembly) -> list[int]:
    """The node keys of :func:`write_compas`: the labels, else ``info["node_keys"]``, if they are keys; else indices."""
    for keys in (assembly.labels, assembly.info.get("node_keys")):
        if (isinstance(keys, (list, tuple)) and len(keys) == len(assembly)
                and all(isinstance(k, (int, np.integer)) and not isinstance(k, (bool, np.bool_)) and k >= 0
                        for k in keys)
                and len({int(k) for k in keys}) == len(keys)):
            return [int(k) for k in keys]
    return list(range(len(assembly)))


def _mesh_data(mesh: trimesh.Trimesh, i: int, key: int) -> dict:
    """A COMPAS mesh's data: the used vertices, faces as polygons (coplanar triangles merged)."""
    polygons = _polygons(mesh)
    used = np.unique(np.concatenate([np.asarray(p) for p in polygons]))
    number = {int(v): k for k, v in enumerate(used.tolist())}
    vertex = {str(k): dict(zip("xyz", p)) for k, p in enumerate(mesh.vertices[used].tolist())}
    face = {str(f): [number[v] for v in polygon] for f, polygon in enumerate(polygons)}
    return {"attributes": {"name": f"block_{i:04d}", "node": key},
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
        raise FormatError(f"cannot write {path}: {problem}")
    try:
        write_atomically(path, text)
    except OSError as error:
        raise FormatError(f"cannot write {path}: {error.strerror or error}") from None


def _nodes(path: Path) -> tuple[dict, str, dict]:
    """The graph's node dict, the top-level dtype and the stored ``info`` (:data:`INFO_ATTRIBUTE`); clear errors."""
    document = read_json_document(path, "COMPAS file")
    dtype = document.get("dtype", "") if isinstance(document, dict) else ""
    data = document.get("data") if isinstance(document, dict) else None
    graph = data.get("graph") if isinstance(data, dict) else None
    graph = graph.get("data", graph) if isinstance(graph, dict) else None
    nodes = graph.get("node") if isinstance(graph, dict) else None
    if not isinstance(nodes, dict) or (dtype and dtype not in COMPAS_DTYPES):
        raise FormatError(f"{path} is not a COMPAS assembly: expected a JSON object with dtype one of "
                            f"{COMPAS_DTYPES} and data.graph.data.node, got dtype {dtype!r}")
    if not nodes:
        raise FormatError(f"{path} is a COMPAS assembly without blocks")
    attributes = data.get("attributes")
    stored = attributes.get(INFO_ATTRIBUTE) if isinstance(attributes, dict) else None
    if isinstance(stored, str):
        stored = json_value(stored)
    return nodes, dtype, dict(stored) if isinstance(stored, dict) else None


def read_json_document(path, what: str = "JSON file"):
    """The value of a JSON file; a :class:`FormatError` in one line for a missing file, text that is not JSON,
    or brackets nested deeper than :data:`~interlock.formats.common.MAX_NESTING` (which would exhaust Python's
    parser, a RecursionError).  ``Infinity`` and ``NaN`` parse, as Python reads them; the readers check numbers.

    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "deep.json"
    >>> _ = path.write_text("[" * 200_000)
    >>> read_json_document(path)
    Traceback (most recent call last):
    ...
    interlock.formats.common.FormatError: ... nests brackets 200000 deep; JSON files of assemblies nest about 10 ...
    """
    path = Path(path)
    if not path.is_file():
        raise FormatError(f"{what} {path} does not exist")
    data = path.read_bytes()
    depth = nesting(data)
    if depth > MAX_NESTING:
        raise FormatError(f"{path} nests brackets {depth} deep; JSON files of assemblies nest about 10 deep (at "
                          f"most {MAX_NESTING} are read)")
    try:
        return json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise FormatError(f"{path} is not JSON ({error})") from None


def _node_key(key):
    """Graph keys are strings in JSON; integer keys come back as int."""
    try:
        return int(key)
    except ValueError:
        return key


def _support_keys(nodes: dict, keys, node_keys, meshes, supports, ours: bool = False) -> tuple[list, str, str | None]:
    """The support node keys, where they came from, and the upstream example the file is (else None).

    A file of :func:`write_compas` (``ours``) states its frame; the upstream supports apply only to a file
    whose node count and :func:`fingerprint` are an example's (:data:`UPSTREAM_FINGERPRINTS`).
    """
    if supports is not None:
        if isinstance(supports, (str, bytes)) or not hasattr(supports, "__iter__"):
            raise FormatError(f"supports must be an iterable of node keys, got {supports!r}")
        return list(supports), "argument", None
    marked = [node_key for key, node_key in zip(keys, node_keys) if nodes[key].get("is_support")]
    if marked or ours:
        return marked, "file", None
    candidates = [stem for stem, (count, _) in UPSTREAM_FINGERPRINTS.items() if count == len(keys)]
    if candidates:
        digest = fingerprint(node_keys, meshes)
        for stem in candidates:
            if UPSTREAM_FINGERPRINTS[stem][1] == digest:
                return list(UPSTREAM_SUPPORTS[stem]), "upstream examples", stem
    return [], "none", None


def _label(node: dict, node_key):
    """A node's label: its ``label`` text unless that is missing, empty or its key's text, else the key; rebuilt
    from the text by the node's ``label_type`` where :func:`write_compas` stored one (:mod:`~.labels`)."""
    label, kind = node.get("label"), node.get("label_type")
    if not isinstance(label, str) or not label or label == str(node_key):
        return node_key
    return label_from_text(kind, label) if isinstance(kind, str) else label


def _block_mesh(path: Path, key, node) -> trimesh.Trimesh:
    """The node's block as a closed triangle mesh (orientation fixed by :class:`Assembly`)."""
    block = node.get("block") if isinstance(node, dict) else None
    mesh = block.get("data", block) if isinstance(block, dict) else None
    if not isinstance(mesh, dict) or not isinstance(mesh.get("vertex"), dict) or not isinstance(mesh.get("face"), dict):
        raise FormatError(f"node {key} of {path.name} has no block mesh (block.data.vertex and block.data.face)")
    default = {"x": 0.0, "y": 0.0, "z": 0.0, **mesh.get("default_vertex_attributes", {})}
    vkeys = list(mesh["vertex"])
    index = {str(k): n for n, k in enumerate(vkeys)}
    try:
        vertices = np.array([[float({**default, **mesh["vertex"][k]}[axis]) for axis in "xyz"] for k in vkeys])
        polygons = [[index[str(v)] for v in face] for face in mesh["face"].values()]
    except (KeyError, TypeError, ValueError) as error:
        raise FormatError(f"block {key} of {path.name}: malformed vertex or face ({error!r})") from None
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        raise FormatError(f"block {key} of {path.name}: vertex {vkeys[bad[0]]} has a coordinate that is not a finite "
                          f"number: {vertices[bad[0]].tolist()}")
    triangles = [tri for polygon in polygons for tri in _triangulate(vertices, polygon)]
    if not triangles:
        raise FormatError(f"block {key} of {path.name} has no faces")
    result = trimesh.Trimesh(vertices, np.array(triangles), process=False)
    result.merge_vertices()
    if not _closed(result.faces):
        raise FormatError(f"block {key} of {path.name} is not a closed mesh (some edges border one face only)")
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


def load_compas(path, supports=None, progress=None) -> Assembly:
    """An assembly from a COMPAS assembly JSON file, without COMPAS.

    The file is ``{"dtype": "compas_assembly.datastructures/Assembly" (or ``compas_cra...CRA_Assembly``),
    "data": {"graph": {"data": {"node": ...}}}}``; each node holds a ``block`` (a COMPAS mesh: ``vertex`` key ->
    ``{x, y, z}``, ``face`` key -> vertex keys) and optionally ``is_support``.  Polygonal faces are triangulated
    (ear clipping in their plane, so non-convex faces work) and every block must be closed.  Interfaces stored in
    the file are ignored: :func:`interlock.verify.contacts` recomputes them.

    Parameters
    ----------
    path : str or Path
    supports : iterable of int, optional
        Node keys of the fixed blocks (the frame).  Default: the nodes marked ``is_support``; when none is and
        the file is one of the upstream examples (its node count and :func:`fingerprint`, whatever its name),
        :data:`UPSTREAM_SUPPORTS`, else no frame.
    progress : callable, optional

    Returns
    -------
    Assembly
        One block per node in increasing key order; ``labels`` are the node keys (int), or a node's ``label``
        text where it has one (then ``info["node_keys"]`` lists the keys); ``frame`` the supports; ``info`` the
        source, dtype, whether the supports came from the file, the argument or the table, and
        ``upstream_example`` when it is one.

    Raises
    ------
    FormatError
        If the file is missing or not COMPAS assembly JSON, a block is not a closed mesh, or a support key is
        not a node.

    Examples
    --------
    >>> import json, pathlib, tempfile, trimesh
    >>> def node(mesh, support):
    ...     vertex = {str(k): dict(zip("xyz", p)) for k, p in enumerate(mesh.vertices.tolist())}
    ...     return {"block": {"data": {"vertex": vertex, "face": dict(enumerate(mesh.faces.tolist()))}},
    ...             "is_support": support}
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> graph = {"node": {str(k): node(m, k == 0) for k, m in enumerate(cubes)}}
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "stack.json"
    >>> _ = path.write_text(json.dumps({"dtype": COMPAS_DTYPES[0], "data": {"graph": {"data": graph}}}))
    >>> a = load_compas(path)
    >>> len(a), a.labels, a.frame, round(float(a.volumes.sum()), 9)
    (2, (0, 1), (0,), 2.0)
    """
    meshes, labels, frame, info = read_compas(path, supports, progress=progress)
    return Assembly.from_meshes(meshes, frame=frame, labels=labels, info=info)
