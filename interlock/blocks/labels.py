"""Block labels in files: a kind and a text on the way out, the same label on the way back.

An :class:`~interlock.blocks.Assembly` labels its blocks with group elements
(Escher blocks), lozenges (RhomBlocks), integer tuples (lattice cells), tuples
such as ``("voussoir", 3)`` (arches), integers or text.  Files hold text, so
every writer of :mod:`interlock.formats` that keeps labels (Rhino ``.3dm`` user strings, COMPAS JSON node
attributes, OBJ comments, GLB node and scene extras, 3MF metadata) stores the pair
``(kind, text)`` of :func:`label_text`, and the readers rebuild the label with
:func:`label_from_text`:

- ``element``: a :class:`~interlock.wallpaper.elements.GroupElement`, as its symop (``-y+1/2,x``);
- ``lozenge``: a :class:`~interlock.blocks.lozenge.Lozenge`, as ``i,j,orientation``;
- ``integers``: a tuple of integers, as ``2,-1,0``;
- ``int``: an integer, as ``7``;
- ``str``: text, as itself;
- ``json``: a float, or a tuple of numbers, text and such tuples, as JSON (tuples as lists);
- ``text``: anything else, as ``str(label)``; it is read back as that text.

Examples
--------
>>> label_text(("voussoir", 3))
('json', '["voussoir", 3]')
>>> label_from_text(*label_text(("voussoir", 3)))
('voussoir', 3)
>>> label_from_text(*label_text((2, -1, 0)))
(2, -1, 0)
"""

from __future__ import annotations

import json
from numbers import Integral, Real

from interlock.blocks.lozenge import Lozenge
from interlock.wallpaper.elements import GroupElement, parse_symop

__all__ = ["LABEL_KINDS", "label_text", "label_from_text"]

#: The kinds :func:`label_text` gives, in the order it tries them.
LABEL_KINDS = ("element", "lozenge", "integers", "int", "str", "json", "text")


def label_text(label) -> tuple[str, str]:
    """``(kind, text)`` from which :func:`label_from_text` rebuilds ``label`` (the module's table)."""
    if isinstance(label, GroupElement):
        return "element", str(label)
    if isinstance(label, Lozenge):
        return "lozenge", f"{label.i},{label.j},{label.orientation}"
    if isinstance(label, tuple) and all(_integer(v) for v in label):
        return "integers", ",".join(str(int(v)) for v in label)
    if _integer(label):
        return "int", str(int(label))
    if isinstance(label, str):
        return "str", label
    if isinstance(label, (tuple, Real)) and _plain(label):
        return "json", json.dumps(_as_lists(label))
    return "text", str(label)


def label_from_text(kind: str, text: str):
    """The label that :func:`label_text` stored as ``(kind, text)``; the text itself for kind ``text``, an
    unknown kind, or a text that does not parse as its kind (a file edited by hand)."""
    try:
        if kind == "element":
            return parse_symop(text)
        if kind == "lozenge":
            return Lozenge(*(int(v) for v in text.split(",")))
        if kind == "integers":
            return tuple(int(v) for v in text.split(",")) if text else ()
        if kind == "int":
            return int(text)
        if kind == "json":
            value = json.loads(text)
            return _as_tuples(value) if isinstance(value, (list, float)) else text
    except (ValueError, TypeError):
        return text
    return text


def _integer(value) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool)


def _plain(value) -> bool:
    """Whether ``value`` is text, a finite number or a tuple of such, all the way down (JSON keeps it)."""
    if isinstance(value, tuple):
        return all(_plain(v) for v in value)
    if isinstance(value, bool):
        return False
    return isinstance(value, (str, Integral)) or (isinstance(value, Real) and float(value) == float(value)
                                                  and abs(float(value)) != float("inf"))


def _as_lists(value):
    if isinstance(value, tuple):
        return [_as_lists(v) for v in value]
    return int(value) if _integer(value) else float(value) if isinstance(value, Real) else value


def _as_tuples(value):
    return tuple(_as_tuples(v) for v in value) if isinstance(value, list) else value
