#!/usr/bin/env python3
"""The instruction gate: instructions per query, counted under valgrind, gated against a baseline.

A shared CI machine cannot time a query loop to 10 % (one `make test` of unchanged code showed
jobs 13-27 % "slower"), so timings there are reported, never gated. The instructions a query loop
executes are another matter: for a given binary, input and (valgrind-emulated) processor, callgrind
counts the same number on every run. This tool counts them for the jobs of
suites/ci_instructions.yml, each in its timed pass only (harness/run/counted_region.hpp), and
compares them with a baseline made under the same *instruction fingerprint* (compiler and flags,
library versions, the processor and ISA as valgrind presents them, which pick the kernels Embree
runs, valgrind's version; a Python method's interpreter too):

  measure   count the jobs: OUT/instructions.json (and each job's result and callgrind file);
            with --groups the jobs of one build group in one process, built once (a large model's
            jobs would otherwise each build it under valgrind)
  compare   BASE NEW: exit 1 when a job needs >= --fail (10 %) more instructions per query
  gate      measure, then compare with --base (a measured folder) or --base-ref (a commit, built
            in a scratch worktree and measured in the same run); what tools/ci_gate.sh runs
  one       print one job's instructions per query (what tools/instr_bisect.py measures)

Exit: 0 nothing gating changed; 1 a job got slower by >= --fail, is missing or failed;
2 a broken run (no valgrind, no binary, a job that did not run, a bad file).
docs/compare.md says how to wire it into CI.
"""
import concurrent.futures
import datetime
import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tool_cli import tool_parser  # noqa: E402  (beside this file)

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_EXE = os.environ.get("BVHBENCH_EXE", str(ROOT / "build" / "bvhbench"))
SCHEMA = "bvhbench.instructions/1"
FAIL_DEFAULT = 0.10
WARN_DEFAULT = 0.03


class BrokenRun(Exception):
    """A run that could not measure (exit 2): not a regression."""


# ---- the job list -------------------------------------------------------------------------------

def load_jobs(path, exe):
    """The jobs of a job list (suites/ci_instructions.yml) as the runner `exe` expands it
    (`bvhbench suite FILE --list --json`; nothing else reads the suite grammar): dicts with id,
    mesh (path), queries (kind, label, and generator_args or a points file), query, method (spec)
    and threads."""
    cmd = [str(exe), "suite", str(path), "--list", "--json"]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise BrokenRun(f"cannot run {exe} to expand {path}: {e} (build it, or pass --exe / --list-exe)")
    if p.returncode != 0:
        raise BrokenRun(f"{path}: the runner refused the job list (exit {p.returncode}): {p.stderr.strip()}")
    try:
        listed = json.loads(p.stdout)["jobs"]
    except (ValueError, KeyError) as e:
        raise BrokenRun(f"{' '.join(cmd)}: not a job listing ({e}): is {exe} older than `suite --list --json`?")
    return [{"id": j["id"], "mesh": str(Path(j["mesh"]["path"]).resolve()), "queries": j["queries"], "query": j["query"],
             "method": j["method"]["spec"], "threads": j["threads"], "build_group": j.get("build_group") or j["id"]}
            for j in listed]


# ---- measuring ----------------------------------------------------------------------------------

def valgrind_version():
    if shutil.which("valgrind") is None:
        raise BrokenRun("valgrind is not installed (Debian: apt-get install valgrind): the instruction gate cannot count")
    return subprocess.run(["valgrind", "--version"], capture_output=True, text=True).stdout.strip()


def _callgrind_parts(path):
    """(label, total) of every file callgrind wrote for one run: OUT and its parts OUT.1, OUT.2,
    ... (one per job of a group of several, harness/run/counted_region.hpp: end_counted_job). The
    label is the dump's trigger ("bvhbench job K", or "Program termination"); the total its
    `totals:` line (`summary:` in older files)."""
    path = Path(path)
    files = [path] + sorted(path.parent.glob(path.name + ".*"), key=lambda p: p.suffix)
    out = []
    for f in files:
        if not f.suffix.lstrip(".").isdigit() and f != path:
            continue
        label, total = "", None
        for line in f.read_text(errors="replace").splitlines():
            if line.startswith("desc: Trigger:"):
                label = line.split(":", 2)[2].strip().removeprefix("Client Request:").strip()
            elif line.startswith("totals:") or (total is None and line.startswith("summary:")):
                total = int(line.split()[1])
        out.append((label, total or 0))
    return out


