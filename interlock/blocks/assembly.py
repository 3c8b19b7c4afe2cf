"""Assemblies: blocks as instanced meshes with labels, a frame and a neighbourhood graph."""

from __future__ import annotations

import re
from collections.abc import Sequence
from functools import cached_property
from pathlib import Path

import networkx as nx
import numpy as np
import shapely
import trimesh

from interlock.errors import InterlockError

__all__ = ["Assembly", "AssemblyError", "NEIGHBOUR_RTOL", "RIGID_TOL", "KIND_DECIMALS", "HEADER_MARKER", "STL_RECORD",
           "BLOCK_DATA"]

#: Bounding boxes closer than this (relative to the model size) count as touching.
NEIGHBOUR_RTOL = 1e-6
#: Allowed deviation of a transform's linear part from an orthogonal matrix.
RIGID_TOL = 1e-9
#: Pairs of blocks whose relative transforms agree to this many decimals (lengths over the model size)
#: are of one kind (:meth:`Assembly.pair_kinds`).
KIND_DECIMALS = 9
#: How an exported file says that it stores a block index per triangle, and how many blocks: the start of
#: a binary STL's 80-byte header, or a PLY comment (``interlock blocks=12`` for 12 blocks).
HEADER_MARKER = b"interlock blocks="
#: One triangle of a binary STL: normal, three vertices, and the 2-byte attribute holding the block index.
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("block", "<u2")])
#: Name of the per-triangle block index in PLY (face property), VTU and XDMF (cell data) files.
BLOCK_DATA = "block"


class AssemblyError(InterlockError):
    """Meshes, transforms, labels or a frame that do not form an assembly."""


