"""The gallery: generated, verified and exported assemblies with pictures and an offline index page."""

from __future__ import annotations

import glob
import hashlib
import json
import math
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

import interlock
from interlock import wallpaper
from interlock.blocks import (Assembly, cell_patch, escher_block, patch, periodic_cell, presets, random_hexagon,
                              rhomblock, rhomblock_assembly, staircase)
from interlock.blocks.escher import Block, DeformationError
from interlock.errors import GalleryError
from interlock.files import PARTIAL, replace_folder, unwritable, write_atomically
from interlock.formats import write
from interlock.gallery.appearance import exploded
from interlock.gallery.motion import export_motion
from interlock.gallery.page import finite_word, write_index
from interlock.gallery.render import render
from interlock.gallery.view.scene import scene
from interlock.verify import check, criterion_4_3, periodic_check
from interlock.verify.check import beyond_first_order
from interlock.verify.contacts import model_contacts

__all__ = ["Claim", "Entry", "EntryResult", "Gallery", "entries", "build", "finite_word", "ESCHER_GROUPS",
           "REFLECTION_GROUPS", "MOTION_FRAMES", "MANIFEST"]

#: Escher blocks with rotations only (main paper Sec. 3.2, Fig. 1 and Fig. 5).
ESCHER_GROUPS = ("p1", "p2", "p3", "p4", "p6")
#: Escher blocks of groups with reflections or glides; mirror edges stay straight.
REFLECTION_GROUPS = ("pm", "pg", "cm", "pmg", "pgg")
#: Pictures of a finite motion shown (order 2), from its start to its last step.
MOTION_FRAMES = 4
#: The file that makes a folder a gallery: interlock's version, the seed, the entries and every file's SHA-256.
MANIFEST = "manifest.json"


@dataclass(frozen=True)
class Claim:
    """What the paper proves about an entry, and how to read it off the entry's record.

    ``test(record)`` is True when the record agrees, False when it contradicts
    the statement, and None when the record cannot say (e.g. an inconclusive verdict).
    """

    source: str
    statement: str
    test: Callable[[dict], bool | None]


@dataclass(frozen=True)
class Entry:
    """One gallery entry, not yet built: how to make its objects and what the paper says about them.

    ``make()`` returns a dict with ``block`` (a Block or a mesh: the single
    block), ``assembly`` (finite, with its frame), optionally ``cell`` (a
    periodic cell) and ``tiling`` (a Block or a LozengeTiling for the 2D picture),
    and ``parameters`` (JSON-ready).
    """

    name: str
    title: str
    kind: str
    make: Callable[[], dict]
    claims: tuple[Claim, ...] = ()
    translational: bool = False


@dataclass(frozen=True)
class EntryResult:
    """A built entry: its JSON record, the files written (relative to the gallery folder), any contradictions, and
    the scene of its 3D view."""

    name: str
    record: dict
    files: dict
    contradictions: tuple[str, ...] = ()
    scene: dict | None = field(default=None, repr=False, compare=False)  # the 3D view's (interlock.gallery.view)


@dataclass(frozen=True)
class Gallery:
    """The built gallery: its folder, entries, the index page and every contradiction with the paper."""

    folder: Path
    entries: tuple[EntryResult, ...]
    index: Path
    seconds: float
    contradictions: tuple[str, ...] = field(default=())


def entries(quick: bool = False, seed: int = 0) -> tuple[Entry, ...]:
    """The gallery's entries: Escher blocks, the paper's presets and RhomBlock assemblies.

    ``quick`` keeps one small entry of each kind (for tests); ``seed`` fixes
    the random deformations and random lozenge tilings.

    >>> [e.name for e in entries(quick=True)]
    ['escher-p4', 'escher-p1', 'ex3.5-cube-grid', 'rhomblock-hexagon-3x3x3-v0', 'rhomblock-staircase-1-1-0-v1']
    """
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise GalleryError(f"seed must be an integer >= 0, got {seed!r}")
    if quick:
        return (_escher("p4", seed, radius=1.0), _escher("p1", seed, radius=1.0), _cube_grid(),
                _hexagon((3, 3, 3), 0, seed), _staircase((1, 1, 0), 1))
    out = [_escher(name, seed) for name in ESCHER_GROUPS]
    out += [_escher(name, seed) for name in REFLECTION_GROUPS]
    out += [_undeformed("p4"), _fig1(), _cube_grid(), _tilted_cubes(), _tetrahedra(),
            _tetrahedra_layer("p3", True, "Fig. 5b"), _tetrahedra_layer("p6", False, "Fig. 5c (this package's slopes)"),
            _honeycomb(), _modified_cubes()]
    out += [_hexagon(size, variant, seed) for size in ((4, 4, 4), (8, 8, 8), (20, 20, 20)) for variant in (0, 1)]
    out += [_staircase(counts, variant) for counts in ((1, 0, 0), (1, 1, 0), (2, 1, 1)) for variant in (0, 1)]
    return tuple(out)