def callgrind_total(path):
    """The instructions callgrind collected in one run, over all of its parts."""
    return sum(total for _, total in _callgrind_parts(path))


def callgrind_job_totals(path):
    """{K: instructions} of a group's run: job K's part ("bvhbench job K")."""
    out = {}
    for label, total in _callgrind_parts(path):
        if label.startswith("bvhbench job "):
            k = int(label.rsplit(" ", 1)[1])
            out[k] = out.get(k, 0) + total
    return out


def _queries_file(exe, job, data_dir):
    q = job["queries"]
    if "file" in q:  # a points file, replayed as it is
        return Path(q["file"])
    out = data_dir / f"{Path(job['mesh']).stem}__{q['label']}.npy"
    if not out.exists():
        data_dir.mkdir(parents=True, exist_ok=True)
        args = [str(exe), "queries", "--mesh", job["mesh"], *q["generator_args"], "--out", str(out)]
        p = subprocess.run(args, capture_output=True, text=True)
        if p.returncode != 0:
            raise BrokenRun(f"{job['id']}: could not make its query set: {' '.join(args)}\n{p.stderr}")
    return out


def _job_env():
    env = dict(os.environ)
    env["PYTHONHASHSEED"] = "0"  # an embedded interpreter's dict and set orders, hence its work, fixed
    env.setdefault("OMP_NUM_THREADS", "1")
    return env


def _remove_callgrind_files(cg):
    """A run's callgrind file and its parts, so that nothing of an earlier run is counted."""
    for f in [cg, *cg.parent.glob(cg.name + ".*")]:
        f.unlink(missing_ok=True)


def _job_paths(job, out_dir):
    """(result, log) of a job under OUT."""
    res = out_dir / "runs" / f"{job['id']}.json"
    log = out_dir / "logs" / f"{job['id']}.log"
    for d in (res.parent, log.parent):
        d.mkdir(parents=True, exist_ok=True)
    return res, log


def measure_job(exe, job, out_dir, toggle_fallback=True):
    """Counts one job's timed pass under callgrind: a record for instructions.json."""
    out_dir = Path(out_dir)
    qfile = _queries_file(exe, job, out_dir / "data" / "queries")
    cg = out_dir / "callgrind" / f"{job['id']}.cg"
    cg.parent.mkdir(parents=True, exist_ok=True)
    res, log = _job_paths(job, out_dir)
    run = [str(exe), "run", "--mesh", job["mesh"], "--method", job["method"], "--queries", str(qfile),
           "--query", job["query"], "--repeat", "1", "--threads", str(job.get("threads", 1)), "--quiet", "--out", str(res)]
    # The timed pass switches instrumentation and collection on itself (counted_region.hpp); a
    # binary made before it had the region is counted by the name of its timed pass instead.
    modes = [("region", ["--instr-atstart=no", "--collect-atstart=no"])]
    if toggle_fallback:
        modes.append(("toggle", ["--collect-atstart=no", "--toggle-collect=bvhbench::ThreadedReplay::timed_pass()"]))
    for mode, opts in modes:
        _remove_callgrind_files(cg)
        vg = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", *opts, *run]
        with open(log, "w") as lf:
            p = subprocess.run(vg, stdout=subprocess.DEVNULL, stderr=lf, env=_job_env())
        if p.returncode != 0 or not res.exists():
            raise BrokenRun(f"{job['id']}: the job did not run under valgrind (exit {p.returncode}); see {log}")
        total = callgrind_total(cg)
        if total > 0:
            break
    else:
        raise BrokenRun(f"{job['id']}: callgrind collected nothing: was {exe} built without valgrind/callgrind.h "
                        "(harness/run/counted_region.hpp)?")
    return _record(job, json.loads(res.read_text()), total, mode)


