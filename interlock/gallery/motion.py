"""Pictures and files of a finite motion: the assembly at evenly spaced steps of a :class:`FiniteMotion`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.formats import write
from interlock.gallery.render import render
from interlock.verify.motion import FiniteMotion, MotionError, moved

__all__ = ["export_motion", "FRAME_FORMATS"]

#: What :func:`export_motion` writes: the mesh formats of :func:`interlock.write`, and PNG pictures.
FRAME_FORMATS = ("stl", "obj", "ply", "glb", "3mf", "vtu", "xdmf", "png")


def export_motion(assembly: Assembly, result: FiniteMotion, folder, frames: int = 8, format: str = "stl") -> list[Path]:
    """Write the assembly at ``frames`` evenly spaced parameters of a :class:`FiniteMotion`, one file per frame.

    ``assembly`` is the one the motion was found for (the result's own, or
    one with the same blocks, such as a re-loaded copy).
    Frames run from the start of the motion to its last measured step (the
    collision, when there was one).  Mesh formats go through
    :func:`interlock.write` (one file holding every block, which
    loads back block by block; colours where the format has them), ``"png"``
    through :func:`~interlock.gallery.render.render` (needs matplotlib:
    ``pip install "interlock[plot]"``, else a :class:`~interlock.errors.GalleryError`).
    Files are ``frame_000.<format>``, ...; the folder is created.

    Examples
    --------
    >>> import tempfile, trimesh
    >>> import interlock
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.motion import finite_motion
    >>> cubes = Assembly.from_meshes([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(2)])
    >>> result = finite_motion(cubes, [[0, 0, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0]], frame=[0])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     paths = export_motion(cubes, result, folder, frames=3)
    ...     [p.name for p in paths], len(interlock.read(paths[-1]))
    (['frame_000.stl', 'frame_001.stl', 'frame_002.stl'], 2)
    """
    if not isinstance(result, FiniteMotion) or result.path is None:
        raise MotionError(f"export_motion needs the FiniteMotion of finite_motion, got {type(result).__name__}")
    if not isinstance(assembly, Assembly) or len(assembly) != len(result.path(result.start)):
        got = f"{len(assembly)} blocks" if isinstance(assembly, Assembly) else type(assembly).__name__
        raise MotionError(f"export_motion needs the Assembly of the motion ({len(result.path(result.start))} blocks), "
                          f"got {got}")
    if isinstance(frames, (bool, np.bool_)) or not isinstance(frames, (int, np.integer)) or frames < 1:
        raise MotionError(f"frames must be an integer >= 1, got {frames!r}")
    kind = str(format).lower().lstrip(".")
    if kind not in FRAME_FORMATS:
        raise MotionError(f"unknown frame format {format!r}; choose one of {', '.join(FRAME_FORMATS)}")
    folder = Path(folder)
    try:
        folder.mkdir(exist_ok=True)  # as every output: created, but never the missing folders above it
    except OSError as error:
        raise MotionError(f"cannot create the folder {folder}: {error.strerror or error}") from None
    last = result.parameters[-1] if result.parameters else result.start
    written = []
    for k, s in enumerate(np.linspace(result.start, last, frames) if frames > 1 else [last]):
        target = folder / f"frame_{k:03d}.{kind}"
        at = moved(assembly, result.path, float(s))
        written.append(render(at, target, title=f"s = {s:.4g}") if kind == "png" else write(at, target))
    return written
