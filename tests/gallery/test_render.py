"""Pictures: the 3D view (Fig. 1c-d, 3a, 3c), the tilings by F and F' (Fig. 1b), lozenges by orientation (Fig. 3b)."""

import sys

import numpy as np
import pytest
import trimesh

pytest.importorskip("matplotlib")
from matplotlib.image import imread  # noqa: E402

from interlock.blocks import (Assembly, LozengeTiling, presets, random_hexagon,  # noqa: E402
                              rhomblock_assembly, staircase)
from interlock.errors import GalleryError  # noqa: E402
from interlock.gallery.appearance import PALETTE  # noqa: E402
from interlock.gallery.render import AMBIENT, FRAME_FADE, FRAME_GREY, LIGHT, render  # noqa: E402

SMALL = {"size": (3.0, 3.0), "dpi": 60}
#: Anti-aliasing and edges blend colours; a pixel within this (0..255 per channel) shows a colour.
TOL = 6


@pytest.fixture(scope="module")
def tiling():
    return random_hexagon(3, 3, 3, seed=0)


@pytest.fixture(scope="module")
def fig1_block():
    return presets.fig1_p6_block()


def _pixels(path) -> np.ndarray:
    """RGB of the PNG, integers 0..255, shape (height, width, 3)."""
    return np.round(imread(path)[:, :, :3] * 255).astype(int)


def _count(pixels, rgb, tol=TOL) -> int:
    return int((np.abs(pixels - np.asarray(rgb, dtype=float)).max(axis=-1) <= tol).sum())


def _top_colour(rgb) -> np.ndarray:
    """A block colour on a face with normal +z, by the Lambert formula of render's Notes."""
    return np.asarray(rgb, dtype=float) * (AMBIENT + (1 - AMBIENT) * max(0.0, LIGHT[2]))


# --- files ---------------------------------------------------------------------------------------


def test_png_has_requested_pixel_size(tmp_path, tiling):
    out = render(tiling, str(tmp_path / "t.png"), size=(3.0, 2.0), dpi=50)
    assert out == tmp_path / "t.png" and out.is_file()
    assert _pixels(out).shape == (100, 150, 3)


def test_3d_picture_is_not_blank(tmp_path, tiling):
    pixels = _pixels(render(rhomblock_assembly(tiling), tmp_path / "a.png", **SMALL))
    colours = np.unique(pixels.reshape(-1, 3), axis=0)
    assert len(colours) > 20
    assert 0.1 < 1 - _count(pixels, (255, 255, 255), 0) / (pixels.size / 3) < 0.95


def test_title_is_printed(tmp_path, tiling):
    plain = _pixels(render(tiling, tmp_path / "a.png", **SMALL))
    titled = _pixels(render(tiling, tmp_path / "b.png", title="RhomBlocks", **SMALL))
    assert not np.array_equal(plain, titled)


# --- 3D view -------------------------------------------------------------------------------------


def test_lambert_shading_of_a_top_face(tmp_path):
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    pixels = _pixels(render(cube, tmp_path / "cube.png", **SMALL))
    top = _count(pixels, _top_colour(PALETTE[0, :3]), 2)
    assert top > 0.05 * pixels.size / 3  # a large flat area in exactly the shaded colour
    assert _count(pixels, PALETTE[0, :3], 2) == 0  # no face is lit at full strength


def test_frame_blocks_are_paler(tmp_path):
    grid = presets.cube_grid()
    loose = _pixels(render(grid.with_frame(()), tmp_path / "loose.png", **SMALL))
    fixed = _pixels(render(grid.with_frame(range(len(grid))), tmp_path / "fixed.png", **SMALL))
    faded = (1 - FRAME_FADE) * PALETTE[0, :3] + FRAME_FADE * 255 * FRAME_GREY
    assert _count(loose, _top_colour(PALETTE[0, :3])) > 300 and _count(loose, _top_colour(faded)) == 0
    assert _count(fixed, _top_colour(PALETTE[0, :3])) == 0 and _count(fixed, _top_colour(faded)) > 300


