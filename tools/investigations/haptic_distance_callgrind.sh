#!/usr/bin/env bash
# Instructions per haptic distance query (callgrind), EBP-Octree coherent and not, Embree coherent.
#
#   tools/investigations/haptic_distance_callgrind.sh BVHBENCH NAME MESH QUERIES OUTDIR [METHOD...]
#
# BVHBENCH the runner (build/bvhbench, or a variant of it), QUERIES a set of `bvhbench queries
# --kind haptic`. For each METHOD (default: ebp_octree:coherent=true ebp_octree
# embree:coherent=true) one `bvhbench run --query distance --repeat 1` under callgrind, collecting
# only inside the method's `distance` (`SharedStructureMethod<EbpQueries>`, `<EbpOocQueries>`, `<EmbreeQueries>`) (`--toggle-collect`), so that the build and the
# harness are left out; then `callgrind_annotate --inclusive=yes --threshold=100` into
# OUTDIR/NAME__METHOD.txt (and with `--tree=caller`, call counts per caller, into .tree.txt) and
# the run's result (counters per query) into OUTDIR/NAME__METHOD.json. --repeat 1 is a warm-up
# pass, one timed pass and the latency pass: 3 calls per query (see the caller tree). The script
# prints the total instructions collected; tools/investigations/callgrind_split.py turns them into a table.
# Counts do not depend on the machine's load; they do on the compiler and the libraries.
set -euo pipefail
B=$1 NAME=$2 MESH=$3 Q=$4 OUT=$5
shift 5
METHODS=("$@")
[ ${#METHODS[@]} -gt 0 ] || METHODS=(ebp_octree:coherent=true ebp_octree embree:coherent=true)
mkdir -p "$OUT"
for M in "${METHODS[@]}"; do
  case $M in
    ebp_octree*store=*) FN='bvhbench::SharedStructureMethod<bvhbench::(anonymous namespace)::EbpOocQueries>::distance(' ;;
    ebp_octree*) FN='bvhbench::SharedStructureMethod<bvhbench::(anonymous namespace)::EbpQueries>::distance(' ;;
    embree*) FN='bvhbench::SharedStructureMethod<bvhbench::(anonymous namespace)::EmbreeQueries>::distance(' ;;
    *) echo "unknown method $M" >&2; exit 2 ;;
  esac
  TAG="${NAME}__${M//[:=,\/]/_}"  # a store path's slashes too
  valgrind --tool=callgrind --collect-atstart=no --toggle-collect="${FN}*" \
    --callgrind-out-file="$OUT/$TAG.cg" \
    "$B" run --mesh "$MESH" --method "$M" --queries "$Q" --query distance --repeat 1 --quiet \
    --out "$OUT/$TAG.json" 2> "$OUT/$TAG.valgrind.log"
  callgrind_annotate --inclusive=yes --threshold=100 "$OUT/$TAG.cg" > "$OUT/$TAG.txt"
  callgrind_annotate --inclusive=yes --threshold=100 --tree=caller "$OUT/$TAG.cg" > "$OUT/$TAG.tree.txt"
  TOTAL=$(awk '/PROGRAM TOTALS/{gsub(",","",$1); print $1; exit}' "$OUT/$TAG.txt")
  [ "$TOTAL" != "." ] || { echo "$TAG: nothing collected: is ${FN}* still the adapter's name?" >&2; exit 1; }
  echo "$TAG total_Ir=$TOTAL"
done
