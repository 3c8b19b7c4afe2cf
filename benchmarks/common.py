"""Shared benchmark plumbing: repeated timing, machine description, result files, and the naive baseline."""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from importlib import metadata
from pathlib import Path

import networkx as nx
import numpy as np
import scipy.optimize
import scipy.sparse as sp

from interlock.blocks import Assembly
from interlock.files import atomic_write, write_atomically

RESULTS = Path(__file__).resolve().parent / "results"
#: The reference data of other projects (TopoLite, compas_cra), kept with the tests.
REFERENCE_DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
#: Environment variable naming another folder for results (``--results DIR``): quick runs in tests write there.
RESULTS_VARIABLE = "INTERLOCK_BENCHMARK_RESULTS"


def results_folder() -> Path:
    """Where JSON and charts go: ``$INTERLOCK_BENCHMARK_RESULTS`` if set, else ``benchmarks/results``."""
    folder = Path(os.environ.get(RESULTS_VARIABLE) or RESULTS)
    folder.mkdir(parents=True, exist_ok=True)
    return folder

PACKAGES = ("interlock", "numpy", "scipy", "shapely", "trimesh", "spglib")
#: Threads of the BLAS while a benchmark times (as in ``periodic_check``): on a 2-core machine shared with
#: one other job, two OpenBLAS threads made the dense rank test of a 241-block patch 8.0 s instead of 0.13 s.
BLAS_THREADS = 1


def median_time(fn, repeats: int = 5) -> float:
    """Median wall time of ``fn()`` over ``repeats`` runs, in seconds (one warm-up run first)."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def limited_blas():
    """A context in which the BLAS runs on :data:`BLAS_THREADS` threads."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(BLAS_THREADS, "blas")


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
        "load_average": load_average(),
        "blas_threads_default": _blas_threads(),
        "versions": versions,
    }


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages (other work on a shared machine), or None where unknown."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None


