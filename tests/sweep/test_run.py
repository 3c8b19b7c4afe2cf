"""Sweeps: specs, records, executors (local processes, Dask), resuming, and bad input."""

import json
import os
import pickle
import re
import signal
import subprocess
import sys
import time
import tracemalloc
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock import InterlockError
from interlock.cli import main
from interlock.sweep import SweepError, SweepWarning, deformation, evaluate, load_spec, read_records, run

#: p4, one point on edge 0: Criterion 4.3 fails (g_0 generates a finite rotation group), |offset| >= 1 makes F'
#: self-intersect (measured), and at offset 0 the point is on its edge.
P4 = {"group": "p4", "verdicts": ["criterion_4_3", "periodic"], "chunk": 3,
      "parameters": {"t": {"range": [0.25, 0.75], "steps": 3}, "s": {"range": [-1.2, 1.2], "steps": 5}},
      "points": [{"edge": 0, "along": "t", "offset": "s"}]}
#: p1, both edge pairs deformed: Criterion 4.3 holds unless the swept point lies on edge 0 (Thm. 4.7: interlocked
#: translationally iff it holds).
P1 = {"group": "p1", "verdicts": ["criterion_4_3", "periodic"], "chunk": 2,
      "parameters": {"s": {"values": [-0.2, 0.0, 0.2]}, "u": {"values": [0.0, 0.15]}},
      "points": [{"edge": 0, "along": 0.5, "offset": "s"}, {"edge": 1, "along": 0.4, "offset": "u"}]}


def _without_time(records):
    return [{k: v for k, v in r.items() if k != "seconds"} for r in records]


def _threads(spec, **options):
    with ThreadPoolExecutor(2) as pool:
        return run(spec, executor=pool, **options)


# --- spec and records ----------------------------------------------------------------------------------------


def test_grid_is_the_product_of_the_parameters_last_fastest():
    spec = load_spec(P4)
    points = spec.points()
    assert len(points) == 15
    assert points[:2] == [{"t": 0.25, "s": -1.2}, {"t": 0.25, "s": -0.6}]
    assert points[-1] == {"t": 0.75, "s": 1.2}


def test_samples_are_reproducible_from_the_seed_and_stay_in_range():
    spec = load_spec({**P4, "samples": 20, "seed": 3})
    again = load_spec({**P4, "samples": 20, "seed": 3}).points()
    other = load_spec({**P4, "samples": 20, "seed": 4}).points()
    assert spec.points() == again != other
    assert all(0.25 <= p["t"] <= 0.75 and -1.2 <= p["s"] <= 1.2 for p in spec.points())


def _points_of_interlock_0_1(spec):
    """The points as interlock 0.1 made them, all at once: what lazily made points must equal (for resuming)."""
    import itertools

    names = [p.name for p in spec.parameters]
    if spec.samples:
        rng = np.random.default_rng(spec.seed)
        columns = [p.sample(rng, spec.samples) for p in spec.parameters]
        return [{n: float(c[i]) for n, c in zip(names, columns)} for i in range(spec.samples)]
    values = [tuple(float(f"{v:.12g}") for v in np.linspace(p.low, p.high, len(p.values))) if p.low is not None
              else p.values for p in spec.parameters]
    return [dict(zip(names, map(float, combo))) for combo in itertools.product(*values)]


@settings(max_examples=40)
@given(st.lists(st.one_of(st.tuples(st.floats(-5, 5), st.floats(0.001, 10), st.integers(2, 40)),
                          st.lists(st.floats(-5, 5), min_size=1, max_size=5)), min_size=1, max_size=3),
       st.integers(0, 50), st.integers(0, 2**31))
def test_points_made_lazily_are_the_points_of_interlock_0_1(parameters, samples, seed):
    table = {}
    for k, parameter in enumerate(parameters):
        if isinstance(parameter, tuple):
            low, width, steps = parameter
            table[f"p{k}"] = {"range": [low, low + width], "steps": steps}
        else:
            table[f"p{k}"] = {"values": parameter}
    spec = load_spec({"group": "p1", "verdicts": ["criterion_4_3"], "parameters": table, "samples": samples,
                      "seed": seed, "points": [{"edge": 0, "along": 0.5, "offset": 0.1}]})
    assert spec.points() == list(spec.iter_points()) == _points_of_interlock_0_1(spec)
    assert len(spec.points()) == spec.size


