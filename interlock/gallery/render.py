"""Pictures of blocks, assemblies and tilings as off-screen PNG files (main paper Fig. 1, 3)."""

from __future__ import annotations

import math
import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.escher import Block
from interlock.blocks.lozenge import LATTICE_BASIS, Lozenge, LozengeTiling
from interlock.blocks.orbits import patch
from interlock.blocks.rhomblock import rhomblock_assembly
from interlock.errors import GalleryError, InterlockError
from interlock.files import atomic_write
from interlock.gallery.appearance import PALETTE, as_assembly, block_classes, block_colours, exploded_factor
from interlock.gallery.appearance import exploded as explode

__all__ = ["render", "VIEWS", "ELEVATION", "AZIMUTH", "LIGHT", "AMBIENT", "FRAME_FADE", "FRAME_GREY",
           "EDGE_COLOUR", "TILING_CELLS", "PERIODS_SHOWN", "MAX_TILES", "MAX_PIXELS"]

#: The views :func:`render` draws.
VIEWS = ("auto", "3d", "tiling")
#: Camera of the 3D view in degrees (matplotlib's convention): height above the xy plane, turn about z.
ELEVATION, AZIMUTH = 35.0, -60.0
#: Unit vector towards the light of the 3D view, fixed in world coordinates (above, on the viewer's side).
LIGHT = np.array([-0.35, -0.55, 1.0]) / np.linalg.norm([-0.35, -0.55, 1.0])
#: Brightness of a face turned away from the light (Lambert shading, see :func:`render`).
AMBIENT = 0.4
#: Fixed blocks (the frame) are their colour mixed with :data:`FRAME_GREY` by this fraction.
FRAME_FADE = 0.65
FRAME_GREY = np.array([0.85, 0.85, 0.85])
#: RGB of face and tile edges.
EDGE_COLOUR = (0.12, 0.12, 0.12)
#: Default radius of a block's tiling view, in cell lengths (the longer lattice vector).
TILING_CELLS = 2.0
#: Default half-width of the window onto a periodic lozenge tiling, in lengths of its longer period.
PERIODS_SHOWN = 2.5
#: Largest image side in pixels (the limit of matplotlib's Agg renderer).
MAX_PIXELS = 2**16
#: Most tiles or blocks an infinite pattern (a block's tilings or patch, a periodic tiling) may be drawn with.
MAX_TILES = 20_000

# Line widths in points: 3D face edges (this scale over sqrt(blocks), clipped to the range), tile edges,
# the outline of F and F'.
_FACE_EDGE_SCALE, _FACE_EDGE_WIDTH = 8.0, (0.15, 0.6)
_TILE_EDGE_WIDTH = 0.5
_DOMAIN_EDGE_WIDTH = 1.8
# Share of the 3D view the projected blocks fill.
_FILL = 0.95


