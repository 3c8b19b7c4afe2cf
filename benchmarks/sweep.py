"""Sweep throughput: periodic verdicts per second on 1 and 2 local processes and on a 2-worker Dask cluster.

For each rotation group p1, p2, p3, p4, p6 (there is no p5: the
crystallographic restriction allows only 1-, 2-, 3-, 4- and 6-fold rotations)
one sweep of N points (48, quick: 8 for p1 and p4): a single intermediate
point at the middle of edge 0 of the fundamental domain, pushed off the edge
by ``s`` edge lengths, ``s`` on an even grid over [-0.1, 0.1] (0 is never on
it, so every block is deformed), with the ``"periodic"`` verdict only.  Each
sweep goes through four paths:

- ``in-process``: ``evaluate_chunk`` (the task of a sweep worker) on all the
  points in this process (no pool; what the points cost by themselves);
- ``1 process`` / ``2 processes``: :func:`interlock.sweep.run` with its own
  ``ProcessPoolExecutor(workers)``, created and shut down inside every call
  (its start-up is part of the time, as for a user);
- ``Dask, 2 workers``: ``run(spec, executor=client)`` on one
  ``distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True)``
  created once; its start-up and the first sweep on its fresh workers are
  reported apart and not in the medians.

Times are wall seconds of the whole call, the median of 3 repeats (1 quick),
the repeats interleaved across groups and paths so that load from other jobs
on a shared machine falls on every path alike.  Reported per group and path:
all times, the median, verdicts per second (points / median seconds), the
mean time of one point where it ran (its record's ``seconds``) and the points'
seconds summed over the wall seconds of the call (about the cores it got), the
speed-up of 2 processes over 1 (verdicts/s of 2 over those of 1) and the Dask overhead
time(Dask) / time(2 processes); plus the counts of ok / invalid / failed
points.  Every path must give identical statuses and verdicts for every
point (asserted; ``verdicts_identical`` in the JSON).  The chunk size is 4
points, so 2 workers have several chunks each.

Run: ``python -m benchmarks.sweep [--quick] [--results DIR]`` (writes
``sweep.json`` and ``sweep.png``).
"""

from __future__ import annotations

import logging
import os
import statistics
import time

from benchmarks.common import limited_blas, load_average, main, pyplot, save_chart, write_json
from interlock.sweep import load_spec
from interlock.sweep import run as run_sweep
from interlock.sweep.record import evaluate_chunk

GROUPS = ("p1", "p2", "p3", "p4", "p6")
QUICK_GROUPS = ("p1", "p4")
PATHS = ("in-process", "1 process", "2 processes", "Dask, 2 workers")
FULL = {"groups": GROUPS, "points": 48, "repeats": 3}
QUICK = {"groups": QUICK_GROUPS, "points": 8, "repeats": 1}
#: The offset range of the intermediate point, in edge lengths (an even number of steps never hits 0).
OFFSETS = (-0.1, 0.1)
CHUNK = 4
STATUSES = ("ok", "invalid", "failed")
DASK_WORKERS = 2


def spec_for(group: str, points: int):
    return load_spec({"group": group, "verdicts": ["periodic"], "name": f"benchmark-{group}",
                      "parameters": {"s": {"range": list(OFFSETS), "steps": points}},
                      "points": [{"edge": 0, "along": 0.5, "offset": "s"}], "chunk": CHUNK})


def _fingerprint(records) -> list:
    """What must agree between paths: index, parameters, status and verdicts of every point."""
    return [(r["index"], r["parameters"], r["status"], r["verdicts"])
            for r in sorted(records, key=lambda r: r["index"])]


def _in_process(spec):
    with limited_blas():
        return evaluate_chunk(spec, list(enumerate(spec.points())))