def measure_group(exe, jobs, out_dir):
    """Counts the timed passes of jobs that share one build (the same `build_group` in the runner's
    listing) in one process under callgrind (`bvhbench run-group`), each job's from its own part
    file: records for instructions.json, one per job. A 32M model's structure is then built once
    under valgrind for all of its jobs, not once a job."""
    out_dir = Path(out_dir)
    group = jobs[0]["build_group"]
    cg = out_dir / "callgrind" / f"{group}.cg"
    plan_file = out_dir / "logs" / f"{group}.plan.json"
    plan_file.parent.mkdir(parents=True, exist_ok=True)
    cg.parent.mkdir(parents=True, exist_ok=True)
    planned = []
    for j in jobs:
        res, log = _job_paths(j, out_dir)
        res.unlink(missing_ok=True)
        planned.append({"mesh": j["mesh"], "method": j["method"],
                        "queries": str(_queries_file(exe, j, out_dir / "data" / "queries")), "query": j["query"],
                        "repeat": 1, "threads": j.get("threads", 1), "truth": "", "out": str(res), "log": str(log)})
    plan_file.write_text(json.dumps({"build_id": group, "built": "", "jobs": planned}, indent=1) + "\n")
    _remove_callgrind_files(cg)
    vg = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", "--instr-atstart=no", "--collect-atstart=no",
          str(exe), "--quiet", "run-group", "--plan", str(plan_file)]
    group_log = out_dir / "logs" / f"{group}.valgrind.log"
    with open(group_log, "w") as lf:
        p = subprocess.run(vg, stdout=subprocess.DEVNULL, stderr=lf, env=_job_env())
    # A group of several jobs dumps a part per job; a lone job's counts are the run's.
    totals = callgrind_job_totals(cg) if len(jobs) > 1 else {0: callgrind_total(cg)}
    records = []
    for k, j in enumerate(jobs):
        res = Path(planned[k]["out"])
        if p.returncode != 0 or not res.exists():
            raise BrokenRun(f"{j['id']}: the group {group} did not run under valgrind (exit {p.returncode}); "
                            f"see {group_log} and {planned[k]['log']}")
        r = json.loads(res.read_text())
        if r.get("status") == "ok" and not totals.get(k):
            raise BrokenRun(f"{j['id']}: callgrind counted nothing for it (part \"bvhbench job {k}\" of a group): was "
                            f"{exe} built without valgrind/callgrind.h, or before end_counted_job "
                            "(harness/run/counted_region.hpp)?")
        records.append(_record(j, r, totals.get(k, 0), "group"))
    return records


def _record(job, r, total, mode):
    """The record of instructions.json for a job's result `r` and the instructions it counted."""
    if r.get("status") != "ok":
        return {"id": job["id"], "status": r.get("status"), "message": r.get("message", "")}
    n = int(r["queries"]["n"]) * int(r["job"]["repetitions"])
    fp = (r.get("machine_dependent") or {}).get("fingerprint") or {}
    rec = {
        "id": job["id"],
        "status": "ok",
        "method": r["job"]["method"],
        "method_spec": job["method"],
        "params": r["job"].get("params", {}),
        "query": job["query"],
        "mesh_sha256": r["job"]["mesh"]["sha256"],
        "queries_sha256": r["job"]["queries"]["sha256"],
        "queries": n,
        "instructions": total,
        "instructions_per_query": total / n if n else None,
        "counted_by": mode,
        "counters": r.get("counters", {}),
        "method_facts": fp.get("method", {}),
        "run_fingerprint": {
            "compiler": r["context"].get("compiler"),
            "cxx_flags": (r["context"].get("cxx_flags") or "").strip(),
            "build_type": r["context"].get("build_type"),
            "libraries": r["context"].get("libraries", {}),
            "cpu": fp.get("cpu", {}),
            "isa": fp.get("isa", {}),
        },
        "commit": r["context"].get("git_commit"),
        "dirty": r["context"].get("git_dirty"),
    }
    slowed = (r.get("structure") or {}).get("TEST_SLOWDOWN")
    if slowed:
        rec["TEST_SLOWDOWN"] = slowed
    return rec