class _Enough(Exception):
    pass


def _stop_after(chunks):
    seen = []

    def progress(count):
        seen.append(count)
        if len(seen) >= chunks:
            raise _Enough

    return progress


def _grid(steps):
    return load_spec({"group": "p1", "verdicts": ["criterion_4_3"], "chunk": 2,
                      "parameters": {"s": {"range": [0.1, 0.2], "steps": steps}, "t": {"range": [0.3, 0.7], "steps": steps}},
                      "points": [{"edge": 0, "along": "t", "offset": "s"}]})


def test_a_large_grid_starts_at_once_in_bounded_memory():
    # issue 40: sweep --max-points 1e20 on a 1e14-point grid made every point first (14 GB after 57 s); now the
    # points are made as chunks are handed out, and a run that is stopped after 3 chunks has used a few MB
    spec = _grid(1000)
    evaluate(spec, 0, next(spec.iter_points()))  # the blocks and the verifier imported before counting
    tracemalloc.start()
    try:
        with ThreadPoolExecutor(1) as pool, pytest.raises(_Enough):
            run(spec, executor=pool, max_points=10**20, progress=_stop_after(3))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 30e6, f"{peak / 1e6:.0f} MB for the first chunks of a {spec.size:,}-point grid"


def test_a_grid_of_1e14_points_costs_nothing_to_read_or_send():
    # the ranges' values are made when asked for: a 1e7-step range was a tuple of 1e7 floats, read in seconds
    # and pickled with the spec to every chunk's worker
    tracemalloc.start()
    try:
        spec = _grid(10_000_000)
        points = spec.iter_points()
        first = [next(points) for _ in range(3)]
        sent = len(pickle.dumps(spec))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert spec.size == 10**14 and first[0] == {"s": 0.1, "t": 0.3} and first[2]["t"] == pytest.approx(0.3 + 0.8e-7)
    assert sent < 10_000 and peak < 1e6
    assert spec.parameters[0].values[-1] == 0.2 and len(spec.parameters[0].values) == 10**7


def test_records_need_not_be_kept(tmp_path):
    output = tmp_path / "p1.jsonl"
    with ThreadPoolExecutor(2) as pool:
        assert run(P1, output, executor=pool, keep=False) == []
    kept = _threads(P1)
    assert _without_time(read_records(output)) == _without_time(kept) and len(kept) == 6
    with pytest.raises(SweepError, match="keep must be True or False"):
        _threads(P1, keep="no")


def test_deformation_places_the_point_along_and_off_its_edge():
    spec = load_spec(P4)
    (point,) = deformation(spec, {"t": 0.25, "s": 0.5})[0]
    from interlock import wallpaper

    corners = wallpaper.group("p4").fundamental_domain().exterior.coords
    (px, py), (qx, qy) = corners[0], corners[1]
    length = ((qx - px) ** 2 + (qy - py) ** 2) ** 0.5
    along = ((point[0] - px) * (qx - px) + (point[1] - py) * (qy - py)) / length ** 2
    left = ((qx - px) * (point[1] - py) - (qy - py) * (point[0] - px)) / length ** 2
    assert along == pytest.approx(0.25) and left == pytest.approx(0.5)


def test_records_hold_verdicts_and_invalid_points_do_not_stop_the_sweep():
    records = _threads(P4)
    assert [r["index"] for r in records] == list(range(15))
    invalid = [r for r in records if r["status"] == "invalid"]
    assert {r["parameters"]["s"] for r in invalid} == {-1.2, 1.2}
    assert all("self-intersecting" in r["message"] and r["verdicts"] == {} for r in invalid)
    ok = [r for r in records if r["status"] == "ok"]
    assert len(ok) == 9 and all(r["verdicts"]["criterion_4_3"] == "fails" for r in ok)
    assert all(r["verdicts"]["periodic"] == "not interlocked" for r in ok)  # Criterion 4.3 fails: H lifts out
    assert all(r["tolerances"]["periodic"] and r["seconds"] > 0 for r in ok)
    json.dumps(records)  # plain data