def build(folder, quick: bool = False, seed: int = 0, names=None, progress=None) -> Gallery:
    """Generate, verify, export and draw every entry into ``folder``, and write ``index.html``.

    Per entry ``NAME``: ``NAME/block.stl`` (the single block), ``NAME/assembly.stl``,
    ``NAME/exploded.stl``, ``NAME/assembly.glb`` (coloured by orientation or coset),
    ``NAME/block.png``, ``NAME/assembly.png``, ``NAME/exploded.png``,
    ``NAME/tiling.png`` (where there is a tiling) and ``NAME/record.json`` with
    the parameters, the finite verdict with its frame, the periodic verdict
    (where there is a cell), Criterion 4.3 (Escher blocks), the paper's claims
    with whether the verdicts agree, and timings.  :data:`MANIFEST` names
    interlock's version, the seed, the entries and the SHA-256 of every file;
    ``index.html`` is written from the records last: a table of contents, the
    legend, and per entry its verdict in one plain sentence, an interactive 3D
    view (:mod:`interlock.gallery.view`, loaded as it scrolls into sight), the
    pictures (click to enlarge) and the files.

    The gallery is built in a new folder beside ``folder`` and put in its
    place only when complete (:func:`interlock.files.replace_folder`), so a
    run that is stopped leaves the previous gallery whole, and a gallery
    never mixes the files of two runs.

    Parameters
    ----------
    folder : path
        Created if missing; an existing folder must be empty or a gallery
        (it holds :data:`MANIFEST`), and is replaced as a whole.
    quick, seed : see :func:`entries`.
    names : iterable of str, optional
        Build only these entries.
    progress : callable, optional
        Called as ``progress(entry_name)`` after each entry.

    Returns
    -------
    Gallery
        ``contradictions`` lists every claim a verdict contradicts; a correct
        package leaves it empty.

    Raises
    ------
    GalleryError
        An unknown entry name, a seed that is not an integer >= 0, or a
        folder that cannot be created or is neither empty nor a gallery.

    Examples
    --------
    >>> import tempfile
    >>> g = build(tempfile.mkdtemp(), quick=True, names=["escher-p4"])
    >>> g.entries[0].record["periodic"]["status"], g.contradictions
    ('interlocked', ())
    >>> json.loads((g.folder / MANIFEST).read_text())["entries"]
    ['escher-p4']
    """
    start = time.perf_counter()
    folder = _folder(folder)
    chosen = entries(quick, seed)
    if names is not None:
        wanted = list(names)
        known = {e.name for e in chosen}
        unknown = [n for n in wanted if n not in known]
        if unknown:
            raise GalleryError(f"unknown gallery entries {unknown}; known: {sorted(known)}")
        chosen = [e for e in chosen if e.name in wanted]
    for stale in folder.parent.glob(f".{glob.escape(folder.name)}.*{PARTIAL}"):  # left by a run that was stopped
        shutil.rmtree(stale, ignore_errors=True)
    building = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=PARTIAL, dir=folder.parent))
    os.chmod(building, 0o777 & ~_umask())  # a new folder as any other, not mkdtemp's 0700
    try:
        results = []
        for entry in chosen:
            results.append(_build_entry(entry, building, seed))
            if progress is not None:
                progress(entry.name)
        _write_manifest(building, results, quick, seed)
        write_index(building, results, quick, seed)
        replace_folder(building, folder)
    except BaseException:
        shutil.rmtree(building, ignore_errors=True)
        raise
    contradictions = tuple(c for r in results for c in r.contradictions)
    return Gallery(folder, tuple(results), folder / "index.html", time.perf_counter() - start, contradictions)


