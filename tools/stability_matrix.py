#!/usr/bin/env python3
"""The stability matrix: method x case (mesh), from a suite's result files.

    python tools/stability_matrix.py RESULTS_DIR [--out DIR]

Reads RESULTS_DIR/runs/*.json (one per job, docs/results.md) and writes, into --out (default
RESULTS_DIR):

- stability_matrix.csv: one row per (method, case): the jobs' statuses and, over the jobs that
  ran `ok`, the worst inside error rate (all points and away from the surface), the worst
  distance error (absolute, and relative to the mesh diagonal), sign errors and NaN/inf answers;
- stability_matrix.md: the same as a table, one row per method and one column per case, each
  cell the status and, for ok, `in` = worst inside error rate, `d` = worst distance error / diagonal.

A case's cell aggregates its jobs (query kinds random, near, surface, haptic; inside and
distance): `ok` only if every job is ok, otherwise the non-ok statuses with their counts.
Standard library only. It never aborts on a result: an unreadable file is counted and reported,
a missing field is a blank.
"""
from __future__ import annotations

import argparse
import csv
import glob
import json
import math
import os
import sys
from collections import OrderedDict, defaultdict

# Worst first: the status shown when a case's jobs disagree.
STATUS_ORDER = ["crash", "oom", "timeout", "error", "rejected_input", "unsupported", "ok"]

CSV_COLUMNS = [
    "method", "case", "status", "jobs", "jobs_ok", "statuses",
    "inside_wrong_rate_max", "inside_wrong_rate_far_max", "inside_wrong_max",
    "dist_abs_err_max", "dist_rel_err_max", "dist_rel_err_p99_max", "sign_wrong", "non_finite",
    "normal_err_p99_deg_max", "triangle_agreement_min", "accuracy_jobs", "message",
]


def get(d, *path):
    """d[path0][path1]... or None when any step is missing or not a dict."""
    for k in path:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def num(v):
    if isinstance(v, bool) or v is None:
        return None
    if isinstance(v, (int, float)) and not (isinstance(v, float) and math.isnan(v)):
        return float(v)
    return None


def worst(values, pick=max):
    vals = [v for v in (num(x) for x in values) if v is not None]
    return pick(vals) if vals else None


def method_label(r):
    m = get(r, "job", "method") or get(r, "job", "method_spec") or "?"
    key = get(r, "job", "params_key")
    if key is None:  # a status row written before the method was resolved
        spec = get(r, "job", "method_spec") or ""
        key = spec.split(":", 1)[1] if ":" in spec else ""
    return f"{m}:{key}" if key else str(m)


def case_label(r):
    name = get(r, "job", "mesh", "name")
    if isinstance(name, str) and name:
        return name
    path = get(r, "job", "mesh", "path")
    if isinstance(path, str) and path:
        return os.path.splitext(os.path.basename(path))[0]
    jid = get(r, "job", "id")
    return jid.split("__")[0] if isinstance(jid, str) and "__" in jid else "?"


def load_runs(results_dir):
    runs, bad = [], []
    for path in sorted(glob.glob(os.path.join(results_dir, "runs", "*.json"))):
        try:
            with open(path) as f:
                r = json.load(f)
            if not isinstance(r, dict):
                raise ValueError("not a JSON object")
            runs.append(r)
        except Exception as e:  # noqa: BLE001 - a broken file must not end the matrix
            bad.append((os.path.basename(path), str(e)[:120]))
    return runs, bad


def aggregate(jobs):
    """One (method, case) cell from its jobs."""
    counts = defaultdict(int)
    for r in jobs:
        counts[str(r.get("status") or "error")] += 1
    statuses = sorted(counts, key=lambda s: STATUS_ORDER.index(s) if s in STATUS_ORDER else -1)
    ok = [r for r in jobs if r.get("status") == "ok"]
    acc = [r for r in ok if isinstance(r.get("accuracy"), dict)]
    inside = [get(r, "accuracy", "inside") for r in acc if isinstance(get(r, "accuracy", "inside"), dict)]
    dist = [get(r, "accuracy", "distance") for r in acc if isinstance(get(r, "accuracy", "distance"), dict)]
    not_ok = [r for r in jobs if r.get("status") != "ok"]
    message = ""
    if not_ok:
        message = str(not_ok[0].get("message") or "").replace("\n", " ")[:160]
    non_finite = sum(int(num(d.get("non_finite")) or 0) for d in dist)
    cell = OrderedDict(
        status="ok" if statuses == ["ok"] else statuses[0],
        jobs=len(jobs),
        jobs_ok=len(ok),
        statuses=" ".join(f"{s}:{counts[s]}" for s in statuses),
        inside_wrong_rate_max=worst(i.get("rate") for i in inside),
        inside_wrong_rate_far_max=worst(i.get("rate_far") for i in inside),
        inside_wrong_max=worst(i.get("wrong") for i in inside),
        dist_abs_err_max=worst(get(d, "abs_error", "max") for d in dist),
        dist_rel_err_max=worst(get(d, "rel_error", "max") for d in dist),
        dist_rel_err_p99_max=worst(get(d, "rel_error", "p99") for d in dist),
        sign_wrong=sum(int(num(d.get("sign_wrong")) or 0) for d in dist) if dist else None,
        non_finite=non_finite if dist else None,
        normal_err_p99_deg_max=worst(get(d, "normal_angle_deg", "p99") for d in dist),
        triangle_agreement_min=worst((d.get("triangle_agreement") for d in dist), pick=min),
        accuracy_jobs=len(acc),
        message=message,
    )
    return cell


