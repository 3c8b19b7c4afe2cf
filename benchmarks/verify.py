"""Finite verifier speed: the TopoLite bunny, contacts through verdict, against a naive baseline.

The baseline searches contacts over all pairs of blocks (no spatial index)
and takes the rank from a dense ``numpy.linalg.matrix_rank``; both run in
the same process, so their ratio is meaningful on a shared machine.
"""

from __future__ import annotations

import time
from pathlib import Path

import networkx as nx
import numpy as np

from benchmarks.common import main, median_time, pyplot, save_chart, write_json
from interlock.blocks import Assembly, presets, random_hexagon, rhomblock_assembly
from interlock.verify import check, contacts
from interlock.verify.check import _positive_stress

BUNNY = Path(__file__).resolve().parents[2] / "shared" / "data" / "topolite" / "bunny"
BUNNY_PARTS = 80


class _AllPairs(Assembly):
    """The same assembly whose candidate contacts are all pairs of blocks."""

    @property
    def neighbours(self):
        return nx.complete_graph(len(self))


def _naive_verdict(assembly):
    from interlock.verify.matrix import interlocking_matrix

    everything = _AllPairs(assembly.meshes, assembly.types, assembly.transforms, assembly.labels, assembly.frame)
    found = contacts(everything)
    A = interlocking_matrix(everything, contacts=found)
    rank = np.linalg.matrix_rank(A.matrix.toarray())
    stress, _ = _positive_stress(A.matrix, 1e-7)
    return stress is not None and rank == A.shape[1]


def run(quick: bool = False) -> dict:
    if not BUNNY.is_dir():
        print(f"skipping the bunny: {BUNNY} is absent")
        return {}
    repeats = 3 if quick else 7
    assembly = Assembly.load([BUNNY / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)], frame=[0, 1])
    stages = {}
    verdicts = {}

    def ours():
        fresh = Assembly(assembly.meshes, assembly.types, assembly.transforms, assembly.labels, assembly.frame)
        verdict = check(fresh, validate=False)
        verdicts["ours"] = verdict
        return verdict

    def ours_validated():
        fresh = Assembly(assembly.meshes, assembly.types, assembly.transforms, assembly.labels, assembly.frame)
        return check(fresh)

    def naive():
        verdicts["naive"] = _naive_verdict(assembly)

    rows = []
    for name, fn in (("check (contacts -> verdict)", ours), ("check with overlap validation", ours_validated),
                     ("naive: all pairs, dense rank", naive)):
        seconds = median_time(fn, repeats)
        rows.append({"method": name, "median_seconds": seconds})
        print(f"{name:34s} {seconds:.3f} s (median of {repeats})")
    base = rows[-1]["median_seconds"]
    for row in rows:
        row["speedup_vs_naive"] = base / row["median_seconds"]
    start = time.perf_counter()
    stages = dict(verdicts["ours"].timings)
    stages["total"] = time.perf_counter() - start + sum(stages.values())
    result = {
        "benchmark": "verify_bunny",
        "blocks": len(assembly),
        "frame": [0, 1],
        "verdict": str(verdicts["ours"]),
        "naive_verdict_interlocked": bool(verdicts["naive"]),
        "repeats": repeats,
        "rows": rows,
        "stages_last_run": stages,
    }
    result["growth"] = _growth(quick)
    result["rhomblock"] = _rhomblock_growth(quick)
    write_json("verify", result)
    _chart(rows, result["growth"], result["rhomblock"])
    return result


def _rhomblock_growth(quick: bool) -> list[dict]:
    """Stage timings of ``check`` on RhomBlock hexagons (random tiling, outer ring fixed), and peak memory."""
    import resource

    sides = (5, 10) if quick else (5, 10, 20, 30, 40)
    rows = []
    for n in sides:
        assembly = rhomblock_assembly(random_hexagon(n, n, n, seed=1), 0, frame="boundary")
        start = time.perf_counter()
        verdict = check(assembly)
        seconds = time.perf_counter() - start
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # MiB (Linux reports KiB)
        rows.append({"side": n, "blocks": len(assembly), "seconds": seconds, "shape": list(verdict.shape),
                     "interlocked": verdict.interlocked, "stages": dict(verdict.timings), "peak_rss_mib": peak})
        print(f"RhomBlock hexagon {n}x{n}x{n} ({len(assembly)} blocks): {seconds:.2f} s, "
              f"{verdict.interlocked}, stages " + ", ".join(f"{k} {v:.2f}" for k, v in verdict.timings.items()))
    return rows


def _growth(quick: bool) -> list[dict]:
    """Seconds per verdict for square cube grids with their outer ring fixed, ours against the naive baseline."""
    sides = (4, 8) if quick else (4, 8, 16, 24)
    repeats = 3
    rows = []
    for side in sides:
        grid = presets.cube_grid(side, side)
        fresh = lambda: Assembly(grid.meshes, grid.types, grid.transforms, grid.labels, grid.frame)  # noqa: E731
        ours = median_time(lambda: check(fresh(), validate=False), repeats)
        naive = median_time(lambda: _naive_verdict(grid), repeats)
        rows.append({"blocks": side * side, "ours_seconds": ours, "naive_seconds": naive, "speedup": naive / ours})
        print(f"cube grid {side}x{side}: ours {ours:.3f} s, naive {naive:.3f} s, x{naive / ours:.1f}")
    return rows


def _chart(rows, growth, rhomblocks):
    plt = pyplot()
    if plt is None:
        return
    fig, (ax, grow, rhomb) = plt.subplots(1, 3, figsize=(16, 3.4), gridspec_kw={"width_ratios": [3, 2, 2]})
    names = [r["method"] for r in rows]
    ax.barh(names, [r["median_seconds"] for r in rows], color=["#4c72b0", "#55a868", "#c44e52"])
    for y, r in enumerate(rows):
        ax.text(r["median_seconds"], y, f"  {r['median_seconds']:.2f} s", va="center")
    ax.set_xlabel("median seconds (TopoLite bunny, 80 parts, frame 0 and 1)")
    ax.invert_yaxis()
    blocks = [g["blocks"] for g in growth]
    grow.loglog(blocks, [g["ours_seconds"] for g in growth], "o-", label="check (spatial index)")
    grow.loglog(blocks, [g["naive_seconds"] for g in growth], "s--", label="naive (all pairs, dense rank)")
    grow.set_xticks(blocks, [str(b) for b in blocks])
    grow.minorticks_off()
    grow.set_xlabel("blocks (square cube grid, ring fixed)")
    grow.set_ylabel("median seconds")
    grow.legend(fontsize=8)
    blocks = [r["blocks"] for r in rhomblocks]
    for stage in ("contacts", "rank", "lp"):
        rhomb.loglog(blocks, [r["stages"].get(stage, float("nan")) for r in rhomblocks], "o-", label=stage)
    rhomb.loglog(blocks, [r["seconds"] for r in rhomblocks], "k.-", label="total")
    rhomb.set_xlabel("RhomBlocks (n x n x n hexagon, ring fixed)")
    rhomb.set_ylabel("seconds")
    rhomb.legend(fontsize=8)
    save_chart(fig, "verify")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
