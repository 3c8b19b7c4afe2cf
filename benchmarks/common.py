"""Shared benchmark plumbing: repeated timing, machine description, result files."""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from importlib import metadata
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"

PACKAGES = ("interlock", "numpy", "scipy", "shapely", "trimesh", "spglib")


def median_time(fn, repeats: int = 5) -> float:
    """Median wall time of ``fn()`` over ``repeats`` runs, in seconds (one warm-up run first)."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def machine() -> dict:
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "versions": versions,
    }


def write_json(name: str, payload: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"machine": machine(), **payload}, indent=2))
    print(f"wrote {path}")
    return path


def pyplot():
    """matplotlib's pyplot on the off-screen backend, or None when the 'plot' extra is missing."""
    try:
        import matplotlib
    except ImportError:
        print("matplotlib is not installed (pip install 'interlock[plot]'); skipping charts")
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_chart(fig, name: str) -> Path:
    """Write ``benchmarks/results/<name>.png`` and close the figure."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    fig.clf()
    return path


def main(run, doc: str) -> None:
    """Command line of one benchmark module: ``python -m benchmarks.<name> [--quick]``."""
    import argparse

    parser = argparse.ArgumentParser(description=doc)
    parser.add_argument("--quick", action="store_true", help="a small version, for tests")
    run(quick=parser.parse_args().quick)
