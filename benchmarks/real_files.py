"""Verdicts on real files: peer assemblies placed at random and passed through what files do to coordinates.

Subjects are the peer data kept with the tests and beside the project
(``tests/data/README.md``, ``../shared/data/README.md``), each with the frames
whose truth is known:

- the TopoLite bunny (80 parts): frame {0, 1} interlocked; {0} and {1} not
  (a part comes out);
- the TopoLite cube (9 parts, a 4 x 4 x 4 voxel puzzle): frame {0, 8}
  interlocked, {8} not (part 0 comes out);
- TopoLite's interlocking shells (``topolite_ti``), frame = the bodies of
  ``Boundary.obj``: ``SphereA80_Hex_T40.0`` and ``tube`` not interlocked (a
  finite motion exists); ``origin`` (and ``chips``, ``--large``) have no known
  full verdict, so their answers are reported but not judged;
- the GeoCombSurfX patches (``geocombsurfx_jl``, nine blocks each), frame =
  blocks 1-8: interlocked (all nine files).

Each subject is placed ``--placements N`` times (a random rotation and a
translation of 1 to 300 model sizes in a random direction, seeded numpy
``Generator``) and then perturbed by each *family*:

- ``float64``: the placement alone (a control: rigid motions must not change
  a verdict);
- ``float32 STL`` / ``PLY`` / ``GLB``: written with
  :func:`interlock.write` and read back with
  :func:`interlock.read` (32-bit coordinates; interlock's PLY holds doubles,
  so for PLY the vertices are rounded to float32 first, as other tools'
  PLY files hold them);
- ``4`` / ``6`` / ``7 digits``: an OBJ file with one object per block and
  coordinates printed ``%.4g`` (``%.6g``, ``%.7g``), read back;
- ``noise 1e-9`` / ``1e-7`` / ``1e-5``: Gaussian noise of that fraction of
  the model size on every vertex (a vertex shared by triangles of one block
  moves once);
- ``re-triangulated (centroids)`` / ``(edges)``: a third of each block's
  triangles fanned from their centroid, or a third of its edges split at
  their midpoint (both triangles beside it split in two); the geometry does
  not move.

Measured per case: ``check(assembly, frame, time_limit=120)``'s answer and
time, the tolerance the verdict states and its source
(``tolerances["tolerance"]``, ``["tolerance_from"]``, ``margin``), and the
class: *right*, *wrong* (True or False against the reference), *inconclusive*
(None), *refused* (an ``InterlockError``), *crashed* (any other exception: a
defect of the library), or *unjudged* (decided, but the subject has no known
verdict).  The reference is the known verdict of the
READMEs, else the float64 original's ``check``.

Perturbation ``p`` (a length): float32 rounding ``2^-24 max|x|``, half the last
printed digit of ``max|x|``, the noise amplitude, and for re-triangulation
and float64 the float64 rounding ``2^-53 max|x|``.  The original's *reach*
(a length) is, for an interlocked original, its margin ``rho`` times the
tolerance ``t`` = 1e-6 of the model size (how far contact vertices may move
and the answer stand; ``rho`` from the per-coordinate LPs, :func:`exact_margin`,
not the lower bound ``check`` proves, which stops once it exceeds 1); for one that is not,
how far its motion moves the blocks before they collide
(:func:`interlock.verify.motion.finite_motion` along the reported motion: the
largest vertex displacement of the steps before the first overlap; it stops
at 10 % of the model size, or where the moving blocks are clear).
The *band* holds the cases with ``reach >= 10 p``; the share of them that
came back inconclusive, "not interlocked within tolerance", refused or
crashed is the *declined share*.  Where the margin's lower bound is loose
(the bunny's is 0), the band is also given with the margin's upper bound
(``declined_in_upper_band``; not proved, a motion attains it).
``within_tolerance_in_band`` is the part of the band answered "not
interlocked within tolerance" (a motion within tolerance that no finite motion
showed: "not interlocked (finite motion shown)" is decided): right where the
original is not interlocked, but counted as declined, as issue 35 counts it.  Targets (issue 35): 0 wrong, at most 10 % declined in the band, 0
refused for re-triangulation.

Reading the chart: one bar per family, stacked by class (green right, red
wrong, grey inconclusive, white refused, black crashed, blue unjudged); the black marker
and the right axis give the declined share in the band (the dashed line is
the 10 % target), the label under each bar the median time of ``check``.

A full run takes about six minutes a placement on one core; ``--shard K N``
runs the placements ``p % N == K`` (one process per core), and ``--merge N``
writes ``real_files.json`` and its chart from the N parts.

A case is rebuilt for reproduction with
``perturbed(subject, placement, family)``, e.g.
``check(perturbed("bunny", 0, "4 digits"), frame=(1,))``.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import tempfile
import time
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np
import scipy.optimize
import trimesh
from scipy.spatial.transform import Rotation

from benchmarks.common import (REFERENCE_DATA, add_arguments, pyplot, results_folder, save_chart, use_results_folder,
                               write_json)
import interlock
from interlock.blocks import Assembly
from interlock.errors import InterlockError
from interlock.verify import check
from interlock.verify.contacts import model_contacts
from interlock.verify.margin import row_tolerances
from interlock.verify.matrix import interlocking_matrix
from interlock.verify.motion import OVERLAP_RTOL, finite_motion

#: The peer data beside the project (``../shared/data``).
SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
#: Placements of the full run and of ``--quick``.
PLACEMENTS = 20
QUICK_PLACEMENTS = 3
#: Seed of the placements and perturbations (numpy Generator).
SEED = 35
#: Translations of a placement: 10**U(0, MAX_SHIFT_DECADES) model sizes, in a random direction.
MAX_SHIFT_DECADES = 2.5
#: Seconds ``check`` may take per case.
TIME_LIMIT = 120.0
#: The tolerance (relative to the model size) at which the original's margin is measured (its reach is rho t).
REACH_TOLERANCE = 1e-6
#: A case is in the band when the original's reach is at least this many perturbations.
BAND_FACTOR = 10.0
#: Share of the triangles (edges) re-triangulated per block.
RETRIANGULATED = 1.0 / 3.0
FAMILIES = ("float64", "float32 STL", "float32 PLY", "float32 GLB", "4 digits", "6 digits", "7 digits",
            "noise 1e-9", "noise 1e-7", "noise 1e-5", "re-triangulated (centroids)", "re-triangulated (edges)")
QUICK_FAMILIES = FAMILIES
CLASSES = ("right", "wrong", "inconclusive", "refused", "crashed", "unjudged")
COLOURS = {"right": "#4daf4a", "wrong": "#e41a1c", "inconclusive": "#bdbdbd", "refused": "#ffffff",
           "crashed": "#000000", "unjudged": "#377eb8"}
GEOCOMB_QUICK = ("[-05,05]", "[025,025]")


# --- subjects --------------------------------------------------------------------------------------


def _topolite_ti(model: str) -> Assembly:
    """A TopoLite shell: ``Part_NN.obj`` then the bodies of ``Boundary.obj`` (the frame, last)."""
    folder = SHARED_DATA / "topolite_ti" / model / "PartGeometry"
    parts = interlock.read(sorted(folder.glob("Part_*.obj")), frame=())
    boundary = interlock.read(folder / "Boundary.obj", frame=())
    meshes = list(parts.world_meshes()) + list(boundary.world_meshes())
    return Assembly.from_meshes(meshes, frame=range(len(parts), len(meshes)))


def subjects(quick: bool = False, large: bool = False) -> dict:
    """name -> (loader, {frame name: (frame, known verdict or None)}); subjects whose data is absent are left out."""
    bunny = REFERENCE_DATA / "topolite" / "bunny"
    cube = REFERENCE_DATA / "topolite" / "cube"
    out = {
        "bunny": (lambda: interlock.read([bunny / f"part_{k}.obj" for k in range(1, 81)], frame=()),
                  {"{0, 1}": ((0, 1), True), "{0}": ((0,), False), "{1}": ((1,), False)}),
        "TopoLite cube": (lambda: interlock.read([cube / f"part_{k}.obj" for k in range(1, 10)], frame=()),
                          {"{0, 8}": ((0, 8), True), "{8}": ((8,), False)}),
    }
    ti = SHARED_DATA / "topolite_ti"
    known = {"origin": None, "SphereA80_Hex_T40.0": False, "tube": False}
    if large:
        known["chips"] = None
    for model, truth in known.items():
        if (ti / model).is_dir():
            out[f"TI {model}"] = (lambda model=model: _topolite_ti(model), {"boundary": ("boundary", truth)})
    geocomb = SHARED_DATA / "geocombsurfx_jl"
    for path in sorted(geocomb.glob("*.obj")):
        if quick and path.stem not in GEOCOMB_QUICK:
            continue
        out[f"GeoComb {path.stem}"] = (lambda path=path: interlock.read(path, frame=()),
                                       {"1-8": (tuple(range(1, 9)), True)})
    return out


@lru_cache(maxsize=4)
def _original(subject: str) -> Assembly:
    return subjects(large=True)[subject][0]()


def _frame(assembly: Assembly, frame):
    return assembly.frame if frame == "boundary" else frame


# --- placements and perturbations ----------------------------------------------------------------


def _placement(rng: np.random.Generator, size: float) -> np.ndarray:
    """A 4 x 4 rigid motion: a uniformly random rotation, then a shift of 1 ... 10**2.5 sizes."""
    direction = rng.normal(size=3)
    shift = direction / np.linalg.norm(direction) * size * 10.0 ** rng.uniform(0.0, MAX_SHIFT_DECADES)
    motion = np.eye(4)
    motion[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    motion[:3, 3] = shift
    return motion


def _placed_meshes(assembly: Assembly, motion: np.ndarray) -> list[trimesh.Trimesh]:
    return [trimesh.Trimesh(m.vertices @ motion[:3, :3].T + motion[:3, 3], m.faces, process=False)
            for m in assembly.world_meshes()]


def _read_back(meshes, frame, suffix: str) -> Assembly:
    """Write the blocks with :func:`interlock.write` and read them back.

    interlock writes PLY coordinates as doubles; other tools write floats, so for PLY the vertices are
    rounded to float32 first.
    """
    if suffix == ".ply":
        meshes = [trimesh.Trimesh(m.vertices.astype(np.float32).astype(float), m.faces, process=False)
                  for m in meshes]
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"blocks{suffix}"
        interlock.write(Assembly.from_meshes(meshes, frame=frame), path)
        return interlock.read(path)


def _digits(meshes, frame, digits: int) -> Assembly:
    """An OBJ file with one object per block, coordinates printed with ``%.<digits>g``, read back."""
    lines, offset = [], 1
    for k, mesh in enumerate(meshes):
        lines.append(f"o block_{k}")
        lines.extend("v " + " ".join(f"%.{digits}g" % x for x in vertex) for vertex in mesh.vertices)
        lines.extend(f"f {a + offset} {b + offset} {c + offset}" for a, b, c in mesh.faces)
        offset += len(mesh.vertices)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "blocks.obj"
        path.write_text("\n".join(lines) + "\n")
        return interlock.read(path, frame=frame)


def _noisy(meshes, frame, amplitude: float, rng: np.random.Generator) -> Assembly:
    """Gaussian noise of ``amplitude`` (a length) per distinct vertex position of each block."""
    out = []
    for mesh in meshes:
        unique, inverse = np.unique(mesh.vertices, axis=0, return_inverse=True)
        moved = unique + rng.normal(scale=amplitude, size=unique.shape)
        out.append(trimesh.Trimesh(moved[inverse.ravel()], mesh.faces, process=False))
    return Assembly.from_meshes(out, frame=frame)


def _fan_centroids(mesh: trimesh.Trimesh, rng: np.random.Generator) -> trimesh.Trimesh:
    """A share of the triangles split into three at their centroid."""
    faces = np.asarray(mesh.faces)
    chosen = rng.random(len(faces)) < RETRIANGULATED
    centres = mesh.vertices[faces[chosen]].mean(axis=1)
    index = len(mesh.vertices) + np.arange(len(centres))
    a, b, c = faces[chosen].T
    fans = np.vstack([np.column_stack([a, b, index]), np.column_stack([b, c, index]),
                      np.column_stack([c, a, index])])
    return trimesh.Trimesh(np.vstack([mesh.vertices, centres]), np.vstack([faces[~chosen], fans]), process=False)


def _split_edges(mesh: trimesh.Trimesh, rng: np.random.Generator) -> trimesh.Trimesh:
    """A share of the edges split at their midpoint, the two triangles beside each split in two.

    Edges are taken one at a time among those whose triangles are still the original ones, so the
    surface stays closed and without T-junctions.
    """
    vertices = [*np.asarray(mesh.vertices)]
    faces = [list(f) for f in np.asarray(mesh.faces)]
    edges = {}
    for f, face in enumerate(faces):
        for k in range(3):
            edges.setdefault(frozenset((face[k], face[(k + 1) % 3])), []).append(f)
    touched = set()
    keys = list(edges)
    for e in rng.permutation(len(keys))[: int(RETRIANGULATED * len(keys))]:
        beside = edges[keys[e]]
        if len(beside) != 2 or touched & set(beside):
            continue
        u, v = tuple(keys[e])
        m = len(vertices)
        vertices.append((vertices[u] + vertices[v]) / 2.0)
        for f in beside:
            face = faces[f]
            i = [k for k in range(3) if face[k] not in (u, v)][0]
            w, p, q = face[i], face[(i + 1) % 3], face[(i + 2) % 3]  # the edge is (p, q) in this face's order
            faces[f] = [w, p, m]
            faces.append([w, m, q])
            touched.add(f)
            touched.add(len(faces) - 1)
    return trimesh.Trimesh(np.array(vertices), np.array(faces), process=False)


def _max_abs(meshes) -> float:
    return max(float(np.abs(m.vertices).max()) for m in meshes)


def perturbation(family: str, meshes, size: float) -> float:
    """The length by which ``family`` moves coordinates of blocks placed as ``meshes``."""
    top = _max_abs(meshes)
    if family.startswith("float32"):
        return 2.0**-24 * top
    if family.endswith("digits"):
        digits = int(family.split()[0])
        return 0.5 * 10.0 ** (math.floor(math.log10(top)) - digits + 1)
    if family.startswith("noise"):
        return float(family.split()[1]) * size
    return 2.0**-53 * top


def perturbed(subject: str, placement: int, family: str, seed: int = SEED) -> Assembly:
    """The subject's placement number ``placement`` perturbed by ``family`` (frame: the subject's boundary, if any)."""
    original = _original(subject)
    rng = np.random.default_rng([seed, placement])
    meshes = _placed_meshes(original, _placement(rng, original.scale))
    frame = original.frame
    family_rng = np.random.default_rng([seed, placement, FAMILIES.index(family)])
    if family == "float64":
        return Assembly.from_meshes(meshes, frame=frame)
    if family.startswith("float32"):
        return _read_back(meshes, frame, "." + family.split()[1].lower())
    if family.endswith("digits"):
        return _digits(meshes, frame, int(family.split()[0]))
    if family.startswith("noise"):
        return _noisy(meshes, frame, float(family.split()[1]) * original.scale, family_rng)
    split = _fan_centroids if "centroids" in family else _split_edges
    return Assembly.from_meshes([split(m, family_rng) for m in meshes], frame=frame)


# --- the reference and its reach ------------------------------------------------------------------


def _reach(assembly: Assembly, frame, verdict) -> tuple[float | None, float | None, str]:
    """The original's reach (a length, see the module docstring), an upper estimate, and how they were measured.

    For an interlocked original the upper estimate is the margin's upper bound times the tolerance (a motion
    attains it); for one that is not, it is the reach itself.
    """
    try:
        if verdict.interlocked is True:
            t = REACH_TOLERANCE * assembly.scale
            measured = check(assembly, frame=frame, tolerance=t, time_limit=TIME_LIMIT)
            if measured.margin is None:
                return None, None, f"no margin ({measured.status})"
            # the margin itself, not a proof's lower bound (which stops once it proves 1): the band must not
            # shrink with a looser proof
            rho = exact_margin(assembly, frame, t)
            return (rho * t, float(measured.margin.upper) * t,
                    f"exact margin {rho:.3g} x tolerance (check: {measured.margin})")
        if verdict.interlocked is False and verdict.motion is not None:
            moved = finite_motion(assembly, verdict.motion, frame=frame)
            clear = 0.0
            for displacement, fraction in zip(moved.displacements, moved.overlap_fractions):
                if fraction > OVERLAP_RTOL:
                    break
                clear = max(clear, displacement)
            return clear, clear, f"finite motion ({moved.ending})"
    except InterlockError as error:
        return None, None, f"refused: {type(error).__name__}: {error}"
    return None, None, "undecided original"


def exact_margin(assembly: Assembly, frame, tolerance: float) -> float:
    """The margin ``rho = 1 / max_j max {|x_j| : A x >= -eps}`` of ``assembly`` against one ``tolerance`` (a length,
    :func:`~interlock.verify.margin.row_tolerances`): two HiGHS LPs per column of its interlocking matrix, each
    within the unit box (a coordinate that reaches the box gives ``rho <= 1``); interior point, 0.18 s an LP on
    the bunny's 4274 x 468 matrix (dual simplex 0.47 s)."""
    A = interlocking_matrix(assembly, frame, contacts=(found := model_contacts(assembly)))
    eps = row_tolerances(A, found, tolerance)
    largest = 0.0
    for j in range(A.shape[1]):
        for sign in (1.0, -1.0):
            c = np.zeros(A.shape[1])
            c[j] = -sign
            result = scipy.optimize.linprog(c, A_ub=-A.matrix, b_ub=eps, bounds=(-1.0, 1.0), method="highs-ipm")
            if result.status != 0:
                raise RuntimeError(f"the margin LP of column {j} failed: {result.message}")
            largest = max(largest, -result.fun)
    return 1.0 / largest if largest > 0 else math.inf


