#!/usr/bin/env python3
"""Prints the EBP-Octree's headline table against Embree, with its targets, from a run of
suites/headline.yml: the table is plots/headline_targets.py's (whose docstring says what each
row and target is), read through plots/results_io.py.

    .venv/bin/python tools/headline_table.py results/headline
    .venv/bin/python tools/headline_table.py --instructions results/headline-instructions

With --instructions, RESULTS is a measurement of tools/instr_gate.py (`measure --groups --jobs
suites/headline.yml --out RESULTS`) and the tables are in instructions per query.
"""
import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plots"))
import headline_targets  # noqa: E402
import results_io  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("results", type=Path)
    ap.add_argument("--instructions", action="store_true",
                    help="RESULTS is an instruction measurement (tools/instr_gate.py): the tables in instructions per query")
    args = ap.parse_args()
    try:
        rs = results_io.load(str(args.results))
        counts = None
        if args.instructions:
            doc = json.loads((args.results / "instructions.json").read_text())
            counts = {r["id"]: r["instructions_per_query"] for r in doc["jobs"] if r.get("status") == "ok"}
    except results_io.ReportError as e:
        print(f"headline_table: {e}", file=sys.stderr)
        return 2
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"headline_table: {args.results / 'instructions.json'}: not an instruction measurement ({e})",
              file=sys.stderr)
        return 2
    sys.stdout.write(headline_targets.markdown(rs, counts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
