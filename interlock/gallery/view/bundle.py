"""three.js as one classic script: the vendored ES modules wrapped so that a page opened from ``file://`` runs them."""

from __future__ import annotations

import functools
import re
from importlib import resources

__all__ = ["three_script", "three_licence", "viewer_script", "viewer_style", "THREE_VERSION", "THREE_FILES"]

#: The three.js release vendored under ``interlock/gallery/vendor/three`` (npm ``three``, MIT licence).
THREE_VERSION = "0.187.0"
#: The vendored files, unchanged from the npm package, in the order they are wrapped.
THREE_FILES = ("three.core.js", "three.module.js", "OrbitControls.js")

_IMPORT = re.compile(r"^import\s*\{([^}]*)\}\s*from\s*'([^']+)';\s*$", re.M)
_EXPORT = re.compile(r"^export\s*\{([^}]*)\}(?:\s*from\s*'([^']+)')?;\s*$", re.M)


@functools.lru_cache(maxsize=1)
def three_script() -> str:
    """three.js (core, WebGL renderer) and its ``OrbitControls`` as one classic script defining ``THREE``.

    Browsers refuse ES modules loaded from ``file://`` and inline modules
    cannot import one another, so each vendored module becomes a function
    whose ``import { a as b } from '...'`` turns into ``const { a: b } = ...``
    and whose ``export { a as b }`` into the object it returns.  The module
    text itself is unchanged (strict mode kept), and ``THREE.OrbitControls`` is
    added beside the library's own names.

    >>> script = three_script()
    >>> script.startswith("/*") and "var THREE =" in script and "OrbitControls" in script
    True
    """
    core, module, orbit = (_vendor(name) for name in THREE_FILES)
    parts = [three_licence_comment(),
             f"var THREE_CORE = {_wrap(core, {})};",
             f"var THREE = {_wrap(module, {'./three.core.js': 'THREE_CORE'})};",
             f"THREE.OrbitControls = {_wrap(orbit, {'three': 'THREE'})}.OrbitControls;"]
    return "\n".join(parts)


def three_licence() -> str:
    """three.js's MIT licence, as vendored."""
    return _vendor("LICENSE")


def three_licence_comment() -> str:
    return f"/* three.js r{THREE_VERSION.split('.')[1]} (npm three {THREE_VERSION}), vendored by interlock.\n" + \
        three_licence().replace("*/", "* /") + "*/"


def viewer_script() -> str:
    """The viewer's own script (``viewer.js`` beside this module)."""
    return resources.files("interlock.gallery.view").joinpath("viewer.js").read_text(encoding="utf-8")


def viewer_style() -> str:
    """The viewer's style sheet (``viewer.css`` beside this module)."""
    return resources.files("interlock.gallery.view").joinpath("viewer.css").read_text(encoding="utf-8")


def _vendor(name: str) -> str:
    return resources.files("interlock.gallery").joinpath("vendor", "three", name).read_text(encoding="utf-8")


def _names(clause: str) -> list[tuple[str, str]]:
    """``a as b, c`` -> ``[("a", "b"), ("c", "c")]``."""
    out = []
    for item in filter(None, (part.strip() for part in clause.split(","))):
        local, _, exported = item.partition(" as ")
        out.append((local.strip(), (exported or local).strip()))
    return out


def _wrap(text: str, sources: dict) -> str:
    """An ES module as ``(function () { ... return {...}; })()``, its imports read from the named globals."""
    exported = []
    spread = []

    def importing(match):
        source = sources[match.group(2)]
        return "const { " + ", ".join(f"{a}: {b}" for a, b in _names(match.group(1))) + f" }} = {source};"

    def exporting(match):
        if match.group(2):  # re-exported from another module: all of it, by name
            spread.append(sources[match.group(2)])
        else:
            exported.extend(_names(match.group(1)))
        return ""

    body = _EXPORT.sub(exporting, _IMPORT.sub(importing, text))
    members = ", ".join([f"...{s}" for s in spread] + [f"{b}: {a}" for a, b in exported])
    return f"(function () {{\n'use strict';\n{body}\nreturn {{ {members} }};\n}})()"