def test_a_patch_with_a_first_order_motion_is_worded_not_infinitesimally_interlocked():
    # the first-order verdict's motion need not be a finite one, so a sweep record does not say "not interlocked"
    spec = load_spec({**P1, "verdicts": ["patch"]})
    assert evaluate(spec, 0, {"s": 0.0, "u": 0.0})["verdicts"] == {"patch": "not infinitesimally interlocked"}
    assert evaluate(spec, 1, {"s": 0.2, "u": 0.15})["verdicts"] == {"patch": "interlocked"}


def test_p1_verdicts_follow_theorem_4_7():
    for r in _threads(P1):
        assert r["status"] == "ok"
        holds = r["parameters"]["s"] != 0.0 or r["parameters"]["u"] != 0.0
        assert r["verdicts"]["criterion_4_3"] == ("holds" if holds else "fails")
        assert r["verdicts"]["periodic"] == ("interlocked" if holds else "not interlocked")


def test_an_unexpected_error_at_one_point_is_recorded_as_failed(monkeypatch):
    import interlock.sweep.record as module

    original = module._verdicts

    def broken(spec, parameters):
        if parameters["s"] == 0.2:
            raise RuntimeError("solver exploded")
        return original(spec, parameters)

    monkeypatch.setattr(module, "_verdicts", broken)
    records = _threads(P1)
    failed = [r for r in records if r["status"] == "failed"]
    assert len(failed) == 2 and all(r["message"] == "RuntimeError: solver exploded" for r in failed)
    assert sum(r["status"] == "ok" for r in records) == 4


# --- executors ---------------------------------------------------------------------------------------------


def test_local_processes_give_the_records_of_one_thread():
    with ThreadPoolExecutor(1) as pool:
        one = run(P4, executor=pool)
    assert _without_time(run(P4, workers=2)) == _without_time(one)


def test_dask_local_cluster_gives_exactly_the_records_of_local_processes():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") \
            as cluster, distributed.Client(cluster) as client:
        on_dask = run(P4, executor=client)
        assert len(client.scheduler_info()["workers"]) == 2
    assert _without_time(on_dask) == _without_time(run(P4, workers=2))


# --- output and resuming -----------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".jsonl", ".parquet"])
def test_output_round_trips_and_resume_evaluates_only_missing_points(tmp_path, suffix):
    if suffix == ".parquet":
        pytest.importorskip("pyarrow")
    path = tmp_path / f"p1{suffix}"
    first = _threads({**P1, "parameters": {**P1["parameters"], "s": {"values": [-0.2, 0.0]}}}, output=path)
    assert read_records(path) == first
    done = []
    second = _threads(P1, output=path, resume=True, progress=done.append)
    assert done[0] == 4 and sum(done[1:]) == 2  # four kept (reported first), the two points of s = 0.2 evaluated
    assert second[:4] == first and read_records(path) == second
    with pytest.raises(SweepError, match="exists: resume it"):
        _threads(P1, output=path)


