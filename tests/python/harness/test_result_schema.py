"""One description of a result file, harness/run/result_schema.json, and everyone who follows it.

The runner writes results (checked here on the report fixture, which test_report_fixture.py keeps
identical in its keys to what the built runner writes today), `bvhbench compare` validates them,
summary.csv takes its columns and cells from the schema, the report's readers ask only for described
fields, and docs/results.md's table is generated from it. Each test fails when one of them drifts.
"""
import ast
import csv
import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT, run

sys.path.insert(0, str(ROOT / "plots"))
import result_schema  # noqa: E402

FIXTURE = ROOT / "tests" / "fixtures" / "results_small"
# Fields that are only written when they apply and that the fixture's suite does not provoke.
CONDITIONAL = {"job.queries.mesh_mismatch": "only when a query set was made on another mesh",
               "job.params_read_from_structure": "only for a structure read from a file (an EBP-Octree store; "
                                                 "tests/python/harness/test_ebp_store_options.py)",
               # The fixture is a local run on one thread; test_suite_dask.py and test_threads.py
               # check these where they are written.
               **{f: "only in a suite run by the Dask executor"
                  for f in ("executor", "executor.name", "executor.worker", "executor.attempts")},
               **{f"queries.threads.single_thread_qps.{k}": "only for a job on more than one thread"
                  for k in ("median", "min", "max", "samples")},
               # The fixture's suite runs once; test_suite_rounds.py checks these where they are written.
               **{f: "only in a suite run in rounds (rounds: N > 1)"
                  for f in ("rounds", "rounds.count", "rounds.kept", "rounds.by_round")}}
# summary.csv columns of those fields: blank in every row of the fixture.
CONDITIONAL_COLUMNS = {c["column"] for c in result_schema.SUMMARY_COLUMNS if c.get("field") in CONDITIONAL}


def fixture_results():
    return {p.name: json.loads(p.read_text(encoding="utf-8")) for p in sorted((FIXTURE / "runs").glob("*.json"))}


def test_the_runners_results_follow_the_schema():
    results = fixture_results()
    assert len(results) > 20 and {r["status"] for r in results.values()} >= {"ok", "crash", "timeout", "error"}
    for name, r in results.items():
        assert result_schema.problems(r) == [], name


def test_every_described_field_is_written_somewhere():
    """A field described but written by no job of the fixture (every method, both queries,
    status rows) is a field the writer lost or the schema should drop."""
    seen = set()
    for r in fixture_results().values():
        seen |= {path for path, _ in result_schema._walk(r)}
    unseen = [p for p in result_schema.FIELDS if "*" not in p.split(".") and p not in seen and p not in CONDITIONAL]
    assert unseen == []


def test_problems_names_each_departure():
    r = copy.deepcopy(next(v for v in fixture_results().values() if v["status"] == "ok"))
    assert result_schema.problems(r) == []
    r["queries"]["latency_ns"]["p99"] = "fast"
    del r["memory"]["peak_rss_bytes"]
    r["job"]["colour"] = "red"
    r["counters"]["nodes_visited"] = [1]
    assert sorted(result_schema.problems(r)) == sorted([
        "queries.latency_ns.p99: must be number|null", "memory.peak_rss_bytes: missing (status ok)",
        "job.colour: not described by the schema", "counters.nodes_visited: must be number|null"])
    # A status row needs no timing block, but always its context and job.
    row = {k: v for k, v in r.items() if k in ("schema", "status", "message", "context", "job", "accuracy")}
    row["status"] = "crash"
    row["job"].pop("colour")
    assert result_schema.problems(row) == []
    del row["context"]["host"]
    assert result_schema.problems(row) == ["context.host: missing"]


def test_compare_accepts_what_the_runner_writes(bvhbench, tmp_path):
    p = run(bvhbench, "compare", str(FIXTURE), str(FIXTURE), "--timing", "report")
    assert p.returncode == 0, p.stdout + p.stderr


