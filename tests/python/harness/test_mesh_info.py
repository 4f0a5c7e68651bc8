"""`bvhbench mesh-info`: every field of the JSON (and the text) against what the file holds,
computed independently here (hashlib, numpy) where it can be."""
import hashlib
import json

import numpy as np
import pytest

from conftest import ROOT, run

FIXTURES = ROOT / "tests" / "fixtures" / "meshes"


def info(bvhbench, path):
    return json.loads(run(bvhbench, "mesh-info", path, "--json", check=0).stdout)


def test_format_variant_counts_and_sha256(bvhbench):
    for name, fmt, variant, polygons in [("good_binary_be.ply", "ply", "binary_big_endian", 2),
                                         ("good_ascii.ply", "ply", "ascii", 2), ("good.obj", "obj", "", 4),
                                         ("good_binary.stl", "stl", "binary", 3), ("good_ascii.stl", "stl", "ascii", 3),
                                         ("good_coff.off", "off", "COFF", 2), ("good_stcnoff.off", "off", "STCNOFF", 2)]:
        j = info(bvhbench, FIXTURES / name)
        assert (j["format"], j["variant"], j["polygons"]) == (fmt, variant, polygons), name
        assert j["sha256"] == hashlib.sha256((FIXTURES / name).read_bytes()).hexdigest(), name
        assert j["path"] == str(FIXTURES / name)


def test_vertices_triangles_and_polygons_triangulated(bvhbench):
    j = info(bvhbench, FIXTURES / "good.off")  # a quad and a triangle
    assert (j["vertices"], j["triangles"], j["polygons"], j["polygons_triangulated"]) == (5, 3, 2, 1)
    j = info(bvhbench, FIXTURES / "good.obj")  # a quad, two triangles, a pentagon; 7 vertices
    assert (j["vertices"], j["triangles"], j["polygons_triangulated"]) == (7, 7, 2)


def test_stl_welds_corners(bvhbench):
    j = info(bvhbench, FIXTURES / "good_ascii.stl")
    assert (j["stl_corners"], j["vertices"], j["stl_solids"]) == (9, 5, 2)


def test_strip_joins_dropped(bvhbench):
    j = info(bvhbench, FIXTURES / "good_tristrips_be.ply")
    assert (j["strips"], j["strip_joins_dropped"], j["triangles"], j["polygons"]) == (2, 2, 3, 0)


def test_bounds_are_exact(bvhbench):
    j = info(bvhbench, FIXTURES / "good_binary_le_double.ply")
    assert j["bounds"] == {"min": [0, 0, 0], "max": [1, 1, 0.3]}
    j = info(bvhbench, FIXTURES / "good_binary_be.ply")  # float32 coordinates, kept exactly
    assert j["bounds"]["max"] == [1, 1, float(np.float32(0.3))]


def test_closed_means_every_edge_twice_once_each_way(bvhbench, shared_meshes):
    for name in ["cow.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"]:
        j = info(bvhbench, shared_meshes / name)
        assert j["closed"] and j["edges_balanced"], name
        assert (j["boundary_edges"], j["nonmanifold_edges"], j["misoriented_edges"]) == (0, 0, 0)
    j = info(bvhbench, shared_meshes / "stanford-bunny.obj")  # holes in the base
    assert not j["closed"] and j["boundary_edges"] > 0
    j = info(bvhbench, FIXTURES / "good_ascii.ply")  # the triangle on the square's edge, same direction
    assert not j["closed"] and j["misoriented_edges"] == 1


def test_degenerate_and_unreferenced(bvhbench, shared_meshes):
    j = info(bvhbench, FIXTURES / "degenerate.obj")  # collinear, the same again, a repeated vertex
    assert j["degenerate_triangles"] == 3
    j = info(bvhbench, shared_meshes / "stanford-bunny.obj")
    assert j["unreferenced_vertices"] == 1113 and j["degenerate_triangles"] == 0


def test_text_output_names_every_field(bvhbench):
    out = run(bvhbench, "mesh-info", FIXTURES / "good_tristrips_be.ply", check=0).stdout
    for key in ["mesh", "format", "sha256", "vertices", "triangles", "polygons", "strips", "bounds", "closed",
                "degenerate"]:
        assert any(line.split()[0] == key for line in out.splitlines()), key
    assert "PLY (binary_big_endian)" in out and "2 joins dropped" in out and "closed       no:" in out


@pytest.mark.parametrize("name,problem", [("bad_nan.stl", "has a NaN coordinate"), ("no_such_file.off", "not found"),
                                          ("bad_truncated.off", "truncated")])
def test_bad_files_exit_2(bvhbench, name, problem):
    p = run(bvhbench, "mesh-info", FIXTURES / name, check=2)
    assert name in p.stderr and problem in p.stderr and p.stdout == ""