def test_resume_after_a_killed_run_repeats_no_finished_point(tmp_path):
    spec = {**P4, "verdicts": ["periodic"], "chunk": 1,
            "parameters": {"t": {"range": [0.2, 0.8], "steps": 7}, "s": {"range": [-0.4, 0.4], "steps": 5}}}
    spec_path, out = tmp_path / "spec.toml", tmp_path / "out.jsonl"
    spec_path.write_text(_toml(spec))
    process = subprocess.Popen([sys.executable, "-m", "interlock", "sweep", str(spec_path), "-o", str(out),
                                "--workers", "1"], start_new_session=True, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and (not out.exists() or out.read_text().count("\n") < 4):  # header + 3
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    before = read_records(out)
    assert 3 <= len(before) < 35, "the run should be killed part-way"
    evaluated = []
    after = run(spec_path, out, workers=2, resume=True, progress=evaluated.append)
    assert evaluated[0] == len(before) and sum(evaluated[1:]) == 35 - len(before)  # kept first, then the rest
    assert [r["index"] for r in after] == list(range(35))
    kept = {r["index"]: r for r in after}
    assert all(kept[r["index"]] == r for r in before)  # same seconds too: not evaluated again
    header, *lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert header["sweep"]["fingerprint"] == load_spec(spec_path).fingerprint
    assert sorted(line["index"] for line in lines) == list(range(35))  # every point once in the file


def _toml(spec: dict) -> str:
    lines = [f'group = "{spec["group"]}"', f"verdicts = {json.dumps(spec['verdicts'])}", f"chunk = {spec['chunk']}",
             "[parameters]"]
    lines += [f"{name} = {{range = [{p['range'][0]}, {p['range'][1]}], steps = {p['steps']}}}"
              for name, p in spec["parameters"].items()]
    for point in spec["points"]:
        lines += ["[[points]]", f"edge = {point['edge']}"]
        lines += [f"{key} = {json.dumps(point[key])}" for key in ("along", "offset")]
    return "\n".join(lines) + "\n"


# --- bad input --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("change, message", [
    ({"colour": 1}, "unknown spec keys"),
    ({"group": "p7"}, "group"),
    ({"verdicts": ["beauty"]}, "verdicts must be"),
    ({"parameters": {"s": {"range": [1, 0], "steps": 3}}}, "low < high"),
    ({"parameters": {"s": {"range": [0, 1], "steps": 1}}}, "steps must be"),
    ({"parameters": {"s": [0, 1]}}, "must be a table"),
    ({"points": [{"edge": 0, "along": 0.5, "offset": "q"}]}, "names the parameter 'q'"),
    ({"points": [{"edge": 0, "along": 0.5}]}, "needs exactly the keys"),
    ({"tiling": {"kind": "hexagon"}}, "exactly one family"),
    ({"chunk": 0}, "chunk must be"),
])
def test_bad_specs_raise_sweep_error(change, message):
    with pytest.raises(SweepError, match=message) as caught:
        load_spec({**P1, **change})
    assert isinstance(caught.value, InterlockError) and isinstance(caught.value, ValueError)


def test_a_missing_edge_is_refused_before_any_point_is_computed():
    with pytest.raises(SweepError, match=r"points\[0\].edge must be an edge of p1's fundamental domain, 0..3, got 9"):
        load_spec({**P1, "points": [{"edge": 9, "along": 0.5, "offset": "s"}]})


def test_a_missing_edge_at_one_point_is_an_invalid_point_not_a_crash():
    spec = load_spec(P1)
    spec.family["points"][0]["edge"] = 9  # past the check of load_spec
    record = evaluate(spec, 0, {"s": 0.1, "u": 0.0})
    assert record["status"] == "invalid" and "edge 9 does not exist" in record["message"]


