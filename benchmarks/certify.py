"""Certificates at scale: ``check(certify=True)`` against the float verdict, and the largest hexagon.

The four families of :mod:`benchmarks.scaling` (RhomBlock hexagons n = 5 ...
40 and p4 Escher patches, ring fixed: interlocked; block 0 fixed: not
interlocked).  For each size, the medians of several runs of ``check``
(contacts precomputed, no overlap validation) without and with
``certify=True`` in the same process, and their ratio (target: at most 10).
Each row records what the certificate rests on (the verdict's status).

Then the RhomBlock hexagon 60 x 60 x 60 (10,800 blocks), ring and block 0
fixed, each in a fresh interpreter: the whole pipeline from the tiling
(generation, contacts, verdict) and the certified verdict, time and peak
resident memory (targets: 60 s and 2 GB each).

Chart: one panel per family, float and certified verdict times against the
number of blocks, the ratio on a second axis; a bar chart of the 10,800-block runs.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.common import limited_blas, load_average, main, pyplot, save_chart, write_json
from benchmarks.scaling import FAMILIES, rhomblocks, rhomblocks_one_fixed
from interlock.verify import check, contacts

ROOT = Path(__file__).resolve().parents[1]
#: Runs per size (fewer once one run takes longer than ``RUN_BUDGET`` seconds).
RUNS, QUICK_RUNS = 3, 1
RUN_BUDGET = 30.0
#: The largest hexagon: n = 60 (10,800 blocks); ``LARGE_QUICK`` for tests.
LARGE, LARGE_QUICK = 60, 6


def _median(fn, runs: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
        if times[-1] > RUN_BUDGET:
            break
    return statistics.median(times), result


def _row(assembly, runs: int) -> dict:
    found = contacts(assembly)
    plain, verdict = _median(lambda: check(assembly, contacts=found, validate=False), runs)
    certified, proof = _median(lambda: check(assembly, contacts=found, validate=False, certify=True), runs)
    return {"blocks": len(assembly), "float_seconds": plain, "certify_seconds": certified,
            "ratio": certified / plain, "interlocked": verdict.interlocked, "certified": proof.certified,
            "certificate": proof.status.rsplit("; ", 1)[-1]}


def large_child(n: int, one_fixed: bool) -> dict:
    """In a fresh interpreter: the pipeline on the n x n x n hexagon, float then certified, with peak memory (MB)."""
    build = rhomblocks_one_fixed if one_fixed else rhomblocks
    start = time.perf_counter()
    with limited_blas():
        assembly = build(n)
        found = contacts(assembly)
        prepared = time.perf_counter()
        verdict = check(assembly, contacts=found, validate=False)
        done = time.perf_counter()
        proof = check(assembly, contacts=found, validate=False, certify=True)
        certified = time.perf_counter()
    peak = _peak_mb()
    return {"blocks": len(assembly), "generation_and_contacts_seconds": prepared - start,
            "pipeline_seconds": done - start, "certified_pipeline_seconds": certified - done + (prepared - start),
            "timings": verdict.timings, "interlocked": verdict.interlocked, "certified": proof.certified,
            "certificate": proof.status.rsplit("; ", 1)[-1], "peak_mb": peak}


def _peak_mb() -> float | None:
    status = Path("/proc/self/status")
    if not status.exists():
        return None
    for line in status.read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return None


def _large(n: int, one_fixed: bool) -> dict | None:
    code = ("import json; from benchmarks.certify import large_child; "
            f"print(json.dumps(large_child({n}, {one_fixed})))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        return {"failed": (done.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def run(quick: bool = False) -> dict:
    start, load = time.perf_counter(), load_average()
    runs = QUICK_RUNS if quick else RUNS
    families = {}
    with limited_blas():
        for family in FAMILIES:
            rows = []
            for size in (family.quick_sizes if quick else family.sizes):
                row = {"size": size, **_row(family.generate(size), runs)}
                print(f"{family.name} {size}: {row['blocks']} blocks, float {row['float_seconds']:.2f} s, "
                      f"certify {row['certify_seconds']:.2f} s (x{row['ratio']:.1f}), {row['certificate']}")
                rows.append(row)
            families[family.name] = {"description": family.description, "rows": rows}
    n = LARGE_QUICK if quick else LARGE
    large = {name: _large(n, one_fixed) for name, one_fixed in (("ring fixed", False), ("one fixed", True))}
    for name, row in large.items():
        print(f"hexagon {n}x{n}x{n} {name}: {row}")
    payload = {"benchmark": "certify", "quick": quick, "runs": runs, "load_average_at_start": load,
               "families": families, "largest_ratio": max(r["ratio"] for f in families.values() for r in f["rows"]),
               "large": {"n": n, **large}, "seconds": time.perf_counter() - start}
    print(f"certify ({'quick' if quick else 'full'}): largest ratio {payload['largest_ratio']:.2f}, "
          f"{payload['seconds']:.0f} s")
    write_json("certify", payload)
    _chart(payload)
    return payload


def _chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    fig, axes = plt.subplots(1, 5, figsize=(24, 4.8))
    for ax, (name, family) in zip(axes, payload["families"].items()):
        rows = family["rows"]
        blocks = [r["blocks"] for r in rows]
        ax.loglog(blocks, [r["float_seconds"] for r in rows], "o-", label="float verdict")
        ax.loglog(blocks, [r["certify_seconds"] for r in rows], "s-", label="certify=True")
        ax.set_xlabel("blocks")
        ax.set_ylabel("seconds (median)")
        ax.set_title(name, fontsize=9)
        twin = ax.twinx()
        twin.semilogx(blocks, [r["ratio"] for r in rows], "k:", label="ratio")
        twin.axhline(10, color="red", lw=0.8)
        twin.set_ylim(0, 12)
        twin.set_ylabel("certify / float (target <= 10, red)")
        ax.legend(fontsize=8, loc="upper left")
    large = payload["large"]
    names = [k for k in ("ring fixed", "one fixed") if "blocks" in large.get(k, {})]
    ax = axes[-1]
    ax.bar([f"{k}\nfloat" for k in names], [large[k]["pipeline_seconds"] for k in names])
    ax.bar([f"{k}\ncertified" for k in names], [large[k]["certified_pipeline_seconds"] for k in names])
    ax.axhline(60, color="red", lw=0.8)
    ax.set_ylabel("seconds, tiling to verdict (target 60, red)")
    ax.set_title(f"hexagon {large['n']}^3: peak MB " + ", ".join(f"{large[k]['peak_mb']:.0f}" for k in names),
                 fontsize=9)
    fig.suptitle("check(certify=True) against the float verdict, same process, same contacts")
    fig.tight_layout()
    save_chart(fig, "certify")


if __name__ == "__main__":
    main(run, __doc__)
