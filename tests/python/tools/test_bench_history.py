"""tools/bench_history.py: step detection, and the history appended and drawn."""
import importlib.util
import json
import random

from conftest import ROOT

spec = importlib.util.spec_from_file_location("bench_history", ROOT / "tools" / "bench_history.py")
bh = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bh)


def test_a_deterministic_count_shows_every_step():
    pieces = bh.detect_steps([1000] * 6 + [1010] * 4 + [1150] * 8)
    assert [(a, b) for a, b, _ in pieces] == [(0, 6), (6, 10), (10, 18)]


def test_a_noisy_rate_shows_the_step_that_stands_out_and_no_other():
    rng = random.Random(1)
    x = [1e6 * rng.gauss(1, 0.08) for _ in range(20)] + [0.75e6 * rng.gauss(1, 0.08) for _ in range(20)]
    pieces = bh.detect_steps(x, min_noise=0.01)
    assert [(a, b) for a, b, _ in pieces] == [(0, 20), (20, 40)]
    flat = [1e6 * rng.gauss(1, 0.08) for _ in range(40)]
    assert len(bh.detect_steps(flat, min_noise=0.01)) == 1


def test_report_draws_and_names_the_step(tmp_path):
    hist = tmp_path / "history" / "abc123"
    hist.mkdir(parents=True)
    (hist / "fingerprint.json").write_text(json.dumps({"compiler": "GNU 12.2.0", "libraries": {"cgal": "5.5.1"}}))
    lines = []
    for i in range(12):
        for job, base in (("steady", 500.0), ("moved", 1000.0)):
            v = base * (1.2 if job == "moved" and i >= 7 else 1.0)
            lines.append({"commit": (f"{i:x}" * 40)[:40], "dirty": False, "date": "", "job": job, "instructions_per_query": v})
    (hist / "instructions.jsonl").write_text("".join(json.dumps(l) + "\n" for l in lines))
    assert bh.main(["report", "--history", str(tmp_path / "history"), "--out", str(tmp_path / "out")]) == 0
    md = (tmp_path / "out" / "history.md").read_text()
    assert "| moved | 12 | 1,200 | 7777777777: 1,000 -> 1,200 (+20.0%) |" in md
    assert "| steady | 12 | 500 | none |" in md
    assert (tmp_path / "out" / "abc123" / "overview.instructions_per_query.png").stat().st_size > 1000
    assert (tmp_path / "out" / "abc123" / "moved.instructions_per_query.png").exists()


def test_the_report_ends_with_the_history(tmp_path):
    # plots/report.py --history: the same section, its charts linked from the report's folder.
    import shutil
    import subprocess
    import sys
    hist = tmp_path / "history" / "abc123"
    hist.mkdir(parents=True)
    lines = [{"commit": (f"{i:x}" * 40)[:40], "dirty": False, "date": "", "job": "moved",
              "instructions_per_query": 1000.0 * (1.3 if i >= 5 else 1.0)} for i in range(10)]
    (hist / "instructions.jsonl").write_text("".join(json.dumps(l) + "\n" for l in lines))
    results = tmp_path / "results"
    shutil.copytree(ROOT / "tests" / "fixtures" / "results_small", results)
    r = subprocess.run([sys.executable, str(ROOT / "plots" / "report.py"), str(results),
                        "--history", str(tmp_path / "history")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    md = (results / "report" / "report.md").read_text()
    assert "## History across commits" in md
    assert "5555555555: 1,000 -> 1,300 (+30.0%)" in md
    assert "](history/abc123/overview.instructions_per_query.png)" in md
    assert (results / "report" / "history" / "abc123" / "overview.instructions_per_query.png").exists()
    html = (results / "report" / "report.html").read_text()
    assert "History across commits" in html
    r = subprocess.run([sys.executable, str(ROOT / "plots" / "report.py"), str(results),
                        "--history", str(tmp_path / "nothing")], capture_output=True, text=True)
    assert r.returncode == 2 and "no history" in r.stderr