def test_cli_reports_bad_input_in_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('group = "p4"\nverdicts = ["nope"]\n')
    assert main(["sweep", str(bad), "-o", str(tmp_path / "x.jsonl")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("interlock sweep: error: verdicts must be")
    assert main(["sweep", str(tmp_path / "none.toml"), "-o", str(tmp_path / "x.jsonl")]) == 2
    assert main(["sweep", str(bad), "-o", str(tmp_path / "x.csv")]) == 2


def test_cli_sweep_writes_records_and_a_map(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    spec = tmp_path / "p1.toml"
    spec.write_text(_toml({**P1, "verdicts": ["criterion_4_3"],
                           "parameters": {"s": {"range": [-0.2, 0.2], "steps": 3},
                                          "u": {"range": [0.0, 0.3], "steps": 3}}}))
    out = tmp_path / "p1.jsonl"
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "1"]) == 0
    printed = capsys.readouterr().out
    assert "9 points (9 ok)" in printed and "criterion_4_3: 1 fails, 8 holds" in printed
    png = tmp_path / "p1-criterion_4_3.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(read_records(out)) == 9


def test_the_example_specs_say_what_their_comments_claim():
    from pathlib import Path

    folder = Path(__file__).resolve().parents[2] / "docs" / "sweeps"
    p1 = run(folder / "p1-edge0.toml", workers=2)
    assert len(p1) == 81 and sum(r["status"] == "invalid" for r in p1) == 2
    for r in (r for r in p1 if r["status"] == "ok"):
        holds = r["parameters"]["s"] != 0.0
        assert r["verdicts"] == {"periodic": "interlocked" if holds else "not interlocked",
                                 "criterion_4_3": "holds" if holds else "fails"}
    p4 = run(folder / "p4-edge0.toml", workers=2)
    assert {r["status"] == "invalid" for r in p4 if abs(r["parameters"]["s"]) >= 1.0} == {True}
    assert {tuple(r["verdicts"].values()) for r in p4 if r["status"] == "ok"} == {("not interlocked", "fails")}


# --- safe outputs (issue 22) ------------------------------------------------------------------------------

SMALL = {**P1, "verdicts": ["criterion_4_3"], "parameters": {"s": {"values": [-0.2, 0.2]}, "u": {"values": [0.15]}}}


@pytest.mark.parametrize("change, message", [
    ({"mu": -0.5}, "mu, the friction coefficient, must be >= 0, got -0.5"),
    ({"points": [{"edge": 42, "along": 0.5, "offset": "s"}]}, "must be an edge of p1's"),
    ({"height": "s"}, "height must be a number > 0, but parameter 's' takes -0.2"),
    ({"height": 0}, "height must be a number > 0, got 0"),
    ({"parameters": {"s": {"range": [0, 1], "steps": 10**11}, "u": {"values": [0.0]}}}, "steps must be 0"),
])
def test_bad_values_are_refused_before_any_point_is_computed(change, message):
    with pytest.raises(SweepError, match=re.escape(message)):
        load_spec({**P1, **change})


@pytest.mark.parametrize("tiling, message", [
    ({"a": 1.5}, "tiling.a must be a whole number >= 0, got 1.5"),
    ({"c": "c"}, "tiling.c must be a whole number >= 0, but parameter 'c' takes -1"),
    ({"variant": 2}, "tiling.variant must be 0 or 1, got 2"),
])
def test_bad_tiling_values_are_refused_before_any_point_is_computed(tiling, message):
    spec = {"tiling": {"kind": "hexagon", **tiling}, "parameters": {"c": {"values": [-1, 2]}}}
    with pytest.raises(SweepError, match=re.escape(message)):
        load_spec(spec)


def test_a_spec_of_ten_billion_points_is_refused_before_they_are_made(tmp_path):
    huge = {**P1, "parameters": {"s": {"range": [0, 1], "steps": 100_000}, "u": {"range": [0, 1], "steps": 100_000}}}
    assert load_spec(huge).size == 10**10
    with pytest.raises(SweepError, match="10,000,000,000 points .* more than the limit 1,000,000"):
        run(huge, tmp_path / "x.jsonl")
    assert not (tmp_path / "x.jsonl").exists()


def test_a_spec_of_another_sweep_does_not_resume_its_results(tmp_path):
    out = tmp_path / "b.jsonl"
    _threads(SMALL, output=out)
    other = {**SMALL, "points": [{"edge": 0, "along": 0.3, "offset": "s"}, {"edge": 1, "along": 0.4, "offset": "u"}]}
    before = out.read_bytes()
    with pytest.raises(SweepError, match="holds the records of another spec"):
        _threads(other, output=out, resume=True)
    assert out.read_bytes() == before  # untouched


def test_records_at_other_parameters_are_not_taken_as_this_specs(tmp_path):
    out = tmp_path / "b.jsonl"
    _threads(SMALL, output=out)
    shifted = {**SMALL, "parameters": {"s": {"values": [-0.3, 0.2]}, "u": {"values": [0.15]}}}
    with pytest.raises(SweepError, match="holds a record for point 0 at"):
        _threads(shifted, output=out, resume=True)


def test_results_without_a_fingerprint_are_not_resumed(tmp_path):
    out = tmp_path / "old.jsonl"
    records = _threads(SMALL)
    out.write_text("".join(json.dumps(r) + "\n" for r in records))
    with pytest.raises(SweepError, match="without a spec fingerprint"):
        _threads(SMALL, output=out, resume=True)


def test_a_damaged_line_is_skipped_with_a_warning_and_its_point_computed_again(tmp_path):
    out = tmp_path / "p1.jsonl"
    first = _threads(SMALL, output=out)
    header, one, two = out.read_text().splitlines(keepends=True)
    out.write_text(header + '{"index": 0, "param' + "\n" + two)
    with pytest.warns(SweepWarning, match="line 2 is not a sweep record"):
        again = _threads(SMALL, output=out, resume=True)
    assert _without_time(again) == _without_time(first)
    assert [json.loads(line).get("index") for line in out.read_text().splitlines()] == [None, 1, 0]


def test_cli_resume_with_a_damaged_line_warns_in_one_line_and_finishes(tmp_path, capsys):
    spec, out = tmp_path / "p1.toml", tmp_path / "p1.jsonl"
    spec.write_text(_toml({**P1, "verdicts": ["criterion_4_3"],
                           "parameters": {"s": {"range": [-0.2, 0.2], "steps": 2}, "u": {"range": [0.1, 0.2],
                                                                                         "steps": 2}}}))
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "1"]) == 0
    lines = out.read_text().splitlines(keepends=True)
    out.write_text(lines[0] + "garbage\n" + "".join(lines[2:]))
    capsys.readouterr()
    assert main(["sweep", str(spec), "-o", str(out), "--workers", "1", "--resume"]) == 0
    err = capsys.readouterr().err
    assert "interlock sweep: warning:" in err and "line 2 is not a sweep record" in err and "Traceback" not in err
    assert len(read_records(out)) == 4


