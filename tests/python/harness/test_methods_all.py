"""`methods: all` in a suite, driving the built binary (suites/README.md, methods/README.md).

- A new method folder reaches a `methods: all` matrix with no other file changed: a toy Python
  method in a temporary folder (BVHBENCH_PYTHON_METHODS) is expanded there with the default
  sweep its method.py declares (SWEEP), beside every registered method's own sweep, and its jobs
  run and reach the report.
- `except:` leaves methods out; a name it gives that no method has is bad input (exit 2).

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing, or built without the host.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW, ROOT

MESH = COW
REPORT = ROOT / "plots" / "report.py"

pytestmark = NEEDS_RUNNER_AND_COW

# A toy method that declares its own default sweep: two radii, one of them in batches.
TOY = '''
import numpy as np

DESCRIPTION = "sweepy: inside a ball about the centroid"
REQUIRES = ["numpy"]
CAPABILITIES = {"inside": True, "distance": False, "closest_triangle": False}
PARAMETERS = [
    {"name": "scale", "type": "real", "role": "build", "default": 1.0, "min": 0.0, "max": 10.0,
     "help": "the ball's radius over the mean vertex distance"},
]
SWEEP = ["", "scale=0.50,batch=true"]


class Method:
    def __init__(self, scale=1.0):
        assert isinstance(scale, float)  # typed by the harness from the declaration
        self.scale = scale

    def build(self, V, F):
        self.c = V.mean(axis=0)
        self.r = self.scale * np.linalg.norm(V - self.c, axis=1).mean()

    def inside(self, P):
        return np.linalg.norm(P - self.c, axis=1) < self.r
'''


def run(*args, env=None, check=None):
    p = subprocess.run([str(EXE), "--quiet", *map(str, args)], capture_output=True, text=True,
                       timeout=900, env=env)
    if check is not None:
        assert p.returncode == check, f"exit {p.returncode}, expected {check}\n{p.stdout}\n{p.stderr}"
    return p


@pytest.fixture
def toy_env(tmp_path):
    folder = tmp_path / "sweepy"
    folder.mkdir()
    (folder / "method.py").write_text(TOY)
    env = dict(os.environ, BVHBENCH_PYTHON_METHODS=str(folder))
    listing = json.loads(run("methods", "--json", env=env, check=0).stdout)
    if not any(m["name"] == "sweepy" for m in listing):
        pytest.skip("this bvhbench was built without the Python host")
    return env, {m["name"]: m for m in listing}


def write_suite(path: Path, methods: str, n=60):
    path.write_text(f"""name: {path.stem}
repeat: 1
timeout_s: 120
truth: true
matrices:
  - meshes: [{{path: "{MESH}", name: cow}}]
    queries: [{{kind: random, n: {n}, seed: 1}}]
    query: [inside]
    methods: {methods}
""")
    return path


def test_methods_all_is_every_method_with_its_declared_sweep(toy_env, tmp_path):
    env, listing = toy_env
    ids = run("suite", write_suite(tmp_path / "all.yml", "all"), "--out", tmp_path / "out", "--list",
              env=env, check=0).stdout.split()
    expected = set()
    for name, m in listing.items():
        if m["testing_only"]:
            continue
        for entry in m["sweep"]:
            spec = name if not entry else f"{name}:{entry}"
            expected.add("cow__random-n60-s1__inside__" + re.sub(r"[^A-Za-z0-9.=_-]", "_", spec))
    assert set(ids) == expected
    # The toy's own sweep, as its folder declares it (the spec as written: 0.50 stays in the id).
    assert "cow__random-n60-s1__inside__sweepy" in ids
    assert "cow__random-n60-s1__inside__sweepy_scale=0.50_batch=true" in ids
    assert not any("__fault" in i for i in ids)  # testing-only methods are not in `all`
    # ebp_octree's sweep has no store (a suite has none to give) but has its coherent variant.
    assert "cow__random-n60-s1__inside__ebp_octree_coherent=true" in ids


def test_except_leaves_methods_out_and_must_name_methods(toy_env, tmp_path):
    env, listing = toy_env
    others = [n for n, m in listing.items() if not m["testing_only"] and n != "sweepy"]
    ids = run("suite", write_suite(tmp_path / "s.yml", "{all: true, except: %s}" % json.dumps(others)),
              "--out", tmp_path / "out", "--list", env=env, check=0).stdout.split()
    assert sorted(ids) == ["cow__random-n60-s1__inside__sweepy", "cow__random-n60-s1__inside__sweepy_scale=0.50_batch=true"]
    p = run("suite", write_suite(tmp_path / "bad.yml", "{all: true, except: [no_such_method]}"),
            "--out", tmp_path / "out", "--list", env=env, check=2)
    assert "no_such_method" in p.stderr and "bad.yml" in p.stderr


def test_a_new_method_folder_reaches_the_suite_results_and_the_report(toy_env, tmp_path):
    env, listing = toy_env
    # `all` but the other methods (their own tests run them): what `all` gives the toy is run.
    others = [n for n, m in listing.items() if not m["testing_only"] and n not in ("sweepy", "brute_force")]
    suite = write_suite(tmp_path / "toy_all.yml", "{all: true, except: %s}" % json.dumps(others))
    out = tmp_path / "out"
    run("suite", suite, "--out", out, env=env, check=0)
    rows = {p.stem: json.loads(p.read_text()) for p in (out / "runs").glob("*.json")}
    toy = [r for r in rows.values() if r["job"]["method"] == "sweepy"]
    assert len(toy) == 2 and all(r["status"] == "ok" for r in toy), [r["message"] for r in toy]
    # The key is printed from the typed value: the folder wrote 0.50, results group by 0.5.
    assert sorted(r["job"]["params_key"] for r in toy) == ["", "batch=true,scale=0.5"]
    proc = subprocess.run([sys.executable, str(REPORT), str(out)], capture_output=True, text=True,
                          env=dict(os.environ, MPLBACKEND="Agg"), timeout=600)
    assert proc.returncode == 0, proc.stderr
    md = (out / "report" / "report.md").read_text(encoding="utf-8")
    assert "sweepy" in md
