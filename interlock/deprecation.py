"""Old import paths kept for one release: module attributes that warn, then forward to the names' new home."""

from __future__ import annotations

import importlib
import warnings

__all__ = ["moved", "REMOVED_IN"]

#: The release that drops the old paths.
REMOVED_IN = "0.3"


def moved(old: str, homes: dict[str, str]):
    """A module ``__getattr__`` for ``old``, whose names ``homes`` now live in other modules (PEP 562).

    Each access to ``old.name`` (also ``from old import name``) warns with a
    ``DeprecationWarning`` pointing at the caller's line, then returns
    ``name`` from the module ``homes[name]``.  The new module is imported on
    first use only, so a deprecated path costs nothing until it is used.

    Examples
    --------
    >>> import warnings
    >>> __getattr__ = moved("old.place", {"sqrt": "math"})
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     root = __getattr__("sqrt")(4.0)
    >>> root, str(caught[0].message)
    (2.0, 'old.place.sqrt moved to math.sqrt; the old path is removed in interlock 0.3')
    """
    def __getattr__(name: str):
        if name not in homes:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        home = homes[name]
        warnings.warn(f"{old}.{name} moved to {home}.{name}; the old path is removed in interlock {REMOVED_IN}",
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(home), name)

    return __getattr__