def test_fig3a_rhomblock_tops_coloured_by_orientation(tmp_path, tiling):
    pixels = _pixels(render(rhomblock_assembly(tiling), tmp_path / "a.png", **SMALL))
    for k in range(3):
        assert _count(pixels, _top_colour(PALETTE[k, :3])) > 50


def test_fig3c_exploded_view_differs(tmp_path, tiling):
    assembly = rhomblock_assembly(tiling)
    plain = _pixels(render(assembly, tmp_path / "a.png", **SMALL))
    spread = _pixels(render(assembly, tmp_path / "b.png", exploded=0.5, **SMALL))
    assert plain.shape == spread.shape and (plain != spread).any(axis=-1).mean() > 0.05


def test_fig1d_block_patch_coloured_by_coset(tmp_path, fig1_block):
    alone = _pixels(render(fig1_block, tmp_path / "a.png", **SMALL))
    pixels = _pixels(render(fig1_block, tmp_path / "b.png", radius=1.0, **SMALL))
    assert sum(_count(alone, _top_colour(PALETTE[k, :3])) > 0 for k in range(6)) == 1
    assert all(_count(pixels, _top_colour(PALETTE[k, :3])) > 20 for k in range(6))


def test_mirror_image_block_drawn_like_its_mirrored_mesh(tmp_path):
    mesh = presets.fig1_p6_block().mesh
    placed = Assembly([mesh], [0], [np.diag([-1.0, 1.0, 1.0, 1.0])])
    baked = Assembly.from_meshes([placed.mesh(0)])
    a, b, unmirrored = (_pixels(render(obj, tmp_path / f"{k}.png", **SMALL))
                        for k, obj in enumerate((placed, baked, Assembly.from_meshes([mesh]))))
    differ = lambda p, q: (np.abs(p - q).max(axis=-1) > TOL).mean()  # noqa: E731
    assert differ(a, b) < 0.015  # only the anti-aliased edges between faces, drawn in another order
    assert differ(a, unmirrored) > 0.05


def test_1000_rhomblocks_are_all_drawn(tmp_path):
    # the time is benchmarks/gallery.py's "render_seconds" (4,800 blocks); here that the blocks are drawn:
    # their faces and edges give about ten times the colours of one block filling the same picture
    assembly = rhomblock_assembly(random_hexagon(18, 18, 18, seed=0), frame="boundary")
    assert len(assembly) == 972

    def colours(obj, name):
        pixels = _pixels(render(obj, tmp_path / name, **SMALL))[..., :3]
        return len(np.unique(pixels.reshape(-1, 3), axis=0))

    assert colours(assembly, "big.png") > 5 * colours(Assembly.from_meshes([assembly.mesh(0)]), "one.png")


# --- tiling views --------------------------------------------------------------------------------


def test_fig3b_lozenges_in_the_three_orientation_colours(tmp_path, tiling):
    pixels = _pixels(render(tiling, tmp_path / "t.png", **SMALL))
    assert all(_count(pixels, PALETTE[k, :3]) > 100 for k in range(3))
    assert all(_count(pixels, PALETTE[k, :3]) == 0 for k in range(3, len(PALETTE)))


def test_rhomblock_assembly_tiling_view_shows_its_lozenges(tmp_path, tiling):
    direct = _pixels(render(tiling, tmp_path / "a.png", **SMALL))
    from_blocks = _pixels(render(rhomblock_assembly(tiling, variant=1), tmp_path / "b.png", view="tiling", **SMALL))
    assert np.array_equal(direct, from_blocks)