def _decide(assembly: Assembly, frame) -> dict:
    start = time.perf_counter()
    try:
        v = check(assembly, frame=frame, time_limit=TIME_LIMIT)
    except InterlockError as error:
        return {"verdict": "refused", "status": f"{type(error).__name__}: {error}",
                "seconds": time.perf_counter() - start}
    except Exception as error:  # noqa: BLE001 -- a defect of the library, recorded as such
        return {"verdict": "crashed", "status": f"{type(error).__name__}: {error}",
                "seconds": time.perf_counter() - start}
    tolerance = v.tolerances.get("tolerance", None if v.margin is None else v.margin.tolerance)
    return {"verdict": v.interlocked, "status": str(v), "seconds": time.perf_counter() - start,
            "within_tolerance": v.motion_kind == "within tolerance" and not (v.finite_motion is not None
                                                                             and v.finite_motion.shown),
            "tolerance": tolerance, "tolerance_from": v.tolerances.get("tolerance_from"),
            "margin": None if v.margin is None else [v.margin.lower, v.margin.upper],
            "moving": len(v.moving), "contacts": v.contacts}


def _classify(outcome: dict, reference) -> str:
    if outcome["verdict"] in ("refused", "crashed"):
        return outcome["verdict"]
    if outcome["verdict"] is None:
        return "inconclusive"
    if reference is None:
        return "unjudged"
    return "right" if outcome["verdict"] == reference else "wrong"


