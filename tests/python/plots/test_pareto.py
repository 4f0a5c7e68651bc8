"""The Pareto charts: the frontier over hand-made points, which configurations share a sweep
curve, and a chart drawn from a hand-made result set with sweeps (plots/metrics.py,
plots/sweeps.py, plots/charts.py)."""
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "plots"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import charts  # noqa: E402
import metrics  # noqa: E402
import results_io  # noqa: E402
import sweeps  # noqa: E402


# ---------------------------------------------------------------------------------------------
# The frontier
# ---------------------------------------------------------------------------------------------
def names(front):
    return [p[2] for p in front]


def test_dominated_points_are_left_out():
    # error (lower is better) against throughput (higher is better)
    pts = [(1e-3, 50, "c"), (1e-2, 40, "d"), (1e-1, 60, "e"), (1e-2, 55, "f"), (1e-1, 30, "g")]
    # d: f has the same error and more speed; g: e has the same error and more speed.
    assert names(metrics.pareto_front(pts, "lower", "higher")) == ["c", "f", "e"]


def test_exact_points_compete_at_zero_error():
    pts = [(0.0, 10, "slow exact"), (0.0, 20, "fast exact"), (1e-3, 15, "approx, slower"),
           (1e-3, 50, "approx, faster"), (0.5, 5, "bad")]
    front = metrics.pareto_front(pts, "lower", "higher")
    # The fastest exact method is on the frontier; the slower exact one and an approximate one
    # slower than it are not; an approximate one faster than every exact one is.
    assert names(front) == ["fast exact", "approx, faster"]


def test_ties_on_both_axes_are_all_kept():
    pts = [(0.0, 20, "a"), (0.0, 20, "b"), (1e-3, 20, "c"), (1e-2, 30, "d"), (1e-2, 30, "e")]
    # a and b tie (neither beats the other); c is as fast as a with more error: dominated.
    assert sorted(names(metrics.pareto_front(pts, "lower", "higher"))) == ["a", "b", "d", "e"]


def test_direction_of_each_axis_is_honoured():
    pts = [(1, 1, "small slow"), (2, 2, "mid"), (3, 3, "big fast"), (2, 1, "dominated")]
    # Both higher-is-better: only the top-right point.
    assert names(metrics.pareto_front(pts, "higher", "higher")) == ["big fast"]
    # Memory (lower is better) against speed (higher is better): a trade-off curve.
    assert names(metrics.pareto_front(pts, "lower", "higher")) == ["small slow", "mid",
                                                                     "big fast"]


def test_frontier_staircase_turns_at_the_worse_corner():
    front = [(0.0, 20), (1e-3, 50), (1e-1, 60)]
    assert metrics.frontier_corners(front, "lower", "higher") == [
        (0.0, 20), (1e-3, 20), (1e-3, 50), (1e-1, 50), (1e-1, 60)]
    front = [(1, 3), (2, 2), (3, 1)]   # both higher-is-better: the staircase steps down
    assert metrics.frontier_corners(front, "higher", "higher") == [
        (1, 3), (1, 2), (2, 2), (2, 1), (3, 1)]


# ---------------------------------------------------------------------------------------------
# Sweep curves
# ---------------------------------------------------------------------------------------------
DEFAULTS = {"leaf_factor": "5", "max_planes": "8", "coherent": "false", "band": "auto",
            "ex_band": "3"}


def curves(keys):
    """{(variant, knobs): [knob values]} of sweeps.series over params_keys."""
    out = sweeps.series([(k, k) for k in keys], lambda key, name: DEFAULTS.get(name))
    return {(s.variant, s.knobs): [v for v, _ in s.points] for s in out}


def test_each_knob_is_a_curve_through_the_defaults():
    got = curves(["", "leaf_factor=2.5", "leaf_factor=10", "max_planes=4", "max_planes=16"])
    assert got == {((), ("leaf_factor",)): [(2.5,), (5.0,), (10.0,)],
                   ((), ("max_planes",)): [(4.0,), (8.0,), (16.0,)]}


def test_a_variant_is_its_own_curve_or_point():
    got = curves(["", "coherent=true", "leaf_factor=3", "coherent=true,leaf_factor=3"])
    assert got == {((), ("leaf_factor",)): [(3.0,), (5.0,)],
                   ((("coherent", "true"),), ("leaf_factor",)): [(3.0,), (5.0,)]}
    # Without a knob turned, each configuration is a point of its own.
    assert curves(["", "coherent=true"]) == {((), ()): [()], ((("coherent", "true"),), ()): [()]}


def test_a_knob_within_a_variant_is_anchored_at_the_variants_default():
    got = curves(["band=fixed", "band=fixed,ex_band=1", "band=fixed,ex_band=10", "voxel=2"])
    assert got[((("band", "fixed"),), ("ex_band",))] == [(1.0,), (3.0,), (10.0,)]
    # voxel has no known default here (not in DEFAULTS), and no anchor ran: a one-point curve.
    assert got[((), ("voxel",))] == [(2.0,)]


def test_numbers_are_knobs_and_words_are_variants():
    assert sweeps.split_key("a=1e-3,b=true,c=fixed,d=4") == (
        (("b", "true"), ("c", "fixed")), (("a", 1e-3), ("d", 4.0)))
    assert sweeps.split_key("") == ((), ())


