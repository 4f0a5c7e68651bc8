#!/usr/bin/env python3
"""How long a suite is expected to take, said before it runs (`make bench` prints it first).

    tools/suite_estimate.py suites/NAME.yml --out results/NAME [--bvhbench build/bvhbench]
                            [--resume] [--reference DIR ...]

The jobs are the runner's own (`bvhbench suite --list`). Each job's time comes, in this order:
  1. from the previous run of the same suite: OUT/runs/<job id>.json's elapsed_seconds (with
     --resume a job already written costs nothing: the runner skips it);
  2. from the most similar result of the reference result sets (every results/*/ on this
     machine, then the committed results/baseline/ and the report tests' fixture): the same
     method, query and batch mode, the same configuration and query kind when there is one, the
     nearest model size. Its time is split into the build (scaled with the triangle count), the
     timed passes (queries / rate x repetitions, scaled with the query count) and the rest
     (process start, mesh loading, the accuracy check; scaled with the square root of the
     triangle count, for the loading);
  3. without any result of the method and query: the median job of the references.
The query sets and the oracle (once per model and query set, cached in OUT/data/) come on top,
from the oracle's rate in the same references. A guess, which the runner's ETA then corrects as
jobs finish; it says what it rests on. Exit 0, or 2 for bad usage.
"""
import argparse
import glob
import json
import math
import os
import statistics
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
DEFAULT_REFERENCES = [os.path.join(ROOT, "results", "baseline"),
                      os.path.join(ROOT, "tests", "fixtures", "results_small")]
# Oracle (bvhbench truth): seconds per query per triangle, when no reference says better. It
# tests queries against a hierarchy, so the cost grows with log(triangles); measured on the
# default suite (2 cores, loaded): a few seconds for 20,000 points on the 1M bunny.
ORACLE_S_PER_QUERY = 2e-5


def fmt_s(s):
    s = int(round(s))
    return f"{s // 60}m{s % 60:02d}s" if s >= 60 else f"{s}s"


def list_jobs(bvhbench, suite, out):
    p = subprocess.run([bvhbench, "suite", suite, "--out", out, "--list"], capture_output=True,
                       text=True)
    if p.returncode != 0:
        raise SystemExit(f"suite_estimate: {bvhbench} suite --list failed: {p.stderr.strip()}")
    return [line.strip() for line in p.stdout.splitlines() if line.strip()]


def method_names(bvhbench):
    p = subprocess.run([bvhbench, "methods", "--json", "--all"], capture_output=True, text=True)
    try:
        data = json.loads(p.stdout)
    except ValueError:
        return []
    items = data.get("methods", data) if isinstance(data, dict) else data
    return sorted({m["name"] for m in items if isinstance(m, dict) and "name" in m},
                  key=len, reverse=True)


def parse_id(job_id, methods):
    """(mesh, kind, n, query, method, params) from a job id (suites/README.md, job ids)."""
    parts = job_id.split("__")
    if len(parts) < 4:
        return None
    mesh, qset, query, spec = parts[0], parts[1], parts[2], "__".join(parts[3:])
    kind, n = qset.split("-")[0], None
    for tok in qset.split("-")[1:]:
        if tok.startswith("n") and tok[1:].isdigit():
            n = int(tok[1:])
    method = next((m for m in methods if spec == m or spec.startswith(m + "_")), spec)
    params = spec[len(method) + 1:]
    return mesh, kind, n, query, method, params


def mesh_triangles(suite_file):
    """{mesh name: triangles} of the suite's mesh files (PLY header, OBJ face lines)."""
    import yaml
    with open(suite_file, encoding="utf-8") as fh:
        cfg = yaml.safe_load(fh) or {}
    base = os.path.dirname(os.path.abspath(suite_file))
    out = {}
    for m in cfg.get("matrices") or []:
        for entry in m.get("meshes") or []:
            path, name = (entry.get("path"), entry.get("name")) if isinstance(entry, dict) else (entry, None)
            if not isinstance(path, str):
                continue
            full = os.path.join(base, path)
            name = name or os.path.splitext(os.path.basename(path))[0]
            if name not in out:
                out[name] = count_triangles(full)
    return out


def count_triangles(path):
    try:
        if path.endswith(".ply"):
            with open(path, "rb") as fh:
                for raw in fh:
                    line = raw.decode("ascii", "replace").strip()
                    if line.startswith("element face"):
                        return int(line.split()[2])
                    if line == "end_header":
                        break
        elif path.endswith(".obj"):
            t = 0
            with open(path, encoding="utf-8", errors="replace") as fh:
                for line in fh:
                    if line.startswith("f "):
                        t += max(1, len(line.split()) - 3)
            return t
    except (OSError, ValueError):
        pass
    return None


def load_results(folder):
    out = []
    for f in glob.glob(os.path.join(folder, "runs", "*.json")):
        try:
            with open(f, encoding="utf-8") as fh:
                r = json.load(fh)
        except (OSError, ValueError):
            continue
        if isinstance(r, dict) and isinstance(r.get("elapsed_seconds"), (int, float)):
            out.append(r)
    return out


