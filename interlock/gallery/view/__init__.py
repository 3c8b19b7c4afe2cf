"""An interactive, offline 3D view of an assembly and its verdicts: one HTML file with three.js inline.

- :func:`write_view`: the file, from an assembly and the results of ``check``, ``rbe`` or ``cra``;
- :func:`scene`: what the page draws, as JSON (one mesh per kind of block, a placement per block);
- :func:`plain_sentence`: the verdict in one plain sentence.
"""

from interlock import lazy_exports

__all__ = ["write_view", "view_html", "scene", "plain_sentence", "collapse_twists", "three_script"]

_HOMES = {
    **dict.fromkeys(["write_view", "view_html"], "interlock.gallery.view.page"),
    "scene": "interlock.gallery.view.scene",
    "plain_sentence": "interlock.gallery.view.words",
    "collapse_twists": "interlock.gallery.view.collapse",
    "three_script": "interlock.gallery.view.bundle",
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
