"""datasets-scripts/preset_sizes.json, the presets' declared triangle counts that `bvhbench suite`
prices a suite by before its data exists, is what `make_datasets.py --declared-sizes` writes from
the presets now: a preset changed without it would be priced at its old sizes."""
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
SCRIPT = ROOT / "datasets-scripts" / "make_datasets.py"
SIZES = ROOT / "datasets-scripts" / "preset_sizes.json"


def test_the_declared_sizes_file_is_current():
    p = subprocess.run([sys.executable, str(SCRIPT), "--declared-sizes"], capture_output=True, text=True, check=True)
    assert json.loads(p.stdout) == json.loads(SIZES.read_text()), (
        "datasets-scripts/preset_sizes.json is stale: run "
        "`.venv/bin/python datasets-scripts/make_datasets.py --declared-sizes > datasets-scripts/preset_sizes.json`")


def test_the_paper_and_huge_models_are_declared():
    sizes = json.loads(SIZES.read_text())["presets"]
    assert sizes["paper"] == {"bunny_closed_32m": 32_000_000, "scan_like_32m": 32_000_000}
    assert sizes["huge"] == {"scan_like_128m": 128_000_000}
