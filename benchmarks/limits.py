"""Time limits: wall time of ``interlock verify`` and ``interlock stability`` against ``--time-limit``.

The cases are those of the command-line fuzz test (``tests/test_cli_fuzz.py``):
RhomBlock hexagons (``random_hexagon(n, n, n, seed=0)``, variant 0) written as
OBJ with block 0 the only support, n = 3 (27 blocks, the fuzz test's file) and
larger ones.  Each command runs in a fresh interpreter, as the ``interlock``
program runs it (``interlock.cli.main()`` on ``sys.argv``), with
``--time-limit`` 1, 5 and 20 s, several times; recorded are the median wall
time of the process and, as the command itself reports it, the answer
(verdict or "inconclusive: time limit reached in <stage>").

Target (issue 40): every median under ``1.1 x limit + 1 s``.  The limit
counts from the start of ``main`` (parsing, the imports a command needs and
reading the file included); the process also starts and ends Python, which
the chart shows as the gap between the two medians: ``process`` (the whole
run, what a user waits for) and ``command`` (importing ``interlock.cli`` and
running ``main``, measured by the process's own clock).

Chart: one panel per command, median wall time against the limit per model,
the target line ``1.1 x + 1 s``.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.common import load_average, main, pyplot, save_chart, write_json

#: Limits (seconds) and runs per point; the quick run (tests) takes one small case at 1 s once.
LIMITS, QUICK_LIMITS = (1.0, 5.0, 20.0), (1.0,)
RUNS, QUICK_RUNS = 3, 1
#: Hexagon sizes ``n`` (3 n^2 blocks): the fuzz test's 27 blocks, then larger ones.
SIZES, QUICK_SIZES = (3, 6, 10), (3,)
#: The commands timed: (name, arguments after the file).
COMMANDS = (("verify", ["verify"]),
            ("stability rbe", ["stability", "--mu", "3", "--method", "rbe"]),
            ("stability cra", ["stability", "--mu", "3", "--method", "cra"]))

#: Runs a command in a fresh interpreter as the ``interlock`` program does (``main()`` reading ``sys.argv``) and
#: prints how long importing ``interlock.cli`` and running ``main`` took (after the interpreter started), then the
#: command's status; the process's wall time, measured outside, adds the interpreter's start and end.
DRIVER = ("import io, contextlib, sys, time, json\n"
          "started = time.perf_counter()\n"
          "from interlock.cli import main\n"
          "out = io.StringIO()\n"
          "sys.argv = ['interlock', *sys.argv[1:]]\n"
          "with contextlib.redirect_stdout(out):\n"
          "    status = main()\n"
          "print(json.dumps({'seconds': time.perf_counter() - started, 'status': status,"
          " 'output': out.getvalue()[-2000:]}))\n")


def _model(n: int, folder: Path) -> Path:
    from interlock.blocks import random_hexagon, rhomblock_assembly
    from interlock.formats import write

    path = folder / f"hexagon-{n}.obj"
    if not path.exists():
        write(rhomblock_assembly(random_hexagon(n, n, n, seed=0), 0, frame="boundary"), path)
    return path


def _run_once(argv: list[str]) -> dict:
    started = time.perf_counter()
    finished = subprocess.run([sys.executable, "-c", DRIVER, *argv], capture_output=True, text=True, check=False)
    process = time.perf_counter() - started
    try:
        record = json.loads(finished.stdout.strip().splitlines()[-1])
    except (IndexError, ValueError):
        record = {"seconds": None, "status": finished.returncode, "output": finished.stderr[-500:]}
    return {"process_seconds": process, "command_seconds": record["seconds"], "status": record["status"],
            "answer": _answer(record["output"])}


def _answer(output: str) -> str:
    """The first line of the command's text output (the verdict), shortened."""
    first = output.strip().splitlines()[0] if output.strip() else ""
    return first[:240]


def run(quick: bool = False) -> dict:
    limits, runs, sizes = (QUICK_LIMITS, QUICK_RUNS, QUICK_SIZES) if quick else (LIMITS, RUNS, SIZES)
    folder = Path(tempfile.mkdtemp(prefix="interlock-limits-"))  # the OBJ models, not results
    rows = []
    for n in sizes:
        path = _model(n, folder)
        for name, arguments in COMMANDS:
            for limit in limits:
                argv = [*arguments[:1], str(path), "--fixed", "0", *arguments[1:], "--time-limit", f"{limit:g}"]
                runs_done = [_run_once(argv) for _ in range(runs)]
                process = statistics.median(r["process_seconds"] for r in runs_done)
                command = [r["command_seconds"] for r in runs_done if r["command_seconds"] is not None]
                row = {"blocks": 3 * n * n, "n": n, "command": name, "limit": limit, "runs": runs,
                       "process_seconds": [round(r["process_seconds"], 3) for r in runs_done],
                       "process_median": round(process, 3),
                       "command_median": round(statistics.median(command), 3) if command else None,
                       "target": round(1.1 * limit + 1.0, 3),
                       "command_within_target": bool(command) and statistics.median(command) <= 1.1 * limit + 1.0,
                       "process_within_target": process <= 1.1 * limit + 1.0,
                       "answers": sorted({r["answer"] for r in runs_done}),
                       "statuses": sorted({r["status"] for r in runs_done}), "load_average": load_average()}
                rows.append(row)
                print(f"{name:14} {3 * n * n:5} blocks  limit {limit:5.1f} s  process {process:6.2f} s  command "
                      f"{row['command_median']} s  {row['answers'][0][:90]}")
    payload = {"description": __doc__.split("\n\n")[0], "quick": quick, "rows": rows,
               "all_commands_within_target": all(r["command_within_target"] for r in rows),
               "all_processes_within_target": all(r["process_within_target"] for r in rows)}
    write_json("limits", payload)
    _chart(payload)
    return payload


def _chart(payload: dict) -> None:
    plt = pyplot()
    if plt is None:
        return
    names = [name for name, _ in COMMANDS]
    fig, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4.6), sharey=True)
    for ax, name in zip(axes, names):
        rows = [r for r in payload["rows"] if r["command"] == name]
        for blocks in sorted({r["blocks"] for r in rows}):
            mine = [r for r in rows if r["blocks"] == blocks]
            limits = [r["limit"] for r in mine]
            line, = ax.plot(limits, [r["process_median"] for r in mine], "o-", label=f"{blocks} blocks, process")
            ax.plot(limits, [r["command_median"] for r in mine], "s--", color=line.get_color(),
                    label=f"{blocks} blocks, command")
        limits = sorted({r["limit"] for r in rows})
        ax.plot(limits, [1.1 * x + 1.0 for x in limits], "r-", lw=0.8, label="target 1.1 x limit + 1 s")
        ax.plot(limits, limits, "k:", lw=0.8, label="the limit")
        ax.set_xlabel("--time-limit (s)")
        ax.set_ylabel("wall time, median (s)")
        ax.set_title(f"interlock {name}", fontsize=10)
        ax.legend(fontsize=7)
    fig.suptitle("wall time against --time-limit: RhomBlock hexagons, block 0 fixed (the fuzz test's cases)")
    save_chart(fig, "limits")


if __name__ == "__main__":
    main(run, __doc__)