def _blas_threads() -> int | None:
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return None
    return max((pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"), default=None)


def write_json(name: str, payload: dict) -> Path:
    """Write ``benchmarks/results/<name>.json`` (with this machine's description) atomically: an interrupted run
    leaves the last record whole (``run_armadillo`` and ``run_exported`` of the stability benchmark read it back)."""
    path = write_atomically(results_folder() / f"{name}.json", json.dumps({"machine": machine(), **payload},
                                                                           indent=2))
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


def save_chart(fig, name: str, tight: bool = True) -> Path:
    """Write ``benchmarks/results/<name>.png`` atomically and clear the figure; ``tight=False`` keeps a layout
    the caller has set (``subplots_adjust``)."""
    path = results_folder() / f"{name}.png"
    if tight:
        fig.tight_layout()
    with atomic_write(path) as temporary:
        fig.savefig(temporary, dpi=120)
    fig.clf()
    return path


def main(run, doc: str) -> None:
    """Command line of one benchmark module: ``python -m benchmarks.<name> [--quick]``."""
    import argparse

    parser = argparse.ArgumentParser(description=doc)
    add_arguments(parser)
    args = parser.parse_args()
    use_results_folder(args.results)
    run(quick=args.quick)


def add_arguments(parser) -> None:
    parser.add_argument("--quick", action="store_true", help="a small version, for tests")
    parser.add_argument("--results", metavar="DIR", help="write JSON and charts here instead of benchmarks/results")


def use_results_folder(folder) -> None:
    if folder is not None:
        os.environ[RESULTS_VARIABLE] = str(Path(folder).resolve())


# --- the naive baseline ---------------------------------------------------------------
# What published solvers do, run in the same process as ``check`` so that ratios mean something on a shared
# machine: every pair of blocks is a candidate contact, the rank is a dense SVD, and the stress LP carries
# one inequality row per contact row.

#: The stages of a naive verdict, in order (the interlocking matrix is the same function as ours).
NAIVE_STAGES = ("contacts", "matrix", "rank", "lp")


class AllPairs(Assembly):
    """The same blocks with every pair a candidate contact, each computed on its own.

    No spatial index (``neighbours`` and ``neighbour_graph`` are the complete
    graph) and no instancing (every pair is its own kind), so
    :func:`~interlock.verify.contacts` does what an all-pairs solver does:
    ``n (n - 1) / 2`` facet matchings.
    """

    @classmethod
    def of(cls, assembly: Assembly) -> AllPairs:
        return cls(assembly.meshes, assembly.types, assembly.transforms, assembly.labels, assembly.frame)

    @property
    def neighbours(self):
        return self.neighbour_graph()

    def neighbour_graph(self, rtol: float = 0.0):
        return nx.complete_graph(len(self))

    def pair_kinds(self, pairs):
        pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
        own = np.arange(len(pairs))
        return own, own, np.broadcast_to(np.eye(4), (len(pairs), 4, 4))


def naive_rank(matrix) -> int:
    """``numpy.linalg.matrix_rank`` of the dense matrix (an SVD of all of ``A``)."""
    return int(np.linalg.matrix_rank(matrix.toarray()))


def naive_stress(matrix) -> bool:
    """Whether ``A^T w = 0`` has ``w > 0``: maximise ``t`` subject to ``w_i >= t``, ``t <= 1`` (HiGHS).

    The form of published solvers: the auxiliary ``t`` and one inequality
    row ``t - w_i <= 0`` (with its slack) per row of ``A``; a positive stress
    exists iff the optimum is ``t = 1``.
    """
    m, n = matrix.shape
    objective = np.zeros(m + 1)
    objective[-1] = -1.0
    equalities = sp.hstack([matrix.T, sp.csr_matrix((n, 1))]).tocsr()
    inequalities = sp.hstack([-sp.identity(m), np.ones((m, 1))]).tocsr()
    result = scipy.optimize.linprog(objective, A_ub=inequalities, b_ub=np.zeros(m), A_eq=equalities,
                                    b_eq=np.zeros(n), bounds=[(None, None)] * m + [(None, 1.0)], method="highs")
    return result.status == 0 and -result.fun > 0.5


def naive_motion(matrix) -> bool:
    """Whether a motion opens contacts: ``max 1^T A x`` subject to ``0 <= A x <= 1``, HiGHS' simplex on ``[A; -A]``.

    The form of TopoLite's motion search, and this project's own before it
    read the motion off the stress problem's infeasibility certificate.
    """
    m, n = matrix.shape
    result = scipy.optimize.linprog(-np.asarray(matrix.sum(axis=0)).ravel(), A_ub=sp.vstack([matrix, -matrix]).tocsr(),
                                    b_ub=np.concatenate([np.ones(m), np.zeros(m)]), bounds=(None, None),
                                    method="highs-ds")
    return result.status == 0 and -result.fun > 1e-7


def naive_verdict(assembly: Assembly, motion: bool = False) -> tuple[bool, dict]:
    """(interlocked, seconds per stage of :data:`NAIVE_STAGES`) of the naive baseline on a fresh copy.

    With ``motion``, a missing stress is followed by :func:`naive_motion` (timed with the LP stage), as a
    verdict that names the moving blocks needs.
    """
    from interlock.verify import contacts
    from interlock.verify.matrix import interlocking_matrix

    everything = AllPairs.of(assembly)
    seconds = {}
    start = time.perf_counter()
    found = contacts(everything)
    seconds["contacts"] = time.perf_counter() - start
    start = time.perf_counter()
    A = interlocking_matrix(everything, contacts=found)
    seconds["matrix"] = time.perf_counter() - start
    start = time.perf_counter()
    full_rank = naive_rank(A.matrix) == A.shape[1]
    seconds["rank"] = time.perf_counter() - start
    start = time.perf_counter()
    stress = naive_stress(A.matrix)
    if motion and not stress:
        naive_motion(A.matrix)
    seconds["lp"] = time.perf_counter() - start
    return full_rank and stress, seconds
