"""The report's charts: one function per chart, registered in CHARTS.

A chart function takes a ResultSet and returns a matplotlib Figure, or raises NoData(reason)
when the suite has nothing for it to show (the report then says so instead of drawing an empty
frame). Adding a chart is one function and one CHARTS entry; report.py saves it as PNG and SVG.
Only ok jobs with the needed values are drawn; non-ok jobs appear in the report's tables.
"""
import math
import os
from collections import namedtuple
from functools import partial

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

import definitions
import fmt
import headline
import metrics
import rate_by_distance
import registry
import stability
import sweeps
import tables
from metrics import METRICS, axis_label
from results_io import is_coherent, median, method_sort_key, shown_configs
from style import (DPI, FIGSIZE_PANEL, HAPTIC_DEADLINE_NS, HAPTIC_RATE_HZ, STATUS_COLORS,
                   STATUS_LABELS, method_color, method_marker)


class NoData(Exception):
    """The suite holds nothing this chart could show."""


Chart = namedtuple("Chart", "func title caption")

MAX_PANELS = 9

_kind_key = registry.kind_sort_key  # panels in the order the runner registers its query kinds


def _grid(n, max_cols=3, panel=FIGSIZE_PANEL, legend_width=2.3):
    cols = min(n, max_cols)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, squeeze=False,
                             figsize=(panel[0] * cols + legend_width, panel[1] * rows),
                             dpi=DPI)
    flat = list(axes.flat)
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def _finish(fig, handles, legend_title=None, note=None, legend_width=2.3):
    """Legend outside the axes, on the right, so it never hides a point."""
    right = 1 - legend_width / fig.get_figwidth() if handles else 1
    fig.tight_layout(rect=(0, 0.04 if note else 0, right, 1))
    if handles:
        fig.legend(handles=handles, loc="center left", title=legend_title, fontsize=8,
                   title_fontsize=8, bbox_to_anchor=(right + 0.005, 0.5), frameon=False)
    if note:
        fig.text(0.01, 0.01, note, fontsize=7, color="#444444", ha="left", va="bottom")
    return fig


def _log_ticks(ax, axis="y", formatter=None):
    """Log axis ticks that stay readable however many decades the data spans: 1..9 labels
    under one decade, 1-2-5 under two, decades beyond. Pads the limits a little."""
    get, set_ = (ax.get_ylim, ax.set_ylim) if axis == "y" else (ax.get_xlim, ax.set_xlim)
    lo, hi = get()
    if lo <= 0 or hi <= 0:
        return
    if math.log10(hi / lo) < 0.3:      # a single value or nearly: give it some room
        mid = math.sqrt(lo * hi)
        lo, hi = mid / 2, mid * 2
    lo, hi = lo / 1.15, hi * 1.15
    set_(lo, hi)
    span = math.log10(hi / lo)
    subs = (tuple(range(1, 10)) if span < 1.0 else (1.0, 2.0, 5.0) if span < 2.2 else (1.0,))
    a = ax.yaxis if axis == "y" else ax.xaxis
    a.set_major_locator(LogLocator(base=10, subs=subs, numticks=12))
    a.set_minor_formatter(NullFormatter())
    if formatter is not None:
        a.set_major_formatter(formatter)


def _time_formatter(ax, axis="x"):
    f = FuncFormatter(lambda v, _: fmt.duration_ns(v))
    (ax.xaxis if axis == "x" else ax.yaxis).set_major_formatter(f)


def _si_formatter(unit=""):
    return FuncFormatter(lambda v, _: fmt.si(v, unit, 3).replace(" ", "\u2009"))


def _log_floor(values, default=1e-6):
    """Position standing for 0 on a log axis: a decade below the smallest positive value."""
    pos = [v for v in values if v and v > 0]
    if not pos:
        return default
    return 10.0 ** (math.floor(math.log10(min(pos))) - 1)


def _mesh_title(rs, mesh, extra=""):
    t = rs.mesh_triangles(mesh)
    s = f"{mesh} ({fmt.count(t)} triangles)" if t else mesh
    return s + (f" · {extra}" if extra else "")


# ---------------------------------------------------------------------------------------------
# Speed against accuracy (Pareto)
# ---------------------------------------------------------------------------------------------
# Which linestyle each curve of one method takes, in turn (a method's colour and marker are its
# own; its curves, a sweep of each knob and each variant, are told apart by the dash).
SERIES_LINESTYLES = ["-", "--", ":", "-."]
# On a log error axis, zero error cannot be drawn: exact points go to a grey band one decade
# left of the smallest measured error. Inside the band the horizontal position has no meaning,
# so methods are spread over +-EXACT_SPREAD decades to keep their markers apart.
EXACT_SPREAD = 0.3
MAX_LABELLED_POINTS = 6   # a longer sweep names only its ends and its frontier points


def _pareto_points(rs, query, xm, ym):
    """[(job, x, y)] drawable on the two metrics' axes, and how many ok jobs lack a value."""
    pts, missing = [], 0
    for j in rs.model_jobs():
        if not (j.ok and j.query == query):
            continue
        x, y = xm.getter(j), ym.getter(j)
        if y is None or (ym.log and y <= 0):
            continue
        if x is None or (xm.log and x <= 0 and not xm.zero_label):
            missing += 1
            continue
        pts.append((j, x, y))
    return pts, missing


