#!/usr/bin/env python3
"""The stability matrix of a suite's results: method configuration x case, per query type.

    python tools/stability_matrix.py RESULTS_DIR [--out DIR]

Reads RESULTS_DIR/runs/*.json (one per job, docs/results.md) and writes, into --out (default
RESULTS_DIR):

- stability_matrix.csv: one row per (query type, method configuration, case) that has jobs:
  the worst status and every status with its count, and over the ok jobs the worst inside error
  rates (all points, away from the surface), distance errors, sign errors, non-finite answers,
  normal error and the lowest closest-triangle agreement, each judged against the method's own
  definition of inside; the definition, what it was judged against, the share of
  definition-dependent points and why the case is outside the method's contract. A cell's
  status keeps apart `ok_wrong` (wrong by its own definition, inside its contract),
  `definition_dependent` (right by it, where the definitions disagree) and `outside_contract`;
- stability_matrix.md: the same as one table per query type, configurations x cases.

The aggregation, and what a cell means, is plots/stability.py, which the report's stability
chart and tables use too. The cases are the result set's stress meshes; a result set with none
(a suite of regular models) gets a matrix over all its meshes. An unreadable result file is
counted and named in the Markdown, never the end of the matrix. Standard library only.
Exit codes: 0 written; 2 no runs/ folder or no readable result in it.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "plots"))

import stability  # noqa: E402
from results_io import ReportError, load  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", help="a suite's result folder (with runs/*.json)")
    ap.add_argument("--out", help="where to write the matrix (default: the result folder)")
    args = ap.parse_args(argv)
    if not os.path.isdir(os.path.join(args.results, "runs")):
        print(f"stability_matrix: {args.results}: no runs/ folder", file=sys.stderr)
        return 2
    try:
        rs = load(args.results)
    except ReportError as e:
        print(f"stability_matrix: {e}", file=sys.stderr)
        return 2
    meshes = stability.cases(rs)
    if not meshes:
        print(f"stability_matrix: {args.results}: no stress mesh among the results; the matrix "
              "is over every mesh", file=sys.stderr)
        meshes = stability.sort_cases({j.mesh for j in rs.jobs})
    csv_path, md_path = stability.write(rs, args.out or args.results, "stability_matrix.csv",
                                        "stability_matrix.md", meshes)
    print(f"stability_matrix: {len(rs.jobs)} job(s)"
          + (f", {len(rs.unreadable)} unreadable" if rs.unreadable else "")
          + f" -> {csv_path}, {md_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
