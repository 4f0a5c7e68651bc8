"""plots/report.py builds every chart and table from a small fixture result set.

The fixture (tests/fixtures/results_small, written by its make_fixture.py) holds 5 methods on
2 models, an EBP-Octree and an OpenVDB sweep, unsupported / crash / timeout / oom / error jobs,
OpenVDB jobs with wrong answers, and 3 stress meshes.
"""
import json
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
REPORT = os.path.join(ROOT, "plots", "report.py")
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "results_small")
sys.path.insert(0, os.path.join(ROOT, "plots"))

import charts  # noqa: E402
import metrics  # noqa: E402
import results_io  # noqa: E402

EXPECTED_CHARTS = list(charts.CHARTS)


def run_report(results, *extra):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, REPORT, str(results), *extra], capture_output=True,
                          text=True, env=env, timeout=300)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The fixture result set copied to a temporary folder, and its report built there."""
    results = tmp_path_factory.mktemp("results") / "results_small"
    shutil.copytree(FIXTURE, results, ignore=shutil.ignore_patterns("*.py"))
    proc = run_report(results, "--strict")
    assert proc.returncode == 0, proc.stderr
    return results / "report"


def read(path):
    return path.read_text(encoding="utf-8")


def test_every_chart_is_written_as_png_and_svg(report):
    for name in EXPECTED_CHARTS:
        for ext in ("png", "svg"):
            f = report / f"{name}.{ext}"
            assert f.is_file(), f"{f.name} missing"
            assert f.stat().st_size > 1000, f"{f.name} is (nearly) empty"
    assert (report / "pareto_inside_wrong_rate.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_md_shows_every_chart(report):
    md = read(report / "report.md")
    for name in EXPECTED_CHARTS:
        assert f"]({name}.png)" in md, f"report.md does not show {name}"
    assert "Not drawn" not in md and "failed to draw" not in md


def test_report_states_machine_and_run(report):
    md = read(report / "report.md")
    assert "bench-1" in md and "E5-2680" in md and "3f9c2a1b7e" in md and "2026-11-20" in md
    assert "bench-1" in read(report / "paper_table.md")
    assert "bench-1" in read(report / "paper_table.tex")


def test_paper_tables_have_ebp_row_ratios_and_published_figures(report):
    md = read(report / "paper_table.md")
    tex = read(report / "paper_table.tex")
    assert "**ebp_octree**" in md
    assert "EBP/peer" in md and "peer/EBP" in md
    # cgal_aabb on bunny: 180 kHz / 72 kHz random point-in-solid = 2.5x for the EBP-Octree.
    cgal_bunny = next(line for line in md.splitlines()
                      if line.startswith("| bunny") and "cgal_aabb" in line and "×" in line)
    assert "| 2.5× |" in cgal_bunny
    assert "2.5 kHz" in md and "32 kHz" in md and "1 MHz" in md
    # A path-coherent variant is its own row, and not an EBP "peer" in the ratios.
    assert "**ebp_octree:coherent=true**" in md
    assert "| bunny | 69.5k | ebp_octree:coherent=true |" not in md
    assert "| 7 |" in md.split("**bunny**")[0] or "**7**" in md   # octree levels
    assert r"\textbf{ebp\_octree}" in tex
    assert r"\begin{tabular}" in tex and r"\bottomrule" in tex
    assert "EBP/peer" in tex and r"$\times$" in tex
    # A crashed or timed-out job shows its status, not an empty cell.
    assert "crash" in md and "timeout" in md


def test_non_ok_jobs_are_listed_with_messages(report):
    md = read(report / "report.md")
    section = md.split("## Jobs that did not finish ok")[1]
    for status, message in [("unsupported", "capability 'distance' not provided"),
                            ("crash", "SIGSEGV"), ("timeout", "time limit of 600 s"),
                            ("oom", "address-space limit"), ("error", "plane fit failed")]:
        row = next((l for l in section.splitlines() if l.startswith(f"| {status} |")), None)
        assert row is not None, f"no {status} row"
        assert message in row


def test_accuracy_warnings_come_first_and_name_the_wrong_jobs(report):
    md = read(report / "report.md")
    assert md.index("## Accuracy warnings") < md.index("## The paper's tables")
    warnings = md.split("## Accuracy warnings")[1].split("\n## ")[0]
    assert "openvdb:voxel=0.01" in warnings and "far from the surface" in warnings
    assert "distance error up to" in warnings
    assert "stress_duplicate" in warnings            # ebp_octree wrong far on a stress case
    assert "| cgal_aabb |" not in warnings            # exact methods are not accused
    assert "spot_noisy__random-n10000-s1__inside__embree" in warnings   # no oracle: said so


def test_stability_matrix_csv_and_md(report):
    csv_text = read(report / "stability.csv")
    assert csv_text.splitlines()[0].startswith("query,method,mesh,status")
    assert "stress_duplicate" in csv_text and ",oom," in csv_text
    assert "spot_noisy" in csv_text                   # stress case known by metadata only
    assert "bunny" not in csv_text and "lucy" not in csv_text
    assert "oom" in read(report / "stability.md")


def test_missing_runs_dir_is_a_clear_error(tmp_path):
    proc = run_report(tmp_path)
    assert proc.returncode == 2
    assert "runs" in proc.stderr and "Traceback" not in proc.stderr
    proc = run_report(tmp_path / "nonexistent")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_empty_runs_dir_is_a_clear_error(tmp_path):
    (tmp_path / "runs").mkdir()
    proc = run_report(tmp_path)
    assert proc.returncode == 2
    assert "no result files" in proc.stderr and "Traceback" not in proc.stderr


def test_sparse_and_broken_results_do_not_break_the_report(tmp_path):
    """Only failed jobs, a job without optional blocks, and an unreadable file."""
    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / "broken.json").write_text("{not json")
    (runs / "failed.json").write_text(json.dumps({
        "schema": "bvhbench.result/1", "status": "crash", "message": "signal 6",
        "job": {"method": "newmethod", "query": "inside",
                "mesh": {"name": "cow", "triangles": 5804}, "queries": {"kind": "haptic"}}}))
    (runs / "bare.json").write_text(json.dumps({
        "status": "ok", "accuracy": None,
        "job": {"method": "newmethod", "query": "distance",
                "mesh": {"name": "cow", "triangles": 5804}, "queries": {"kind": "random", "n": 10}},
        "queries": {"throughput_qps": {"median": 1000.0}}}))
    proc = run_report(tmp_path, "--strict")
    assert proc.returncode == 0, proc.stderr
    md = read(tmp_path / "report" / "report.md")
    assert "signal 6" in md and "broken.json" in md and "Not drawn" in md


def test_pareto_front():
    pts = [(0.0, 10, "a"), (0.0, 20, "b"), (1e-3, 50, "c"), (1e-2, 40, "d"), (1e-1, 60, "e")]
    front = metrics.pareto_front(pts, "lower", "higher")
    assert [p[2] for p in front] == ["b", "c", "e"]


def test_every_metric_declares_a_direction():
    for m in metrics.METRICS.values():
        assert m.better in ("higher", "lower") and m.unit


def test_representative_config_prefers_defaults(tmp_path):
    rs = results_io.load(FIXTURE)
    reps = results_io.representative_configs(rs.model_jobs())
    assert reps["ebp_octree"] == "" and reps["openvdb"] == "voxel=0.01"
    assert rs.stress_meshes == {"stress_degenerate", "stress_duplicate", "spot_noisy"}


def _job(mesh, status, method="m"):
    return results_io.Job({"status": status, "job": {
        "method": method, "query": "inside", "mesh": {"name": mesh, "triangles": 100},
        "queries": {"kind": "random"}}}, f"{mesh}.json")


def test_stress_suite_recognised_by_its_failures():
    """Meshes with unremarkable names, most of whose jobs fail: a stress suite."""
    jobs = [_job(m, s) for m in ("a", "b", "c", "d") for s in ("ok", "crash", "timeout")]
    rs = results_io.ResultSet("/tmp/suite", jobs, [], [])
    assert rs.stress_meshes == {"a", "b", "c", "d"}
    # One failure among many ok jobs does not make a stress suite.
    jobs = [_job(m, "ok") for m in ("a", "b", "c", "d") for _ in range(5)] + [_job("a", "crash")]
    assert results_io.ResultSet("/tmp/suite", jobs, [], []).stress_meshes == set()
    # The suite's name says so.
    assert results_io.ResultSet("/tmp/stability", jobs, [], []).stress_meshes == {"a", "b", "c",
                                                                                  "d"}


def test_unknown_methods_get_a_stable_colour():
    import style
    assert style.method_color("ebp_octree") == style.METHOD_COLORS["ebp_octree"]
    assert style.method_color("my_new_bvh") == style.method_color("my_new_bvh")
    assert style.method_color("my_new_bvh").startswith("#")


def test_coherent_peer_is_compared_with_the_coherent_ebp_variant(tmp_path):
    """A path-coherent peer row's ratio uses the EBP-Octree's coherent variant (same coherence on
    both sides), not its default: bunny haptic inside, EBP coherent 1.6 MHz / Embree coherent
    800 kHz = 2x (against the default EBP's 900 kHz it would be 1.12x)."""
    results = tmp_path / "results_small"
    shutil.copytree(FIXTURE, results, ignore=shutil.ignore_patterns("*.py"))
    src = results / "runs" / "bunny__haptic-n20000-s1__inside__embree.json"
    r = json.loads(src.read_text())
    r["job"]["id"] += "-coherent=true"
    r["job"]["method_spec"] = "embree:coherent=true"
    r["job"]["params"]["coherent"] = "true"
    r["job"]["params_key"] = "coherent=true"
    tq = r["queries"]["throughput_qps"]
    tq.update(median=800000.0, min=790000.0, max=810000.0, samples=[790000.0, 800000.0, 810000.0])
    (results / "runs" / (r["job"]["id"] + ".json")).write_text(json.dumps(r))
    proc = run_report(results)
    assert proc.returncode == 0, proc.stderr
    md = read(results / "report" / "paper_table.md")
    line = next(x for x in md.splitlines() if x.startswith("| bunny") and "embree:coherent=true" in x and "×" in x)
    assert line.split("|")[5].strip() == "2×", line


def test_median_is_the_harness_median():
    """One median for tables, charts and the representative configuration, computed as the
    harness computes its own (the middle two averaged)."""
    assert results_io.median([3.0, None, 1.0, 2.0]) == 2.0
    assert results_io.median([4.0, 1.0, 2.0, 3.0]) == 2.5
    assert results_io.median([None]) is None and results_io.median([]) is None


def test_non_finite_distances_are_wrong_answers():
    """The harness keeps NaN and infinite distances out of the error statistics, so a job that
    answered only NaN has no error to speak of: it must be flagged by its count."""
    import tables
    job = results_io.Job({"status": "ok", "job": {"method": "m", "query": "distance"},
                          "accuracy": {"distance": {"rel_error": {"max": 0.0, "p99": 0.0},
                                                    "sign_wrong": 0, "non_finite": 3}}}, "m.json")
    assert tables.accuracy_problems(job) == ["3 non-finite distances (NaN or infinite)"]