def run(quick: bool = False) -> dict:
    from distributed import Client, LocalCluster

    settings = QUICK if quick else FULL
    groups, n, repeats = settings["groups"], settings["points"], settings["repeats"]
    specs = {g: spec_for(g, n) for g in groups}
    for spec in specs.values():
        assert not any(p["s"] == 0.0 for p in spec.points()), "an offset of 0 leaves the edge undeformed"

    load_at_start = load_average()
    # warm this process (imports, caches) before anything is timed; forked pool workers inherit it
    _in_process(spec_for(groups[0], 2))

    start = time.perf_counter()
    cluster = LocalCluster(n_workers=DASK_WORKERS, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    client.wait_for_workers(DASK_WORKERS)
    cluster_seconds = time.perf_counter() - start
    print(f"Dask LocalCluster ({DASK_WORKERS} workers) up in {cluster_seconds:.2f} s")

    reference = {g: None for g in groups}
    seconds = {g: {path: [] for path in PATHS} for g in groups}
    busy = {g: {path: [] for path in PATHS} for g in groups}  # the sum of the points' own seconds, per run
    counts = {}

    def record(group, path, elapsed, records):
        fingerprint = _fingerprint(records)
        assert len(fingerprint) == n, (group, path, len(fingerprint))
        if reference[group] is None:
            reference[group] = fingerprint
            counts[group] = {status: sum(r["status"] == status for r in records) for status in STATUSES}
            counts[group]["verdicts"] = {}
            for r in records:
                for word in r["verdicts"].values():
                    counts[group]["verdicts"][word] = counts[group]["verdicts"].get(word, 0) + 1
        assert fingerprint == reference[group], f"{group}: {path} gives other verdicts than the first path"
        if elapsed is not None:
            seconds[group][path].append(elapsed)
            busy[group][path].append(sum(r["seconds"] for r in records))

    try:
        # the first sweep on the cluster: the first tasks of its freshly spawned workers, not in the medians
        start = time.perf_counter()
        records = run_sweep(specs[groups[0]], executor=client)
        first_dask_seconds = time.perf_counter() - start
        record(groups[0], "Dask, 2 workers", None, records)
        print(f"first Dask sweep (cold workers, {groups[0]}, {n} points) {first_dask_seconds:.2f} s")

        paths = {
            "in-process": _in_process,
            "1 process": lambda spec: run_sweep(spec, workers=1),
            "2 processes": lambda spec: run_sweep(spec, workers=2),
            "Dask, 2 workers": lambda spec: run_sweep(spec, executor=client),
        }
        for repeat in range(repeats):
            for group in groups:
                # rotate the order of the paths per repeat and group, so no path always runs first
                shift = (repeat + groups.index(group)) % len(PATHS)
                for path in PATHS[shift:] + PATHS[:shift]:
                    start = time.perf_counter()
                    records = paths[path](specs[group])
                    record(group, path, time.perf_counter() - start, records)
            print(f"repeat {repeat + 1}/{repeats} done")
    finally:
        client.close()
        cluster.close()

    rows = []
    for group in groups:
        row = {"group": group, "points": n, "counts": counts[group], "paths": {}}
        for path in PATHS:
            median = statistics.median(seconds[group][path])
            runs = seconds[group][path]
            row["paths"][path] = {"seconds_median": median, "seconds_all": runs, "verdicts_per_second": n / median,
                                  # points' own wall seconds summed over wall seconds of the call: about the
                                  # number of cores the path got (below 1: pool or scheduling overhead)
                                  "busy_over_wall_median": statistics.median(b / t for b, t in
                                                                             zip(busy[group][path], runs)),
                                  # the mean of the points' own seconds (record["seconds"]) where they ran
                                  "point_seconds_median": statistics.median(busy[group][path]) / n}
        t = {path: row["paths"][path]["seconds_median"] for path in PATHS}
        row["ratios"] = {"speedup_2_vs_1_processes": t["1 process"] / t["2 processes"],
                         "dask_overhead_vs_2_processes": t["Dask, 2 workers"] / t["2 processes"],
                         "pool_overhead_1_process_vs_in_process": t["1 process"] / t["in-process"]}
        rows.append(row)
        print(f"{group}: " + ", ".join(f"{path} {n / t[path]:.1f}/s (busy/wall "
                                       f"{row['paths'][path]['busy_over_wall_median']:.2f})" for path in PATHS)
              + f"; 2/1 speed-up {row['ratios']['speedup_2_vs_1_processes']:.2f}, Dask/2 processes "
              f"{row['ratios']['dask_overhead_vs_2_processes']:.2f}; counts {counts[group]}")

    total = {}
    for path in PATHS:
        # all groups together: total points over the sum of the per-group medians
        total_seconds = sum(row["paths"][path]["seconds_median"] for row in rows)
        total[path] = {"seconds_median_sum": total_seconds, "verdicts_per_second": n * len(rows) / total_seconds}
    overall = {"speedup_2_vs_1_processes": total["1 process"]["seconds_median_sum"]
               / total["2 processes"]["seconds_median_sum"],
               "dask_overhead_vs_2_processes": total["Dask, 2 workers"]["seconds_median_sum"]
               / total["2 processes"]["seconds_median_sum"]}
    print("all groups: " + ", ".join(f"{path} {total[path]['verdicts_per_second']:.1f}/s" for path in PATHS)
          + f"; 2/1 speed-up {overall['speedup_2_vs_1_processes']:.2f}, Dask overhead "
          f"{overall['dask_overhead_vs_2_processes']:.2f}")

    payload = {
        "benchmark": "sweep throughput: periodic verdicts per second on local processes and Dask",
        "quick": quick,
        "parameters": {"groups": list(groups), "points_per_group": n, "repeats": repeats, "chunk": CHUNK,
                       "offsets": list(OFFSETS), "edge": 0, "along": 0.5, "verdicts": ["periodic"],
                       "dask": {"n_workers": DASK_WORKERS, "threads_per_worker": 1, "processes": True}},
        "load_average_at_start": load_at_start,
        "dask_cluster_start_seconds": cluster_seconds,
        "dask_first_sweep_seconds": first_dask_seconds,
        "verdicts_identical": True,  # asserted above for every path and repeat
        "counts": {g: counts[g] for g in groups},
        "rows": rows,
        "total": total,
        "ratios": overall,
    }
    write_json("sweep", payload)
    _chart(rows, repeats, load_at_start)
    return payload


def _chart(rows, repeats, load):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(10, 5.2))
    width = 0.8 / len(PATHS)
    colours = ("#999999", "#56B4E9", "#0072B2", "#E69F00")
    for k, path in enumerate(PATHS):
        xs = [i + (k - (len(PATHS) - 1) / 2) * width for i in range(len(rows))]
        values = [row["paths"][path]["verdicts_per_second"] for row in rows]
        bars = ax.bar(xs, values, width, label=path, color=colours[k])
        ax.bar_label(bars, fmt="%.0f", fontsize=7, padding=1)
    ax.set_xticks(range(len(rows)), [f"{row['group']}\n2 proc./1 proc. "
                                     f"{row['ratios']['speedup_2_vs_1_processes']:.2f}x\ntime Dask/2 proc. "
                                     f"{row['ratios']['dask_overhead_vs_2_processes']:.2f}x" for row in rows],
                  fontsize=8)
    ax.set_ylabel("periodic verdicts per second")
    ax.set_title(f"Sweep throughput, {rows[0]['points']} points per group "
                 f"(median of {repeats} run{'s' if repeats > 1 else ''}, {os.cpu_count()} cores)"
                 + ("" if load is None else f"\nshared machine, load average {load[0]:.1f} at the start"), fontsize=11)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    ax.grid(axis="y", alpha=0.3)
    save_chart(fig, "sweep")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