def _declined(outcome: dict) -> bool:
    return outcome["verdict"] in (None, "refused", "crashed") or outcome.get("within_tolerance", False)


def _references(subject: str, frames: dict) -> dict:
    original = _original(subject)
    out = {}
    for name, (frame, known) in frames.items():
        frame = _frame(original, frame)
        start = time.perf_counter()
        try:
            v = check(original, frame=frame, time_limit=TIME_LIMIT)
            answer, status = v.interlocked, str(v)
        except InterlockError as error:
            v, answer, status = None, "refused", f"{type(error).__name__}: {error}"
        seconds = time.perf_counter() - start
        reference = known if known is not None else (answer if answer in (True, False) else None)
        reach, upper, how = _reach(original, frame, v) if v is not None else (None, None, "original refused")
        if reach is None and v is not None and v.interlocked is not True and known is True:
            how += "; original not interlocked"
        out[name] = {"frame": list(frame), "known": known, "original": answer, "original_status": status,
                     "original_seconds": seconds, "reference": reference, "reach": reach, "reach_upper": upper, "reach_from": how,
                     "original_wrong": known is not None and answer in (True, False) and answer != known}
        print(f"  {subject} frame {name}: original {answer} ({seconds:.1f} s), reference {reference}, "
              f"reach {reach} ({how})", flush=True)
    return out