# --- entries --------------------------------------------------------------------------------------


def _record_value(record: dict, *keys):
    for key in keys:
        if record is None:
            return None
        record = record.get(key)
    return record


def _finite_not_moving(source: str) -> Claim:
    # a motion of the free blocks with the ring fixed is a finite-support motion of the infinite assembly
    return Claim(source, "no motion of the free blocks of the patch with its ring fixed",
                 lambda r: None if r["finite"]["interlocked"] is None else r["finite"]["interlocked"] is not False)


def _periodic_is(status: str, source: str, key: str = "periodic") -> Claim:
    return Claim(source, f"the infinite assembly is {status}" + (" (translations)" if "translational" in key else ""),
                 lambda r: None if _record_value(r, key, "status") in (None, "inconclusive")
                 else _record_value(r, key, "status") == status)


def _finite_is(interlocked: bool, source: str) -> Claim:
    word = "interlocked" if interlocked else "not interlocked"
    return Claim(source, f"the finite assembly with its frame is {word}", lambda r: _finite_verdict(r, interlocked))


def _finite_verdict(record: dict, interlocked: bool) -> bool | None:
    """Whether the record settles the finite assembly as ``interlocked``: first order proves "interlocked";
    only a finite motion shown (order 2) proves "not interlocked"."""
    settled = record["finite"]["interlocked"]
    if settled is not True:
        settled = _record_value(record, "beyond", "interlocked")
    return None if settled is None else settled is interlocked


def _no_sliding_iff_criterion() -> Claim:
    return Claim("Prop. 4.6", "the infinite matrix has no kernel (full generic rank) iff Criterion 4.3 holds",
                 lambda r: None if r["criterion_4_3"]["holds"] is None else
                 (r["periodic"]["generic_rank"] == r["periodic"]["columns"]) == r["criterion_4_3"]["holds"])


def _deformation(group, rng) -> dict:
    """One or two points pushed off every deformable edge (one per pair), a valid block's deformation."""
    corners = np.asarray(group.fundamental_domain().exterior.coords)
    for _ in range(100):
        deformation = {}
        for s in group.side_pairings():
            if s.partner < s.edge or s.self_paired:
                continue
            p, q = corners[s.edge], corners[s.edge + 1]
            normal = np.array([q[1] - p[1], p[0] - q[0]])
            m = int(rng.integers(1, 3))
            along = (np.arange(1, m + 1) + rng.uniform(-0.25, 0.25, m)) / (m + 1)
            side = rng.choice([-1.0, 1.0])
            deformation[s.edge] = p + along[:, None] * (q - p) + side * rng.uniform(0.06, 0.16, (m, 1)) * normal
        try:
            escher_block(group, deformation)
        except DeformationError:
            continue
        return {e: points.tolist() for e, points in deformation.items()}
    raise GalleryError(f"no valid random deformation of {group.name} found; try another seed")


def _escher(name: str, seed: int, radius: float = 2.0) -> Entry:
    def make():
        group = wallpaper.group(name)
        stream = (ESCHER_GROUPS + REFLECTION_GROUPS).index(name)  # each group its own random stream
        deformation = _deformation(group, np.random.default_rng([seed, stream]))
        block = escher_block(group, deformation)
        unit = math.sqrt(group.cell_area)
        return {"block": block, "assembly": patch(block, radius * unit, frame="boundary"),
                "cell": periodic_cell(block), "tiling": block,
                "parameters": {"group": name, "deformation": deformation, "height": block.height,
                               "patch_radius_cells": radius, "frame": "outer ring", "seed": seed}}

    claims = [_finite_not_moving("Cor. 4.8 with the periodic verdict"), _no_sliding_iff_criterion()]
    if name == "p1":
        claims.append(Claim("Thm. 4.7", "translationally interlocked iff Criterion 4.3 holds",
                            lambda r: None if r["periodic_translational"]["status"] == "inconclusive"
                            or r["criterion_4_3"]["holds"] is None else
                            (r["periodic_translational"]["status"] == "interlocked") == r["criterion_4_3"]["holds"]))
    title = f"{name}: Escher block, every deformable edge deformed"
    return Entry(f"escher-{name}", title, "escher", make, tuple(claims), translational=name == "p1")