def run_fingerprint(records, vg_version):
    """The fingerprint every job of a measurement shares, and its short key (history folder name)."""
    ok = [r["run_fingerprint"] for r in records if r.get("status") == "ok"]
    # A Python method's job adds the interpreter's and its packages' versions to the libraries: the
    # fingerprint holds every job's (one run has one version of each).
    libraries = {}
    for f in ok:
        libraries.update(f.get("libraries") or {})
    fps = {json.dumps(dict(f, libraries=None), sort_keys=True) for f in ok}
    if len(fps) > 1:
        raise BrokenRun("the jobs of one measurement report different builds or processors")
    fp = json.loads(fps.pop()) if fps else {}
    fp["libraries"] = libraries
    fp["valgrind"] = vg_version
    key = hashlib.sha256(json.dumps(fp, sort_keys=True).encode()).hexdigest()[:12]
    return fp, key


def measure(exe, jobs, out_dir, parallel=2, progress=True, groups=False):
    exe = Path(exe).resolve()
    if not os.access(exe, os.X_OK):
        raise BrokenRun(f"no bvhbench binary at {exe} (build it, or pass --exe)")
    vg = valgrind_version()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    for j in jobs:  # made once, before the parallel runs share them
        _queries_file(exe, j, out_dir / "data" / "queries")
    # Each task a list of jobs: one job, or with `groups` the jobs of one build group (largest
    # mesh first, so that the longest build does not start last).
    if groups:
        by_group = {}
        for j in jobs:
            by_group.setdefault(j["build_group"], []).append(j)
        tasks = sorted(by_group.values(), key=lambda js: -Path(js[0]["mesh"]).stat().st_size)
        run_task = lambda js: measure_group(exe, js, out_dir)  # noqa: E731
    else:
        tasks = [[j] for j in jobs]
        run_task = lambda js: [measure_job(exe, js[0], out_dir)]  # noqa: E731
    records = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, parallel)) as pool:
        futs = [pool.submit(run_task, t) for t in tasks]
        for f in concurrent.futures.as_completed(futs):
            for rec in f.result():
                records.append(rec)
                if progress:
                    ipq = rec.get("instructions_per_query")
                    print(f"instr_gate: {rec['id']}: " + (f"{ipq:,.0f} instructions/query" if ipq else rec.get("status", "?")),
                          file=sys.stderr)
    records.sort(key=lambda r: r["id"])
    fp, key = run_fingerprint(records, vg)
    slowed = sorted({json.dumps(r["TEST_SLOWDOWN"]) for r in records if "TEST_SLOWDOWN" in r})
    doc = {"schema": SCHEMA, "fingerprint": fp, "fingerprint_key": key,
           "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
           "commit": next((r.get("commit") for r in records if r.get("commit")), None),
           "dirty": any(r.get("dirty") for r in records),
           "jobs": records}
    if slowed:
        doc["TEST_SLOWDOWN"] = [json.loads(s) for s in slowed]
        print("instr_gate: WARNING: BVHBENCH_TEST_SLOWDOWN is set: these counts include test-only extra work",
              file=sys.stderr)
    (out_dir / "instructions.json").write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    return doc


# ---- comparing ----------------------------------------------------------------------------------

def load_measurement(path):
    p = Path(path)
    if p.is_dir():
        p = p / "instructions.json"
    try:
        doc = json.loads(p.read_text())
    except (OSError, ValueError) as e:
        raise BrokenRun(f"{p}: cannot read: {e} (no baseline? `make rebaseline` counts one; or gate with --base-ref)")
    if doc.get("schema") != SCHEMA:
        raise BrokenRun(f"{p}: not an instruction measurement (schema {doc.get('schema')!r}, expected {SCHEMA})")
    return doc


def fingerprint_differences(a, b, prefix=""):
    out = []
    for k in sorted(set(a) | set(b)):
        va, vb = a.get(k), b.get(k)
        if isinstance(va, dict) and isinstance(vb, dict):
            out += fingerprint_differences(va, vb, f"{prefix}{k}.")
        elif va != vb:
            out.append(f"{prefix}{k} {va} -> {vb}")
    return out