def observation(r):
    job = r.get("job") or {}
    q = r.get("queries") or {}
    qps = (q.get("throughput_qps") or {}).get("median")
    n = q.get("n") or (job.get("queries") or {}).get("n")
    reps = job.get("repetitions") or 1
    elapsed = float(r["elapsed_seconds"])
    timed = reps * n / qps if qps and n else 0.0
    build = (r.get("build") or {}).get("seconds") or 0.0
    return {"method": job.get("method"), "params": job.get("params_key") or "",
            "query": job.get("query"), "kind": (job.get("queries") or {}).get("kind"),
            "tri": (job.get("mesh") or {}).get("triangles") or 1, "n": n or 1,
            "timed": timed, "build": min(build, elapsed),
            "rest": max(0.0, elapsed - timed - build), "elapsed": elapsed}


def is_batch(params):
    return "batch=true" in params.replace("_", ",").split(",")


def predict(job, obs):
    """Seconds for one job from the most similar observation; None without one."""
    mesh, kind, n, query, method, params, tri = job
    same = [o for o in obs if o["method"] == method and o["query"] == query
            and is_batch(o["params"].replace(",", "_")) == is_batch(params)]
    if not same:
        return None
    tri = tri or 1

    def score(o):
        # A model of about the same size first (within 2x), then the same configuration and
        # query kind: a build scaled up from a small model is the worst part of a guess.
        apart = abs(math.log(tri / max(o["tri"], 1)))
        return (apart > math.log(2), o["params"].replace(",", "_") != params, o["kind"] != kind,
                apart)
    o = min(same, key=score)
    t = tri / max(o["tri"], 1)
    # A query's cost grows with the depth of a hierarchy: about log(triangles).
    per_query = 1.0 + max(0.0, math.log2(t)) / 4
    timed = o["timed"] * (n or o["n"]) / o["n"] * per_query
    return o["build"] * t + timed + o["rest"] * math.sqrt(t)


def main(argv=None):
    ap = argparse.ArgumentParser(description="A suite's expected time, from earlier results.")
    ap.add_argument("suite")
    ap.add_argument("--out", required=True, help="the suite's result folder")
    ap.add_argument("--bvhbench", default=os.path.join(ROOT, "build", "bvhbench"))
    ap.add_argument("--resume", action="store_true", help="jobs already written cost nothing")
    ap.add_argument("--reference", action="append", default=None,
                    help="a result folder to learn from (repeatable; default: results/*/, "
                         "results/baseline/, the report tests' fixture)")
    args = ap.parse_args(argv)
    if not os.path.isfile(args.suite):
        print(f"suite_estimate: {args.suite}: no such suite file", file=sys.stderr)
        return 2
    ids = list_jobs(args.bvhbench, args.suite, args.out)
    methods = method_names(args.bvhbench)
    tris = mesh_triangles(args.suite)
    previous = {}
    for r in load_results(args.out):
        previous[(r.get("job") or {}).get("id")] = r
    refs = args.reference
    if refs is None:
        refs = [d for d in sorted(glob.glob(os.path.join(ROOT, "results", "*")))
                if os.path.abspath(d) != os.path.abspath(args.out)] + DEFAULT_REFERENCES
    obs = [observation(r) for d in refs for r in load_results(d)]
    obs += [observation(r) for r in previous.values()]
    # A model not made yet (or moved): its size as the results that ran on it recorded it.
    for r in list(previous.values()) + [r for d in refs for r in load_results(d)]:
        mesh = (r.get("job") or {}).get("mesh") or {}
        if tris.get(mesh.get("name")) is None and mesh.get("triangles"):
            tris[mesh["name"]] = mesh["triangles"]
    fallback = statistics.median([o["elapsed"] for o in obs]) if obs else 1.0

    total, skipped, how = 0.0, 0, {"previous run": 0, "similar result": 0, "guessed": 0}
    qsets = {}
    for jid in ids:
        if args.resume and (os.path.exists(os.path.join(args.out, "runs", jid + ".json"))
                            or os.path.exists(os.path.join(args.out, "runs", jid + ".json.child"))):
            skipped += 1
            continue
        parsed = parse_id(jid, methods)
        if parsed is None:
            total += fallback
            how["guessed"] += 1
            continue
        mesh, kind, n, query, method, params = parsed
        qsets[(mesh, jid.split("__")[1])] = (tris.get(mesh), n)
        if jid in previous:
            total += float(previous[jid]["elapsed_seconds"])
            how["previous run"] += 1
            continue
        est = predict((mesh, kind, n, query, method, params, tris.get(mesh)), obs)
        if est is None:
            total += fallback
            how["guessed"] += 1
        else:
            total += est
            how["similar result"] += 1
    # Query sets and oracles not cached yet in OUT/data (the runner makes them once each).
    oracle = 0.0
    for (mesh, qset), (tri, n) in qsets.items():
        if not glob.glob(os.path.join(args.out, "data", "queries", f"{mesh}__{qset}*")):
            oracle += 0.5 + ORACLE_S_PER_QUERY * (n or 1000) * max(1.0, math.log10(tri or 10))
    to_run = len(ids) - skipped
    rest = ", ".join(f"{v} from {k}" for k, v in how.items() if v)
    print(f"suite {os.path.splitext(os.path.basename(args.suite))[0]}: {to_run} job(s) to run"
          + (f" ({skipped} already done)" if skipped else "")
          + f"; expected ~{fmt_s(total + oracle)} (jobs {fmt_s(total)}: {rest or 'none'}; "
          f"query sets and oracles {fmt_s(oracle)}). The ETA after each job corrects it.",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
