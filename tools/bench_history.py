#!/usr/bin/env python3
"""Per-machine history of each job's rate and instructions per query, with step detection.

  append RESULTS [--history results/history]   a suite's results (RESULTS/runs/*.json): each ok
                                               job's median throughput and calibration-normalised
                                               rate, under HISTORY/<machine key>/rates.jsonl
  report [--history results/history] --out DIR each fingerprint's jobs across commits: one chart a
                                               job that moved (DIR/<key>/<job>.png), an overview
                                               chart, and DIR/history.md (the report can include it)

The instruction gate appends instructions per query itself (tools/instr_gate.py --history) under
HISTORY/<instruction fingerprint key>/instructions.jsonl. Histories are kept apart per fingerprint
(rates: processor, ISA, libraries, compiler and flags; instructions: the same as valgrind presents
them, and valgrind's version): figures from two machines are never drawn on one line.
results/ is git-ignored: a history lives where CI keeps it (a cache, an artifact, a branch;
docs/compare.md).

Steps are found by optimal partitioning of the series into constant pieces (the L1 cost of asv's
step detection, on log values, so a step is a ratio), with a penalty per step scaled by the
series' own noise (the median absolute difference of consecutive points): a deterministic
instruction count shows every real step, a noisy rate only the ones that stand out.
"""
import hashlib
import json
import math
import statistics
import sys
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parents[1] / "plots"), str(Path(__file__).resolve().parent)]
import results_io  # noqa: E402  (every reader of results goes through it)
from tool_cli import tool_parser  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def fmt(v):
    v = float(f"{v:.6g}")  # a level is exp(log(x)): 999.9999999 is 1,000
    return f"{v:,.0f}" if abs(v) >= 1000 else f"{v:.4g}"


# ---- step detection (asv-style, small) ----------------------------------------------------------

def _l1_cost(seg):
    m = statistics.median(seg)
    return sum(abs(v - m) for v in seg), m


def detect_steps(values, min_noise=0.002, penalty_factor=4.0):
    """Pieces [(start, end, level)] of the series, by minimising sum(L1 cost) + beta * pieces.

    Values are positive figures; the fit is on their logs. beta = penalty_factor * sigma * log(n+1),
    sigma the noise of consecutive differences (median absolute difference / 0.6745 / sqrt 2), never
    below min_noise (0.2 %: a deterministic count's steps of a fraction of a percent are kept as one
    piece unless they add up)."""
    x = [math.log(v) for v in values]
    n = len(x)
    if n == 0:
        return []
    diffs = [abs(x[i + 1] - x[i]) for i in range(n - 1)]
    sigma = (statistics.median(diffs) / 0.6745 / math.sqrt(2)) if diffs else 0.0
    sigma = max(sigma, min_noise)
    beta = penalty_factor * sigma * math.log(n + 1)
    best = [0.0] + [math.inf] * n
    prev = [0] * (n + 1)
    for j in range(1, n + 1):
        for i in range(j):
            c = best[i] + _l1_cost(x[i:j])[0] + beta
            if c < best[j]:
                best[j], prev[j] = c, i
    pieces = []
    j = n
    while j > 0:
        i = prev[j]
        pieces.append((i, j, math.exp(_l1_cost(x[i:j])[1])))
        j = i
    return pieces[::-1]


# ---- appending ----------------------------------------------------------------------------------

def machine_key(job):
    """The machine and build a result was measured on (results_io.Job), and its short key."""
    fp = job.get("machine_dependent.fingerprint") or {}
    key = {"cpu": fp.get("cpu"), "isa": fp.get("isa"), "libraries": job.get("context.libraries"),
           "compiler": job.get("context.compiler"), "cxx_flags": (job.get("context.cxx_flags") or "").strip(),
           "build_type": job.get("context.build_type"), "host": job.get("context.host")}
    return key, hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:12]


def append_suite(results_dir, history):
    """Each ok job's rate of a suite's results (read through plots/results_io.py) appended to
    HISTORY/<machine key>/rates.jsonl."""
    try:
        rs = results_io.load(str(results_dir))
    except results_io.ReportError as e:
        print(f"bench_history: {e}", file=sys.stderr)
        return 2
    if rs.unreadable:
        print(f"bench_history: {results_dir}/runs/{rs.unreadable[0][0]}: unreadable: {rs.unreadable[0][1]}",
              file=sys.stderr)
        return 2
    n = 0
    for job in sorted(rs.jobs, key=lambda j: j.path):
        qps = job.num("queries.throughput_qps.median")
        if not job.ok or not qps:
            continue
        key, k = machine_key(job)
        d = Path(history) / k
        d.mkdir(parents=True, exist_ok=True)
        (d / "fingerprint.json").write_text(json.dumps(key, indent=1, sort_keys=True) + "\n")
        cal = job.num("calibration.median_seconds")
        line = {"commit": job.get("context.git_commit"), "dirty": job.get("context.git_dirty"),
                "date": job.get("context.date"), "job": job.get("job.id"), "qps_median": qps,
                "qps_normalised": qps * cal if cal else None}
        with open(d / "rates.jsonl", "a") as out:
            out.write(json.dumps(line, sort_keys=True) + "\n")
        n += 1
    print(f"bench_history: {n} job rates appended under {history}")
    return 0