def _undeformed(name: str) -> Entry:
    def make():
        block = escher_block(wallpaper.group(name), {})
        return {"block": block, "assembly": patch(block, 1.5, frame="boundary"), "cell": periodic_cell(block),
                "tiling": block, "parameters": {"group": name, "deformation": {}, "frame": "outer ring"}}

    claims = (Claim("Criterion 4.3", "Criterion 4.3 fails: a finite set H of blocks lifts out",
                    lambda r: r["criterion_4_3"]["holds"] is False),
              _periodic_is("not interlocked", "Criterion 4.3 (H lifts out)"), _no_sliding_iff_criterion(),
              _finite_is(False, "Criterion 4.3 (H lifts out)"))
    return Entry(f"escher-{name}-undeformed", f"{name}: undeformed prisms (Criterion 4.3 fails)", "escher", make,
                 claims)


def _fig1() -> Entry:
    def make():
        block = presets.fig1_p6_block()
        return {"block": block, "assembly": patch(block, 1.5, frame="boundary"), "cell": periodic_cell(block),
                "tiling": block, "parameters": {"preset": "fig1_p6_block", "frame": "outer ring"}}

    return Entry("fig1-p6", "Fig. 1: the paper's p6 block", "preset", make,
                 (_finite_not_moving("Cor. 4.8 with the periodic verdict"), _no_sliding_iff_criterion()))


def _cube_grid() -> Entry:
    def make():
        grid = presets.cube_grid()
        return {"block": grid.mesh(0), "assembly": grid, "cell": presets.cube_grid_cell(),
                "parameters": {"preset": "cube_grid", "rows": 3, "cols": 3, "frame": "outer ring"}}

    return Entry("ex3.5-cube-grid", "Ex. 3.5: a grid of cubes slides", "preset", make,
                 (_finite_is(False, "Ex. 3.5"), _periodic_is("not interlocked", "Ex. 3.5")))


def _tilted_cubes() -> Entry:
    def make():
        layer = presets.interlocking_cubes()
        return {"block": layer.mesh(0), "assembly": layer, "cell": presets.interlocking_cubes_cell(),
                "parameters": {"preset": "interlocking_cubes", "rows": 3, "cols": 3, "frame": "outer ring"}}

    return Entry("ex3.6-tilted-cubes", "Ex. 3.6: the tilted cube layer interlocks", "preset", make,
                 (_finite_is(True, "Ex. 3.6"), _periodic_is("interlocked", "Ex. 3.6")))


def _tetrahedra() -> Entry:
    def make():
        layer = presets.tetrahedra("p4", radius=1.5)  # the frame of Fig. 5a
        return {"block": layer.mesh(0), "assembly": layer,
                "parameters": {"preset": "tetrahedra", "symmetry": "p4", "radius": 1.5,
                               "frame": "outer ring and one orientation class (Fig. 5a, red)"}}

    return Entry("fig5a-tetrahedra", "Fig. 5a: tetrahedra with a p4 frame", "preset", make,
                 (_finite_is(True, "Fig. 5a"),))


def _tetrahedra_layer(symmetry: str, interlocked: bool, source: str) -> Entry:
    """Fig. 5b/5c: a layer of tetrahedra with the outer ring as frame, held (or not) by edge-to-edge contacts."""
    def make():
        layer = presets.tetrahedra(symmetry, radius=1.5)
        return {"block": layer.mesh(0), "assembly": layer,
                "parameters": {"preset": "tetrahedra", "symmetry": symmetry, "radius": 1.5,
                               "frame": "outer ring", "contacts": "every type (Remark 3.11)"}}

    figure = {"p3": "5b", "p6": "5c"}[symmetry]
    return Entry(f"fig{figure}-tetrahedra", f"Fig. {figure}: tetrahedra with {symmetry} symmetry, outer ring fixed",
                 "preset", make, (_finite_is(interlocked, source),))


