"""Acceptance: the mesh files people really have, read as the same mesh as its PLY.

- A tristrip PLY shaped like igea.ply (binary big endian, `confidence` and `intensity` per
  vertex, one `tristrips` item of `list int int` with -1 restarts, joins and real strip
  continuations, so that odd triangles are flipped), stripified here from the Stanford bunny.
- A binary STL (trimesh's, once with its header rewritten to start with "solid": the classic
  trap), an ASCII STL (trimesh's) and OFF files (trimesh's and one written here, COFF with
  comments) of a closed model.

Each runs through `bvhbench run` (brute_force and ebp_octree, inside and distance, random and
haptic queries) with answers (`--answers`) that must equal, bit for bit, those of the same mesh
read from a face-list PLY; `mesh-info` must say closed for the closed model, and count the joins.
The "same mesh" is the model with float32 coordinates and its vertices welded exactly, numbered
in order of first use: what an STL reader must give back (docs/meshes.md).
"""
import hashlib
import json
import shutil

import numpy as np
import pytest
import trimesh

from conftest import run

pytestmark = pytest.mark.usefixtures("shared_meshes")

METHODS = ["brute_force", "ebp_octree"]


def read_obj(path):
    """The `v` and `f` lines of a plain OBJ (triangles, 1-based indices)."""
    v, f = [], []
    for line in open(path, encoding="utf-8"):
        t = line.split()
        if t and t[0] == "v":
            v.append([float(x) for x in t[1:4]])
        elif t and t[0] == "f":
            f.append([int(x.split("/")[0]) - 1 for x in t[1:]])
    return np.array(v), np.array(f, dtype=np.int64)


def canonical(v, f):
    """float32 coordinates, corners welded exactly, vertices in order of first use."""
    corners = v.astype(np.float32)[f.ravel()] + np.float32(0.0)  # -0 + 0 = +0: welded alike
    uniq, first, inverse = np.unique(corners, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    return uniq[order].astype(np.float64), rank[inverse.ravel()].reshape(-1, 3)


def write_face_ply(path, v, f):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(v), len(f)))
    rec = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", 3)])
    rec["n"], rec["i"] = 3, f
    path.write_bytes(head.encode() + v.astype("<f4").tobytes() + rec.tobytes())


def decode_strips(strip):
    """The triangles of a -1-separated strip list (OpenGL/VCG: odd ones (v[k+1], v[k], v[k+2])),
    dropping those with a repeated index; also the runs between restarts and the join count."""
    tris, runs, joins, cur = [], [], 0, []
    for x in list(strip) + [-1]:
        if x == -1:
            if cur:
                runs.append(cur)
            cur = []
            continue
        cur.append(int(x))
        k = len(cur) - 3
        if k >= 0:
            a, b, c = cur[k:k + 3]
            if a == b or b == c or a == c:
                joins += 1
            else:
                tris.append((a, b, c) if k % 2 == 0 else (b, a, c))
    return np.array(tris, dtype=np.int64), runs, joins


def stripify(f, restart_every=7):
    """f's triangles as one strip list, greedily: a strip goes on while the triangle across the
    edge it needs next is unused (one index each: even ones as they are, odd ones flipped); a new
    strip starts after a -1 (every `restart_every`-th) or after a join (the last index and the new
    triangle's first, repeated). Returns the list and how many triangles sit at odd positions."""
    across = {}  # directed edge -> the triangle that has it
    for i, t in enumerate(f.tolist()):
        for j in range(3):
            across[(t[j], t[(j + 1) % 3])] = i
    used = np.zeros(len(f), dtype=bool)
    strip, run, flipped, starts = [], 0, 0, 0
    for s, t in enumerate(f.tolist()):
        if used[s]:
            continue
        if not strip:
            strip += t
            run = 3
        elif starts % restart_every == 0:
            strip += [-1] + t
            run = 3
        else:
            last, a = strip[-1], t[0]
            pad = [last, a, a] + ([a] if (run + 2) % 2 else [])  # the last `a` at an even position
            strip += pad + t[1:]
            run += len(pad) + 2
        used[s] = True
        starts += 1
        while True:
            k = run - 2  # the window a new entry would end
            p, q = (strip[-2], strip[-1]) if k % 2 == 0 else (strip[-1], strip[-2])
            i = across.get((p, q))
            if i is None or used[i]:
                break
            strip.append(next(x for x in f[i].tolist() if x != p and x != q))
            used[i] = True
            run += 1
            flipped += k % 2
    return np.array(strip, dtype=np.int64), flipped


def same_up_to_rotation(x, y):
    """The same triangles, each with the same orientation (any starting corner), in any order."""
    def keys(ts):
        return sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in np.asarray(ts))
    return len(x) == len(y) and keys(x) == keys(y)


def write_strip_ply(path, v, strip):
    head = ("ply\nformat binary_big_endian 1.0\ncomment stripified for a test, shaped like igea.ply\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\nproperty float confidence\n"
            "property float intensity\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
            % len(v))
    verts = np.column_stack([v, np.full(len(v), 0.8), np.linspace(0, 1, len(v))]).astype(">f4")
    path.write_bytes(head.encode() + verts.tobytes() + np.array([len(strip)], ">i4").tobytes()
                     + strip.astype(">i4").tobytes())


def exact_text(x):
    return repr(float(x))


