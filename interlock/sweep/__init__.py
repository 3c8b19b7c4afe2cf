"""Design-space sweeps: which deformations (or tilings) interlock, over a grid or random samples.

>>> from interlock.sweep import load_spec, run
>>> spec = load_spec({"group": "p2", "verdicts": ["criterion_4_3"], "parameters": {"s": {"values": [0.0, 0.1]}},
...                   "points": [{"edge": 0, "along": 0.5, "offset": "s"}]})
>>> len(spec.points())
2

``run(spec, output="results.jsonl")`` evaluates them on local processes (or on a
Dask cluster, ``executor=dask.distributed.Client(address)``); ``verdict_map``
draws a two-parameter sweep.
"""

from interlock.sweep.record import deformation, evaluate
from interlock.sweep.run import MAX_POINTS, SweepWarning, check_size, read_records, run
from interlock.sweep.spec import VERDICTS, SweepError, SweepSpec, load_spec

__all__ = ["SweepError", "SweepWarning", "SweepSpec", "VERDICTS", "MAX_POINTS", "load_spec", "run", "check_size",
           "read_records", "evaluate", "deformation"]
