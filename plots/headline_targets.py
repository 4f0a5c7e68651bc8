"""The EBP-Octree's headline against Embree, with its targets, from a run of suites/headline.yml.

Per model: the haptic distance (coherent EBP-Octree with its default certificate policy, with
the certificate at every renewal, without it, and Embree's coherent variant; and where it ran,
both without coherence, >= 1x), inside on the haptic path (not coherent and coherent) and on
random points, each as the median pass's throughput and the ratio to Embree measured in the same
run; then the structure's bytes per triangle, and the out-of-core rows (throughput, p99.9
latency, peak RSS). Targets beside them (the EBP-Octree's headline issue): distance >= 2x Embree
coherent; inside haptic >= 1x Embree without coherence and >= 2x with; inside random >= 2x from
1M triangles; bytes <= Embree's; out of core >= 1 MHz, p99.9 < 1 ms, RSS < 400 MiB. Then the
contact regime (the `contact` kind's band and speed sweep): per model, band and speed, the
coherent distance (EBP-Octree default and plain search, Embree coherent; >= 2x) and, where it
ran, without coherence (>= 1x). A query set's band and speed are read from its sidecar
(RESULTS/data/queries/NAME.json, or beside the path the result names).

The same tables in instructions: given a measurement of tools/instr_gate.py (`measure --groups
--jobs suites/headline.yml`: each job's result in RESULTS/runs and its instructions per query in
RESULTS/instructions.json), every figure is a job's instructions per query in its timed pass and
every ratio is Embree's instructions over the EBP-Octree's, so that a ratio reads as a speed-up in
both tables. Deterministic where wall clock on a shared machine moves 10-15 %, but blind to cache
misses: the two tables together say how much of a ratio is work and how much memory.

Results are read through results_io (the one reader of result files); `tools/headline_table.py`
is the command that prints these tables. Standard library only.
"""
import json
import os
from pathlib import Path

import results_io


def _stem(path):
    return os.path.splitext(os.path.basename(path or ""))[0]


class Headline:
    """The results of one run, one per (model, path, contact setting, query, method spec); with
    `instructions` ({job id: instructions per query}) its figures are those counts."""

    def __init__(self, rs, instructions=None):
        self.instructions = instructions
        self.root = Path(rs.root)
        self.jobs = rs.jobs
        self._sidecars = {}
        self.by = {}
        for j in self.jobs:  # the most queries, then the latest run
            k = self.key(j)
            rank = (j.num("job.queries.n") or 0, results_io.as_str(j.get("context.date")))
            if k not in self.by or rank > self.by[k][0]:
                self.by[k] = (rank, j)
        self.by = {k: j for k, (_, j) in self.by.items()}
        self.models = sorted(dict.fromkeys(self.model(j) for j in self.jobs), key=self.triangles)

    @staticmethod
    def model(j):
        return _stem(j.get("job.mesh.path"))

    def triangles(self, model):
        return next(j.triangles for j in self.jobs if self.model(j) == model) or 0

    def query_params(self, j):
        """The generator's parameters of the job's query set, from its sidecar ({} if none)."""
        path = results_io.as_str(j.get("job.queries.path"))
        if path not in self._sidecars:
            self._sidecars[path] = {}
            for side in (self.root / "data" / "queries" / (Path(path).stem + ".json"), Path(path).with_suffix(".json")):
                try:
                    self._sidecars[path] = json.loads(side.read_text()).get("params") or {}
                    break
                except (OSError, ValueError):
                    continue
        return self._sidecars[path]

    def contact_setting(self, j):
        """(band_mm, slide_speed) of a contact-path result, None for other kinds."""
        if j.kind != "contact":
            return None
        p = self.query_params(j)
        return (p.get("band_mm"), p.get("slide_speed"))

    def key(self, j):
        return (self.model(j), j.kind, self.contact_setting(j), j.query, results_io.as_str(j.get("job.method_spec")))

    def speed(self, j):
        """Queries per second, or in instructions the reciprocal of the instructions per query
        (higher is faster in both, and a ratio of two is the same speed-up)."""
        if j is None or not j.ok:
            return None
        if self.instructions is None:
            return j.qps
        ipq = self.instructions.get(j.id)
        return 1.0 / ipq if ipq else None

    def rate(self, model, kind, query, spec, setting=None):
        return self.speed(self.by.get((model, kind, setting, query, spec)))

    def fmt(self, q):
        """A speed as the table shows it: a rate, or instructions per query."""
        if q is None:
            return "—"
        if self.instructions is not None:
            return f"{1.0 / q:,.0f}"
        return fmt_rate(q)


def fmt_rate(q):
    if q is None:
        return "—"
    return f"{q / 1e6:.2f} M" if q >= 1e6 else f"{q / 1e3:.0f} k"


def fmt_ratio(a, b, target=None):
    if a is None or b is None or b == 0:
        return "—"
    x = a / b
    mark = "" if target is None else (" ✔" if x >= target else " ✘")
    # Rounded to two decimals, except where that would print the target beside a ✘: 1.995
    # against 2x prints 1.99 ✘, never 2.00 ✘.
    shown = round(x, 2)
    if target is not None and x < target <= shown:
        shown = target - 0.01
    return f"{shown:.2f}×{mark}"


def _bytes_per_triangle(j, tris):
    b = j.num("memory.structure_bytes") if j is not None else None
    return f"{b / tris:.1f}" if b is not None and tris else "—"


