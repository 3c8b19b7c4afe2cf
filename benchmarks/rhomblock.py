"""Cost of RhomBlock assemblies: sampling uniform n x n x n hexagon tilings and building their assemblies.

For each side ``n`` (``3 n^2`` blocks) reports the median wall time of
``random_hexagon(n, n, n, seed)`` (coupling from the past; the time varies with
the seed, so every run uses another one) and of ``rhomblock_assembly`` on the
sampled tiling, for both variants of main paper Thm. 4.9.
"""

from __future__ import annotations

import statistics
import time

from benchmarks.common import main, pyplot, save_chart, write_json
from interlock.blocks.lozenge import random_hexagon
from interlock.blocks.rhomblock import VARIANTS, rhomblock_assembly


def run(quick: bool = False) -> dict:
    sides = (10, 20, 40) if quick else (5, 10, 20, 30, 40, 50)
    repeats = 3 if quick else 7
    rows = []
    for n in sides:
        sample, build = [], []
        for seed in range(repeats):
            start = time.perf_counter()
            tiling = random_hexagon(n, n, n, seed=seed)
            sample.append(time.perf_counter() - start)
            start = time.perf_counter()
            assemblies = [rhomblock_assembly(tiling, variant) for variant in VARIANTS]
            build.append((time.perf_counter() - start) / len(VARIANTS))
        assert all(len(a) == 3 * n * n for a in assemblies)
        rows.append({"side": n, "blocks": 3 * n * n, "sample_seconds": statistics.median(sample),
                     "assembly_seconds": statistics.median(build), "sample_runs": sample, "assembly_runs": build})
        print(f"n = {n:3d} ({3 * n * n:5d} blocks): sampling {rows[-1]['sample_seconds']:.3f} s, "
              f"assembly {rows[-1]['assembly_seconds']:.3f} s (medians of {repeats})")
    write_json("rhomblock", {"benchmark": "random_hexagon + rhomblock_assembly", "repeats": repeats,
                                    "rows": rows})
    _chart(rows)
    return {"rows": rows}


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    sides = [r["side"] for r in rows]
    ax.loglog(sides, [r["sample_seconds"] for r in rows], "o-", label="random_hexagon (coupling from the past)")
    ax.loglog(sides, [r["assembly_seconds"] for r in rows], "s-", label="rhomblock_assembly (per variant)")
    for r in rows:
        ax.annotate(f"{r['blocks']} blocks", (r["side"], r["sample_seconds"]), textcoords="offset points",
                    xytext=(4, 6), fontsize=7)
    ax.set_xticks(sides, [str(n) for n in sides])
    ax.minorticks_off()
    ax.set_xlabel("hexagon side n (n x n x n hexagon, 3 n^2 blocks)")
    ax.set_ylabel("median seconds")
    ax.set_title("RhomBlock assemblies on uniform random lozenge tilings")
    ax.legend(fontsize=8)
    save_chart(fig, "rhomblock")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
