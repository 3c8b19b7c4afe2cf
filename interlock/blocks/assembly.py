"""Assemblies: blocks as instanced meshes with labels, a frame and a neighbourhood graph."""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Sequence
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from interlock import deprecation
from interlock.blocks.repair import TJUNCTION_RTOL, consistently_wound, split_t_junctions, unmatched_edges
from interlock.errors import AssemblyError

if TYPE_CHECKING:  # networkx and shapely load where a graph or a ring is built
    import networkx as nx

__all__ = ["Assembly", "AssemblyError", "load_compas", "load_3dm", "NEIGHBOUR_RTOL", "RIGID_TOL", "KIND_DECIMALS",
           "MAX_COORDINATE"]

#: Bounding boxes closer than this (relative to the model size) count as touching.
NEIGHBOUR_RTOL = 1e-6
#: Allowed deviation of a transform's linear part from an orthogonal matrix.
RIGID_TOL = 1e-9
#: Pairs of blocks whose relative transforms agree to this many decimals (lengths over the model size)
#: are of one kind (:meth:`Assembly.pair_kinds`).
KIND_DECIMALS = 9
#: The farthest a block's vertex may lie from the origin (in model units): block volumes are cubes of lengths and
#: squared distances and booleans multiply coordinates, so beyond about 1e100 they overflow float64 (1.8e308)
#: into inf and nan; the constructor refuses such blocks with an :class:`AssemblyError`.
MAX_COORDINATE = 1e100


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
        self.meshes: tuple[trimesh.Trimesh, ...] = _checked_meshes(
            meshes, [_mesh_name(k, labels, one_mesh_per_block) for k in range(len(meshes))])
        if types.size and (types.min() < 0 or types.max() >= len(self.meshes)):
            raise AssemblyError(f"block types must index the {len(self.meshes)} meshes, "
                                f"got values {types.min()}..{types.max()}")
        transforms = np.asarray(transforms, dtype=float).reshape(-1, 4, 4)
        if len(transforms) != len(types):
            raise AssemblyError(f"got {len(types)} block types but {len(transforms)} transforms; "
                                "give one of each per block")
        _check_transforms(transforms)
        _check_reach(self.meshes, types, transforms, self.labels)
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
    def load(cls, paths, frame=None, progress=None) -> Assembly:
        """Deprecated alias of :func:`interlock.read` (``interlock.formats.read``), removed in interlock 0.3."""
        return _moved("Assembly.load", "read")(paths, frame, progress=progress)

    def with_frame(self, frame) -> Assembly:
        """The same blocks with another frame."""
        return Assembly(self.meshes, self.types, self.transforms, self.labels, frame, self.lattice,
                        self._boundary, self.info)

    @property
    def unit(self) -> str | None:
        """The length unit of the coordinates (``"mm"``, ``"m"``, ``"in"``, ...), None for a model without one.

        Kept in ``info["unit"]``, so every assembly made from this one keeps it; files state it
        (:mod:`interlock.formats.units`, ``docs/formats.md``).
        """
        unit = self.info.get("unit")
        return unit if isinstance(unit, str) else None

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

    @cached_property
    def block_sizes(self) -> np.ndarray:
        """Each block's size: the diagonal of its bounding box (the local length of its contacts' tolerances)."""
        if not len(self):
            return np.ones(0)
        sizes = np.linalg.norm(self.bounds[:, 1] - self.bounds[:, 0], axis=1)
        return np.where(sizes > 0, sizes, 1.0)

    @cached_property
    def block_size(self) -> float:
        """The typical block size: the median of :attr:`block_sizes` (a far-away block does not change it)."""
        return float(np.median(self.block_sizes)) if len(self) else 1.0

    # --- neighbourhood -----------------------------------------------------------
    @cached_property
    def neighbours(self) -> "nx.Graph":
        """Candidate contacts: blocks whose bounding boxes touch (``NEIGHBOUR_RTOL``).

        Each box is padded by ``NEIGHBOUR_RTOL`` times its own size and largest
        coordinate (its own rounding), never by a fraction of the scene: a
        block far away adds no candidates near the origin.

        Nodes are block indices with attributes ``label``, ``type``,
        ``mirrored`` and ``fixed``.  Every face-to-face contact is an edge of
        this graph; some edges (blocks touching along an edge or a corner) carry
        no face contact.  Built from a spatial index (shapely STRtree on the xy
        boxes, then the z intervals), never from all pairs.
        """
        return self.neighbour_graph(pad=self.local_padding(NEIGHBOUR_RTOL))

    def local_padding(self, rtol: float) -> np.ndarray:
        """Per block, ``rtol`` times its size plus its largest coordinate: a distance within its own precision."""
        return rtol * (self.block_sizes + np.abs(self.bounds).max(axis=(1, 2)))

    def neighbour_graph(self, rtol: float = NEIGHBOUR_RTOL, pad=None) -> "nx.Graph":
        """:attr:`neighbours` with another tolerance: ``rtol`` relative to :attr:`scale`, or ``pad`` per block.

        ``pad`` (a length, or one per block) widens each block's box by that much.
        """
        import networkx as nx
        import shapely

        graph = nx.Graph()
        fixed = set(self.frame)
        for i in range(len(self)):
            graph.add_node(i, label=self.labels[i], type=int(self.types[i]),
                           mirrored=bool(self.mirrored[i]), fixed=i in fixed)
        if len(self) < 2:
            return graph
        pad = rtol * self.scale if pad is None else np.broadcast_to(np.asarray(pad, dtype=float), (len(self),))[:, None]
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
        import shapely

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
        :data:`KIND_DECIMALS` decimals, lengths over the size of the pair's first block.

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
        shape[:, :, 3] /= self.block_sizes[i, None]  # lengths over block i's own size, not the scene's
        key = np.hstack([self.types[i, None], self.types[j, None],
                         np.round(shape.reshape(-1, 12), KIND_DECIMALS) + 0.0])
        _, first, kind_of = np.unique(key, axis=0, return_index=True, return_inverse=True)
        return first, kind_of.ravel(), relative

    def block_indices(self, values, what: str = "frame") -> tuple[int, ...]:
        """Sorted distinct block indices; a clear :class:`AssemblyError` for anything else."""
        if values is not None and (isinstance(values, (str, bytes)) or not hasattr(values, "__iter__")):
            raise AssemblyError(f"{what} must be a list of block indices (e.g. [0, 3]), got {values!r}")
        values = [] if values is None else list(values)
        out = []
        for v in values:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
                raise AssemblyError(f"{what} must list block indices (integers), got {v!r}")
            if not 0 <= v < len(self.types):
                raise AssemblyError(f"{what} index {v} is out of range for {len(self.types)} blocks")
            out.append(int(v))
        return tuple(sorted(set(out)))


