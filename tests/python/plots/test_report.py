"""plots/report.py builds every chart and table from a small result set of the real runner.

The fixture (tests/fixtures/results_small: a real suite run, tests/fixtures/results_small.yml,
committed by its make_fixture.py; test_report_fixture.py checks it still matches the runner)
holds 5 methods on 2 models (cow, fandisk), an EBP-Octree sweep around its default and an OpenVDB
sweep without it, path-coherent variants, approximate OpenVDB answers, crash / timeout / oom /
error / rejected_input jobs and 4 stress meshes. Expected figures are computed here from the
fixture's own results, so that a regenerated fixture keeps the tests meaningful.
"""
import json
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
REPORT = os.path.join(ROOT, "plots", "report.py")
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "results_small")
sys.path.insert(0, os.path.join(ROOT, "plots"))

import charts  # noqa: E402
import fmt  # noqa: E402
import metrics  # noqa: E402
import results_io  # noqa: E402

# The fixture is a run on one thread: the thread-scaling chart is drawn and checked from a suite
# with a thread axis in tests/python/harness/test_threads.py.
EXPECTED_CHARTS = [name for name in charts.CHARTS if name != "thread_scaling"]
STRESS_CASES = {"spot_open", "stress_nonmanifold_edges", "stress_single_triangle", "stress_empty"}


def fixture_results():
    """{job id: parsed result} of the committed fixture."""
    runs = os.path.join(FIXTURE, "runs")
    out = {}
    for f in sorted(os.listdir(runs)):
        with open(os.path.join(runs, f), encoding="utf-8") as fh:
            r = json.load(fh)
        out[r["job"]["id"]] = r
    return out


RESULTS = fixture_results()


def qps(job_id):
    return RESULTS[job_id]["queries"]["throughput_qps"]["median"]


def table_line(md, *starts_and_parts):
    """The one Markdown table line that starts with the first string and contains the others."""
    start, *parts = starts_and_parts
    found = [l for l in md.splitlines() if l.startswith(start) and all(p in l for p in parts)]
    assert len(found) == 1, (starts_and_parts, found)
    return found[0]


def cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


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
    # Every chart the fixture has data for is drawn; the thread-scaling one says why it is not.
    not_drawn = [line for line in md.splitlines() if "Not drawn" in line]
    assert len(not_drawn) <= 1 and all("thread" in line for line in not_drawn), not_drawn
    assert "failed to draw" not in md


def test_report_states_machine_and_run(report):
    md = read(report / "report.md")
    ctx = next(iter(RESULTS.values()))["context"]
    for value in (ctx["host"], ctx["cpu_model"], ctx["git_commit"][:10], ctx["date"][:10]):
        assert value in md
    assert ctx["host"] in read(report / "paper_table.md")
    assert ctx["host"] in read(report / "paper_table.tex")


def test_paper_tables_have_ebp_row_ratios_and_published_figures(report):
    md = read(report / "paper_table.md")
    tex = read(report / "paper_table.tex")
    assert "**ebp_octree**" in md
    assert "EBP/peer" in md and "peer/EBP" in md
    # cgal_aabb on cow, random point-in-solid: the EBP-Octree's rate over CGAL's.
    ratio = qps("cow__random-n500-s1__inside__ebp_octree") / qps(
        "cow__random-n500-s1__inside__cgal_aabb")
    assert cells(table_line(md, "| cow | 5.8k | cgal_aabb |", "×"))[3] == fmt.ratio(ratio)
    assert "2.5 kHz" in md and "32 kHz" in md and "1 MHz" in md
    # A path-coherent variant is its own row, and not an EBP "peer" in the ratios.
    assert "**ebp_octree:coherent=true**" in md
    assert "| cow | 5.8k | ebp_octree:coherent=true |" not in md
    levels = RESULTS["cow__random-n500-s1__inside__ebp_octree"]["structure"]["levels"]
    assert cells(table_line(md, "| **cow** | **5.8k** | **ebp_octree** |"))[3] == f"**{levels}**"
    assert r"\textbf{ebp\_octree}" in tex
    assert r"\begin{tabular}" in tex and r"\bottomrule" in tex
    assert "EBP/peer" in tex and r"$\times$" in tex
    # A job that did not finish ok shows its status, not an empty cell (the row of the fault
    # method's representative configuration, one of its failing modes).
    rep = results_io.representative_configs(results_io.load(FIXTURE).model_jobs())["fault"]
    status = RESULTS[f"cow__random-n500-s1__inside__fault_{rep}"]["status"]
    assert status in ("crash", "timeout")
    main_table = md.split("\nRatios")[0]
    assert cells(table_line(main_table, f"| cow | 5.8k | fault:{rep} |"))[7] == status


