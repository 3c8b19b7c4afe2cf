"""Parameter checks, rigid motions and mesh assembly shared by the presets, and their error."""

from __future__ import annotations

import math
from itertools import product
from numbers import Integral, Real

import numpy as np
import trimesh

from interlock.errors import InterlockError

__all__ = ["PresetError", "count", "finite", "positive", "grid", "translation", "turn", "split", "fan", "outward"]


class PresetError(InterlockError):
    """Parameters of a preset outside the allowed range (the message says which values are allowed)."""


def count(value, name) -> int:
    """``value`` as an int, if it is an integer >= 1 (not a bool).

    Raises
    ------
    PresetError
        Otherwise; the message names the parameter ``name``.

    Examples
    --------
    >>> count(3, "rows")
    3
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) or value < 1:
        raise PresetError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def finite(value, name) -> float:
    """``value`` as a float, if it is a finite real number (not a bool).

    Raises
    ------
    PresetError
        Otherwise; the message names the parameter ``name``.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real) or not math.isfinite(value):
        raise PresetError(f"{name} must be a finite real number, got {value!r}")
    return float(value)


def positive(value, name) -> float:
    """``value`` as a float, if it is finite and > 0.

    Raises
    ------
    PresetError
        Otherwise; the message names the parameter ``name``.

    Examples
    --------
    >>> positive(2, "size")
    2.0
    """
    value = finite(value, name)
    if value <= 0:
        raise PresetError(f"{name} must be > 0, got {value}")
    return value


def grid(rows: int, cols: int) -> tuple[list[tuple[int, int]], list[int]]:
    """Labels ``(i, j)`` of a ``rows x cols`` grid row by row, and the indices of its outer ring.

    Examples
    --------
    >>> grid(2, 3)[1]
    [0, 1, 2, 3, 4, 5]
    >>> grid(3, 3)[1]
    [0, 1, 2, 3, 5, 6, 7, 8]
    """
    labels = list(product(range(rows), range(cols)))
    return labels, [k for k, (i, j) in enumerate(labels) if i in (0, rows - 1) or j in (0, cols - 1)]


def translation(shift) -> np.ndarray:
    """The 4 x 4 homogeneous matrix of the translation by ``shift`` (three numbers)."""
    out = np.eye(4)
    out[:3, 3] = shift
    return out


def turn(quarters: int) -> np.ndarray:
    """The 4 x 4 rotation by ``quarters`` * 90 degrees about the z-axis, with exact entries.

    Examples
    --------
    >>> turn(1)[:2, :2].tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    """
    c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[quarters % 4]
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    return out


def split(quad) -> list[tuple]:
    """The two triangles ``(q0, q1, q2), (q0, q2, q3)`` of the quadrilateral ``quad`` (vertex indices)."""
    return [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]


def fan(quad, apex) -> list[tuple]:
    """The four triangles joining the edges of the quadrilateral ``quad`` to the vertex ``apex`` (indices)."""
    return [(quad[k], quad[(k + 1) % 4], apex) for k in range(4)]


def outward(vertices, faces) -> trimesh.Trimesh:
    """A closed mesh with consistent, outward winding, vertices kept in the given order.

    Parameters
    ----------
    vertices : array (n, 3) of float
    faces : array (m, 3) of int
        Triangles, wound any way; they must close up (a watertight surface).

    Returns
    -------
    trimesh.Trimesh
        Not processed (no vertex is merged or reordered), with positive volume.
    """
    mesh = trimesh.Trimesh(np.asarray(vertices, dtype=float), np.asarray(faces, dtype=int), process=False)
    trimesh.repair.fix_winding(mesh)
    if mesh.volume < 0:
        mesh.invert()
    return mesh
