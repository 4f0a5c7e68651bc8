#!/usr/bin/env bash
# A bvhbench whose only change is `__attribute__((noinline))` on the steps of the EBP-Octree's
# distance search (Query::DistanceSearch: coherent_start, descend, narrowed_start, node_bound,
# leaf_hint, scan_leaf, order_blocks, triangle_pruned, test_triangle), so that callgrind can
# attribute instructions to each step (in the project's binary some are inlined). Nothing in the
# worktree changes: the patched copy of core/query_distance.cpp is compiled with the build's own
# command line into OUTDIR, put into a copy of libebp_octree_core.a, and bvhbench is relinked
# there with the build's link line.
#
#   tools/investigations/build_noinline_variant.sh BUILD_DIR OUTDIR      # writes OUTDIR/bvhbench_noinline
#
# The extra calls cost 3-6 % of the search's instructions (methods/ebp_octree/HISTORY.md, "Haptic distance: where the
# time goes"); use the project's binary for totals, this one for the split.
set -euo pipefail
BUILD=$(cd "$1" && pwd) OUT=$(mkdir -p "$2" && cd "$2" && pwd)
CMDS="$OUT/commands.txt"
(cd "$BUILD" && ninja -t commands bvhbench > "$CMDS")
SRC=$(grep -o '[^ ]*core/query_distance\.cpp$' "$CMDS" | head -n1)
sed -E 's/^(  )(void coherent_start\(\)|void descend\(\)|void test_triangle\(|void scan_leaf\(|std::uint32_t order_blocks\(|bool triangle_pruned\(|PlaneHint leaf_hint\(|double node_bound\(|StackItem narrowed_start\(\))/\1__attribute__((noinline)) \2/' \
  "$SRC" > "$OUT/query_distance_noinline.cpp"
[ "$(grep -c 'noinline' "$OUT/query_distance_noinline.cpp")" -eq 9 ] || { echo "expected 9 steps to mark" >&2; exit 1; }
cd "$BUILD"
CC_LINE=$(grep -- "-c $SRC\$" "$CMDS" | head -n1)
OBJ=$(sed -E 's/.* -o ([^ ]+) -c .*/\1/' <<< "$CC_LINE")
CC_LINE=${CC_LINE/#ccache /}
CC_LINE=${CC_LINE/ -o $OBJ -c $SRC/ -o $OUT/query_distance.cpp.o -c $OUT/query_distance_noinline.cpp}
CC_LINE=$(sed -E 's/ -MD -MT [^ ]+ -MF [^ ]+//' <<< "$CC_LINE")
eval "$CC_LINE"
LIB=methods/ebp_octree/libebp_octree_core.a
cp "$LIB" "$OUT/"
(cd "$OUT" && ar r libebp_octree_core.a query_distance.cpp.o)
LINK=$(grep -- '-o bvhbench ' "$CMDS" | head -n1)
LINK=${LINK/ -o bvhbench / -o $OUT/bvhbench_noinline }
LINK=${LINK/ $LIB / $OUT/libebp_octree_core.a }
eval "${LINK#: && }"
echo "$OUT/bvhbench_noinline"