def render(obj, path, *, view: str = "auto", exploded: float = 0.0, radius: float | None = None,
           title: str | None = None, size=(6.0, 6.0), dpi: float = 110) -> Path:
    """Draw an assembly, a block, a mesh or a lozenge tiling into a PNG file, off-screen.

    Parameters
    ----------
    obj : Assembly, Block, trimesh.Trimesh or LozengeTiling
        What to draw.
    path : str or path-like
        The PNG file to write (suffix ``.png``, in an existing folder); it is overwritten.
    view : {"auto", "3d", "tiling"}
        ``"3d"``: the blocks, shaded, seen from above at :data:`ELEVATION`, each coloured by
        :func:`~interlock.gallery.appearance.block_colours`, the frame paler and greyer.
        ``"tiling"``: for a :class:`~interlock.blocks.Block`, two panels as in Fig. 1b: the tilings
        of the plane by F (its bottom) and by F' (its top) under the group elements whose tile
        meets a disc of ``radius``, each tile coloured by its coset (identity first, as
        :func:`~interlock.gallery.appearance.block_classes`), F and F' outlined; for a
        :class:`~interlock.blocks.LozengeTiling` or a RhomBlock assembly (labels are lozenges), the
        lozenges coloured by orientation as in Fig. 3b.  ``"auto"``: ``"tiling"`` for a lozenge
        tiling, ``"3d"`` for everything else (a lozenge tiling in 3D is its RhomBlock assembly).
    exploded : float
        3D view only: every block moved away from the centre by this factor
        (:func:`~interlock.gallery.appearance.exploded`), as in Fig. 3c.
    radius : float, optional
        Only for infinite objects.  A block: the disc of tiles of the tiling view (default
        :data:`TILING_CELLS` cell lengths), or the patch of the 3D view (Fig. 1d; default: the
        block alone).  A periodic lozenge tiling: half the width of the square window shown
        (default :data:`PERIODS_SHOWN` lengths of the longer period).
    title : str, optional
        Printed above the picture.
    size : (float, float)
        Width and height in inches; the image has ``int(size * dpi)`` pixels.
    dpi : float
        Pixels per inch.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    GalleryError
        An unknown view, an object it cannot draw (a tiling view of a bare mesh, an empty
        assembly or tiling), a bad ``exploded``, ``size`` or ``dpi``, a ``radius`` that is not
        positive or asks for more than :data:`MAX_TILES` tiles, a path that is not a ``.png`` file
        in an existing, writable folder, or matplotlib missing (install it with
        ``pip install "interlock[plot]"``).

    Notes
    -----
    The 3D view is an orthographic projection.  A face with outward unit normal ``n`` (in world
    coordinates: ``R n`` for a block placed by ``x -> R x + t``, also for mirror images) is
    drawn only when it faces the camera, ``n . e > 0`` for the unit vector ``e`` towards the
    eye (back-face culling, which is exact for closed blocks under an orthographic camera), in
    the colour ``c (a + (1 - a) max(0, n . l))`` with the block colour ``c``, the ambient
    brightness ``a`` = :data:`AMBIENT` and the light direction ``l`` = :data:`LIGHT`.  Faces are
    the planar facets of each mesh (coplanar triangles merged), so block outlines show but
    triangulations do not.  All facets of all blocks are placed by one ``einsum`` per mesh
    type, so the cost is ``O(n f)`` for ``n`` blocks of ``f`` facets, plus matplotlib's depth sort.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import random_hexagon
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     png = render(random_hexagon(3, 3, 3, seed=0), Path(folder) / "tiling.png", size=(2, 2), dpi=50)
    ...     png.name, png.stat().st_size > 0
    ('tiling.png', True)
    """
    path = _png_path(path)
    size, dpi = _figure_size(size, dpi)
    if view not in VIEWS:
        raise GalleryError(f"unknown view {view!r}; choose one of {', '.join(map(repr, VIEWS))}")
    if title is not None and not isinstance(title, str):
        raise GalleryError(f"title must be a string or None, got {type(title).__name__}")
    if not isinstance(obj, (Assembly, Block, trimesh.Trimesh, LozengeTiling)):
        raise GalleryError("render draws an Assembly, a Block, a trimesh.Trimesh or a LozengeTiling, "
                           f"got {type(obj).__name__}")
    if isinstance(obj, (Assembly, LozengeTiling)) and not len(obj):
        raise GalleryError(f"nothing to draw: the {type(obj).__name__} is empty")
    if view == "auto":
        view = "tiling" if isinstance(obj, LozengeTiling) else "3d"
    radius = _radius(obj, radius)
    exploded = _exploded(exploded, view)
    mpl = _matplotlib()
    fig = mpl.Figure(figsize=size, dpi=dpi, facecolor="white")
    mpl.FigureCanvasAgg(fig)
    top = 1.0 if title is None else 0.92
    if title is not None:
        fig.suptitle(title)
    try:
        if view == "3d":
            _draw_3d(fig, mpl, _assembly(obj, radius, exploded), top)
        elif isinstance(obj, Block):
            _draw_block_tilings(fig, mpl, obj, radius, top)
        else:
            _draw_lozenges(fig, mpl, _lozenge_tiling(obj), radius, top)
        with atomic_write(path) as temporary:  # whole or not at all (interlock.files)
            fig.savefig(temporary, format="png", dpi=dpi, facecolor="white")
    except OSError as error:
        raise GalleryError(f"cannot write {path}: {error.strerror or error}") from None
    return path


# --- arguments -------------------------------------------------------------------------------


def _png_path(path) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise GalleryError(f"path must be a file name (str or path-like), got {type(path).__name__}")
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise GalleryError(f"render writes PNG images; give a path ending in .png, got {str(path)!r}")
    if not path.parent.is_dir():
        raise GalleryError(f"cannot write {path}: the folder {str(path.parent)!r} does not exist")
    return path