class Assembly:
    """A set of rigid blocks, each an instance of a shared mesh under a 4x4 transform.

    Block ``i`` is ``meshes[types[i]]`` moved by ``transforms[i]`` (a rotation
    or, for mirror-image blocks, an improper orthogonal matrix, plus a
    translation).  Sharing one mesh per block type keeps large patches cheap.

    Parameters
    ----------
    meshes : sequence of trimesh.Trimesh
        The block types; each must be closed (watertight) with positive volume.
    types : sequence of int
        For each block, the index of its mesh.
    transforms : array (n, 4, 4)
        For each block, the placement of its mesh.
    labels : sequence, optional
        One hashable label per block (group element, tiling cell, file name);
        defaults to ``0 .. n-1``.
    frame : iterable of int, optional
        Indices of the fixed blocks.
    lattice : array (2, 3), optional
        For a periodic cell: the two translation vectors that repeat it.
    boundary : iterable of int, optional
        Indices of the outer ring, when the constructor knows it (patches);
        otherwise :meth:`boundary` uses the convex hull.
    info : dict, optional
        Free-form provenance (group, deformation, preset name), kept as is.

    Examples
    --------
    >>> cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)]
    >>> a = Assembly.from_meshes(cubes, frame=[0, 2])
    >>> len(a), a.frame, sorted(a.neighbours.edges)
    (3, (0, 2), [(0, 1), (1, 2)])
    """

    def __init__(self, meshes, types, transforms, labels=None, frame=(), lattice=None, boundary=None, info=None):
        meshes = list(meshes)
        types = np.asarray(types, dtype=int).reshape(-1)
        self.labels: tuple = tuple(range(len(types))) if labels is None else tuple(labels)
        if len(self.labels) != len(types):
            raise AssemblyError(f"got {len(self.labels)} labels for {len(types)} blocks")
        one_mesh_per_block = len(meshes) == len(types) and bool(np.array_equal(types, np.arange(len(types))))
        self.meshes: tuple[trimesh.Trimesh, ...] = tuple(
            _checked_mesh(m, _mesh_name(k, labels, one_mesh_per_block)) for k, m in enumerate(meshes))
        if types.size and (types.min() < 0 or types.max() >= len(self.meshes)):
            raise AssemblyError(f"block types must index the {len(self.meshes)} meshes, got values {types.min()}..{types.max()}")
        transforms = np.asarray(transforms, dtype=float).reshape(-1, 4, 4)
        if len(transforms) != len(types):
            raise AssemblyError(f"got {len(types)} block types but {len(transforms)} transforms; give one of each per block")
        _check_transforms(transforms)
        types.setflags(write=False)
        transforms.setflags(write=False)
        self.types = types
        self.transforms = transforms
        self.frame: tuple[int, ...] = self.block_indices(frame, "frame")
        self.lattice = None if lattice is None else _checked_lattice(lattice)
        self._boundary = None if boundary is None else self.block_indices(boundary, "boundary")
        self.info = dict(info or {})

    # --- constructors ----------------------------------------------------------
    @classmethod
    def from_meshes(cls, meshes: Sequence[trimesh.Trimesh], frame=(), labels=None, info=None) -> Assembly:
        """One block per closed mesh, placed where it is (identity transforms)."""
        meshes = list(meshes)
        return cls(meshes, range(len(meshes)), np.tile(np.eye(4), (len(meshes), 1, 1)), labels, frame, info=info)

    @classmethod
    def load(cls, paths, frame=()) -> Assembly:
        """Blocks from mesh files (OBJ, STL, PLY, GLB, 3MF, ... through trimesh; VTU, XDMF through meshio).

        ``paths`` is a sequence of files, one block each (labels: file names),
        or one file holding every block.  In one file the blocks are, in this order of preference:

        - the stored block indices of :func:`~interlock.gallery.export.export` files: the
          triangle attribute of a binary STL with :data:`HEADER_MARKER` in its header,
          the face property :data:`BLOCK_DATA` of a PLY file with an
          ``interlock blocks=N`` comment, the cell data :data:`BLOCK_DATA` of VTU and XDMF;
        - its objects: OBJ ``o`` statements, GLB/3MF scene nodes (node transforms
          applied), in file order for OBJ and by name (digits as numbers) otherwise;
        - else its connected bodies.

        Bodies that touch cannot be told apart in a single plain STL or PLY file;
        that is an error asking for one file per block or an OBJ with objects.
        Polygonal faces are triangulated.
        """
        if isinstance(paths, (str, Path)) and Path(paths).suffix.lower() == ".json":  # COMPAS; frame: node keys
            from interlock.blocks.compas import load_compas
            return load_compas(paths, supports=list(frame or ()) or None)
        if isinstance(paths, (str, Path)):
            path = Path(paths)
            bodies = _load_bodies(path)
            labels = [f"{path.name}:{name}" for name, _ in bodies]
            return cls.from_meshes([m for _, m in bodies], frame=frame, labels=labels, info={"source": [str(path)]})
        paths = [Path(p) for p in paths]
        if not paths:
            raise AssemblyError("no mesh files given; pass one path or a list of paths")
        meshes = [trimesh.util.concatenate([m for _, m in _load_bodies(p, split=False)]) for p in paths]
        return cls.from_meshes(meshes, frame=frame, labels=[p.name for p in paths],
                               info={"source": [str(p) for p in paths]})

    def with_frame(self, frame) -> Assembly:
        """The same blocks with another frame."""
        return Assembly(self.meshes, self.types, self.transforms, self.labels, frame, self.lattice,
                        self._boundary, self.info)

    # --- per-block data ----------------------------------------------------------
    def __len__(self) -> int:
        return len(self.types)

    def __repr__(self) -> str:
        kind = "periodic cell" if self.lattice is not None else "assembly"
        return f"<{kind}: {len(self)} blocks of {len(self.meshes)} type(s), frame {len(self.frame)}>"

    def mesh(self, i: int) -> trimesh.Trimesh:
        """Block ``i`` as a new mesh in world coordinates (outward-oriented, also when mirrored)."""
        if not -len(self) <= i < len(self):
            raise AssemblyError(f"block index {i} is out of range for {len(self)} blocks")
        return self.meshes[self.types[i]].copy().apply_transform(self.transforms[i])

    def world_meshes(self) -> list[trimesh.Trimesh]:
        """Every block as a mesh in world coordinates."""
        return [self.mesh(i) for i in range(len(self))]

    @cached_property
    def mirrored(self) -> np.ndarray:
        """Whether each block is a mirror image of its mesh (transform with determinant -1)."""
        return np.linalg.det(self.transforms[:, :3, :3]) < 0

    @cached_property
    def centroids(self) -> np.ndarray:
        """Centres of mass in world coordinates, shape (n, 3)."""
        centres = np.array([m.center_mass for m in self.meshes]).reshape(-1, 3)[self.types]
        return np.einsum("nij,nj->ni", self.transforms[:, :3, :3], centres) + self.transforms[:, :3, 3]

    @cached_property
    def volumes(self) -> np.ndarray:
        return np.array([m.volume for m in self.meshes])[self.types]

    @cached_property
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounding box of each block, shape (n, 2, 3)."""
        out = np.empty((len(self), 2, 3))
        for t, mesh in enumerate(self.meshes):
            idx = np.flatnonzero(self.types == t)
            if idx.size:
                world = np.einsum("nij,vj->nvi", self.transforms[idx, :3, :3], mesh.vertices)
                world += self.transforms[idx, None, :3, 3]
                out[idx, 0], out[idx, 1] = world.min(axis=1), world.max(axis=1)
        return out

    @cached_property
    def scale(self) -> float:
        """The model size: diagonal of the bounding box of all blocks (for relative tolerances)."""
        if not len(self):
            return 1.0
        lo, hi = self.bounds[:, 0].min(axis=0), self.bounds[:, 1].max(axis=0)
        return float(np.linalg.norm(hi - lo)) or 1.0

    # --- neighbourhood -----------------------------------------------------------
    @cached_property
    def neighbours(self) -> nx.Graph:
        """Candidate contacts: blocks whose bounding boxes touch (``NEIGHBOUR_RTOL``).

        Nodes are block indices with attributes ``label``, ``type``,
        ``mirrored`` and ``fixed``.  Every face-to-face contact is an edge of
        this graph; some edges (blocks touching along an edge or a corner) carry
        no face contact.  Built from a spatial index (shapely STRtree on the xy
        boxes, then the z intervals), never from all pairs.
        """
        return self.neighbour_graph(NEIGHBOUR_RTOL)

    def neighbour_graph(self, rtol: float = NEIGHBOUR_RTOL) -> nx.Graph:
        """:attr:`neighbours` with another tolerance (relative to :attr:`scale`)."""
        graph = nx.Graph()
        fixed = set(self.frame)
        for i in range(len(self)):
            graph.add_node(i, label=self.labels[i], type=int(self.types[i]),
                           mirrored=bool(self.mirrored[i]), fixed=i in fixed)
        if len(self) < 2:
            return graph
        pad = rtol * self.scale
        lo, hi = self.bounds[:, 0] - pad, self.bounds[:, 1] + pad
        boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
        left, right = shapely.STRtree(boxes).query(boxes, predicate="intersects")
        keep = left < right
        left, right = left[keep], right[keep]
        keep = (lo[left, 2] <= hi[right, 2]) & (lo[right, 2] <= hi[left, 2])
        graph.add_edges_from(zip(left[keep].tolist(), right[keep].tolist()))
        return graph

    def boundary(self) -> tuple[int, ...]:
        """Indices of the blocks on the outer ring: the natural frame (main paper Cor. 4.8).

        For a patch of a generated assembly these are the blocks with a
        neighbour across an edge of their tile that is missing from the patch.
        For other assemblies, seen as a layer: the blocks with a vertex on the
        boundary of the convex hull of all vertices projected onto the layer's
        plane (the lattice plane, or else the plane of the two largest
        principal axes).
        """
        if self._boundary is not None:
            return self._boundary
        if len(self) < 3:
            return tuple(range(len(self)))
        meshes = self.world_meshes()
        points = np.vstack([m.vertices for m in meshes])
        if self.lattice is not None:
            plane = np.linalg.qr(self.lattice.T)[0].T
        else:
            centred = points - points.mean(axis=0)
            plane = np.linalg.svd(centred, full_matrices=False)[2][:2]
        ring = shapely.MultiPoint(points @ plane.T).convex_hull.exterior
        tol = 1e-9 * self.scale
        return tuple(i for i, m in enumerate(meshes)
                     if (shapely.distance(shapely.points(m.vertices @ plane.T), ring) <= tol).any())

    def pair_kinds(self, pairs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Group block pairs by kind: their two block types and relative transform ``T_i^-1 T_j``.

        Anything computed from the two meshes in each other's frame (contacts,
        overlaps) depends only on the kind, so instanced patches need one
        computation per kind.  Transforms are compared to
        :data:`KIND_DECIMALS` decimals, lengths over the model size.

        Returns
        -------
        first : ndarray of int
            Index (into ``pairs``) of one representative pair per kind.
        kind_of : ndarray of int
            The kind of every pair.
        relative : ndarray (len(pairs), 4, 4)
            ``T_i^-1 T_j`` of every pair.
        """
        pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
        i, j = pairs.T
        relative = np.linalg.inv(self.transforms[i]) @ self.transforms[j]
        shape = relative[:, :3].copy()
        shape[:, :, 3] /= self.scale
        key = np.hstack([self.types[i, None], self.types[j, None],
                         np.round(shape.reshape(-1, 12), KIND_DECIMALS) + 0.0])
        _, first, kind_of = np.unique(key, axis=0, return_index=True, return_inverse=True)
        return first, kind_of.ravel(), relative

    def block_indices(self, values, what: str = "frame") -> tuple[int, ...]:
        """Sorted distinct block indices; a clear :class:`AssemblyError` for anything else."""
        values = [] if values is None else list(values)
        out = []
        for v in values:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
                raise AssemblyError(f"{what} must list block indices (integers), got {v!r}")
            if not 0 <= v < len(self.types):
                raise AssemblyError(f"{what} index {v} is out of range for {len(self.types)} blocks")
            out.append(int(v))
        return tuple(sorted(set(out)))


