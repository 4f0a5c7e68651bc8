"""tools/headline_table.py (the table of plots/headline_targets.py) on a made-up run of suites/headline.yml: the contact rows take each
query set's band and speed from its sidecar, so results on paths of the same kind but different
bands stay apart, and each row's ratios are the right pair's."""
import json
import subprocess
import sys

from conftest import ROOT


def result(out, mesh, kind, label, query, spec, qps, tris=1000):
    path = f"{out}/data/queries/{mesh}__{label}.npy"
    r = {
        "status": "ok",
        "job": {"mesh": {"path": f"data/{mesh}.ply", "triangles": tris},
                "queries": {"kind": kind, "n": 20000, "path": path},
                "query": query, "method_spec": spec,
                "params": {"store": None}},
        "context": {"date": "2026-12-03T00:00:00Z"},
        "queries": {"throughput_qps": {"median": qps}},
        "memory": {"structure_bytes": 100 * tris},
    }
    name = f"{mesh}__{label}__{query}__{spec}".replace(":", "_").replace("=", "_").replace(",", "_")
    (out / "runs" / f"{name}.json").write_text(json.dumps(r))


def sidecar(out, mesh, label, kind, params):
    (out / "data" / "queries" / f"{mesh}__{label}.json").write_text(
        json.dumps({"kind": kind, "n": 20000, "seed": 1, "params": params}))


def test_contact_rows_per_band_and_speed(tmp_path):
    out = tmp_path / "headline"
    (out / "runs").mkdir(parents=True)
    (out / "data" / "queries").mkdir(parents=True)
    sidecar(out, "cow", "haptic-n20000-s1", "haptic", {"band_mm": 0.5, "slide_speed": 0.1})
    result(out, "cow", "haptic", "haptic-n20000-s1", "distance", "ebp_octree:coherent=true", 3e6)
    result(out, "cow", "haptic", "haptic-n20000-s1", "distance", "embree:coherent=true", 1e6)
    result(out, "cow", "haptic", "haptic-n20000-s1", "distance", "ebp_octree", 1.5e6)
    result(out, "cow", "haptic", "haptic-n20000-s1", "distance", "embree", 1e6)
    # Two contact paths: their labels differ only by the parameters' hash.
    sidecar(out, "cow", "contact-n20000-s1-aaaa", "contact", {"band_mm": 0.05, "slide_speed": 0.1})
    sidecar(out, "cow", "contact-n20000-s1-bbbb", "contact", {"band_mm": 0.5, "slide_speed": 0.3})
    for label, auto, plain, emb in [("contact-n20000-s1-aaaa", 4e6, 5e6, 1e6),
                                    ("contact-n20000-s1-bbbb", 1e6, 0.5e6, 2e6)]:
        result(out, "cow", "contact", label, "distance", "ebp_octree:coherent=true", auto)
        result(out, "cow", "contact", label, "distance", "ebp_octree:coherent=true,certificate=false", plain)
        result(out, "cow", "contact", label, "distance", "embree:coherent=true", emb)
    result(out, "cow", "contact", "contact-n20000-s1-aaaa", "distance", "ebp_octree", 3e5)
    result(out, "cow", "contact", "contact-n20000-s1-aaaa", "distance", "embree", 6e5)
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "headline_table.py"), str(out)],
                       capture_output=True, text=True, check=True)
    lines = p.stdout.splitlines()
    rows = [line for line in lines if line.startswith("| cow |")]
    assert len(rows) == 2, p.stdout
    # Band 0.05: the best EBP variant (plain, 5 M) over Embree coherent (1 M); not coherent 0.5x.
    assert rows[0].startswith("| cow | 0.05 | 0.1 | 4.00 M | 5.00 M | 1.00 M | 5.00× ✔ | 0.50× ✘ |"), rows[0]
    # Band 0.5 at 0.3 m/s: 1 M against 2 M; no run without coherence.
    assert rows[1].startswith("| cow | 0.5 | 0.3 | 1.00 M | 500 k | 2.00 M | 0.50× ✘ | — |"), rows[1]
    # The haptic row is the haptic path's alone (3x), not mixed with a contact path's; then the
    # haptic path without coherence (1.5x), beside it.
    assert any(line.startswith("| cow (1,000) | 3.00 M |") and "| 3.00× ✔ | 1.50× ✔ |" in line for line in lines), p.stdout


def test_ratio_mark_agrees_with_its_figure():
    sys.path.insert(0, str(ROOT / "plots"))
    import headline_targets as headline_table
    assert headline_table.fmt_ratio(1.995, 1.0, 2.0) == "1.99× ✘"
    assert headline_table.fmt_ratio(2.0, 1.0, 2.0) == "2.00× ✔"
    assert headline_table.fmt_ratio(0.29, 1.0) == "0.29×"  # rounded, not truncated: 0.29 * 100 < 29
    assert headline_table.fmt_ratio(1.006, 1.0) == "1.01×"
    assert headline_table.fmt_ratio(0.9999, 1.0, 1.0) == "0.99× ✘"
    assert headline_table.fmt_ratio(1.0, None) == "—"


def test_the_same_table_in_instructions(tmp_path):
    """With --instructions the figures are each job's instructions per query (instructions.json of
    tools/instr_gate.py, by the result file's job id) and each ratio is Embree's count over the
    EBP-Octree's: fewer instructions read as the higher ratio, as a higher rate does."""
    out = tmp_path / "instr"
    (out / "runs").mkdir(parents=True)
    (out / "data" / "queries").mkdir(parents=True)
    sidecar(out, "cow", "contact-n20000-s1-aaaa", "contact", {"band_mm": 0.2, "slide_speed": 0.3})
    counts = {}
    for spec, ipq in [("ebp_octree:coherent=true", 2000), ("ebp_octree:coherent=true,certificate=false", 1600),
                      ("embree:coherent=true", 4000), ("ebp_octree", 5000), ("embree", 4000)]:
        result(out, "cow", "contact", "contact-n20000-s1-aaaa", "distance", spec, qps=123.0)  # valgrind's rate: unread
        jid = f"cow__contact-n20000-s1-aaaa__distance__{spec}".replace(":", "_").replace("=", "_").replace(",", "_")
        counts[jid] = ipq
    (out / "instructions.json").write_text(json.dumps(
        {"jobs": [{"id": k, "status": "ok", "instructions_per_query": v} for k, v in counts.items()]}))
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "headline_table.py"), "--instructions", str(out)],
                       capture_output=True, text=True, check=True)
    assert p.stdout.startswith("Instructions per query"), p.stdout
    (row,) = [line for line in p.stdout.splitlines() if line.startswith("| cow |")]
    # best EBP (1,600) against Embree coherent (4,000): 2.5x; not coherent 4,000 / 5,000 = 0.8x
    assert row == "| cow | 0.2 | 0.3 | 2,000 | 1,600 | 4,000 | 2.50× ✔ | 0.80× ✘ |", row
    bad = subprocess.run([sys.executable, str(ROOT / "tools" / "headline_table.py"), "--instructions", str(tmp_path)],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "headline_table:" in bad.stderr
    # results, but no instruction measurement beside them: named, exit 2
    (out / "instructions.json").unlink()
    missing = subprocess.run([sys.executable, str(ROOT / "tools" / "headline_table.py"), "--instructions", str(out)],
                             capture_output=True, text=True)
    assert missing.returncode == 2 and "instructions.json: not an instruction measurement" in missing.stderr