def load_compas(path, supports=None, progress=None) -> Assembly:
    """Deprecated alias of :func:`interlock.formats.compas.load_compas` (or :func:`interlock.read`), removed in
    interlock 0.3."""
    return _moved("interlock.blocks.load_compas", "compas.load_compas")(path, supports, progress=progress)


def load_3dm(path, frame=None, *, frame_layer: str = "frame", progress=None) -> Assembly:
    """Deprecated alias of :func:`interlock.formats.rhino.read_3dm` (or :func:`interlock.read`), removed in
    interlock 0.3."""
    return _moved("interlock.blocks.load_3dm", "rhino.read_3dm")(path, frame, frame_layer=frame_layer,
                                                                  progress=progress)


def _moved(old: str, new: str):
    """The function ``interlock.formats.<new>`` that the deprecated ``old`` forwards to, after a
    ``DeprecationWarning`` pointing at the caller.  Files are read in :mod:`interlock.formats`, a layer above
    this one, so it is found by name on first use, as :func:`interlock.deprecation.moved` finds old paths.
    Callers inside interlock not yet moved to ``interlock.read`` are not warned (their users could do nothing
    about it)."""
    caller = sys._getframe(2).f_globals.get("__name__", "")
    if not caller.startswith("interlock."):
        warnings.warn(f"{old} moved to interlock.formats.{new}; the old path is removed in interlock "
                      f"{deprecation.REMOVED_IN}", DeprecationWarning, stacklevel=3)
    module, _, name = f"interlock.formats.{new}".rpartition(".")
    return getattr(importlib.import_module(module), name)