# ---------------------------------------------------------------------------------------------
# A chart from a result set with a sweep
# ---------------------------------------------------------------------------------------------
def result(method, params_key, qps, wrong_rate, bytes_per_tri, kind="random", mesh="blob",
           params=None):
    tri = 1000
    return {
        "schema": "bvhbench.result/1", "status": "ok", "message": "",
        "job": {"id": f"{mesh}__{kind}__inside__{method}_{params_key}", "method": method,
                "method_spec": method + (":" + params_key if params_key else ""),
                "params_key": params_key, "params": params or {}, "query": "inside",
                "mesh": {"name": mesh, "triangles": tri},
                "queries": {"kind": kind, "n": 1000}},
        "build": {"seconds": 0.1, "structure_bytes": bytes_per_tri * tri},
        "queries": {"n": 1000, "throughput_qps": {"median": qps}},
        "accuracy": {"inside": {"wrong": round(wrong_rate * 1000), "rate": wrong_rate,
                                "wrong_far": round(wrong_rate * 1000), "rate_far": wrong_rate,
                                "n_far": 1000}},
    }


def swept_results():
    """An approximate method swept over a knob `grid` (default 1), an exact method with a
    knob `leaf` (default 5), and an exact method with no knob."""
    out = []
    for grid, qps, rate, b in [(0.5, 2e5, 1e-4, 400), (1, 5e5, 1e-3, 100), (2, 9e5, 1e-2, 25)]:
        key = "" if grid == 1 else f"grid={grid:g}"
        out.append(result("approx", key, qps, rate, b, params={"grid": f"{grid:g}"}))
    for leaf, qps, b in [(2, 3e5, 150), (5, 4e5, 90), (10, 2e5, 60)]:
        key = "" if leaf == 5 else f"leaf={leaf}"
        out.append(result("exact_tree", key, qps, 0.0, b, params={"leaf": str(leaf)}))
    out.append(result("exact_plain", "", 1e5, 0.0, 40))
    return out


def result_set(tmp_path, results):
    runs = tmp_path / "runs"
    runs.mkdir()
    for r in results:
        (runs / (r["job"]["id"] + ".json")).write_text(json.dumps(r))
    return results_io.load(str(tmp_path))


def test_a_sweep_is_drawn_as_a_curve_in_knob_order(tmp_path):
    rs = result_set(tmp_path, swept_results())
    fig = charts.pareto_chart(rs, query="inside", x_metric="bytes_per_triangle")
    ax = fig.axes[0]
    lines = {tuple(l.get_xdata()): list(l.get_ydata()) for l in ax.get_lines()
             if len(l.get_xdata()) == 3 and l.get_linestyle() != "None"}
    # x = bytes per triangle in the order of the knob's value (0.5, 1, 2 and 2, 5, 10).
    assert lines[(400.0, 100.0, 25.0)] == [2e5, 5e5, 9e5]
    assert lines[(150.0, 90.0, 60.0)] == [3e5, 4e5, 2e5]
    labels = [t.get_text() for t in ax.texts if isinstance(t, matplotlib.text.Annotation)]
    # The knob's name on its first turned point, values on the others, the defaults once.
    assert sorted(labels) == sorted(["grid=0.5", "2", "default", "leaf=2", "10", "default"])
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "approx \u00b7 grid" in legend and "exact_tree \u00b7 leaf" in legend
    assert "exact_plain" in legend


def test_exact_methods_are_drawn_in_the_exact_band_and_the_fastest_is_on_the_frontier(tmp_path):
    rs = result_set(tmp_path, swept_results())
    fig = charts.pareto_chart(rs, query="inside", x_metric="inside_wrong_rate")
    ax = fig.axes[0]
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    assert ticks[0] == "exact"
    floor = ax.get_xticks()[0]
    assert floor < 1e-4      # below every measured error
    # Frontier rings: the fastest exact configuration (exact_tree, defaults, 4e5) and the
    # approximate ones faster than it (5e5 at 1e-3, 9e5 at 1e-2); nothing else.
    rings = [c for c in ax.collections if c.get_sizes().size and c.get_sizes()[0] == 120]
    assert len(rings) == 1
    ring_y = sorted(y for _, y in rings[0].get_offsets())
    assert ring_y == [4e5, 5e5, 9e5]
    ring_x = sorted(x for x, _ in rings[0].get_offsets())
    assert ring_x[0] < floor * 10 and ring_x[1:] == [1e-3, 1e-2]


def test_the_report_writes_the_pareto_charts_of_a_swept_result_set(tmp_path):
    result_set(tmp_path, swept_results())
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "plots", "report.py"),
                           str(tmp_path), "--strict"], capture_output=True, text=True,
                          env=dict(os.environ, MPLBACKEND="Agg"), timeout=600)
    assert proc.returncode == 0, proc.stderr
    for name in ("pareto_inside_wrong_rate", "pareto_inside_memory"):
        png = tmp_path / "report" / f"{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (tmp_path / "report" / "report.md").read_text()
    assert "](pareto_inside_memory.png)" in md
    assert "Not drawn: no ok `distance` job" in md   # the suite ran no distance job


@pytest.mark.parametrize("metric", ["inside_wrong_rate", "bytes_per_triangle"])
def test_nothing_to_draw_is_said_not_drawn(tmp_path, metric):
    r = swept_results()[0]
    r["status"] = "crash"
    rs = result_set(tmp_path, [r])
    with pytest.raises(charts.NoData):
        charts.pareto_chart(rs, query="inside", x_metric=metric)
