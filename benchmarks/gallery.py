"""The gallery and exports: the whole gallery's wall time, and exporting and drawing a 4,800-block RhomBlock assembly.

Per gallery entry the time of each stage (generate, finite verdict, periodic
verdict, export, render) comes from the entries' records; the export of the
4,800-block assembly (:func:`interlock.write`) is timed per format, and its picture (``render``, small
size), as medians of several runs.  (The tests assert what these write, not how
fast.)
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from benchmarks.common import main, median_time, pyplot, save_chart, write_json
from interlock.blocks import random_hexagon, rhomblock_assembly
from interlock.formats import write
from interlock.gallery import build, render



def _big(quick: bool):
    """A RhomBlock assembly on a random hexagon: 4,800 blocks (a x b + b x c + c x a with a = b = c = 40)."""
    size = (10, 10, 10) if quick else (40, 40, 40)
    return rhomblock_assembly(random_hexagon(*size, seed=0), 0)


def run(quick: bool = False) -> dict:
    with tempfile.TemporaryDirectory() as folder:
        gallery = build(Path(folder) / "gallery", quick=quick)
        entries = [{"name": r.name, "blocks": r.record["blocks"], "timings": r.record["timings"]}
                   for r in gallery.entries]
        print(f"gallery ({'quick' if quick else 'full'}): {len(entries)} entries in {gallery.seconds:.1f} s, "
              f"{len(gallery.contradictions)} contradictions")
        assembly = _big(quick)
        exports = {}
        for suffix in (".stl", ".glb", ".3mf", ".vtu"):
            path = Path(folder) / f"big{suffix}"
            exports[suffix] = median_time(lambda: write(assembly, path), 3)
            print(f"export {len(assembly)} RhomBlocks to {suffix}: {exports[suffix]:.2f} s "
                  f"({path.stat().st_size / 1e6:.1f} MB)")
        picture = Path(folder) / "big.png"
        drawing = median_time(lambda: render(assembly, picture, size=(3.0, 3.0), dpi=60), 3)
        print(f"render {len(assembly)} RhomBlocks: {drawing:.2f} s")
    payload = {"benchmark": "gallery and exports", "quick": quick, "gallery_seconds": gallery.seconds,
               "contradictions": list(gallery.contradictions), "entries": entries,
               "export_blocks": len(assembly), "export_seconds": exports,
               "render_seconds": drawing}
    write_json("gallery", payload)
    _chart(entries)
    return payload


def _chart(entries):
    plt = pyplot()
    if plt is None:
        return
    stages = ("generate", "finite_verdict", "periodic_verdict", "export", "render")
    fig, ax = plt.subplots(figsize=(8, 0.28 * len(entries) + 1.5))
    left = [0.0] * len(entries)
    for k, stage in enumerate(stages):
        widths = [e["timings"].get(stage, 0.0) for e in entries]
        ax.barh(range(len(entries)), widths, left=left, color=f"C{k}", label=stage.replace("_", " "))
        left = [a + b for a, b in zip(left, widths)]
    ax.set_yticks(range(len(entries)), [f"{e['name']} ({e['blocks']})" for e in entries], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("seconds")
    ax.set_title(f"Gallery: {sum(left):.0f} s for {len(entries)} entries")
    ax.legend(fontsize=7, loc="lower right")
    save_chart(fig, "gallery")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