def write_coff(path, v, f):
    lines = ["# written by a test: COFF, counts on the keyword line", "COFF %d %d 0" % (len(v), len(f))]
    lines += ["%s %s %s 200 100 50 255" % tuple(map(exact_text, p)) for p in v]
    lines += ["", "# the faces, each with a colour"] + ["3 %d %d %d 0.1 0.2 0.3" % tuple(t) for t in f]
    path.write_text("\n".join(lines) + "\n")


def queries_for(bvhbench, ref, mesh, out_dir):
    """The query sets of `ref`, re-labelled for `mesh` (their sidecar names the mesh's sha256)."""
    sha = hashlib.sha256(mesh.read_bytes()).hexdigest()
    sets = []
    for kind in ["random", "haptic"]:
        src = out_dir / f"ref_{kind}.npy"
        if not src.exists():
            run(bvhbench, "queries", "--mesh", ref, "--kind", kind, "--n", 150, "--seed", 5, "--out", src, check=0)
        dst = out_dir / f"{mesh.name}_{kind}.npy"
        shutil.copy(src, dst)
        meta = json.loads(src.with_suffix(".json").read_text())
        meta["mesh_sha256"] = sha
        dst.with_suffix(".json").write_text(json.dumps(meta))
        sets.append((kind, dst))
    return sets


def answers(bvhbench, mesh, out_dir, ref):
    """{(method, query, kind): {array name: bytes}} of `bvhbench run --answers` on `mesh`."""
    out = {}
    for kind, q in queries_for(bvhbench, ref, mesh, out_dir):
        for method in METHODS:
            for query in ["inside", "distance"]:
                a = out_dir / f"{mesh.name}_{method}_{query}_{kind}.npz"
                run(bvhbench, "--quiet", "run", "--mesh", mesh, "--method", method, "--queries", q, "--query", query,
                    "--repeat", 1, "--answers", a, "--out", out_dir / "r.json", check=0)
                with np.load(a) as z:
                    out[(method, query, kind)] = {k: z[k].tobytes() for k in z.files}
    return out


def mesh_info(bvhbench, path):
    return json.loads(run(bvhbench, "mesh-info", path, "--json", check=0).stdout)


def test_igea_like_tristrip_ply_answers_as_its_face_ply(bvhbench, shared_meshes, tmp_path):
    v, f = canonical(*read_obj(shared_meshes / "stanford-bunny.obj"))
    strip, flipped = stripify(f)
    tris, runs, joins = decode_strips(strip)
    assert same_up_to_rotation(tris, f), "the strips hold the bunny's triangles, each oriented as it was"
    assert flipped > 10000 and len(runs) > 100 and joins > 1000, (flipped, len(runs), joins)
    # trimesh's decoder starts odd triangles at another corner; the same triangles otherwise.
    tm = trimesh.util.triangle_strips_to_faces([np.array(r) for r in runs if len(r) >= 3])
    tm = tm[(tm[:, 0] != tm[:, 1]) & (tm[:, 1] != tm[:, 2]) & (tm[:, 0] != tm[:, 2])]
    assert same_up_to_rotation(tm, tris)

    strips, ref = tmp_path / "bunny_strips.ply", tmp_path / "bunny_faces.ply"
    write_strip_ply(strips, v, strip)
    write_face_ply(ref, v, tris)
    want = answers(bvhbench, ref, tmp_path, ref)
    got = answers(bvhbench, strips, tmp_path, ref)
    for job in want:
        assert got[job] == want[job], f"answers differ for {job}"
    info = mesh_info(bvhbench, strips)
    assert (info["format"], info["variant"]) == ("ply", "binary_big_endian")
    assert (info["triangles"], info["strips"], info["strip_joins_dropped"]) == (len(f), len(runs), joins)
    assert not info["closed"]  # the bunny has holes in its base


def test_stl_and_off_of_a_closed_model_answer_as_its_ply(bvhbench, shared_meshes, tmp_path):
    v, f = canonical(*read_obj(shared_meshes / "rocker-arm.obj"))
    ref = tmp_path / "rocker.ply"
    write_face_ply(ref, v, f)
    tm = trimesh.Trimesh(vertices=v, faces=f, process=False)  # process=False: no merging, no reordering
    files = {"binary.stl": tm.export(file_type="stl"), "ascii.stl": tm.export(file_type="stl_ascii").encode(),
             "trimesh.off": tm.export(file_type="off", digits=25).encode()}  # 25 decimals: every float exact
    trap = bytearray(files["binary.stl"])
    trap[:80] = b"solid rocker-arm, binary, exported by trimesh".ljust(80, b" ")
    files["solid_header.stl"] = bytes(trap)
    paths = []
    for name, data in files.items():
        paths.append(tmp_path / name)
        paths[-1].write_bytes(data)
    paths.append(tmp_path / "written.off")
    write_coff(paths[-1], v, f)

    want = answers(bvhbench, ref, tmp_path, ref)
    assert mesh_info(bvhbench, ref)["closed"]
    for p in paths:
        info = mesh_info(bvhbench, p)
        assert info["closed"], p.name
        assert (info["vertices"], info["triangles"]) == (len(v), len(f)), p.name
        got = answers(bvhbench, p, tmp_path, ref)
        for job in want:
            assert got[job] == want[job], f"{p.name}: answers differ for {job}"
    assert mesh_info(bvhbench, tmp_path / "solid_header.stl")["variant"] == "binary"
    assert mesh_info(bvhbench, tmp_path / "ascii.stl")["stl_corners"] == 3 * len(f)
