"""interlock: interlocking assemblies of rigid blocks.

Generate assemblies with crystallographic symmetry (``interlock.wallpaper``,
``interlock.blocks``), read and write them (``interlock.read``,
``interlock.write``: ``interlock.formats``), prove or disprove that they
interlock (``interlock.check``: ``interlock.verify``) and draw them
(``interlock.gallery``).

Every name and submodule is imported on first use (PEP 562,
:func:`lazy_exports`), so ``import interlock`` loads no numpy.

>>> import interlock
>>> interlock.wallpaper.group("p6").point_group_order
6
>>> print(interlock.check(interlock.blocks.presets.cube_grid()))  # doctest: +ELLIPSIS
not infinitesimally interlocked: block 4 has a first-order motion...
"""

__version__ = "0.1.0"

import importlib
import sys
import types

from interlock.errors import AssemblyError, GalleryError, GroupError, InterlockError, LatticeError

__all__ = ["read", "write", "check", "Assembly", "InterlockError", "GroupError", "LatticeError", "AssemblyError",
           "GalleryError", "wallpaper", "blocks", "formats", "verify", "gallery", "sweep", "__version__"]

# where each exported name lives (the submodules load by their names)
_HOMES = {**dict.fromkeys(["read", "write"], "interlock.formats.readwrite"), "check": "interlock.verify.check",
          "Assembly": "interlock.blocks.assembly"}


class LazyPackage(types.ModuleType):
    """A package whose names are imported on first use (:func:`lazy_exports`).

    The import system binds a submodule to the attribute of its name on the
    package when it loads it; where the package exports a function of that
    name (``interlock.verify.check``, ``.contacts``, ``.npod``;
    ``interlock.gallery.export``), the function stays bound instead.
    """

    def __setattr__(self, name, value):
        homes = self.__dict__.get("__lazy_homes__", {})
        if name in homes and isinstance(value, types.ModuleType) and value.__name__ == f"{self.__name__}.{name}":
            value = getattr(importlib.import_module(homes[name]), name)
        super().__setattr__(name, value)


def lazy_exports(package: str, homes: dict[str, str], fallback=None):
    """The module ``__getattr__`` and ``__dir__`` (PEP 562) of a package whose names load on first use.

    ``homes`` maps each exported name to the module that defines it; that
    module is imported when the name is first asked for (``package.name`` or
    ``from package import name``), so importing the package costs only what
    a command uses.  Other names are the package's submodules, then
    ``fallback`` (e.g. :func:`interlock.deprecation.moved` for old paths).
    The package becomes a :class:`LazyPackage`.

    Examples
    --------
    >>> import interlock.gallery.export  # the module, loaded by its name ...
    >>> callable(interlock.gallery.export)  # ... leaves the function of that name bound
    True
    """
    module = sys.modules[package]
    module.__dict__["__lazy_homes__"] = dict(homes)
    module.__class__ = LazyPackage

    def __getattr__(name: str):
        if name in homes:
            value = getattr(importlib.import_module(homes[name]), name)
            module.__dict__[name] = value
            return value
        if not name.startswith("__"):
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as error:
                if error.name != f"{package}.{name}":
                    raise
        if fallback is not None:
            return fallback(name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(module.__dict__) | set(homes))

    return __getattr__, __dir__



__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
