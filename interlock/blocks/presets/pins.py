"""A block held by fixed pins along lines and at points: interlocked only at second order."""

from __future__ import annotations

import math

import numpy as np
import shapely
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.contact import Contact
from interlock.blocks.presets.common import PresetError, positive

__all__ = ["block_on_pins"]


def block_on_pins(h: float = 1.0, c: float = 2.0) -> Assembly:
    """A block held by fixed pins that touch it along lines and at points: interlocked only at second order.

    The block (0) is a prism along ``y`` (``|y| <= 1``) with a V-shaped
    valley on top whose faces have outward normals ``(+-1, 0, h)`` and pass
    through ``(-+1, 0, 0)``, so their normals there meet at ``O = (0, 0, h)``.
    Wedge pins (fixed) touch the valley faces along ``x = -+1, z = 0``, the
    bottom face ``z = -c`` along ``x = 0``, and the end faces ``y = -+1`` at
    ``(+-1/2, -+1, -c/2)``.  The only first-order motion is the turn about
    the line through ``O`` along ``y``; the stressed second-order form on it
    is ``2 lambda (1 - h c) / sqrt(1 + h^2)``, so the block is interlocked
    (second order) exactly when ``h c > 1`` (which is also when the valley
    stays above the bottom face).

    :func:`~interlock.verify.contacts.contacts` finds face-to-face contacts
    only, so the assembly carries the pins' contacts, made by
    :meth:`Contact.at_points <interlock.blocks.contact.Contact.at_points>`, in
    ``info["contacts"]``; :func:`~interlock.verify.check` and
    :func:`~interlock.verify.second_order.second_order` use them when no
    ``contacts=`` is given.

    Parameters
    ----------
    h : float
        Slope of the valley faces (> 0): the turning axis ``O`` lies at height ``h``.
    c : float
        Depth of the bottom face below the valley's rim (> 0), with ``h c > 1``.

    Returns
    -------
    Assembly
        Block 0 free, pins 1..7 the frame; ``info["contacts"]`` the seven
        point and line contacts (ten rows).

    Raises
    ------
    PresetError
        ``h`` or ``c`` not finite and > 0, or ``h c <= 1``.

    Examples
    --------
    >>> cup = block_on_pins(h=1.0, c=2.0)
    >>> len(cup), cup.frame, sum(len(c.vertices) for c in cup.info["contacts"])
    (8, (1, 2, 3, 4, 5, 6, 7), 10)
    """
    h, c = positive(h, "h"), positive(c, "c")
    if not h * c > 1:
        raise PresetError(f"the valley must stay above the bottom face: h c > 1, got h = {h:g}, c = {c:g}")
    top = 0.5 / h
    section = shapely.Polygon([(-2, -c), (2, -c), (2, top), (1.5, top), (0, -1 / h), (-1.5, top), (-2, top)])
    prism = trimesh.creation.extrude_polygon(section, 2.0)
    prism.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
    prism.apply_translation([0, 1, 0])
    a = math.hypot(1, h)

    def wedge(tip, direction, side, axis=(0, 1, 0), half=0.5):
        tip, d, s, ax = (np.asarray(v, dtype=float) for v in (tip, direction, side, axis))
        corners = [tip, tip + 0.3 * (d + s), tip + 0.3 * (d - s)]
        return trimesh.convex.convex_hull(np.array([x + e * half * ax for x in corners for e in (-1, 1)]))

    left, right, down = np.array([1, 0, h]) / a, np.array([-1, 0, h]) / a, np.array([0.0, 0, -1])
    pins = [wedge((-1, 0, 0), left, np.array([h, 0, -1]) / (2 * a)),
            wedge((1, 0, 0), right, np.array([h, 0, 1]) / (2 * a)), wedge((0, 0, -c), down, (0.5, 0, 0))]
    found = [Contact.at_points(0, 1, left, [[-1, -0.5, 0], [-1, 0.5, 0]]),
             Contact.at_points(0, 2, right, [[1, -0.5, 0], [1, 0.5, 0]]),
             Contact.at_points(0, 3, down, [[0, -0.5, -c], [0, 0.5, -c]])]
    for x in (-0.5, 0.5):
        for y in (-1, 1):
            point, out = np.array([x, y, -c / 2]), np.array([0, y, 0.0])
            pins.append(wedge(point, out, (0.1, 0, 0), axis=(0, 0, 1), half=0.05))
            found.append(Contact.at_points(0, len(pins), out, [point]))
    return Assembly.from_meshes([prism, *pins], frame=range(1, len(pins) + 1),
                                labels=["block"] + [f"pin {k}" for k in range(1, len(pins) + 1)],
                                info={"preset": "block_on_pins", "h": h, "c": c, "contacts": tuple(found)})
