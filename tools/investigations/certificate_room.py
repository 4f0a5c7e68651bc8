#!/usr/bin/env python3
"""How much room a distance certificate (and an inside ball) has on a haptic path.

A certificate issued at a query point p with radius r is the set S of triangles whose distance
from p is at most best(p) + 2r. For any later q with |q - p| <= r, best(q) <= best(p) + r and
every triangle outside S is farther than best(p) + r from q, so q's closest triangle is in S:
the queries that stay in the ball are a scan of |S| triangles. For inside, the ball of radius
|best(p)| around p holds no surface, so the winding number is constant in it.

This script replays the certificate offline on a query set (numpy only) and reports, for a grid
of radius rules, (a) how many consecutive queries one certificate serves, (b) |S|, both as
distributions over the certificates (mean, p50, p99), and an instruction model of the
certificate path against today's query (see --today). It also reports the inside ball.

Run (from the repository root, after `cmake --build build`):

    build/bvhbench queries --mesh M --kind haptic --n 20000 --seed 1 --out Q.npy
    build/bvhbench truth   --mesh M --queries Q.npy --out T.npz
    python3 tools/investigations/certificate_room.py --mesh M --queries Q.npy --truth T.npz \
        [--today INSTR --tri-instr INSTR --inside-instr INSTR] [--max-centres 2000] \
        [--only REGEX] [--json OUT.json] [--name NAME]

M is an OBJ or a binary little-endian PLY (as datasets-scripts writes). --today is the
instructions per query of today's (coherent, unsigned) search and --tri-instr the instructions
per exact triangle test in it (both from callgrind, methods/ebp_octree/HISTORY.md, "Haptic distance: where the time
goes"), --inside-instr today's coherent inside (the sign); without them only the geometry is
reported. |S| is counted at up to --max-centres certificates per rule (evenly sampled; the
served counts are over all of them). The model of the certificate path:

    per certificate: renewal = today + |S| * c_collect   (the relaxed prune collects S;
                       c_collect = tri_instr, or 40 for a SIMD collection of whole blocks)
                     + (served - 1) * (ball_check + |S| * c_scan + tri_instr)
                       (each served query: the ball test, the scan, the winner's exact test)
    per query      = sum over certificates / number of queries,
    (c_collect, c_scan) = (tri_instr, 25), (tri_instr, 40), (40, 40)

The rules: k x step, f x best, k x local step (speed), K nearest (r = (d_(K+1) - best) / 2,
|S| = K) and min(k x step, r of K nearest). The inside ball: certificates of radius best, and the
chained form (q_j has q_(j-1)'s sign when |q_j - q_(j-1)| < best(q_(j-1))). About 10-60 s per
mesh of 20k triangles, 4 min and 0.5 GB on 1M.

Standard library + numpy. Prints Markdown tables on stdout.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "datasets-scripts"))
from bvhdata.ply import read_ply  # noqa: E402


# ------------------------------------------------------------------------------------------------
# Mesh reading (OBJ v/f with v/vt/vn forms and negative indices, polygons fanned; binary PLY)
# ------------------------------------------------------------------------------------------------

def read_obj(path: str) -> tuple[np.ndarray, np.ndarray]:
    verts, faces = [], []
    with open(path, "r", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                t = line.split()
                verts.append((float(t[1]), float(t[2]), float(t[3])))
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
    return np.asarray(verts, dtype=np.float64), np.asarray(faces, dtype=np.int64)


def read_mesh(path: str) -> tuple[np.ndarray, np.ndarray]:
    """PLY as datasets-scripts writes it (its own reader), or OBJ (the shared meshes): the
    vertices and triangles in the order the runner reads them, so that triangle indices match
    the oracle's."""
    return read_ply(path) if path.lower().endswith(".ply") else read_obj(path)


# ------------------------------------------------------------------------------------------------
# Point-triangle distances (Ericson's closest point, vectorised over triangles)
# ------------------------------------------------------------------------------------------------

def point_triangle_d2(p: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    ab, ac, ap = B - A, C - A, p - A
    bp, cp = p - B, p - C
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)  # noqa: E731
    d1, d2 = dot(ab, ap), dot(ac, ap)
    d3, d4 = dot(ab, bp), dot(ac, bp)
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        den = va + vb + vc
        v, w = vb / den, vc / den
        q = A + ab * v[:, None] + ac * w[:, None]  # interior
        wbc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        m = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
        q = np.where(m[:, None], B + (C - B) * wbc[:, None], q)
        wac = d2 / (d2 - d6)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        q = np.where(m[:, None], A + ac * wac[:, None], q)
        m = (d6 >= 0) & (d5 <= d6)
        q = np.where(m[:, None], C, q)
        vab = d1 / (d1 - d3)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        q = np.where(m[:, None], A + ab * vab[:, None], q)
        m = (d3 >= 0) & (d4 <= d3)
        q = np.where(m[:, None], B, q)
        m = (d1 <= 0) & (d2 <= 0)
        q = np.where(m[:, None], A, q)
    d = np.einsum("ij,ij->i", q - p, q - p)
    # degenerate triangles: the nearest vertex is an upper bound, good enough for counting
    bad = ~np.isfinite(d)
    if bad.any():
        dv = np.minimum(np.minimum(np.einsum("ij,ij->i", ap, ap), np.einsum("ij,ij->i", bp, bp)),
                        np.einsum("ij,ij->i", cp, cp))
        d = np.where(bad, dv, d)
    return d