@pytest.mark.parametrize("output, message", [
    ("missing/x.jsonl", "does not exist; create it first"),
    ("folder.jsonl", "it is a folder"),
    ("readonly/x.jsonl", "is not writable"),
])
def test_an_output_that_cannot_be_written_is_refused_before_computing(tmp_path, monkeypatch, output, message):
    (tmp_path / "folder.jsonl").mkdir()
    (tmp_path / "readonly").mkdir()
    if output.startswith("readonly"):
        monkeypatch.setattr(os, "access", lambda path, mode: False)  # root may write anywhere
    calls = []
    import importlib

    monkeypatch.setattr(importlib.import_module("interlock.sweep.run"), "evaluate_chunk",
                        lambda *a: calls.append(a) or [])
    with pytest.raises(SweepError, match=message):
        run(SMALL, tmp_path / output, executor=ThreadPoolExecutor(1))
    assert calls == []


def test_a_folder_as_spec_is_a_sweep_error(tmp_path):
    with pytest.raises(SweepError, match="is a folder; give the sweep spec"):
        load_spec(tmp_path)


def test_cli_exits_non_zero_when_no_point_succeeds(tmp_path, capsys):
    spec = tmp_path / "bad.toml"
    grid = {"t": {"range": [0.2, 0.8], "steps": 2}, "s": {"range": [1.5, 2.0], "steps": 2}}  # F' self-intersects
    spec.write_text(_toml({**P4, "verdicts": ["criterion_4_3"], "parameters": grid}))
    assert main(["sweep", str(spec), "-o", str(tmp_path / "x.jsonl"), "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert "no point succeeded" in err and "invalid" in err


def test_cli_max_points_refuses_and_raises_the_limit(tmp_path, capsys):
    spec = tmp_path / "p1.toml"
    grid = {"s": {"range": [-0.2, 0.2], "steps": 3}, "u": {"range": [0.1, 0.2], "steps": 2}}
    spec.write_text(_toml({**P1, "verdicts": ["criterion_4_3"], "parameters": grid}))
    assert main(["sweep", str(spec), "-o", str(tmp_path / "x.jsonl"), "--max-points", "5"]) == 2
    assert "6 points" in capsys.readouterr().err
    assert main(["sweep", str(spec), "-o", str(tmp_path / "x.jsonl"), "--max-points", "6", "--workers", "1"]) == 0


# --- nothing lost, nothing leaked (issue 36) ---------------------------------------------------------------

#: How many times (and how long apart) a test looks for what other processes did: bounded, never a time limit.
TRIES, PAUSE = 600, 0.1


def _foreign_json_lines(draw_dicts):
    return "".join(json.dumps(d) + "\n" for d in draw_dicts).encode()


@settings(max_examples=25, deadline=None)
@given(st.one_of(
    st.binary(min_size=1, max_size=2000),
    st.lists(st.dictionaries(st.sampled_from(["user", "note", "index", "status", "sweep", "x"]),
                             st.one_of(st.integers(), st.text(max_size=8), st.none()), min_size=1),
             min_size=1, max_size=6).map(_foreign_json_lines),
    st.sampled_from([b'{"user": "alice", "note": "precious"}\n{"user": "bob"}\n', b'{"sweep": "my notes"}\n',
                     b'{"sweep": {"name": "mine"}}\nfree text\n', b"\n", b"[1, 2, 3]\n" * 3, b"\xff\xfe\x00"])))
def test_resume_refuses_a_file_that_is_not_a_sweeps_and_leaves_it_byte_identical(tmp_path_factory, data):
    out = tmp_path_factory.mktemp("foreign") / "results.jsonl"
    out.write_bytes(data)
    calls = []
    with pytest.raises(SweepError, match="not a sweep's output|records without a spec fingerprint"), \
            warnings.catch_warnings():
        warnings.simplefilter("error", SweepWarning)  # refused before any line is read as a record
        _threads(SMALL, output=out, resume=True, progress=calls.append)
    assert out.read_bytes() == data and calls == []
    assert sorted(p.name for p in out.parent.iterdir()) == ["results.jsonl"]


def test_cli_resume_of_a_foreign_json_lines_file_is_one_line_and_the_file_is_unchanged(tmp_path):
    spec, out = tmp_path / "p1.toml", tmp_path / "r.jsonl"
    spec.write_text(_toml({**P1, "verdicts": ["criterion_4_3"],
                           "parameters": {"s": {"range": [-0.2, 0.2], "steps": 2}, "u": {"range": [0.1, 0.2],
                                                                                         "steps": 2}}}))
    data = b'{"user": "alice", "note": "precious"}\n{"user": "bob"}\n'
    out.write_bytes(data)
    done = subprocess.run([sys.executable, "-m", "interlock", "sweep", str(spec), "-o", str(out), "--resume",
                           "--workers", "1"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "is not a sweep's output" in done.stderr and "warning" not in done.stderr
    assert out.read_bytes() == data
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p1.toml", "r.jsonl"]


def test_resume_into_a_folder_that_is_not_a_sweeps_parquet_output_is_refused(tmp_path):
    folder = tmp_path / "results.parquet"
    folder.mkdir()
    (folder / "notes.txt").write_text("precious")
    with pytest.raises(SweepError, match="not a sweep's Parquet output"):
        _threads(SMALL, output=folder, resume=True)
    assert [p.name for p in folder.iterdir()] == ["notes.txt"]


def test_an_empty_file_and_a_link_to_a_sweeps_output_are_resumed(tmp_path):
    empty = tmp_path / "empty.jsonl"
    empty.touch()
    assert len(_threads(SMALL, output=empty, resume=True)) == 2 and len(read_records(empty)) == 2
    real, link = tmp_path / "real.jsonl", tmp_path / "link.jsonl"
    first = _threads({**SMALL, "parameters": {**SMALL["parameters"], "s": {"values": [-0.2]}}}, output=real)
    link.symlink_to(real)
    again = _threads(SMALL, output=link, resume=True)
    assert again[:1] == first and link.is_symlink() and len(read_records(real)) == 2
    loop = tmp_path / "loop.jsonl"
    loop.symlink_to(loop)
    with pytest.raises(SweepError, match="symbolic link to nothing"):
        _threads(SMALL, output=loop, resume=True)
    renamed, other = tmp_path / "renamed.txt", tmp_path / "other.jsonl"
    renamed.write_bytes(real.read_bytes())
    other.symlink_to(renamed)
    with pytest.raises(SweepError, match="which does not end in .jsonl"):
        _threads(SMALL, output=other, resume=True)
    assert renamed.read_bytes() == real.read_bytes()


@pytest.mark.parametrize("edge, message", [
    (0.0, r"edge = 0, not 0\.0"),
    (True, "must be an edge of p1's fundamental domain, 0..3, got True"),
    (2.5, "got 2.5"),
])
def test_an_edge_that_is_no_whole_number_is_named_as_such(edge, message):
    with pytest.raises(SweepError, match=message):
        load_spec({**SMALL, "points": [{"edge": edge, "along": 0.5, "offset": "s"}]})


def test_the_example_specs_name_the_partner_edges_the_group_has():
    from pathlib import Path

    from interlock import wallpaper

    for spec in (Path(__file__).resolve().parents[2] / "docs" / "sweeps").glob("*.toml"):
        text = spec.read_text()
        claims = re.findall(r"edge (\d+) \(paired with edge (\d+)", text.replace("\n# ", " "))
        group = wallpaper.group(load_spec(spec).family["group"])
        for edge, partner in claims:
            assert group.side_pairings()[int(edge)].partner == int(partner), spec.name


def _alive(pid: int) -> bool:
    import psutil

    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


# the command line with another start method for the local workers (forkserver: Python 3.14's default on Linux)
WITH_START_METHOD = ("import multiprocessing, sys; multiprocessing.set_start_method(sys.argv[1]); "
                     "from interlock.cli import main; sys.exit(main(sys.argv[2:]))")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux: /proc, psutil and the parent-death signal")
@pytest.mark.parametrize("start", ["default", "forkserver"])
def test_workers_end_when_the_sweep_is_killed_with_sigkill(tmp_path, start):
    psutil = pytest.importorskip("psutil")
    spec = {**P4, "verdicts": ["periodic"], "chunk": 1,
            "parameters": {"t": {"range": [0.2, 0.8], "steps": 40}, "s": {"range": [-0.4, 0.4], "steps": 40}}}
    spec_path, out = tmp_path / "spec.toml", tmp_path / "out.jsonl"
    spec_path.write_text(_toml(spec))
    command = ["-m", "interlock"] if start == "default" else ["-c", WITH_START_METHOD, start]
    process = subprocess.Popen([sys.executable, *command, "sweep", str(spec_path), "-o", str(out),
                                "--workers", "2"], start_new_session=True, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    workers = []
    try:
        for _ in range(TRIES):  # until both workers run and records arrive
            workers = [child.pid for child in psutil.Process(process.pid).children(recursive=True)]  # forkserver too
            if len(workers) >= 2 and out.exists() and out.read_text().count("\n") >= 3:
                break
            time.sleep(PAUSE)
        assert len(workers) >= 2, "the sweep should run two workers"
        os.kill(process.pid, signal.SIGKILL)  # the sweep alone, not its process group
        process.wait()
        for _ in range(TRIES):
            if not any(_alive(pid) for pid in workers):
                break
            time.sleep(PAUSE)
        assert not [pid for pid in workers if _alive(pid)], "workers outlived the sweep"
    finally:
        for pid in workers + [process.pid]:  # whatever is left of what this test started
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        process.wait()


@pytest.mark.parametrize("change, message", [
    ({"height": 1e90}, r"height must be a number > 0 and at most 1e\+30, got 1e\+90"),
    ({"height": "s", "parameters": {"s": {"values": [1.0, 1e200]}}}, r"parameter 's' takes 1e\+200"),
    ({"verdicts": ["stability"], "mu": 1e308}, r"mu: mu = 1e\+308 is outside the range the solvers represent"),
])
def test_values_no_point_could_use_are_refused_before_any_is_computed(change, message, monkeypatch):
    import importlib

    calls = []
    monkeypatch.setattr(importlib.import_module("interlock.sweep.run"), "evaluate_chunk",
                        lambda *a: calls.append(a) or [])
    spec = {**P4, "points": [{"edge": 0, "along": 0.5, "offset": 0.1}], **change}
    spec.setdefault("parameters", {})
    with pytest.raises(SweepError, match=message):
        _threads({**spec, "verdicts": change.get("verdicts", ["criterion_4_3"])})
    assert calls == []
