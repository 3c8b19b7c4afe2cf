"""Memory: time and peak resident memory of ``check`` on inputs that are small but once blew up (issue 40).

Two families, each case in a fresh interpreter (one at a time), under
``check(..., time_limit=600)`` and an address-space cap of :data:`CAP_GB` GB
(a case past it records the error instead of taking the shared machine down):

- ``separate cubes``: ``n`` cubes of 1 mm, 10 mm apart on a square grid, no
  contact anywhere, block 0 fixed: "not interlocked" (every other block flies
  off).  Issue 40: 10,000 of them asked for 26.8 GiB (a dense ``6n x 6n``
  identity in the rank test).  Target: seconds, under 1 GB.
- ``prism``: one regular ``n``-gon prism (radius 1, height 1, built from
  ``trimesh.creation.cylinder(sections=n)``) standing on a unit-thick box of
  the same width, the box fixed (frame ``[0]``), checked with validation on
  (``validate.self_intersections`` on long thin triangles was quadratic: n =
  4,000 took 63 s and 9.4 GB).  Target for n = 20,000: under 5 s and 500 MB.

Per case: the wall time of ``check`` (validation included), its stages
(``Verdict.timings``), the verdict (``interlocked``, ``status``,
``tolerances["motion_from"]``), the peak resident set of the whole process
(``VmHWM``) and its peak above the resident set just before ``check``
(``clear_refs`` reset), in MB (10^6 bytes).  One run per case: these are
memory targets; the times are single runs on a shared 2-core machine.

``python -m benchmarks.memory [--quick] [--cubes | --prism]``: ``--quick``
runs small sizes; one flag runs that family alone (the recorded JSON is only
replaced by a run of both).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import (BLAS_THREADS, add_arguments, load_average, pyplot, save_chart, use_results_folder,
                               write_json)

ROOT = Path(__file__).resolve().parents[1]
MB = 1e6
#: Seconds for every ``check``.
TIME_LIMIT = 600.0
#: Address-space cap of each child (GB): well above the targets, well below the machine's memory.
CAP_GB = 8.0
#: Seconds before a child is killed (the time limit plus imports and building).
CHILD_TIMEOUT = TIME_LIMIT + 120.0
#: The cubes' edge and spacing (model units: mm).
CUBE_EDGE, CUBE_SPACING = 1.0, 10.0
FAMILIES = {
    "separate cubes": {"sizes": (100, 1000, 10000), "quick": (10, 100), "size": "cubes",
                       "targets": {10000: {"seconds": 10.0, "peak_mb": 1000.0}}},
    "prism": {"sizes": (500, 2000, 4000, 20000), "quick": (100, 500), "size": "sections",
              "targets": {20000: {"seconds": 5.0, "peak_mb": 500.0}}},
}


def separate_cubes(n: int):
    """``n`` 1 mm cubes 10 mm apart (no contacts), block 0 fixed."""
    import trimesh

    from interlock.blocks import Assembly

    side = int(np.ceil(np.sqrt(n)))
    transforms = np.tile(np.eye(4), (n, 1, 1))
    k = np.arange(n)
    transforms[:, 0, 3], transforms[:, 1, 3] = k % side * CUBE_SPACING, k // side * CUBE_SPACING
    return Assembly([trimesh.creation.box((CUBE_EDGE,) * 3)], np.zeros(n, dtype=int), transforms, frame=[0])


def prism(sections: int):
    """A fixed unit-thick box (block 0) and a regular ``sections``-gon prism of radius 1 standing on it."""
    import trimesh

    from interlock.blocks import Assembly

    column = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=sections)
    column.apply_translation((0, 0, 0.5))
    base = trimesh.creation.box((2.5, 2.5, 1.0))
    base.apply_translation((0, 0, -0.5))
    return Assembly.from_meshes([base, column], frame=[0])


MAKERS = {"separate cubes": separate_cubes, "prism": prism}


def child(family: str, size: int) -> dict:
    """In a fresh interpreter: build the case, run ``check`` once, report seconds and peak memory."""
    import resource

    from threadpoolctl import threadpool_limits

    import clarabel  # noqa: F401  (imported on first use; counted before the check)
    from interlock.verify import check

    cap = int(CAP_GB * 1e9)
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    with threadpool_limits(BLAS_THREADS, "blas"):
        start = time.perf_counter()
        assembly = MAKERS[family](size)
        built = time.perf_counter() - start
        Path("/proc/self/clear_refs").write_text("5")
        before = _status("VmRSS")
        start = time.perf_counter()
        try:
            verdict = check(assembly, time_limit=TIME_LIMIT)
        except MemoryError as error:
            return {"size": size, "error": f"MemoryError {error}", "seconds": time.perf_counter() - start,
                    "peak_mb": _status("VmHWM") / MB}
        seconds = time.perf_counter() - start
    return {"size": size, "blocks": len(assembly), "faces": int(sum(len(m.faces) for m in assembly.meshes)),
            "build_seconds": built, "seconds": seconds, "stages": verdict.timings,
            "interlocked": verdict.interlocked, "status": verdict.status[:300],
            "motion_from": verdict.tolerances.get("motion_from"), "shape": list(verdict.shape),
            "peak_mb": _status("VmHWM") / MB, "peak_above_start_mb": (_status("VmHWM") - before) / MB,
            "rss_before_mb": before / MB}


def _status(key: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    raise KeyError(key)


def _run_child(family: str, size: int) -> dict:
    code = f"import json; from benchmarks.memory import child; print(json.dumps(child({family!r}, {size})))"
    start = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                              timeout=CHILD_TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"size": size, "error": f"killed after {CHILD_TIMEOUT:.0f} s", "seconds": CHILD_TIMEOUT}
    if done.returncode != 0:
        return {"size": size, "error": " | ".join(done.stderr.strip().splitlines()[-3:]),
                "seconds": time.perf_counter() - start}
    return json.loads(done.stdout.strip().splitlines()[-1])


def run(quick: bool = False, only=None) -> dict:
    start, load = time.perf_counter(), load_average()
    families = {}
    for name, family in FAMILIES.items():
        if only and name != only:
            continue
        rows = []
        for size in family["quick" if quick else "sizes"]:
            row = _run_child(name, size)
            target = family["targets"].get(size)
            if target and "error" not in row:
                row["target"] = target
                row["meets_target"] = row["seconds"] <= target["seconds"] and row["peak_mb"] <= target["peak_mb"]
            rows.append(row)
            _print(name, family["size"], row)
        families[name] = {"size": family["size"], "rows": rows}
    payload = {"benchmark": "memory", "quick": quick,
               "policy": {"time_limit": TIME_LIMIT, "cap_gb": CAP_GB, "blas_threads": BLAS_THREADS, "runs": 1},
               "load_average_at_start": load, "families": families, "seconds": time.perf_counter() - start}
    if only is None:
        write_json("memory", payload)
        _chart(payload)
    return payload


def _print(name: str, size_name: str, row: dict) -> None:
    if "error" in row:
        print(f"{name} {size_name}={row['size']}: {row['error']} after {row['seconds']:.1f} s", flush=True)
        return
    stages = ", ".join(f"{k} {v:.2f}" for k, v in row["stages"].items() if v >= 0.01)
    print(f"{name} {size_name}={row['size']} ({row['blocks']} blocks, {row['faces']} faces): {row['seconds']:.2f} s "
          f"[{stages}], peak {row['peak_mb']:.0f} MB ({row['peak_above_start_mb']:.0f} above the start); "
          f"{row['interlocked']} ({row['motion_from']}): {row['status'][:90]}"
          + (f"; meets target {row['meets_target']}" if "target" in row else ""), flush=True)


def _chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    fig, grid = plt.subplots(1, 2, figsize=(13, 5))
    for (name, family), colour in zip(payload["families"].items(), ("C0", "C1")):
        rows = [row for row in family["rows"] if "error" not in row]
        sizes = [row["size"] for row in rows]
        grid[0].loglog(sizes, [row["seconds"] for row in rows], "o-", color=colour,
                       label=f"{name} (x: {family['size']})")
        grid[1].loglog(sizes, [row["peak_mb"] for row in rows], "o-", color=colour, label=f"{name}: process peak")
        grid[1].loglog(sizes, [row["peak_above_start_mb"] for row in rows], "s--", color=colour,
                       label=f"{name}: above the start of check")
        for size, target in FAMILIES[name]["targets"].items():
            grid[0].plot([size], [target["seconds"]], "v", color=colour, ms=9, mfc="none",
                         label=f"{name}: target at {size:,}")
            grid[1].plot([size], [target["peak_mb"]], "v", color=colour, ms=9, mfc="none",
                         label=f"{name}: target at {size:,}")
        for row in family["rows"]:
            if "error" in row:
                grid[0].plot([row["size"]], [row["seconds"]], "x", color=colour, ms=9)
    grid[0].set_ylabel("seconds of check (validation included), one run")
    grid[1].set_ylabel("peak resident memory (MB)")
    grid[0].set_xlabel("cubes / prism sections")
    grid[1].set_xlabel("cubes / prism sections")
    for ax in grid:
        ax.legend(fontsize=7)
        ax.grid(True, which="major", alpha=0.3)
    save_chart(fig, "memory")
    plt.close(fig)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(parser)
    alone = parser.add_mutually_exclusive_group()
    alone.add_argument("--cubes", action="store_true", help="the separate cubes alone")
    alone.add_argument("--prism", action="store_true", help="the prism alone")
    args = parser.parse_args()
    use_results_folder(args.results)
    run(args.quick, "separate cubes" if args.cubes else "prism" if args.prism else None)