class TriangleIndex:
    """Triangles sorted by centroid x, with bounding spheres: all distances within R of p."""

    def __init__(self, V: np.ndarray, F: np.ndarray):
        A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        c = (A + B + C) / 3.0
        rad = np.sqrt(np.max(np.stack([((A - c) ** 2).sum(1), ((B - c) ** 2).sum(1), ((C - c) ** 2).sum(1)]), 0))
        o = np.argsort(c[:, 0], kind="stable")
        self.A, self.B, self.C, self.c, self.rad = A[o], B[o], C[o], c[o], rad[o] * (1 + 1e-9)
        self.cx = self.c[:, 0].copy()
        self.rmax = float(self.rad.max()) if len(rad) else 0.0

    def distances_within(self, p: np.ndarray, R: float) -> np.ndarray:
        """Sorted distances from p of the triangles within R (and maybe a few beyond)."""
        lo = np.searchsorted(self.cx, p[0] - R - self.rmax, "left")
        hi = np.searchsorted(self.cx, p[0] + R + self.rmax, "right")
        c, rad = self.c[lo:hi], self.rad[lo:hi]
        dc = np.sqrt(((c - p) ** 2).sum(1)) - rad
        k = np.nonzero(dc <= R)[0] + lo
        if len(k) == 0:
            return np.zeros(0)
        d = np.sqrt(point_triangle_d2(p, self.A[k], self.B[k], self.C[k]))
        return np.sort(d)


# ------------------------------------------------------------------------------------------------
# Certificates along the path
# ------------------------------------------------------------------------------------------------

