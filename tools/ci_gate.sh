#!/usr/bin/env bash
# The CI regression gate (docs/compare.md).
#
#   tools/ci_gate.sh                 run suites/ci.yml into results/ci-latest/ and compare it with
#                                    the committed baseline results/baseline/ (--timing report)
#   tools/ci_gate.sh --rebaseline    regenerate results/baseline/ on purpose (then commit it)
#   tools/ci_gate.sh -- ARGS...      extra arguments for `bvhbench compare` (e.g. --timing gate on a
#                                    dedicated machine; the last --timing given wins)
#
# Environment: BVHBENCH_EXE (default build/bvhbench), CI_GATE_OUT (default results/ci-latest),
#              CI_GATE_BASE (default results/baseline: the committed baseline; a baseline of your
#              own, made on this machine, gates the machine-dependent counters exactly too).
# Exit: 0 nothing gating changed; 1 counters, accuracy or statuses changed (or a job is missing);
#       2 a broken run (no binary, no baseline, the suite or compare could not read its input).
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
    -h|--help) sed -n '2,16p' "${BASH_SOURCE[0]}"; exit 0 ;;
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
  echo
  echo "Baseline regenerated: $BASE ($(ls "$BASE/runs" | wc -l) results)."
  echo "Review what changed, then commit it with the change that made it:"
  echo "  git diff --stat -- results/baseline"
  echo "  git add results/baseline/runs results/baseline/summary.csv results/baseline/suite.yml"
  echo "  git commit -m \"rebaseline: <why>\" -- results/baseline"
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
case $rc in
  0) if [ -n "$not_gated" ]; then
       echo "ci_gate: OK: portable counters, accuracy and statuses match the baseline; machine-dependent counters reported above, not gated (timings reported only)."
     else
       echo "ci_gate: OK: counters, accuracy and statuses match the baseline (timings reported only)."
     fi ;;
  1) echo
     echo "ci_gate: FAILED: the results differ from the committed baseline (see the table above)."
     echo "ci_gate: if the change is intended (a new method, a better traversal, a fixed answer), run"
     echo "ci_gate:   make rebaseline"
     echo "ci_gate: and commit results/baseline/ together with your change." ;;
  *) echo "ci_gate: compare could not read the results (exit $rc): a broken run, not a regression." >&2 ;;
esac
exit $rc