def _exact_positions(here, floor):
    """method -> drawn x of its exact (zero-error) points, spread around the floor."""
    exact = sorted({j.method for j, x, _ in here if x <= 0}, key=method_sort_key)
    n = len(exact)
    return {m: floor * 10 ** (EXACT_SPREAD * (2 * i / (n - 1) - 1) if n > 1 else 0.0)
            for i, m in enumerate(exact)}


def _short_value(v):
    """A variant's value for a legend: a path by its file name."""
    return os.path.basename(v) if "/" in v else v


def _series_label(method, s):
    return sweeps.series_label(method, s._replace(
        variant=tuple((k, _short_value(v)) for k, v in s.variant)))


def _curve_style(styles, method, s):
    """(linestyle, marker face) of a curve, the same in every panel of a chart: a method's knobs
    take the dashes in turn (a lone configuration has none); a variant's markers are hollow."""
    if s.knobs:
        dashes = styles.setdefault(method, {})
        ls = dashes.setdefault(s.knobs, SERIES_LINESTYLES[len(dashes) % len(SERIES_LINESTYLES)])
    else:
        ls = "none"
    return ls, "white" if s.variant else method_color(method)


def _draw_method_curves(ax, method, here, shown_x, front_ids, styles, handles):
    """One method's configurations in a panel: each sweep a curve along its knob, each lone
    configuration a marker, knob values written beside their points. Adds the legend entries
    it uses to `handles` {sort key: handle}."""
    configs = {}
    for j, x, y in here:
        if j.method == method:
            configs.setdefault(j.params_key, (j, shown_x(j, x), y))
    curves = sweeps.series(list(configs.items()),
                           lambda p, name: p[0].get("job.params." + name))
    c, mk = method_color(method), method_marker(method)
    z = 3 if method == tables.STAR else 2
    labelled = set()    # job ids already named in this panel
    for s in curves:
        ls, face = _curve_style(styles, method, s)
        xs = [p[1][1] for p in s.points]
        ys = [p[1][2] for p in s.points]
        ax.plot(xs, ys, color=c, marker=mk, markersize=6, linewidth=1.5, linestyle=ls,
                markerfacecolor=face, zorder=z, alpha=0.9)
        # Which inside it computes (plots/definitions.py): the sign of a distance follows it.
        label = _series_label(method, s) + definitions.legend_suffix(s.points[0][1][0])
        handles.setdefault((method_sort_key(method), s.variant, s.knobs), Line2D(
            [], [], color=c, marker=mk, linestyle=ls, markerfacecolor=face, markersize=6,
            label=label))
        if s.knobs:
            _label_knob_points(ax, s, c, front_ids, labelled, odd=len(labelled) % 2)


def _label_knob_points(ax, s, color, front_ids, labelled, odd):
    """Knob values beside a curve's points, the knob's name on the first point that turns it.
    The default configuration, shared by every curve of its variant, is labelled once
    ('default'); successive curves put their labels above and below, so they do not overlap."""
    n = len(s.points)
    named = False
    for k, (values, (j, x, y)) in enumerate(s.points):
        anchor = not sweeps.split_key(j.params_key)[1]
        if anchor:
            if j.id in labelled:
                continue
            text = "default"
        elif n > MAX_LABELLED_POINTS and 0 < k < n - 1 and j.id not in front_ids:
            continue
        else:
            text = sweeps.knob_text(values)
            if not named:
                text, named = ",".join(s.knobs) + "=" + text, True
        labelled.add(j.id)
        ax.annotate(text, (x, y), textcoords="offset points", xytext=(5, -4 if odd else 3),
                    va="top" if odd else "bottom", fontsize=6, color=color, zorder=6)


def _draw_frontier(ax, front, rings, xm, ym):
    """The Pareto frontier over every point of the panel: a staircase through `front` [(x, y)]
    bounding the region its points dominate (shaded), and a ring at each of `rings` [(x, y)],
    where the frontier's points are drawn. Call once the axis limits are final; they are kept."""
    if not front:
        return
    xl, yl = ax.get_xlim(), ax.get_ylim()
    stairs = metrics.frontier_corners(front, xm.better, ym.better)
    if xm.better == "higher":      # walk from the best-x end to the best-y end
        stairs = stairs[::-1]
    edge_x = xl[1] if xm.better == "lower" else xl[0]   # the worse end of each axis
    edge_y = yl[0] if ym.better == "higher" else yl[1]
    path = [(stairs[0][0], edge_y)] + stairs + [(edge_x, stairs[-1][1])]
    ax.fill([p[0] for p in path] + [edge_x], [p[1] for p in path] + [edge_y],
            color="#000000", alpha=0.05, zorder=0, linewidth=0)
    ax.plot([p[0] for p in path], [p[1] for p in path], color="#333333", linewidth=2.5,
            alpha=0.35, zorder=1, solid_joinstyle="miter")
    ax.scatter([p[0] for p in rings], [p[1] for p in rings], s=120, facecolors="none",
               edgecolors="black", linewidths=1.0, zorder=5)
    ax.set_xlim(xl)
    ax.set_ylim(yl)