def test_non_ok_jobs_are_listed_with_messages(report):
    md = read(report / "report.md")
    section = md.split("## Jobs that did not finish ok")[1].split("\n## ")[0]
    failed = {jid: r for jid, r in RESULTS.items() if r["status"] != "ok"}
    assert {r["status"] for r in failed.values()} == {"crash", "timeout", "oom", "error",
                                                       "rejected_input"}
    for jid, r in failed.items():
        row = table_line(section, f"| {r['status']} |", f"| {jid} |")
        assert r["message"] and r["message"] in row
    assert "SIGSEGV" in md or "Segmentation fault" in md


def _wrong(r):
    """Does an ok result break the report's accuracy tolerances? (Restated from the raw
    numbers, independently of tables.accuracy_problems.)"""
    acc = r.get("accuracy") or {}
    inside, dist = acc.get("inside") or {}, acc.get("distance") or {}
    return (inside.get("wrong_far", 0) > 0 or (dist.get("rel_error") or {}).get("max", 0) > 1e-5
            or dist.get("sign_wrong", 0) > 0 or dist.get("non_finite", 0) > 0)


def test_first_screen_answers_the_question_then_accuracy_then_pareto(report):
    """The report opens with the fastest exact method per model and query, then one accuracy
    line per method, then the speed/accuracy charts; the paper's tables come after."""
    md = read(report / "report.md")
    order = ["## Fastest exact method per model and query", "## Accuracy, per method",
             "](pareto_inside_wrong_rate.png)", "](pareto_distance_rel_err_p99.png)",
             "## The paper's tables", "## Appendix: accuracy, job by job"]
    at = [md.index(s) for s in order]
    assert at == sorted(at), list(zip(order, at))
    # No wall of warnings before the answer: the first table is the headline.
    assert md[:at[0]].count("| ") == 0


def _exact_result(r):
    return r["status"] == "ok" and r.get("accuracy") and not _wrong(r)


def test_headline_table_names_the_fastest_exact_method_and_the_ebp_ratio(report):
    """Per model, query and path, recomputed from the raw results: the fastest exact
    configuration (batch rows aside) and the EBP-Octree's fastest exact rate over the fastest
    exact rate of any other method."""
    md = read(report / "report.md")
    section = md.split("## Fastest exact method per model and query")[1].split("\n## ")[0]
    rows = [cells(l) for l in section.splitlines() if l.startswith("| ") and "---" not in l][1:]
    cellsets = {}
    for r in RESULTS.values():
        j = r["job"]
        if _exact_result(r) and j.get("threads", 1) == 1 and "batch=true" not in j["params_key"] \
                and j["mesh"]["name"] in ("cow", "fandisk"):
            cellsets.setdefault((j["mesh"]["name"], j["query"], j["queries"]["kind"]), []).append(r)
    assert len(rows) == len(cellsets) > 0
    for row in rows:
        jobs = cellsets[(row[0], row[2], row[3])]
        best = max(jobs, key=lambda r: r["queries"]["throughput_qps"]["median"])
        assert row[5] == fmt.hz(best["queries"]["throughput_qps"]["median"]), row
        star = [r for r in jobs if r["job"]["method"] == "ebp_octree"]
        other = [r for r in jobs if r["job"]["method"] != "ebp_octree"]
        if star and other:
            rate = lambda rs: max(r["queries"]["throughput_qps"]["median"] for r in rs)
            assert row[8].startswith(fmt.ratio(rate(star) / rate(other))), row