def serve(Q: np.ndarray, radius) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Greedy certificates: one at query i serves i and the following queries within radius(i)
    of Q[i]; the first one outside renews. Returns (centres, radii, served counts)."""
    n = len(Q)
    centres, radii, served = [], [], []
    i = 0
    while i < n:
        r = radius(i)
        j = i + 1
        # vectorised look-ahead in chunks
        while j < n:
            k = min(n, j + 256)
            out = np.nonzero(np.sqrt(((Q[j:k] - Q[i]) ** 2).sum(1)) > r)[0]
            if len(out):
                j += int(out[0])
                break
            j = k
        centres.append(i)
        radii.append(r)
        served.append(j - i)
        i = j
    return np.asarray(centres), np.asarray(radii, dtype=float), np.asarray(served)


def dist_stats(x: np.ndarray) -> dict:
    x = np.asarray(x, dtype=float)
    return {"mean": float(x.mean()), "p50": float(np.percentile(x, 50)), "p99": float(np.percentile(x, 99)),
            "max": float(x.max())}


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--queries", required=True, help="Q.npy of `bvhbench queries`")
    ap.add_argument("--truth", required=True, help="T.npz of `bvhbench truth`")
    ap.add_argument("--name", default=None)
    ap.add_argument("--today", type=float, default=None,
                    help="instructions per query of today's coherent unsigned distance search")
    ap.add_argument("--tri-instr", type=float, default=None,
                    help="instructions per exact triangle test of today's search (renewal collects S)")
    ap.add_argument("--inside-instr", type=float, default=None,
                    help="instructions per query of today's coherent inside (the sign), for the totals")
    ap.add_argument("--ball-check", type=float, default=15.0, help="instructions of the |q - p| <= r test")
    ap.add_argument("--max-centres", type=int, default=3000,
                    help="|S| is computed at up to this many certificates per rule (evenly spaced)")
    ap.add_argument("--only", default=None, help="only the rules whose label matches this regex")
    ap.add_argument("--json", default=None)
    return ap.parse_args(argv)


class HapticPath:
    """The haptic path and its answers: points Q, exact distances best, the steps between them."""

    def __init__(self, a):
        self.V, self.F = read_mesh(a.mesh)
        self.Q = np.load(a.queries).astype(np.float64)
        self.best = np.abs(np.load(a.truth)["distance"].astype(np.float64))
        if len(self.best) != len(self.Q):
            raise SystemExit("truth and queries differ in length")
        self.diag = float(np.linalg.norm(self.V.max(0) - self.V.min(0)))
        self.steps = np.sqrt(((self.Q[1:] - self.Q[:-1]) ** 2).sum(1))
        self.med = float(np.median(self.steps))
        self.jumps = self.steps > 20 * self.med
        self.step = float(self.steps[~self.jumps].mean())  # the path's mean step, jumps between episodes left out
        self.idx = TriangleIndex(self.V, self.F)
        self.edge = float(np.mean(np.sqrt(((self.V[self.F[:, 1]] - self.V[self.F[:, 0]]) ** 2).sum(1))))
        # local step (for the speed-adaptive rule): mean of the last 8 steps before i (jumps out)
        st = np.concatenate([[self.step], np.where(self.jumps, self.step, self.steps)])
        cs = np.cumsum(np.concatenate([[0.0], st]))
        self.loc = np.array([(cs[i + 1] - cs[max(0, i - 7)]) / (i + 1 - max(0, i - 7)) for i in range(len(self.Q))])


def radius_rules(P):
    """[(label, kind, r(i))]: the certificate radius rules compared."""
    step, best, loc = P.step, P.best, P.loc
    rules = []
    for k in (0.5, 1, 2, 4, 8, 16, 32):
        rules.append((f"{k:g} x step", "step", lambda i, k=k: k * step))
    for f in (0.1, 0.25, 0.5, 1.0):
        rules.append((f"{f:g} x best", "best", lambda i, f=f: f * best[i]))
    for k in (2, 4, 8, 16):
        rules.append((f"{k:g} x local step", "local", lambda i, k=k: k * loc[i]))
    for k in (2, 4, 8):
        rules.append((f"max({k:g} x step, 0.5 x best)", "hybrid", lambda i, k=k: max(k * step, 0.5 * best[i])))
    # K nearest: the renewal collects the K nearest triangles and takes r = (d_(K+1) - best) / 2,
    # so that every triangle left out is at least best + 2r away: |S| = K, r from the geometry.
    knn_cache: dict = {}
    KMAX = 256

    def kth(i: int, K: int) -> float:
        d = knn_cache.get(i)
        if d is None:
            R = best[i] * (1 + 1e-9) + 4 * step
            while True:
                d = P.idx.distances_within(P.Q[i], R)
                d = d[d <= R]
                if len(d) >= KMAX + 1 or len(d) == len(P.F):
                    break
                R *= 2
            knn_cache[i] = d
        return float(d[min(K, len(d) - 1)])

    rk = lambda i, K: max(0.0, (kth(i, K) - best[i]) / 2 * (1 - 1e-9))  # noqa: E731
    for K in (4, 8, 16, 32, 64, 128, 256):
        rules.append((f"{K} nearest", "knn", lambda i, K=K: rk(i, K)))
    # capped: k steps, but never more than the K nearest triangles
    for k, K in ((4, 64), (8, 32), (8, 64), (8, 128), (16, 32), (16, 64), (16, 128), (16, 256)):
        rules.append((f"min({k} x step, r of {K} nearest)", "capped", lambda i, k=k, K=K: min(k * step, rk(i, K))))
    return rules


def rule_row(P, a, rng, label, kind, rad):
    """One rule's certificates along the path, |S| on a sample of them, and the estimated cost."""
    centres, radii, served = serve(P.Q, rad)
    m = len(centres)
    sel = np.arange(m) if m <= a.max_centres else np.sort(rng.choice(m, a.max_centres, replace=False))
    S = np.empty(len(sel))
    for t, c in enumerate(sel):
        i = int(centres[c])
        R = P.best[i] + 2 * radii[c]
        S[t] = np.searchsorted(P.idx.distances_within(P.Q[i], R * (1 + 1e-12)), R * (1 + 1e-12), "right")
    sv = served[sel]
    row = {"rule": label, "kind": kind, "certificates": m, "served": dist_stats(served),
           "S": dist_stats(S), "S_sampled": int(len(sel))}
    scale = m / len(sel)  # the sampled certificates scaled to all of them
    row["sums"] = {"S": float(S.sum() * scale), "served_minus_1": float((sv - 1).sum() * scale),
                   "served_minus_1_times_S": float(((sv - 1) * S).sum() * scale), "queries": int(len(P.Q))}
    if a.today is not None and a.tri_instr is not None:
        ests = []
        # (collect, scan): S collected at the exact test's cost, scanned at 25 or 40; or S
        # collected at the scan's cost (block triangles copied and distanced 8 at a time,
        # the optimistic end: the relaxed traversal's extra nodes and blocks not counted)
        for ccol, cscan in ((a.tri_instr, 25.0), (a.tri_instr, 40.0), (40.0, 40.0)):
            # a served query: the ball test, the scan of S, and the winner's exact closest
            # point in double (one triangle test) for bit-identical answers
            per_cert = a.today + S * ccol + (sv - 1) * (a.ball_check + S * cscan + a.tri_instr)
            ests.append(float(per_cert.sum() * scale / len(P.Q)))
        row["instr_per_query"] = ests
    return row