def pareto_chart(rs, query, x_metric, y_metric="qps"):
    """Speed against accuracy (or memory), one panel per (model, query path).

    Each method's sweep is a curve along its knob (plots/sweeps.py says which configurations
    share a curve), a configuration without a knob a single marker; the Pareto frontier over
    every point of the panel, all methods together, is the shaded staircase, its points ringed.
    Which direction is better comes from the metrics (metrics.METRICS). On a log error axis,
    zero error (an exact method) is drawn in a grey band left of every measured error.
    """
    xm, ym = METRICS[x_metric], METRICS[y_metric]
    pts, missing = _pareto_points(rs, query, xm, ym)
    if not pts:
        raise NoData(f"no ok `{query}` job has both {xm.label.lower()} and "
                     f"{ym.label.lower()}" + (f" ({missing} ok jobs lack the first)"
                                              if missing else ""))
    panels, dropped = _pareto_panels(rs, pts)
    legend_width = 3.4
    fig, axes = _grid(len(panels), legend_width=legend_width)
    has_zero = xm.log and xm.zero_label and any(x <= 0 for _, x, _ in pts)
    floor = _log_floor([x for _, x, _ in pts]) if has_zero else None
    methods = sorted({j.method for j, _, _ in pts}, key=method_sort_key)
    handles, styles = {}, {}
    for ax, (mesh, kind) in zip(axes, panels):
        here = [(j, x, y) for j, x, y in pts if j.mesh == mesh and j.kind == kind]
        exact_x = _exact_positions(here, floor) if floor else {}

        def shown_x(j, x):
            return exact_x[j.method] if floor and x <= 0 else x

        # An exact point dominates the whole band (zero error is no better at one spot of it
        # than at another), so its frontier corner is drawn at the band's left edge.
        front = metrics.pareto_front(
            [(x, y, floor * 10 ** -0.5 if floor and x <= 0 else x, j) for j, x, y in here],
            xm.better, ym.better)
        front_ids = {p[3].id for p in front}
        for method in methods:
            _draw_method_curves(ax, method, here, shown_x, front_ids, styles, handles)
        ax.set_title(_mesh_title(rs, mesh, f"{kind} path"), fontsize=9)
        _pareto_axes(ax, xm, ym, [y for _, _, y in here], [x for _, x, _ in pts if x > 0], floor)
        _draw_frontier(ax, [(p[2], p[1]) for p in front],
                       [(shown_x(p[3], p[0]), p[1]) for p in front], xm, ym)
        _better_corner(ax, xm, ym)
    legend = [handles[k] for k in sorted(handles)]
    legend.append(Line2D([], [], color="#333333", linewidth=2.5, alpha=0.35,
                         label="Pareto frontier\n(all methods; shaded: dominated)"))
    legend.append(Line2D([], [], color="black", marker="o", markersize=9, linestyle="none",
                         markerfacecolor="none", label="on the frontier"))
    note = []
    if floor:
        note.append(f"'{xm.zero_label}' (grey band): zero error, which a log axis cannot show; "
                    "inside the band the horizontal position only sets methods apart.")
    if missing:
        note.append(f"{missing} ok jobs without a value for the x axis are not drawn.")
    if dropped > 0:
        note.append(f"{dropped} smaller model/path panels omitted.")
    return _finish(fig, legend, "method · swept parameter", " ".join(note),
                   legend_width=legend_width)


def _pareto_panels(rs, pts):
    """The (model, path) panels to draw, largest models kept when there are too many, drawn
    smallest first; and how many were left out."""
    panels = sorted({(j.mesh, j.kind) for j, _, _ in pts},
                    key=lambda p: (-(rs.mesh_triangles(p[0]) or 0), _kind_key(p[1])))
    dropped = len(panels) - MAX_PANELS
    panels = sorted(panels[:MAX_PANELS],
                    key=lambda p: (rs.mesh_triangles(p[0]) or 0, _kind_key(p[1])))
    return panels, dropped


def _pareto_axes(ax, xm, ym, ys, xs, floor):
    """A panel's scales, labels and limits: ys the panel's values, xs every panel's positive x."""
    if xm.log:
        ax.set_xscale("log")
    if ym.log:
        ax.set_yscale("log")
    ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel(axis_label(xm), fontsize=8)
    ax.set_ylabel(axis_label(ym), fontsize=8)
    ax.tick_params(labelsize=7)
    if ym.log:
        ax.set_ylim(min(ys) / 1.8, max(ys) * 1.8)   # room for markers and labels
        _log_ticks(ax, "y", _si_formatter("q/s") if ym.unit == "queries/s" else None)
    if floor:
        _exact_axis(ax, xm, floor, max(xs) if xs else floor)
    elif xm.log:
        ax.set_xlim(min(xs) / 1.5, max(xs) * 2.5)    # room for the knob labels
        _log_ticks(ax, "x", FuncFormatter(lambda v, _: f"{v:g}"))
        if math.log10(max(xs) / min(xs)) > 6:        # many decades: label a few of them
            ax.xaxis.set_major_locator(LogLocator(base=10, numticks=7))