def _mesh_name(k: int, labels, one_mesh_per_block: bool) -> str:
    """How error messages name mesh ``k``: by its block (and label) when every block has its own mesh."""
    if not one_mesh_per_block:
        return f"mesh {k}"
    return f"block {k} ({labels[k]})" if labels is not None else f"block {k}"


def _checked_meshes(meshes, names) -> tuple[trimesh.Trimesh, ...]:
    """The meshes, outward-oriented; each must be closed: every directed edge matched by its reverse.

    Non-manifold edges (four faces meeting, as in voxel parts) are allowed, and so are
    T-junctions: meshes with unmatched edges get them split at the vertices on them
    (:func:`~interlock.blocks.repair.split_t_junctions`, :data:`~interlock.blocks.repair.TJUNCTION_RTOL`)
    before they are judged, and if that does not close them, their repeated triangles dropped and their
    winding made consistent (:func:`~interlock.blocks.repair.consistently_wound`).  All meshes are checked
    at once with numpy (edges, T-junctions, signed volumes); only meshes that need it are rebuilt.
    """
    for mesh, name in zip(meshes, names):
        if not isinstance(mesh, trimesh.Trimesh):
            raise AssemblyError(f"{name} must be a trimesh.Trimesh, got {type(mesh).__name__}")
        if len(mesh.faces) == 0 or not np.all(np.isfinite(mesh.vertices)):
            raise AssemblyError(f"{name} is empty or has non-finite vertex coordinates")
    if not meshes:
        return ()
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes])
    vertices = np.vstack([m.vertices for m in meshes]).astype(float, copy=False)
    local = np.maximum.reduceat(_reach(vertices), offsets[:-1])
    if local.max() > MAX_COORDINATE:  # before any product of coordinates overflows
        k = int(np.argmax(local))
        raise AssemblyError(f"{names[k]} reaches {local[k]:.3g} from the origin: beyond {MAX_COORDINATE:g} its "
                            "volumes and squared distances overflow float64; give the model in other units (scale "
                            "it down) or nearer the origin")
    vertex_mesh = np.repeat(np.arange(len(meshes)), np.diff(offsets))
    faces = [np.asarray(m.faces, dtype=np.int64) + o for m, o in zip(meshes, offsets)]
    open_meshes = np.unique(vertex_mesh[unmatched_edges(np.vstack(faces))[:, 0]])
    meshes = list(meshes)
    if open_meshes.size:
        split = split_t_junctions(vertices, np.vstack([faces[k] for k in open_meshes]), TJUNCTION_RTOL, vertex_mesh)
        split = split[np.argsort(vertex_mesh[split[:, 0]], kind="stable")]
        ends = np.searchsorted(vertex_mesh[split[:, 0]], open_meshes, side="right")
        still = vertex_mesh[unmatched_edges(split)[:, 0]]  # the meshes open also after the split, per edge
        still_open = set(still.tolist())
        for k, own in zip(open_meshes.tolist(), np.split(split, ends[:-1])):
            if k in still_open:  # triangles twice or wound the other way round: the same solid, once repaired
                wound = consistently_wound(meshes[k].vertices, own - offsets[k])
                if wound is None:
                    raise AssemblyError(
                        f"{names[k]} is not a closed surface ({np.count_nonzero(still == k)} edges without a "
                        "matching opposite edge, also after splitting edges at the vertices on them, dropping "
                        "repeated triangles and making the winding consistent): it has holes or loose triangles; "
                        "blocks must be closed polyhedra")
                own = wound + offsets[k]
            faces[k] = own
            meshes[k] = trimesh.Trimesh(meshes[k].vertices, own - offsets[k], process=False)
    for k in np.flatnonzero(_signed_volumes(vertices, faces, offsets) <= 0).tolist():
        with warnings.catch_warnings(), np.errstate(all="ignore"):  # trimesh divides by a flat mesh's volume 0
            warnings.simplefilter("ignore")
            volume = meshes[k].volume
        if volume < 0:
            meshes[k] = meshes[k].copy()
            meshes[k].invert()
            volume = -volume
        if not volume > 0:
            raise AssemblyError(f"{names[k]} encloses no volume")
    return tuple(meshes)


