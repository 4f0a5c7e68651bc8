"""Shared pytest fixtures: where the built runner and the shared meshes are."""
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED_MESHES = Path(os.environ.get("BVHBENCH_SHARED_MESHES", ROOT.parent / "shared" / "meshes"))


def _exe():
    env = os.environ.get("BVHBENCH_EXE")
    return Path(env) if env else ROOT / "build" / "bvhbench"


EXE = _exe()
COW = SHARED_MESHES / "cow.obj"
# The module marks (`pytestmark = NEEDS_RUNNER_AND_COW`) of the tests that drive the built runner on
# the shared cow.obj: skipped, saying which is missing, where either is.
NEEDS_RUNNER_AND_COW = [
    pytest.mark.skipif(not EXE.exists(), reason=f"bvhbench binary not found at {EXE} (set BVHBENCH_EXE)"),
    pytest.mark.skipif(not COW.exists(), reason=f"test mesh {COW} not found"),
]


@pytest.fixture(scope="session")
def bvhbench():
    """Path of the built runner; tests that need it are skipped when it was not built."""
    exe = _exe()
    if not exe.exists():
        pytest.skip(f"runner not built: {exe} (run `make build` or set BVHBENCH_EXE)")
    return exe


@pytest.fixture(scope="session")
def shared_meshes():
    if not SHARED_MESHES.is_dir():
        pytest.skip(f"shared meshes not found at {SHARED_MESHES}")
    return SHARED_MESHES


def run(exe, *args, check=None, **kw):
    """Runs the runner; returns CompletedProcess with text output."""
    p = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=600, **kw)
    if check is not None:
        assert p.returncode == check, f"exit {p.returncode}, expected {check}\nstdout:{p.stdout}\nstderr:{p.stderr}"
    return p
