"""``benchmarks/real_files.py``: its perturbations do what they say, and a small run writes its JSON and chart."""

import json

import numpy as np
import pytest
import trimesh

from benchmarks import common, real_files


@pytest.fixture
def block():
    return trimesh.creation.icosphere(subdivisions=1)


@pytest.mark.parametrize("split", [real_files._fan_centroids, real_files._split_edges])
def test_re_triangulation_keeps_the_geometry_closed_and_in_place(block, split):
    out = split(block, np.random.default_rng(0))
    assert len(out.faces) > len(block.faces)
    assert out.is_watertight and out.is_winding_consistent
    assert out.volume == pytest.approx(block.volume, rel=1e-12)
    assert np.allclose(out.area, block.area, rtol=1e-12)


def test_vertex_noise_keeps_a_block_closed(block):
    noisy = real_files._noisy([block], (), 1e-3, np.random.default_rng(0)).meshes[0]
    assert noisy.is_watertight
    assert 0 < np.abs(noisy.vertices - block.vertices).max() < 1e-2


def test_perturbation_sizes():
    meshes = [trimesh.Trimesh([[1000.0, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2]], process=False)]
    assert real_files.perturbation("float32 STL", meshes, 2.0) == 2.0**-24 * 1000
    assert real_files.perturbation("4 digits", meshes, 2.0) == pytest.approx(0.5)
    assert real_files.perturbation("noise 1e-7", meshes, 2.0) == pytest.approx(2e-7)


def test_a_small_run_classifies_every_case_and_writes_json_and_chart(tmp_path, monkeypatch):
    monkeypatch.setenv(common.RESULTS_VARIABLE, str(tmp_path))
    payload = real_files.run(quick=True, placements=1, only=["TopoLite cube"])
    record = json.loads((tmp_path / "real_files.json").read_text())
    assert record["summary"] == json.loads(json.dumps(payload["summary"]))
    assert set(record["summary"]) == set(real_files.FAMILIES)
    for row in record["summary"].values():
        assert sum(row["counts"].values()) == row["cases"] == 2  # two frames, one placement
    assert {case["class"] for case in record["cases"]} <= set(real_files.CLASSES)
    assert record["references"]["TopoLite cube"]["{0, 8}"]["reference"] is True
    assert (tmp_path / "real_files.png").read_bytes()[:4] == b"\x89PNG"


def test_shards_merge_into_the_whole_run(tmp_path, monkeypatch):
    """Two shards of two placements (one each) merge into what one run of both writes: the same cases, in order
    (two families of the twelve: sharding splits placements, not families)."""
    monkeypatch.setenv(common.RESULTS_VARIABLE, str(tmp_path))
    monkeypatch.setattr(real_files, "FAMILIES", ("float64", "float32 STL"))
    whole = real_files.run(quick=True, placements=2, only=["TopoLite cube"])
    for k in range(2):
        part = real_files.run(quick=True, placements=2, only=["TopoLite cube"], shard=(k, 2))
        assert {case["placement"] for case in part["cases"]} == {k}
    merged = real_files.merge(2)
    strip = [{k: v for k, v in case.items() if not k.endswith("seconds")} for case in whole["cases"]]
    assert [{k: v for k, v in case.items() if not k.endswith("seconds")} for case in merged["cases"]] == strip
    assert merged["summary"]["float64"]["cases"] == whole["summary"]["float64"]["cases"] == 4
    assert set(merged["summary"]) == {"float64", "float32 STL"} and len(merged["cases"]) == 8
    assert json.loads((tmp_path / "real_files.json").read_text())["complete"] is True
    with pytest.raises(ValueError, match="shard"):
        real_files.run(quick=True, placements=2, shard=(2, 2))