def _better_corner(ax, xm, ym):
    """'better' written in the corner the metrics' directions point to."""
    better_x = "left" if xm.better == "lower" else "right"
    better_y = "top" if ym.better == "higher" else "bottom"
    ax.text(0.02 if better_x == "left" else 0.98, 0.97 if better_y == "top" else 0.03,
            "better", transform=ax.transAxes, fontsize=7, color="#888888",
            ha=better_x, va=better_y, style="italic")


def _exact_axis(ax, xm, floor, x_max):
    """A log error axis with a labelled grey band at `floor` standing for zero error."""
    lo, band_hi = floor * 10 ** -0.5, floor * 10 ** 0.5
    hi = max(x_max, floor * 10) * 10     # room for the knob labels
    ax.set_xlim(lo, hi)
    ax.axvspan(lo, band_hi, color="#e6e6e6", zorder=0)
    ticks = [10.0 ** e for e in range(round(math.log10(floor)) + 1,
                                      math.floor(math.log10(hi)) + 1)]
    step = max(1, math.ceil(len(ticks) / 6))          # at most about six decade labels
    ticks = ticks[::-1][::step][::-1]
    ax.set_xticks([floor] + ticks)
    ax.set_xticklabels([xm.zero_label or "0"] +
                       [f"$10^{{{round(math.log10(t))}}}$" for t in ticks])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlim(lo, hi)


# ---------------------------------------------------------------------------------------------
# Scaling with model size
# ---------------------------------------------------------------------------------------------
def _rep_jobs(rs, coherent_variants=True):
    """Jobs of the configurations shown per method, and those configurations [(method, key)]."""
    jobs = rs.model_jobs()
    configs = [c for c in shown_configs(jobs) if coherent_variants or not is_coherent(c[1])]
    wanted = set(configs)
    return [j for j in jobs if (j.method, j.params_key) in wanted], configs


def _cfg_label(cfg):
    method, key = cfg
    return method + (f" ({key})" if key else "")


def _cfg_handle(cfg, approximate=False):
    """A configuration's legend entry; an approximate one (headline.approximate_configs) has a
    hollow marker, as on the charts, and says so."""
    return Line2D([], [], color=method_color(cfg[0]), marker=method_marker(cfg[0]),
                  linestyle=_cfg_linestyle(cfg), markersize=6,
                  markerfacecolor="white" if approximate else method_color(cfg[0]),
                  label=_cfg_label(cfg) + (" (approximate)" if approximate else ""))


def _cfg_linestyle(cfg):
    if "store=" in cfg[1]:  # out of core: the same method's other storage
        return "-."
    return "--" if is_coherent(cfg[1]) else "-"


def _plot_cfg(ax, xs, ys, cfg, approximate=False):
    """One configuration's curve. Approximate ones are drawn apart from exact ones: hollow
    markers and a thinner line, so that their speed is not read as an exact method's."""
    c = method_color(cfg[0])
    ax.plot(xs, ys, color=c, marker=method_marker(cfg[0]), linewidth=1.0 if approximate else 1.6,
            linestyle=_cfg_linestyle(cfg), zorder=3 if cfg[0] == tables.STAR else 2,
            markerfacecolor="white" if approximate else c, markersize=7 if approximate else 6,
            markeredgewidth=1.5 if approximate else 1.0)


def _failed_marks(ax, failed, method):
    """Non-ok jobs as crosses on the bottom edge, at their model size."""
    xs = [j.triangles for j in failed if j.method == method and j.triangles]
    if xs:
        ax.scatter(xs, [0.02] * len(xs), transform=ax.get_xaxis_transform(), marker="x",
                   color=method_color(method), s=40, linewidths=1.8, zorder=4, clip_on=False)


def _series(jobs, cfg, getter):
    """(triangles, median value) per model for one (method, params_key), sorted by size."""
    by_t = {}
    for j in jobs:
        if (j.method, j.params_key) == cfg and j.ok and j.triangles:
            v = getter(j)
            if v is not None and v > 0:
                by_t.setdefault(j.triangles, []).append(v)
    xs = sorted(by_t)
    return xs, [median(by_t[x]) for x in xs]


def _size_axis(ax):
    """Model size on a log x axis; call after plotting, ticks follow the data's span."""
    ax.set_xscale("log")
    ax.set_xlabel("Model size [triangles]", fontsize=8)
    _log_ticks(ax, "x", _si_formatter())
    ax.tick_params(labelsize=7)
    ax.grid(True, which="major", alpha=0.3)