def run(quick: bool = False, placements: int | None = None, large: bool = False, only=None,
        shard: tuple[int, int] | None = None) -> dict:
    """Every subject through every placement and family; ``shard=(k, n)``: only the placements ``p`` with
    ``p % n == k``, written as ``real_files_shard{k}of{n}`` for :func:`merge` (n processes, one per core)."""
    placements = placements if placements is not None else (QUICK_PLACEMENTS if quick else PLACEMENTS)
    if shard is not None and not (len(shard) == 2 and 0 <= shard[0] < shard[1]):
        raise ValueError(f"shard must be (k, n) with 0 <= k < n, got {shard!r}")
    stem = "real_files" if shard is None else _shard_name(*shard)
    cases, references = [], {}
    start_all = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ordered = subjects(quick, large)
        ordered = {**{k: v for k, v in ordered.items() if k != "bunny"}, **{k: v for k, v in ordered.items()
                                                                            if k == "bunny"}}
        for subject, (_, frames) in ordered.items():  # the bunny, the slowest, last
            if only and not any(word.lower() in subject.lower() for word in only):
                continue
            original = _original(subject)
            references[subject] = refs = _references(subject, frames)
            for placement in range(placements):
                if shard is not None and placement % shard[1] != shard[0]:
                    continue
                for family in FAMILIES:
                    start = time.perf_counter()
                    try:
                        assembly = perturbed(subject, placement, family)
                        built = None
                    except InterlockError as error:
                        assembly, built = None, f"{type(error).__name__}: {error}"
                    except Exception as error:  # noqa: BLE001 -- a defect of the library, recorded as such
                        assembly, built = None, f"crashed: {type(error).__name__}: {error}"
                    prepare = time.perf_counter() - start
                    meshes = _placed_meshes(original, _placement(np.random.default_rng([SEED, placement]),
                                                                 original.scale))
                    p = perturbation(family, meshes, original.scale)
                    for name, ref in refs.items():
                        if assembly is None:
                            outcome = {"verdict": "crashed" if built.startswith("crashed") else "refused",
                                       "status": built, "seconds": 0.0}
                        else:
                            outcome = _decide(assembly, tuple(ref["frame"]))
                        cls = _classify(outcome, ref["reference"])
                        reach, upper = ref["reach"], ref["reach_upper"]
                        case = {"subject": subject, "frame": name, "placement": placement, "family": family,
                                "reference": ref["reference"], "class": cls, "perturbation": p,
                                "reach": reach, "in_band": reach is not None and reach >= BAND_FACTOR * p,
                                "in_upper_band": upper is not None and upper >= BAND_FACTOR * p,
                                "declined": _declined(outcome), "prepare_seconds": prepare, **outcome}
                        cases.append(case)
                        if cls in ("wrong", "refused", "crashed"):
                            print(f"    {cls.upper()}: {subject} frame {name} placement {placement} {family}: "
                                  f"{outcome['status'][:300]}", flush=True)
                print(f"  {subject} placement {placement} done ({time.perf_counter() - start_all:.0f} s)",
                      flush=True)
            _report(cases, references, quick, placements, time.perf_counter() - start_all, final=False, name=stem)
    return _report(cases, references, quick, placements, time.perf_counter() - start_all, final=True, name=stem)


