"""Periodic verdicts cost the same whatever the patch: periodic_check against finite patches of radius 1..6.

For a fully deformed Escher block in each of p1, p2, p3, p4, p6 (seeded),
reports the median time of ``periodic_check`` on its cell and of ``check``
on patches of growing radius with their outer ring fixed, in the same process.
"""

from __future__ import annotations

import math

import numpy as np

from benchmarks.common import main, median_time, pyplot, save_chart, write_json
from interlock import wallpaper
from interlock.blocks import escher_block, patch, periodic_cell
from interlock.verify import check, periodic_check

GROUPS = ("p1", "p2", "p3", "p4", "p6")


def _block(name: str, seed: int = 0):
    """A block with one point pushed off the middle of each deformable edge pair."""
    group = wallpaper.group(name)
    corners = np.asarray(group.fundamental_domain().exterior.coords)
    rng = np.random.default_rng(seed)
    deformation = {}
    for s in group.side_pairings():
        if s.partner >= s.edge and not s.self_paired:
            p, q = corners[s.edge], corners[s.edge + 1]
            normal = np.array([q[1] - p[1], p[0] - q[0]])
            deformation[s.edge] = [p + 0.5 * (q - p) + rng.uniform(0.08, 0.15) * normal]
    return escher_block(group, deformation)


def run(quick: bool = False) -> dict:
    radii = (1, 2, 3) if quick else (1, 2, 3, 4, 5, 6)
    repeats = 3 if quick else 7
    rows = []
    for name in GROUPS:
        block = _block(name)
        cell = periodic_cell(block)
        verdict = periodic_check(cell)
        row = {"group": name, "status": verdict.status, "periodic_seconds": median_time(lambda: periodic_check(cell), repeats),
               "patches": []}
        unit = math.sqrt(block.group.cell_area)
        for r in radii:
            assembly = patch(block, r * unit, frame="boundary")
            seconds = median_time(lambda: check(assembly, validate=False), max(1, repeats // 2))
            row["patches"].append({"radius_cells": r, "blocks": len(assembly), "seconds": seconds,
                                   "interlocked": check(assembly, validate=False).interlocked})
        rows.append(row)
        print(f"{name}: periodic {verdict.status} in {1000 * row['periodic_seconds']:.1f} ms; patches "
              + ", ".join(f"r={p['radius_cells']}: {p['blocks']} blocks {p['seconds']:.2f} s" for p in row["patches"]))
    write_json("periodic", {"benchmark": "periodic_check vs patches", "repeats": repeats, "rows": rows})
    _chart(rows)
    return {"rows": rows}


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k, row in enumerate(rows):
        colour = f"C{k}"
        radii = [p["radius_cells"] for p in row["patches"]]
        ax.semilogy(radii, [p["seconds"] for p in row["patches"]], "o-", color=colour, label=f"{row['group']} patch")
        ax.axhline(row["periodic_seconds"], color=colour, linestyle="--", linewidth=1)
    ax.set_xlabel("patch radius (cells), outer ring fixed")
    ax.set_ylabel("median seconds per verdict")
    ax.set_title("Finite patches grow; the periodic verdict (dashed) does not")
    ax.legend(fontsize=8, ncol=2)
    save_chart(fig, "periodic")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
