#!/usr/bin/env python3
"""Instructions per query of a haptic distance run, split by the steps of the search.

Reads what tools/investigations/haptic_distance_callgrind.sh writes (OUTDIR/NAME__METHOD.tree.txt, the output
of `callgrind_annotate --inclusive=yes --tree=caller`, and the run's result JSON beside it) and
prints one Markdown row per run: inclusive instructions per call of the adapter's distance method
and of the steps below it, with the run's work counters per query.

    python3 tools/investigations/callgrind_split.py OUTDIR [--noinline OUTDIR_NOINLINE] [--inside INSIDE_DIR]

OUTDIR holds the runs of the project's binary. OUTDIR_NOINLINE, if given, holds runs of a binary
whose only change is `__attribute__((noinline))` on the DistanceSearch steps (see methods/ebp_octree/HISTORY.md,
"Haptic distance: where the time goes"): there every step is a function of its own, so the leaf
scan splits into block bounds (order_blocks), triangle pre-tests (triangle_pruned) and exact
tests (test_triangle). INSIDE_DIR holds `bvhbench run --query inside` results of the same
methods on the same query sets (INSIDE_DIR/NAME__METHOD.json): a distance query's counters
include those of its sign (`Query::distance` calls `inside`, which counts its own nodes, planes
and crossing tests into the same counters), so they are subtracted to give the distance search's
own. Standard library only.
"""
from __future__ import annotations

import glob
import json
import os
import re
import sys

LINE = re.compile(r"^\s*([\d,]+)\s+\([\s\d.]+%\)\s+([<>*])\s+(?:\S*?:)?(.*?)(?:\s+\((\d[\d,]*)x\))?\s+\[[^\]]*\]\s*$")


def short(fn: str) -> str:
    fn = fn.replace("bvhbench::(anonymous namespace)::", "").replace("ebp::Query::DistanceSearch::", "DS::")
    fn = fn.replace("ebp::Query::", "Query::")
    return fn.split("(")[0]


def parse_tree(path: str) -> dict:
    """function -> {"incl": Ir, "callers": {caller: (Ir, calls)}}"""
    funcs: dict = {}
    pending = []
    for line in open(path, errors="replace"):
        m = LINE.match(line)
        if not m:
            pending = []
            continue
        ir = int(m.group(1).replace(",", ""))
        kind, fn = m.group(2), short(m.group(3))
        calls = int(m.group(4).replace(",", "")) if m.group(4) else 0
        if kind == "<":
            pending.append((fn, ir, calls))
        elif kind == "*":
            f = funcs.setdefault(fn, {"incl": 0, "callers": {}})
            f["incl"] = max(f["incl"], ir)
            for c, cir, cc in pending:
                f["callers"][c] = (cir, cc)
            pending = []
    return funcs


def incl(funcs, fn):
    return funcs.get(fn, {"incl": 0})["incl"]


def from_caller(funcs, fn, caller):
    return funcs.get(fn, {"callers": {}})["callers"].get(caller, (0, 0))


