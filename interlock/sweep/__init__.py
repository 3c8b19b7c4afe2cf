"""Design-space sweeps: which deformations (or tilings) interlock, over a grid or random samples.

>>> from interlock.sweep import load_spec, run
>>> spec = load_spec({"group": "p2", "verdicts": ["criterion_4_3"], "parameters": {"s": {"values": [0.0, 0.1]}},
...                   "points": [{"edge": 0, "along": 0.5, "offset": "s"}]})
>>> len(spec.points())
2

``run(spec, output="results.jsonl")`` evaluates them on local processes (or on a
Dask cluster, ``executor=dask.distributed.Client(address)``); ``verdict_map``
draws a two-parameter sweep.  Each name is imported on first use
(:func:`interlock.lazy_exports`).
"""

from interlock import lazy_exports

__all__ = ["SweepError", "SweepWarning", "SweepSpec", "VERDICTS", "MAX_POINTS", "load_spec", "run", "check_size",
           "read_records", "evaluate", "deformation"]

# where each exported name lives: reading a spec loads neither the blocks nor the verifier
_HOMES = {
    **dict.fromkeys(["deformation", "evaluate"], "interlock.sweep.record"),
    **dict.fromkeys(["MAX_POINTS", "SweepWarning", "check_size", "read_records", "run"], "interlock.sweep.run"),
    **dict.fromkeys(["VERDICTS", "SweepError", "SweepSpec", "load_spec"], "interlock.sweep.spec"),
}

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
