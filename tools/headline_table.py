#!/usr/bin/env python3
"""Prints the EBP-Octree's headline table against Embree, with its targets, from a run of
suites/headline.yml: the table is plots/headline_targets.py's (whose docstring says what each
row and target is), read through plots/results_io.py.

    .venv/bin/python tools/headline_table.py results/headline
"""
import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plots"))
import headline_targets  # noqa: E402
import results_io  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("results", type=Path)
    args = ap.parse_args()
    try:
        rs = results_io.load(str(args.results))
    except results_io.ReportError as e:
        sys.exit(f"headline_table: {e}")
    sys.stdout.write(headline_targets.markdown(rs))


if __name__ == "__main__":
    main()