def _signed_volumes(vertices, faces, offsets) -> np.ndarray:
    """Each mesh's signed volume (positive for outward faces), about the mean of its vertices."""
    counts = np.diff(offsets)
    centres = np.add.reduceat(vertices, offsets[:-1]) / counts[:, None]  # every mesh has vertices
    face_mesh = np.repeat(np.arange(len(faces)), [len(f) for f in faces])
    corners = vertices[np.vstack(faces)] - centres[face_mesh][:, None]
    triple = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2]))
    return np.bincount(face_mesh, triple, minlength=len(faces)) / 6


def _check_transforms(transforms):
    if not np.all(np.isfinite(transforms)):
        raise AssemblyError("transforms must be finite 4x4 matrices")
    if not np.allclose(transforms[:, 3], [0, 0, 0, 1]):
        raise AssemblyError("transforms must be affine: the last row of each 4x4 matrix is (0, 0, 0, 1)")
    linear = transforms[:, :3, :3]
    err = np.abs(linear @ linear.transpose(0, 2, 1) - np.eye(3)).max(initial=0.0)
    if err > RIGID_TOL:
        raise AssemblyError("transforms must be rigid motions or mirror images (orthogonal linear part); "
                            f"deviation {err:.2e}")


def _reach(points) -> np.ndarray:
    """The distance of each point (row) from the origin, scaled by the largest coordinate so it cannot overflow."""
    points = np.asarray(points, dtype=float)
    largest = np.abs(points).max(initial=0.0)
    if not largest > 0:
        return np.zeros(len(points))
    return largest * np.sqrt(np.square(points / largest).sum(axis=1))


def _check_reach(meshes, types, transforms, labels) -> None:
    """Refuse a block with a vertex farther than :data:`MAX_COORDINATE` from the origin (the transform's translation
    plus the mesh's farthest vertex: an upper bound, exact for unrotated blocks), before anything overflows."""
    if not len(types):
        return
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes])
    local = np.maximum.reduceat(_reach(np.vstack([m.vertices for m in meshes])), offsets[:-1])
    reach = local[types] + _reach(transforms[:, :3, 3])
    if reach.max() > MAX_COORDINATE:
        k = int(np.argmax(reach))
        raise AssemblyError(f"block {k} ({labels[k]}) reaches {reach[k]:.3g} from the origin: beyond "
                            f"{MAX_COORDINATE:g} its volumes and squared distances overflow float64; give the "
                            "model in other units (scale it down) or nearer the origin")


def _checked_lattice(lattice) -> np.ndarray:
    lattice = np.array(lattice, dtype=float)
    if lattice.shape != (2, 3) or not np.all(np.isfinite(lattice)):
        raise AssemblyError(f"a periodic cell needs two finite translation vectors, shape (2, 3); got {lattice.shape}")
    if np.linalg.norm(np.cross(lattice[0], lattice[1])) <= 1e-12 * np.linalg.norm(lattice) ** 2:
        raise AssemblyError("the two lattice vectors of a periodic cell must be linearly independent")
    lattice.setflags(write=False)
    return lattice


# Deprecated: the markers of interlock's files live with the formats (interlock.formats.common); removed in 0.3.
__getattr__ = deprecation.moved(__name__, dict.fromkeys(["HEADER_MARKER", "STL_RECORD", "BLOCK_DATA"],
                                                        "interlock.formats.common"))
