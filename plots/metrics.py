"""The metric registry: every number a chart can put on an axis.

Each metric declares its getter, unit and which direction is better, so any two of them make a
Pareto chart (as in ann-benchmarks). Adding a metric is one entry in METRICS.
"""
from collections import namedtuple

Metric = namedtuple("Metric", "name label unit getter better log zero_label")
# better: "higher" or "lower". log: draw on a log axis. zero_label: text for a clamped zero on
# a log axis (None: zeros are dropped, e.g. a throughput of 0 means "no measurement").


def _acc(path):
    return lambda job: job.num("accuracy." + path)


def _inside_rate(job):
    rate = job.num("accuracy.inside.rate")
    if rate is None:
        wrong, n = job.num("accuracy.inside.wrong"), job.n_queries
        rate = wrong / n if wrong is not None and n else None
    return rate


def _inside_rate_far(job):
    rate = job.num("accuracy.inside.rate_far")
    if rate is None:
        wrong, n = job.num("accuracy.inside.wrong_far"), job.num("accuracy.inside.n_far")
        rate = wrong / n if wrong is not None and n else None
    return rate


def _bytes_per_triangle(job):
    b, t = job.structure_bytes, job.triangles
    return b / t if b and t else None


METRICS = {m.name: m for m in [
    Metric("qps", "Throughput (median of repetitions)", "queries/s",
           lambda j: j.qps, "higher", True, None),
    Metric("inside_wrong_rate", "Wrong inside answers", "fraction of queries",
           _inside_rate, "lower", True, "exact"),
    Metric("inside_wrong_rate_far", "Wrong inside answers far from the surface",
           "fraction of far queries", _inside_rate_far, "lower", True, "exact"),
    Metric("dist_rel_err_p99", "Distance error, p99", "fraction of mesh diagonal",
           _acc("distance.rel_error.p99"), "lower", True, "exact"),
    Metric("dist_rel_err_max", "Distance error, max", "fraction of mesh diagonal",
           _acc("distance.rel_error.max"), "lower", True, "exact"),
    Metric("normal_err_p99", "Contact normal error, p99", "degrees",
           _acc("distance.normal_angle_deg.p99"), "lower", True, "exact"),
    Metric("latency_p99", "Latency, p99", "ns",
           lambda j: j.num("queries.latency_ns.p99"), "lower", True, None),
    Metric("latency_max", "Latency, max", "ns",
           lambda j: j.num("queries.latency_ns.max"), "lower", True, None),
    Metric("build_seconds", "Build time", "s",
           lambda j: j.build_seconds, "lower", True, None),
    Metric("bytes_per_triangle", "Structure size", "bytes/triangle",
           _bytes_per_triangle, "lower", True, None),
    Metric("peak_rss", "Peak RSS", "bytes",
           lambda j: j.peak_rss_bytes, "lower", True, None),
    Metric("nodes_visited", "Nodes visited", "per query",
           lambda j: j.num("counters.nodes_visited"), "lower", True, None),
]}


def axis_label(metric):
    arrow = "higher is better \u2192" if metric.better == "higher" else "\u2190 lower is better"
    return f"{metric.label} [{metric.unit}]\n({arrow})"


def pareto_front(points, x_better, y_better):
    """Non-dominated subset of (x, y, payload...) points, sorted by x ascending.

    A point is dominated when another is at least as good on both axes and better on one, so
    points that tie on both axes are all kept (neither beats the other), and of two points with
    the same x only the better y stays. Exact answers are x = 0 on an error axis, and compete
    as any value: the fastest exact configuration is on the frontier.
    """
    sx = 1 if x_better == "higher" else -1
    sy = 1 if y_better == "higher" else -1
    # Best x first (best y first among equal x); keep a point when its y beats every y seen so
    # far, or when it ties on both axes with the last point kept.
    ordered = sorted(points, key=lambda p: (-sx * p[0], -sy * p[1]))
    front = []
    for p in ordered:
        if not front or sy * p[1] > sy * front[-1][1] or tuple(p[:2]) == tuple(front[-1][:2]):
            front.append(p)
    return sorted(front, key=lambda p: p[0])


def frontier_corners(front, x_better, y_better):
    """The staircase through frontier points (as pareto_front returns them, x ascending): the
    boundary of the region they dominate, [(x, y)] from one end to the other. Between two
    frontier points the corner takes the worse x and the worse y of the pair."""
    worse_x = max if x_better == "lower" else min
    worse_y = min if y_better == "higher" else max
    out = []
    for a, b in zip(front, front[1:]):
        out.append((a[0], a[1]))
        out.append((worse_x(a[0], b[0]), worse_y(a[1], b[1])))
    if front:
        out.append((front[-1][0], front[-1][1]))
    return out