def test_accuracy_lines_one_per_method_and_the_appendix_names_the_wrong_jobs(report):
    md = read(report / "report.md")
    lines = md.split("## Accuracy, per method")[1].split("\n## ")[0]
    bullets = [l for l in lines.splitlines() if l.startswith("- ")]
    methods = {r["job"]["method"] for r in RESULTS.values()
               if r["status"] == "ok" and r.get("accuracy")
               and not r["job"]["mesh"]["name"].startswith(("stress", "spot_open"))}
    assert len([b for b in bullets if "ok job(s) ran without an oracle" not in b]) == len(methods)
    openvdb = next(b for b in bullets if b.startswith("- openvdb"))
    assert "approximate by design" in openvdb and "UNEXPECTED" not in openvdb
    worst = max(r["accuracy"]["distance"]["rel_error"]["max"] for r in RESULTS.values()
                if r["job"]["method"] == "openvdb" and r["status"] == "ok"
                and r["job"]["mesh"]["name"] in ("cow", "fandisk") and r["job"]["query"] == "distance")
    assert fmt.sci(worst) in openvdb
    # Each line names the method's own definition of inside.
    for exact, definition in (("ebp_octree", "winding number > 1/2"), ("cgal_aabb", "ray parity"),
                              ("embree", "ray parity"), ("brute_force", "generalized winding number > 0.5")):
        assert next(b for b in bullets if b.startswith(f"- {exact} (")).startswith(
            f"- {exact} ({definition}): exact on all")
    # The appendix: every wrong ok job, on models and stress cases, with its problem.
    appendix = md.split("## Appendix: accuracy, job by job")[1].split("\n## ")[0]
    listed = {cells(l)[-1] for l in appendix.splitlines() if l.startswith("| ") and "__" in l}
    expected = {jid for jid, r in RESULTS.items() if r["status"] == "ok" and _wrong(r)}
    assert listed == expected
    assert "openvdb:voxel=3" in appendix and "far from the surface" in appendix
    assert "distance error up to" in appendix and "distances with the wrong sign" in appendix
    assert "| spot_open |" in appendix
    for exact in ("ebp_octree", "cgal_aabb", "embree", "brute_force"):
        assert f"| {exact}" not in appendix


def _acc_job(method, mesh, wrong_far, key=""):
    return results_io.Job({"status": "ok", "job": {
        "method": method, "params_key": key, "query": "inside", "threads": 1,
        "mesh": {"name": mesh, "triangles": 100}, "queries": {"kind": "random", "n": 1000}},
        "accuracy": {"inside": {"wrong": wrong_far, "wrong_far": wrong_far}},
        "queries": {"throughput_qps": {"median": 1e6}}}, f"{method}_{mesh}.json")


def test_a_method_wrong_on_a_few_jobs_is_named_loudly_not_called_approximate():
    """Wrong on most of its checked jobs: approximate by design. Right on most and wrong on
    one: unexpected, in bold, with a warning sign (an exact method that failed somewhere)."""
    import headline
    jobs = ([_acc_job("sampled", m, 5) for m in "abcd"]
            + [_acc_job("exactish", m, 0) for m in "abc"] + [_acc_job("exactish", "d", 2)]
            + [_acc_job("exact", m, 0) for m in "abcd"])
    rs = results_io.ResultSet("/tmp/suite", jobs, [], [])
    lines = headline.accuracy_lines(rs)
    sampled = next(l for l in lines if "sampled" in l)
    exactish = next(l for l in lines if "exactish" in l)
    assert "approximate by design" in sampled and "UNEXPECTED" not in sampled
    assert exactish.startswith("- **\u26a0 exactish: UNEXPECTED wrong answers in 1 of 4")
    assert next(l for l in lines if "- exact:" in l).startswith("- exact: exact on all 4")
    assert headline.approximate_configs(rs) == {("sampled", "")}