def merge(shards: int) -> dict:
    """``real_files`` from the ``shards`` parts written by ``run(shard=(k, shards))``: their cases together, the
    references of the first, the longest part's seconds; complete only if every part is."""
    parts = [json.loads((results_folder() / f"{_shard_name(k, shards)}.json").read_text()) for k in range(shards)]
    if len({(part["quick"], part["placements"], part["seed"]) for part in parts}) != 1:
        raise ValueError("the shards were run with different --quick, --placements or seeds")
    cases = sorted((case for part in parts for case in part["cases"]),
                   key=lambda c: (c["subject"], c["placement"], FAMILIES.index(c["family"]), c["frame"]))
    return _report(cases, parts[0]["references"], parts[0]["quick"], parts[0]["placements"],
                   max(part["seconds"] for part in parts), final=all(part["complete"] for part in parts))


def _shard_name(k: int, shards: int) -> str:
    """The results name of part ``k`` of ``shards``."""
    return f"real_files_shard{k}of{shards}"


def _report(cases, references, quick: bool, placements: int, seconds: float, final: bool,
            name: str = "real_files") -> dict:
    """Write the JSON (and, for the whole run, the chart) of the cases so far (after each subject, so a long run
    leaves its part)."""
    summary = _summary(cases)
    if final:
        for family, row in summary.items():
            counts = " ".join(f"{c} {row['counts'][c]}" for c in CLASSES)
            share = row["declined_in_band"]
            shown = "-" if share is None else f"{100 * share:.0f} % of {row['in_band']}"
            print(f"{family:30s} {counts}; declined in band {shown}; median check {row['median_seconds']:.2f} s")
    payload = {"benchmark": "verdicts on real files", "quick": quick, "placements": placements, "seed": SEED,
               "complete": final, "families": list(FAMILIES), "band_factor": BAND_FACTOR,
               "reach_tolerance": REACH_TOLERANCE, "references": references, "summary": summary,
               "targets": _targets(summary), "seconds": seconds, "cases": cases}
    write_json(name, payload)
    if name == "real_files":
        _chart(summary, placements)
    return payload


