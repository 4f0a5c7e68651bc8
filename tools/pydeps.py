#!/usr/bin/env python3
"""Prints the Python requirements of pyproject.toml that are not installed (one per line).

Used by `make deps` so that pip runs only when something is missing. Standard library only.
"""
import argparse
import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def requirements():
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    reqs = list(data["project"]["dependencies"])
    reqs += data["project"].get("optional-dependencies", {}).get("test", [])
    return reqs


def installed(req):
    name = re.split(r"[<>=!~\[; ]", req, maxsplit=1)[0]
    try:
        metadata.version(name)
        return True
    except metadata.PackageNotFoundError:
        return False


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--missing", action="store_true", help="print only missing requirements")
    args = ap.parse_args()
    for r in requirements():
        if not args.missing or not installed(r):
            print(r)
    return 0


if __name__ == "__main__":
    sys.exit(main())