def compare(base, new, fail=FAIL_DEFAULT, warn=WARN_DEFAULT, only=None):
    """Rows (one per job) and a summary; `gated` is False when the fingerprints differ. With
    `only` (job ids), the baseline's other jobs are left out rather than counted missing."""
    diffs = fingerprint_differences(base["fingerprint"], new["fingerprint"])
    gated = not diffs
    bjobs = {j["id"]: j for j in base["jobs"] if only is None or j["id"] in only}
    njobs = {j["id"]: j for j in new["jobs"]}
    rows = []
    for jid in sorted(set(bjobs) | set(njobs)):
        b, n = bjobs.get(jid), njobs.get(jid)
        row = {"id": jid}
        if n is None:
            row.update(verdict="missing", gates=gated)
        elif b is None:
            row.update(verdict="new", gates=False, new=n.get("instructions_per_query"))
        elif n.get("status") != "ok" or b.get("status") != "ok":
            row.update(verdict="failed" if b.get("status") == "ok" else "not_measured",
                       gates=gated and b.get("status") == "ok", message=n.get("message", ""))
        elif (b["mesh_sha256"], b["queries_sha256"], b["params"]) != (n["mesh_sha256"], n["queries_sha256"], n["params"]):
            row.update(verdict="inputs_changed", gates=gated,
                       message="the mesh, query set or parameters differ from the baseline's: remake it")
        else:
            bi, ni = b["instructions_per_query"], n["instructions_per_query"]
            change = ni / bi - 1.0 if bi else float("inf")
            row.update(base=bi, new=ni, change=change)
            job_gated = gated and b.get("method_facts") == n.get("method_facts")
            if change >= fail:
                row.update(verdict="slower", gates=job_gated)
            elif change >= warn:
                row.update(verdict="warn", gates=False)
            elif change <= -warn:
                row.update(verdict="faster", gates=False)
            else:
                row.update(verdict="same", gates=False)
            if gated and not job_gated:
                row["message"] = "the method's library chose otherwise (method facts differ): reported, not gated"
            if n.get("counters") != b.get("counters"):
                row["counters_changed"] = True
        rows.append(row)
    failing = [r for r in rows if r["gates"]]
    return {"gated": gated, "fingerprint_differences": diffs, "rows": rows,
            "failing": [r["id"] for r in failing], "fail": fail, "warn": warn,
            "base_commit": base.get("commit"), "new_commit": new.get("commit"),
            "fingerprint_key": new.get("fingerprint_key"),
            "test_slowdown": new.get("TEST_SLOWDOWN")}


def markdown(cmp):
    L = [f"## Instructions per query (callgrind, timed pass only): base {str(cmp['base_commit'])[:10]} -> "
         f"new {str(cmp['new_commit'])[:10]}", ""]
    if cmp.get("test_slowdown"):
        L += [f"**TEST KNOB SET in the new run: BVHBENCH_TEST_SLOWDOWN {cmp['test_slowdown']}**", ""]
    L += ["| job | base | new | change | verdict |", "|---|---:|---:|---:|---|"]
    for r in cmp["rows"]:
        fmt = lambda v: f"{v:,.0f}" if isinstance(v, (int, float)) else ""
        ch = f"{r['change']:+.2%}" if "change" in r else ""
        verdict = r["verdict"] + (" **GATES**" if r["gates"] else "") + (" (counters changed too)" if r.get("counters_changed") else "")
        if r.get("message"):
            verdict += f": {r['message']}"
        L.append(f"| {r['id']} | {fmt(r.get('base'))} | {fmt(r.get('new'))} | {ch} | {verdict} |")
    L.append("")
    if not cmp["gated"]:
        L.append("Not gated: the instruction fingerprints differ (" + "; ".join(cmp["fingerprint_differences"]) +
                 "): counts from another compiler, library, processor or valgrind say nothing about this change. "
                 "Gate against a baseline measured here: `tools/instr_gate.py gate --base-ref <merge-base>` "
                 "(docs/compare.md).")
    else:
        L.append(f"Gated: the same fingerprint ({cmp['fingerprint_key']}); a job fails at >= {cmp['fail']:.0%} more "
                 f"instructions per query, is flagged at >= {cmp['warn']:.0%}. The counts are deterministic "
                 "(identical over repeated runs of identical code, docs/compare.md), so a change of that size is "
                 "the code's, not noise; instructions are a proxy for time (cache misses are not in them).")
    return "\n".join(L) + "\n"