def _figure_size(size, dpi) -> tuple[tuple[float, float], float]:
    try:
        width, height = (float(v) for v in size)
        dpi = float(dpi)
    except (TypeError, ValueError):
        raise GalleryError(f"size must be (width, height) in inches and dpi a number, got {size!r}, {dpi!r}") from None
    if not all(math.isfinite(v) and v > 0 for v in (width, height, dpi)) or min(width, height) * dpi < 1:
        raise GalleryError(f"size and dpi must be positive and give at least one pixel, got {size!r}, {dpi!r}")
    if max(width, height) * dpi >= MAX_PIXELS:
        raise GalleryError(f"size * dpi must stay below {MAX_PIXELS} pixels a side, got {size!r}, {dpi!r}")
    return (width, height), dpi


def _radius(obj, radius) -> float | None:
    if radius is None:
        return None
    if not (isinstance(obj, Block) or (isinstance(obj, LozengeTiling) and obj.is_periodic)):
        raise GalleryError("radius applies to a Block or a periodic LozengeTiling (the part of the infinite "
                           f"pattern to draw); leave it out for a {type(obj).__name__}")
    try:
        radius = float(radius)
    except (TypeError, ValueError):
        raise GalleryError(f"radius must be a positive number, got {radius!r}") from None
    if not (math.isfinite(radius) and radius > 0):
        raise GalleryError(f"radius must be a positive finite number, got {radius}")
    return radius


def _exploded(factor, view) -> float:
    factor = exploded_factor(factor)
    if factor > 0 and view != "3d":
        raise GalleryError(f"exploded applies to the 3d view, not to the {view} view")
    return factor


def _matplotlib() -> SimpleNamespace:
    """The matplotlib classes used here, imported on demand (matplotlib is an optional extra)."""
    try:
        import matplotlib  # noqa: F401  (fails first when matplotlib is absent)
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import PolyCollection
        from matplotlib.figure import Figure
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    except ImportError:
        raise GalleryError('drawing pictures needs matplotlib; install it with pip install "interlock[plot]"') from None
    return SimpleNamespace(Figure=Figure, FigureCanvasAgg=FigureCanvasAgg, PolyCollection=PolyCollection,
                           Poly3DCollection=Poly3DCollection)


# --- what to draw ------------------------------------------------------------------------------


def _assembly(obj, radius, factor) -> Assembly:
    if isinstance(obj, Block) and radius is not None:
        _check_tile_count(math.pi * (radius + _reach(obj)) ** 2 / obj.bottom.area)
        assembly = patch(obj, radius)
    elif isinstance(obj, LozengeTiling):
        rows = _window_lozenges(obj, radius, margin=0.0)[0] if obj.is_periodic else obj.lozenges
        assembly = rhomblock_assembly(LozengeTiling(rows))
    else:
        assembly = as_assembly(obj)
    return explode(assembly, factor)


def _lozenge_tiling(obj) -> LozengeTiling:
    if isinstance(obj, LozengeTiling):
        return obj
    if isinstance(obj, Assembly) and obj.labels and all(isinstance(label, Lozenge) for label in obj.labels):
        rows = [(z.i, z.j, z.orientation) for z in obj.labels]
        periods = obj.info.get("periods") if obj.lattice is not None else None
        try:
            return LozengeTiling(rows, periods)
        except InterlockError as error:
            raise GalleryError(f"the assembly's lozenge labels do not form a tiling: {error}") from None
    raise GalleryError("the tiling view draws a Block (its tilings by F and F'), a LozengeTiling or a RhomBlock "
                       f"assembly (labels are lozenges); use view='3d' for this {type(obj).__name__}")


