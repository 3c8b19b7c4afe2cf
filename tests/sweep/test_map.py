"""Verdict maps of a sweep: categories and their colours, grid image or scatter, theory lines, PNG files, errors."""

import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("matplotlib")
from matplotlib.collections import PathCollection, QuadMesh  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.image import imread  # noqa: E402

from interlock.errors import InterlockError  # noqa: E402
from interlock.sweep.map import verdict_map  # noqa: E402
from interlock.sweep.spec import SweepError  # noqa: E402

#: Expected colours, written out here (Okabe-Ito) rather than read from the module under test.
GREEN, VERMILLION, ORANGE, GREY, BLACK = "#009E73", "#D55E00", "#E69F00", "#999999", "#000000"
#: Anti-aliasing blends colours; a pixel within this (0..1 per channel) shows a colour.
TOL = 3 / 255


def record(index, s0, t0, word=None, status="ok", verdict="periodic"):
    return {"index": index, "parameters": {"s0": s0, "t0": t0, "u": 1.0}, "status": status,
            "verdicts": {verdict: word} if status == "ok" else {}, "message": "", "tolerances": {}, "seconds": 0.1}


#: A 3x3 grid over s0 in (0, 0.1, 0.2) and t0 in (0, 0.5, 1): cell (i, j) has s0 = 0.1 i, t0 = 0.5 j.
GRID_WORDS = {(0, 0): "interlocked", (1, 0): "not interlocked", (2, 0): "inconclusive",
              (0, 1): "interlocked", (1, 1): "interlocked", (2, 1): "not interlocked",
              (0, 2): "interlocked", (1, 2): "invalid", (2, 2): "failed"}
GRID_COLOURS = {"interlocked": GREEN, "not interlocked": VERMILLION, "inconclusive": ORANGE,
                "invalid": GREY, "failed": BLACK}


def grid_records():
    out = []
    for n, ((i, j), word) in enumerate(sorted(GRID_WORDS.items())):
        status = word if word in ("invalid", "failed") else "ok"
        out.append(record(n, 0.1 * i, 0.5 * j, None if status != "ok" else word, status))
    return out


def artists(fig, kind):
    return [a for a in fig.axes[0].get_children() if isinstance(a, kind)]


def legend_texts(fig):
    return [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def pixel(fig, x, y):
    """RGBA (0..1) of the drawn figure at data point (x, y)."""
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba()) / 255
    px, py = fig.axes[0].transData.transform((x, y))
    return image[image.shape[0] - 1 - int(round(py)), int(round(px))]


def test_grid_is_an_image_coloured_by_category():
    fig = verdict_map(grid_records(), "s0", "t0")
    meshes = artists(fig, QuadMesh)
    assert len(meshes) == 1 and not artists(fig, PathCollection)
    for (i, j), word in GRID_WORDS.items():
        drawn = pixel(fig, 0.1 * i, 0.5 * j)
        assert np.allclose(drawn, to_rgba(GRID_COLOURS[word]), atol=TOL), ((i, j), word, drawn)
    # The mesh's array holds one value per cell, rows along t0 and columns along s0.
    array = np.asarray(meshes[0].get_array()).reshape(3, 3)
    for (i, j), word in GRID_WORDS.items():
        assert np.allclose(meshes[0].to_rgba(array[j, i]), to_rgba(GRID_COLOURS[word]))


def test_grid_legend_counts_every_category_in_order():
    fig = verdict_map(grid_records(), "s0", "t0")
    assert legend_texts(fig) == ["interlocked (4)", "not interlocked (2)", "inconclusive (1)",
                                 "invalid deformation (1)", "failed (1)"]


def test_cell_edges_lie_halfway_between_uneven_grid_values():
    records = [record(n, x, y, "interlocked") for n, (x, y) in enumerate((x, y) for x in (0, 1, 3) for y in (10, 20))]
    fig = verdict_map(records, "s0", "t0")
    coordinates = artists(fig, QuadMesh)[0].get_coordinates()
    assert np.allclose(coordinates[0, :, 0], [-0.5, 0.5, 2.0, 4.0])
    assert np.allclose(coordinates[:, 0, 1], [5.0, 15.0, 25.0])


