"""Scaling: time and peak memory of each stage against the number of blocks, with a naive baseline in the same run.

Two families of assemblies, each with its outer ring fixed (main paper Cor. 4.8):

- ``rhomblock``: RhomBlocks (variant 0) on a uniformly random n x n x n hexagon
  (seed 0), ``3 n^2`` blocks, n = 5, 10, 15, 20, 30, 40 (75 to 4,800 blocks);
- ``escher``: patches of radius r = 2 ... 12 of a p4 Escher block with edges 0
  and 1 deformed (69 to 1,901 blocks).

and the same assemblies with one block fixed (block 0), which do not
interlock (``rhomblock, one fixed``, ``escher, one fixed``): the failing case
of every wrong frame and failed design.  ``one_fixed_over_ring`` gives, per
size, the verdict's median with one block fixed over that with the ring fixed
(target: at most 2).  Their naive baseline also looks for the motion, by
HiGHS' simplex on ``[A; -A]`` (:func:`benchmarks.common.naive_motion`).

Each size runs the whole pipeline several times and times every stage on its
own: ``generation`` (``random_hexagon`` + ``rhomblock_assembly``, or
``escher_block`` + ``patch``), ``contacts``, ``matrix``, ``rank`` and ``lp``
(the stress LP, Clarabel in feasibility form) — these four from
``check(assembly, validate=False).timings`` — and ``export`` (binary STL, :func:`interlock.write`);
``verdict`` is contacts through lp.  The BLAS runs on one thread
(:data:`benchmarks.common.BLAS_THREADS`), for ours and the baseline alike.
Every run generates a new assembly, so nothing is cached between runs.  Up to
5 runs per size, fewer for big sizes (no further run once the runs of a size
would pass 40 s; :data:`FULL`); each row records its number of runs, and the
medians are reported.

The naive baseline (:func:`benchmarks.common.naive_verdict`) runs in the same
process on the same assemblies: contacts over all pairs of blocks without
instancing, the same matrix, ``numpy.linalg.matrix_rank`` of the dense matrix,
and HiGHS on ``max t : A^T w = 0, w_i >= t, t <= 1``.  It grows with the
sizes until one naive verdict takes more than 60 s, or would take more than
twice that by a cubic extrapolation (the dense rank); rows then say why it was
skipped.  ``ours_over_naive`` holds the ratios of the medians
(below 1: ours is faster).

Peak memory comes from one fresh interpreter per size (with ``quick``, for the
largest size of each family only), run after all timings, two at a time: per
stage, the peak resident set above the resident set at the stage's start
(Linux: ``VmHWM`` after resetting it through ``/proc/self/clear_refs``), and
the peak of the whole pipeline above the resident set after imports, in MB
(10^6 bytes).  ``dense_A_mb`` is what a dense copy of ``A`` takes, which the
naive rank needs.

Growth exponents are least-squares slopes of log(seconds) against log(blocks)
over the sizes where a stage takes more than :data:`FIT_FLOOR` seconds (of
log(MB) over the sizes above :data:`MEMORY_FIT_FLOOR` MB for memory).

The **float32 family** (:func:`run_float32`, ``scaling_float32.json`` and
``.png``; issue 35): the same assemblies, ring fixed and block 0 fixed, turned
by a random rotation (seed: the size), written as binary STL (float32) and
read back with ``interlock.read``.  Each size runs ``check(validate=False)`` on
the turned float64 assembly and on the float32 file alternately, in the same
process; ``seconds`` are medians of the verdict (contacts through lp, and the
margin, which only the float32 file needs).  Targets: every float32 verdict
True or False (never None), equal to the float64 one (0 wrong), in at most
twice its time (``ratio``).  The chart shows both verdicts' seconds against
blocks per family, and the ratio.

The **peer family** (:func:`run_peers`, ``scaling_peers.json`` and ``.png``;
issue 40): "one block fixed" on peer-like matrices.  p4 patches (the
``escher`` block above, radius 3 to 19.2: 137 to 4,781 blocks), p6 patches of
the main paper's Fig. 1 block (radius 3 to 14.5: 229 to 4,726 blocks) and
1 to 30 TopoLite bunnies (80 parts each) side by side, not touching.  Each
assembly is checked with three frames, alternating in one process
(``check(validate=False, time_limit=600)``, a fresh assembly per call,
:data:`PEER_RUNS` runs, medians of the wall time): ``ring`` (the outer ring;
bunny: parts 0 and 1 of every copy; interlocked), ``one`` (block 0; bunny:
part 1 of the first copy) and ``few`` (:data:`FEW` ring blocks evenly spread,
as in issue 40's 559-block peer; bunny: part 1 of every copy), neither
interlocked.  ``ratios`` are the negative medians over the positive (target:
at most 2); ``verdict_ratios`` the same for contacts through lp, without the
margin that only a positive answer computes.  Each frame records its verdict:
``interlocked``, ``status`` and ``tolerances["motion_from"]``.

The **grid family** (:func:`run_grid`, ``scaling_grid.json`` and ``.png``):
``side`` x ``side`` touching unit cubes (top and bottom rows fixed) against
the RhomBlock hexagon of about as many blocks (ring fixed), 100 x 100 against
n = 60 (10,800 blocks) at the largest size; one fresh process per size, the
two alternating in it (up to :data:`GRID_RUNS` pairs within
:data:`GRID_BUDGET` seconds), wall times and the peak resident set of each
check.  Target: grid at most 2x the hexagon.  Separate cubes and the n-gon
prism are in :mod:`benchmarks.memory`.

``python -m benchmarks.scaling [--quick] [--float32 | --peers [p4,p6,bunny] |
--grid] [--sizes ...]`` runs one family alone (with ``--sizes``, without
replacing the recorded JSON).

Reading the chart: one log-log panel of seconds against blocks per family,
one line per stage (ours solid, naive dashed, the verdict in black), the
exponent ``~N^k`` in each legend entry; a line that is steeper grows faster,
and the vertical gap between a dashed and a solid line of one colour is the
speed-up.  The right panel shows the peak memory of the whole pipeline and of
its heaviest stages, and what a dense ``A`` would take.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from benchmarks.common import (BLAS_THREADS, limited_blas, load_average, naive_verdict, pyplot, save_chart,
                               write_json)
from interlock import wallpaper
from interlock.blocks import Assembly, escher_block, patch, random_hexagon, rhomblock_assembly
from interlock.formats import read, write
from interlock.verify import check

ROOT = Path(__file__).resolve().parents[1]
#: The stages of one pipeline run, in order.
STAGES = ("generation", "contacts", "matrix", "rank", "lp", "export")
#: The stages of ``check`` that make up a verdict (validation is off).
VERDICT = ("contacts", "matrix", "rank", "lp")


@dataclass(frozen=True)
class Policy:
    """How long to measure.

    At most ``runs`` runs per size, and no further run of ours (of the naive
    baseline) once the runs so far plus one more would pass ``run_budget``
    (``naive_budget``) seconds; the naive baseline stops growing once one of
    its verdicts takes longer than ``naive_limit`` seconds.
    """

    runs: int
    run_budget: float
    naive_budget: float
    naive_limit: float


FULL = Policy(runs=5, run_budget=40.0, naive_budget=30.0, naive_limit=60.0)
QUICK = Policy(runs=3, run_budget=1.0, naive_budget=1.0, naive_limit=2.0)

#: Exponents are fitted over the sizes where a stage takes longer than this (seconds) ...
FIT_FLOOR = 0.005
#: ... and where the pipeline's peak memory is above this (MB; a first pipeline costs about 8 MB whatever its size).
MEMORY_FIT_FLOOR = 10.0
#: The deformation of the p4 Escher block: edge -> points.
ESCHER_DEFORMATION = {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}
MB = 1e6


def rhomblocks(n: int):
    """RhomBlocks on a random n x n x n hexagon (seed 0), outer ring fixed: ``3 n^2`` blocks."""
    return rhomblock_assembly(random_hexagon(n, n, n, seed=0), 0, frame="boundary")


def escher_patch(radius: float):
    """A patch of radius ``radius`` of the p4 Escher block, outer ring fixed."""
    return patch(escher_block(wallpaper.group("p4"), ESCHER_DEFORMATION), radius, frame="boundary")


@dataclass(frozen=True)
class Family:
    """Assemblies of growing size: ``generate(size)`` for each of ``sizes`` (``quick_sizes`` for tests).

    ``generate`` gives an :class:`Assembly`, or for the peer families (assembly, {frame name: fixed blocks}).
    """

    name: str
    generate: Callable[[object], object]
    size_name: str
    description: str
    sizes: tuple
    quick_sizes: tuple


def rhomblocks_one_fixed(n: int):
    """:func:`rhomblocks` with block 0 as the only fixed block: not interlocked."""
    return rhomblocks(n).with_frame([0])


def escher_patch_one_fixed(radius: float):
    """:func:`escher_patch` with block 0 as the only fixed block: not interlocked."""
    return escher_patch(radius).with_frame([0])


FAMILIES = (
    Family("rhomblock", rhomblocks, "n", "RhomBlocks on a random n x n x n hexagon, ring fixed",
           (5, 10, 15, 20, 30, 40), (3, 5, 8)),
    Family("escher", escher_patch, "radius", "patch of a p4 Escher block (edges 0, 1 deformed), ring fixed",
           (2, 3, 4, 6, 9, 12), (1, 2)),
    Family("rhomblock, one fixed", rhomblocks_one_fixed, "n", "the same RhomBlock hexagons, block 0 fixed",
           (5, 10, 15, 20, 30, 40), (3, 5, 8)),
    Family("escher, one fixed", escher_patch_one_fixed, "radius", "the same p4 patches, block 0 fixed",
           (2, 3, 4, 6, 9, 12), (1, 2)),
)
#: Which ring-fixed family each one-fixed family is compared with.
ONE_FIXED = {"rhomblock, one fixed": "rhomblock", "escher, one fixed": "escher"}


def run(quick: bool = False) -> dict:
    policy = QUICK if quick else FULL
    start, load = time.perf_counter(), load_average()
    with tempfile.TemporaryDirectory() as folder, limited_blas():
        _warm_up(Path(folder))
        families = {family.name: _time_family(family, family.quick_sizes if quick else family.sizes, policy,
                                                   Path(folder))
                    for family in FAMILIES}
    # quick: only the largest size of each family (a fresh interpreter costs about a second of imports)
    jobs = [(name, row["size"]) for name, rows in families.items() for row in (rows[-1:] if quick else rows)]
    for (name, size), memory in zip(jobs, _peak_memories(jobs)):
        row = next(r for r in families[name] if r["size"] == size)
        row["memory_mb"] = memory
    payload = {
        "benchmark": "scaling",
        "quick": quick,
        "policy": {**asdict(policy), "fit_floor_seconds": FIT_FLOOR, "memory_fit_floor_mb": MEMORY_FIT_FLOOR,
                   "blas_threads": BLAS_THREADS},
        "load_average_at_start": load,
        "families": {family.name: {"description": family.description, "size": family.size_name,
                                   "rows": families[family.name], "exponents": _exponents(families[family.name])}
                     for family in FAMILIES},
    }
    payload["one_fixed_over_ring"] = {
        name: [{"blocks": one["blocks"], "ratio": one["seconds"]["verdict"] / ring["seconds"]["verdict"]}
               for one, ring in zip(families[name], families[ring_name])]
        for name, ring_name in ONE_FIXED.items()}
    payload["seconds"] = time.perf_counter() - start
    for name, ratios in payload["one_fixed_over_ring"].items():
        print(f"{name} over ring: " + ", ".join(f"{r['blocks']}: {r['ratio']:.2f}" for r in ratios))
    for name, family in payload["families"].items():
        print(f"{name} exponents: " + "; ".join(
            who + " " + ", ".join(f"{k} {v:.2f}" for k, v in family["exponents"][who].items() if v is not None)
            for who in ("ours", "naive")))
    print(f"scaling ({'quick' if quick else 'full'}): {payload['seconds']:.0f} s")
    write_json("scaling", payload)
    _chart(payload)
    payload["float32"] = run_float32(quick)
    payload["peers"] = run_peers(quick)
    payload["grid"] = run_grid(quick)
    return payload


# --- the float32 family -----------------------------------------------------------------

#: Stages of the float32 verdict (the float64 one has no margin).
VERDICT_FLOAT32 = ("contacts", "matrix", "rank", "lp", "margin")
#: Runs per size at most, and no further pair of runs once the pairs so far plus one would pass this (seconds).
FLOAT32_RUNS, FLOAT32_BUDGET, FLOAT32_QUICK_BUDGET = 3, 120.0, 1.0


def turned(assembly: Assembly, seed: int) -> Assembly:
    """``assembly`` with every block turned by one random rotation (``seed``), the frame kept (float64)."""
    import trimesh
    from scipy.spatial.transform import Rotation

    turn = Rotation.random(random_state=seed).as_matrix()
    return Assembly.from_meshes([trimesh.Trimesh(m.vertices @ turn.T, m.faces, process=False)
                                 for m in assembly.world_meshes()], frame=assembly.frame)


def run_float32(quick: bool = False) -> dict:
    """The float32 family: each assembly as float64 and as binary STL read back; verdicts, seconds, ratios."""
    start, load = time.perf_counter(), load_average()
    budget = FLOAT32_QUICK_BUDGET if quick else FLOAT32_BUDGET
    families = {}
    with tempfile.TemporaryDirectory() as folder, limited_blas():
        for family in FAMILIES:
            rows = []
            for size in family.quick_sizes[:2] if quick else family.sizes:  # quick: the two smallest
                rows.append(_float32_row(family, size, Path(folder), budget))
                _print_float32(family, rows[-1])
            families[family.name] = {"description": family.description, "size": family.size_name, "rows": rows}
    every = [row for family in families.values() for row in family["rows"]]
    payload = {
        "benchmark": "scaling_float32",
        "quick": quick,
        "policy": {"runs": FLOAT32_RUNS, "budget_seconds": budget, "blas_threads": BLAS_THREADS},
        "load_average_at_start": load,
        "families": families,
        "summary": {"verdicts": len(every),
                    "inconclusive": sum(row["float32"]["interlocked"] is None for row in every),
                    "wrong": sum(row["float32"]["interlocked"] is not None and not row["agrees"] for row in every),
                    "over_twice": sum(row["ratio"] > 2 for row in every),
                    "largest_ratio": max((row["ratio"] for row in every), default=None)},
        "seconds": time.perf_counter() - start,
    }
    print("float32 family: " + ", ".join(f"{k} {v}" for k, v in payload["summary"].items()))
    write_json("scaling_float32", payload)
    _float32_chart(payload)
    return payload


def _float32_row(family: Family, size, folder: Path, budget: float) -> dict:
    """One size: the float64 and the float32 verdicts, alternately, up to :data:`FLOAT32_RUNS` pairs."""
    made = turned(family.generate(size), seed=int(round(10 * size)))
    path = folder / "float32.stl"
    write(made, path)
    stored = read(path)
    runs, spent = [], 0.0
    while len(runs) < FLOAT32_RUNS:
        begin = time.perf_counter()
        exact = check(made, validate=False)
        rounded = check(stored, validate=False)
        runs.append((exact, rounded))
        last = time.perf_counter() - begin
        spent += last
        if spent + last > budget:
            break
    exact, rounded = runs[-1]
    seconds64 = statistics.median(sum(e.timings.get(k, 0.0) for k in VERDICT_FLOAT32) for e, _ in runs)
    seconds32 = statistics.median(sum(r.timings.get(k, 0.0) for k in VERDICT_FLOAT32) for _, r in runs)
    margin = rounded.margin
    return {"size": size, "blocks": len(made), "frame": len(made.frame), "runs": len(runs),
            "float64": {"interlocked": exact.interlocked, "seconds": seconds64, "shape": list(exact.shape)},
            "float32": {"interlocked": rounded.interlocked, "seconds": seconds32, "shape": list(rounded.shape),
                        "margin_seconds": statistics.median(r.timings.get("margin", 0.0) for _, r in runs),
                        "margin": None if margin is None else margin.to_dict(), "status": rounded.status[:300],
                        "same_frame": stored.frame == made.frame},
            "agrees": rounded.interlocked == exact.interlocked, "ratio": seconds32 / seconds64}


def _print_float32(family: Family, row: dict) -> None:
    f32, f64 = row["float32"], row["float64"]
    margin = f32["margin"]
    bounds = "" if margin is None else f", margin >= {margin['lower']:.3g}"
    print(f"float32 {family.name} {family.size_name}={row['size']} ({row['blocks']} blocks): float64 "
          f"{f64['interlocked']} {f64['seconds']:.3f} s, float32 {f32['interlocked']} {f32['seconds']:.3f} s "
          f"(margin {f32['margin_seconds']:.3f} s{bounds}), x{row['ratio']:.2f}, agrees {row['agrees']} "
          f"({row['runs']} runs)", flush=True)


def _float32_chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    fig, grid = plt.subplots(1, 2, figsize=(13, 5))
    for (name, family), colour in zip(payload["families"].items(), ("C0", "C1", "C2", "C3")):
        rows = family["rows"]
        blocks = [row["blocks"] for row in rows]
        grid[0].loglog(blocks, [row["float64"]["seconds"] for row in rows], "s--", color=colour, ms=3,
                       label=f"{name}: float64")
        grid[0].loglog(blocks, [row["float32"]["seconds"] for row in rows], "o-", color=colour, ms=3,
                       label=f"{name}: float32 STL (margin included)")
        marks = ["x" if row["float32"]["interlocked"] is None or not row["agrees"] else "o" for row in rows]
        for b, row, mark in zip(blocks, rows, marks):
            grid[1].semilogx([b], [row["ratio"]], mark, color=colour, ms=5)
        grid[1].semilogx(blocks, [row["ratio"] for row in rows], "-", color=colour, lw=1, label=name)
    grid[1].axhline(2.0, color="grey", ls=":", label="target: 2x")
    grid[0].set_xlabel("blocks")
    grid[0].set_ylabel("seconds (median)")
    grid[0].set_title("verdict of the float64 assembly and of its float32 STL", fontsize=9)
    grid[1].set_xlabel("blocks")
    grid[1].set_ylabel("float32 over float64 (x: None or wrong)")
    grid[1].set_title("float32 verdict time over float64 verdict time", fontsize=9)
    for ax in grid:
        ax.legend(fontsize=6.5)
        ax.grid(True, which="major", alpha=0.3)
    save_chart(fig, "scaling_float32")
    plt.close(fig)


# --- peer-like matrices with a small frame, and the cube grid (issue 40) ------------------------------------

#: Seconds for every ``check`` of the peer and grid families, so that nothing hangs (a verdict that reaches
#: it says "inconclusive: time limit reached ..." and is recorded as such).
TIME_LIMIT = 600.0
#: Runs per size and frame (the frames alternate in one process, so the ratios share the machine's load).
PEER_RUNS = 3
#: Blocks of the "few fixed" frame: this many ring blocks, evenly spread (issue 40's 559-block peer had 10 of
#: its 186 ring blocks fixed).
FEW = 10
#: The TopoLite bunny: 80 parts; frame {0, 1} interlocks, frame {1} does not (``tests/data/README.md``).
BUNNY_PARTS, BUNNY_RING, BUNNY_ONE = 80, (0, 1), (1,)
#: Copies of the bunny side by side are this fraction of its width apart (they do not touch).
BUNNY_GAP = 0.5


def _ring_frames(assembly: Assembly) -> tuple:
    ring = assembly.boundary()
    few = tuple(ring[k] for k in np.linspace(0, len(ring), FEW, endpoint=False).astype(int))
    return assembly, {"ring": tuple(ring), "one": (0,), "few": few}


def p4_peers(radius: float) -> tuple:
    """The p4 patch of the scaling family (edges 0 and 1 deformed): the ring, block 0, or 10 ring blocks fixed."""
    return _ring_frames(patch(escher_block(wallpaper.group("p4"), ESCHER_DEFORMATION), radius))


def p6_peers(radius: float) -> tuple:
    """A patch of the p6 block of main paper Fig. 1: the ring, block 0, or 10 ring blocks fixed."""
    from interlock.blocks.presets import fig1

    return _ring_frames(patch(fig1.fig1_p6_block(), radius))


_BUNNY: list = []


def bunny_peers(copies: int) -> tuple:
    """``copies`` TopoLite bunnies side by side (not touching): frame {0, 1} of each ("ring", interlocked),
    {1} of the first ("one") or {1} of each ("few"); fresh meshes every call (nothing cached between runs)."""
    import trimesh

    from benchmarks.common import REFERENCE_DATA

    if not _BUNNY:
        folder = REFERENCE_DATA / "topolite" / "bunny"
        _BUNNY.extend(read([folder / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)], frame=()).world_meshes())
    meshes = [trimesh.Trimesh(m.vertices.copy(), m.faces.copy(), process=False) for m in _BUNNY]
    low = np.min([m.bounds[0] for m in meshes], axis=0)
    high = np.max([m.bounds[1] for m in meshes], axis=0)
    step = (1 + BUNNY_GAP) * (high - low)[0]
    side = int(np.ceil(np.sqrt(copies)))
    transforms = np.tile(np.eye(4), (copies * BUNNY_PARTS, 1, 1))
    for copy in range(copies):
        transforms[copy * BUNNY_PARTS:(copy + 1) * BUNNY_PARTS, :2, 3] = (copy % side * step,
                                                                         copy // side * step)
    assembly = Assembly(meshes, np.tile(np.arange(BUNNY_PARTS), copies), transforms)
    every = [copy * BUNNY_PARTS for copy in range(copies)]
    return assembly, {"ring": tuple(c + k for c in every for k in BUNNY_RING), "one": BUNNY_ONE,
                      "few": tuple(c + k for c in every for k in BUNNY_ONE)}


PEER_FAMILIES = (
    Family("p4", p4_peers, "radius", "p4 Escher patch (edges 0, 1 deformed)", (3, 4, 5, 6, 8, 9, 12, 19.2),
               (1, 2)),
    Family("p6", p6_peers, "radius", "p6 Escher patch (main paper Fig. 1 block)", (3, 4, 5, 6, 8, 10, 14.5),
               (1,)),
    Family("bunny", bunny_peers, "copies", "TopoLite bunny (80 parts), copies side by side",
               (1, 4, 16, 30), (1,)),
)
#: What each frame is, for the JSON.
PEER_FRAMES = {"ring": "positive: the outer ring fixed (bunny: parts 0 and 1 of every copy)",
               "one": "negative: block 0 fixed (bunny: part 1 of the first copy)",
               "few": f"negative: {FEW} ring blocks evenly spread (bunny: part 1 of every copy)"}


def run_peers(quick: bool = False, names=None, sizes=None) -> dict:
    """The peer family: per size, the negative verdicts ("one", "few") over the positive ("ring"); target <= 2."""
    start, load, library = time.perf_counter(), load_average(), library_state()
    families = {}
    with limited_blas():
        _peer_row(PEER_FAMILIES[0], PEER_FAMILIES[0].quick_sizes[0], runs=1)  # warm-up (imports, first calls)
        for family in PEER_FAMILIES:
            if names and family.name not in names:
                continue
            rows = [_peer_row(family, size, PEER_RUNS)
                    for size in sizes or (family.quick_sizes if quick else family.sizes)]
            families[family.name] = {"description": family.description, "size": family.size_name, "rows": rows}
    every = [row for family in families.values() for row in family["rows"]]
    payload = {
        "benchmark": "scaling_peers",
        "quick": quick,
        "policy": {"runs": PEER_RUNS, "time_limit": TIME_LIMIT, "blas_threads": BLAS_THREADS,
                   "seconds": "wall time of check(assembly, validate=False, time_limit=...), median of the runs",
                   "frames": PEER_FRAMES},
        "load_average_at_start": load,
        "library": library,
        "families": families,
        "summary": {"sizes": len(every),
                    "largest_ratio": max((r for row in every for r in row["ratios"].values()), default=None),
                    "over_twice": [f"{row['family']} {row['blocks']} {k}" for row in every
                                   for k, r in row["ratios"].items() if r > 2],
                    "largest_verdict_ratio": max((r for row in every for r in row["verdict_ratios"].values()),
                                                 default=None),
                    "verdict_over_twice": [f"{row['family']} {row['blocks']} {k}" for row in every
                                           for k, r in row["verdict_ratios"].items() if r > 2],
                    "unexpected": [f"{row['family']} {row['blocks']} {k}: {f['status'][:80]}" for row in every
                                   for k, f in row["frames"].items() if f["interlocked"] is not (k == "ring")]},
        "seconds": time.perf_counter() - start,
    }
    print("peers: " + ", ".join(f"{k} {v}" for k, v in payload["summary"].items()))
    if not (names or sizes):  # a partial run does not replace the record
        write_json("scaling_peers", payload)
        _peers_chart(payload)
    return payload


def library_state() -> dict:
    """The commit of the library measured, and its files changed since (a shared working tree), at the start."""
    def git(*args):
        done = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
        return done.stdout.strip() if done.returncode == 0 else None

    changed = git("status", "--porcelain", "--", "interlock")
    return {"commit": git("rev-parse", "HEAD"), "changed": changed.splitlines() if changed else []}


def _peer_row(family: Family, size, runs: int) -> dict:
    """One size: every frame ``runs`` times on a fresh assembly, frames alternating (rotated each run)."""
    names = list(PEER_FRAMES)
    seconds = {name: [] for name in names}
    stages = {name: [] for name in names}
    last = {}
    for run in range(runs):
        for name in names[run % len(names):] + names[:run % len(names)]:
            assembly, frames = family.generate(size)
            begin = time.perf_counter()
            verdict = check(assembly, frames[name], validate=False, time_limit=TIME_LIMIT)
            seconds[name].append(time.perf_counter() - begin)
            stages[name].append(verdict.timings)
            last[name] = (verdict, frames[name])
    row = {"family": family.name, "size": size, "blocks": len(assembly), "runs": runs, "frames": {}}
    for name in names:
        verdict, fixed = last[name]
        row["frames"][name] = {
            "fixed": len(fixed), "shape": list(verdict.shape), "interlocked": verdict.interlocked,
            "status": verdict.status[:300], "motion_from": verdict.tolerances.get("motion_from"),
            "seconds": statistics.median(seconds[name]), "run_seconds": seconds[name],
            "verdict_seconds": statistics.median(sum(t.get(k, 0.0) for k in VERDICT) for t in stages[name]),
            "stages": {k: statistics.median(t.get(k, 0.0) for t in stages[name]) for k in stages[name][-1]}}
    ring = row["frames"]["ring"]
    row["ratios"] = {name: row["frames"][name]["seconds"] / ring["seconds"] for name in names if name != "ring"}
    # without the margin (the positive verdict's "play" bound), which only an "interlocked" answer computes
    row["verdict_ratios"] = {name: row["frames"][name]["verdict_seconds"] / ring["verdict_seconds"]
                             for name in names if name != "ring"}
    print(f"peers {family.name} {family.size_name}={size} ({row['blocks']} blocks, {runs} runs): " + "; ".join(
        f"{name} [{f['fixed']} fixed] {f['seconds']:.3f} s (margin {f['stages'].get('margin', 0.0):.3f}) "
        f"{f['interlocked']} ({f['motion_from']})" for name, f in row["frames"].items())
        + " | " + ", ".join(f"{k}/ring {r:.2f} (contacts..lp {row['verdict_ratios'][k]:.2f})"
                            for k, r in row["ratios"].items()), flush=True)
    return row


def _peers_chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    fig, grid = plt.subplots(1, 2, figsize=(13, 5))
    styles = {"ring": "o-", "one": "s--", "few": "D:"}
    for (name, family), colour in zip(payload["families"].items(), ("C0", "C1", "C2")):
        rows = family["rows"]
        blocks = [row["blocks"] for row in rows]
        for frame, style in styles.items():
            grid[0].loglog(blocks, [row["frames"][frame]["seconds"] for row in rows], style, color=colour, ms=3,
                           label=f"{name}: {frame}")
            if frame != "ring":
                grid[1].semilogx(blocks, [row["ratios"][frame] for row in rows], style, color=colour, ms=4,
                                 label=f"{name}: {frame} / ring")
    grid[1].axhline(2.0, color="grey", ls=":", label="target: 2x")
    grid[0].set_ylabel("seconds (median of check)")
    grid[0].set_title("positive (ring fixed) and negative (one or few fixed) verdicts", fontsize=9)
    grid[1].set_ylabel("negative over positive")
    grid[1].set_title("negative verdict time over positive, same assembly, same process", fontsize=9)
    for ax in grid:
        ax.set_xlabel("blocks")
        ax.legend(fontsize=6.5)
        ax.grid(True, which="major", alpha=0.3)
    save_chart(fig, "scaling_peers")
    plt.close(fig)


#: The grid family: (grid side, hexagon n) per size; 100 x 100 cubes against the 10,800-block hexagon (n = 60).
GRID_SIZES, GRID_QUICK_SIZES = ((30, 17), (60, 35), (100, 60)), ((6, 4),)
#: Runs of each (alternating) per size, and no further pair once the pairs so far plus one would pass this (s).
GRID_RUNS, GRID_BUDGET = 3, 240.0


def cube_grid(side: int) -> Assembly:
    """``side`` x ``side`` touching unit cubes in the x-z plane; the top and bottom rows fixed."""
    import trimesh

    cells = np.array([(i, j) for j in range(side) for i in range(side)], dtype=float)
    transforms = np.tile(np.eye(4), (len(cells), 1, 1))
    transforms[:, 0, 3], transforms[:, 2, 3] = cells[:, 0], cells[:, 1]
    rows = [k for k, (_, j) in enumerate(cells) if j in (0, side - 1)]
    return Assembly([trimesh.creation.box((1.0, 1.0, 1.0))], np.zeros(len(cells), dtype=int), transforms, frame=rows)


def run_grid(quick: bool = False, sizes=None) -> dict:
    """The cube grid against the RhomBlock hexagon of about as many blocks; target: grid <= 2x hexagon."""
    start, load = time.perf_counter(), load_average()
    rows = []
    for side, n in sizes or (GRID_QUICK_SIZES if quick else GRID_SIZES):
        code = ("import json; from benchmarks.scaling import grid_child; "
                f"print(json.dumps(grid_child({side}, {n})))")
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            rows.append({"side": side, "n": n, "failed": done.stderr.strip().splitlines()[-3:]})
            print(f"grid {side} / hexagon {n} failed: {rows[-1]['failed']}", flush=True)
            continue
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        row = rows[-1]
        print(f"grid {side}x{side} ({row['grid']['blocks']} blocks) {row['grid']['seconds']:.2f} s "
              f"{row['grid']['interlocked']}, {row['grid']['peak_mb']:.0f} MB; hexagon n={n} "
              f"({row['hexagon']['blocks']} blocks) {row['hexagon']['seconds']:.2f} s {row['hexagon']['interlocked']}, "
              f"{row['hexagon']['peak_mb']:.0f} MB; ratio {row['ratio']:.2f} ({row['runs']} runs)", flush=True)
    payload = {"benchmark": "scaling_grid", "quick": quick,
               "policy": {"runs": GRID_RUNS, "budget_seconds": GRID_BUDGET, "time_limit": TIME_LIMIT,
                          "blas_threads": BLAS_THREADS,
                          "seconds": "wall time of check(assembly, validate=False, time_limit=...), median; "
                                     "grid and hexagon alternate in one fresh process per size",
                          "peak_mb": "peak resident set during the check above the resident set at its start "
                                     "(VmHWM after clear_refs), MB"},
               "load_average_at_start": load, "rows": rows, "seconds": time.perf_counter() - start}
    if sizes is None:
        write_json("scaling_grid", payload)
        _grid_chart(payload)
    return payload


def grid_child(side: int, n: int) -> dict:
    """In a fresh interpreter: the grid and the hexagon alternately, wall times and peak memory of each check."""
    import clarabel  # noqa: F401  (imported on first use; not counted in the first check's memory)

    makers = {"grid": lambda: cube_grid(side), "hexagon": lambda: rhomblocks(n)}
    seconds = {name: [] for name in makers}
    verdicts = {name: [] for name in makers}
    peaks = {name: [] for name in makers}
    result, spent = {}, 0.0
    with limited_blas():
        check(cube_grid(3), validate=False)  # warm-up
        while len(seconds["grid"]) < GRID_RUNS:
            pair = 0.0
            for name, make in makers.items():
                assembly = make()
                _reset_peak()
                before = _proc_status("VmRSS")
                begin = time.perf_counter()
                verdict = check(assembly, validate=False, time_limit=TIME_LIMIT)
                seconds[name].append(time.perf_counter() - begin)
                verdicts[name].append(sum(verdict.timings.get(k, 0.0) for k in VERDICT))
                peaks[name].append((_proc_status("VmHWM") - before) / MB)
                pair += seconds[name][-1]
                result[name] = {"blocks": len(assembly), "fixed": len(assembly.frame), "shape": list(verdict.shape),
                                "interlocked": verdict.interlocked, "status": verdict.status[:300],
                                "motion_from": verdict.tolerances.get("motion_from"),
                                "stages": {k: round(v, 4) for k, v in verdict.timings.items()}}
            spent += pair
            if spent + pair > GRID_BUDGET:
                break
    for name in makers:
        result[name].update(seconds=statistics.median(seconds[name]), run_seconds=seconds[name],
                            verdict_seconds=statistics.median(verdicts[name]), peak_mb=max(peaks[name]))
    return {"side": side, "n": n, "runs": len(seconds["grid"]), **result,
            "ratio": result["grid"]["seconds"] / result["hexagon"]["seconds"],
            "verdict_ratio": result["grid"]["verdict_seconds"] / result["hexagon"]["verdict_seconds"]}


def _grid_chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    rows = [row for row in payload["rows"] if "failed" not in row]
    fig, grid = plt.subplots(1, 2, figsize=(13, 5))
    for name, colour in (("grid", "C0"), ("hexagon", "C1")):
        blocks = [row[name]["blocks"] for row in rows]
        label = "cube grid (top, bottom rows fixed)" if name == "grid" else "RhomBlock hexagon (ring fixed)"
        grid[0].loglog(blocks, [row[name]["seconds"] for row in rows], "o-", color=colour, label=label)
        grid[1].loglog(blocks, [row[name]["peak_mb"] for row in rows], "o-", color=colour, label=label)
    twin = grid[0].twinx()
    twin.semilogx([row["grid"]["blocks"] for row in rows], [row["ratio"] for row in rows], "k:", marker="x",
                  label="grid / hexagon (right axis)")
    twin.axhline(2.0, color="grey", ls="--", lw=0.8)
    twin.set_ylabel("grid over hexagon (target <= 2, dashed)")
    grid[0].set_ylabel("seconds (median of check)")
    grid[1].set_ylabel("peak memory of the check (MB)")
    for ax in grid:
        ax.set_xlabel("blocks")
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(True, which="major", alpha=0.3)
    twin.legend(fontsize=7, loc="lower right")
    save_chart(fig, "scaling_grid")
    plt.close(fig)



# --- timings -------------------------------------------------------------------


def _warm_up(folder: Path) -> None:
    """One small pipeline and naive verdict first, so that no size pays for first calls (imports, BLAS threads)."""
    _pipeline(FAMILIES[0], FAMILIES[0].quick_sizes[0], folder)
    naive_verdict(FAMILIES[0].generate(FAMILIES[0].quick_sizes[0]))


def _pipeline(family: Family, size, folder: Path):
    """One run: (seconds per stage and for the verdict, the assembly, its verdict)."""
    seconds = {}
    start = time.perf_counter()
    assembly = family.generate(size)
    seconds["generation"] = time.perf_counter() - start
    verdict = check(assembly, validate=False)
    seconds.update({stage: verdict.timings[stage] for stage in VERDICT})
    start = time.perf_counter()
    write(assembly, folder / "scaling.stl")
    seconds["export"] = time.perf_counter() - start
    seconds["verdict"] = sum(seconds[stage] for stage in VERDICT)
    return seconds, assembly, verdict


def _repeat(fn, runs: int, budget: float) -> list:
    """The results of up to ``runs`` calls of ``fn``, stopping before a call would take the total past ``budget``."""
    results, spent = [], 0.0
    while len(results) < runs:
        start = time.perf_counter()
        results.append(fn())
        last = time.perf_counter() - start
        spent += last
        if spent + last > budget:
            break
    return results


def _medians(runs: list[dict]) -> tuple[dict, dict]:
    """(median per key, every run's value per key) of per-run dictionaries of seconds."""
    every = {key: [run[key] for run in runs] for key in runs[0]}
    return {key: statistics.median(values) for key, values in every.items()}, every


def _time_family(family: Family, sizes, policy: Policy, folder: Path) -> list[dict]:
    rows = []
    for size in sizes:
        runs = _repeat(lambda: _pipeline(family, size, folder), policy.runs, policy.run_budget)
        seconds, every = _medians([r[0] for r in runs])
        _, assembly, verdict = runs[-1]
        row = {"size": size, "blocks": len(assembly), "shape": list(verdict.shape), "contacts": verdict.contacts,
               "interlocked": verdict.interlocked, "dense_A_mb": verdict.shape[0] * verdict.shape[1] * 8 / MB,
               "runs": len(runs), "seconds": seconds, "run_seconds": every, "memory_mb": None}
        skip = _naive_skip(rows, row["blocks"], policy.naive_limit)
        row["naive"] = {"skipped": skip} if skip else _naive(assembly, verdict, seconds, policy)
        rows.append(row)
        _print_row(family, row)
    return rows


def _naive(assembly, verdict, ours: dict, policy: Policy) -> dict:
    """The naive baseline's medians on ``assembly``, and our medians over them."""
    motion = verdict.interlocked is False
    runs = _repeat(lambda: naive_verdict(assembly, motion=motion), policy.runs, policy.naive_budget)
    per_run = [dict(seconds, verdict=sum(seconds.values())) for _, seconds in runs]
    seconds, every = _medians(per_run)
    interlocked = runs[0][0]
    return {"runs": len(runs), "seconds": seconds, "run_seconds": every, "interlocked": interlocked,
            "agrees": interlocked == verdict.interlocked,
            "ours_over_naive": {stage: ours[stage] / seconds[stage] for stage in ("contacts", "rank", "lp", "verdict")}}


def _naive_skip(rows: list[dict], blocks: int, limit: float) -> str | None:
    """Why the naive baseline does not run at ``blocks`` (after ``rows``), or None when it does."""
    done = [row for row in rows if "seconds" in row["naive"]]
    if not done:
        return None
    last = done[-1]
    slowest = max(last["naive"]["run_seconds"]["verdict"])
    if slowest > limit:
        return f"stopped: a naive verdict took {slowest:.0f} s at {last['blocks']} blocks (limit {limit:.0f} s)"
    predicted = last["naive"]["seconds"]["verdict"] * (blocks / last["blocks"]) ** 3
    if predicted > 2 * limit:
        return f"skipped: predicted {predicted:.0f} s (cubic from {last['blocks']} blocks; limit {limit:.0f} s)"
    return None


def _print_row(family: Family, row: dict) -> None:
    s = row["seconds"]
    line = (f"{family.name} {family.size_name}={row['size']} ({row['blocks']} blocks, A {row['shape'][0]}x"
            f"{row['shape'][1]}): verdict {s['verdict']:.3f} s [" + ", ".join(f"{k} {s[k]:.3f}" for k in STAGES)
            + f"] ({row['runs']} runs)")
    naive = row["naive"]
    if "seconds" in naive:
        line += (f"; naive {naive['seconds']['verdict']:.3f} s ({naive['runs']} runs, x"
                 f"{1 / naive['ours_over_naive']['verdict']:.1f}, agrees {naive['agrees']})")
    else:
        line += f"; naive {naive['skipped']}"
    print(line, flush=True)


# --- growth exponents --------------------------------------------------------------


def _slope(blocks, values, floor: float) -> float | None:
    """Least-squares slope of log(value) against log(blocks) over values above ``floor`` (None below 2 points)."""
    points = [(b, v) for b, v in zip(blocks, values) if v is not None and v > floor]
    if len(points) < 2 or len({b for b, _ in points}) < 2:
        return None
    x, y = np.log(np.array(points, dtype=float)).T
    return float(np.polyfit(x, y, 1)[0])


def _exponents(rows: list[dict]) -> dict:
    blocks = [row["blocks"] for row in rows]
    naive = [row for row in rows if "seconds" in row["naive"]]
    memory = [row.get("memory_mb") or {} for row in rows]
    return {
        "ours": {stage: _slope(blocks, [row["seconds"][stage] for row in rows], FIT_FLOOR)
                 for stage in (*STAGES, "verdict")},
        "naive": {stage: _slope([row["blocks"] for row in naive], [row["naive"]["seconds"][stage] for row in naive],
                                FIT_FLOOR) for stage in ("contacts", "matrix", "rank", "lp", "verdict")},
        "peak_memory": _slope(blocks, [m.get("peak") for m in memory], MEMORY_FIT_FLOOR),
    }


# --- peak memory -------------------------------------------------------------------


def _peak_memories(jobs: list[tuple[str, object]]) -> list[dict | None]:
    """Peak memory of each (family, size), each in a fresh interpreter, two at a time."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(lambda job: _peak_memory(*job), jobs))


def _peak_memory(family: str, size) -> dict | None:
    code = ("import json; from benchmarks.scaling import memory_child; "
            f"print(json.dumps(memory_child({family!r}, {size!r})))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        print(f"peak memory of {family} {size} failed: {done.stderr.strip().splitlines()[-1:]}")
        return None
    return json.loads(done.stdout.strip().splitlines()[-1])


def memory_child(family: str, size) -> dict | None:
    """Run one pipeline in this (fresh) interpreter: peak MB per stage and of the whole pipeline."""
    import clarabel  # noqa: F401  (the stress LP imports it on first use; count it in the baseline)

    if not Path("/proc/self/status").exists():
        return None
    generate = next(f.generate for f in FAMILIES if f.name == family)
    with tempfile.TemporaryDirectory() as folder, limited_blas():
        meter = _PeakMeter()
        meter.enter("generation")
        assembly = generate(size)
        check(assembly, validate=False, progress=meter.enter)
        meter.enter("export")
        write(assembly, Path(folder) / "scaling.stl")
        meter.enter(None)
    return meter.result()


class _PeakMeter:
    """Peak resident memory of this process per stage (Linux ``/proc``), above the resident set at the stage's start."""

    def __init__(self):
        self.base = self.top = _proc_status("VmRSS")
        self.stage, self.start, self.stages = None, 0, {}
        self.resets = True

    def enter(self, stage: str | None) -> None:
        """End the current stage and start ``stage`` (None: just end)."""
        if self.stage is not None:
            high = _proc_status("VmHWM")
            self.stages[self.stage] = (high - self.start) / MB
            self.top = max(self.top, high)
        self.resets = _reset_peak() and self.resets
        self.stage, self.start = stage, _proc_status("VmRSS")

    def result(self) -> dict:
        return {"peak": (self.top - self.base) / MB, **(self.stages if self.resets else {})}


def _proc_status(key: str) -> int:
    """A ``/proc/self/status`` memory entry in bytes."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    raise KeyError(key)


def _reset_peak() -> bool:
    """Reset this process's peak resident set to the current one (Linux >= 4.0); whether that worked."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True


# --- chart ----------------------------------------------------------------------------

COLOURS = {"generation": "C0", "contacts": "C1", "matrix": "C2", "rank": "C3", "lp": "C4", "export": "C5",
           "verdict": "black"}


def _label(name: str, exponent: float | None) -> str:
    return name if exponent is None else f"{name} ~N^{exponent:.2f}"


def _chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    families = payload["families"]
    fig, grid = plt.subplots(2, 3, figsize=(18, 10.4))
    panels = [grid[0, 0], grid[0, 1], grid[1, 0], grid[1, 1]]  # ring fixed on top, one block fixed below
    for ax, (name, family) in zip(panels, families.items()):
        _time_panel(ax, family)
        ax.set_title(family["description"], fontsize=9)
    _memory_panel(grid[0, 2], families)
    grid[1, 2].axis("off")
    save_chart(fig, "scaling")
    plt.close(fig)


def _time_panel(ax, family: dict) -> None:
    rows = family["rows"]
    blocks = [row["blocks"] for row in rows]
    for stage in (*STAGES, "verdict"):
        ax.loglog(blocks, [row["seconds"][stage] for row in rows], "o-", color=COLOURS[stage], ms=3,
                  lw=2 if stage == "verdict" else 1.2, label=_label(stage, family["exponents"]["ours"][stage]))
    naive = [row for row in rows if "seconds" in row["naive"]]
    for stage in ("contacts", "rank", "lp", "verdict"):
        ax.loglog([row["blocks"] for row in naive], [row["naive"]["seconds"][stage] for row in naive], "s--",
                  color=COLOURS[stage], ms=3, label=_label(f"naive {stage}", family["exponents"]["naive"][stage]))
    _block_ticks(ax, blocks)
    ax.set_ylabel("seconds (median)")
    ax.legend(fontsize=6.5, ncol=2, loc="upper left")
    ax.grid(True, which="major", alpha=0.3)


def _block_ticks(ax, blocks) -> None:
    """The sizes measured as plain numbers on the (log) block axis."""
    ax.set_xticks(blocks, [f"{b:,}" for b in blocks], fontsize=7, rotation=45)
    ax.minorticks_off()
    ax.set_xlabel("blocks")


def _memory_panel(ax, families: dict) -> None:
    for (name, family), marker, style in zip(families.items(), "osD^", ("-", ":", "-.", "--")):
        rows = [row for row in family["rows"] if row.get("memory_mb")]
        blocks = [row["blocks"] for row in rows]
        ax.loglog(blocks, [row["memory_mb"]["peak"] for row in rows], marker + style, color="black", ms=4,
                  label=_label(f"{name}: whole pipeline", family["exponents"]["peak_memory"]))
        for stage in ("contacts", "rank", "lp"):
            values = [row["memory_mb"].get(stage) for row in rows]
            if any(v is not None for v in values):
                ax.loglog(blocks, values, marker + style, color=COLOURS[stage], ms=3, lw=1, label=f"{name}: {stage}")
        dense = family["rows"]
        ax.loglog([row["blocks"] for row in dense], [row["dense_A_mb"] for row in dense], style, color="grey",
                  lw=1, label=f"{name}: a dense A (naive rank)")
    _block_ticks(ax, (100, 300, 1000, 3000))
    ax.set_ylabel("peak memory above the start (MB)")
    ax.set_title("peak resident memory, one fresh process per size", fontsize=9)
    ax.legend(fontsize=6.5, loc="upper left")
    ax.grid(True, which="major", alpha=0.3)


def _command_line() -> None:
    """``python -m benchmarks.scaling [--quick] [--float32 | --peers [NAMES] | --grid] [--sizes ...]``."""
    import argparse

    from benchmarks.common import add_arguments, use_results_folder

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    alone = parser.add_mutually_exclusive_group()
    alone.add_argument("--float32", action="store_true", help="the float32 family alone")
    alone.add_argument("--peers", nargs="?", const="", metavar="NAMES",
                       help="the peer family alone (optionally some of p4,p6,bunny)")
    alone.add_argument("--grid", action="store_true", help="the cube grid against the hexagon alone")
    parser.add_argument("--sizes", metavar="LIST",
                        help="with --peers: sizes (radius or copies) as 3,6; with --grid: side:n pairs as 30:17; "
                             "a run with sizes does not replace the recorded JSON")
    args = parser.parse_args()
    use_results_folder(args.results)
    if args.float32:
        run_float32(args.quick)
    elif args.peers is not None:
        sizes = [float(s) if "." in s else int(s) for s in args.sizes.split(",")] if args.sizes else None
        run_peers(args.quick, [n for n in args.peers.split(",") if n] or None, sizes)
    elif args.grid:
        sizes = [tuple(int(x) for x in s.split(":")) for s in args.sizes.split(",")] if args.sizes else None
        run_grid(args.quick, sizes)
    else:
        run(args.quick)


if __name__ == "__main__":
    _command_line()