def _honeycomb() -> Entry:
    def make():
        layer = presets.honeycomb_layer(1.5)
        return {"block": layer.mesh(0), "assembly": layer,
                "parameters": {"preset": "honeycomb_layer", "radius": 1.5, "frame": "outer ring",
                               "contacts": "every type (Remark 3.11)"}}

    return Entry("honeycomb-layer", "A layer of the tetrahedral-octahedral honeycomb, outer ring fixed", "preset",
                 make, (_finite_is(False, "tet-oct honeycomb layer cut along its planes"),))


def _modified_cubes() -> Entry:
    def make():
        a = presets.modified_cube_assembly()
        return {"block": presets.modified_cube(), "assembly": a,
                "parameters": {"preset": "modified_cube_assembly", "rows": 4, "cols": 4, "frame": "outer ring"}}

    return Entry("fig7-modified-cubes", "Fig. 6/7: modified cubes, four move together", "preset", make,
                 (_finite_is(False, "Fig. 7"),))


def _hexagon(size, variant: int, seed: int) -> Entry:
    a, b, c = size

    def make():
        tiling = random_hexagon(a, b, c, seed=seed)
        return {"block": rhomblock(), "assembly": rhomblock_assembly(tiling, variant, frame="boundary"),
                "tiling": tiling, "parameters": {"hexagon": [a, b, c], "variant": variant, "seed": seed,
                                                 "frame": "outer ring"}}

    return Entry(f"rhomblock-hexagon-{a}x{b}x{c}-v{variant}",
                 f"RhomBlocks on a random {a}x{b}x{c} hexagon, variant {variant}", "rhomblock", make,
                 (_finite_not_moving("Thm. 4.9 (the tiling extends to the plane)"),))


def _staircase(counts, variant: int) -> Entry:
    def make():
        tiling = staircase(counts)
        cell = rhomblock_assembly(tiling, variant)
        return {"block": rhomblock(), "assembly": cell_patch(cell, 2), "cell": cell, "tiling": tiling,
                "parameters": {"staircase": list(counts), "variant": variant, "patch_radius_cells": 2,
                               "frame": "ring of cell translates"}}

    label = "-".join(map(str, counts))
    return Entry(f"rhomblock-staircase-{label}-v{variant}",
                 f"RhomBlocks on the periodic staircase {tuple(counts)}, variant {variant}", "rhomblock", make,
                 (_periodic_is("interlocked", "Thm. 4.9"), _finite_not_moving("Thm. 4.9")))


# --- building -------------------------------------------------------------------------------------


def _folder(folder) -> Path:
    """The gallery folder, absolute; created if missing (the folder above it must exist), else checked to be empty
    or a gallery."""
    try:
        folder = Path(folder).resolve()
        problem = unwritable(folder, folder_output=True)
        if problem:
            raise GalleryError(f"cannot write the gallery {folder}: {problem}")
        folder.mkdir(exist_ok=True)
        contents = [p.name for p in folder.iterdir()]
    except OSError as error:
        raise GalleryError(f"cannot create the gallery folder {folder}: {error.strerror or error}") from None
    except TypeError:
        raise GalleryError(f"the gallery folder must be a path, got {type(folder).__name__}") from None
    if contents and MANIFEST not in contents:
        raise GalleryError(f"{folder} holds other files ({', '.join(sorted(contents)[:3])}, ...) and no {MANIFEST}: "
                           "a gallery replaces its folder as a whole, so give an empty or new folder")
    if not os.access(folder.parent, os.W_OK):
        raise GalleryError(f"cannot build the gallery beside {folder}: the folder {folder.parent} is not writable")
    return folder


def _write_manifest(folder: Path, results, quick: bool, seed: int) -> Path:
    """:data:`MANIFEST`: what was built, by which version and seed, and each file's SHA-256."""
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    manifest = {"interlock": interlock.__version__, "seed": seed, "quick": quick,
                "entries": [r.name for r in results],
                "files": {_relative(p, folder): hashlib.sha256(p.read_bytes()).hexdigest() for p in files}}
    return write_atomically(folder / MANIFEST, json.dumps(manifest, indent=1))