def model_rows(h):
    """The per-model table: haptic distance, inside, bytes per triangle."""
    out = ["| model (triangles) | EBP haptic distance (auto) | always | plain | Embree coherent | auto / Embree (≥ 2×) "
           "| not coherent / not coherent (≥ 1×) "
           "| EBP inside haptic / Embree (≥ 1×) | coherent / coherent (≥ 2×) | inside random / Embree (≥ 2× from 1M) "
           "| bytes / triangle EBP, Embree |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for m in h.models:
        tris = h.triangles(m)
        q = lambda kind, query, spec: h.rate(m, kind, query, spec)  # noqa: E731
        d_auto = q("haptic", "distance", "ebp_octree:coherent=true")
        d_emb = q("haptic", "distance", "embree:coherent=true")
        eb = h.by.get((m, "random", None, "inside", "ebp_octree")) or h.by.get((m, "haptic", None, "distance", "ebp_octree:coherent=true"))
        em = h.by.get((m, "random", None, "inside", "embree")) or h.by.get((m, "haptic", None, "distance", "embree:coherent=true"))
        out.append(
            f"| {m} ({int(tris):,}) | {h.fmt(d_auto)} "
            f"| {h.fmt(q('haptic', 'distance', 'ebp_octree:coherent=true,certificate_policy=always'))} "
            f"| {h.fmt(q('haptic', 'distance', 'ebp_octree:coherent=true,certificate=false'))} | {h.fmt(d_emb)} "
            f"| {fmt_ratio(d_auto, d_emb, 2)} "
            f"| {fmt_ratio(q('haptic', 'distance', 'ebp_octree'), q('haptic', 'distance', 'embree'), 1)} "
            f"| {fmt_ratio(q('haptic', 'inside', 'ebp_octree'), q('haptic', 'inside', 'embree'), 1)} "
            f"| {fmt_ratio(q('haptic', 'inside', 'ebp_octree:coherent=true'), q('haptic', 'inside', 'embree:coherent=true'), 2)} "
            f"| {fmt_ratio(q('random', 'inside', 'ebp_octree'), q('random', 'inside', 'embree'), 2 if tris >= 950_000 else None)} "
            f"| {_bytes_per_triangle(eb, tris)}, {_bytes_per_triangle(em, tris)} |")
    return out


def contact_rows(h):
    """The contact regime per model, band and speed ([] when the run has no contact path)."""
    settings = sorted({k[2] for k in h.by if k[1] == "contact" and k[2] is not None},
                      key=lambda s: (s[0] is None, s[0] or 0, s[1] is None, s[1] or 0))
    if not settings:
        return []
    out = ["| contact: model | band ± mm | slide m/s | EBP coherent (auto) | plain | Embree coherent "
           "| best EBP / Embree (≥ 2×) | EBP / Embree not coherent (≥ 1×) |",
           "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for m in h.models:
        for st in settings:
            auto = h.rate(m, "contact", "distance", "ebp_octree:coherent=true", st)
            plain = h.rate(m, "contact", "distance", "ebp_octree:coherent=true,certificate=false", st)
            emb = h.rate(m, "contact", "distance", "embree:coherent=true", st)
            nc_ebp = h.rate(m, "contact", "distance", "ebp_octree", st)
            nc_emb = h.rate(m, "contact", "distance", "embree", st)
            if auto is None and plain is None and emb is None and nc_ebp is None:
                continue
            best = max((x for x in (auto, plain) if x is not None), default=None)
            out.append(f"| {m} | {st[0]} | {st[1]} | {h.fmt(auto)} | {h.fmt(plain)} | {h.fmt(emb)} "
                       f"| {fmt_ratio(best, emb, 2)} | {fmt_ratio(nc_ebp, nc_emb, 1)} |")
    return out


def out_of_core_rows(h):
    """The jobs on a store ([] when none ran)."""
    ooc = [j for j in h.jobs if (j.get("job.params") or {}).get("store")]
    if not ooc:
        return []
    out = ["| out of core (256 MiB cache) | path | query | throughput (≥ 1 MHz) | p50 | p99.9 (< 1 ms) | RSS querying (< 400 MiB) |",
           "|---|---|---|---:|---:|---:|---:|"]
    cold = lambda j: str((j.get("job.params") or {}).get("cold"))  # noqa: E731
    for j in sorted(ooc, key=lambda j: (j.kind, j.query, cold(j))):
        where = "cold" if cold(j).lower() == "true" else "warm"
        st = h.contact_setting(j)
        path = j.kind + (f" ±{st[0]} mm, {st[1]} m/s" if st else "")
        if not j.ok:
            out.append(f"| {h.model(j)}, {where} | {path} | {j.query} | {j.status} | | | |")
            continue
        if h.instructions is not None:  # latency and memory under valgrind say nothing
            out.append(f"| {h.model(j)}, {where} | {path} | {j.query} | {h.fmt(h.speed(j))} | | | |")
            continue
        lat = j.get("queries.latency_ns") or {}
        # The RSS while querying: the job also loads the mesh once, to check the store against it.
        rss = j.num("memory.query_rss_bytes")
        out.append(f"| {h.model(j)}, {where} | {path} | {j.query} | {fmt_rate(j.qps)} "
                   f"| {lat.get('p50', 0) / 1e3:.2f} µs | {lat.get('p999', 0) / 1e3:.1f} µs "
                   f"| {rss / 2**20:.0f} MiB |" if rss else "| — |")
    return out


def markdown(rs, instructions=None):
    """Every table of the headline, Markdown, a blank line between tables; in instructions per
    query with `instructions` ({job id: instructions per query})."""
    h = Headline(rs, instructions)
    lines = model_rows(h)
    if instructions is not None:
        lines = ["Instructions per query (callgrind, timed pass only); each ratio is Embree's count over "
                 "the EBP-Octree's.", ""] + lines
    for more in (contact_rows(h), out_of_core_rows(h)):
        if more:
            lines += [""] + more
    return "\n".join(lines) + "\n"
