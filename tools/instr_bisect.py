#!/usr/bin/env python3
"""Names the commit that moved a job's instructions per query: `git bisect run` over the count.

  tools/instr_bisect.py --good GOOD --bad BAD --job JOB [--threshold 0.03]

measures JOB (an id of suites/ci_instructions.yml, as the instruction gate names it) at GOOD and at
BAD, then bisects between them in a scratch worktree (--work, default results/bisect-work/: the
checkout you work in is never touched): each step builds the commit (cmake + ninja, ccache when
installed, so a step rebuilds only what changed) and counts the job under callgrind; a commit is
"bad" when its count exceeds GOOD's by more than --threshold (default 3 %, well above the 0 %
run-to-run spread of the count and well below the gate's 10 %). A commit that does not build or
whose job does not run is skipped (exit 125), as `git bisect run` wants.

--build-cmd and --measure-cmd replace the build and the measure (shell commands run in the
checked-out commit; the measure prints the figure on its last line): a project of your own, or a
wall-clock measure on a quiet machine. --repo bisects another repository (default: this one).

Prints the first bad commit, its subject, and the figure at every step; exit 0 when a commit was
named, 1 when BAD does not differ from GOOD by more than the threshold (nothing to bisect), 2 on
a broken run (a commit that is not one, GOOD or BAD that cannot be measured, git bisect failing).
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tool_cli import tool_parser  # noqa: E402  (beside this file)

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve()


def git(repo, *args, check=True):
    p = subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise SystemExit(f"instr_bisect: git {' '.join(args)}: {p.stderr.strip()}")
    return p


def default_build_cmd(work, jobs):
    launcher = " -DCMAKE_CXX_COMPILER_LAUNCHER=ccache" if shutil.which("ccache") else ""
    # build/ inside the checkout, as in a developer's tree: with CCACHE_BASEDIR set, ccache then
    # serves every file the step's commit did not change.
    b = "build"
    return (f"cmake -S . -B {b} -G Ninja -DCMAKE_BUILD_TYPE=Release{launcher} >/dev/null && "
            f"cmake --build {b} -j {jobs} --target bvhbench >/dev/null")


def default_measure_cmd(work, job):
    return (f"{shlex.quote(sys.executable)} {shlex.quote(str(ROOT / 'tools' / 'instr_gate.py'))} one "
            f"--exe {shlex.quote(str(Path(work) / 'src' / 'build' / 'bvhbench'))} "
            f"--jobs {shlex.quote(str(ROOT / 'suites' / 'ci_instructions.yml'))} --job {shlex.quote(job)} "
            f"--out {shlex.quote(str(Path(work) / 'measure'))}")


def build_and_measure(src, build_cmd, measure_cmd):
    """The figure at the commit checked out in `src`, or None when it does not build or measure."""
    for cmd in (build_cmd, measure_cmd):
        p = subprocess.run(cmd, shell=True, cwd=src, capture_output=True, text=True)
        if p.returncode != 0:
            sys.stderr.write(f"instr_bisect: `{cmd}` failed (exit {p.returncode}):\n{p.stderr[-2000:]}\n")
            return None
    lines = p.stdout.strip().splitlines()
    try:
        return float(lines[-1])
    except (IndexError, ValueError):
        sys.stderr.write(f"instr_bisect: the measure printed no number on its last line: {p.stdout[-500:]!r}\n")
        return None


def step(args):
    """One `git bisect run` step: 0 good, 1 bad, 125 skip (cannot build or measure)."""
    src = Path.cwd()
    sha = git(src, "rev-parse", "HEAD").stdout.strip()
    v = build_and_measure(src, args.build_cmd, args.measure_cmd)
    if v is None:
        print(f"instr_bisect-step {sha} skip", flush=True)
        return 125
    bad = v > args.ref * (1 + args.threshold)
    print(f"instr_bisect-step {sha} {v!r} {'bad' if bad else 'good'}", flush=True)
    return 1 if bad else 0


def main(argv=None):
    ap = tool_parser(__doc__)
    ap.add_argument("--good", required=True)
    ap.add_argument("--bad", required=True)
    ap.add_argument("--job", required=True, help="a job id of suites/ci_instructions.yml (any name with --measure-cmd)")
    ap.add_argument("--threshold", type=float, default=0.03)
    ap.add_argument("--repo", default=str(ROOT))
    ap.add_argument("--work", default=str(ROOT / "results" / "bisect-work"))
    ap.add_argument("--build-cmd")
    ap.add_argument("--measure-cmd")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="build parallelism")
    ap.add_argument("--step", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--ref", type=float, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if not 0 < args.threshold < 10:
        print(f"instr_bisect: --threshold {args.threshold}: expected a fraction such as 0.03", file=sys.stderr)
        return 2
    work = Path(args.work).resolve()
    args.build_cmd = args.build_cmd or default_build_cmd(work, args.jobs)
    args.measure_cmd = args.measure_cmd or default_measure_cmd(work, args.job)
    if args.step:
        return step(args)

    repo = Path(args.repo).resolve()
    shas = {}
    for name in ("good", "bad"):
        p = git(repo, "rev-parse", "--verify", f"{getattr(args, name)}^{{commit}}", check=False)
        if p.returncode != 0:
            print(f"instr_bisect: --{name} {getattr(args, name)}: not a commit of {repo}", file=sys.stderr)
            return 2
        shas[name] = p.stdout.strip()
    if git(repo, "merge-base", "--is-ancestor", shas["good"], shas["bad"], check=False).returncode != 0:
        print(f"instr_bisect: --good {args.good} is not an ancestor of --bad {args.bad}", file=sys.stderr)
        return 2

    # A scratch worktree of its own: bisecting moves its HEAD, never the checkout you work in.
    src = work / "src"
    if src.exists():
        git(repo, "worktree", "remove", "--force", str(src), check=False)
        shutil.rmtree(src, ignore_errors=True)
        git(repo, "worktree", "prune")
    work.mkdir(parents=True, exist_ok=True)
    git(repo, "worktree", "add", "--detach", str(src), shas["bad"])
    try:
        figures = {}
        for name in ("good", "bad"):
            git(src, "checkout", "--quiet", "--detach", shas[name])
            v = build_and_measure(src, args.build_cmd, args.measure_cmd)
            if v is None:
                print(f"instr_bisect: cannot measure --{name} {getattr(args, name)} ({shas[name][:10]})", file=sys.stderr)
                return 2
            figures[name] = v
            print(f"instr_bisect: {name} {shas[name][:10]}: {v:,.3f}", flush=True)
        change = figures["bad"] / figures["good"] - 1 if figures["good"] else float("inf")
        if change <= args.threshold:
            print(f"instr_bisect: {args.job}: {change:+.2%} from good to bad, within --threshold {args.threshold:.0%}: "
                  "nothing to bisect")
            return 1
        git(src, "bisect", "start", shas["bad"], shas["good"])
        step_cmd = [sys.executable, str(HERE), "--step", "--ref", repr(figures["good"]), "--threshold", str(args.threshold),
                    "--job", args.job, "--good", shas["good"], "--bad", shas["bad"], "--work", str(work),
                    "--build-cmd", args.build_cmd, "--measure-cmd", args.measure_cmd]
        p = subprocess.run(["git", "-C", str(src), "bisect", "run", *step_cmd], capture_output=True, text=True)
        out = p.stdout
        steps = re.findall(r"^instr_bisect-step (\S+) (\S+)(?: (\S+))?$", out, re.M)
        m = re.search(r"^([0-9a-f]{40}) is the first bad commit", out, re.M)
        if not m:
            print(f"instr_bisect: git bisect run named no commit (exit {p.returncode}):\n{out[-3000:]}\n{p.stderr[-2000:]}",
                  file=sys.stderr)
            return 2
        first = m.group(1)
        subject = git(repo, "log", "-1", "--format=%s", first).stdout.strip()
        print(f"instr_bisect: {args.job}: {figures['good']:,.3f} at good -> {figures['bad']:,.3f} at bad ({change:+.2%})")
        for sha, v, verdict in steps:
            print(f"instr_bisect:   step {sha[:10]} {v if v == 'skip' else format(float(v), ',.3f')} {verdict}")
        print(f"instr_bisect: first bad commit: {first} {subject}")
        return 0
    finally:
        git(src, "bisect", "reset", check=False)
        git(repo, "worktree", "remove", "--force", str(src), check=False)
        git(repo, "worktree", "prune", check=False)


if __name__ == "__main__":
    sys.exit(main())