@pytest.mark.parametrize("verdict, positive, negative", [("stability", "stable", "unstable"),
                                                          ("criterion_4_3", "holds", "fails"),
                                                          ("patch", "interlocked", "not interlocked"),
                                                          ("patch", "interlocked", "not infinitesimally interlocked")])
def test_legend_uses_the_words_of_the_verdict(verdict, positive, negative):
    records = [record(n, n % 2, n // 2, positive if n < 3 else negative, verdict=verdict) for n in range(4)]
    fig = verdict_map(records, "s0", "t0", verdict=verdict)
    assert legend_texts(fig) == [f"{positive} (3)", f"{negative} (1)"]
    assert np.allclose(pixel(fig, 0, 0), to_rgba(GREEN), atol=TOL)
    assert np.allclose(pixel(fig, 1, 1), to_rgba(VERMILLION), atol=TOL)


def test_random_points_are_a_scatter_with_category_colours():
    rng = np.random.default_rng(1)
    points = rng.uniform(0, 1, (30, 2))
    words = ["interlocked" if x < y else "not interlocked" for x, y in points]
    records = [record(n, x, y, w) for n, ((x, y), w) in enumerate(zip(points, words))]
    records.append(record(30, 0.5, 0.5, status="invalid"))
    fig = verdict_map(records, "s0", "t0")
    assert not artists(fig, QuadMesh)
    scatters = {s.get_label(): s for s in artists(fig, PathCollection)}
    below = sum(w == "interlocked" for w in words)
    assert set(scatters) == {f"interlocked ({below})", f"not interlocked ({30 - below})", "invalid deformation (1)"}
    inside = scatters[f"interlocked ({below})"]
    assert np.allclose(np.sort(inside.get_offsets(), axis=0), np.sort(points[points[:, 0] < points[:, 1]], axis=0))
    assert np.allclose(inside.get_facecolor()[0], to_rgba(GREEN))
    assert np.allclose(scatters["invalid deformation (1)"].get_offsets(), [[0.5, 0.5]])
    assert np.allclose(scatters["invalid deformation (1)"].get_facecolor()[0], to_rgba(GREY))


def test_grid_with_a_missing_cell_or_a_repeated_point_is_drawn_as_a_scatter():
    records = grid_records()
    fig = verdict_map(records[:-1], "s0", "t0")       # a resumed, partial run
    assert not artists(fig, QuadMesh) and sum(len(s.get_offsets()) for s in artists(fig, PathCollection)) == 8
    fig = verdict_map(records + [records[0]], "s0", "t0")
    assert not artists(fig, QuadMesh) and sum(len(s.get_offsets()) for s in artists(fig, PathCollection)) == 10


def test_theory_lines_are_dashed_and_labelled():
    theory = [{"axis": "x", "value": 0.15, "label": "point on its edge (collinear)"},
              {"axis": "y", "value": 0.25, "label": "t0 bound"},
              {"points": [[0, 0], [0.2, 1.0]], "label": "a curve"}]
    fig = verdict_map(grid_records(), "s0", "t0", theory=theory)
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    assert set(lines) == {"point on its edge (collinear)", "t0 bound", "a curve"}
    assert np.allclose(lines["point on its edge (collinear)"].get_xdata(), [0.15, 0.15])
    assert np.allclose(lines["t0 bound"].get_ydata(), [0.25, 0.25])
    assert np.allclose(np.column_stack(lines["a curve"].get_data()), [[0, 0], [0.2, 1.0]])
    assert all(line.get_linestyle() == "--" for line in lines.values())
    assert legend_texts(fig)[-3:] == ["point on its edge (collinear)", "t0 bound", "a curve"]


def test_title_and_axis_labels():
    fig = verdict_map(iter(grid_records()), "t0", "s0", verdict="periodic")
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("t0", "s0")
    assert ax.get_title() == "periodic over t0, s0 (9 points)"
    assert verdict_map(grid_records(), "s0", "t0", title="Fig. 5").axes[0].get_title() == "Fig. 5"


def test_saving_writes_a_png(tmp_path):
    path = tmp_path / "map.png"
    out = verdict_map(grid_records(), "s0", "t0", path=str(path), theory=[{"axis": "x", "value": 0.1, "label": "l"}])
    assert out == path
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    image = imread(path)
    assert image.shape[1] > 700     # 7 in at 150 dpi is 1050 pixels wide
    with pytest.raises(SweepError, match="cannot write"):
        verdict_map(grid_records(), "s0", "t0", path=tmp_path / "missing" / "map.png")


@pytest.mark.parametrize("kwargs, message", [({"x": "a"}, r"unknown parameter 'a'; the records have 's0', 't0', 'u'"),
                                             ({"y": "b"}, r"unknown parameter 'b'"),
                                             ({"verdict": "cra"}, r"no record has the verdict 'cra'.*'periodic'"),
                                             ({"theory": [{"axis": "z", "value": 1, "label": "l"}]}, "theory line"),
                                             ({"theory": [{"points": [[0, 0]], "label": "l"}]}, "theory line"),
                                             ({"theory": [{"axis": "x", "value": 1}]}, "label")])
def test_bad_input_is_a_sweep_error(kwargs, message):
    arguments = {"x": "s0", "y": "t0", **kwargs}
    with pytest.raises(SweepError, match=message) as caught:
        verdict_map(grid_records(), **arguments)
    assert isinstance(caught.value, InterlockError) and isinstance(caught.value, ValueError)


def test_empty_records_bad_status_and_bad_word_are_errors():
    with pytest.raises(SweepError, match="no records"):
        verdict_map([], "s0", "t0")
    with pytest.raises(SweepError, match="record 4 has status 'skipped'"):
        verdict_map([record(4, 0, 0, status="skipped"), record(5, 1, 1, "holds")], "s0", "t0")
    with pytest.raises(SweepError, match="record 0 has verdict 'periodic' = 'maybe'"):
        verdict_map([record(0, 0, 0, "maybe")], "s0", "t0")
    bad = record(1, 0, 0, "interlocked")
    bad["parameters"]["t0"] = "n/a"
    with pytest.raises(SweepError, match="record 1 has no number"):
        verdict_map([bad, record(2, 1, 1, "interlocked")], "s0", "t0")


def test_missing_matplotlib_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    with pytest.raises(SweepError, match=r'pip install "interlock\[plot\]"'):
        verdict_map(grid_records(), "s0", "t0")


WORDS = ["interlocked", "not interlocked", "inconclusive", "invalid", "failed"]


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 4), st.integers(2, 4), st.data())
def test_any_full_grid_image_holds_each_cell_category(nx, ny, data):
    kinds = data.draw(st.lists(st.integers(0, 4), min_size=nx * ny, max_size=nx * ny))
    records = []
    for n, kind in enumerate(kinds):
        status = WORDS[kind] if kind >= 3 else "ok"
        records.append(record(n, float(n % nx), float(n // nx) ** 2, WORDS[kind] if kind < 3 else None, status))
    fig = verdict_map(records, "s0", "t0")
    mesh = artists(fig, QuadMesh)[0]
    expected = [to_rgba(c) for c in (GREEN, VERMILLION, ORANGE, GREY, BLACK)]
    colours = mesh.to_rgba(np.asarray(mesh.get_array()).reshape(ny, nx))
    for n, kind in enumerate(kinds):
        assert np.allclose(colours[n // nx, n % nx], expected[kind])
    counts = [int(text.rsplit("(", 1)[1].rstrip(")")) for text in legend_texts(fig)]
    assert sum(counts) == nx * ny and len(counts) == len(set(kinds))


def test_a_sweep_with_only_invalid_points_is_still_drawn():
    # found by hypothesis: with no "ok" record no verdict exists, but the map of invalid points is the answer
    records = [record(n, float(n % 2), float(n // 2), None, "invalid") for n in range(4)]
    assert legend_texts(verdict_map(records, "s0", "t0")) == ["invalid deformation (4)"]