def _window_lozenges(tiling: LozengeTiling, radius, margin: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Lozenges of a periodic tiling near a square window: rows (i, j, orientation), the centre, the half-width.

    Kept are the lozenges whose centre lies within ``half-width + margin`` of the window's
    centre along both axes.
    """
    periods = tiling.periods @ LATTICE_BASIS
    corners = tiling.polygons()
    centre = corners.reshape(-1, 2).mean(axis=0)
    half = radius if radius is not None else PERIODS_SHOWN * float(np.linalg.norm(periods, axis=1).max())
    reach = math.sqrt(2) * (half + margin) + float(np.linalg.norm(corners - centre, axis=2).max())
    bound = np.ceil(reach * np.linalg.norm(np.linalg.inv(periods), axis=0)).astype(int)
    _check_tile_count(float(np.prod(2 * bound + 1)) * len(tiling))
    k = np.stack(np.meshgrid(*(np.arange(-b, b + 1) for b in bound), indexing="ij"), axis=-1).reshape(-1, 2)
    rows = (tiling.lozenges[None, :, :] + np.pad(k @ tiling.periods, ((0, 0), (0, 1)))[:, None, :]).reshape(-1, 3)
    middles = (corners.mean(axis=1)[None] + (k @ periods)[:, None]).reshape(-1, 2)
    inside = np.all(np.abs(middles - centre) <= half + margin, axis=1)
    return rows[inside], centre, half


# --- 3D view -----------------------------------------------------------------------------------


def _draw_3d(fig, mpl, assembly: Assembly, top: float):
    polygons, normals, owner = _world_facets(assembly)
    lo, hi = polygons.reshape(-1, 3).min(axis=0), polygons.reshape(-1, 3).max(axis=0)
    elev, azim = np.radians(ELEVATION), np.radians(AZIMUTH)
    eye = np.array([math.cos(elev) * math.cos(azim), math.cos(elev) * math.sin(azim), math.sin(elev)])
    visible = normals @ eye > 0
    colours = _block_rgb(assembly)[owner[visible]] * _brightness(normals[visible])[:, None]
    width = float(np.clip(_FACE_EDGE_SCALE / math.sqrt(len(assembly)), *_FACE_EDGE_WIDTH))
    ax = fig.add_axes((0.0, 0.0, 1.0, top), projection="3d")
    ax.add_collection3d(mpl.Poly3DCollection(polygons[visible], facecolors=colours, edgecolors=EDGE_COLOUR,
                                             linewidths=width))
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
    ax.set_proj_type("ortho")
    ax.view_init(elev=ELEVATION, azim=AZIMUTH)
    ax.set_axis_off()
    aspect = hi - lo
    ax.set_box_aspect(aspect)
    ax.set_box_aspect(aspect, zoom=_zoom_to_fit(ax, polygons[visible].reshape(-1, 3)))


def _zoom_to_fit(ax, points: np.ndarray) -> float:
    """The zoom that makes the projected points fill the share ``_FILL`` of the 3D axes' view."""
    homogeneous = ax.get_proj() @ np.column_stack([points, np.ones(len(points))]).T
    projected = homogeneous[:2] / homogeneous[3]
    view = ax.viewLim
    limits = ((view.x0, view.x1), (view.y0, view.y1))
    zoom = min(low / p.min() if p.min() < 0 else np.inf for p, (low, _) in zip(projected, limits))
    zoom = min(zoom, *(high / p.max() if p.max() > 0 else np.inf for p, (_, high) in zip(projected, limits)))
    return _FILL * float(zoom) if np.isfinite(zoom) else 1.0


def _brightness(normals: np.ndarray) -> np.ndarray:
    """Lambert shading: ``a + (1 - a) max(0, n . l)``."""
    return AMBIENT + (1.0 - AMBIENT) * np.clip(normals @ LIGHT, 0.0, None)


def _block_rgb(assembly: Assembly) -> np.ndarray:
    """RGB in [0, 1] per block; frame blocks faded towards grey."""
    rgb = block_colours(assembly)[:, :3] / 255.0
    frame = list(assembly.frame)
    rgb[frame] = (1 - FRAME_FADE) * rgb[frame] + FRAME_FADE * FRAME_GREY
    return rgb


def _world_facets(assembly: Assembly) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every facet of every block in world coordinates: corners (m, k, 3), unit normals (m, 3), block index (m,)."""
    shapes = [_facet_outlines(mesh) for mesh in assembly.meshes]
    width = max(outline.shape[1] for outline, _ in shapes)
    polygons, normals, owner = [], [], []
    for t, (outline, normal) in enumerate(shapes):
        blocks = np.flatnonzero(assembly.types == t)
        if not blocks.size:
            continue
        outline = np.concatenate([outline, np.repeat(outline[:, -1:], width - outline.shape[1], axis=1)], axis=1)
        linear, shift = assembly.transforms[blocks, :3, :3], assembly.transforms[blocks, :3, 3]
        polygons.append((np.einsum("nij,fkj->nfki", linear, outline) + shift[:, None, None, :]).reshape(-1, width, 3))
        normals.append(np.einsum("nij,fj->nfi", linear, normal).reshape(-1, 3))
        owner.append(np.repeat(blocks, len(normal)))
    return np.concatenate(polygons), np.concatenate(normals), np.concatenate(owner)


def _facet_outlines(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """The planar faces of a mesh as corner loops, padded by repeating the last corner, and their unit normals.

    A facet (coplanar adjacent triangles) whose boundary is not one loop, such as a face with
    a hole, is kept as its triangles.
    """
    grouped = np.zeros(len(mesh.faces), dtype=bool)
    groups = []
    for facet in mesh.facets:
        grouped[facet] = True
        groups.append(facet)
    groups += [[f] for f in np.flatnonzero(~grouped)]
    loops, normals = [], []
    for faces in groups:
        loop = _boundary_loop(mesh.faces[faces])
        pieces = [loop] if loop is not None else list(mesh.faces[faces])
        loops += pieces
        normals += [mesh.face_normals[faces[0]]] * len(pieces) if loop is not None else list(mesh.face_normals[faces])
    width = max(len(loop) for loop in loops)
    padded = np.array([list(loop) + [loop[-1]] * (width - len(loop)) for loop in loops])
    return mesh.vertices[padded], np.asarray(normals, dtype=float)


def _boundary_loop(triangles: np.ndarray) -> list[int] | None:
    """The boundary of a patch of consistently wound triangles as one vertex loop, or None if it is not one loop."""
    directed = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).tolist()
    inner = {tuple(edge) for edge in directed}
    following = {}
    for a, b in directed:
        if (b, a) not in inner:
            if a in following:
                return None
            following[a] = b
    start = next(iter(following))
    loop = [start]
    while following[loop[-1]] != start and len(loop) <= len(following):
        loop.append(following[loop[-1]])
    return loop if len(loop) == len(following) else None


# --- tiling views ------------------------------------------------------------------------------


def _draw_block_tilings(fig, mpl, block: Block, radius, top: float):
    group = block.group
    if radius is None:
        radius = TILING_CELLS * float(np.linalg.norm(group.lattice, axis=1).max())
    bottom = np.asarray(block.bottom.exterior.coords)[:-1]
    topside = np.asarray(block.top.exterior.coords)[:-1]
    centre = bottom.mean(axis=0)
    # Tiles meeting the window's circumscribed disc, widened by how far F' reaches from F, cover the window.
    disc = math.sqrt(2) * radius + 2 * _reach(block)
    _check_tile_count(math.pi * disc**2 / block.bottom.area)
    assembly = patch(block, disc, center=centre)
    classes, _ = block_classes(assembly)
    matrices = group.matrices(assembly.labels)
    colours = PALETTE[classes % len(PALETTE)] / 255.0
    window = (centre - radius, centre + radius)
    for k, (domain, name) in enumerate(((bottom, "F (bottom)"), (topside, "F' (top)"))):
        tiles = np.einsum("nij,vj->nvi", matrices[:, :2, :2], domain) + matrices[:, None, :2, 2]
        ax = fig.add_axes((0.5 * k + 0.01, 0.02, 0.48, top - 0.1))
        _draw_polygons(ax, mpl, tiles, colours, window)
        ax.plot(*np.vstack([domain, domain[:1]]).T, color=EDGE_COLOUR, linewidth=_DOMAIN_EDGE_WIDTH)
        ax.set_title(f"tiling by {name}", fontsize="small")


def _reach(block: Block) -> float:
    """The largest distance of a corner of F or F' from the centre of F's corners."""
    bottom = np.asarray(block.bottom.exterior.coords)[:-1]
    corners = np.vstack([bottom, np.asarray(block.top.exterior.coords)[:-1]])
    return float(np.linalg.norm(corners - bottom.mean(axis=0), axis=1).max())


def _check_tile_count(estimate: float):
    if estimate > MAX_TILES:
        raise GalleryError(f"radius too large: about {estimate:.0f} tiles or blocks to draw, more than "
                           f"MAX_TILES = {MAX_TILES}; choose a smaller radius")


def _draw_lozenges(fig, mpl, tiling: LozengeTiling, radius, top: float):
    if tiling.is_periodic:
        rows, centre, half = _window_lozenges(tiling, radius, margin=1.0)
        tiling, window = LozengeTiling(rows), (centre - half, centre + half)
    else:
        corners = tiling.polygons().reshape(-1, 2)
        window = (corners.min(axis=0), corners.max(axis=0))
    ax = fig.add_axes((0.02, 0.02, 0.96, top - 0.04))
    _draw_polygons(ax, mpl, tiling.polygons(), PALETTE[tiling.lozenges[:, 2] % len(PALETTE)] / 255.0, window)


def _draw_polygons(ax, mpl, polygons: np.ndarray, colours: np.ndarray, window):
    ax.add_collection(mpl.PolyCollection(polygons, facecolors=colours, edgecolors=EDGE_COLOUR,
                                         linewidths=_TILE_EDGE_WIDTH))
    (x0, y0), (x1, y1) = window
    ax.set(xlim=(x0, x1), ylim=(y0, y1))
    ax.set_aspect("equal")
    ax.set_axis_off()