def throughput_vs_size(rs):
    jobs, configs = _rep_jobs(rs)
    combos = sorted({(j.query, j.kind) for j in jobs if j.ok and j.qps},
                    key=lambda p: (p[0] != "inside", _kind_key(p[1])))
    if not combos:
        raise NoData("no ok job with a throughput on a regular model")
    fig, axes = _grid(len(combos), max_cols=2)
    approx = headline.approximate_configs(rs)
    any_failed = False
    for ax, (query, kind) in zip(axes, combos):
        here = [j for j in jobs if j.query == query and j.kind == kind]
        for cfg in configs:
            xs, ys = _series(here, cfg, lambda j: j.qps)
            if xs:
                _plot_cfg(ax, xs, ys, cfg, cfg in approx)
            failed = [j for j in here if (j.method, j.params_key) == cfg and not j.ok
                      and j.status != "unsupported"]
            any_failed |= bool(failed)
            _failed_marks(ax, failed, cfg[0])
        ax.axhline(HAPTIC_RATE_HZ, color="black", linestyle="--", linewidth=1)
        ax.text(0.99, HAPTIC_RATE_HZ, "1 kHz haptic rate", transform=ax.get_yaxis_transform(),
                ha="right", va="bottom", fontsize=7)
        _size_axis(ax)
        ax.set_yscale("log")
        lo, hi = ax.get_ylim()
        ax.set_ylim(min(lo, HAPTIC_RATE_HZ / 3), max(hi, HAPTIC_RATE_HZ * 3))
        _log_ticks(ax, "y", _si_formatter("q/s"))
        ax.set_ylabel("Throughput [queries/s]\n(higher is better \u2192)", fontsize=8)
        ax.set_title(f"{query} · {kind} path", fontsize=9)
    handles = [_cfg_handle(c, c in approx) for c in configs]
    if any_failed:
        handles.append(Line2D([], [], color="#555555", marker="x", linestyle="none",
                              label="did not finish ok\n(see non-ok table)"))
    return _finish(fig, handles, "method")


def memory_vs_size(rs):
    jobs, configs = _rep_jobs(rs, coherent_variants=False)   # same structure either way
    bpt, rss = METRICS["bytes_per_triangle"].getter, METRICS["peak_rss"].getter
    if not any(bpt(j) or rss(j) for j in jobs if j.ok):
        raise NoData("no ok job reports its memory")
    fig, axes = _grid(2, max_cols=2)
    for cfg in configs:
        for ax, get in zip(axes, (bpt, rss)):
            xs, ys = _series(jobs, cfg, get)
            if xs:
                _plot_cfg(ax, xs, ys, cfg)
    # The mesh itself, for scale: what any method must at least hold.
    mesh_pts = {}
    for j in jobs:
        mb = j.num("memory.mesh_bytes")
        if mb and j.triangles:
            mesh_pts[j.triangles] = mb
    if mesh_pts:
        xs = sorted(mesh_pts)
        axes[1].plot(xs, [mesh_pts[x] for x in xs], color="black", linestyle=":", linewidth=1)
        axes[0].plot(xs, [mesh_pts[x] / x for x in xs], color="black", linestyle=":",
                     linewidth=1)
    axes[0].set_ylabel("Structure size [bytes/triangle]\n(\u2190 lower is better)", fontsize=8)
    axes[0].set_title("Structure bytes per triangle (method's own count)", fontsize=9)
    axes[1].set_ylabel("Peak RSS [bytes]\n(\u2190 lower is better)", fontsize=8)
    axes[1].set_title("Peak resident memory of the job", fontsize=9)
    for ax in axes:
        _size_axis(ax)
        ax.set_yscale("log")
    _log_ticks(axes[0], "y", FuncFormatter(lambda v, _: f"{v:g}"))
    _log_ticks(axes[1], "y", FuncFormatter(lambda v, _: fmt.nbytes(v)))
    handles = [_cfg_handle(c) for c in configs]
    if mesh_pts:
        handles.append(Line2D([], [], color="black", linestyle=":", label="the mesh itself"))
    return _finish(fig, handles, "method")


def build_time_vs_size(rs):
    jobs, configs = _rep_jobs(rs, coherent_variants=False)   # same structure either way
    if not any(j.build_seconds for j in jobs if j.ok):
        raise NoData("no ok job reports a build time")
    fig, axes = _grid(1)
    ax = axes[0]
    for cfg in configs:
        xs, ys = _series(jobs, cfg, lambda j: j.build_seconds)
        if xs:
            _plot_cfg(ax, xs, ys, cfg)
    _size_axis(ax)
    ax.set_yscale("log")
    _log_ticks(ax, "y", FuncFormatter(lambda v, _: fmt.seconds(v)))
    ax.set_ylabel("Build time [s]\n(\u2190 lower is better)", fontsize=8)
    ax.set_title("Build time (median over the model's jobs)", fontsize=9)
    return _finish(fig, [_cfg_handle(c) for c in configs], "method")


# ---------------------------------------------------------------------------------------------
# Latency on haptic paths
# ---------------------------------------------------------------------------------------------
PERCENTILES = [("p50", 0.5), ("p99", 0.01), ("p999", 0.001)]