def test_periodic_tiling_fills_its_window(tmp_path):
    pixels = _pixels(render(staircase((1, 1, 1)), tmp_path / "t.png", **SMALL))
    h, w, _ = pixels.shape
    inner = pixels[h // 10: -h // 10, w // 10: -w // 10]
    assert _count(inner, (255, 255, 255), 0) == 0
    assert all(_count(inner, PALETTE[k, :3]) > 100 for k in range(3))


def test_periodic_tiling_in_3d_is_its_rhomblock_assembly(tmp_path):
    pixels = _pixels(render(staircase((2, 1, 1)), tmp_path / "t.png", view="3d", radius=3.0, **SMALL))
    assert all(_count(pixels, _top_colour(PALETTE[k, :3])) > 20 for k in range(3))


def test_fig1b_two_panels_tiled_by_f_and_f_prime(tmp_path, fig1_block):
    pixels = _pixels(render(fig1_block, tmp_path / "t.png", view="tiling", size=(6.0, 3.0), dpi=60))
    half = pixels.shape[1] // 2
    for panel in (pixels[:, :half], pixels[:, half:]):
        assert all(_count(panel, PALETTE[k, :3]) > 50 for k in range(6))  # the six cosets of p6
    assert not np.array_equal(pixels[:, :half], pixels[:, half:2 * half])


# --- errors --------------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, message", [
    ({"view": "side"}, "unknown view 'side'"),
    ({"exploded": -1.0}, "exploded must be a finite factor >= 0"),
    ({"exploded": 0.5, "view": "tiling"}, "exploded applies to the 3d view"),
    ({"radius": 2.0}, "radius applies to a Block or a periodic LozengeTiling"),
    ({"size": (0.0, 3.0)}, "size and dpi must be positive"),
    ({"size": "big"}, "size must be"),
    ({"dpi": float("nan")}, "size and dpi must be positive"),
    ({"size": (1000.0, 10.0), "dpi": 100}, "size \\* dpi must stay below 65536 pixels"),
    ({"title": 3}, "title must be a string"),
])
def test_bad_options(tmp_path, tiling, kwargs, message):
    with pytest.raises(GalleryError, match=message):
        render(tiling, tmp_path / "t.png", **kwargs)


def test_bad_objects(tmp_path):
    with pytest.raises(GalleryError, match="render draws an Assembly, a Block"):
        render("cube", tmp_path / "t.png")
    with pytest.raises(GalleryError, match="use view='3d' for this Trimesh"):
        render(trimesh.creation.box(), tmp_path / "t.png", view="tiling")
    with pytest.raises(GalleryError, match="use view='3d' for this Assembly"):
        render(presets.cube_grid(), tmp_path / "t.png", view="tiling")
    with pytest.raises(GalleryError, match="nothing to draw: the LozengeTiling is empty"):
        render(LozengeTiling(np.empty((0, 3), dtype=int)), tmp_path / "t.png", view="3d")


def test_radius_must_be_positive_and_not_too_large(tmp_path, fig1_block):
    with pytest.raises(GalleryError, match="radius must be a positive finite number"):
        render(fig1_block, tmp_path / "t.png", radius=-1.0)
    with pytest.raises(GalleryError, match="radius too large: about .* tiles"):
        render(fig1_block, tmp_path / "t.png", view="tiling", radius=1e4)
    with pytest.raises(GalleryError, match="radius too large"):
        render(staircase((1, 1, 1)), tmp_path / "t.png", radius=1e4)


@pytest.mark.parametrize("name, message", [
    ("t.jpg", "give a path ending in .png"),
    ("missing/t.png", "the folder .* does not exist"),
    ("folder.png", "cannot write"),
])
def test_bad_paths(tmp_path, tiling, name, message):
    (tmp_path / "folder.png").mkdir()
    with pytest.raises(GalleryError, match=message):
        render(tiling, tmp_path / name)
    with pytest.raises(GalleryError, match="path must be a file name"):
        render(tiling, 3)


def test_missing_matplotlib_gives_the_install_hint(tmp_path, tiling, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(GalleryError, match=r'pip install "interlock\[plot\]"'):
        render(tiling, tmp_path / "t.png")
    assert not (tmp_path / "t.png").exists()
