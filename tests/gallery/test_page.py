"""interlock/gallery/page.py: the gallery's index.html in headless Chromium, and the folder's mode."""

from __future__ import annotations

import os
import stat
import time

import pytest

from interlock.gallery import build
from tests.gallery.browser import Page, launch, varied

pytestmark = pytest.mark.timeout(900)


@pytest.fixture(scope="module")
def gallery(tmp_path_factory):
    return build(tmp_path_factory.mktemp("gallery") / "out", quick=True, seed=0)


@pytest.fixture(scope="module")
def page(gallery):
    driver = launch()
    driver.set_window_size(1280, 900)
    yield Page(driver, gallery.index)
    driver.quit()


def test_table_of_contents_links_every_entry(page, gallery):
    links = page.js("return Array.from(document.querySelectorAll('nav.toc a')).map(a => a.getAttribute('href'))")
    assert links == [f"#{r.name}" for r in gallery.entries]
    for result in gallery.entries:
        assert page.js("return !!document.getElementById(arguments[0])", result.name)


def test_every_entry_has_a_viewer_that_loads_when_it_scrolls_into_sight(page, gallery):
    viewers = page.js("return Array.from(document.querySelectorAll('.iv-viewer')).map(v => v.dataset.scene)")
    assert viewers == [f"scene-{r.name}" for r in gallery.entries]
    for k, result in enumerate(gallery.entries):
        page.js("document.querySelectorAll('.iv-viewer')[arguments[0]].scrollIntoView({block: 'center'})", k)
        page.wait("return document.querySelectorAll('.iv-viewer')[arguments[0]].classList.contains('iv-live')", k)
        stats = page.js("var c = document.querySelectorAll('.iv-viewer')[arguments[0]];"
                        "return window.interlock.views.find(v => v.container === c).stats()", k)
        assert stats["blocks"] == result.record["blocks"] and stats["frame"] == len(result.record["frame"])
        canvas = page.driver.find_elements("css selector", ".iv-viewer")[k].find_element("css selector", "canvas")
        assert varied(page.pixels(canvas)), result.name
    assert page.js("return window.interlock.mounted") == len(gallery.entries)
    grid = next(r for r in gallery.entries if r.name == "ex3.5-cube-grid")
    assert grid.scene["motion"]["kind"] == "finite" and grid.scene["motion"]["moving"] == [4]


def test_no_console_error_and_no_request_leaves_the_folder(page, gallery):
    page.js("window.scrollTo(0, document.body.scrollHeight)")
    time.sleep(0.5)
    assert page.errors() == []
    assert page.outside() == []
    assert all(url.startswith("file://") for url in page.requests())


def test_legend_viewport_and_a_plain_verdict_line_per_entry(page, gallery):
    assert page.js("return document.querySelector('meta[name=viewport]').content") == \
        "width=device-width, initial-scale=1"
    legend = page.driver.find_element("css selector", "section.legend").text
    assert "frame: the fixed blocks" in legend and "blocks that move" in legend
    sentences = page.js("return Array.from(document.querySelectorAll('.entry .sentence')).map(p => p.textContent)")
    assert len(sentences) == len(gallery.entries)
    by_name = dict(zip([r.name for r in gallery.entries], sentences))
    assert by_name["escher-p4"].startswith("interlocked: With the outer ring (")
    assert by_name["escher-p4"].endswith(" blocks) fixed, no block can move.")
    assert "block 4 can be lifted straight up and out" in by_name["ex3.5-cube-grid"]


def test_tiling_pictures_are_readable(page):
    """The two-panel tiling picture (1100 px wide) spans the entry, not a 220 px thumbnail; a click enlarges it."""
    width = page.js("var img = document.querySelector('#escher-p4 figure.wide img');"
                    "img.scrollIntoView(); return img.getBoundingClientRect().width")
    assert width >= 800
    page.js("document.querySelector('#escher-p4 figure.wide a').click()")
    assert page.js("return document.getElementById('lightbox').classList.contains('open')")
    page.js("document.getElementById('lightbox').click()")
    assert not page.js("return document.getElementById('lightbox').classList.contains('open')")


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_the_gallery_folder_respects_the_umask(tmp_path, mask):
    old = os.umask(mask)
    try:
        g = build(tmp_path / "g", quick=True, names=["escher-p1"])
    finally:
        os.umask(old)
    assert stat.S_IMODE(g.folder.stat().st_mode) == 0o777 & ~mask