def main(argv) -> int:
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--noinline", default=None)
    ap.add_argument("--inside", default=None)
    a = ap.parse_args(argv)
    dirs = [a.outdir] + ([a.noinline] if a.noinline else [])
    rows = []
    for d in dirs:
        noinline = d is not dirs[0]
        for tree in sorted(glob.glob(os.path.join(d, "*.tree.txt"))):
            tag = os.path.basename(tree)[: -len(".tree.txt")]
            name, method = tag.split("__", 1)
            res = json.load(open(os.path.join(d, tag + ".json")))
            n = 3 * int(res["queries"]["n"])  # warm-up, one timed pass, the latency pass
            c = dict(res.get("counters", {}))
            ins = os.path.join(a.inside, tag + ".json") if a.inside else None
            if method.startswith("ebp") and ins and os.path.exists(ins):
                ci = json.load(open(ins))["counters"]
                for k in ("nodes_visited", "planes_tested", "triangles_tested"):
                    c[k] = float(c.get(k, 0)) - float(ci.get(k, 0))
                c["inside_subtracted"] = 1
            F = parse_tree(tree)
            pq = lambda x: x / n  # noqa: E731
            r = {"mesh": name, "method": method, "binary": "noinline" if noinline else "project", "counters": c}
            if method.startswith("ebp"):
                tot = incl(F, "EbpOctreeMethod::distance")
                r["adapter"] = pq(tot)
                r["inside"] = pq(incl(F, "Query::inside"))
                r["search"] = pq(incl(F, "Query::distance_bound"))
                r["descend"] = pq(incl(F, "DS::descend"))
                r["node_bound"] = pq(incl(F, "DS::node_bound"))
                r["scan_leaf"] = pq(incl(F, "DS::scan_leaf"))
                r["test_triangle"] = pq(incl(F, "DS::test_triangle"))
                r["test_triangle_calls"] = sum(v[1] for v in F.get("DS::test_triangle", {"callers": {}})["callers"].values()) / n
                if noinline:
                    r["coherent_start"] = pq(incl(F, "DS::coherent_start"))
                    r["narrowed_start"] = pq(incl(F, "DS::narrowed_start"))
                    r["order_blocks"] = pq(incl(F, "DS::order_blocks"))
                    r["triangle_pruned"] = pq(incl(F, "DS::triangle_pruned"))
                    r["leaf_hint"] = pq(incl(F, "DS::leaf_hint"))
                    r["scan_leaf_in_descent"] = pq(from_caller(F, "DS::scan_leaf", "DS::descend")[0])
                    r["triangle_pruned_calls"] = from_caller(F, "DS::triangle_pruned", "DS::scan_leaf")[1] / n
                else:
                    # coherent_start is inlined into distance_bound: its scan_leaf and seed test
                    r["coherent_start"] = pq(from_caller(F, "DS::scan_leaf", "Query::distance_bound")[0] +
                                             from_caller(F, "DS::test_triangle", "Query::distance_bound")[0])
                    r["scan_leaf_in_descent"] = pq(from_caller(F, "DS::scan_leaf", "DS::descend")[0])
                tt = float(c.get("triangles_tested", 0))
                r["instr_per_exact_test"] = r["test_triangle"] / tt if tt else 0.0
            else:
                r["adapter"] = pq(incl(F, "Embree::distance"))
                r["point_query"] = pq(max(incl(F, "rtcPointQuery"), incl(F, "embree::rtcPointQuery")))
                r["inside"] = pq(incl(F, "rtcIntersect1"))  # the ray parity (inside_impl is inlined)
            rows.append(r)
    print("| mesh | method | binary | adapter distance | inside (sign) | search | coherent start | descent "
          "(node bounds, leaf scans in it) | leaf scans all (block bounds, triangle pre-tests, exact tests) | "
          "nodes / planes / exact tris per query | instr per exact test |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        c = r["counters"]
        if r["method"].startswith("ebp"):
            inner = f"{r['scan_leaf']:,.0f}"
            if r["binary"] == "noinline":
                inner += (f" ({r['order_blocks']:,.0f}, {r['triangle_pruned']:,.0f}, {r['test_triangle']:,.0f}; "
                          f"leaf hints {r['leaf_hint']:,.0f}, narrowed start {r['narrowed_start']:,.0f})")
            else:
                inner += f" (-, -, {r['test_triangle']:,.0f})"
            print(f"| {r['mesh']} | {r['method']} | {r['binary']} | {r['adapter']:,.0f} | {r['inside']:,.0f} | "
                  f"{r['search']:,.0f} | {r['coherent_start']:,.0f} | {r['descend']:,.0f} ({r['node_bound']:,.0f}, "
                  f"{r['scan_leaf_in_descent']:,.0f}) | {inner} | {float(c.get('nodes_visited', 0)):.2f} / "
                  f"{float(c.get('planes_tested', 0)):.1f} / {float(c.get('triangles_tested', 0)):.2f} | "
                  f"{r['instr_per_exact_test']:.0f} |")
        else:
            print(f"| {r['mesh']} | {r['method']} | {r['binary']} | {r['adapter']:,.0f} | {r['inside']:,.0f} | "
                  f"{r['point_query']:,.0f} (rtcPointQuery) | | | | - / - / {float(c.get('triangles_tested', 0)):.2f} | |")
    with open(os.path.join(dirs[0], "split.json"), "w") as f:
        json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
