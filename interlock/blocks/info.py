"""``Assembly.info`` in files: plain values on the way out, the same values on the way back.

The COMPAS JSON writer (:mod:`~interlock.blocks.compas`) and the Rhino writer
(:mod:`~interlock.blocks.rhino`, a Python literal) store ``info`` as text, so
:func:`plain` turns every value into numbers, text, lists and dicts: numpy
arrays and scalars become lists and numbers, infinities and NaN become text
(neither JSON nor a literal holds them), and the contacts an assembly carries
(``info["contacts"]``, e.g. :func:`~interlock.blocks.presets.block_on_pins`)
become tagged dicts (:data:`CONTACT_TAG`) that :func:`restored` turns back
into :class:`~interlock.blocks.contact.Contact` objects.  Anything else is
stored as its text.
"""

from __future__ import annotations

import numpy as np

from interlock.blocks.contact import Contact
from interlock.files import json_float

__all__ = ["plain", "restored", "CONTACT_TAG"]

#: The key of a dict that stands for a :class:`~interlock.blocks.contact.Contact` (its ``to_dict()``).
CONTACT_TAG = "interlock.contact"


def plain(value, *, json: bool = True):
    """``value`` as numbers, text, lists and dicts (see the module docstring).

    ``json=True``: dict keys become text and tuples lists, as JSON has them.
    ``json=False`` (a Python literal): keys that are numbers stay numbers and
    tuples stay tuples.

    >>> plain({1: (np.float32(0.5), float("inf")), "a": np.arange(2)})
    {'1': [0.5, 'inf'], 'a': [0, 1]}
    >>> plain({1: (np.int64(2),)}, json=False)
    {1: (2,)}
    """
    if isinstance(value, Contact):
        return {CONTACT_TAG: plain(value.to_dict(), json=json)}
    if isinstance(value, dict):
        return {_key(k, json): plain(v, json=json) for k, v in value.items()}
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
    """``info`` as read from a file, with its stored contacts as :class:`~interlock.blocks.contact.Contact` again.

    >>> c = Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0]])
    >>> back = restored(plain({"contacts": (c,)}))
    >>> type(back["contacts"][0]).__name__, back["contacts"][0].to_dict() == c.to_dict()
    ('Contact', True)
    """
    stored = info.get("contacts")
    if isinstance(stored, (list, tuple)) and stored and all(
            isinstance(item, dict) and set(item) == {CONTACT_TAG} for item in stored):
        return {**info, "contacts": tuple(Contact.from_dict(item[CONTACT_TAG]) for item in stored)}
    return info


def _key(key, json: bool):
    if isinstance(key, np.generic):
        key = key.item()
    return str(key) if json or not isinstance(key, (int, float, bool, str)) else key
