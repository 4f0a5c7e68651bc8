"""Malformed files never end in an internal error: small valid meshes and query sets with a few
bytes changed (0xFF among them, so that header lines stop being UTF-8) are either still valid
(exit 0) or refused with exit 2, a message that names the file, and a `rejected_input` result."""
import json
import os
import random
import shutil

import numpy as np
import pytest

from conftest import ROOT, run

FIXTURES = ROOT / "tests" / "fixtures" / "meshes"
VARIANTS = 40  # per file; each run takes a few milliseconds


def mutate(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        i = rng.randrange(len(b))
        b[i] = rng.choice([0xFF, 0xFE, 0x80, 0x00, rng.randrange(256)])
    return bytes(b)


@pytest.fixture(scope="module")
def queries(bvhbench, tmp_path_factory):
    d = tmp_path_factory.mktemp("q")
    q = d / "q.npy"
    run(bvhbench, "queries", "--mesh", FIXTURES / "good_ascii.ply", "--kind", "random", "--n", 20, "--seed", 3,
        "--out", q, check=0)
    return q


def check_run(bvhbench, tmp_path, mesh, queries, named):
    out = tmp_path / "r.json"
    out.unlink(missing_ok=True)
    p = run(bvhbench, "run", "--mesh", mesh, "--method", "brute_force", "--queries", queries, "--query", "distance",
            "--repeat", 1, "--quiet", "--out", out)
    assert p.returncode in (0, 2), f"exit {p.returncode} for {named}\n{p.stderr}"
    r = json.loads(out.read_text(encoding="utf-8"))  # valid UTF-8 JSON, whatever the file held
    if p.returncode == 2:
        assert r["status"] == "rejected_input", r
        assert str(named) in r["message"] and str(named) in p.stderr, (r["message"], p.stderr)
        assert "json.exception" not in p.stderr
    else:
        assert r["status"] == "ok", r


@pytest.mark.parametrize("name", ["good_ascii.ply", "good_binary_be.ply", "good_binary_le_double.ply", "good.obj",
                                  "good_tristrips_be.ply", "good_tristrips_ascii.ply", "good_binary.stl", "good_ascii.stl",
                                  "good.off", "good_coff.off"])
def test_mutated_meshes_are_refused_cleanly(bvhbench, tmp_path, queries, name):
    rng = random.Random(name)
    data = (FIXTURES / name).read_bytes()
    mesh = tmp_path / name
    for _ in range(VARIANTS):
        mesh.write_bytes(mutate(data, rng))
        check_run(bvhbench, tmp_path, mesh, queries, mesh)


def test_mutated_query_sets_are_refused_cleanly(bvhbench, tmp_path, queries):
    rng = random.Random("npy")
    data = queries.read_bytes()
    q = tmp_path / "m.npy"
    shutil.copy(queries.with_suffix(".json"), q.with_suffix(".json"))
    for _ in range(VARIANTS):
        q.write_bytes(mutate(data, rng))
        check_run(bvhbench, tmp_path, FIXTURES / "good_ascii.ply", q, q)


def test_a_non_utf8_header_line_is_quoted_escaped(bvhbench, tmp_path, queries):
    mesh = tmp_path / "bad.ply"
    mesh.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flo\xffat x\nend_header\n")
    out = tmp_path / "r.json"
    p = run(bvhbench, "run", "--mesh", mesh, "--method", "brute_force", "--queries", queries, "--out", out, check=2)
    r = json.loads(out.read_text(encoding="utf-8"))
    assert r["status"] == "rejected_input"
    assert "'flo\\xFFat'" in r["message"] and "'flo\\xFFat'" in p.stderr
    assert str(mesh) in r["message"]


def test_non_utf8_bytes_reach_messages_escaped(bvhbench, tmp_path):
    """A file name and contents that are not UTF-8, through compare, suite and run (text points):
    exit 2, stderr decodes as UTF-8 (run() decodes strictly), and the file and the quoted bytes
    are named escaped, in the message and in the result JSON."""
    ff = os.fsdecode(b"\xff")  # a file name byte that is not UTF-8
    result = tmp_path / f"r{ff}.json"
    result.write_bytes(b'{"schema": "bvhbench.result/1", "status": "o\xfek"}')
    p = run(bvhbench, "compare", result, result, check=2)
    assert "r\\xFF.json: malformed JSON" in p.stderr, p.stderr
    suite = tmp_path / f"s{ff}.yml"
    suite.write_bytes(b"matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    methods: [br\xfeute]\n")
    p = run(bvhbench, "suite", suite, "--out", tmp_path / "out", "--list", check=2)
    assert "s\\xFF.yml" in p.stderr and "br\\xFEute" in p.stderr, p.stderr
    points = tmp_path / f"p{ff}.xyz"
    points.write_bytes(b"1 2 3\n4 5 \xfe6\n")
    out = tmp_path / "r.json"
    p = run(bvhbench, "run", "--mesh", FIXTURES / "good_ascii.ply", "--method", "brute_force", "--queries", points,
            "--out", out, check=2)
    r = json.loads(out.read_text(encoding="utf-8"))
    assert r["status"] == "rejected_input"
    assert "p\\xFF.xyz: line 2: '\\xFE6' in column 3 is not a number" in r["message"], r["message"]
    assert "p\\xFF.xyz" in p.stderr
