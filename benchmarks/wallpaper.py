"""Cost of orbits: ``elements_within`` for the 17 groups as the disc grows.

Reports the median time per call and per tile, and each group's time as a
ratio to p1 at the same radius (measured in the same process).
"""

from __future__ import annotations

import math

from benchmarks.common import main, median_time, pyplot, save_chart, write_json
from interlock import wallpaper


def run(quick: bool = False) -> dict:
    radii = (2, 4) if quick else (2, 4, 8, 16)  # in units of sqrt(cell area)
    repeats = 3 if quick else 7
    rows = []
    for name in wallpaper.GROUPS:
        g = wallpaper.group(name)
        cell = math.sqrt(g.cell_area)
        for r in radii:
            tiles = len(g.elements_within(r * cell))
            seconds = median_time(lambda: g.elements_within(r * cell), repeats)
            rows.append({"group": name, "radius_cells": r, "tiles": tiles, "seconds": seconds,
                         "us_per_tile": 1e6 * seconds / tiles})
    base = {row["radius_cells"]: row["seconds"] for row in rows if row["group"] == "p1"}
    for row in rows:
        row["ratio_to_p1"] = row["seconds"] / base[row["radius_cells"]]
    write_json("wallpaper", {"benchmark": "elements_within", "repeats": repeats, "rows": rows})
    _chart(rows)
    return {"rows": rows}


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name in wallpaper.GROUPS:
        mine = [r for r in rows if r["group"] == name]
        ax.loglog([r["tiles"] for r in mine], [r["seconds"] for r in mine], "o-", ms=3, label=name)
    ax.set_xlabel("tiles meeting the disc")
    ax.set_ylabel("median seconds per elements_within call")
    ax.set_title("Orbit enumeration cost, 17 wallpaper groups")
    ax.legend(ncol=3, fontsize=7)
    save_chart(fig, "wallpaper")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