def _mesh_name(k: int, labels, one_mesh_per_block: bool) -> str:
    """How error messages name mesh ``k``: by its block (and label) when every block has its own mesh."""
    if not one_mesh_per_block:
        return f"mesh {k}"
    return f"block {k} ({labels[k]})" if labels is not None else f"block {k}"


def _checked_mesh(mesh, name) -> trimesh.Trimesh:
    """The mesh, outward-oriented; it must be closed: every directed edge matched by its reverse.

    Non-manifold edges (four faces meeting, as in voxel parts) are allowed.
    """
    if not isinstance(mesh, trimesh.Trimesh):
        raise AssemblyError(f"{name} must be a trimesh.Trimesh, got {type(mesh).__name__}")
    if len(mesh.faces) == 0 or not np.all(np.isfinite(mesh.vertices)):
        raise AssemblyError(f"{name} is empty or has non-finite vertex coordinates")
    if not mesh.is_watertight:
        directed = mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        edges, counts = np.unique(directed, axis=0, return_counts=True)
        count_of = dict(zip(map(tuple, edges.tolist()), counts.tolist()))
        unmatched = sum(1 for (a, b), k in count_of.items() if count_of.get((b, a), 0) != k)
        if unmatched:
            raise AssemblyError(f"{name} is not a closed, consistently oriented surface ({unmatched} edges without "
                                "a matching opposite edge); blocks must be closed polyhedra")
    if mesh.volume < 0:
        mesh = mesh.copy()
        mesh.invert()
    if not mesh.volume > 0:
        raise AssemblyError(f"{name} encloses no volume")
    return mesh