def _build_entry(entry: Entry, folder: Path, seed: int) -> EntryResult:
    timings = {}
    clock = time.perf_counter()
    made = entry.make()
    timings["generate"] = time.perf_counter() - clock
    assembly: Assembly = made["assembly"]
    record = {"name": entry.name, "title": entry.title, "kind": entry.kind, "parameters": made["parameters"],
              "blocks": len(assembly), "frame": list(assembly.frame)}

    clock = time.perf_counter()
    found = model_contacts(assembly)  # of every type (Remark 3.11), as check finds them
    first = check(assembly, validate=False, contacts=found)
    record["finite"] = first.to_dict()
    timings["finite_verdict"] = time.perf_counter() - clock
    beyond = record["beyond"] = None  # a first-order motion taken to second order and tried as a finite one
    if first.interlocked is not True:
        clock = time.perf_counter()
        beyond = beyond_first_order(assembly, first, contacts=found)
        record["beyond"] = beyond.to_dict()
        timings["beyond_first_order"] = time.perf_counter() - clock
    record["periodic"] = record["periodic_translational"] = record["criterion_4_3"] = None
    if "cell" in made:
        clock = time.perf_counter()
        record["periodic"] = periodic_check(made["cell"]).to_dict()
        if entry.translational:
            record["periodic_translational"] = periodic_check(made["cell"], translational=True).to_dict()
        timings["periodic_verdict"] = time.perf_counter() - clock
    if isinstance(made["block"], Block):
        record["criterion_4_3"] = criterion_4_3(made["block"]).to_dict()

    directory = folder / entry.name
    directory.mkdir(exist_ok=True)
    clock = time.perf_counter()
    spread = 0.6 if entry.kind != "rhomblock" else 0.35
    files = {"block.stl": made["block"], "assembly.stl": assembly, "assembly.glb": assembly}
    written = {name: _relative(write(obj, directory / name), folder) for name, obj in files.items()}
    written["exploded.stl"] = _relative(write(exploded(assembly, spread), directory / "exploded.stl"), folder)
    timings["export"] = time.perf_counter() - clock

    clock = time.perf_counter()
    pictures = {"block.png": (made["block"], {}), "assembly.png": (assembly, {}),
                "exploded.png": (assembly, {"exploded": spread})}
    if "tiling" in made:
        wide = isinstance(made["tiling"], Block)  # two panels: the tilings by F and by F' (Fig. 1)
        pictures["tiling.png"] = (made["tiling"], {"view": "tiling", "size": (10.0, 5.0) if wide else (6.0, 6.0)})
    for name, (obj, options) in pictures.items():
        written[name] = _relative(render(obj, directory / name, title=None, **options), folder)
    if beyond is not None and beyond.finite_motion is not None and beyond.finite_motion.shown:
        frames = export_motion(assembly, beyond.finite_motion, directory / "motion", frames=MOTION_FRAMES,
                               format="png")
        written.update({f"motion {k}.png": _relative(path, folder) for k, path in enumerate(frames)})
    timings["render"] = time.perf_counter() - clock

    clock = time.perf_counter()
    ring = {"outer ring": "the outer ring", "ring of cell translates": "the ring of cell translates"}
    view = scene(assembly, beyond if beyond is not None else first, title=entry.title, contacts=found,
                 frame_words=ring.get(made["parameters"].get("frame")))
    record["sentence"] = view["sentence"]
    timings["view"] = time.perf_counter() - clock

    claims, contradictions = [], []
    for claim in entry.claims:
        holds = claim.test(record)
        claims.append({"source": claim.source, "statement": claim.statement, "holds": holds})
        if holds is False:
            contradictions.append(f"{entry.name}: contradicts {claim.source}: {claim.statement}")
    record["claims"] = claims
    record["timings"] = timings
    record["files"] = dict(written)
    record_path = write_atomically(directory / "record.json", json.dumps(record, indent=1, default=_json_default))
    written["record.json"] = _relative(record_path, folder)
    return EntryResult(entry.name, record, written, tuple(contradictions), view)


def _relative(path, folder: Path) -> str:
    return Path(path).relative_to(folder).as_posix()


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
