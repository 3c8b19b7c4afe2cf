"""The infinitesimal interlocking matrix (main paper Def. 3.3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph
import scipy.spatial

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError
from interlock.verify.contacts import model_contacts

__all__ = ["InterlockingMatrix", "interlocking_matrix", "MERGE_RTOL"]

#: Rows whose entries agree to this (relative to the largest entry) are merged.
MERGE_RTOL = 1e-12


@dataclass(frozen=True, eq=False)
class InterlockingMatrix:
    """``A`` with ``A x >= 0`` for every admissible infinitesimal motion ``x`` (Def. 3.3).

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix
        One row per distinct contact-polygon vertex (per contact when
        translational); 6 columns ``(omega, t / length_scale)`` per free block,
        or 3 (``t``) when translational.
    free : ndarray of int
        The block of each column group: columns ``6k .. 6k+5`` belong to block ``free[k]``.
    centres : ndarray (len(free), 3)
        Each free block's reference point (its centroid): twists are taken about it.
    row_contact, row_vertex : ndarray of int
        For each row, the contact (index into ``contacts``) and the vertex of
        its polygon that produced it (the first, when identical rows were merged).
    length_scale : float
        Coordinates were divided by this before building rows (conditioning).
    translational : bool
    """

    matrix: sp.csr_matrix
    free: np.ndarray
    centres: np.ndarray
    row_contact: np.ndarray
    row_vertex: np.ndarray
    length_scale: float
    translational: bool

    @property
    def shape(self) -> tuple[int, int]:
        return self.matrix.shape

    @property
    def block_size(self) -> int:
        """Columns per free block: 6, or 3 when translational."""
        return 3 if self.translational else 6

    def twists(self, x) -> np.ndarray:
        """A column vector as one world-unit twist ``(omega, t)`` per free block, shape (k, 6)."""
        x = np.asarray(x, dtype=float).reshape(len(self.free), self.block_size)
        if self.translational:
            return np.hstack([np.zeros_like(x), x * self.length_scale])
        return np.hstack([x[:, :3], x[:, 3:] * self.length_scale])

    def columns(self, twists) -> np.ndarray:
        """The column vector of world-unit twists ``(omega, t)`` of the free blocks, shape (k, 6): :meth:`twists` inverted."""
        twists = np.asarray(twists, dtype=float).reshape(len(self.free), 6)
        if self.translational:
            return (twists[:, 3:] / self.length_scale).ravel()
        return np.hstack([twists[:, :3], twists[:, 3:] / self.length_scale]).ravel()


def interlocking_matrix(assembly: Assembly, frame=None, translational: bool = False,
                        contacts=None) -> InterlockingMatrix:
    """The reduced infinitesimal interlocking matrix of an assembly (Def. 3.3).

    For a contact polygon between blocks ``i`` and ``j`` with unit normal ``n``
    pointing from ``i`` to ``j`` and a vertex ``p`` of it, the row is

        ``(-(r_i x n), -n)`` in the columns of ``i``, ``((r_j x n), n)`` in those of ``j``,

    with ``r_k = (p - c_k) / L``: twists are about each block's centroid
    ``c_k`` and lengths are divided by the typical block size ``L``
    (:attr:`~interlock.blocks.Assembly.block_size`, the median, so a block far
    away does not shrink every moment arm), which changes no verdict but
    conditions the matrix (docs/interlocking.md).  ``A x >= 0`` says no
    contact vertex moves into the other block.  Frame columns are dropped and
    identical rows merged (the reduced matrix of Def. 3.3).  Translational:
    rows ``(-n)`` / ``(n)``, one per contact.

    Parameters
    ----------
    assembly : Assembly
    frame : iterable of int, optional
        Fixed blocks; defaults to ``assembly.frame``.
    translational : bool
        Only translations (``omega = 0``).
    contacts : sequence of Contact, optional
        Precomputed :func:`~interlock.verify.contacts.contacts` of the assembly.

    Examples
    --------
    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(2)]
    >>> A = interlocking_matrix(Assembly.from_meshes(cubes), frame=[0])
    >>> A.shape
    (4, 6)
    """
    if not isinstance(assembly, Assembly):
        raise InterlockError(f"expected an Assembly, got {type(assembly).__name__}")
    fixed = _frame(assembly, frame)
    found = model_contacts(assembly, contacts)
    free = np.array([b for b in range(len(assembly)) if b not in fixed], dtype=int)
    column_of = np.full(len(assembly), -1)
    column_of[free] = np.arange(len(free))
    length = assembly.block_size
    centres = assembly.centroids[free]
    size = 3 if translational else 6

    blocks_i, blocks_j, points, normals, contact_of, vertex_of = [], [], [], [], [], []
    for c, contact in enumerate(found):
        if contact.normals is not None:  # a cone of admissible normals is no row (docs/interlocking.md)
            continue
        vertices = np.asarray(contact.vertices, dtype=float)
        if translational:
            vertices = vertices[:1]
        count = len(vertices)
        blocks_i.append(np.full(count, contact.i))
        blocks_j.append(np.full(count, contact.j))
        points.append(vertices)
        normals.append(np.broadcast_to(np.asarray(contact.normal, dtype=float), (count, 3)))
        contact_of.append(np.full(count, c))
        vertex_of.append(np.arange(count))
    if not points:
        empty = sp.csr_matrix((0, size * len(free)))
        return InterlockingMatrix(empty, free, centres, np.empty(0, int), np.empty(0, int), length, translational)
    bi, bj = np.concatenate(blocks_i), np.concatenate(blocks_j)
    p, n = np.vstack(points), np.vstack(normals)
    contact_of, vertex_of = np.concatenate(contact_of), np.concatenate(vertex_of)
    keep = (column_of[bi] >= 0) | (column_of[bj] >= 0)
    bi, bj, p, n, contact_of, vertex_of = bi[keep], bj[keep], p[keep], n[keep], contact_of[keep], vertex_of[keep]

    # dense per-row entries for block i and block j (zero where the block is fixed)
    all_centroids = assembly.centroids
    def entries(blocks, sign):
        if translational:
            return sign * n
        r = (p - all_centroids[blocks]) / length
        return sign * np.hstack([np.cross(r, n), n])
    values_i, values_j = entries(bi, -1.0), entries(bj, 1.0)
    col_i, col_j = column_of[bi], column_of[bj]
    values_i[col_i < 0] = 0.0
    values_j[col_j < 0] = 0.0

    first = _distinct_rows(col_i, col_j, values_i, values_j)
    values_i, values_j, col_i, col_j = values_i[first], values_j[first], col_i[first], col_j[first]

    rows = np.arange(len(first))
    offsets = np.arange(size)
    data, r_idx, c_idx = [], [], []
    for values, cols in ((values_i, col_i), (values_j, col_j)):
        on = cols >= 0
        data.append(values[on].ravel())
        r_idx.append(np.repeat(rows[on], size))
        c_idx.append((size * cols[on][:, None] + offsets).ravel())
    matrix = sp.csr_matrix((np.concatenate(data), (np.concatenate(r_idx), np.concatenate(c_idx))),
                           shape=(len(first), size * len(free)))
    matrix.eliminate_zeros()
    return InterlockingMatrix(matrix, free, centres, contact_of[first], vertex_of[first], length, translational)


def _distinct_rows(col_i, col_j, values_i, values_j) -> np.ndarray:
    """Index of the first row of each class of identical rows (entries within ``MERGE_RTOL``).

    Rows are points in R^12 (their two blocks' entries), grouped by their
    column pair; rows closer than the tolerance are joined (k-d tree pairs,
    then connected components), which unlike rounding to a grid does not
    depend on where the rounding boundaries fall.
    """
    values = np.hstack([values_i, values_j])
    scale = np.abs(values).max(initial=0.0) or 1.0
    spread = 4.0 * scale * values.shape[1]  # farther apart than any two rows of one column pair
    points = np.hstack([values, spread * np.column_stack([col_i, col_j])])
    pairs = scipy.spatial.cKDTree(points).query_pairs(MERGE_RTOL * scale, output_type="ndarray")
    count = len(points)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(count, count))
    _, label = scipy.sparse.csgraph.connected_components(graph, directed=False)
    first = np.full(label.max(initial=-1) + 1, count)
    np.minimum.at(first, label, np.arange(count))
    return np.sort(first)


def _frame(assembly: Assembly, frame) -> set[int]:
    if frame is None:
        return set(assembly.frame)
    return set(assembly.block_indices(frame, "frame"))