# ---- reporting ----------------------------------------------------------------------------------

SERIES = [("instructions.jsonl", "instructions_per_query", "instructions / query", 0.002),
          ("rates.jsonl", "qps_normalised", "normalised rate (q/s x calibration s)", 0.01)]


def load_series(d, fname, field):
    """{job: [(commit, value)]}, in the order appended; a commit measured more than once keeps its median."""
    path = d / fname
    if not path.exists():
        return {}
    by_job = {}
    for line in path.read_text().splitlines():
        if not line.strip():
            continue
        rec = json.loads(line)
        v = rec.get(field)
        if v is None or v <= 0 or rec.get("test_slowdown"):
            continue
        commit = (rec.get("commit") or "?")[:10] + ("+" if rec.get("dirty") else "")
        pts = by_job.setdefault(rec["job"], {})
        pts.setdefault(commit, []).append(v)
    return {job: [(c, statistics.median(vs)) for c, vs in pts.items()] for job, pts in by_job.items()}


def report(history, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    history, out = Path(history), Path(out)
    dirs = sorted(p for p in history.iterdir() if p.is_dir()) if history.is_dir() else []
    if not dirs:
        print(f"bench_history: no history under {history}", file=sys.stderr)
        return 2
    md = ["## History across commits", "",
          "Each job's figure per commit, per fingerprint, with the steps found (tools/bench_history.py).", ""]
    for d in dirs:
        fp = json.loads((d / "fingerprint.json").read_text()) if (d / "fingerprint.json").exists() else {}
        for fname, field, label, floor in SERIES:
            series = load_series(d, fname, field)
            if not series:
                continue
            (out / d.name).mkdir(parents=True, exist_ok=True)
            md += [f"### {label}, fingerprint {d.name}", "",
                   f"{fp.get('compiler', '?')}, {', '.join(f'{k} {v}' for k, v in sorted((fp.get('libraries') or {}).items()))}"
                   + (f", {fp['valgrind']}" if fp.get("valgrind") else ""), ""]
            md += ["| job | commits | last | steps (commit: before -> after) |", "|---|---:|---:|---|"]
            fig, ax = plt.subplots(figsize=(10, 5))
            for job, pts in sorted(series.items()):
                vals = [v for _, v in pts]
                pieces = detect_steps(vals, min_noise=floor)
                steps = []
                for (a, b, lvl), (a2, b2, lvl2) in zip(pieces, pieces[1:]):
                    steps.append(f"{pts[a2][0]}: {fmt(lvl)} -> {fmt(lvl2)} ({lvl2 / lvl - 1:+.1%})")
                md.append(f"| {job} | {len(pts)} | {fmt(vals[-1])} | {'; '.join(steps) or 'none'} |")
                rel = [v / vals[0] for v in vals]
                ax.plot(range(len(rel)), rel, marker=".", label=job if steps else None, alpha=0.9 if steps else 0.3)
                if steps:
                    f2, a2x = plt.subplots(figsize=(8, 4))
                    a2x.plot(range(len(vals)), vals, marker="o", label=job)
                    for a, b, lvl in pieces:
                        a2x.hlines(lvl, a - 0.4, b - 0.6, colors="red")
                    a2x.set_xticks(range(len(vals)), [c for c, _ in pts], rotation=60, fontsize=7)
                    a2x.set_ylabel(label)
                    a2x.set_title(f"{job} ({d.name})", fontsize=9)
                    f2.tight_layout()
                    f2.savefig(out / d.name / f"{job}.{field}.png", dpi=100)
                    plt.close(f2)
            ax.set_xlabel("commit (in the order measured)")
            ax.set_ylabel(f"{label}, relative to the first")
            ax.set_title(f"{label}: every job ({d.name}); the jobs with steps are labelled", fontsize=9)
            if any(line.get_label() and not line.get_label().startswith("_") for line in ax.get_lines()):
                ax.legend(fontsize=6)
            fig.tight_layout()
            chart = out / d.name / f"overview.{field}.png"
            fig.savefig(chart, dpi=100)
            plt.close(fig)
            md += ["", f"![{label}]({chart.relative_to(out)})", ""]
    out.mkdir(parents=True, exist_ok=True)
    (out / "history.md").write_text("\n".join(md) + "\n")
    print(f"bench_history: {out / 'history.md'}")
    return 0


def main(argv=None):
    ap = tool_parser(__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("append")
    p.add_argument("results")
    p.add_argument("--history", default=str(ROOT / "results" / "history"))
    p = sub.add_parser("report")
    p.add_argument("--history", default=str(ROOT / "results" / "history"))
    p.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    if args.cmd == "append":
        return append_suite(args.results, args.history)
    return report(args.history, args.out)


if __name__ == "__main__":
    sys.exit(main())
