"""``python -m benchmarks --quick`` runs every benchmark and writes its JSON and chart, and their facts hold."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import SHARED_DATA

ROOT = Path(__file__).resolve().parents[1]
NAMES = ("wallpaper", "rhomblock", "verify", "scaling", "periodic", "accuracy", "degeneracy", "gallery")


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("benchmarks")
    run = subprocess.run([sys.executable, "-m", "benchmarks", "--quick", "--results", str(folder)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    return {name: json.loads((folder / f"{name}.json").read_text()) for name in NAMES
            if (folder / f"{name}.json").exists()}, folder


def test_every_benchmark_writes_json_with_the_machine_and_a_chart(results):
    records, folder = results
    # only the bunny benchmark needs the reference data beside the project
    assert set(NAMES) - set(records) <= ({"verify"} if not SHARED_DATA.is_dir() else set())
    for name, record in records.items():
        assert record["machine"]["cpus"] >= 1 and record["machine"]["versions"]["numpy"], name
        assert (folder / f"{name}.png").read_bytes()[:4] == b"\x89PNG", name
    # the committed full results were not touched by the quick run
    assert json.loads((ROOT / "benchmarks" / "results" / "accuracy.json").read_text())["quick"] is False


def test_no_method_is_wrong_where_a_proof_labels_the_answer(results):
    accuracy = results[0]["accuracy"]
    assert accuracy["wrong"] == [] and accuracy["labelled"]


def test_default_tolerances_never_answer_wrongly_near_degeneracy(results):
    degeneracy = results[0]["degeneracy"]
    assert all(degeneracy["defaults_never_wrong"].values())
    assert degeneracy["delta_star"] <= 1e-3


def test_the_gallery_agrees_with_the_paper_and_the_naive_baseline_with_us(results):
    records = results[0]
    assert records["gallery"]["contradictions"] == []
    if "verify" in records:
        assert records["verify"]["agrees"] is True
