"""``Assembly.info`` in files: plain values on the way out, the same values on the way back.

The writers of :mod:`interlock.formats` (COMPAS JSON, OBJ, PLY, GLB and 3MF as JSON; Rhino ``.3dm`` as a
Python literal) store ``info`` as text, so
:func:`plain` turns every value into numbers, text, lists and dicts: numpy
arrays and scalars become lists and numbers, infinities and NaN become text
(neither JSON nor a literal holds them), and the contacts an assembly carries
(``info["contacts"]``, e.g. :func:`~interlock.blocks.presets.block_on_pins`)
become tagged dicts (:data:`CONTACT_TAG`) that :func:`restored` turns back
into :class:`~interlock.blocks.contact.Contact` objects.  In JSON, whose keys
are text, a dict with other keys (an Escher block's ``deformation``, keyed by
edge number) is stored as its ``[key, value]`` pairs under :data:`ITEMS_TAG`,
so its keys come back as they were.  Anything else is stored as its text.
"""

from __future__ import annotations

import numpy as np

from interlock.blocks.contact import Contact
from interlock.files import json_float

__all__ = ["plain", "restored", "CONTACT_TAG", "ITEMS_TAG"]

#: The key of a dict that stands for a :class:`~interlock.blocks.contact.Contact` (its ``to_dict()``).
CONTACT_TAG = "interlock.contact"
#: The key of a dict that stands for a dict with keys other than text, as ``[key, value]`` pairs (JSON only).
ITEMS_TAG = "interlock.items"


def plain(value, *, json: bool = True):
    """``value`` as numbers, text, lists and dicts (see the module docstring).

    ``json=True``: tuples become lists, and a dict whose keys are not all
    text becomes ``{ITEMS_TAG: [[key, value], ...]}``, as JSON has only text
    keys.  ``json=False`` (a Python literal): keys and tuples stay as they are.

    >>> plain({"a": (np.float32(0.5), float("inf")), "b": np.arange(2)})
    {'a': [0.5, 'inf'], 'b': [0, 1]}
    >>> plain({1: [2]}), plain({1: (np.int64(2),)}, json=False)
    ({'interlock.items': [[1, [2]]]}, {1: (2,)})
    """
    if isinstance(value, Contact):
        return {CONTACT_TAG: plain(value.to_dict(), json=json)}
    if isinstance(value, dict):
        keys = [_key(k) for k in value]
        if json and not all(isinstance(k, str) for k in keys):
            return {ITEMS_TAG: [[plain(k, json=True), plain(v, json=True)] for k, v in zip(keys, value.values())]}
        return {k: plain(v, json=json) for k, v in zip(keys, value.values())}
    if isinstance(value, (list, tuple)):
        items = [plain(v, json=json) for v in value]
        return items if json or isinstance(value, list) else tuple(items)
    if isinstance(value, np.ndarray):
        return plain(value.tolist(), json=json)
    if isinstance(value, np.generic):
        return plain(value.item(), json=json)
    if isinstance(value, float):
        return json_float(value)
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


def restored(info: dict) -> dict:
    """``info`` as read from a file: stored contacts as :class:`~interlock.blocks.contact.Contact` again (the
    ``contacts`` entry as a tuple), dicts stored as pairs (:data:`ITEMS_TAG`) with their keys again.

    >>> c = Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0]])
    >>> back = restored(plain({"contacts": (c,), "deformation": {0: [[0.25, 0.1]]}}))
    >>> type(back["contacts"][0]).__name__, back["contacts"][0].to_dict() == c.to_dict(), back["deformation"]
    ('Contact', True, {0: [[0.25, 0.1]]})
    """
    back = _restored(info)
    if isinstance(back.get("contacts"), list) and back["contacts"] and all(
            isinstance(c, Contact) for c in back["contacts"]):
        back["contacts"] = tuple(back["contacts"])
    return back


def _restored(value):
    if isinstance(value, dict):
        if set(value) == {CONTACT_TAG} and isinstance(value[CONTACT_TAG], dict):
            return Contact.from_dict(value[CONTACT_TAG])
        if set(value) == {ITEMS_TAG} and isinstance(value[ITEMS_TAG], list) and all(
                isinstance(pair, list) and len(pair) == 2 for pair in value[ITEMS_TAG]):
            return {_hashable(k): _restored(v) for k, v in value[ITEMS_TAG]}
        return {k: _restored(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_restored(v) for v in value]
    if isinstance(value, tuple):
        return tuple(_restored(v) for v in value)
    return value


def _hashable(key):
    """A key read back from JSON: a list (a tuple key) becomes a tuple again."""
    return tuple(_hashable(k) for k in key) if isinstance(key, list) else key


def _key(key):
    if isinstance(key, np.generic):
        key = key.item()
    if isinstance(key, tuple):
        return tuple(_key(k) for k in key)
    return key if key is None or isinstance(key, (int, float, bool, str)) else str(key)