@pytest.mark.parametrize("edit,needle", [
    (lambda r: r["memory"].pop("query_rss_bytes"), "result without memory.query_rss_bytes (status ok)"),
    (lambda r: r["queries"]["latency_ns"].update(p99="fast"), "queries.latency_ns.p99 must be a number"),
    (lambda r: r["context"].update(cores=2.5), "context.cores must be an integer"),
    (lambda r: r["counters"].update(nodes_visited="12"), "counters.nodes_visited must be a number or null"),
    (lambda r: r["job"]["params"].update(leaf_factor=5), "job.params.leaf_factor must be a string"),
])
def test_compare_refuses_what_departs_from_the_schema(bvhbench, tmp_path, edit, needle):
    """The C++ side reads the same schema (compiled in): its verdicts match the Python one's."""
    base = tmp_path / "base" / "runs"
    base.mkdir(parents=True)
    name = "cow__random-n500-s1__inside__ebp_octree.json"
    r = json.loads((FIXTURE / "runs" / name).read_text(encoding="utf-8"))
    edit(r)
    assert result_schema.problems(r), "the edit must break the schema on the Python side too"
    (base / name).write_text(json.dumps(r), encoding="utf-8")
    p = run(bvhbench, "compare", str(tmp_path / "base"), str(FIXTURE), "--timing", "report", "--ignore-missing")
    assert p.returncode == 2 and needle in p.stderr and name in p.stderr, p.stderr


def _cell(result, column):
    """A summary.csv cell computed from the schema's rule for its column, in Python."""
    def at(path):
        v = result
        for k in path.split("."):
            v = v.get(k) if isinstance(v, dict) else None
        return v

    def num(v):
        if v is None or isinstance(v, (dict, list)):
            return None
        if isinstance(v, bool):
            return "true" if v else "false"
        return v

    if "ratio" in column:
        a, b = at(column["ratio"][0]), at(column["ratio"][1])
        return a / b if isinstance(a, (int, float)) and isinstance(b, (int, float)) and b > 0 else None
    if "share" in column:
        a, b = at(column["share"][0]), at(column["share"][1])
        ok = isinstance(a, (int, float)) and isinstance(b, (int, float)) and a + b > 0
        return a / (a + b) if ok else None
    v = at(column["field"])
    if v is None and column.get("or_stem_of"):
        p = at(column["or_stem_of"])
        return Path(p).stem if isinstance(p, str) else None
    return num(v)


def _same(cell, want):
    if want is None:
        return cell == ""
    if isinstance(want, (int, float)) and not isinstance(want, bool):
        return cell != "" and abs(float(cell) - want) <= 1e-8 * max(1.0, abs(want))
    return cell == str(want)


def test_summary_csv_is_the_schemas_columns():
    with open(FIXTURE / "summary.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    columns = result_schema.SUMMARY_COLUMNS
    with open(FIXTURE / "summary.csv", newline="", encoding="utf-8") as fh:
        assert next(csv.reader(fh)) == [c["column"] for c in columns]
    results = {r["job"]["id"]: r for r in fixture_results().values()}
    assert {row["job_id"] for row in rows} == set(results)
    for row in rows:
        for c in columns:
            want = _cell(results[row["job_id"]], c)
            assert _same(row[c["column"]], want), (row["job_id"], c["column"], row[c["column"]], want)
    # Every column is filled by some job: no column that nothing fills (but those of fields the
    # fixture's suite does not provoke).
    empty = [c["column"] for c in columns if all(row[c["column"]] == "" for row in rows)]
    assert empty == sorted(CONDITIONAL_COLUMNS, key=[c["column"] for c in columns].index)
    assert CONDITIONAL_COLUMNS == {"round", "rounds"}


def _literal_paths(tree):
    """String literals passed to .get(...), .num(...) or dig(x, ...) that look like result paths."""
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
        args = node.args[1:] if name == "dig" else node.args if name in ("get", "num") else []
        receiver = f.value.id if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) else ""
        if name in ("get", "num") and receiver not in ("j", "job", "self", "any_job", "x", "b"):
            continue
        for a in args[:1]:
            if isinstance(a, ast.Constant) and isinstance(a.value, str) and a.value:
                out.append((node.lineno, a.value))
    return out


def test_the_report_reads_only_described_fields():
    found = 0
    for py in sorted((ROOT / "plots").glob("*.py")):
        for line, path in _literal_paths(ast.parse(py.read_text(encoding="utf-8"))):
            if path.endswith("."):   # a prefix completed at run time ("accuracy." + path)
                continue
            found += 1
            assert result_schema.describe(path) is not None, f"{py.name}:{line}: {path!r}"
    assert found > 20, "the scan found too few field reads to be looking at the right calls"


def test_docs_field_table_is_generated_from_the_schema():
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "result_schema_doc.py"), "--check"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