def fmt(v, pct=False):
    if v is None:
        return ""
    if pct:
        return "0" if v == 0 else f"{100 * v:.3g}%"
    return "0" if v == 0 else f"{v:.2g}"


def cell_text(c):
    if c is None:
        return "—"
    if c["status"] != "ok":
        n_bad = c["jobs"] - c["jobs_ok"]
        text = f"**{c['status']}**" + (f" {n_bad}/{c['jobs']}" if c["jobs"] > 1 else "")
        if c["jobs_ok"] == 0:
            return text
        text += " · "
    else:
        text = "ok"
        if c["accuracy_jobs"] == 0:
            return text + " (no oracle)"
        text += " · "
    parts = []
    # Far from the surface: points within 1e-6 of the diagonal (all of the `surface` kind) have no
    # well-defined side, so the overall rate would mostly measure how a method breaks ties there.
    if c["inside_wrong_rate_far_max"] is not None:
        parts.append("in " + fmt(c["inside_wrong_rate_far_max"], pct=True))
    elif c["inside_wrong_rate_max"] is not None:
        parts.append("in(all) " + fmt(c["inside_wrong_rate_max"], pct=True))
    if c["dist_rel_err_max"] is not None:
        parts.append("d " + fmt(c["dist_rel_err_max"]))
    if c["non_finite"]:
        parts.append(f"NaN {c['non_finite']}")
    return text + " · ".join(parts) if parts else text.rstrip(" ·")


def write_outputs(runs, bad, out_dir):
    cells = defaultdict(list)
    methods, cases = [], []
    for r in runs:
        try:
            m, c = method_label(r), case_label(r)
        except Exception:  # noqa: BLE001
            m, c = "?", "?"
        if m not in methods:
            methods.append(m)
        if c not in cases:
            cases.append(c)
        cells[(m, c)].append(r)
    methods.sort()
    cases.sort(key=lambda c: (not c.endswith("_open"), c))
    agg = {}
    for key, jobs in cells.items():
        try:
            agg[key] = aggregate(jobs)
        except Exception as e:  # noqa: BLE001 - never lose a row over one odd result
            agg[key] = OrderedDict(status="error", jobs=len(jobs), jobs_ok=0, statuses="?",
                                   accuracy_jobs=0, message=f"matrix: {e}")
    os.makedirs(out_dir, exist_ok=True)
    csv_path = os.path.join(out_dir, "stability_matrix.csv")
    with open(csv_path + ".tmp", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(CSV_COLUMNS)
        for m in methods:
            for c in cases:
                if (m, c) not in agg:
                    continue
                a = agg[(m, c)]
                row = {"method": m, "case": c, **a}
                w.writerow(["" if row.get(k) is None else row.get(k) for k in CSV_COLUMNS])
    os.replace(csv_path + ".tmp", csv_path)

    md = ["# Stability matrix", "",
          f"{len(runs)} job(s), {len(methods)} method(s) x {len(cases)} case(s). Each cell: the status "
          "over the case's jobs (query kinds x inside/distance; `ok` only if all are ok, else the "
          "worst status and how many jobs had it) and, over the ok jobs, `in` = worst inside error "
          "rate among points farther than 1e-6 of the diagonal from the surface (the CSV also has the "
          "rate over all points), `d` = worst distance error / mesh diagonal, `NaN` = non-finite "
          "distances. The oracle is exact on closed meshes and the generalized winding number "
          "(> 1/2) on open or broken ones. "
          "`—` = not run.", ""]
    if bad:
        md += [f"{len(bad)} result file(s) could not be read: "
               + ", ".join(f"`{n}` ({e})" for n, e in bad[:10]), ""]
    md.append("| method | " + " | ".join(cases) + " |")
    md.append("|---|" + "---|" * len(cases))
    for m in methods:
        md.append(f"| {m} | " + " | ".join(cell_text(agg.get((m, c))) for c in cases) + " |")
    md.append("")
    md_path = os.path.join(out_dir, "stability_matrix.md")
    with open(md_path + ".tmp", "w") as f:
        f.write("\n".join(md))
    os.replace(md_path + ".tmp", md_path)
    return csv_path, md_path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", help="a suite's result folder (with runs/*.json)")
    ap.add_argument("--out", help="where to write the matrix (default: the result folder)")
    args = ap.parse_args(argv)
    if not os.path.isdir(os.path.join(args.results, "runs")):
        print(f"stability_matrix: {args.results}: no runs/ folder", file=sys.stderr)
        return 2
    runs, bad = load_runs(args.results)
    csv_path, md_path = write_outputs(runs, bad, args.out or args.results)
    print(f"stability_matrix: {len(runs)} job(s)"
          + (f", {len(bad)} unreadable" if bad else "") + f" -> {csv_path}, {md_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