def _check_transforms(transforms):
    if not np.all(np.isfinite(transforms)):
        raise AssemblyError("transforms must be finite 4x4 matrices")
    if not np.allclose(transforms[:, 3], [0, 0, 0, 1]):
        raise AssemblyError("transforms must be affine: the last row of each 4x4 matrix is (0, 0, 0, 1)")
    linear = transforms[:, :3, :3]
    err = np.abs(linear @ linear.transpose(0, 2, 1) - np.eye(3)).max(initial=0.0)
    if err > RIGID_TOL:
        raise AssemblyError(f"transforms must be rigid motions or mirror images (orthogonal linear part); deviation {err:.2e}")


def _checked_lattice(lattice) -> np.ndarray:
    lattice = np.array(lattice, dtype=float)
    if lattice.shape != (2, 3) or not np.all(np.isfinite(lattice)):
        raise AssemblyError(f"a periodic cell needs two finite translation vectors, shape (2, 3); got {lattice.shape}")
    if np.linalg.norm(np.cross(lattice[0], lattice[1])) <= 1e-12 * np.linalg.norm(lattice) ** 2:
        raise AssemblyError("the two lattice vectors of a periodic cell must be linearly independent")
    lattice.setflags(write=False)
    return lattice


def _load_bodies(path: Path, split: bool = True) -> list[tuple[str, trimesh.Trimesh]]:
    """(name, mesh in file coordinates) for every block of a mesh file, in file order.

    Stored block indices win (:func:`_indexed_blocks`), then the file's objects.
    With ``split``, a file holding one object is split into its connected bodies;
    without, the file is to be one block, so several stored blocks are refused.
    """
    if not path.is_file():
        raise AssemblyError(f"mesh file {path} does not exist")
    try:
        blocks = _indexed_blocks(path)
        bodies = _scene_objects(path) if blocks is None else blocks
    except AssemblyError:
        raise
    except Exception as error:  # the readers raise many types for unreadable files
        raise AssemblyError(f"cannot read {path} as a mesh ({type(error).__name__}: {error})") from None
    if not bodies:
        raise AssemblyError(f"{path} holds no triangle mesh")
    if not split and blocks is not None and len(blocks) > 1:
        raise AssemblyError(f"{path} holds {len(blocks)} blocks, which would merge into one in a list of "
                            f"one file per block; load it on its own: Assembly.load({str(path)!r})")
    if split and blocks is None and len(bodies) == 1:
        parts = bodies[0][1].split(only_watertight=False)
        if len(parts) > 1:
            if not all(part.is_watertight for part in parts):
                raise AssemblyError(f"{path} holds several bodies that touch, which a single {path.suffix} file cannot "
                                    "separate; give one file per block, or an OBJ file with one object ('o') per block")
            bodies = [(f"body{k}", part) for k, part in enumerate(parts)]
    return bodies


