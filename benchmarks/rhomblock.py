"""RhomBlock generation across seeds: how much the sampling time of n x n x n hexagons varies, and both variants.

Sampling a uniform lozenge tiling by coupling from the past takes a random
time, so for each side ``n`` (``3 n^2`` blocks) ``random_hexagon(n, n, n, seed)``
runs with several seeds and every time is kept (min, median, max); then
``rhomblock_assembly`` builds each variant of main paper Thm. 4.9 on the
sampled tiling (median over the seeds).  The cost of generation next to the
verifier's stages, for one seed, is ``benchmarks/scaling.py``.
"""

from __future__ import annotations

import statistics
import time

from benchmarks.common import main, pyplot, save_chart, write_json
from interlock.blocks.lozenge import random_hexagon
from interlock.blocks.rhomblock import VARIANTS, rhomblock_assembly


def run(quick: bool = False) -> dict:
    sides = (5, 10, 20) if quick else (5, 10, 20, 30, 40, 50)
    seeds = range(3 if quick else 7)
    rows = []
    for n in sides:
        sample, build = [], {variant: [] for variant in VARIANTS}
        for seed in seeds:
            start = time.perf_counter()
            tiling = random_hexagon(n, n, n, seed=seed)
            sample.append(time.perf_counter() - start)
            for variant in VARIANTS:
                start = time.perf_counter()
                assembly = rhomblock_assembly(tiling, variant)
                build[variant].append(time.perf_counter() - start)
                assert len(assembly) == 3 * n * n
        rows.append({"side": n, "blocks": 3 * n * n, "sample_seconds": statistics.median(sample),
                     "sample_min": min(sample), "sample_max": max(sample), "sample_runs": sample,
                     "assembly_seconds": {str(v): statistics.median(t) for v, t in build.items()}})
        print(f"n = {n:3d} ({3 * n * n:5d} blocks): sampling {min(sample):.3f} / {statistics.median(sample):.3f} / "
              f"{max(sample):.3f} s (min / median / max of {len(sample)} seeds), assembly "
              + ", ".join(f"variant {v} {statistics.median(t):.3f} s" for v, t in build.items()))
    write_json("rhomblock", {"benchmark": "random_hexagon across seeds + rhomblock_assembly per variant",
                             "seeds": len(seeds), "rows": rows})
    _chart(rows)
    return {"rows": rows}


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    blocks = [r["blocks"] for r in rows]
    for r in rows:
        ax.loglog([r["blocks"]] * len(r["sample_runs"]), r["sample_runs"], ".", color="C0", alpha=0.5)
    ax.loglog(blocks, [r["sample_seconds"] for r in rows], "o-", color="C0",
              label="random_hexagon: every seed (dots), median (line)")
    for k, variant in enumerate(rows[0]["assembly_seconds"]):
        ax.loglog(blocks, [r["assembly_seconds"][variant] for r in rows], "s-", color=f"C{k + 1}",
                  label=f"rhomblock_assembly, variant {variant} (median)")
    ax.set_xticks(blocks, [f"{b}\nn={r['side']}" for b, r in zip(blocks, rows)], fontsize=7)
    ax.minorticks_off()
    ax.set_xlabel("blocks (n x n x n hexagon, 3 n^2 blocks)")
    ax.set_ylabel("seconds")
    ax.set_title("RhomBlock generation: coupling from the past takes a random time")
    ax.legend(fontsize=8)
    save_chart(fig, "rhomblock")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
