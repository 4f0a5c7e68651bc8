#!/usr/bin/env python3
"""Prints the Python requirements of pyproject.toml that are not installed (one per line).

Used by `make deps` so that pip runs only when something is missing. Standard library only.
"""
import argparse
import re
import sys
from importlib import metadata
from pathlib import Path

try:
    import tomllib  # Python 3.11+
except ModuleNotFoundError:  # an older interpreter: read the two lists this file needs by hand
    tomllib = None

ROOT = Path(__file__).resolve().parent.parent


def _string_list(text, key):
    """The strings of `key = [ ... ]` in pyproject.toml (a plain list of quoted strings)."""
    m = re.search(r"^" + re.escape(key) + r"\s*=\s*\[(.*?)\]", text, re.S | re.M)
    return re.findall(r'"([^"]+)"', m.group(1)) if m else []


def requirements():
    text = (ROOT / "pyproject.toml").read_text()
    if tomllib is None:
        return _string_list(text, "dependencies") + _string_list(text, "test")
    data = tomllib.loads(text)
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