def _scene_objects(path: Path) -> list[tuple[str, trimesh.Trimesh]]:
    """One mesh per object (OBJ ``o``) or scene node (GLB, 3MF), node transform applied, named by the node."""
    obj = path.suffix.lower() == ".obj"
    scene = trimesh.load_scene(path, **({"split_objects": True, "group_material": False} if obj else {}))
    bodies = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if isinstance(geometry, trimesh.Trimesh) and len(geometry.faces):
            body = geometry.copy().apply_transform(transform)  # a reflection also flips the faces
            body.merge_vertices(merge_tex=True, merge_norm=True)  # per-face normals must not split corners
            bodies.append((str(node), body))
    if obj and len(bodies) > 1:
        order = [line.split(maxsplit=1)[1].strip() for line in path.read_text(errors="replace").splitlines()
                 if line.startswith("o ") and len(line.split(maxsplit=1)) == 2]
        bodies.sort(key=lambda body: order.index(body[0]) if body[0] in order else len(order))
    elif len(bodies) > 1:
        bodies.sort(key=lambda body: _natural_key(body[0]))
    return bodies


def _natural_key(name: str) -> tuple:
    """Sort key reading runs of digits as numbers: ``block_9`` before ``block_10``."""
    return tuple((0, int(part), "") if part.isdigit() else (1, 0, part) for part in re.split(r"(\d+)", name))


def _indexed_blocks(path: Path) -> list[tuple[str, trimesh.Trimesh]] | None:
    """The blocks of a file that stores a block index per triangle; None if it does not.

    Binary STL with :data:`HEADER_MARKER` (the triangle attribute), PLY with an
    ``interlock blocks=N`` comment (the face property :data:`BLOCK_DATA`), VTU
    and XDMF (cell data :data:`BLOCK_DATA`, required).  Block ``k`` is named
    ``block_k`` (four digits at least).
    """
    reader = {".stl": _stl_triangles, ".ply": _ply_triangles, ".vtu": _meshio_triangles,
              ".xdmf": _meshio_triangles}.get(path.suffix.lower())
    triangles = None if reader is None else reader(path)
    return None if triangles is None else _split_by_block(path, *triangles)


