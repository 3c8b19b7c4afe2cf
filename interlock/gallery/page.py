"""The gallery's ``index.html``: a table of contents, the legend, and per entry its verdict in words, a 3D view
loaded as it scrolls into sight, readable pictures and the files."""

from __future__ import annotations

import html
from pathlib import Path

from interlock.files import write_atomically
from interlock.gallery.appearance import PALETTE
from interlock.gallery.view.page import page_head, scene_script, scripts
from interlock.gallery.view.scene import FRAME_COLOUR, MOVING_COLOUR

__all__ = ["write_index", "finite_word", "LIVE_VIEWS", "GALLERY_POLICY"]

#: 3D views kept running at once; one further out of sight is closed when another opens (a browser gives a
#: page about 16 WebGL contexts).
LIVE_VIEWS = 6
#: As the single view's policy, and the gallery's own pictures (``file:``) besides.
GALLERY_POLICY = ("default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                  "img-src file: data: blob:")

_STYLE = """
html { scroll-behavior: smooth; scroll-padding-top: 12px; }
body { font: 15px/1.45 system-ui, sans-serif; margin: 0; color: #222; background: #fafafa; }
.layout { display: grid; grid-template-columns: minmax(0, 1fr); max-width: 1240px; margin: 0 auto; padding: 0 16px; }
@media (min-width: 1000px) { .layout { grid-template-columns: 250px minmax(0, 1fr); gap: 24px; }
  .toc { position: sticky; top: 0; max-height: 100vh; overflow-y: auto; } }
.toc { padding: 12px 0; font-size: 13.5px; } .toc ol { padding-left: 2.1em; margin: 0.3em 0; }
.toc li { margin: 0.25em 0; } .toc a { color: #1a4d8f; text-decoration: none; }
.toc a:hover { text-decoration: underline; }
h1 { margin: 0.6em 0 0.2em; } .lead { color: #555; margin-top: 0; }
.legend { background: white; border: 1px solid #ddd; border-radius: 8px; padding: 0.6em 1em; margin: 1em 0; }
.legend .row { display: inline-flex; align-items: center; gap: 6px; margin: 2px 14px 2px 0; }
.swatch { width: 14px; height: 14px; border-radius: 3px; border: 1px solid rgba(0, 0, 0, 0.3); display: inline-block; }
.entry { background: white; border: 1px solid #ddd; border-radius: 8px; padding: 1em; margin: 1.2em 0; }
.entry h2 { margin: 0 0 0.3em; font-size: 1.25em; }
.sentence { font-size: 1.05em; margin: 0.2em 0 0.8em; }
.viewer-box { height: min(480px, 70vh); position: relative; margin-bottom: 0.8em; }
.viewer-box .iv-viewer { position: absolute; inset: 0; min-height: 0; }
.placeholder { color: #777; padding: 2em; margin: 0; background: #f4f5f7; border-radius: 6px; height: 100%;
  box-sizing: border-box; }
.pictures { display: grid; grid-template-columns: repeat(auto-fill, minmax(200px, 1fr)); gap: 0.5em; }
.pictures figure { margin: 0; } .pictures img { width: 100%; border: 1px solid #eee; cursor: zoom-in; display: block; }
.pictures figure.wide { grid-column: 1 / -1; } .pictures figure.wide img { width: auto; max-width: 100%; }
.pictures figcaption { font-size: 12px; color: #666; }
.yes { color: #0a7a3a; font-weight: 600; } .no { color: #b3261e; font-weight: 600; } .maybe { color: #a15c00; }
table { border-collapse: collapse; } td, th { padding: 0.15em 0.7em 0.15em 0; text-align: left; vertical-align: top; }
details.verdicts summary { cursor: pointer; color: #444; margin: 0.6em 0 0.3em; }
.files a { margin-right: 0.8em; } code { background: #f1f1f1; padding: 0 0.2em; }
#lightbox { position: fixed; inset: 0; background: rgba(0, 0, 0, 0.8); display: none; align-items: center;
  justify-content: center; z-index: 10; cursor: zoom-out; }
#lightbox.open { display: flex; } #lightbox img { max-width: 96vw; max-height: 92vh; background: white; }
"""

_LIGHTBOX = """
(function () {
  var box = document.getElementById('lightbox'), picture = box.querySelector('img');
  document.querySelectorAll('a.zoom').forEach(function (link) {
    link.addEventListener('click', function (event) {
      event.preventDefault();
      picture.src = link.getAttribute('href');
      picture.alt = link.querySelector('img').alt;
      box.classList.add('open');
    });
  });
  box.addEventListener('click', function () { box.classList.remove('open'); });
  document.addEventListener('keydown', function (event) { if (event.key === 'Escape') box.classList.remove('open'); });
})();
"""


def write_index(folder: Path, results, quick: bool, seed: int) -> Path:
    """``index.html`` of the built entries (``EntryResult``: record, files and the scene of the 3D view)."""
    e = html.escape
    toc = "".join(f"<li><a href='#{e(r.name)}'>{e(r.record['title'])}</a> {_verdict_word(_settled(r.record))}</li>"
                  for r in results)
    parts = [page_head("interlock gallery", _STYLE, GALLERY_POLICY), "<body><div class='layout'>",
             f"<nav class='toc' aria-label='entries'><strong>{len(results)} entries</strong><ol>{toc}</ol></nav>",
             "<main><h1>interlock gallery</h1>",
             f"<p class='lead'>{len(results)} entries{' (quick)' if quick else ''}, seed {seed}. Every verdict was "
             "computed when this page was built; the claims are what the paper proves. Each 3D view loads when it "
             "scrolls into sight: drag to orbit, wheel to zoom, right-drag to pan, click a block for its "
             "details; pictures enlarge on a click.</p>",
             _legend()]
    parts += [_entry_html(r) for r in results]
    parts.append("</main></div><div id='lightbox' role='dialog' aria-label='picture'><img alt=''></div>")
    parts += [scene_script(f"scene-{r.name}", r.scene) for r in results if r.scene is not None]
    parts.append(scripts(f"InterlockViewer.mountLazily({LIVE_VIEWS});\n{_LIGHTBOX}"))
    parts.append("</body></html>")
    return write_atomically(folder / "index.html", "\n".join(parts))


def _legend() -> str:
    def row(colour, words):
        return f"<span class='row'><span class='swatch' style='background:{colour}'></span>{html.escape(words)}</span>"

    classes = "".join(row("#%02x%02x%02x" % tuple(PALETTE[k][:3]), f"class {k}") for k in range(4))
    return ("<section class='legend' aria-label='legend'><strong>Legend</strong><br>"
            f"{classes}{row(FRAME_COLOUR, 'frame: the fixed blocks')}{row(MOVING_COLOUR, 'blocks that move')}"
            f"{row('#ffd400', 'the block you picked')}<br><small>Blocks are coloured by class: the coset of an "
            "Escher block's group element, or the orientation of a RhomBlock's lozenge (else the shape). In the "
            "3D views the frame is grey; in the pictures it is the class colour faded to grey. 'Not "
            "infinitesimally interlocked' means a first-order motion exists; only a finite motion shown proves "
            "that blocks come out.</small></section>")


def finite_word(record: dict) -> str:
    """The finite verdict in words: first order, or beyond it when first order did not prove it interlocked."""
    if record["finite"]["interlocked"] is True:
        return "interlocked"
    beyond = record.get("beyond") or {}
    return {True: "interlocked (2nd order)", False: "not interlocked", None: "inconclusive"}[beyond.get("interlocked")]


def _settled(record: dict):
    """True, False or None: the finite verdict, beyond first order where it was taken there."""
    if record["finite"]["interlocked"] is True or not record.get("beyond"):
        return record["finite"]["interlocked"]
    return record["beyond"]["interlocked"]


def _verdict_word(value) -> str:
    if value in (True, "interlocked"):
        return "<span class='yes'>interlocked</span>"
    if value in (False, "not interlocked"):
        return "<span class='no'>not interlocked</span>"
    return "<span class='maybe'>inconclusive</span>"


def _picture_caption(name: str) -> str:
    stem = name.removesuffix(".png")
    if stem.startswith("motion"):
        return f"the finite motion, step {int(stem.split()[-1]) + 1}"
    return {"block": "the block", "assembly": "the assembly", "exploded": "exploded",
            "tiling": "the tiling (click to enlarge)"}.get(stem, stem)


def _entry_html(result) -> str:
    r, e = result.record, html.escape
    first = _verdict_word(r["finite"]["interlocked"]).replace(">not interlocked<", ">not infinitesimally interlocked<")
    rows = [f"<tr><th>finite ({r['blocks']} blocks, {len(r['frame'])} fixed)</th><td>"
            f"{first} — {e(r['finite']['status'])}</td></tr>"]
    if r.get("beyond"):
        word = _verdict_word(r["beyond"]["interlocked"]).replace(">interlocked<", ">interlocked (second order)<")
        rows.append(f"<tr><th>beyond first order</th><td>{word} — {e(r['beyond']['status'])}</td></tr>")
    for key, label in (("periodic", "infinite (periodic)"), ("periodic_translational", "infinite, translations")):
        if r.get(key):
            word = _verdict_word(r[key]["status"])
            rows.append(f"<tr><th>{label}</th><td>{word} — {e(r[key]['reason'])}</td></tr>")
    if r.get("criterion_4_3"):
        holds = r["criterion_4_3"]["holds"]
        rows.append(f"<tr><th>Criterion 4.3</th><td>{'holds' if holds else 'fails'}</td></tr>")
    for claim in r["claims"]:
        mark = {True: "<span class='yes'>agrees</span>", False: "<span class='no'>CONTRADICTS</span>",
                None: "<span class='maybe'>cannot tell</span>"}[claim["holds"]]
        rows.append(f"<tr><th>{e(claim['source'])}</th><td>{e(claim['statement'])}: {mark}</td></tr>")
    seconds = ", ".join(f"{k.replace('_', ' ')} {v:.2f} s" for k, v in r["timings"].items())
    figures = []
    for name, path in result.files.items():
        if name.endswith(".png"):
            wide = " class='wide'" if name == "tiling.png" else ""
            caption = _picture_caption(name)
            figures.append(f"<figure{wide}><a class='zoom' href='{e(path)}'><img src='{e(path)}' alt='{e(caption)}' "
                           f"loading='lazy'></a><figcaption>{e(caption)}</figcaption></figure>")
    figures.sort(key=lambda f: " class='wide'" not in f)  # the tiling first, across the whole width
    links = "".join(f"<a href='{e(path)}' download>{e(name)}</a>" for name, path in result.files.items()
                    if not name.endswith(".png"))
    viewer = (f"<div class='viewer-box'><div class='iv-viewer' data-scene='scene-{e(result.name)}'>"
              "<p class='placeholder'>The 3D view opens when this entry scrolls into sight.</p></div></div>"
              if result.scene is not None else "")
    sentence = e(r.get("sentence") or "")
    return (f"<section class='entry' id='{e(result.name)}'><h2>{e(r['title'])}</h2>"
            f"<p class='sentence'>{_verdict_word(_settled(r))}: {sentence}</p>{viewer}"
            f"<div class='pictures'>{''.join(figures)}</div>"
            f"<details class='verdicts' open><summary>The precise verdicts and the paper's claims</summary>"
            f"<table>{''.join(rows)}</table></details>"
            f"<p class='files'>Download: {links}</p><p class='lead'>{seconds}</p></section>")