# ---- a commit built in a scratch worktree -------------------------------------------------------

def build_commit(ref, work_dir, jobs_n=2):
    """The bvhbench binary of commit `ref`, built in a scratch worktree under work_dir (kept, so that
    the next run at the same commit only rebuilds what changed)."""
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", f"{ref}^{{commit}}"],
                         capture_output=True, text=True)
    if sha.returncode != 0:
        raise BrokenRun(f"--base-ref {ref}: not a commit of {ROOT}")
    sha = sha.stdout.strip()
    wt = Path(work_dir) / "src"
    if not (wt / ".git").exists():
        Path(work_dir).mkdir(parents=True, exist_ok=True)
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt), sha], check=True,
                       capture_output=True)
    else:
        subprocess.run(["git", "-C", str(wt), "checkout", "--detach", "--force", sha], check=True, capture_output=True)
    # The build inside the checkout, as in a developer's tree: compiler lines then read the same
    # relative to CCACHE_BASEDIR, and ccache serves the files the commit did not change.
    build = wt / "build"
    cfg = ["cmake", "-S", str(wt), "-B", str(build), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release"]
    if shutil.which("ccache"):
        cfg.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
    for cmd in (cfg, ["cmake", "--build", str(build), "-j", str(jobs_n), "--target", "bvhbench"]):
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            raise BrokenRun(f"building {ref} ({sha[:10]}) failed: {' '.join(cmd)}\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}")
    return build / "bvhbench"


# ---- history ------------------------------------------------------------------------------------

def append_history(doc, history_root):
    """One line per job in HISTORY/<fingerprint key>/instructions.jsonl (fingerprint.json beside it)."""
    d = Path(history_root) / doc["fingerprint_key"]
    d.mkdir(parents=True, exist_ok=True)
    (d / "fingerprint.json").write_text(json.dumps(doc["fingerprint"], indent=1, sort_keys=True) + "\n")
    with open(d / "instructions.jsonl", "a") as f:
        for j in doc["jobs"]:
            if j.get("status") != "ok":
                continue
            f.write(json.dumps({"commit": doc["commit"], "dirty": doc["dirty"], "date": doc["date"], "job": j["id"],
                                "instructions_per_query": j["instructions_per_query"],
                                "test_slowdown": j.get("TEST_SLOWDOWN")}, sort_keys=True) + "\n")
    return d


# ---- the commands -------------------------------------------------------------------------------

def _jobs_arg(args):
    jobs = load_jobs(args.jobs, args.list_exe or args.exe)
    if args.only:
        wanted = set(args.only)
        unknown = wanted - {j["id"] for j in jobs}
        if unknown:
            raise BrokenRun(f"--only: no such job in {args.jobs}: {', '.join(sorted(unknown))}")
        jobs = [j for j in jobs if j["id"] in wanted]
    return jobs


def cmd_measure(args):
    doc = measure(args.exe, _jobs_arg(args), args.out, args.parallel, groups=args.groups)
    if args.history:
        append_history(doc, args.history)
    return 0


def _report(cmp, out_dir=None):
    md = markdown(cmp)
    print(md)
    if out_dir:
        Path(out_dir, "instructions_compare.md").write_text(md)
        Path(out_dir, "instructions_compare.json").write_text(json.dumps(cmp, indent=1) + "\n")
    if cmp["failing"]:
        for r in cmp["rows"]:
            if r["gates"]:
                fig = f"{r['change']:+.1%} instructions per query ({r['base']:,.0f} -> {r['new']:,.0f})" if "change" in r else r["verdict"]
                print(f"instr_gate: FAILED: {r['id']}: {fig}")
        return 1
    return 0


def cmd_compare(args):
    return _report(compare(load_measurement(args.base), load_measurement(args.new), args.fail, args.warn))


def cmd_gate(args):
    jobs = _jobs_arg(args)
    out = Path(args.out)
    if out.exists():
        shutil.rmtree(out)
    new = measure(args.exe, jobs, out / "new", args.parallel)
    if args.history:
        append_history(new, args.history)
    if args.base_ref:
        exe = build_commit(args.base_ref, Path(args.work), args.parallel)
        base = measure(exe, jobs, out / "base", args.parallel)
    else:
        base = load_measurement(args.base)
        if base["fingerprint"] != new["fingerprint"]:
            print("instr_gate: the baseline was measured under another fingerprint: NOT GATED (see below)", file=sys.stderr)
    return _report(compare(base, new, args.fail, args.warn, set(args.only) if args.only else None), out)


def cmd_one(args):
    jobs = [j for j in load_jobs(args.jobs, args.list_exe) if j["id"] == args.job]
    if not jobs:
        raise BrokenRun(f"no job '{args.job}' in {args.jobs}")
    rec = measure_job(Path(args.exe).resolve(), jobs[0], Path(args.out))
    if rec.get("status") != "ok":
        raise BrokenRun(f"{args.job}: status {rec.get('status')}: {rec.get('message', '')}")
    print(f"{rec['instructions_per_query']:.3f}")
    return 0


def main(argv=None):
    ap = tool_parser(__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)

    def common(p, out_default):
        p.add_argument("--exe", default=DEFAULT_EXE)
        p.add_argument("--jobs", default=str(ROOT / "suites" / "ci_instructions.yml"), help="job list")
        p.add_argument("--list-exe", help="the bvhbench that expands the job list (default: --exe)")
        p.add_argument("--only", action="append", help="only this job id (repeatable)")
        p.add_argument("--out", default=out_default)
        p.add_argument("--parallel", type=int, default=2, help="jobs under valgrind at once")
        p.add_argument("--history", help="append the counts to HISTORY/<fingerprint key>/instructions.jsonl")

    def thresholds(p):
        p.add_argument("--fail", type=float, default=FAIL_DEFAULT, help="fail at this relative growth (0.10)")
        p.add_argument("--warn", type=float, default=WARN_DEFAULT, help="flag at this relative change (0.03)")

    p = sub.add_parser("measure", help="count the jobs into OUT/instructions.json")
    common(p, "results/instr-latest")
    p.add_argument("--groups", action="store_true",
                   help="the jobs of one build group in one process, built once (the gate runs each job alone)")
    p.set_defaults(fn=cmd_measure)
    p = sub.add_parser("compare", help="compare two measurements")
    p.add_argument("base")
    p.add_argument("new")
    thresholds(p)
    p.set_defaults(fn=cmd_compare)
    p = sub.add_parser("gate", help="measure, then compare with --base or --base-ref")
    common(p, "results/instr-latest")
    thresholds(p)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--base", default=str(ROOT / "results" / "instr-baseline"), help="a measured folder")
    g.add_argument("--base-ref", help="a commit (the merge-base): built in a scratch worktree, measured in this run")
    p.add_argument("--work", default=str(ROOT / "results" / "instr-work"), help="scratch worktree and build for --base-ref")
    p.set_defaults(fn=cmd_gate)
    p = sub.add_parser("one", help="print one job's instructions per query")
    p.add_argument("--exe", default=str(ROOT / "build" / "bvhbench"))
    p.add_argument("--jobs", default=str(ROOT / "suites" / "ci_instructions.yml"))
    # A bisection step measures an older commit's binary: the jobs are this checkout's.
    p.add_argument("--list-exe", default=DEFAULT_EXE,
                   help="the bvhbench that expands the job list (default: $BVHBENCH_EXE or build/bvhbench)")
    p.add_argument("--job", required=True)
    p.add_argument("--out", required=True, help="scratch folder")
    p.set_defaults(fn=cmd_one)
    args = ap.parse_args(argv)
    for k in ("fail", "warn"):
        if hasattr(args, k) and not 0 < getattr(args, k) < 10:
            print(f"instr_gate: --{k} {getattr(args, k)}: expected a fraction such as 0.10", file=sys.stderr)
            return 2
    try:
        return args.fn(args)
    except BrokenRun as e:
        print(f"instr_gate: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
