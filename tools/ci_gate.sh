#!/usr/bin/env bash
# The CI regression gate (docs/compare.md).
#
#   tools/ci_gate.sh                 run suites/ci.yml into results/ci-latest/ and compare it with
#                                    the committed baseline results/baseline/ (--timing report)
#   tools/ci_gate.sh --rebaseline    regenerate results/baseline/ on purpose (then commit it)
#   tools/ci_gate.sh -- ARGS...      extra arguments for `bvhbench compare` (e.g. --timing gate on a
#                                    dedicated machine; the last --timing given wins)
#
# Then the instruction gate (tools/instr_gate.py): instructions per query of each job of
# suites/ci_instructions.yml, counted under valgrind in the timed pass only, against
# results/instr-baseline/ when it was measured under the same fingerprint (compiler, libraries,
# processor as valgrind presents it); it fails on a job >= 10 % slower by that count.
#
# Environment: BVHBENCH_EXE (default build/bvhbench), CI_GATE_OUT (default results/ci-latest),
#              CI_GATE_BASE (default results/baseline: the committed baseline; a baseline of your
#              own, made on this machine, gates the machine-dependent counters exactly too),
#              CI_GATE_INSTR (default on; off skips the instruction gate, and says so),
#              CI_GATE_INSTR_BASE (default results/instr-baseline),
#              CI_GATE_INSTR_BASE_REF (a commit, say the merge-base: built in a scratch worktree
#              and counted in this run, instead of CI_GATE_INSTR_BASE: gates on any machine),
#              CI_GATE_HISTORY (a folder: append this run's rates and counts to its history,
#              tools/bench_history.py).
# Exit: 0 nothing gating changed; 1 counters, accuracy or statuses changed (or a job is missing),
#       or a job's instructions per query grew by >= 10 %;
#       2 a broken run (no binary, no baseline, no valgrind, the suite or compare could not read its input).
# Counters a method declares machine-dependent (Embree's traversal) gate only against a baseline
# of the same machine fingerprint; the summary says how many were reported instead, and why.
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
EXE="${BVHBENCH_EXE:-$ROOT/build/bvhbench}"
case "$EXE" in /*) ;; *) EXE="$PWD/$EXE" ;; esac
# Paths relative to the repository, so that the committed results do not name this checkout.
cd "$ROOT" || exit 2
SUITE="suites/ci.yml"
BASE="${CI_GATE_BASE:-results/baseline}"
OUT="${CI_GATE_OUT:-results/ci-latest}"
case "$OUT" in ""|/|.|..|"$ROOT") echo "ci_gate: refusing CI_GATE_OUT='$OUT'" >&2; exit 2 ;; esac

mode=gate
compare_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rebaseline) mode=rebaseline ;;
    --) shift; compare_args=("$@"); break ;;
    -h|--help) sed -n '2,30p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "ci_gate: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

if [ ! -x "$EXE" ]; then
  echo "ci_gate: no bvhbench binary at $EXE (build it, or set BVHBENCH_EXE)" >&2
  exit 2
fi

run_suite() {  # run_suite OUT_DIR: a fresh run (query sets and oracles are made again, too)
  rm -rf "$1"
  local t0=$SECONDS
  "$EXE" suite "$SUITE" --out "$1"
  local rc=$?
  if [ $rc -ne 0 ]; then
    echo "ci_gate: the CI suite did not run (exit $rc): see the messages above" >&2
    exit 2
  fi
  echo "ci_gate: CI suite took $((SECONDS - t0)) s" >&2
}

if [ "$mode" = rebaseline ] && [ "$BASE" != results/baseline ]; then
  echo "ci_gate: --rebaseline regenerates results/baseline only (CI_GATE_BASE='$BASE'): make your own with" >&2
  echo "ci_gate:   $EXE suite $SUITE --out $BASE" >&2
  exit 2
fi
if [ "$mode" = rebaseline ]; then
  echo "ci_gate: regenerating the baseline in $BASE" >&2
  run_suite "$BASE"
  echo "ci_gate: counting the instruction baseline in results/instr-baseline" >&2
  rm -rf results/instr-baseline
  python3 tools/instr_gate.py measure --exe "$EXE" --out results/instr-baseline || exit 2
  echo
  echo "Baseline regenerated: $BASE ($(ls "$BASE/runs" | wc -l) results), results/instr-baseline/instructions.json."
  echo "Review what changed, then commit it with the change that made it:"
  echo "  git diff --stat -- results/baseline results/instr-baseline"
  echo "  git add results/baseline/runs results/baseline/summary.csv results/baseline/suite.yml results/instr-baseline/instructions.json"
  echo "  git commit -m \"rebaseline: <why>\" -- results/baseline results/instr-baseline"
  exit 0
fi

if [ ! -d "$BASE/runs" ]; then
  echo "ci_gate: no baseline in $BASE/runs: run 'make rebaseline' and commit results/baseline/" >&2
  exit 2
fi
if [ -f "$BASE/suite.yml" ] && ! cmp -s "$BASE/suite.yml" "$SUITE"; then
  echo "ci_gate: note: suites/ci.yml changed since the baseline was made (expect new/missing jobs)" >&2
fi

run_suite "$OUT"
"$EXE" compare "$BASE" "$OUT" --timing report --format json "${compare_args[@]}" > "$OUT/compare.json"
"$EXE" compare "$BASE" "$OUT" --timing report "${compare_args[@]}" | tee "$OUT/compare.md"
rc=${PIPESTATUS[0]}
# compare's own summary of the machine-dependent counters it reported instead of gating.
not_gated="$(grep -m1 '^Not gated:' "$OUT/compare.md")"
if [ -n "$not_gated" ]; then
  echo
  echo "ci_gate: ${not_gated}"
  echo "ci_gate: they gate exactly against a baseline made on this machine:"
  echo "ci_gate:   $EXE suite $SUITE --out results/mybase   # once, on a clean commit"
  echo "ci_gate:   CI_GATE_BASE=results/mybase tools/ci_gate.sh"
fi
# ---- the instruction gate -------------------------------------------------------------------
instr_rc=0
if [ "${CI_GATE_INSTR:-on}" = off ]; then
  echo "ci_gate: instruction gate NOT RUN (CI_GATE_INSTR=off): a slower query loop that changes no counter would pass."
else
  instr_args=(gate --exe "$EXE" --out "$OUT/instructions")
  if [ -n "${CI_GATE_INSTR_BASE_REF:-}" ]; then
    instr_args+=(--base-ref "$CI_GATE_INSTR_BASE_REF")
  else
    instr_args+=(--base "${CI_GATE_INSTR_BASE:-results/instr-baseline}")
  fi
  [ -n "${CI_GATE_HISTORY:-}" ] && instr_args+=(--history "$CI_GATE_HISTORY")
  t0=$SECONDS
  echo
  python3 tools/instr_gate.py "${instr_args[@]}"
  instr_rc=$?
  echo "ci_gate: instruction gate took $((SECONDS - t0)) s" >&2
  if grep -q '^Not gated:' "$OUT/instructions/instructions_compare.md" 2>/dev/null; then
    echo "ci_gate: instruction gate NOT GATED here: the baseline was counted under another fingerprint (above)."
    echo "ci_gate:   gate against the merge-base, built and counted in this run: CI_GATE_INSTR_BASE_REF=origin/main tools/ci_gate.sh"
  fi
fi
if [ -n "${CI_GATE_HISTORY:-}" ]; then
  python3 tools/bench_history.py append "$OUT" --history "$CI_GATE_HISTORY" || true
fi

case $instr_rc in
  0) ;;
  1) echo "ci_gate: FAILED: a query loop needs >= 10 % more instructions per query than the baseline (see above)."
     echo "ci_gate: find the commit: tools/instr_bisect.py --good <last good> --bad HEAD --job <job>"
     echo "ci_gate: if the slowdown is the price of something you meant, run 'make rebaseline' and commit results/instr-baseline/." ;;
  *) echo "ci_gate: the instruction gate could not count (exit $instr_rc): a broken run, not a regression." >&2 ;;
esac

case $rc in
  0) if [ -n "$not_gated" ]; then
       echo "ci_gate: OK: portable counters, accuracy and statuses match the baseline; machine-dependent counters reported above, not gated (timings reported only; the query loops' work is the instruction gate's, above)."
     else
       echo "ci_gate: OK: counters, accuracy and statuses match the baseline (timings reported only; the query loops' work is the instruction gate's, above)."
     fi ;;
  1) echo
     echo "ci_gate: FAILED: the results differ from the committed baseline (see the table above)."
     echo "ci_gate: if the change is intended (a new method, a better traversal, a fixed answer), run"
     echo "ci_gate:   make rebaseline"
     echo "ci_gate: and commit results/baseline/ together with your change." ;;
  *) echo "ci_gate: compare could not read the results (exit $rc): a broken run, not a regression." >&2 ;;
esac
[ $instr_rc -eq 1 ] && echo "ci_gate: FAILED: the instruction gate (a query loop got slower; see above)."
# A broken run wins, then a regression of either gate.
if [ $rc -ge 2 ] || [ $instr_rc -ge 2 ]; then exit 2; fi
if [ $rc -ne 0 ] || [ $instr_rc -ne 0 ]; then exit 1; fi
exit 0