def _stl_triangles(path: Path):
    """Vertices, faces, block per face and block count of a marked binary STL; None if unmarked."""
    with open(path, "rb") as file:
        header = file.read(80)
        if not header.startswith(HEADER_MARKER):
            return None
        count = int.from_bytes(file.read(4), "little")
        data = file.read()
    if len(data) != count * STL_RECORD.itemsize:
        raise AssemblyError(f"{path} is cut short or padded: its header announces {count} triangles "
                            f"({count * STL_RECORD.itemsize} bytes), it holds {len(data)} bytes")
    records = np.frombuffer(data, dtype=STL_RECORD)
    vertices = records["vertices"].reshape(-1, 3).astype(float)
    return vertices, np.arange(len(vertices)).reshape(-1, 3), records["block"], _block_count(header, path)


def _ply_triangles(path: Path):
    """Vertices, faces, block per face and block count of a PLY with an interlock comment; None without."""
    with open(path, "rb") as file:
        header = file.read(4096).split(b"end_header", 1)[0]
        marker = re.search(rb"^comment (" + re.escape(HEADER_MARKER) + rb".*)$", header, re.MULTILINE)
        if marker is None:
            return None
        file.seek(0)
        loaded = trimesh.exchange.ply.load_ply(file)
    properties = loaded["metadata"]["_ply_raw"]["face"]["data"]  # every face property as read, by name
    names = properties.dtype.names if isinstance(properties, np.ndarray) else tuple(properties)
    if BLOCK_DATA not in (names or ()):
        raise AssemblyError(f"{path} says it holds interlock blocks but has no face property {BLOCK_DATA!r}")
    return loaded["vertices"], loaded["faces"], properties[BLOCK_DATA], _block_count(marker.group(1), path)


def _meshio_triangles(path: Path):
    """Vertices, triangles and cell data :data:`BLOCK_DATA` of a VTU or XDMF file (meshio)."""
    import meshio  # here, not above: it takes a tenth of a second to import, and few files need it

    mesh = meshio.read(path)
    kept = [k for k, cells in enumerate(mesh.cells) if cells.type == "triangle"]
    if BLOCK_DATA not in mesh.cell_data or not kept:
        raise AssemblyError(f"{path} has no triangles with cell data {BLOCK_DATA!r} telling the blocks apart; "
                            "write it with interlock.gallery.export, or give one mesh file per block")
    faces = np.vstack([mesh.cells[k].data for k in kept])
    blocks = np.concatenate([np.ravel(mesh.cell_data[BLOCK_DATA][k]) for k in kept])
    return mesh.points[:, :3], faces, blocks, None


def _block_count(marker: bytes, path: Path) -> int:
    """N from ``interlock blocks=N``."""
    digits = re.match(rb"\d+", marker[len(HEADER_MARKER):])
    if digits is None:
        raise AssemblyError(f"{path} says it holds interlock blocks but not how many ({marker[:40]!r})")
    return int(digits.group())


def _split_by_block(path: Path, vertices, faces, blocks, count) -> list[tuple[str, trimesh.Trimesh]]:
    """One mesh per block index (merged vertices), in index order; ``count`` blocks if given."""
    blocks = np.asarray(blocks).astype(np.int64).ravel()
    if len(blocks) != len(faces):
        raise AssemblyError(f"{path} gives {len(blocks)} block indices for {len(faces)} triangles")
    order = np.argsort(blocks, kind="stable")
    indices, starts = np.unique(blocks[order], return_index=True)
    if count is not None and not np.array_equal(indices, np.arange(count)):
        found = f"{indices[0]}..{indices[-1]}" if len(indices) else "none"
        raise AssemblyError(f"{path} announces {count} blocks 0..{count - 1} but its triangles carry "
                            f"{len(indices)} distinct block indices ({found})")
    bodies = []
    for index, own in zip(indices.tolist(), np.split(order, starts[1:])):
        used, local = np.unique(faces[own], return_inverse=True)
        body = trimesh.Trimesh(vertices[used], local.reshape(-1, 3), process=False)
        body.merge_vertices()
        bodies.append((f"block_{index:04d}", body))
    return bodies
