"""The runner's registries, as the runner lists them: query kinds (`bvhbench kinds --json`) and
methods (`bvhbench methods --json`), so that the report and the tests order and name what the
runner registered instead of lists of their own.

The runner is $BVHBENCH_EXE, else build/bvhbench beside this folder. A report can be written
from results alone, on a machine without the runner: then the registries are empty and what
depends on them falls back to the names' order (kind_sort_key). Standard library only.
"""
import functools
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def runner():
    """The bvhbench whose registries are read, or None when there is none."""
    exe = os.environ.get("BVHBENCH_EXE") or os.path.join(ROOT, "build", "bvhbench")
    return exe if os.access(exe, os.X_OK) else None


@functools.lru_cache(maxsize=None)
def _listing(command):
    exe = runner()
    if exe is None:
        return []
    try:
        p = subprocess.run([exe, command, "--json"], capture_output=True, text=True, timeout=60)
        return json.loads(p.stdout) if p.returncode == 0 else []
    except (OSError, ValueError, subprocess.SubprocessError):
        return []


def query_kinds():
    """[{name, description, ordered, params: [{name, type, default, help, min, max}]}], in the
    runner's order; [] without a runner."""
    return _listing("kinds")


def methods():
    """[{name, description, capabilities, params, sweep, ...}] of `bvhbench methods --json`."""
    return _listing("methods")


def kind_sort_key(kind):
    """Query kinds in the order the runner registers them (random, near, haptic, ...), any other
    (a points file, a kind this runner does not know) after them by name."""
    names = [k["name"] for k in query_kinds()]
    return (names.index(kind) if kind in names else len(names), kind)
