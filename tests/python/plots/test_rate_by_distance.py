"""The chart of query rate against distance to the surface (plots/rate_by_distance.py): the
binned rates it draws, from hand-made results carrying `queries.by_distance` as the runner
writes it, and results without it (older ones) read without complaint."""
import json
import math
import os
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "plots"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import charts  # noqa: E402
import rate_by_distance  # noqa: E402
import results_io  # noqa: E402

# The runner's bins (harness/run/latency_by_distance.hpp): 15 inner edges, 16 bins.
EDGES = [10.0 ** (0.5 * k) for k in range(-14, 1)]


def by_distance(per_bin):
    """{bin index: (count, median latency ns)} -> the result block (each query's latency the
    median: the sums follow)."""
    counts = [0] * (len(EDGES) + 1)
    p50s = [0.0] * (len(EDGES) + 1)
    for i, (c, m) in per_bin.items():
        counts[i], p50s[i] = c, m
    return {"edges": EDGES, "count": counts, "latency_ns_sum": [c * m for c, m in zip(counts, p50s)],
            "latency_ns_p50": p50s}


def result(method, params_key, kind, per_bin, mesh="blob", query="distance", triangles=1000,
           status="ok"):
    r = {
        "schema": "bvhbench.result/1", "status": status, "message": "",
        "job": {"id": f"{mesh}__{kind}__{query}__{method}_{params_key}", "method": method,
                "method_spec": method + (":" + params_key if params_key else ""),
                "params_key": params_key, "params": {}, "query": query,
                "mesh": {"name": mesh, "triangles": triangles},
                "queries": {"kind": kind, "n": 1000}},
        "build": {"seconds": 0.1, "structure_bytes": 100 * triangles},
        "queries": {"n": 1000, "throughput_qps": {"median": 1e5}},
    }
    if per_bin is not None:
        r["queries"]["by_distance"] = by_distance(per_bin)
    return r


def result_set(tmp_path, results):
    runs = tmp_path / "runs"
    runs.mkdir()
    for r in results:
        (runs / (r["job"]["id"] + ".json")).write_text(json.dumps(r))
    return results_io.load(str(tmp_path))


def rates(bins):
    return {i: (b.count, b.rate) for i, b in enumerate(bins) if b.count}


def test_a_bins_rate_is_one_over_its_median_latency_over_every_path(tmp_path):
    rs = result_set(tmp_path, [
        # Contact: near the surface, fast; the haptic path adds its approach far away.
        result("tree", "", "contact", {5: (400, 1000.0), 6: (600, 2000.0)}),
        result("tree", "", "haptic", {6: (200, 500.0), 12: (800, 10000.0)}),
        result("tree", "coherent=true", "contact", {5: (400, 250.0), 6: (600, 500.0)}),
    ])
    data = rate_by_distance.binned_rates(rs)
    assert set(data) == {("distance", "blob")}
    plain = rates(data[("distance", "blob")][("tree", "")])
    assert plain[5] == (400, pytest.approx(1e6))
    # Bin 6 of both paths together: medians 2,000 ns (600 queries) and 500 ns (200 queries),
    # weighted by their counts: 1,625 ns.
    assert plain[6] == (800, pytest.approx(1e9 / 1625.0))
    assert plain[12] == (800, pytest.approx(1e5))
    assert set(plain) == {5, 6, 12}
    coherent = rates(data[("distance", "blob")][("tree", "coherent=true")])
    assert coherent == {5: (400, pytest.approx(4e6)), 6: (600, pytest.approx(2e6))}


def test_bins_span_their_edges_and_the_open_ends_sit_beyond_them(tmp_path):
    rs = result_set(tmp_path, [result("tree", "", "random", {0: (50, 1e3), 15: (50, 1e5),
                                                              3: (50, 1e3)})])
    bins = rate_by_distance.binned_rates(rs)[("distance", "blob")][("tree", "")]
    assert len(bins) == len(EDGES) + 1 == 16
    assert (bins[0].lo, bins[0].hi) == (0.0, EDGES[0]) and bins[0].centre < EDGES[0]
    assert (bins[3].lo, bins[3].hi) == (EDGES[2], EDGES[3])
    assert bins[3].centre == pytest.approx(math.sqrt(EDGES[2] * EDGES[3]))
    assert bins[15].lo == EDGES[-1] and bins[15].hi == math.inf and bins[15].centre > EDGES[-1]
    assert [b.rate for b in bins if b.count == 0] == [None] * 13


def test_only_the_shown_configurations_and_ok_jobs_with_bins_count(tmp_path):
    rs = result_set(tmp_path, [
        result("tree", "", "contact", {5: (100, 1e3)}),
        result("tree", "leaf=9", "contact", {5: (100, 1e5)}),           # a sweep point
        result("tree", "", "contact", {5: (100, 1e5)}, mesh="other", status="crash"),
        result("old", "", "contact", None),                              # an older result
        result("tree", "", "haptic", {5: (100, 1e3)}, query="inside"),
    ])
    data = rate_by_distance.binned_rates(rs)
    assert set(data) == {("distance", "blob"), ("inside", "blob")}
    assert set(data[("distance", "blob")]) == {("tree", "")}


def test_the_chart_draws_the_bins_with_enough_queries(tmp_path):
    few = rate_by_distance.MIN_QUERIES - 1
    rs = result_set(tmp_path, [
        result("tree", "", "contact", {5: (100, 1e3), 6: (100, 2e3), 9: (few, 10.0)}),
        result("tree", "", "contact", {5: (100, 1e4)}, mesh="big", triangles=10 ** 6),
    ])
    fig = charts.CHARTS["rate_vs_distance"].func(rs)
    # The larger model's panel first.
    axes = [ax for ax in fig.axes if ax.get_title()]
    assert axes[0].get_title().startswith("big")
    blob = next(ax for ax in axes if ax.get_title().startswith("blob"))
    (line,) = blob.get_lines()
    assert list(line.get_ydata()) == pytest.approx([1e6, 5e5])   # bin 9 has too few queries
    assert list(line.get_xdata()) == pytest.approx([math.sqrt(EDGES[4] * EDGES[5]),
                                                    math.sqrt(EDGES[5] * EDGES[6])])


def test_results_without_bins_are_no_data(tmp_path):
    rs = result_set(tmp_path, [result("old", "", "contact", None),
                               result("tree", "", "contact", {5: (3, 300.0)})])
    with pytest.raises(charts.NoData):
        charts.CHARTS["rate_vs_distance"].func(rs)
