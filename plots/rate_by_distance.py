"""The report's chart of each method's query rate against the query's distance to the surface.

Where a method is strong and where it is weak: a distance search is cheap in contact and dear
far from the surface, a ray-parity point-in-solid test often the other way round. The runner
writes, for every job with an oracle whose method answers one query at a time, the latency
pass's queries binned by the oracle's |d| relative to the mesh diagonal (`queries.by_distance`,
fixed half-decade bins: the same in every result). A bin's rate is one over its queries' median
latency in the latency pass (one timestamped pass, the timer included): the typical query's
rate there, which one preempted query on a shared machine does not move as it moves a mean. It
is not the throughput of the timed passes.

One panel per (query, model), the largest models first; in a panel one line per configuration
the report shows for its method (the representative and its path-coherent variant), the bins
of every query path the configuration ran on that model together (the median of a bin over
several paths: the query-weighted mean of their medians). Bins holding fewer than MIN_QUERIES
queries are left out: a median of a handful of latencies is noise.
"""
import math
from collections import namedtuple

from results_io import is_coherent, method_sort_key, shown_configs
from style import FIGSIZE_PANEL, method_color, method_marker

MIN_QUERIES = 20
MAX_PANELS = 6
# The haptic query kinds take the diagonal as this many metres (query kind `model_size_m`'s
# default): the top axis reads the relative distance as millimetres on such a model.
MODEL_SIZE_MM = 300.0

TITLE = "Query rate against distance to the surface"
CAPTION = (
    "Each method's queries per second (one over the median latency of the latency pass) in bins "
    "of the query point's distance to the surface (the oracle's |d| over the mesh diagonal, "
    "half decades; top axis: millimetres when the diagonal is 0.3 m, as on the haptic paths), "
    "every query path of the model together, one panel per query and model. Where a line "
    "falls is where a method is weak. Bins of fewer than 20 queries are not drawn; the "
    "leftmost point is every query closer than 1e-7 of the diagonal (the surface itself), "
    "the rightmost every query beyond the diagonal.")

Bin = namedtuple("Bin", "lo hi centre count rate")


def _bins(edges, counts, p50s):
    """[Bin] of one job's (or several jobs' pooled) by_distance block, rate = 1 / median latency
    in queries/s (None where the bin is empty)."""
    out = []
    half = math.sqrt(10.0)
    for i, (c, m) in enumerate(zip(counts, p50s)):
        lo = edges[i - 1] if i > 0 else 0.0
        hi = edges[i] if i < len(edges) else math.inf
        # Open ends are drawn half a bin beyond the last edge, as a bin of their own.
        centre = (math.sqrt(lo * hi) if 0 < lo and hi < math.inf
                  else edges[0] / math.sqrt(half) if i == 0 else edges[-1] * math.sqrt(half))
        out.append(Bin(lo, hi, centre, c, 1e9 / m if c and m > 0 else None))
    return out


def binned_rates(rs):
    """{(query, mesh): {(method, params_key): [Bin]}} over the ok jobs of the configurations
    the report shows that carry `queries.by_distance`; a configuration's jobs on one model (its
    query paths) are pooled bin by bin (counts pooled, medians weighted by their counts).
    Every bin is listed, MIN_QUERIES or not."""
    jobs = [j for j in rs.model_jobs() if j.ok]
    wanted = set(shown_configs(jobs))
    pooled = {}
    for j in jobs:
        if (j.method, j.params_key) not in wanted:
            continue
        block = j.get("queries.by_distance")
        if not isinstance(block, dict):
            continue
        edges, counts, p50s = block.get("edges"), block.get("count"), block.get("latency_ns_p50")
        if not (isinstance(edges, list) and isinstance(counts, list) and isinstance(p50s, list)
                and len(counts) == len(p50s) == len(edges) + 1):
            continue
        key = ((j.query, j.mesh), (j.method, j.params_key))
        weighted = [c * m for c, m in zip(counts, p50s)]
        have = pooled.get(key)
        if have is None:
            pooled[key] = (list(edges), list(counts), weighted)
        elif have[0] == edges:   # bins of another layout cannot be pooled: the first one stays
            have[1][:] = [a + b for a, b in zip(have[1], counts)]
            have[2][:] = [a + b for a, b in zip(have[2], weighted)]
    out = {}
    for (panel, cfg), (edges, counts, weighted) in pooled.items():
        p50s = [w / c if c else 0.0 for c, w in zip(counts, weighted)]
        out.setdefault(panel, {})[cfg] = _bins(edges, counts, p50s)
    return out


def _panels(rs, data):
    """Distance panels before inside ones, the largest models first, at most MAX_PANELS."""
    return sorted(data, key=lambda p: (p[0] != "distance", -(rs.mesh_triangles(p[1]) or 0),
                                       p[1]))[:MAX_PANELS]


def chart(rs):
    import charts  # the registry imports this module: its helpers are read at call time
    from matplotlib.lines import Line2D

    data = binned_rates(rs)
    drawable = {p: cfgs for p, cfgs in data.items()
                if any(b.rate and b.count >= MIN_QUERIES for bins in cfgs.values() for b in bins)}
    if not drawable:
        raise charts.NoData("no ok job records its latencies by distance to the surface "
                            "(queries.by_distance: a job run with an oracle)")
    panels = _panels(rs, drawable)
    fig, axes = charts._grid(len(panels), max_cols=2, legend_width=2.6,
                             panel=(FIGSIZE_PANEL[0] + 0.6, FIGSIZE_PANEL[1]))
    handles = {}
    for ax, (query, mesh) in zip(axes, panels):
        cfgs = drawable[(query, mesh)]
        for cfg in sorted(cfgs, key=lambda c: (method_sort_key(c[0]), c[1])):
            pts = [b for b in cfgs[cfg] if b.rate and b.count >= MIN_QUERIES]
            if not pts:
                continue
            method, key = cfg
            coh = is_coherent(key)
            style = dict(color=method_color(method), marker=method_marker(method),
                         linestyle="--" if coh else "-", markersize=5, linewidth=1.4,
                         markerfacecolor="white" if coh else method_color(method))
            ax.plot([b.centre for b in pts], [b.rate for b in pts], **style)
            label = method + (f" ({key})" if key else "")
            handles.setdefault(label, Line2D([], [], label=label, **style))
        ax.set_xscale("log")
        ax.set_yscale("log")
        charts._log_ticks(ax, "y", charts._si_formatter("Hz"))
        ax.grid(True, which="major", alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("|d| / diagonal (the oracle's)", fontsize=8)
        ax.set_ylabel("Queries per second\n(\u2191 higher is better)", fontsize=8)
        ax.set_title(charts._mesh_title(rs, mesh, query), fontsize=9)
        top = ax.secondary_xaxis("top", functions=(lambda x: x * MODEL_SIZE_MM,
                                                   lambda mm: mm / MODEL_SIZE_MM))
        top.tick_params(labelsize=6)
        top.set_xlabel("mm on a 0.3 m model", fontsize=7)
    note = (f"Rate = 1 / the median latency of the bin's queries in one timestamped pass, bins "
            f"of at least {MIN_QUERIES} queries; every query path of a model together.")
    return charts._finish(fig, list(handles.values()), "configuration", note, legend_width=2.6)
