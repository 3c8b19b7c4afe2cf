"""The view as one self-contained HTML file: the scene, three.js and the viewer's script inline, nothing fetched."""

from __future__ import annotations

import html
import json
from pathlib import Path

from interlock.errors import GalleryError
from interlock.files import unwritable, write_atomically
from interlock.gallery.view.bundle import three_script, viewer_script, viewer_style
from interlock.gallery.view.scene import scene

__all__ = ["write_view", "view_html", "scene_script", "page_head", "scripts", "CONTENT_POLICY"]

#: The page may run only its own inline scripts and styles and show inline pictures: a view that tried to load
#: anything from the network would be refused by the browser (and the tests would see the refusal).
CONTENT_POLICY = ("default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                  "img-src data: blob:")

_PAGE_STYLE = """
html, body { margin: 0; height: 100%; background: #fafafa; color: #222; font: 15px/1.4 system-ui, sans-serif; }
body.iv-single { display: flex; flex-direction: column; }
.iv-head { padding: 10px 16px 6px; border-bottom: 1px solid #ddd; background: #fff; }
.iv-head h1 { font-size: 17px; margin: 0 0 4px; font-weight: 600; }
.iv-sentence { font-size: 16px; margin: 0 0 4px; }
.iv-statement { margin: 0 0 2px; font-size: 12.5px; color: #444; font-family: ui-monospace, monospace; }
.iv-details summary { cursor: pointer; color: #555; font-size: 13px; }
.iv-details p { margin: 2px 0; font-size: 12.5px; color: #444; font-family: ui-monospace, monospace; }
.iv-main { position: relative; flex: 1; min-height: 360px; }
.iv-main .iv-viewer { position: absolute; inset: 0; }
.iv-foot { font-size: 11px; color: #777; padding: 2px 16px 4px; }
"""


def write_view(obj, path, verdict=None, stability=None, *, title: str | None = None, contacts=None,
               frame_words: str | None = None) -> Path:
    """Write an interactive 3D view of an assembly and its verdicts to one HTML file that works offline.

    The file holds everything it needs (three.js, vendored under its MIT
    licence, the viewer's script and the scene) and loads nothing: open it
    from disk in any browser with WebGL 2, or send it to a colleague.  It
    shows one plain sentence about the verdict, then the precise statement
    and its tolerances; the blocks coloured by class (coset or lozenge
    orientation) with the frame grey, and a legend; orbit (drag), zoom
    (wheel), pan (right-drag) and reset; the motion of a "not interlocked"
    verdict with play/pause and a slider; the contact forces of a stable
    result, or the collapse mechanism of an unstable one; a click on a block
    shows its index, label, volume and contacts; "Pick frame" lets the user
    choose the fixed blocks and copy the matching ``--fixed`` list.

    Blocks that share a mesh share one geometry on the page (instancing): a
    4,800-block RhomBlock hexagon is about 3 MB.

    Parameters
    ----------
    obj : Assembly, Block or trimesh.Trimesh
    path : path
        The ``.html`` file to write (written whole or not at all).
    verdict : Verdict, optional
        From :func:`~interlock.verify.check` (``order=2`` for the finite motion).
    stability : StabilityResult or CRAResult, optional
        From :func:`~interlock.verify.rbe` or :func:`~interlock.verify.cra`.
    title, contacts, frame_words
        See :func:`~interlock.gallery.view.scene.scene`.

    Returns
    -------
    Path

    Raises
    ------
    GalleryError
        Not an assembly, no blocks, or a path that cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import presets
    >>> from interlock.verify import check
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     page = write_view(grid, Path(folder) / "view.html", check(grid, order=2))
    ...     text = page.read_text()
    >>> "block 4 can be lifted straight up" in text, "http://" in text.split("</style>")[0]
    (True, False)
    """
    target = Path(path)
    reason = unwritable(target)
    if reason:
        raise GalleryError(f"cannot write {target}: {reason}")
    data = scene(obj, verdict, stability, title=title, contacts=contacts, frame_words=frame_words)
    return write_atomically(target, view_html(data))


def view_html(data: dict) -> str:
    """The page of one scene (:func:`~interlock.gallery.view.scene.scene`): header, viewer, scripts."""
    e = html.escape
    statement, *rest = data["details"] or [""]
    lines = "".join(f"<p>{e(line)}</p>" for line in rest)
    details = (f"<p class='iv-statement' id='statement'>{e(statement)}</p>" if statement else "") + \
        (f"<details class='iv-details'><summary>Tolerances and details</summary>{lines}</details>" if lines else "")
    return "\n".join([
        page_head(data["title"], _PAGE_STYLE),
        "<body class='iv-single'>",
        f"<header class='iv-head'><h1>{e(data['title'])}</h1>"
        f"<p class='iv-sentence' id='sentence'>{e(data['sentence'])}</p>{details}</header>",
        "<main class='iv-main'><div class='iv-viewer' data-scene='scene-0'></div></main>",
        "<footer class='iv-foot'>interlock view: drag to orbit, wheel to zoom, right-drag to pan. three.js is "
        "included under its MIT licence (see the script's first comment).</footer>",
        scene_script("scene-0", data),
        scripts("InterlockViewer.mountAll();"),
        "</body></html>"])


def page_head(title: str, style: str = "", policy: str = CONTENT_POLICY) -> str:
    """``<!doctype html>`` to ``</head>``: charset, viewport, the content policy, no favicon request, the styles."""
    return ("<!doctype html><html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<meta http-equiv='Content-Security-Policy' content=\"{policy}\">"
            "<link rel='icon' href='data:,'>"
            f"<title>{html.escape(title)}</title><style>{viewer_style()}{style}</style></head>")


def scene_script(identifier: str, data: dict) -> str:
    """A scene as an inline JSON block the viewer reads by id (``</`` escaped so that it cannot end the block)."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return f"<script type='application/json' id='{html.escape(identifier)}'>{text}</script>"


def scripts(start: str) -> str:
    """three.js, the viewer and the statement that starts it, as inline scripts."""
    for piece in (start,):
        if "</script" in piece.lower():
            raise GalleryError("a page script may not contain '</script'")
    return (f"<script>{three_script()}</script>\n<script>{viewer_script()}</script>\n"
            f"<script>{start}</script>")