def _summary(cases) -> dict:
    out = {}
    for family in FAMILIES:
        mine = [c for c in cases if c["family"] == family]
        band = [c for c in mine if c["in_band"]]
        upper_band = [c for c in mine if c["in_upper_band"]]
        seconds = [c["seconds"] for c in mine if c["verdict"] not in ("refused", "crashed")]
        out[family] = {"cases": len(mine), "counts": {k: sum(c["class"] == k for c in mine) for k in CLASSES},
                       "in_band": len(band),
                       "declined_in_band": (sum(c["declined"] for c in band) / len(band)) if band else None,
                       "within_tolerance_in_band": (sum(c.get("within_tolerance", False) for c in band) / len(band))
                       if band else None,
                       "in_upper_band": len(upper_band),
                       "declined_in_upper_band": (sum(c["declined"] for c in upper_band) / len(upper_band))
                       if upper_band else None,
                       "median_seconds": statistics.median(seconds) if seconds else 0.0,
                       "by_subject": {s: {k: sum(c["class"] == k for c in mine if c["subject"] == s) for k in CLASSES}
                                      for s in dict.fromkeys(c["subject"] for c in mine)}}
    return out


def _targets(summary) -> dict:
    return {"no wrong": all(r["counts"]["wrong"] == 0 for r in summary.values()),
            "declined in band <= 10 %": all(r["declined_in_band"] is None or r["declined_in_band"] <= 0.1
                                           for r in summary.values()),
            "re-triangulation never refused": all(summary[f]["counts"]["refused"] == 0
                                                  for f in FAMILIES if f.startswith("re-triangulated"))}