def latency_haptic(rs):
    """Exceedance plot: share of queries slower than x, from the recorded percentiles.

    The results carry only p50, p99, p99.9 and max, so those are the only points drawn; the
    dotted lines between them are a guide for the eye, not data.
    """
    jobs, _ = _rep_jobs(rs)
    jobs = [j for j in jobs if j.ok and j.kind == "haptic" and j.num("queries.latency_ns.p50")]
    if not jobs:
        raise NoData("no ok job on a haptic path records latency percentiles")
    panels = sorted({(j.query, j.mesh) for j in jobs},
                    key=lambda p: (p[0] != "inside", -(rs.mesh_triangles(p[1]) or 0)))
    # At most the 3 largest models per query kind, then drawn smallest first.
    per_q = {}
    panels = [p for p in panels if per_q.setdefault(p[0], []).append(p) or
              len(per_q[p[0]]) <= 3]
    panels.sort(key=lambda p: (p[0] != "inside", rs.mesh_triangles(p[1]) or 0))
    fig, axes = _grid(len(panels), max_cols=2, legend_width=0.0,
                      panel=(FIGSIZE_PANEL[0] + 2.2, FIGSIZE_PANEL[1]))
    all_n = [j.n_queries for j in jobs if j.n_queries]
    y_lo = 0.5 / max(all_n) if all_n else 1e-4
    for ax, (query, mesh) in zip(axes, panels):
        here = sorted([j for j in jobs if j.query == query and j.mesh == mesh],
                      key=lambda j: (method_sort_key(j.method), j.params_key))
        handles, all_x = [], []
        for j in here:
            n = j.n_queries
            xs, ys = [], []
            for key, share in PERCENTILES:
                v = j.num("queries.latency_ns." + key)
                # With n <= 1000 queries, p99.9 is the max itself: draw it once, as the max.
                if v and v > 0 and not (n and share <= 1.0 / n):
                    xs.append(v)
                    ys.append(share)
            vmax = j.num("queries.latency_ns.max")
            if vmax and vmax > 0 and n:
                xs.append(vmax)
                ys.append(1.0 / n)
            all_x += xs
            c, mk = method_color(j.method), method_marker(j.method)
            coh = is_coherent(j.params_key)
            ax.plot(xs, ys, color=c, marker=mk, linestyle="--" if coh else ":", linewidth=1.2,
                    markersize=6, markerfacecolor="white" if coh else c)
            over = j.num("queries.over_deadline")
            share = f"{100.0 * over / n:.2g}%" if over is not None and n else "unknown"
            handles.append(Line2D([], [], color=c, marker=mk, linestyle="--" if coh else ":",
                                  markerfacecolor="white" if coh else c,
                                  label=f"{j.method}{' (coherent)' if coh else ''}: {share}"))
        deadline = next((j.num("queries.deadline_ns") for j in here
                         if (j.num("queries.deadline_ns") or 0) > 0), HAPTIC_DEADLINE_NS)
        ax.axvline(deadline, color="black", linestyle="--", linewidth=1)
        ax.text(deadline, 0.98, f" {fmt.duration_ns(deadline)} deadline",
                transform=ax.get_xaxis_transform(), fontsize=7, va="top", ha="left")
        ax.set_xscale("log")
        ax.set_yscale("log")
        lo = min(all_x) if all_x else deadline / 100
        hi = max(all_x + [deadline * 5])
        ax.set_xlim(lo / 2, hi * 1.5)
        ax.axvspan(deadline, ax.get_xlim()[1], color="#fde0dd", zorder=0)
        ax.set_ylim(y_lo, 1.0)
        ax.set_yticks([t for t in (0.5, 0.1, 0.01, 1e-3, 1e-4, 1e-5, 1e-6) if t >= y_lo])
        ax.yaxis.set_major_formatter(FuncFormatter(
            lambda v, _: f"{100 * v:g}%" if v >= 1e-4 else f"{100 * v:.0e}%"))
        ax.yaxis.set_minor_formatter(NullFormatter())
        _time_formatter(ax, "x")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(labelsize=7)
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xlabel("Per-query latency (\u2190 lower is better)", fontsize=8)
        ax.set_ylabel("Share of queries slower than x", fontsize=8)
        ax.set_title(_mesh_title(rs, mesh, f"{query}, haptic path"), fontsize=9)
        # Beside the panel, not on it: the tail points are what the chart is for.
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  frameon=False, title=f"share > {fmt.duration_ns(deadline)}", title_fontsize=7)
    note = ("Points: p50, p99, p99.9 and max (at 1/n) of one replay; dotted lines only join "
            "them. Shaded: beyond the 1 ms haptic deadline.")
    return _finish(fig, [], None, note)


