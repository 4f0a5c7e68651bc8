"""A result records what the dataset manifest beside its mesh says of it (job.mesh.dataset: kind
and family), so that the report knows a stress case from how it was made; only when the manifest
lists these very bytes (its sha256), and nothing when there is no manifest.

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing.
"""
from __future__ import annotations

import hashlib
import json
import shutil
import subprocess

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW

MESH = COW
pytestmark = NEEDS_RUNNER_AND_COW


def job(tmp_path, mesh):
    q, out = tmp_path / "q.npy", tmp_path / "r.json"
    if not q.exists():
        subprocess.run([str(EXE), "--quiet", "queries", "--mesh", str(mesh), "--kind", "random", "--n", "20",
                        "--out", str(q)], check=True)
    subprocess.run([str(EXE), "--quiet", "run", "--mesh", str(mesh), "--method", "brute_force", "--queries", str(q),
                    "--query", "inside", "--repeat", "1", "--out", str(out)], check=True)
    return json.loads(out.read_text())["job"]["mesh"]


def test_the_manifests_kind_is_recorded_for_the_bytes_it_lists(tmp_path):
    mesh = tmp_path / "odd_name.obj"
    shutil.copy(MESH, mesh)
    sha = hashlib.sha256(mesh.read_bytes()).hexdigest()
    assert "dataset" not in job(tmp_path, mesh)  # no manifest
    manifest = {"meshes": [{"name": "odd_name", "file": "odd_name.obj", "sha256": sha, "kind": "stress",
                            "family": "stress_flipped_patch"}]}
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    d = job(tmp_path, mesh)["dataset"]
    assert d["kind"] == "stress" and d["family"] == "stress_flipped_patch" and d["manifest"].endswith("manifest.json")
    manifest["meshes"][0]["sha256"] = "0" * 64  # the manifest describes other bytes
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    assert "dataset" not in job(tmp_path, mesh)