def _chart(summary: dict, placements: int) -> None:
    plt = pyplot()
    if plt is None:
        return
    from matplotlib.patches import Patch

    families = list(summary)
    fig, ax = plt.subplots(figsize=(13, 6))
    bottom = np.zeros(len(families))
    for cls in CLASSES:
        counts = np.array([summary[f]["counts"][cls] for f in families], dtype=float)
        ax.bar(range(len(families)), counts, bottom=bottom, color=COLOURS[cls], edgecolor="#666666", label=cls)
        bottom += counts
    ax.set_xticks(range(len(families)),
                  [f"{f}\n{summary[f]['median_seconds']:.2f} s" for f in families], fontsize=7, rotation=30,
                  ha="right")
    ax.set_ylabel("cases (subject x frame x placement)")
    ax.set_ylim(0, 1.3 * max(bottom.max(), 1))  # room for the legend
    right = ax.twinx()
    shares = [summary[f]["declined_in_band"] for f in families]
    right.plot([k for k, s in enumerate(shares) if s is not None], [100 * s for s in shares if s is not None],
               "kD", label="declined in band")
    right.axhline(10, color="black", linestyle="--", linewidth=1)
    right.set_ylim(0, 105)
    right.set_ylabel(f"% declined where the original's reach >= {BAND_FACTOR:g} x perturbation")
    handles = [Patch(facecolor=COLOURS[c], edgecolor="#666666", label=c) for c in CLASSES]
    ax.legend(handles=handles + right.get_legend_handles_labels()[0], fontsize=8, loc="upper left", ncol=3)
    wrong = sum(summary[f]["counts"]["wrong"] for f in families)
    ax.set_title(f"check on peer assemblies, {placements} random placements per perturbation family: "
                 f"{wrong} wrong (target 0); median time of check under each bar", fontsize=10)
    save_chart(fig, "real_files")
    plt.close(fig)


def _main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    parser.add_argument("--placements", type=int, metavar="N", help=f"random placements (default {PLACEMENTS}, "
                                                                     f"--quick {QUICK_PLACEMENTS})")
    parser.add_argument("--large", action="store_true", help="also TopoLite's 331-block 'chips' shell")
    parser.add_argument("--only", nargs="+", metavar="WORD", help="only the subjects whose name contains a word")
    parser.add_argument("--shard", nargs=2, type=int, metavar=("K", "N"),
                        help="only the placements p with p %% N == K (run N of these at once, then --merge N)")
    parser.add_argument("--merge", type=int, metavar="N", help="write real_files from the N shards' results")
    args = parser.parse_args()
    use_results_folder(args.results)
    if args.merge:
        merge(args.merge)
        return
    run(quick=args.quick, placements=args.placements, large=args.large, only=args.only,
        shard=None if args.shard is None else tuple(args.shard))


if __name__ == "__main__":
    _main()