# ---------------------------------------------------------------------------------------------
# Thread scaling
# ---------------------------------------------------------------------------------------------
def thread_scaling(rs):
    """Throughput against query threads, per (model, query, query kind), with the ideal line."""
    jobs = [j for j in rs.thread_jobs() if j.ok and j.qps]
    if not any(j.threads > 1 for j in jobs):
        raise NoData("no ok job ran its queries on more than one thread (a suite's threads: axis)")
    scaled = {(j.mesh, j.query, j.kind, j.config) for j in jobs if j.threads > 1}
    panels = sorted({(m, q, k) for m, q, k, _ in scaled},
                    key=lambda p: (-(rs.mesh_triangles(p[0]) or 0), p[1] != "inside", _kind_key(p[2])))
    panels = panels[:MAX_PANELS]
    fig, axes = _grid(len(panels), max_cols=2)
    # Every configuration run on these panels' model and queries: also those that ran on one
    # thread only (a method that does not declare concurrent queries has `unsupported` rows for
    # T > 1), drawn as a point, so that the chart shows every method of the suite.
    on_panels = set(panels)
    configs = sorted({(j.method, j.params_key) for j in jobs if (j.mesh, j.query, j.kind) in on_panels},
                     key=lambda c: (method_sort_key(c[0]), c[1]))
    one_thread_only = set()
    approx = headline.approximate_configs(rs)
    cores = {int(c) for c in (j.num("context.cores") for j in jobs) if c}
    for ax, (mesh, query, kind) in zip(axes, panels):
        all_t = set()
        for cfg in configs:
            here = [j for j in jobs if (j.mesh, j.query, j.kind) == (mesh, query, kind)
                    and (j.method, j.params_key) == cfg]
            by_t = {}
            for j in here:
                by_t.setdefault(j.threads, []).append(
                    (j.qps, j.num("queries.threads.single_thread_qps.median")))
            if not any(t > 1 for t in by_t):
                if 1 in by_t:
                    ax.plot([1], [median([q for q, _ in by_t[1]])], color=method_color(cfg[0]),
                            marker=method_marker(cfg[0]), linestyle="none", markersize=7, zorder=2)
                    one_thread_only.add(cfg)
                    all_t.add(1)
                continue
            ts = sorted(by_t)
            ys = [median([q for q, _ in by_t[t]]) for t in ts]
            # The ideal's base: the T = 1 job's throughput, else the one-thread passes the
            # T > 1 jobs timed beside their own (queries.threads.single_thread_qps).
            singles = [s for t in ts for _, s in by_t[t] if s]
            base = ys[0] if ts[0] == 1 else (median(singles) if singles else None)
            _plot_cfg(ax, ts, ys, cfg, cfg in approx)
            if base:
                ideal_t = sorted(set(ts) | {1})
                ax.plot(ideal_t, [base * t for t in ideal_t], color=method_color(cfg[0]),
                        linestyle=":", linewidth=1.0, zorder=1)
            all_t |= set(ts)
        for c in sorted(cores):
            ax.axvline(c, color="#888888", linestyle="--", linewidth=0.8)
            ax.text(c, 0.02, f" {c} cores", transform=ax.get_xaxis_transform(), fontsize=7,
                    color="#555555", ha="left", va="bottom")
        ax.set_xscale("log", base=2)
        ticks = sorted(all_t | {1})
        ax.set_xticks(ticks)
        ax.set_xticklabels([str(t) for t in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_yscale("log")
        _log_ticks(ax, "y", _si_formatter("q/s"))
        ax.tick_params(labelsize=7)
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xlabel("Query threads", fontsize=8)
        ax.set_ylabel("Throughput [queries/s]\n(higher is better \u2192)", fontsize=8)
        ax.set_title(_mesh_title(rs, mesh, f"{query} · {kind}"), fontsize=9)
    handles = []
    for c in configs:
        h = _cfg_handle(c, c in approx)
        if c in one_thread_only:
            h.set_linestyle("none")
            h.set_label(h.get_label() + " (one thread: no concurrent queries)")
        handles.append(h)
    handles.append(Line2D([], [], color="#555555", linestyle=":", label="ideal: T \u00d7 one thread"))
    return _finish(fig, handles, "method")


# ---------------------------------------------------------------------------------------------
# Stability matrix
# ---------------------------------------------------------------------------------------------
def stability_matrix(rs):
    if not rs.is_stability_suite():
        raise NoData("the suite has no stress meshes")
    data = stability.matrix(rs)
    queries = list(data)   # inside first (stability.matrix orders them)
    n_cfg = max(len(data[q][0]) for q in queries)
    n_mesh = max(len(data[q][1]) for q in queries)
    # One panel per query kind, stacked: stability suites have many stress cases (columns).
    fig, axes = plt.subplots(len(queries), 1, squeeze=False, dpi=DPI,
                             figsize=(max(4.0, 0.85 * n_mesh + 2.8) + 2.2,
                                      (0.42 * n_cfg + 2.4) * len(queries)))
    axes = axes.T
    severity = stability.SEVERITY
    cmap = ListedColormap([STATUS_COLORS[s] for s in severity])
    used = set()
    for ax, query in zip(axes[0], queries):
        configs, meshes, cells = data[query]
        grid = np.array([[severity.index(cells[(c, m)]["status"]) for m in meshes]
                         for c in configs])
        used |= {cells[k]["status"] for k in cells}
        ax.imshow(grid, cmap=cmap, vmin=-0.5, vmax=len(severity) - 0.5, aspect="auto")
        for i, c in enumerate(configs):
            for k, m in enumerate(meshes):
                cell = cells[(c, m)]
                dark = cell["status"] in ("crash", "oom", "timeout")
                ax.text(k, i, stability.short_text(query, cell), ha="center", va="center",
                        fontsize=7, color="white" if dark else "black",
                        fontweight="bold" if cell["status"] == "ok_wrong" else "normal")
        ax.set_xticks(range(len(meshes)))
        ax.set_xticklabels(meshes, rotation=35, ha="right", fontsize=7)
        ax.set_yticks(range(len(configs)))
        ax.set_yticklabels(configs, fontsize=7)
        ax.set_xticks(np.arange(-0.5, len(meshes)), minor=True)
        ax.set_yticks(np.arange(-0.5, len(configs)), minor=True)
        ax.grid(which="minor", color="white", linewidth=2)
        ax.tick_params(which="minor", length=0)
        what = ("cell text: wrong-answer rate away from the surface" if query == "inside"
                else "cell text: worst distance error / diagonal")
        ax.set_title(f"{query} · {what}", fontsize=9)
        ax.set_xlabel("stress case", fontsize=8)
    handles = [Patch(facecolor=STATUS_COLORS[s], edgecolor="#999999", label=STATUS_LABELS[s])
               for s in severity if s in used]
    fig.tight_layout()
    fig.subplots_adjust(right=1 - 2.0 / fig.get_figwidth())
    fig.legend(handles=handles, loc="center left", fontsize=8, frameon=False,
               bbox_to_anchor=(1 - 1.95 / fig.get_figwidth(), 0.5), title="status",
               title_fontsize=8)
    return fig


# ---------------------------------------------------------------------------------------------
# The registry. Order is the order in report.md.
# ---------------------------------------------------------------------------------------------
CHARTS = {
    "pareto_inside_wrong_rate": Chart(
        partial(pareto_chart, query="inside", x_metric="inside_wrong_rate"),
        "Point-in-solid: speed against wrong answers",
        "Throughput against the share of wrong `inside` answers, one panel per model and query "
        "path. Up and left is better. Each method's parameter sweep is a curve along its knob "
        "(the knob's values beside the points; a method's curves are told apart by their "
        "dashes); a configuration without a knob is one marker. The shaded staircase is the "
        "Pareto frontier over every point of the panel, all methods together: the ringed "
        "points are those no other configuration beats on both axes. Exact answers (no wrong "
        "answer) are drawn in the grey band marked 'exact'."),
    "pareto_inside_wrong_rate_far": Chart(
        partial(pareto_chart, query="inside", x_metric="inside_wrong_rate_far"),
        "Point-in-solid: speed against wrong answers far from the surface",
        "As above, counting only queries farther than the near-surface threshold "
        "(1e-6 × diagonal) from the surface, where any wrong answer is a real error."),
    "pareto_distance_rel_err_p99": Chart(
        partial(pareto_chart, query="distance", x_metric="dist_rel_err_p99"),
        "Distance: speed against error",
        "Throughput against the 99th percentile of the signed-distance error, as a fraction "
        "of the mesh diagonal. Up and left is better; curves, frontier and the 'exact' band "
        "as in the point-in-solid chart."),
    "pareto_inside_memory": Chart(
        partial(pareto_chart, query="inside", x_metric="bytes_per_triangle"),
        "Point-in-solid: speed against memory",
        "Throughput of `inside` queries against the structure's own bytes per triangle. Up "
        "and left is better; curves and frontier as above. A method that reports no "
        "structure bytes is not drawn (the note under the chart counts them). Accuracy is "
        "not on this chart: an approximate configuration on its frontier is there for its "
        "speed and size; its error is on the accuracy charts above."),
    "pareto_distance_memory": Chart(
        partial(pareto_chart, query="distance", x_metric="bytes_per_triangle"),
        "Distance: speed against memory",
        "Throughput of `distance` queries against the structure's own bytes per triangle, as "
        "above."),
    "throughput_vs_size": Chart(
        throughput_vs_size, "Throughput against model size",
        "Median queries per second of each method (one configuration per method, named in the "
        "legend) on each regular model, log-log. The dashed line is the 1 kHz rate a haptic "
        "loop needs. Crosses on the bottom edge: jobs that crashed, timed out or failed. "
        "Hollow markers on a thin line: a configuration approximate by design (wrong answers "
        "on most of its checked jobs; the report's accuracy lines): its speed is not an exact "
        "method's."),
    "memory_vs_size": Chart(
        memory_vs_size, "Memory against model size",
        "Left: the structure's own byte count per triangle. Right: the job's peak resident "
        "set size. They answer different questions; neither replaces the other."),
    "build_time_vs_size": Chart(
        build_time_vs_size, "Build time against model size",
        "Seconds to build each method's structure, log-log."),
    "latency_haptic": Chart(
        latency_haptic, "Latency on haptic paths",
        "For each method, the share of queries slower than a given latency, from the recorded "
        "percentiles (p50, p99, p99.9, max). The dashed line is the 1 ms haptic deadline; the "
        "legend gives the share of queries that missed it."),
    "rate_vs_distance": Chart(rate_by_distance.chart, rate_by_distance.TITLE, rate_by_distance.CAPTION),
    "thread_scaling": Chart(
        thread_scaling, "Throughput against query threads",
        "Aggregate queries per second with T query threads (a suite's `threads:` axis), each "
        "with its own query state: random points split between the threads, haptic paths as T "
        "independent probes. Dotted: the ideal, T times the one-thread throughput (the T = 1 "
        "job's). Dashed vertical: the machine's cores; beyond it the threads share them."),
    "stability_matrix": Chart(
        stability_matrix, "Stability matrix",
        "Each method configuration (rows) on each stress case (columns), over every query kind "
        "run there. Colour: the worst status of its jobs; 'ok, wrong answers' marks answers "
        "beyond the accuracy tolerance. Text: the wrong-answer rate away from the surface "
        "(inside) or the worst relative distance error (distance) of ok cells; 'n/a' = "
        "unsupported, 'ok?' = no oracle. What a cell aggregates: plots/stability.py."),
}