def print_rule(row, today):
    cost = ratio = ""
    if "instr_per_query" in row:
        cost = " / ".join(f"{e:,.0f}" for e in row["instr_per_query"])
        ratio = " / ".join(f"{today / e:.2f}x" for e in row["instr_per_query"])
    s1, s2 = row["served"], row["S"]
    print(f"| {row['rule']} | {row['certificates']} | {s1['mean']:.1f}, {s1['p50']:.0f}, {s1['p99']:.0f} | "
          f"{s2['mean']:.1f}, {s2['p50']:.0f}, {s2['p99']:.0f} | {cost} | {ratio} |")


def inside_ball(P, out):
    """Inside: the ball of radius |best(p)| holds no surface. Returns the chained share."""
    centres, radii, served = serve(P.Q, lambda i: P.best[i] * (1 - 1e-12))
    chained = np.zeros(len(P.Q), dtype=bool)  # q_j within best(q_{j-1}) of q_{j-1}: sign known
    chained[1:] = P.steps < P.best[:-1] * (1 - 1e-12)
    s1 = dist_stats(served)
    out["inside_ball"] = {"certificates": int(len(centres)), "served": s1,
                          "chained_fraction": float(chained.mean())}
    print(f"\nInside ball (r = best at the centre): {len(centres)} certificates, queries per "
          f"certificate mean {s1['mean']:.2f}, p50 {s1['p50']:.0f}, p99 {s1['p99']:.0f}, max {s1['max']:.0f}; "
          f"chained (each query within the previous query's distance of it): "
          f"{chained.mean() * 100:.1f} % of queries need no inside test\n")
    return float(chained.mean())


def print_best_rules(a, out, chained):
    for col, cscan in ((0, "exact collect, 25"), (1, "exact collect, 40"), (2, "SIMD collect, 40")):
        b = min(out["rules"], key=lambda r: r["instr_per_query"][col])
        line = (f"Best rule ({cscan}): {b['rule']}, {b['instr_per_query'][col]:,.0f} instructions per "
                f"unsigned query against {a.today:,.0f} today ({a.today / b['instr_per_query'][col]:.2f}x)")
        if a.inside_instr is not None:
            now = a.today + a.inside_instr
            cert = b["instr_per_query"][col] + a.ball_check + (1 - chained) * a.inside_instr
            line += (f"; with the sign: {cert:,.0f} (inside only where the chained ball fails) against "
                     f"{now:,.0f} ({now / cert:.2f}x)")
            out.setdefault("totals", []).append({"c_scan": cscan, "rule": b["rule"], "cert": cert, "today": now})
        print(line)


def main(argv=None) -> int:
    a = parse_args(argv)
    name = a.name or a.mesh.rsplit("/", 1)[-1]
    P = HapticPath(a)
    rules = radius_rules(P)
    if a.only:
        import re
        rules = [r for r in rules if re.search(a.only, r[0])]
    best = P.best
    print(f"## {name}: {len(P.F)} triangles, {len(P.Q)} queries, diag {P.diag:.6g}, mean edge {P.edge:.4g}")
    print(f"mean step {P.step:.4g} ({P.step / P.diag * 100:.3f} % of diag; median {P.med:.4g}; "
          f"{int(P.jumps.sum())} jumps > 20x median left out), best distance mean {best.mean():.4g} "
          f"p50 {np.median(best):.4g} (= {np.median(best) / P.step:.2f} steps)\n")
    out = {"name": name, "triangles": int(len(P.F)), "queries": int(len(P.Q)), "diag": P.diag, "step": P.step,
           "median_step": P.med, "best_mean": float(best.mean()), "best_p50": float(np.median(best)),
           "rules": []}
    print("| r rule | certificates | queries / certificate (mean, p50, p99) | |S| (mean, p50, p99) | "
          "instr / query (collect exact + scan 25, exact + 40, SIMD 40 + 40) | vs today |")
    print("|---|---:|---:|---:|---:|---:|")
    rng = np.random.default_rng(1)
    for label, kind, rad in rules:
        row = rule_row(P, a, rng, label, kind, rad)
        out["rules"].append(row)
        print_rule(row, a.today)
    chained = inside_ball(P, out)
    if a.today is not None and a.tri_instr is not None:
        print_best_rules(a, out, chained)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
