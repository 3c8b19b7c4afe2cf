"""The cost of contacts of every type: the all-types contact search against the face-only one, same process.

``contacts(assembly, kinds="all")`` (faces, then vertex-face, edge-edge,
vertex-edge and vertex-vertex contacts: :mod:`interlock.verify.point_contacts`)
against ``contacts(assembly, kinds="faces")`` (Def. 3.3's model) on:

* the TopoLite bunny (``tests/data/topolite/bunny``, 80 parts, one mesh type
  each: no instancing),
* the RhomBlock hexagon 40 x 40 x 40 (``random_hexagon(40, 40, 40, seed=0)``,
  variant 0: 4,800 blocks of one mesh type, the instanced path).

The two searches alternate, ``repeats`` times each after a warm-up, in one
process, so that both see the same load on a shared machine; the ratio is
that of the medians.  The target (issue 38): all types at most twice faces.
``benchmarks/results/contact_kinds.json`` records the medians, every run, the
ratio, the contacts of each kind and the machine's load.
"""

from __future__ import annotations

import statistics
import time

from benchmarks.common import REFERENCE_DATA, limited_blas, load_average, main, write_json
from interlock.blocks import random_hexagon, rhomblock_assembly
from interlock.formats import read
from interlock.verify.contacts import contacts
from interlock.verify.point_contacts import contact_kinds

#: The all-types search may cost at most this many times the face-only one (issue 38).
TARGET_RATIO = 2.0


def subjects(quick: bool = False) -> dict:
    """The assemblies measured: the bunny and the 4,800-block hexagon (quick: the hexagon 10 x 10 x 10)."""
    folder = REFERENCE_DATA / "topolite" / "bunny"
    bunny = read([folder / f"part_{k}.obj" for k in range(1, 81)])
    side = 10 if quick else 40
    return {"bunny": bunny, f"hexagon {side}x{side}x{side}": rhomblock_assembly(random_hexagon(side, side, side,
                                                                                             seed=0), 0)}


def measure(assembly, repeats: int) -> dict:
    """Alternating runs of both searches: medians, every run, the ratio and the contacts of each kind."""
    runs = {"faces": [], "all": []}
    found = {}
    for model in ("faces", "all"):  # warm-up (facet tables of both, imports)
        found[model] = contacts(assembly, kinds=model)
    for _ in range(repeats):
        for model in ("faces", "all"):
            start = time.perf_counter()
            contacts(assembly, kinds=model)
            runs[model].append(time.perf_counter() - start)
    medians = {model: statistics.median(times) for model, times in runs.items()}
    return {"blocks": len(assembly), "median_seconds": medians, "runs": runs,
            "ratio": medians["all"] / medians["faces"], "contact_kinds": contact_kinds(found["all"]),
            "load_average": load_average()}


def run(quick: bool = False) -> dict:
    repeats = 3 if quick else 7
    results = {}
    with limited_blas():
        for name, assembly in subjects(quick).items():
            results[name] = measure(assembly, repeats)
            r = results[name]
            print(f"{name}: {r['blocks']} blocks, faces {r['median_seconds']['faces']:.3f} s, all types "
                  f"{r['median_seconds']['all']:.3f} s, ratio {r['ratio']:.2f} (target <= {TARGET_RATIO}); "
                  f"{r['contact_kinds']}")
    payload = {"repeats": repeats, "target_ratio": TARGET_RATIO, "quick": quick, "results": results,
               "within_target": all(r["ratio"] <= TARGET_RATIO for r in results.values())}
    write_json("contact_kinds" + ("_quick" if quick else ""), payload)
    return payload


if __name__ == "__main__":
    main(run, __doc__)
