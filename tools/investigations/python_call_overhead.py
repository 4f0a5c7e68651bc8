#!/usr/bin/env python3
"""The cost of calling a method written in Python, per query and per batch call.

    .venv/bin/python tools/investigations/python_call_overhead.py [--exe build/bvhbench] [--mesh M] [--n 100000]

Makes a *null* Python method in a temporary folder (its answers are constants, so what is timed
is the host: taking the GIL, building the arguments, the interpreter's call, checking and
converting the answer) and runs it through `bvhbench run` beside the C++ null method
(`fault:mode=none`, the harness's own per-query cost), one point at a time (inside_one /
distance_one, and inside(P) / distance(P) of one row when a module has no *_one) and in batches
(batch=true, the whole set per call). Prints a Markdown table of per-query nanoseconds: latency
p50 and mean of the timestamped pass, and the median pass time over n. Wall-clock figures: run it
on a quiet machine, or read them as ratios to the C++ null method of the same run.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

NULL = '''
import numpy as np
DESCRIPTION = "null: constant answers, to time the host"
REQUIRES = ["numpy"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = []
ONE = (1.0, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0)

class Method:
    def build(self, V, F):
        pass
    def inside(self, P):
        return np.zeros(len(P), dtype=bool)
    def distance(self, P):
        n = len(P)
        return np.ones(n), np.zeros((n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1)), np.zeros(n, dtype=np.int64)
    def structure_bytes(self):
        return 1
'''
ONE = '''
    def inside_one(self, p):
        return False
    def distance_one(self, p):
        return ONE
'''


def run(exe, env, mesh, queries, method, query, out):
    subprocess.run([str(exe), "--quiet", "run", "--mesh", str(mesh), "--method", method, "--queries",
                    str(queries), "--query", query, "--repeat", "5", "--out", str(out)],
                   env=env, check=True)
    r = json.loads(out.read_text())
    q = r["queries"]
    n = q["n"]
    per_pass = sorted(q["pass_seconds"])[len(q["pass_seconds"]) // 2] / n * 1e9
    lat = q["latency_ns"]
    return per_pass, lat["p50"], lat["mean"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exe", default=str(ROOT / "build" / "bvhbench"))
    ap.add_argument("--mesh", default=str(ROOT.parent / "shared" / "meshes" / "cow.obj"))
    ap.add_argument("--n", type=int, default=100000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, body in (("null_one", NULL + ONE), ("null_rows", NULL)):
            (tmp / name).mkdir()
            (tmp / name / "method.py").write_text(body)
        env = dict(os.environ, BVHBENCH_PYTHON_METHODS=f"{tmp / 'null_one'}:{tmp / 'null_rows'}")
        queries = tmp / "q.npy"
        subprocess.run([args.exe, "--quiet", "queries", "--mesh", args.mesh, "--kind", "random", "--n",
                        str(args.n), "--seed", "1", "--out", str(queries)], check=True)
        rows = []
        for method, what in (("fault:mode=none", "C++ null method (the harness's own cost)"),
                             ("null_one", "Python, one point per call (inside_one / distance_one)"),
                             ("null_rows", "Python, one point per call (inside / distance of one row)"),
                             ("null_one:batch=true", "Python, batch: the whole set per call")):
            for query in ("inside", "distance"):
                per_pass, p50, mean = run(args.exe, env, args.mesh, queries, method, query, tmp / "r.json")
                rows.append((what, query, per_pass, p50, mean))
        print(f"n = {args.n} random points on {args.mesh}; ns per query\n")
        print("| caller | query | pass time / n | latency p50 | latency mean |")
        print("|---|---|---|---|---|")
        fmt = lambda v: "–" if v is None else f"{v:,.0f}"
        for what, query, per_pass, p50, mean in rows:
            print(f"| {what} | {query} | {fmt(per_pass)} | {fmt(p50)} | {fmt(mean)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