def test_stability_matrix_csv_and_md(report, tmp_path):
    csv_text = read(report / "stability.csv")
    assert csv_text.splitlines()[0].startswith("query,method,mesh,status")
    for case in STRESS_CASES:
        assert f",{case}," in csv_text
    assert "cow" not in csv_text and "fandisk" not in csv_text
    assert ",rejected_input," in csv_text and ",ok_wrong," in csv_text and ",oom," in csv_text
    md = read(report / "stability.md")
    assert "**rejected_input**" in md and "**oom**" in md and "**wrong**" in md
    # One matrix: the command-line tool writes the same CSV from the same results.
    tool = os.path.join(ROOT, "tools", "stability_matrix.py")
    proc = subprocess.run([sys.executable, tool, str(report.parent), "--out", str(tmp_path)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert read(tmp_path / "stability_matrix.csv") == csv_text
    # report.md shows the matrix too, with the same cells.
    matrix = md.split("## Every cell")[0].split("| inside \\ mesh |", 1)[1]
    assert matrix in read(report / "report.md")


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
    # No method of today's runner declines a query type; a status row as run_job writes it.
    unsupported = json.loads(json.dumps(RESULTS["cow__random-n500-s1__inside__fault_mode=crash"]))
    unsupported.update(status="unsupported", message="fault does not answer inside queries")
    (runs / "unsupported.json").write_text(json.dumps(unsupported))
    proc = run_report(tmp_path, "--strict")
    assert proc.returncode == 0, proc.stderr
    md = read(tmp_path / "report" / "report.md")
    assert "signal 6" in md and "broken.json" in md and "Not drawn" in md
    assert "| unsupported |" in md and "fault does not answer inside queries" in md
    assert "Not checked (no oracle): 1 ok job(s)" in md


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
    # ebp_octree ran its defaults; openvdb did not: voxel=3 ran on both models, 1.5 on one.
    assert reps["ebp_octree"] == "" and reps["openvdb"] == "voxel=3"
    assert rs.stress_meshes == STRESS_CASES


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


def test_stress_cases_are_what_the_dataset_manifest_says():
    """The runner records the manifest's kind of a mesh (job.mesh.dataset.kind): it decides,
    whatever the mesh is called; the name rule is only for results without it."""
    def job(mesh, kind, closed=True):
        j = _job(mesh, "ok")
        j.raw["job"]["mesh"]["dataset"] = {"kind": kind, "family": "f", "manifest": "m.json", "closed": closed}
        return j
    jobs = [job("weird_shape", "stress"), job("stress_looking_name", "real"), job("a_scan", "real", False),
            _job("cow", "ok"), _job("stress_by_name", "ok")]
    assert results_io.ResultSet("/tmp/suite", jobs, [], []).stress_meshes == {"weird_shape", "a_scan",
                                                                               "stress_by_name"}


def test_a_reader_cannot_ask_for_a_field_nobody_writes():
    """Job.get takes only paths of harness/run/result_schema.json, so a chart or table reading a
    field the runner does not write fails in the first test that draws it."""
    import result_schema
    job = _job("cow", "ok")
    assert job.get("job.mesh.name") == "cow"
    assert job.get("counters.any_counter") is None          # described: counters.*
    with pytest.raises(result_schema.SchemaError, match="job.mesh.family"):
        job.get("job.mesh.family")


def test_unknown_methods_get_a_stable_colour():
    import style
    assert style.method_color("ebp_octree") == style.METHOD_COLORS["ebp_octree"]
    assert style.method_color("my_new_bvh") == style.method_color("my_new_bvh")
    assert style.method_color("my_new_bvh").startswith("#")


def test_coherent_peer_is_compared_with_the_coherent_ebp_variant(report):
    """A path-coherent peer row's ratio uses the EBP-Octree's coherent variant (same coherence on
    both sides), not its default: cow haptic inside, EBP coherent / Embree coherent."""
    peer = qps("cow__haptic-n500-s1__inside__embree_coherent=true")
    coherent = fmt.ratio(qps("cow__haptic-n500-s1__inside__ebp_octree_coherent=true") / peer)
    default = fmt.ratio(qps("cow__haptic-n500-s1__inside__ebp_octree") / peer)
    assert coherent != default, "the fixture cannot tell the two apart; regenerate it"
    md = read(report / "paper_table.md")
    line = table_line(md, "| cow", "embree:coherent=true", "×")
    assert cells(line)[4] == coherent, line


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


def test_ratios_are_never_taken_across_hosts(tmp_path):
    """A suite run on a cluster: cgal_aabb's cow jobs on one host, everything else on another.
    The tables get a Host column; cgal_aabb on cow has its rates on its host but no ratio (no
    EBP-Octree ran there), and the other peers keep their same-host ratios."""
    import tables
    results = tmp_path / "results_small"
    shutil.copytree(FIXTURE, results, ignore=shutil.ignore_patterns("*.py"))
    for f in (results / "runs").glob("*.json"):
        r = json.loads(f.read_text(encoding="utf-8"))
        apart = r["job"]["mesh"]["name"] == "cow" and r["job"]["method"] == "cgal_aabb"
        r["context"]["host"] = "node-b" if apart else "node-a"
        f.write_text(json.dumps(r), encoding="utf-8")
    (mh, mrows, _), (rh, rrows, _) = tables.paper_tables(results_io.load(str(results)))
    assert mh[0] == "Host" and rh[0] == "Host"
    assert any(r[:4] == ["node-b", "cow", "5.8k", "cgal_aabb"] for r in mrows)
    assert not any(r[1] == "cow" and r[3] == "cgal_aabb" for r in rrows)
    assert all(r[0] == "node-a" for r in rrows)
    embree = qps("cow__random-n500-s1__inside__ebp_octree") / qps("cow__random-n500-s1__inside__embree")
    assert next(r for r in rrows if r[1:4] == ["cow", "5.8k", "embree"])[4] == fmt.ratio(embree)
    import report as report_py   # the tables only: the charts are the other tests'
    report_py.build_paper(results_io.load(str(results)), str(tmp_path))
    md = read(tmp_path / "paper_table.md")
    assert "| Host | Model |" in md and "| node-b | cow | 5.8k | cgal_aabb |" in md
    assert r"\begin{tabular}{llll" in read(tmp_path / "paper_table.tex")
