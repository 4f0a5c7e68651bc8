#!/usr/bin/env bash
# Runs every fuzz target of build-fuzz/ for SECONDS each (fuzz/README.md), PARALLEL at a time
# (default 1; at most 2 on the shared 2-core machine), each on a scratch copy of its seeds under
# WORK, with its findings and its log under FINDINGS/<target>/. Prints each target's last status
# line (runs, coverage) and its findings.
#
#   fuzz/run_all.sh SECONDS [TARGET...]        e.g. fuzz/run_all.sh 900 npz suite
#   env: BUILD (build-fuzz), WORK (/tmp/bvhbench-fuzz), FINDINGS (fuzz-findings), PARALLEL (1),
#        MALLOC_LIMIT_MB (512; the largest single allocation an input may make)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
seconds=${1:?usage: run_all.sh SECONDS [TARGET...]}
shift
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=($(cd "$here/corpus" && ls))
fi
BUILD=${BUILD:-build-fuzz}
WORK=${WORK:-/tmp/bvhbench-fuzz}
FINDINGS=${FINDINGS:-fuzz-findings}
PARALLEL=${PARALLEL:-1}
MALLOC_LIMIT_MB=${MALLOC_LIMIT_MB:-512}
dict_of() {
  case $1 in
    npy) echo npy ;; npz) echo npz ;; ply|obj|stl|off) echo "$1" ;; suite) echo yaml ;; compare|query_sidecar) echo json ;; *) echo "" ;;
  esac
}
run_one() {
  local t=$1 dict
  mkdir -p "$WORK/$t" "$FINDINGS/$t"
  cp -n "$here/corpus/$t/"* "$WORK/$t/"
  dict=$(dict_of "$t")
  "$BUILD/fuzz_$t" -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb="$MALLOC_LIMIT_MB" -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$FINDINGS/$t/" ${dict:+-dict="$here/dict/$dict.dict"} \
    "$WORK/$t" > "$FINDINGS/$t.log" 2>&1 || true
  echo "$t: $(grep -E '^#[0-9]+' "$FINDINGS/$t.log" | tail -1)"
  grep -E 'stat::number_of_executed_units|stat::peak_rss_mb' "$FINDINGS/$t.log" | sed "s/^/$t: /" || true
  ls "$FINDINGS/$t" | sed "s/^/$t: finding /" || true
}
export -f run_one dict_of
export here seconds BUILD WORK FINDINGS MALLOC_LIMIT_MB
printf '%s\n' "${targets[@]}" | xargs -P "$PARALLEL" -I{} bash -c 'run_one {}'
